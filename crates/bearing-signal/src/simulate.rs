//! The signal model of a localized bearing defect (MODELS.md §4, after McFadden & Smith):
//! a train of impacts, each ringing at a resonance `f_n` and decaying at rate `B`, scaled by
//! the Stribeck load distribution at the defect's angle, with slip jitter, an optional entry
//! and exit impact for a defect of finite length, and white noise.
//!
//! A damaged cage (a cracked bar or a worn pocket) has no race defect to strike: the ball in
//! the damaged pocket is free to lead and lag, so once per cage revolution, where it is loaded,
//! it knocks the cage (an impact at FTF, less regular than a race spall: triple jitter and a
//! varying strength), and while loaded it rubs the broken bar (broadband noise gated by the
//! load on that pocket, so its level is FTF-periodic).
//!
//! [`Nuisance`] adds what a real machine adds and a detector must not take for a fault: shaft
//! harmonics (looseness, misalignment), noise whose level follows the shaft angle, random
//! impulses that repeat at no rate (debris, electrical spikes, knocks from elsewhere), a gear
//! mesh tone modulated by its shaft, an electrical tone, and optionally a fault of the machine
//! itself (unbalance, misalignment, looseness: [`crate::machine_fault`]). Each draws from its
//! own random stream: with [`Nuisance::none`] the signal is exactly what it was without it.
//!
//! It is the one simulator of the project: `bearingd simulate`, `analyze --demo`, the
//! firmware simulator and the daemon's embedded default all draw from [`Simulator`], which
//! produces the signal block by block (so a sensor can stream it for months) and is
//! deterministic for a given seed.

use crate::bearing::{BearingGeometry, FaultFrequencies, FaultKind, Race};
use crate::machine_fault::{MachineFault, MachineVibration};
use crate::random::Rng;
use serde::{Deserialize, Serialize};

/// Which defect the simulated bearing has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SimulatedFault {
    None,
    OuterRace,
    InnerRace,
    Ball,
    Cage,
}

impl SimulatedFault {
    /// Every simulated condition, healthy first.
    pub const ALL: [SimulatedFault; 5] = [
        SimulatedFault::None,
        SimulatedFault::OuterRace,
        SimulatedFault::InnerRace,
        SimulatedFault::Ball,
        SimulatedFault::Cage,
    ];

    /// The simulated fault of a fault kind.
    pub fn of(kind: FaultKind) -> Self {
        match kind {
            FaultKind::OuterRace => SimulatedFault::OuterRace,
            FaultKind::InnerRace => SimulatedFault::InnerRace,
            FaultKind::Ball => SimulatedFault::Ball,
            FaultKind::Cage => SimulatedFault::Cage,
        }
    }

    /// `none`, or the fault kind's name.
    pub fn name(self) -> &'static str {
        self.kind().map_or("none", FaultKind::name)
    }

    pub fn kind(self) -> Option<FaultKind> {
        match self {
            SimulatedFault::None => None,
            SimulatedFault::OuterRace => Some(FaultKind::OuterRace),
            SimulatedFault::InnerRace => Some(FaultKind::InnerRace),
            SimulatedFault::Ball => Some(FaultKind::Ball),
            SimulatedFault::Cage => Some(FaultKind::Cage),
        }
    }
}

/// What a real machine adds to a bearing's signal that is not a bearing fault. All levels in g;
/// 0 switches a part off.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Nuisance {
    /// Amplitude of the shaft harmonics 2× … `shaft_harmonic_count`×, the k-th at `1/k` of it
    /// (the 1× line is [`SimulationParams::shaft_tone_g`]).
    pub shaft_harmonics_g: f64,
    pub shaft_harmonic_count: u32,
    /// Standard deviation of a second, shaft-modulated noise: `g · (1 + depth·cos 2π fr t) · n(t)`.
    pub modulated_noise_g: f64,
    pub modulation_depth: f64,
    /// Mean rate of random impulses (Poisson arrivals, no period), per second, and their mean
    /// amplitude (exponentially distributed); they ring at the same resonance as the fault.
    pub random_impulses_per_s: f64,
    pub random_impulse_g: f64,
    /// A gear mesh at `gear_teeth` × the shaft rate, amplitude-modulated by the shaft (depth
    /// 0.5), of amplitude `gear_mesh_g`.
    pub gear_teeth: u32,
    pub gear_mesh_g: f64,
    /// An electrical tone (e.g. twice the line frequency) at a fixed frequency.
    pub electrical_hz: f64,
    pub electrical_g: f64,
    /// A fault of the machine, not of the bearing: unbalance, misalignment or looseness at
    /// shaft orders (see [`crate::machine_fault`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machine_fault: Option<MachineFault>,
}

impl Nuisance {
    /// Nothing but the bearing, the 1× tone and white noise.
    pub fn none() -> Self {
        Nuisance {
            shaft_harmonics_g: 0.0,
            shaft_harmonic_count: 0,
            modulated_noise_g: 0.0,
            modulation_depth: 0.0,
            random_impulses_per_s: 0.0,
            random_impulse_g: 0.0,
            gear_teeth: 0,
            gear_mesh_g: 0.0,
            electrical_hz: 0.0,
            electrical_g: 0.0,
            machine_fault: None,
        }
    }

    /// (choice) A machine in fair condition: shaft harmonics to 6× at 0.1 g, a shaft-modulated
    /// noise of 0.1 g (depth 0.5), one random impulse every 2 s of 1.5 g mean (larger than
    /// the fault's own impacts: a kurtosis-based band choice is tempted), a 23-tooth gear mesh
    /// at 0.2 g and a 100 Hz electrical tone at 0.1 g.
    pub fn typical() -> Self {
        Nuisance {
            shaft_harmonics_g: 0.1,
            shaft_harmonic_count: 6,
            modulated_noise_g: 0.1,
            modulation_depth: 0.5,
            random_impulses_per_s: 0.5,
            random_impulse_g: 1.5,
            gear_teeth: 23,
            gear_mesh_g: 0.2,
            electrical_hz: 100.0,
            electrical_g: 0.1,
            machine_fault: None,
        }
    }

    fn is_none(&self) -> bool {
        *self == Nuisance::none()
    }
}

/// Everything that defines a simulated record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimulationParams {
    pub fault: SimulatedFault,
    pub rpm: f64,
    pub bearing: BearingGeometry,
    pub fs_hz: f64,
    /// Impact amplitude `a` at full load, in g.
    pub amplitude_g: f64,
    /// Decay rate `B` of each impact's ringing, 1/s.
    pub decay_per_s: f64,
    /// Structural resonance `f_n` excited by the impacts, Hz.
    pub resonance_hz: f64,
    /// Stribeck load-distribution factor ε (0.5: half the bearing loaded).
    pub load_zone: f64,
    /// Stribeck exponent n (3/2 ball bearings, 10/9 roller bearings).
    pub load_exponent: f64,
    /// Standard deviation of the impact-time jitter, as a fraction of the impact period.
    pub jitter: f64,
    /// Defect length in mm; above 0, each impact splits into entry and exit.
    pub defect_length_mm: f64,
    /// Standard deviation of the additive white noise, g.
    pub noise_g: f64,
    /// Amplitude of a once-per-revolution (imbalance) tone, g.
    pub shaft_tone_g: f64,
    /// What else the machine adds (see [`Nuisance`]).
    pub nuisance: Nuisance,
    /// The fault starts at this time (s) and grows linearly to full amplitude over `ramp_s`.
    pub onset_s: f64,
    pub ramp_s: f64,
    pub seed: u64,
}

impl SimulationParams {
    /// A typical CWRU-like outer-race case: SKF 6205-2RS at 1772 rpm, 12 kHz, resonance 3 kHz.
    #[allow(
        clippy::expect_used,
        reason = "a catalog entry; the catalog tests check it exists"
    )]
    pub fn example(fault: SimulatedFault) -> Self {
        SimulationParams {
            fault,
            rpm: 1772.0,
            bearing: BearingGeometry::from_catalog("skf-6205-2rs").expect("catalog entry"),
            fs_hz: 12_000.0,
            amplitude_g: 1.0,
            decay_per_s: 800.0,
            resonance_hz: 3_000.0,
            load_zone: 0.5,
            load_exponent: 1.5,
            jitter: 0.01,
            defect_length_mm: 0.0,
            noise_g: 0.2,
            shaft_tone_g: 0.05,
            // Off: the twin-fit, speed-estimation and monitor tests (tests/suite/twin.rs,
            // speed.rs, monitor.rs) check exact behaviour on this clean signal, and fail with
            // the typical nuisance on. `bearingd evaluate` turns it on.
            nuisance: Nuisance::none(),
            onset_s: 0.0,
            ramp_s: 0.0,
            seed: 1,
        }
    }

    pub fn frequencies(&self) -> FaultFrequencies {
        self.bearing.fault_frequencies(self.rpm / 60.0)
    }

    /// The impact rate `f_d` of the simulated fault (0 without a fault).
    pub fn impact_rate_hz(&self) -> f64 {
        self.fault
            .kind()
            .map_or(0.0, |k| k.frequency(&self.frequencies()))
    }

    /// Time between the entry and the exit impact of a defect of finite length:
    /// `Δt = Z·L / (2π r f_d)`, `r` the radius the rolling element runs on.
    pub fn entry_exit_delay_s(&self) -> f64 {
        let f_d = self.impact_rate_hz();
        if self.defect_length_mm <= 0.0 || f_d <= 0.0 {
            return 0.0;
        }
        let g = &self.bearing;
        match self.fault {
            SimulatedFault::OuterRace => {
                g.entry_exit_delay_s(Race::Outer, self.defect_length_mm, f_d)
            }
            SimulatedFault::InnerRace => {
                g.entry_exit_delay_s(Race::Inner, self.defect_length_mm, f_d)
            }
            // A ball defect runs on the ball's own radius.
            SimulatedFault::Ball => {
                f64::from(g.rolling_elements) * self.defect_length_mm
                    / (std::f64::consts::TAU * g.element_diameter_mm / 2.0 * f_d)
            }
            // A cage defect has no length the rolling element runs over.
            SimulatedFault::None | SimulatedFault::Cage => 0.0,
        }
    }

    /// Stribeck load `q(θ)/q_max` at angle θ from the load line.
    pub fn load_at(&self, theta: f64) -> f64 {
        let inner = 1.0 - (1.0 - theta.cos()) / (2.0 * self.load_zone);
        if inner > 0.0 {
            inner.powf(self.load_exponent)
        } else {
            0.0
        }
    }

    /// The defect's angle from the load line at time `t`: fixed on the outer race, turning with
    /// the shaft on the inner race, with the cage for a ball or a damaged cage pocket (which
    /// is on the load line at `t = 0` and at every cage revolution after).
    pub fn defect_angle(&self, t: f64) -> f64 {
        let f = self.frequencies();
        match self.fault {
            SimulatedFault::InnerRace => std::f64::consts::TAU * f.shaft * t,
            SimulatedFault::Ball | SimulatedFault::Cage => std::f64::consts::TAU * f.ftf * t,
            SimulatedFault::OuterRace | SimulatedFault::None => 0.0,
        }
    }

    /// Fault amplitude factor at time `t` (onset and ramp).
    pub fn growth_at(&self, t: f64) -> f64 {
        if t < self.onset_s {
            0.0
        } else if self.ramp_s <= 0.0 {
            1.0
        } else {
            ((t - self.onset_s) / self.ramp_s).min(1.0)
        }
    }
}

/// One impact still ringing.
#[derive(Debug, Clone, Copy)]
struct Impact {
    time_s: f64,
    amplitude: f64,
}

/// Streams a simulated record block by block.
pub struct Simulator {
    params: SimulationParams,
    /// Separate streams for the noise and the impact jitter, so that the signal does not
    /// depend on how it is cut into blocks.
    noise_rng: Rng,
    jitter_rng: Rng,
    /// Streams of the parts added later (cage, nuisance), each its own, so that a signal
    /// without them is the same as before they existed, and block cuts still do not matter.
    cage_knock_rng: Rng,
    cage_rub_rng: Rng,
    modulated_noise_rng: Rng,
    random_impulse_rng: Rng,
    /// Time of the next random impulse, s (infinite without them).
    next_random_impulse_s: f64,
    /// Phase of each shaft harmonic 2×, 3×, …, rad.
    harmonic_phases: Vec<f64>,
    /// The machine fault's lines, if the nuisance has one.
    machine: Option<MachineVibration>,
    next_sample: u64,
    next_impact_index: u64,
    ringing: Vec<Impact>,
    /// Time after which an impact's ringing is below e⁻¹² of its start, s.
    ring_time_s: f64,
}

/// (choice) Rubbing noise of a damaged cage pocket under full load, relative to the impact
/// amplitude `a`.
const CAGE_RUB: f64 = 0.3;

impl Simulator {
    pub fn new(params: SimulationParams) -> Self {
        let ring_time_s = 12.0 / params.decay_per_s.max(1.0);
        let seed = params.seed;
        let mut random_impulse_rng = Rng::new(seed ^ 0x1A7E_5EED_0B5E);
        let next_random_impulse_s = next_arrival(
            0.0,
            params.nuisance.random_impulses_per_s,
            &mut random_impulse_rng,
        );
        let mut phase_rng = Rng::new(seed ^ 0x0DD_4A7E_D1CE);
        let harmonic_phases = (2..=params.nuisance.shaft_harmonic_count)
            .map(|_| std::f64::consts::TAU * phase_rng.uniform())
            .collect();
        let machine = params
            .nuisance
            .machine_fault
            .map(|fault| MachineVibration::new(&fault, seed));
        Simulator {
            machine,
            noise_rng: Rng::new(seed),
            jitter_rng: Rng::new(seed ^ 0x5EED_0F11_77E5),
            cage_knock_rng: Rng::new(seed ^ 0xCA6E_0000_C0C0),
            cage_rub_rng: Rng::new(seed ^ 0xCA6E_0000_2B2B),
            modulated_noise_rng: Rng::new(seed ^ 0x5AF7_0000_AAAA),
            random_impulse_rng,
            next_random_impulse_s,
            harmonic_phases,
            params,
            next_sample: 0,
            next_impact_index: 0,
            ringing: Vec::with_capacity(64),
            ring_time_s,
        }
    }

    pub fn params(&self) -> &SimulationParams {
        &self.params
    }

    /// Index of the next sample [`Self::fill`] will produce.
    pub fn next_sample(&self) -> u64 {
        self.next_sample
    }

    /// Writes the next `out.len()` samples (g).
    pub fn fill(&mut self, out: &mut [f32]) {
        if out.is_empty() {
            return;
        }
        let fs = self.params.fs_hz;
        let block_start_s = self.next_sample as f64 / fs;
        let block_end_s = (self.next_sample + out.len() as u64) as f64 / fs;
        self.schedule_impacts_until(block_end_s);
        let p = &self.params;
        let shaft_hz = p.rpm / 60.0;
        let with_nuisance = !p.nuisance.is_none();
        let cage = p.fault == SimulatedFault::Cage;
        for (i, o) in out.iter_mut().enumerate() {
            let t = block_start_s + i as f64 / fs;
            let mut x = p.noise_g * self.noise_rng.normal();
            x += p.shaft_tone_g * (std::f64::consts::TAU * shaft_hz * t).sin();
            if with_nuisance {
                x += nuisance_at(
                    &p.nuisance,
                    &self.harmonic_phases,
                    shaft_hz,
                    t,
                    &mut self.modulated_noise_rng,
                );
            }
            if let Some(machine) = &self.machine {
                x += machine.at(shaft_hz, t);
            }
            if cage {
                let level =
                    CAGE_RUB * p.amplitude_g * p.load_at(p.defect_angle(t)) * p.growth_at(t);
                if level > 0.0 {
                    x += level * self.cage_rub_rng.normal();
                }
            }
            *o = x as f32;
        }
        let omega = std::f64::consts::TAU * p.resonance_hz;
        for impact in &self.ringing {
            let first = ((impact.time_s * fs).ceil() as u64).max(self.next_sample);
            let last = (((impact.time_s + self.ring_time_s) * fs).floor() as u64)
                .min(self.next_sample + out.len() as u64 - 1);
            if first > last {
                continue;
            }
            for n in first..=last {
                let tau = n as f64 / fs - impact.time_s;
                out[(n - self.next_sample) as usize] +=
                    (impact.amplitude * (-p.decay_per_s * tau).exp() * (omega * tau).sin()) as f32;
            }
        }
        self.next_sample += out.len() as u64;
        let keep_after = block_end_s - self.ring_time_s;
        self.ringing.retain(|impact| impact.time_s > keep_after);
    }

    /// Convenience: `seconds` of signal from the start.
    pub fn record(params: SimulationParams, seconds: f64) -> Vec<f32> {
        let mut sim = Simulator::new(params);
        let mut out = vec![0.0; (seconds * sim.params.fs_hz).round() as usize];
        sim.fill(&mut out);
        out
    }

    fn schedule_impacts_until(&mut self, end_s: f64) {
        while self.next_random_impulse_s <= end_s {
            let time_s = self.next_random_impulse_s;
            // Exponentially distributed strength around the mean.
            let amplitude =
                -self.params.nuisance.random_impulse_g * self.random_impulse_rng.uniform().ln();
            self.ringing.push(Impact { time_s, amplitude });
            self.next_random_impulse_s = next_arrival(
                time_s,
                self.params.nuisance.random_impulses_per_s,
                &mut self.random_impulse_rng,
            );
        }
        let rate = self.params.impact_rate_hz();
        if rate <= 0.0 {
            return;
        }
        let period = 1.0 / rate;
        let delay = self.params.entry_exit_delay_s();
        let cage = self.params.fault == SimulatedFault::Cage;
        // A loose ball knocks its cage less regularly than a spall is struck.
        let jitter = if cage {
            3.0 * self.params.jitter
        } else {
            self.params.jitter
        };
        loop {
            let nominal = self.next_impact_index as f64 * period;
            if nominal > end_s + period {
                break;
            }
            let time_s = nominal + jitter * period * self.jitter_rng.normal();
            self.next_impact_index += 1;
            let strength = if cage {
                0.7 + 0.6 * self.cage_knock_rng.uniform()
            } else {
                1.0
            };
            let amplitude = strength
                * self.params.amplitude_g
                * self.params.load_at(self.params.defect_angle(time_s))
                * self.params.growth_at(time_s);
            if amplitude <= 0.0 {
                continue;
            }
            self.ringing.push(Impact { time_s, amplitude });
            if delay > 0.0 {
                self.ringing.push(Impact {
                    time_s: time_s + delay,
                    amplitude,
                });
            }
        }
    }
}

/// The next arrival of a Poisson process of `rate` per second after `after_s` (never without
/// a rate).
fn next_arrival(after_s: f64, rate: f64, rng: &mut Rng) -> f64 {
    if rate > 0.0 {
        after_s - rng.uniform().ln() / rate
    } else {
        f64::INFINITY
    }
}

/// The nuisance signal at time `t`, g: shaft harmonics, shaft-modulated noise, gear mesh and
/// electrical tone (the random impulses ring with the impacts). A function of `t` alone (and of
/// the modulated-noise stream), so that block cuts do not change it.
fn nuisance_at(n: &Nuisance, harmonic_phases: &[f64], shaft_hz: f64, t: f64, rng: &mut Rng) -> f64 {
    use std::f64::consts::TAU;
    let shaft_angle = TAU * shaft_hz * t;
    let (sin1, cos1) = shaft_angle.sin_cos();
    let mut x = 0.0;
    if n.shaft_harmonics_g > 0.0 {
        // e^{ikθ} by repeated multiplication with e^{iθ}: one sin_cos for every harmonic.
        let (mut sin_k, mut cos_k) = (sin1, cos1);
        for (i, phase) in harmonic_phases.iter().enumerate() {
            (sin_k, cos_k) = (sin_k * cos1 + cos_k * sin1, cos_k * cos1 - sin_k * sin1);
            let k = (i + 2) as f64;
            x += n.shaft_harmonics_g / k * (sin_k * phase.cos() + cos_k * phase.sin());
        }
    }
    if n.modulated_noise_g > 0.0 {
        x += n.modulated_noise_g * (1.0 + n.modulation_depth * cos1) * rng.normal();
    }
    if n.gear_mesh_g > 0.0 && n.gear_teeth > 0 {
        x += n.gear_mesh_g * (1.0 + 0.5 * cos1) * (f64::from(n.gear_teeth) * shaft_angle).sin();
    }
    if n.electrical_g > 0.0 {
        x += n.electrical_g * (TAU * n.electrical_hz * t).sin();
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(fault: SimulatedFault, nuisance: Nuisance) -> SimulationParams {
        SimulationParams {
            nuisance,
            ..SimulationParams::example(fault)
        }
    }

    #[test]
    fn cage_and_nuisance_do_not_depend_on_block_cuts_and_follow_the_seed() {
        let params = with(SimulatedFault::Cage, Nuisance::typical());
        let whole = Simulator::record(params.clone(), 3.0);
        let mut sim = Simulator::new(params.clone());
        let mut pieces = Vec::new();
        for len in [1, 999, 4096, 7, 12_000, 100].iter().cycle() {
            if pieces.len() >= whole.len() {
                break;
            }
            let mut block = vec![0.0; (*len).min(whole.len() - pieces.len())];
            sim.fill(&mut block);
            pieces.extend(block);
        }
        assert_eq!(whole, pieces);
        let again = Simulator::record(params.clone(), 3.0);
        assert_eq!(whole, again);
        let other = Simulator::record(SimulationParams { seed: 9, ..params }, 3.0);
        assert_ne!(whole, other);
    }

    #[test]
    fn without_nuisance_the_older_parts_are_unchanged_by_it() {
        // The nuisance draws from its own streams: taking it away leaves the rest bit for bit.
        let clean = Simulator::record(with(SimulatedFault::InnerRace, Nuisance::none()), 2.0);
        let noisy = Simulator::record(with(SimulatedFault::InnerRace, Nuisance::typical()), 2.0);
        let only_nuisance = Simulator::record(
            SimulationParams {
                fault: SimulatedFault::None,
                noise_g: 0.0,
                shaft_tone_g: 0.0,
                ..with(SimulatedFault::InnerRace, Nuisance::typical())
            },
            2.0,
        );
        let worst = clean
            .iter()
            .zip(&noisy)
            .zip(&only_nuisance)
            .map(|((c, n), o)| (n - c - o).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-4, "signal ≠ clean + nuisance by {worst}");
        let nuisance_rms =
            (only_nuisance.iter().map(|x| x * x).sum::<f32>() / only_nuisance.len() as f32).sqrt();
        assert!(nuisance_rms > 0.1, "nuisance RMS {nuisance_rms}");
    }
}
