//! Where and when a [`PipelineMessage`] is: its channel and its place in sample time, asked of
//! the message itself instead of matched out of every variant by each consumer (the MCAP log
//! times its messages by them, the fleet bridge routes and dates its observations by them).
//! A [`DetectorMessage`](super::DetectorMessage) answers through its records'
//! [`Stamped`](super::detect::Stamped).

use super::{ChannelId, PipelineMessage};

impl PipelineMessage {
    /// The channel the message belongs to, so that a consumer routing or timing messages by
    /// channel need not match every variant. `None` for [`IngestMessage`] alone: it counts a
    /// whole source (a CAN interface, a node's shared memory), which may feed several channels.
    pub fn channel(&self) -> Option<&ChannelId> {
        match self {
            PipelineMessage::Raw(m) => Some(&m.channel),
            PipelineMessage::Spectrum(m) => Some(&m.channel),
            PipelineMessage::Indicators(m) => Some(&m.channel),
            PipelineMessage::Twin(m) => Some(&m.channel),
            PipelineMessage::Hw(m) => Some(&m.channel),
            PipelineMessage::Trend(m) => Some(&m.channel),
            PipelineMessage::Flag(m) => Some(&m.channel),
            PipelineMessage::Health(m) => Some(&m.channel),
            PipelineMessage::Speed(m) => Some(&m.channel),
            PipelineMessage::Detector(m) => Some(m.channel()),
            PipelineMessage::Ingest(_) => None,
        }
    }

    /// Where the message stands in its channel's sample time: one past the last sample it
    /// covers ([`RawBlock::end_sample`](super::RawBlock::end_sample) for a raw block). `None` for [`IngestMessage`]: a
    /// source's counters are taken on the daemon's clock, not at a sample.
    pub fn end_sample(&self) -> Option<u64> {
        match self {
            PipelineMessage::Raw(m) => Some(m.end_sample()),
            PipelineMessage::Spectrum(m) => Some(m.end_sample),
            PipelineMessage::Indicators(m) => Some(m.end_sample),
            PipelineMessage::Twin(m) => Some(m.end_sample),
            PipelineMessage::Hw(m) => Some(m.end_sample),
            PipelineMessage::Trend(m) => Some(m.end_sample),
            PipelineMessage::Flag(m) => Some(m.end_sample),
            PipelineMessage::Health(m) => Some(m.end_sample),
            PipelineMessage::Speed(m) => Some(m.end_sample),
            PipelineMessage::Detector(m) => Some(m.end_sample()),
            PipelineMessage::Ingest(_) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{
        FaultKind, FlagLevel, FlagMessage, HealthKind, HealthMessage, HealthStage, HwMessage,
        IndicatorsMessage, IngestMessage, IsoZone, RawBlock, SpectrumMessage, SpeedMessage,
        SpeedSource, TrendMessage, TwinMessage, VelocityFlagMessage, VelocityMessage,
    };

    /// A channel of its own per variant, so that an accessor reading the wrong message's field
    /// could not pass.
    fn channel(axis: &str) -> ChannelId {
        ChannelId {
            sensor: "motor-de".into(),
            axis: axis.into(),
        }
    }

    /// One message of every variant with a channel, each with its axis name and its end sample.
    fn stamped() -> Vec<(PipelineMessage, &'static str, u64)> {
        vec![
            (
                PipelineMessage::Raw(RawBlock {
                    channel: channel("raw"),
                    first_sample: 1_000,
                    sample_rate_hz: 25_600.0,
                    scale_g_per_count: 0.000_488,
                    counts: vec![3, -2, 7],
                }),
                "raw",
                1_003,
            ),
            (
                PipelineMessage::Spectrum(SpectrumMessage::new(
                    channel("spectrum"),
                    2_000,
                    [500.0, 2500.0],
                    0.5,
                    3,
                    vec![1.0],
                )),
                "spectrum",
                2_000,
            ),
            (
                PipelineMessage::Indicators(IndicatorsMessage {
                    channel: channel("indicators"),
                    end_sample: 3_000,
                    rpm: 1797.0,
                    band_hz: [500.0, 2500.0],
                    rms: 0.1,
                    peak: 0.5,
                    crest: 5.0,
                    kurtosis: 3.0,
                    score_outer_race: 1.0,
                    score_inner_race: 1.0,
                    score_ball: 1.0,
                    score_cage: 1.0,
                }),
                "indicators",
                3_000,
            ),
            (
                PipelineMessage::Twin(TwinMessage {
                    channel: channel("twin"),
                    end_sample: 4_000,
                    hypothesis: FaultKind::OuterRace,
                    error: 0.1,
                    margin: 0.5,
                    error_outer_race: 0.1,
                    error_inner_race: 0.6,
                    error_ball: 0.7,
                    a: 1.0,
                    decay_per_s: 800.0,
                    f_n: 3000.0,
                    f_d: 107.0,
                    jitter: 0.01,
                    residual_energy_ratio: 0.2,
                    residual_peak_hz: 214.0,
                    residual_bin_hz: 0.5,
                    residual: vec![0.0],
                    learned: None,
                }),
                "twin",
                4_000,
            ),
            (
                PipelineMessage::Hw(HwMessage {
                    channel: channel("hw"),
                    end_sample: 5_000,
                    first_sample: 4_500,
                    fs_hz: 25_600.0,
                    order: 2,
                    states: "raw_once".into(),
                    problem: None,
                    warm_start: false,
                    iterations: 4,
                    accuracy_simulation: 90.0,
                    accuracy_one_step: 95.0,
                    numerators: vec![vec![1.0]],
                    denominators: vec![vec![0.5]],
                    pole_radius: vec![0.5],
                    output_polynomial: vec![0.0, 1.0],
                    output_mean: 0.0,
                    output_scale: 1.0,
                    residual_simulation: vec![0.0],
                    residual_one_step: vec![0.0],
                    baseline_fits: 1,
                    residual_drift_sigma: None,
                    parameter_drift: None,
                }),
                "hw",
                5_000,
            ),
            (
                PipelineMessage::Trend(TrendMessage {
                    channel: channel("trend"),
                    end_sample: 6_000,
                    stage: HealthStage::Healthy,
                    rms: 0.1,
                    points: 1,
                    threshold: None,
                    rate_per_s: None,
                    doubling_s: None,
                    time_to_threshold_s: None,
                    earliest_s: None,
                    latest_s: None,
                    confidence: 0.9,
                }),
                "trend",
                6_000,
            ),
            (
                PipelineMessage::Flag(FlagMessage {
                    channel: channel("flag"),
                    end_sample: 7_000,
                    fault: FaultKind::InnerRace,
                    from: FlagLevel::Ok,
                    to: FlagLevel::Watch,
                    score: 6.0,
                    fault_frequency_hz: 162.2,
                    runner_up_score: None,
                }),
                "flag",
                7_000,
            ),
            (
                PipelineMessage::Health(HealthMessage {
                    channel: channel("health"),
                    end_sample: 8_000,
                    kind: HealthKind::Gap,
                    stage: None,
                    detail: String::new(),
                }),
                "health",
                8_000,
            ),
            (
                PipelineMessage::Speed(SpeedMessage {
                    channel: channel("speed"),
                    end_sample: 9_000,
                    source: SpeedSource::Can,
                    given_rpm: Some(1797.0),
                    rpm: Some(1797.0),
                }),
                "speed",
                9_000,
            ),
            (
                VelocityMessage {
                    channel: channel("velocity"),
                    end_sample: 10_000,
                    rms_mm_s: 3.7,
                    zone: IsoZone::C,
                    band_hz: [10.0, 1000.0],
                    windows_averaged: 8,
                    flag: FlagLevel::Watch,
                }
                .into(),
                "velocity",
                10_000,
            ),
            (
                VelocityFlagMessage {
                    channel: channel("velocity-flag"),
                    end_sample: 11_000,
                    from: FlagLevel::Ok,
                    to: FlagLevel::Watch,
                    rms_mm_s: 3.7,
                    zone: IsoZone::C,
                    watch_mm_s: 2.8,
                    alarm_mm_s: 4.5,
                }
                .into(),
                "velocity-flag",
                11_000,
            ),
        ]
    }

    #[test]
    fn every_message_of_a_channel_says_its_channel_and_end_sample() {
        for (message, axis, end_sample) in stamped() {
            assert_eq!(message.channel(), Some(&channel(axis)), "{message:?}");
            assert_eq!(message.end_sample(), Some(end_sample), "{message:?}");
        }
    }

    #[test]
    fn a_raw_block_ends_one_past_its_last_sample() {
        let (raw, _, _) = stamped().swap_remove(0);
        let PipelineMessage::Raw(mut block) = raw else {
            panic!("the first sample is the raw block");
        };
        block.counts.clear();
        assert_eq!(
            PipelineMessage::Raw(block).end_sample(),
            Some(1_000),
            "an empty block ends where it starts"
        );
    }

    #[test]
    fn a_sources_counters_have_neither_channel_nor_sample() {
        // A node's shared memory: one source for both of its axes.
        let ingest = PipelineMessage::Ingest(IngestMessage {
            source: "shm-node1".into(),
            frames: 400,
            samples: 102_400,
            gaps: 1,
            missing_samples: 256,
            malformed: 0,
            restarts: 0,
            dropped_blocks: 0,
            speed_frames: 10,
            sensor_lost: 0,
            handoff_dropped: 1,
        });
        assert_eq!(ingest.channel(), None);
        assert_eq!(ingest.end_sample(), None);
    }
}
