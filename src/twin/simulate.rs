//! The signal model of a localized bearing defect (MODELS.md §4, after McFadden & Smith):
//! a train of impacts, each ringing at a resonance `f_n` and decaying at rate `B`, scaled by
//! the Stribeck load distribution at the defect's angle, with slip jitter, an optional entry
//! and exit impact for a defect of finite length, and white noise.
//!
//! It is the one simulator of the project: `bearingd simulate`, `analyze --demo`, the
//! firmware simulator and the daemon's embedded default all draw from [`Simulator`], which
//! produces the signal block by block (so a sensor can stream it for months) and is
//! deterministic for a given seed.

use super::rng::Rng;
use crate::bearing::{BearingGeometry, FaultFrequencies, Race};
use crate::messages::FaultKind;
use serde::{Deserialize, Serialize};

/// Which defect the simulated bearing has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SimulatedFault {
    None,
    OuterRace,
    InnerRace,
    Ball,
}

impl SimulatedFault {
    pub fn kind(self) -> Option<FaultKind> {
        match self {
            SimulatedFault::None => None,
            SimulatedFault::OuterRace => Some(FaultKind::OuterRace),
            SimulatedFault::InnerRace => Some(FaultKind::InnerRace),
            SimulatedFault::Ball => Some(FaultKind::Ball),
        }
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
            SimulatedFault::None => 0.0,
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
    /// the shaft on the inner race, with the cage for a ball.
    pub fn defect_angle(&self, t: f64) -> f64 {
        let f = self.frequencies();
        match self.fault {
            SimulatedFault::InnerRace => std::f64::consts::TAU * f.shaft * t,
            SimulatedFault::Ball => std::f64::consts::TAU * f.ftf * t,
            SimulatedFault::OuterRace | SimulatedFault::None => 0.0,
        }
    }

    /// Fault amplitude factor at time `t` (onset and ramp).
    fn growth_at(&self, t: f64) -> f64 {
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
    next_sample: u64,
    next_impact_index: u64,
    ringing: Vec<Impact>,
    /// Time after which an impact's ringing is below e⁻¹² of its start, s.
    ring_time_s: f64,
}

impl Simulator {
    pub fn new(params: SimulationParams) -> Self {
        let ring_time_s = 12.0 / params.decay_per_s.max(1.0);
        Simulator {
            noise_rng: Rng::new(params.seed),
            jitter_rng: Rng::new(params.seed ^ 0x5EED_0F11_77E5),
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
        for (i, o) in out.iter_mut().enumerate() {
            let t = block_start_s + i as f64 / fs;
            let mut x = p.noise_g * self.noise_rng.normal();
            x += p.shaft_tone_g * (std::f64::consts::TAU * shaft_hz * t).sin();
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
        let rate = self.params.impact_rate_hz();
        if rate <= 0.0 {
            return;
        }
        let period = 1.0 / rate;
        let delay = self.params.entry_exit_delay_s();
        loop {
            let nominal = self.next_impact_index as f64 * period;
            if nominal > end_s + period {
                break;
            }
            let time_s = nominal + self.params.jitter * period * self.jitter_rng.normal();
            self.next_impact_index += 1;
            let amplitude = self.params.amplitude_g
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
