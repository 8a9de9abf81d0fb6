//! What is swept: the axes of a sweep and the list of cases they make.
//!
//! A case is one simulated record. Its seed is derived from the sweep's seed and the case's own
//! coordinates (not its position in the list), so the same case gives the same record in the
//! quick and the full sweep, in any order, on any number of threads.

use crate::bearing::BearingGeometry;
use crate::twin::{Nuisance, SimulatedFault, SimulationParams};
use serde::Serialize;

/// A bearing and the machine it sits in.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Machine {
    pub bearing: BearingGeometry,
    /// The speed the speed axis scales, rpm.
    pub nominal_rpm: f64,
    pub fs_hz: f64,
    /// Structural resonance the impacts ring at, Hz.
    pub resonance_hz: f64,
}

impl Machine {
    /// The CWRU drive end: SKF 6205-2RS at 1772 rpm, 12 kHz, resonance 3 kHz (the simulator's
    /// example).
    pub fn cwru() -> Self {
        let example = SimulationParams::example(SimulatedFault::None);
        Machine {
            bearing: example.bearing,
            nominal_rpm: example.rpm,
            fs_hz: example.fs_hz,
            resonance_hz: example.resonance_hz,
        }
    }

    /// The IMS rig: Rexnord ZA-2115 (16 rollers, contact angle 15.17°) at 2000 rpm, 20.48 kHz;
    /// resonance 4 kHz (choice).
    #[allow(
        clippy::expect_used,
        reason = "a catalog entry; the catalog tests check it exists"
    )]
    pub fn ims() -> Self {
        Machine {
            bearing: BearingGeometry::from_catalog("rexnord-za-2115").expect("catalog entry"),
            nominal_rpm: 2000.0,
            fs_hz: 20_480.0,
            resonance_hz: 4_000.0,
        }
    }

    /// Seed 002's test stand: SKF 61804 at 3000 rpm; sampled at the daemon's default
    /// 25.6 kHz, resonance 5 kHz (choice). A hard case on purpose: its BPFI (7.375 × fr) and
    /// 2·BSF (7.294 × fr) lie 1.1 % apart, inside the ±2 % slip tolerance, so only the
    /// sidebands (±fr against ±FTF) can tell an inner-race from a ball fault.
    #[allow(
        clippy::expect_used,
        reason = "a catalog entry; the catalog tests check it exists"
    )]
    pub fn siegen() -> Self {
        Machine {
            bearing: BearingGeometry::from_catalog("skf-61804").expect("catalog entry"),
            nominal_rpm: 3000.0,
            fs_hz: 25_600.0,
            resonance_hz: 5_000.0,
        }
    }
}

/// How loud the white noise is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "db")]
pub enum NoiseLevel {
    /// The simulator's own default, [`SimulationParams::example`]'s `noise_g` (0.2 g).
    SimulatorDefault,
    /// Fault-to-noise power ratio in dB: the RMS of the fault's own signal (impacts and, for a
    /// cage, rubbing; measured on a noiseless simulation of the same case) over the RMS of the
    /// broadband noise (the white noise and the nuisance's shaft-modulated noise, kept in the
    /// preset's proportion). Healthy cases take the noise of an outer-race fault of the
    /// default severity on the same machine and speed. The nuisance's tones and random
    /// impulses keep their levels: severity is the fault's strength against them.
    Snr(f64),
}

impl NoiseLevel {
    pub fn label(self) -> String {
        match self {
            NoiseLevel::SimulatorDefault => "sim default".into(),
            NoiseLevel::Snr(db) => format!("{db:+.0} dB"),
        }
    }

    /// Sort key: SNR ascending, the simulator's default last.
    pub fn order(self) -> f64 {
        match self {
            NoiseLevel::Snr(db) => db,
            NoiseLevel::SimulatorDefault => f64::INFINITY,
        }
    }
}

/// The axes of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sweep {
    pub name: String,
    pub seed: u64,
    pub machines: Vec<Machine>,
    /// Shaft speeds as fractions of each machine's nominal speed.
    pub speed_factors: Vec<f64>,
    /// Impact amplitude `a` at full load, g (the simulator's default is 1 g).
    pub severities: Vec<f64>,
    pub noise: Vec<NoiseLevel>,
    /// Healthy records per machine, speed and noise level (each its own seed).
    pub healthy_repeats: usize,
    pub nuisance: Nuisance,
    /// Seconds `analyze` gets: the first part of the record.
    pub record_s: f64,
    /// Seconds the daemon's channel monitor gets: the whole record.
    pub monitor_s: f64,
}

/// The simulator's default severity, g.
pub const DEFAULT_SEVERITY: f64 = 1.0;

impl Sweep {
    /// The small sweep CI runs: two machines (CWRU, IMS) at their nominal speed, the default
    /// severity and the simulator's default noise, plus 0 dB; three healthy records each.
    pub fn quick(seed: u64) -> Self {
        Sweep {
            name: "quick".into(),
            seed,
            machines: vec![Machine::cwru(), Machine::ims()],
            speed_factors: vec![1.0],
            severities: vec![DEFAULT_SEVERITY],
            noise: vec![NoiseLevel::SimulatorDefault, NoiseLevel::Snr(0.0)],
            healthy_repeats: 3,
            nuisance: Nuisance::typical(),
            record_s: 10.0,
            monitor_s: 30.0,
        }
    }

    /// The full sweep: three machines (the quick two and seed 002's SKF 61804), two speeds,
    /// three severities, six SNRs and the default noise.
    pub fn full(seed: u64) -> Self {
        Sweep {
            name: "full".into(),
            machines: vec![Machine::cwru(), Machine::ims(), Machine::siegen()],
            speed_factors: vec![0.6, 1.0],
            severities: vec![0.5, DEFAULT_SEVERITY, 2.0],
            noise: vec![
                NoiseLevel::Snr(-15.0),
                NoiseLevel::Snr(-10.0),
                NoiseLevel::Snr(-5.0),
                NoiseLevel::Snr(0.0),
                NoiseLevel::Snr(5.0),
                NoiseLevel::Snr(10.0),
                NoiseLevel::SimulatorDefault,
            ],
            ..Sweep::quick(seed)
        }
        .named("full")
    }

    fn named(mut self, name: &str) -> Self {
        self.name = name.into();
        self
    }

    /// Every case, healthy ones included, in a fixed order.
    pub fn cases(&self) -> Vec<Case> {
        let mut cases = Vec::new();
        for (machine_index, machine) in self.machines.iter().enumerate() {
            for &speed in &self.speed_factors {
                let rpm = machine.nominal_rpm * speed;
                for &noise in &self.noise {
                    for fault in SimulatedFault::ALL {
                        let (severities, repeats) = if fault == SimulatedFault::None {
                            (vec![0.0], self.healthy_repeats)
                        } else {
                            (self.severities.clone(), 1)
                        };
                        for severity in severities {
                            for repeat in 0..repeats {
                                let mut case = Case {
                                    fault,
                                    machine: machine_index,
                                    bearing: machine.bearing.name.clone(),
                                    rpm,
                                    severity,
                                    noise,
                                    repeat,
                                    seed: 0,
                                };
                                case.seed = case.derive_seed("", self.seed);
                                cases.push(case);
                            }
                        }
                    }
                }
            }
        }
        cases
    }
}

/// One simulated record of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Case {
    pub fault: SimulatedFault,
    /// Index into [`Sweep::machines`].
    pub machine: usize,
    pub bearing: String,
    pub rpm: f64,
    /// Impact amplitude, g (0 for healthy records).
    pub severity: f64,
    pub noise: NoiseLevel,
    /// Which of a healthy case's repeats.
    pub repeat: usize,
    pub seed: u64,
}

impl Case {
    /// FNV-1a over the sweep seed and the case's coordinates: stable across builds, orders
    /// and thread counts. `stream` keeps the seeds of another use of the same coordinates
    /// apart from the sweep's ("" for the sweep).
    pub(super) fn derive_seed(&self, stream: &str, sweep_seed: u64) -> u64 {
        let key = format!(
            "{stream}{sweep_seed}|{}|{}|{}|{}|{}|{}",
            self.fault.name(),
            self.bearing,
            self.rpm.to_bits(),
            self.severity.to_bits(),
            self.noise.label(),
            self.repeat
        );
        key.bytes().fold(0xcbf2_9ce4_8422_2325, |hash, b| {
            (hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_depend_on_the_case_not_its_position() {
        let quick = Sweep::quick(7).cases();
        let full = Sweep::full(7).cases();
        let shared = quick
            .iter()
            .filter(|c| full.iter().any(|f| f == *c))
            .count();
        assert!(
            shared >= 8,
            "only {shared} quick cases found in the full sweep"
        );
        let mut seeds: Vec<u64> = full.iter().map(|c| c.seed).collect();
        seeds.sort_unstable();
        seeds.dedup();
        assert_eq!(seeds.len(), full.len(), "two cases share a seed");
        assert_ne!(Sweep::quick(8).cases()[0].seed, quick[0].seed);
    }

    #[test]
    fn full_sweep_holds_every_fault_and_healthy_runs() {
        let cases = Sweep::full(1).cases();
        for fault in SimulatedFault::ALL {
            assert!(cases.iter().any(|c| c.fault == fault), "{fault:?} missing");
        }
        // 3 machines × 2 speeds × 7 noise levels × (4 faults × 3 severities + 3 healthy).
        assert_eq!(cases.len(), 3 * 2 * 7 * (4 * 3 + 3));
    }
}
