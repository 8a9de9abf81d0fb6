//! The shaft speed estimated from the vibration (crates/bearing-core/src/analysis/speed.rs) on
//! real and simulated records: from a nominal speed 3 % off, the estimate lands within 0.5 % of the measured speed,
//! and the diagnosis with the estimated speed is the diagnosis with the measured one.

use bearingd::analysis::envelope::FftPlans;
use bearingd::analysis::record::RecordAnalyzer;
use bearingd::analysis::speed::{estimate_shaft_hz, SpeedSearch};
use bearingd::analysis::{AnalysisSettings, Verdict};
use bearingd::bearing::BearingGeometry;
use bearingd::recording::{read_recording, ReadOptions};
use bearingd::twin::{SimulatedFault, SimulationParams, Simulator};
use bearingd_testdata::{read_manifest, shared_data_dir};

/// CWRU record 234 (outer race 0.021 in, 0 hp, 1796 rpm measured): its diagnosis is `none`,
/// not outer race, for any speed from 1795.2 to 1795.5 rpm (the inner-race score of one band
/// of the refinement jumps from 7 to 13.9 there, and outer race then is only 1.6× it; outer race
/// below 1795.2 and above 1795.5). The estimate, 1795.3 rpm by both the harmonic sum and the
/// harmonics' own peaks, lands in that window: the speed is right within 0.04 %, the
/// diagnosis's own sensitivity to a 0.3 rpm change is what differs.
const FRAGILE: &str = "12k_Drive_End_OR021@6_0_234.mat";

#[test]
fn cwru_drive_end_speed_estimated_from_three_per_cent_off_within_half_a_per_cent() {
    let Some(dir) = shared_data_dir("cwru") else {
        return;
    };
    let bearing = BearingGeometry::from_catalog("skf-6205-2rs").unwrap();
    let settings = AnalysisSettings::default();
    let mut analyzer = RecordAnalyzer::default();
    let mut plans = FftPlans::default();
    let mut problems = Vec::new();
    let mut lines = Vec::new();
    for row in read_manifest(&dir) {
        if row["sensor_location"] != "drive_end" {
            continue;
        }
        let recording = read_recording(
            &dir.join(&row["file"]),
            &ReadOptions {
                channel: Some(row["channel_var"].clone()),
                column: None,
                unit: None,
            },
        )
        .unwrap();
        let fs: f64 = row["fs_hz"].parse().unwrap();
        let rpm: f64 = row["rpm"].parse().unwrap();
        let signal: Vec<f32> = recording.samples.iter().map(|&x| x as f32).collect();
        for off in [-0.03, 0.03] {
            let nominal = rpm * (1.0 + off);
            let estimate = estimate_shaft_hz(
                &mut plans,
                &signal,
                fs,
                SpeedSearch {
                    nominal_hz: nominal / 60.0,
                    range: 0.05,
                },
            );
            let Some(estimate) = estimate else {
                problems.push(format!(
                    "{}: no estimate from {nominal:.0} rpm",
                    row["file"]
                ));
                continue;
            };
            let error = estimate.rpm() / rpm - 1.0;
            lines.push(format!(
                "{} rpm {rpm} nominal {nominal:.0}: estimate {:.1} rpm ({:+.3} %), prominence {:.2}",
                row["file"],
                estimate.rpm(),
                100.0 * error,
                estimate.prominence
            ));
            if error.abs() > 0.005 {
                problems.push(lines.last().unwrap().clone());
            }
            let truth = analyzer
                .analyze(
                    &signal,
                    fs,
                    &bearing.fault_frequencies(rpm / 60.0),
                    &settings,
                )
                .unwrap();
            let estimated = analyzer
                .analyze(
                    &signal,
                    fs,
                    &bearing.fault_frequencies(estimate.shaft_hz),
                    &settings,
                )
                .unwrap();
            lines.push(format!(
                "    truth {:?} {} | estimated {:?} {}",
                truth.diagnosis.verdict,
                truth.diagnosis.reason,
                estimated.diagnosis.verdict,
                estimated.diagnosis.reason
            ));
            let same = truth.diagnosis.verdict == estimated.diagnosis.verdict;
            if row["file"] == FRAGILE && !same {
                // The documented exception: the estimate may land in the window where the
                // diagnosis itself flips; it must then say "none", never a wrong class.
                if estimated.diagnosis.verdict != Verdict::None {
                    problems.push(format!(
                        "{}: a wrong class {:?} with the estimate",
                        row["file"], estimated.diagnosis.verdict
                    ));
                }
            } else if !same {
                problems.push(format!(
                    "{}: diagnosis {:?} with the measured speed, {:?} with the estimate",
                    row["file"], truth.diagnosis.verdict, estimated.diagnosis.verdict
                ));
            }
        }
    }
    eprintln!("{}", lines.join("\n"));
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The twin simulator at a known speed (an outer-race fault, its once-per-revolution tone and
/// noise): from 3 % off, the estimate is within 0.1 % and the diagnosis is the same.
#[test]
fn twin_speed_estimated_from_three_per_cent_off() {
    let mut plans = FftPlans::default();
    let mut analyzer = RecordAnalyzer::default();
    let settings = AnalysisSettings::default();
    for (rpm, fault) in [
        (1772.0, SimulatedFault::OuterRace),
        (1500.0, SimulatedFault::InnerRace),
    ] {
        let mut params = SimulationParams::example(fault);
        params.rpm = rpm;
        params.fs_hz = 25_600.0;
        params.noise_g = 0.1;
        params.seed = 7;
        let bearing = params.bearing.clone();
        let mut signal = vec![0f32; 256_000];
        Simulator::new(params).fill(&mut signal);
        for off in [-0.03, 0.03] {
            let estimate = estimate_shaft_hz(
                &mut plans,
                &signal,
                25_600.0,
                SpeedSearch {
                    nominal_hz: rpm * (1.0 + off) / 60.0,
                    range: 0.05,
                },
            )
            .expect("an estimate");
            let error = estimate.rpm() / rpm - 1.0;
            eprintln!(
                "twin {fault:?} {rpm} rpm from {:.0}: {:.2} rpm ({:+.4} %)",
                rpm * (1.0 + off),
                estimate.rpm(),
                100.0 * error
            );
            assert!(error.abs() < 0.001, "{estimate:?} for {rpm} rpm");
            let truth = analyzer
                .analyze(
                    &signal,
                    25_600.0,
                    &bearing.fault_frequencies(rpm / 60.0),
                    &settings,
                )
                .unwrap();
            let estimated = analyzer
                .analyze(
                    &signal,
                    25_600.0,
                    &bearing.fault_frequencies(estimate.shaft_hz),
                    &settings,
                )
                .unwrap();
            assert_eq!(truth.diagnosis.verdict, estimated.diagnosis.verdict);
            assert_ne!(truth.diagnosis.verdict, Verdict::None);
        }
    }
}
