//! Machine faults that are not in the bearing: unbalance, misalignment and mechanical
//! looseness, as a condition monitor sees them in the velocity spectrum, at orders of the shaft
//! rate (ISO 13373-3 and the usual vibration-analysis charts):
//!
//! - **unbalance**: a once-per-revolution force, a 1× line and little else;
//! - **misalignment**: a 2× line as strong as 1× or stronger, with some 3× (the coupling
//!   bends twice per revolution);
//! - **looseness**: many running-speed harmonics decaying slowly, with half orders (0.5×,
//!   1.5×, …) from the part that lifts off and lands once every two revolutions.
//!
//! A pattern is given in **velocity** (what the charts and ISO 10816 speak of): the fault's
//! level is the RMS velocity of its 1× line, mm/s, and each order's line is a multiple of it.
//! The simulator turns each line into acceleration (`a = 2πf·v`) at its own random phase, so a
//! detector reading the velocity spectrum finds the chart's shape. Lines are pure tones: no
//! amplitude or phase wander (choice: the detector reads averaged spectra, a wander would
//! only widen the lines).

use crate::random::Rng;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Standard gravity, m/s² per g.
const G: f64 = 9.806_65;

/// Which machine fault.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MachineFaultKind {
    Unbalance,
    Misalignment,
    Looseness,
}

impl MachineFaultKind {
    pub const ALL: [MachineFaultKind; 3] = [
        MachineFaultKind::Unbalance,
        MachineFaultKind::Misalignment,
        MachineFaultKind::Looseness,
    ];

    pub fn name(self) -> &'static str {
        match self {
            MachineFaultKind::Unbalance => "unbalance",
            MachineFaultKind::Misalignment => "misalignment",
            MachineFaultKind::Looseness => "looseness",
        }
    }

    /// The kind of a name (as `name` gives it).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|kind| kind.name() == name)
    }

    /// The velocity lines of the pattern: (order of the shaft rate, RMS velocity relative to
    /// the 1× line). Choices, after the charts: misalignment's 2× at 1.5 of 1× and 3× at 0.5;
    /// looseness's integer orders 1…10 falling by 15 % per order and half orders 0.5…9.5 at
    /// 0.4 of their integer neighbour below.
    pub fn orders(self) -> Vec<(f64, f64)> {
        match self {
            MachineFaultKind::Unbalance => vec![(1.0, 1.0)],
            MachineFaultKind::Misalignment => vec![(1.0, 1.0), (2.0, 1.5), (3.0, 0.5)],
            MachineFaultKind::Looseness => {
                let integer = |k: u32| 0.85f64.powi(k as i32 - 1);
                let mut lines: Vec<(f64, f64)> =
                    (1..=10).map(|k| (f64::from(k), integer(k))).collect();
                lines.push((0.5, 0.4));
                lines.extend((1..=9).map(|k| (f64::from(k) + 0.5, 0.4 * integer(k))));
                lines
            }
        }
    }
}

/// A machine fault of a given strength.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MachineFault {
    pub kind: MachineFaultKind,
    /// RMS velocity of the 1× line, mm/s (ISO 10816-3 zone B/C for a group-2 machine on a
    /// rigid foundation is 2.8 mm/s for the whole band).
    pub velocity_mm_s: f64,
}

/// The tones of a machine fault at one shaft rate: amplitude (g, peak) and phase per order.
#[derive(Debug, Clone)]
pub struct MachineVibration {
    /// (order, peak acceleration per unit shaft rate, g/Hz, phase rad).
    lines: Vec<(f64, f64, f64)>,
}

impl MachineVibration {
    /// The fault's lines with phases from `seed` (their own stream: the rest of a simulated
    /// signal does not change with or without them).
    pub fn new(fault: &MachineFault, seed: u64) -> Self {
        let mut rng = Rng::new(seed ^ 0x3AC4_1E00_F417);
        let lines = fault
            .kind
            .orders()
            .into_iter()
            .map(|(order, relative)| {
                // Peak velocity √2·v_rms; a = 2πf·v, per Hz of shaft rate: 2π·order·v.
                let v_peak_m_s = std::f64::consts::SQRT_2 * relative * fault.velocity_mm_s / 1e3;
                let g_per_hz = std::f64::consts::TAU * order * v_peak_m_s / G;
                (order, g_per_hz, std::f64::consts::TAU * rng.uniform())
            })
            .collect();
        MachineVibration { lines }
    }

    /// The acceleration at time `t` (s), g, for a shaft at `shaft_hz`.
    pub fn at(&self, shaft_hz: f64, t: f64) -> f64 {
        let angle = std::f64::consts::TAU * shaft_hz * t;
        self.lines
            .iter()
            .map(|&(order, g_per_hz, phase)| g_per_hz * shaft_hz * (order * angle + phase).sin())
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The RMS velocity of the line at `order` in `x` (g samples at `fs`), mm/s: the
    /// acceleration's projection on the order's sine and cosine over whole revolutions.
    fn line_velocity_mm_s(x: &[f64], fs: f64, shaft_hz: f64, order: f64) -> f64 {
        let f = order * shaft_hz;
        let (mut s, mut c) = (0.0, 0.0);
        for (n, v) in x.iter().enumerate() {
            let phase = std::f64::consts::TAU * f * n as f64 / fs;
            s += v * phase.sin();
            c += v * phase.cos();
        }
        let peak_g = 2.0 * (s * s + c * c).sqrt() / x.len() as f64;
        peak_g * G / (std::f64::consts::TAU * f) / std::f64::consts::SQRT_2 * 1e3
    }

    #[test]
    fn each_pattern_has_the_charts_velocity_lines() {
        let (fs, shaft_hz) = (12_000.0, 30.0);
        // 20 whole revolutions of 2 (half orders need two revolutions to be periodic).
        let n = (40.0 / shaft_hz * fs) as usize;
        for kind in MachineFaultKind::ALL {
            let fault = MachineFault {
                kind,
                velocity_mm_s: 4.0,
            };
            let vib = MachineVibration::new(&fault, 7);
            let x: Vec<f64> = (0..n).map(|i| vib.at(shaft_hz, i as f64 / fs)).collect();
            for (order, relative) in kind.orders() {
                let v = line_velocity_mm_s(&x, fs, shaft_hz, order);
                assert!(
                    (v - 4.0 * relative).abs() < 0.01,
                    "{} at {order}×: {v:.3} mm/s, expected {:.3}",
                    kind.name(),
                    4.0 * relative
                );
            }
            // Nothing between the pattern's orders.
            let absent = line_velocity_mm_s(&x, fs, shaft_hz, 11.0);
            assert!(absent < 1e-3, "{} at 11×: {absent}", kind.name());
        }
    }

    #[test]
    fn the_shapes_differ_as_the_charts_say() {
        let orders = |kind: MachineFaultKind| kind.orders();
        assert_eq!(orders(MachineFaultKind::Unbalance), vec![(1.0, 1.0)]);
        let mis = orders(MachineFaultKind::Misalignment);
        assert!(mis.iter().any(|&(o, r)| o == 2.0 && r > 1.0));
        let loose = orders(MachineFaultKind::Looseness);
        assert!(loose.iter().filter(|(o, _)| o.fract() == 0.5).count() >= 5);
        assert!(loose.iter().filter(|(o, _)| o.fract() == 0.0).count() >= 8);
        for kind in MachineFaultKind::ALL {
            assert_eq!(MachineFaultKind::from_name(kind.name()), Some(kind));
        }
    }
}
