//! [`PhysicsModel`]: the 6-DOF model integrated in time and sampled like a real sensor.
//!
//! Integration: the adaptive Dormand–Prince 5(4) method of the `ode_solvers` crate (error
//! control per step, 4th-order dense output), run chunk by chunk so that memory stays bounded on
//! records of any length. Why adaptive: the contact is stiff and non-smooth (Hertz contacts
//! opening and closing, a defect edge every pass); error control shortens the steps exactly
//! where that happens and lengthens them elsewhere, instead of paying everywhere for the worst
//! moment. Why explicit: the sensor signal *is* the fastest mode (the resonator), so it must be
//! resolved anyway; an implicit method's large stable steps would buy nothing. Two limits on
//! the step: the largest step is half the time a ball takes to cross the defect (so that no
//! step can jump over it: at least two of the method's stages fall inside), and the
//! stiffness detector of the crate is off (the resonator keeps the steps near the stability
//! limit on purpose). Accuracy against tolerance and against a fixed-step reference:
//! docs/PHYSICS.md.
//!
//! Sampling: like a real acquisition chain, the resonator's acceleration is taken at `M·fs`
//! (dense output), low-pass filtered (windowed sinc, Blackman, passband to 0.4·fs, −74 dB
//! from 0.5·fs) and decimated to `fs`. Without that filter the default 15 kHz resonance would
//! alias to 3 kHz at 12 kHz sampling and fake a resonance in the CWRU band. The filter is
//! zero-phase (the integration runs ahead by half its length), so sample `n` is the signal at
//! `n/fs`. Then white noise is added.

use super::dynamics::{Dynamics, State};
use super::params::{PhysicsError, PhysicsParams};
use crate::random::Rng;
use ode_solvers::dop_shared::IntegrationError;
use ode_solvers::{Dopri5, OutputType, System};

/// Standard gravity, m/s² per g.
const STANDARD_GRAVITY: f64 = 9.80665;
/// Fine (oversampled) points integrated per chunk.
const CHUNK_FINE_SAMPLES: usize = 4096;
/// Filter taps per unit of oversampling: the transition band is 0.1·fs wide.
const TAPS_PER_OVERSAMPLE: usize = 56;

/// Each chunk is integrated this many fine samples past its last output point, and the next
/// chunk starts from the dense output at that point. Why: `ode_solvers` 0.6.2 adds a point at
/// `x_end` whenever the next dense-output time falls within 10⁻⁹ of it, also when the current
/// step ended *before* `x_end`; that point is then extrapolated from the step (θ > 1) and can
/// be far off (found by the energy test: the last state of a conservative run jumped by 100
/// times the energy of the motion). Ending the integration half a sample later keeps every
/// output point strictly inside an accepted step.
const PAST_THE_END: f64 = 0.5;

/// Counters of the integration, for the documentation and the benchmark.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IntegrationStats {
    /// Right-hand-side evaluations.
    pub evaluations: u64,
    pub accepted_steps: u64,
    pub rejected_steps: u64,
}

/// The adapter `ode_solvers` calls.
struct Rhs<'a>(&'a Dynamics);

impl System<f64, State> for Rhs<'_> {
    fn system(&self, t: f64, y: &State, dy: &mut State) {
        self.0.rhs(t, y, dy);
    }
}

/// The physics twin, streaming: [`PhysicsModel::fill`] writes the next samples of the sensor
/// signal in g. Deterministic: the same parameters (seed included) give the same samples
/// however the record is cut into blocks.
pub struct PhysicsModel {
    params: PhysicsParams,
    dynamics: Dynamics,
    state: State,
    /// Oversampling factor `M` of the integration's output.
    oversample: usize,
    fine_dt: f64,
    max_step_s: f64,
    atol: f64,
    /// Fine samples (m/s²) from index `fine_base` (negative: the rest before t = 0); index
    /// `i` is time `i·fine_dt`.
    fine: Vec<f64>,
    fine_base: i64,
    /// Index of the last fine sample integrated (the state's time).
    fine_done: u64,
    taps: Vec<f64>,
    noise: Rng,
    next_sample: u64,
    stats: IntegrationStats,
}

impl PhysicsModel {
    /// Validates the parameters and puts the bearing at rest under its load.
    pub fn new(params: PhysicsParams) -> Result<Self, PhysicsError> {
        params.validate()?;
        let dynamics = Dynamics::new(&params);
        let state = dynamics.equilibrium();
        if !state.iter().all(|v| v.is_finite()) {
            return Err(PhysicsError::Integration {
                time_s: 0.0,
                reason: "no static equilibrium under the load".into(),
            });
        }
        let top_hz = dynamics.highest_mode_rad_s() / std::f64::consts::TAU;
        // Content up to twice the highest mode must not fold back below fs/2 through the
        // filter: (M − ½)·fs > 2·f_top.
        let oversample = ((2.0 * top_hz / params.fs_hz + 0.5).ceil() as usize).clamp(2, 64);
        let fine_dt = 1.0 / (params.fs_hz * oversample as f64);
        let max_step_s = (dynamics.defect_transit_s() / 2.0).min(8.0 * fine_dt);
        let taps = lowpass_taps(oversample);
        let half = taps.len() / 2;
        let mut fine = Vec::with_capacity(CHUNK_FINE_SAMPLES + taps.len());
        // Before t = 0 the bearing rests: zero acceleration.
        fine.resize(half, 0.0);
        fine.push(dynamics.sensor_acceleration(&state));
        Ok(PhysicsModel {
            noise: Rng::new(params.seed),
            atol: params.tolerance * 1e-3,
            params,
            dynamics,
            state,
            oversample,
            fine_dt,
            max_step_s,
            fine,
            fine_base: -(half as i64),
            fine_done: 0,
            taps,
            next_sample: 0,
            stats: IntegrationStats::default(),
        })
    }

    pub fn params(&self) -> &PhysicsParams {
        &self.params
    }

    /// Index of the next sample [`Self::fill`] writes.
    pub fn next_sample(&self) -> u64 {
        self.next_sample
    }

    /// The integrator's counters so far.
    pub fn stats(&self) -> IntegrationStats {
        self.stats
    }

    /// The oversampling factor of the integration's output.
    pub fn oversample(&self) -> usize {
        self.oversample
    }

    /// Writes the next `out.len()` samples of the sensor signal (the resonator's vertical
    /// acceleration plus noise), g.
    pub fn fill(&mut self, out: &mut [f32]) -> Result<(), PhysicsError> {
        let half = (self.taps.len() / 2) as i64;
        let m = self.oversample as i64;
        for o in out.iter_mut() {
            let centre = self.next_sample as i64 * m;
            while (self.fine_done as i64) < centre + half {
                self.integrate_chunk()?;
            }
            let first = (centre - half - self.fine_base) as usize;
            let window = &self.fine[first..first + self.taps.len()];
            let filtered: f64 = window.iter().zip(&self.taps).map(|(x, h)| x * h).sum();
            let noise = self.params.noise_g * self.noise.normal();
            *o = (filtered / STANDARD_GRAVITY + noise) as f32;
            self.next_sample += 1;
        }
        // Forget the fine samples no later output needs.
        let keep_from = self.next_sample as i64 * m - half;
        let drop = (keep_from - self.fine_base).max(0) as usize;
        if drop > 0 && drop <= self.fine.len() {
            self.fine.drain(..drop);
            self.fine_base = keep_from;
        }
        Ok(())
    }

    /// Integrates the next chunk of fine samples and appends their accelerations.
    fn integrate_chunk(&mut self) -> Result<(), PhysicsError> {
        let start = self.fine_done;
        let count = CHUNK_FINE_SAMPLES as u64;
        let t0 = start as f64 * self.fine_dt;
        let t1 = (start + count) as f64 * self.fine_dt;
        // Half a fine sample past t1: see [`PAST_THE_END`].
        let t_end = t1 + PAST_THE_END * self.fine_dt;
        self.dynamics.slip.extend(t0, t_end);
        let rtol = self.params.tolerance;
        let mut solver = Dopri5::from_param(
            Rhs(&self.dynamics),
            t0,
            t_end,
            self.fine_dt,
            self.state,
            rtol,
            self.atol,
            0.9,
            0.04,
            0.2,
            10.0,
            self.max_step_s,
            0.0,
            (count as u32).saturating_mul(2_000),
            u32::MAX,
            OutputType::Dense,
        );
        let stats = solver.integrate().map_err(|e| PhysicsError::Integration {
            time_s: match e {
                IntegrationError::MaxNumStepReached { x, .. }
                | IntegrationError::StepSizeUnderflow { x }
                | IntegrationError::StiffnessDetected { x } => x,
            },
            reason: e.to_string(),
        })?;
        self.stats.evaluations += u64::from(stats.num_eval);
        self.stats.accepted_steps += u64::from(stats.accepted_steps);
        self.stats.rejected_steps += u64::from(stats.rejected_steps);
        let states = solver.y_out();
        if states.len() < count as usize + 1 {
            return Err(PhysicsError::Integration {
                time_s: t1,
                reason: format!(
                    "the dense output gave {} of {} points",
                    states.len(),
                    count + 1
                ),
            });
        }
        let last = states[count as usize];
        if !last.iter().all(|v| v.is_finite()) {
            return Err(PhysicsError::Integration {
                time_s: t1,
                reason: "the state is no longer finite".into(),
            });
        }
        for y in &states[1..=count as usize] {
            self.fine.push(self.dynamics.sensor_acceleration(y));
        }
        self.state = last;
        self.fine_done = start + count;
        Ok(())
    }
}

/// Zero-phase low-pass FIR for decimation by `oversample`: windowed sinc (Blackman) with its
/// −6 dB point at 0.45·fs, unit gain at DC, odd length.
fn lowpass_taps(oversample: usize) -> Vec<f64> {
    let len = TAPS_PER_OVERSAMPLE * oversample + 1;
    let centre = (len / 2) as f64;
    let cutoff = 0.45 / oversample as f64; // cycles per fine sample
    let mut taps: Vec<f64> = (0..len)
        .map(|k| {
            let x = k as f64 - centre;
            let sinc = if x == 0.0 {
                2.0 * cutoff
            } else {
                (std::f64::consts::TAU * cutoff * x).sin() / (std::f64::consts::PI * x)
            };
            let phase = std::f64::consts::TAU * k as f64 / (len - 1) as f64;
            let blackman = 0.42 - 0.5 * phase.cos() + 0.08 * (2.0 * phase).cos();
            sinc * blackman
        })
        .collect();
    let sum: f64 = taps.iter().sum();
    for t in &mut taps {
        *t /= sum;
    }
    taps
}

/// The whole record `params` describes (`params.samples()` samples at `params.fs_hz`), g.
pub fn simulate(params: &PhysicsParams) -> Result<Vec<f32>, PhysicsError> {
    let mut model = PhysicsModel::new(params.clone())?;
    let mut out = vec![0f32; params.samples()];
    model.fill(&mut out)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::twin::physics::Dof;
    use crate::twin::SimulatedFault;

    /// Integrates `dynamics` from `y0` for `seconds` and returns the states every 0.1 ms.
    fn trajectory(dynamics: &Dynamics, y0: State, seconds: f64, tolerance: f64) -> Vec<State> {
        let mut solver = Dopri5::from_param(
            Rhs(dynamics),
            0.0,
            seconds + PAST_THE_END * 1e-4,
            1e-4,
            y0,
            tolerance,
            tolerance * 1e-3,
            0.9,
            0.04,
            0.2,
            10.0,
            1e-4,
            0.0,
            u32::MAX,
            u32::MAX,
            OutputType::Dense,
        );
        solver.integrate().unwrap();
        solver.y_out().clone()
    }

    /// A bearing under load, its shaft and resonator knocked out of equilibrium.
    fn knocked(dynamics: &Dynamics) -> State {
        let mut y0 = dynamics.equilibrium();
        y0[7] += 0.5; // shaft: 5 mm/s (velocity states are v/Ω_ref in µm)
        y0[11] += 0.01; // resonator relative to the housing: 0.1 mm/s
        y0[4] += 1e-3; // horizontal resonator: 1 nm
        y0
    }

    #[test]
    fn energy_is_conserved_without_damping_or_rotation() {
        for fault in [SimulatedFault::None, SimulatedFault::OuterRace] {
            let dynamics =
                Dynamics::new(&PhysicsParams::cwru(fault).unwrap()).without_damping_or_rotation();
            let rest = dynamics.energy(0.0, &dynamics.equilibrium());
            let states = trajectory(&dynamics, knocked(&dynamics), 0.05, 1e-10);
            let start = dynamics.energy(0.0, &states[0]) - rest;
            assert!(start > 0.0);
            let worst = states
                .iter()
                .map(|y| ((dynamics.energy(0.0, y) - rest) / start - 1.0).abs())
                .fold(0.0, f64::max);
            // The knock's energy, 10⁻⁵ J, against a static energy of 10⁻² J: a relative drift
            // of 10⁻⁴ of the knock is 10⁻⁷ of the total, near what f64 resolves here.
            assert!(
                worst < 1e-4,
                "{fault:?}: energy drift {worst:e} of the knock"
            );
        }
    }

    #[test]
    fn damping_only_takes_energy_away() {
        let mut dynamics = Dynamics::new(&PhysicsParams::cwru(SimulatedFault::None).unwrap());
        // Damped but standing still: no work from rotating contacts.
        let damped = dynamics.clone();
        dynamics = dynamics.without_damping_or_rotation();
        let mut still = damped.with_rotation_of(&dynamics);
        still.slip = dynamics.slip.clone();
        let rest = still.energy(0.0, &still.equilibrium());
        let states = trajectory(&still, knocked(&still), 0.05, 1e-9);
        let energies: Vec<f64> = states.iter().map(|y| still.energy(0.0, y) - rest).collect();
        for pair in energies.windows(2) {
            assert!(pair[1] <= pair[0] * (1.0 + 1e-9), "{pair:?}");
        }
        assert!(energies[energies.len() - 1] < 0.01 * energies[0]);
    }

    #[test]
    fn the_record_does_not_depend_on_how_it_is_cut_into_blocks() {
        let mut params = PhysicsParams::cwru(SimulatedFault::InnerRace).unwrap();
        params.duration_s = 0.3;
        params.noise_g = 0.01;
        params.slip = 0.01;
        let whole = simulate(&params).unwrap();
        let mut model = PhysicsModel::new(params).unwrap();
        let mut pieces = Vec::new();
        for len in [1, 999, 17, 2000, 583].iter().cycle().take(30) {
            let mut block = vec![0f32; *len];
            model.fill(&mut block).unwrap();
            pieces.extend(block);
            if pieces.len() >= whole.len() {
                break;
            }
        }
        assert_eq!(&pieces[..whole.len()], &whole[..]);
    }

    #[test]
    fn unusable_parameters_are_errors_not_panics() {
        let mut params = PhysicsParams::cwru(SimulatedFault::Ball).unwrap();
        params.structure.contact_stiffness = f64::INFINITY;
        assert!(matches!(
            simulate(&params),
            Err(PhysicsError::Invalid { .. })
        ));
    }

    /// CWRU's bearing at 1797 rpm with the resonator moved to 3.2 kHz (inside the 12 kHz
    /// band, where CWRU's drive-end resonance is), `seconds` long.
    fn in_band(fault: SimulatedFault, dof: Dof, seconds: f64) -> PhysicsParams {
        let mut params = PhysicsParams::cwru(fault).unwrap();
        params.dof = dof;
        params.duration_s = seconds;
        let s = &mut params.structure;
        s.resonator_stiffness = s.resonator_mass_kg * (std::f64::consts::TAU * 3_200.0f64).powi(2);
        s.resonator_damping = 2.0 * 0.05 * (s.resonator_stiffness * s.resonator_mass_kg).sqrt();
        params
    }

    /// The strongest envelope line between `lo` and `hi` Hz (band 2–4.5 kHz, one window over
    /// the whole signal): its frequency refined by a parabola through the peak bin and its
    /// neighbours (log amplitude), and its amplitude.
    fn envelope_peak(signal: &[f32], fs: f64, lo: f64, hi: f64) -> (f64, f64) {
        use crate::analysis::band::Band;
        use crate::analysis::envelope::{welch_envelope_spectrum, FftPlans};
        let window = signal.len();
        let bins = (hi * window as f64 / fs) as usize + 2;
        let spectrum = welch_envelope_spectrum(
            &mut FftPlans::default(),
            signal,
            fs,
            Band::new(2_000.0, 4_500.0),
            window,
            0.0,
            bins,
        );
        let a = &spectrum.amplitude;
        let first = (lo / spectrum.bin_hz).ceil() as usize;
        let last = ((hi / spectrum.bin_hz) as usize).min(a.len() - 2);
        let k = (first..=last)
            .max_by(|&i, &j| a[i].total_cmp(&a[j]))
            .unwrap();
        let (l, c, r) = (
            f64::from(a[k - 1]).ln(),
            f64::from(a[k]).ln(),
            f64::from(a[k + 1]).ln(),
        );
        let offset = 0.5 * (l - r) / (l - 2.0 * c + r);
        ((k as f64 + offset) * spectrum.bin_hz, f64::from(a[k]))
    }

    /// Issue 14's first check: the output's fault lines sit where the kinematics put them.
    #[test]
    fn fault_lines_match_the_kinematic_frequencies_within_one_percent() {
        let freqs = PhysicsParams::cwru(SimulatedFault::None)
            .unwrap()
            .bearing
            .fault_frequencies(1797.0 / 60.0);
        for (fault, dof, expected) in [
            (SimulatedFault::OuterRace, Dof::Six, freqs.bpfo),
            (SimulatedFault::OuterRace, Dof::Five, freqs.bpfo),
            (SimulatedFault::InnerRace, Dof::Six, freqs.bpfi),
            (SimulatedFault::Ball, Dof::Six, freqs.two_bsf),
        ] {
            let params = in_band(fault, dof, 4.0);
            let signal = simulate(&params).unwrap();
            assert!(signal.iter().all(|x| x.is_finite()));
            let (found, _) = envelope_peak(&signal, params.fs_hz, 0.8 * expected, 1.2 * expected);
            let error = found / expected - 1.0;
            assert!(
                error.abs() < 0.01,
                "{fault:?} {dof:?}: line at {found:.2} Hz, kinematics {expected:.2} Hz ({:+.2} %)",
                100.0 * error
            );
        }
    }

    /// Issue 14's healthy check: without a defect the only thing that changes in time is where
    /// the balls stand, which repeats every ball pass; all the vibration is at multiples of
    /// BPFO (the varying-compliance vibration), nothing at the shaft rate, BPFI or 2×BSF.
    #[test]
    fn a_healthy_bearing_vibrates_at_the_ball_pass_frequency_only() {
        let params = in_band(SimulatedFault::None, Dof::Six, 2.5);
        let signal = simulate(&params).unwrap();
        // Skip the first 0.5 s (the start from the t = 0 equilibrium rings briefly).
        let steady = &signal[6_000..];
        let n = steady.len();
        let mean = steady.iter().map(|&x| f64::from(x)).sum::<f64>() / n as f64;
        let bpfo = params.bearing.fault_frequencies(params.rpm / 60.0).bpfo;
        let bin_hz = params.fs_hz / n as f64;
        // Hann-windowed power spectrum by direct DFT of the bins we need would be slow; use
        // the FFT.
        let mut buffer: Vec<rustfft::num_complex::Complex64> = steady
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                let w = 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos();
                rustfft::num_complex::Complex64::new((f64::from(x) - mean) * w, 0.0)
            })
            .collect();
        rustfft::FftPlanner::new()
            .plan_fft_forward(n)
            .process(&mut buffer);
        let power: Vec<f64> = buffer[..n / 2].iter().map(|c| c.norm_sqr()).collect();
        let total: f64 = power[(20.0 / bin_hz) as usize..].iter().sum();
        let near_harmonic = |k: usize| {
            let f = k as f64 * bin_hz;
            let nearest = (f / bpfo).round() * bpfo;
            nearest > 0.0 && (f - nearest).abs() <= 3.0 * bin_hz
        };
        let harmonic: f64 = (0..power.len())
            .filter(|&k| k as f64 * bin_hz >= 20.0 && near_harmonic(k))
            .map(|k| power[k])
            .sum();
        assert!(total > 0.0);
        assert!(
            harmonic / total > 0.999,
            "{:.5} of the power at multiples of BPFO",
            harmonic / total
        );
        let freqs = params.bearing.fault_frequencies(params.rpm / 60.0);
        for (name, f) in [
            ("shaft", freqs.shaft),
            ("BPFI", freqs.bpfi),
            ("2xBSF", freqs.two_bsf),
        ] {
            let k = (f / bin_hz).round() as usize;
            let line: f64 = power[k - 2..=k + 2].iter().sum();
            let bpfo_line: f64 = {
                let b = (bpfo / bin_hz).round() as usize;
                power[b - 2..=b + 2].iter().sum()
            };
            assert!(
                line < 1e-6 * bpfo_line,
                "{name}: {line:e} vs BPFO {bpfo_line:e}"
            );
        }
    }

    /// An inner-race defect turns with the shaft through the load zone: its impacts are
    /// strong in the zone and weak out of it, so the envelope shows sidebands at BPFI ± the
    /// shaft rate; an outer-race defect sits still and has none.
    #[test]
    fn an_inner_race_defect_is_modulated_by_the_load_zone() {
        let freqs = PhysicsParams::cwru(SimulatedFault::None)
            .unwrap()
            .bearing
            .fault_frequencies(1797.0 / 60.0);
        let sideband_ratio = |fault: SimulatedFault, line: f64| {
            let params = in_band(fault, Dof::Six, 4.0);
            let signal = simulate(&params).unwrap();
            let (_, centre) = envelope_peak(&signal, params.fs_hz, line - 2.0, line + 2.0);
            let lower = line - freqs.shaft;
            let (_, side) = envelope_peak(&signal, params.fs_hz, lower - 2.0, lower + 2.0);
            side / centre
        };
        let inner = sideband_ratio(SimulatedFault::InnerRace, freqs.bpfi);
        let outer = sideband_ratio(SimulatedFault::OuterRace, freqs.bpfo);
        assert!(inner > 0.2, "inner race: sideband {inner:.3} of the line");
        assert!(outer < 0.02, "outer race: sideband {outer:.3} of the line");
    }

    #[test]
    fn lowpass_passes_the_band_and_stops_the_alias() {
        let taps = lowpass_taps(4);
        let gain = |f_over_fs: f64| {
            let w = std::f64::consts::TAU * f_over_fs / 4.0;
            let centre = (taps.len() / 2) as f64;
            let (re, im) = taps
                .iter()
                .enumerate()
                .fold((0.0, 0.0), |(re, im), (k, h)| {
                    let a = w * (k as f64 - centre);
                    (re + h * a.cos(), im + h * a.sin())
                });
            (re * re + im * im).sqrt()
        };
        for f in [0.0, 0.1, 0.3, 0.4] {
            assert!((gain(f) - 1.0).abs() < 0.01, "passband {f}: {}", gain(f));
        }
        for f in [0.55, 0.75, 1.0, 1.5, 1.9] {
            assert!(gain(f) < 1e-3, "stopband {f}: {}", gain(f));
        }
    }
}
