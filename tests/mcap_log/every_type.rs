//! One message of every type the pipeline logs, and the topic and JSON each must have, written
//! out by hand (not taken from the registry) so that the wire is checked against what it was.

use bearingd::machine_fault::MachineFaultKind;
use bearingd::messages::detect::machine::{MachineFlagMessage, MachineMessage};
use bearingd::messages::detect::Emitted;
use bearingd::messages::*;

use super::ch;

/// One message of every type, with edge values: i16 extremes, large u64, None and Some.
pub(crate) fn every_type() -> Vec<PipelineMessage> {
    let c = ch("motor-de", "radial");
    vec![
        PipelineMessage::Raw(RawBlock {
            channel: c.clone(),
            first_sample: 123_456_789_012,
            sample_rate_hz: 25_600.0,
            scale_g_per_count: 0.000488,
            counts: vec![0, 1, -1, 32_767, -32_768, 12_345, -2, 7],
        }),
        PipelineMessage::Raw(RawBlock {
            channel: ch("motor-nde", "axial"),
            first_sample: 0,
            sample_rate_hz: 12_000.0,
            scale_g_per_count: 1.0 / 2048.0,
            counts: (-500..500).collect(),
        }),
        PipelineMessage::Spectrum(SpectrumMessage::new(
            c.clone(),
            u64::MAX / 3,
            [2_000.0, 4_000.5],
            0.78125,
            8,
            vec![0.1, 1e-7, 3.5, 0.0, 123_456.79],
        )),
        PipelineMessage::Indicators(IndicatorsMessage {
            channel: c.clone(),
            end_sample: 25_600,
            rpm: 1772.0,
            band_hz: [1000.0, 2000.0],
            rms: 0.123_456_789,
            peak: 1.5,
            crest: 12.1,
            kurtosis: 3.000_000_1,
            score_outer_race: 42.0,
            score_inner_race: 1.1,
            score_ball: 0.9,
            score_cage: 1.0,
        }),
        PipelineMessage::Twin(TwinMessage {
            channel: c.clone(),
            end_sample: 51_200,
            hypothesis: FaultKind::OuterRace,
            error: 0.01,
            margin: 0.5,
            error_outer_race: 0.01,
            error_inner_race: 0.2,
            error_ball: 0.3,
            a: 1.0,
            decay_per_s: 800.0,
            f_n: 3000.0,
            f_d: 107.36,
            jitter: 0.01,
            residual_energy_ratio: 0.05,
            residual_peak_hz: 214.7,
            residual_bin_hz: 0.5,
            residual: vec![-0.25, 0.5, 1e-3],
            learned: None,
        }),
        PipelineMessage::Hw(HwMessage {
            channel: c.clone(),
            end_sample: 51_200,
            first_sample: 48_640,
            fs_hz: 25_600.0,
            order: 0,
            states: "raw_once".into(),
            problem: None,
            warm_start: true,
            iterations: 6,
            accuracy_simulation: 93.25,
            accuracy_one_step: 98.5,
            numerators: vec![vec![0.125], vec![-0.5], vec![0.25]],
            denominators: vec![vec![-0.75, 0.125, 0.0625]; 3],
            pole_radius: vec![0.875; 3],
            output_polynomial: vec![0.0, 1.0, 0.015625, -0.001],
            output_mean: 0.001,
            output_scale: 0.2,
            residual_simulation: vec![0.5, -0.25, 1e-3],
            residual_one_step: vec![0.125, 0.0, -2.5],
            baseline_fits: 10,
            residual_drift_sigma: Some(1.5),
            parameter_drift: None,
        }),
        PipelineMessage::Trend(TrendMessage {
            channel: c.clone(),
            end_sample: 1_536_000,
            stage: HealthStage::Degrading,
            rms: 0.25,
            points: 12,
            threshold: Some(0.375),
            rate_per_s: Some(0.0001),
            doubling_s: Some(6931.5),
            time_to_threshold_s: Some(4700.0),
            earliest_s: Some(1200.5),
            latest_s: None,
            confidence: 0.9,
        }),
        PipelineMessage::Flag(FlagMessage {
            channel: c.clone(),
            end_sample: 76_800,
            fault: FaultKind::OuterRace,
            from: FlagLevel::Watch,
            to: FlagLevel::Alarm,
            score: 37.5,
            fault_frequency_hz: 107.36,
            runner_up_score: Some(2.25),
        }),
        PipelineMessage::Health(HealthMessage {
            channel: c.clone(),
            end_sample: 1,
            kind: HealthKind::Stage,
            stage: Some(HealthStage::Degrading),
            detail: "score over 15 for 10 min".into(),
        }),
        PipelineMessage::Health(HealthMessage {
            channel: c,
            end_sample: 2,
            kind: HealthKind::Gap,
            stage: None,
            detail: "12 samples missing".into(),
        }),
        PipelineMessage::Ingest(IngestMessage {
            source: "can0".into(),
            frames: 1_000_000,
            samples: 4_000_000,
            gaps: 1,
            missing_samples: 12,
            malformed: 0,
            restarts: 0,
            dropped_blocks: 0,
            speed_frames: 10,
            sensor_lost: 1,
            handoff_dropped: 2,
        }),
        PipelineMessage::Speed(SpeedMessage {
            channel: ch("motor-de", "radial"),
            end_sample: 25_600,
            source: SpeedSource::Can,
            given_rpm: Some(1772.25),
            rpm: Some(1772.25),
        }),
        PipelineMessage::Speed(SpeedMessage {
            channel: ch("motor-de", "radial"),
            end_sample: 51_200,
            source: SpeedSource::Can,
            given_rpm: None,
            rpm: None,
        }),
        PipelineMessage::from(VelocityMessage {
            channel: ch("motor-de", "radial"),
            end_sample: 32_768,
            rms_mm_s: 3.745,
            zone: IsoZone::C,
            band_hz: [10.0, 1000.0],
            windows_averaged: 1,
            flag: FlagLevel::Ok,
        }),
        PipelineMessage::from(VelocityFlagMessage {
            channel: ch("motor-de", "radial"),
            end_sample: 163_840,
            from: FlagLevel::Ok,
            to: FlagLevel::Watch,
            rms_mm_s: 3.75,
            zone: IsoZone::C,
            watch_mm_s: 2.8,
            alarm_mm_s: 4.5,
        }),
        PipelineMessage::from(MachineMessage {
            channel: ch("motor-de", "radial"),
            end_sample: 61_440,
            shaft_hz: 29.53,
            overall_mm_s: 4.1,
            orders_mm_s: [3.9, 0.4, 0.1],
            fault: Some(MachineFaultKind::Unbalance),
            fault_mm_s: 3.9,
            zone: IsoZone::C,
            windows_averaged: 8,
        }),
        PipelineMessage::from(MachineFlagMessage {
            channel: ch("motor-de", "radial"),
            end_sample: 61_440,
            kind: MachineFaultKind::Unbalance,
            from: FlagLevel::Ok,
            to: FlagLevel::Watch,
            velocity_mm_s: 3.9,
            watch_mm_s: 2.8,
            alarm_mm_s: 4.5,
        }),
    ]
}

pub(crate) fn topic_and_json(m: &PipelineMessage) -> (String, String) {
    let j = |v: &dyn erased::Ser| v.json();
    match m {
        PipelineMessage::Raw(b) => (format!("/raw/{}", b.channel), j(b)),
        PipelineMessage::Spectrum(s) => (format!("/spectrum/{}", s.channel), j(s)),
        PipelineMessage::Indicators(s) => (format!("/indicators/{}", s.channel), j(s)),
        PipelineMessage::Twin(s) => (format!("/twin/{}", s.channel), j(s)),
        PipelineMessage::Hw(s) => (format!("/hw/{}", s.channel), j(s)),
        PipelineMessage::Trend(s) => (format!("/trend/{}", s.channel), j(s)),
        PipelineMessage::Flag(s) => (format!("/flags/{}", s.channel), j(s)),
        PipelineMessage::Health(s) => (format!("/health/{}", s.channel), j(s)),
        PipelineMessage::Ingest(s) => (format!("/ingest/{}", s.source), j(s)),
        PipelineMessage::Speed(s) => (format!("/speed/{}", s.channel), j(s)),
        // Written out, not taken from the registry: the ISO wire is the one it always was.
        PipelineMessage::Detector(DetectorMessage::Velocity(Emitted::Reading(s))) => {
            (format!("/velocity/{}", s.channel), j(s))
        }
        PipelineMessage::Detector(DetectorMessage::Velocity(Emitted::Flag(s))) => {
            (format!("/velocity_flags/{}", s.channel), j(s))
        }
        PipelineMessage::Detector(DetectorMessage::Machine(Emitted::Reading(s))) => {
            (format!("/machine/{}", s.channel), j(s))
        }
        PipelineMessage::Detector(DetectorMessage::Machine(Emitted::Flag(s))) => {
            (format!("/machine_flags/{}", s.channel), j(s))
        }
    }
}

mod erased {
    pub trait Ser {
        fn json(&self) -> String;
    }
    impl<T: serde::Serialize> Ser for T {
        fn json(&self) -> String {
            serde_json::to_string(self).expect("serialize")
        }
    }
}
