//! The twin's squared-envelope spectrum in closed form (MODELS.md §4), on the same bins and in
//! the same units as the measured Welch spectrum ([`crate::analysis::envelope`]).
//!
//! Why closed form: a fit evaluates the twin hundreds of times; simulating the time signal and
//! transforming it each time costs milliseconds per evaluation, the expression below costs
//! microseconds.
//!
//! The derivation, for impacts `a·q_k` at `t_k = k·T + τ_k` (Gaussian jitter of standard
//! deviation `σ`), each ringing as `e^{−Bt}·sin(2π f_n t)`, band-passed to `[lo, hi]`:
//!
//! - one impact's squared analytic envelope `p(t) = |g(t)|²` has the transform
//!   `P(f) = ∫ G(ν+f) G*(ν) dν` over the band, which with `G(ν) = 1/(i(B + i2π(ν − f_n)))`
//!   integrates to
//!   `P(f) = [ln(B + i2π(u+f)) − ln(B − i2πu)]_{u=lo−f_n}^{hi−f−f_n} / (i2π (2B + i2πf))`
//!   (`1/(2B + i2πf)` when the band holds the whole resonance);
//! - the load `q(θ)` of the defect's angle, squared, has Fourier coefficients `Q_l` over the
//!   modulation (the shaft for an inner race, the cage for a ball, none for an outer race), so
//!   the envelope has lines at `m·f_d + l·f_mod` of amplitude `2·a²·f_d·|Q_l·P(f)|`, reduced by
//!   the jitter's `e^{−(2πfσ)²/2}`; each line is spread over the bins by the Hann window's kernel;
//! - the power the jitter takes from the lines becomes a continuum of two-sided density
//!   `f_d·a⁴·mean(Q²)·|P(f)|²·(1 − e^{−(2πfσ)²})`, which a Hann-windowed Welch bin sees as
//!   `6·Δf` times the density;
//! - the band's noise adds a floor shaped like its own autocorrelation, `1 − f/bandwidth`.
//!
//! So the twin's power spectrum is `a⁴·U(f; f_d, B, f_n, σ) + c·N(f)`: linear in `a⁴` and the
//! noise level `c`, non-linear in the rest. [`EnvelopeModel::basis`] computes `U` and `N`.

use crate::analysis::Band;
use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;
use rustfft::num_complex::Complex64;
use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

/// The shape parameters of the twin (everything but the amplitude and the noise level).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ShapeParams {
    /// Impact rate `f_d` in Hz (the fault frequency including slip).
    pub impact_rate_hz: f64,
    /// Decay rate `B`, 1/s.
    pub decay_per_s: f64,
    /// Resonance `f_n`, Hz.
    pub resonance_hz: f64,
    /// Jitter standard deviation as a fraction of the impact period.
    pub jitter: f64,
}

/// Harmonics of the load modulation kept (`l = −L..=L`).
const MODULATION_ORDERS: i32 = 8;
/// Bins on each side of a line that its Hann kernel reaches.
const KERNEL_HALF_WIDTH: i32 = 3;

/// Load zone ε of the Stribeck distribution the twin assumes (MODELS.md §4; not fitted).
pub const LOAD_ZONE: f64 = 0.5;
/// Load exponent n of that distribution (3/2 for ball bearings).
pub const LOAD_EXPONENT: f64 = 1.5;

/// Everything about one fault hypothesis that does not change during a fit.
#[derive(Debug, Clone)]
pub struct EnvelopeModel {
    pub fault: FaultKind,
    pub band: Band,
    pub bin_hz: f64,
    pub bins: usize,
    /// Frequency of the load modulation (0 for an outer race).
    modulation_hz: f64,
    load: &'static LoadSpectrum,
    /// Per bin, where it falls on the coarse grid of `|P(f)|²`: the grid interval and the
    /// fraction into it (the grid spans the model's bins, so this is fixed per model).
    grid_position: Vec<(usize, f64)>,
    /// The noise shape `N` per bin (fixed per model).
    noise_shape: Vec<f64>,
    /// `|P(f)|²` on the coarse grid for the last decay and resonance asked for.
    grid: TransformGrid,
    /// Where the last impact rate's lines fall and how their Hann kernels spread them.
    lines: LineLayout,
}

/// `|P(f)|²` at the points of the coarse grid, for one decay and resonance. The impact-rate
/// scans keep both fixed, so they reuse it.
#[derive(Debug, Clone)]
struct TransformGrid {
    /// `(decay, resonance)` the values belong to (NaN before the first use).
    key: (f64, f64),
    values: [f64; GRID_POINTS + 1],
}

/// The lines `m·f_d + l·f_mod` of one impact rate with their Hann kernels' weights on the
/// bins: they depend on `f_d` alone, and a Nelder–Mead search over the decay, the jitter and
/// the noise keeps `f_d` fixed for hundreds of evaluations, so the positions, sines and
/// kernels are computed once per impact rate instead of once per evaluation.
#[derive(Debug, Clone)]
struct LineLayout {
    /// The impact rate the lines belong to (NaN before the first use).
    impact_rate_hz: f64,
    lines: Vec<PlacedLine>,
}

/// One line: its frequency, the power of its load coefficient, and the weights of its Hann
/// kernel on the bins `first_bin ..` (at most `2·KERNEL_HALF_WIDTH + 1`, fewer at the edges).
#[derive(Debug, Clone, Copy)]
struct PlacedLine {
    f: f64,
    load_power: f64,
    first_bin: usize,
    taps: usize,
    weights: [f64; KERNEL_TAPS],
}

/// Bins a line's kernel can reach.
const KERNEL_TAPS: usize = 2 * KERNEL_HALF_WIDTH as usize + 1;

/// The squared load `q²` over the modulation, in Fourier coefficients: the same for every
/// model with (or every model without) a modulation, so computed once per process.
#[derive(Debug)]
struct LoadSpectrum {
    /// `Q_l` for `l = −L..=L` (index `l + L`).
    coefficients: Vec<Complex64>,
    /// Mean of `q⁴` over the modulation.
    fourth_moment: f64,
    /// Modulation orders that carry power (`|Q_l|² > 10⁻⁵·|Q_0|²`), at most [`MODULATION_ORDERS`].
    orders: i32,
}

impl LoadSpectrum {
    /// The load spectrum of a defect that moves through the load zone (`modulated`: inner
    /// race, ball) or stays on the load line (outer race).
    fn of(modulated: bool) -> &'static LoadSpectrum {
        static MODULATED: OnceLock<LoadSpectrum> = OnceLock::new();
        static FIXED: OnceLock<LoadSpectrum> = OnceLock::new();
        let cell = if modulated { &MODULATED } else { &FIXED };
        cell.get_or_init(|| LoadSpectrum::compute(modulated))
    }

    fn compute(modulated: bool) -> LoadSpectrum {
        const STEPS: usize = 360;
        let squared_load: Vec<f64> = (0..STEPS)
            .map(|i| {
                let theta = if modulated {
                    TAU * i as f64 / STEPS as f64
                } else {
                    0.0
                };
                stribeck_load(theta, LOAD_ZONE, LOAD_EXPONENT).powi(2)
            })
            .collect();
        let coefficients: Vec<Complex64> = (-MODULATION_ORDERS..=MODULATION_ORDERS)
            .map(|l| {
                squared_load
                    .iter()
                    .enumerate()
                    .map(|(i, &q2)| {
                        Complex64::from_polar(q2, -f64::from(l) * TAU * i as f64 / STEPS as f64)
                    })
                    .sum::<Complex64>()
                    / STEPS as f64
            })
            .collect();
        let fourth_moment = squared_load.iter().map(|q2| q2 * q2).sum::<f64>() / STEPS as f64;
        let coefficient_power = |l: i32| load_coefficients_power(&coefficients, l);
        let orders = if modulated {
            (1..=MODULATION_ORDERS)
                .rev()
                .find(|&l| coefficient_power(l) > 1e-5 * coefficient_power(0))
                .unwrap_or(0)
        } else {
            0
        };
        LoadSpectrum {
            coefficients,
            fourth_moment,
            orders,
        }
    }
}

/// Stribeck load `q(θ)/q_max` (MODELS.md §4).
pub fn stribeck_load(theta: f64, load_zone: f64, exponent: f64) -> f64 {
    let inner = 1.0 - (1.0 - theta.cos()) / (2.0 * load_zone);
    if inner > 0.0 {
        inner.powf(exponent)
    } else {
        0.0
    }
}

impl EnvelopeModel {
    /// The load follows the Stribeck distribution of [`LOAD_ZONE`] and [`LOAD_EXPONENT`]; the
    /// defect starts on the load line.
    pub fn new(
        fault: FaultKind,
        freqs: &FaultFrequencies,
        band: Band,
        bin_hz: f64,
        bins: usize,
    ) -> Self {
        let modulation_hz = match fault {
            FaultKind::InnerRace => freqs.shaft,
            FaultKind::Ball => freqs.ftf,
            FaultKind::OuterRace | FaultKind::Cage => 0.0,
        };
        let grid_per_bin = bin_hz / grid_step_hz(bins, bin_hz);
        let grid_position = (0..bins)
            .map(|k| {
                let x = k as f64 * grid_per_bin;
                let i = (x as usize).min(GRID_POINTS - 1);
                (i, x - i as f64)
            })
            .collect();
        let noise_per_bin = bin_hz / band.width_hz();
        let noise_shape = (0..bins)
            .map(|k| (1.0 - k as f64 * noise_per_bin).max(0.0))
            .collect();
        EnvelopeModel {
            fault,
            band,
            bin_hz,
            bins,
            modulation_hz,
            load: LoadSpectrum::of(modulation_hz > 0.0),
            grid_position,
            noise_shape,
            grid: TransformGrid {
                key: (f64::NAN, f64::NAN),
                values: [0.0; GRID_POINTS + 1],
            },
            lines: LineLayout {
                impact_rate_hz: f64::NAN,
                lines: Vec::new(),
            },
        }
    }

    /// Transform of one impact's squared band-limited envelope at envelope frequency `f`.
    pub fn impact_envelope_transform(&self, f: f64, decay: f64, resonance: f64) -> Complex64 {
        let u_low = self.band.lo_hz - resonance;
        let u_high = self.band.hi_hz - f - resonance;
        if u_high <= u_low {
            return Complex64::new(0.0, 0.0);
        }
        let alpha = Complex64::new(decay, TAU * f);
        let term = |u: f64| {
            (alpha + Complex64::new(0.0, TAU * u)).ln() - Complex64::new(decay, -TAU * u).ln()
        };
        (term(u_high) - term(u_low))
            / (Complex64::new(0.0, TAU) * Complex64::new(2.0 * decay, TAU * f))
    }

    /// `|T(f)|²` of [`Self::impact_envelope_transform`], which is all the basis needs, with one
    /// logarithm and two arctangents instead of four complex logarithms.
    ///
    /// With `A(u) = decay + i2π(f + u)` and `B(u) = decay − i2πu` the numerator is
    /// `ln A_h − ln B_h − ln A_l + ln B_l`: its real part is `½ ln(|A_h|²|B_l|² / (|B_h|²|A_l|²))`,
    /// its imaginary part `arg(A_h·conj A_l) − arg(B_h·conj B_l)`, exact without a 2π correction
    /// because every `A` and `B` has a positive real part (arguments in (−π/2, π/2)).
    pub fn impact_envelope_power(&self, f: f64, decay: f64, resonance: f64) -> f64 {
        let u_low = self.band.lo_hz - resonance;
        let u_high = self.band.hi_hz - f - resonance;
        if u_high <= u_low {
            return 0.0;
        }
        let a = |u: f64| Complex64::new(decay, TAU * (f + u));
        let b = |u: f64| Complex64::new(decay, -TAU * u);
        let (a_high, a_low, b_high, b_low) = (a(u_high), a(u_low), b(u_high), b(u_low));
        let real = 0.5
            * ((a_high.norm_sqr() * b_low.norm_sqr()) / (b_high.norm_sqr() * a_low.norm_sqr()))
                .ln();
        let imaginary = (a_high * a_low.conj()).arg() - (b_high * b_low.conj()).arg();
        let denominator = TAU * TAU * (4.0 * decay * decay + (TAU * f).powi(2));
        (real * real + imaginary * imaginary) / denominator
    }

    /// Writes the unit-amplitude twin spectrum `U` and the noise shape `N` into the two
    /// slices (`bins` values each, power per bin as in the Welch spectrum).
    ///
    /// `|P(f)|²` is smooth in `f` (its scale is the decay rate, hundreds of Hz), so it is
    /// evaluated on a coarse grid and interpolated; this keeps an evaluation at a few
    /// microseconds. The grid and the lines' kernels are kept between calls while the
    /// parameters they depend on stay the same (the values are those a fresh model gives).
    pub fn basis(&mut self, params: &ShapeParams, twin: &mut [f64], noise: &mut [f64]) {
        debug_assert!(twin.len() == self.bins && noise.len() == self.bins);
        twin.iter_mut().for_each(|v| *v = 0.0);
        let f_d = params.impact_rate_hz;
        let sigma_t = params.jitter / f_d.max(1e-9);
        let jitter_power = |f: f64| (-(TAU * f * sigma_t).powi(2)).exp();
        self.update_grid(params.decay_per_s, params.resonance_hz);
        self.update_lines(f_d);
        let grid = &self.grid.values;
        let grid_step = grid_step_hz(self.bins, self.bin_hz);
        let transform_power = |f: f64| {
            let x = (f / grid_step).clamp(0.0, GRID_POINTS as f64);
            let i = (x as usize).min(GRID_POINTS - 1);
            let t = x - i as f64;
            grid[i] * (1.0 - t) + grid[i + 1] * t
        };

        for line in &self.lines.lines {
            let power =
                4.0 * line.load_power * f_d * f_d * transform_power(line.f) * jitter_power(line.f);
            if let Some(bins) = twin.get_mut(line.first_bin..line.first_bin + line.taps) {
                for (slot, weight) in bins.iter_mut().zip(&line.weights) {
                    *slot += power * weight;
                }
            }
        }
        // The continuum the jitter makes.
        let continuum_scale = 6.0 * self.bin_hz * f_d * self.load.fourth_moment;
        // e^{−c·k²} by recurrence: e^{−c(k+1)²} = e^{−ck²}·e^{−c(2k+1)}.
        let c = (TAU * self.bin_hz * sigma_t).powi(2);
        let (mut gaussian, mut step, step_ratio) = (1.0, (-c).exp(), (-2.0 * c).exp());
        for (t, &(i, frac)) in twin.iter_mut().zip(&self.grid_position) {
            let transform = grid[i] + (grid[i + 1] - grid[i]) * frac;
            *t += continuum_scale * transform * (1.0 - gaussian);
            gaussian *= step;
            step *= step_ratio;
        }
        let shape = &self.noise_shape[..noise.len().min(self.noise_shape.len())];
        noise[..shape.len()].copy_from_slice(shape);
        twin[0] = 0.0;
    }

    /// `|P(f)|²` on the coarse grid for `decay` and `resonance`, unless it holds them already.
    fn update_grid(&mut self, decay: f64, resonance: f64) {
        if self.grid.key == (decay, resonance) {
            return;
        }
        let grid_step = grid_step_hz(self.bins, self.bin_hz);
        let mut values = [0f64; GRID_POINTS + 1];
        for (i, g) in values.iter_mut().enumerate() {
            *g = self.impact_envelope_power(i as f64 * grid_step, decay, resonance);
        }
        self.grid = TransformGrid {
            key: (decay, resonance),
            values,
        };
    }

    /// Places the lines of impact rate `f_d` on the model's bins, unless they are placed
    /// already.
    fn update_lines(&mut self, f_d: f64) {
        if self.lines.impact_rate_hz == f_d {
            return;
        }
        let top_hz = self.bins as f64 * self.bin_hz;
        let max_m = (top_hz / f_d).ceil() as i32 + 1;
        let orders = self.load.orders;
        self.lines.lines.clear();
        for m in 0..=max_m {
            for l in -orders..=orders {
                let f = f64::from(m) * f_d + f64::from(l) * self.modulation_hz;
                if f <= 0.5 * self.bin_hz || f >= top_hz {
                    continue;
                }
                let load_power = load_coefficients_power(&self.load.coefficients, l);
                if let Some(line) = place_line(f, load_power, self.bin_hz, self.bins) {
                    self.lines.lines.push(line);
                }
            }
        }
        self.lines.impact_rate_hz = f_d;
    }
}

/// A line of frequency `f` on `bins` bins of `bin_hz`: the bins its Hann kernel reaches (from
/// bin 1) and its weight on each. `sin(π(k − c))` has the same magnitude for every bin `k`, so
/// one sine serves the whole kernel. `None` when the kernel reaches no bin.
fn place_line(f: f64, load_power: f64, bin_hz: f64, bins: usize) -> Option<PlacedLine> {
    let centre = f / bin_hz;
    let nearest = centre.round();
    let sine = (PI * (centre - nearest)).sin().abs();
    let mut line = PlacedLine {
        f,
        load_power,
        first_bin: 0,
        taps: 0,
        weights: [0.0; KERNEL_TAPS],
    };
    for j in -KERNEL_HALF_WIDTH..=KERNEL_HALF_WIDTH {
        let k = nearest + f64::from(j);
        if k < 1.0 || k as usize >= bins {
            continue;
        }
        if line.taps == 0 {
            line.first_bin = k as usize;
        }
        line.weights[line.taps] = hann_kernel_with_sine(k - centre, sine);
        line.taps += 1;
    }
    (line.taps > 0).then_some(line)
}

fn load_coefficients_power(coefficients: &[Complex64], l: i32) -> f64 {
    coefficients[(l + MODULATION_ORDERS) as usize].norm_sqr()
}

/// Points of the coarse grid on which `|P(f)|²` is evaluated.
const GRID_POINTS: usize = 40;

/// The coarse grid's spacing for a model of `bins` bins of `bin_hz`: it spans the bins.
fn grid_step_hz(bins: usize, bin_hz: f64) -> f64 {
    bins as f64 * bin_hz / GRID_POINTS as f64
}

/// [`hann_kernel`] given `|sin(π δ)|`.
fn hann_kernel_with_sine(delta: f64, sine: f64) -> f64 {
    let d = delta.abs();
    if d < 1e-9 {
        return 1.0;
    }
    if (d - 1.0).abs() < 1e-9 {
        return 0.25;
    }
    (sine / (PI * d * (1.0 - d * d))).powi(2)
}

/// Power response of a periodic Hann window to a line `delta` bins away, normalised to 1 on
/// the line: `[sinc(δ)/(1 − δ²)]²`.
pub fn hann_kernel(delta: f64) -> f64 {
    hann_kernel_with_sine(delta, (PI * delta).sin().abs())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_band_transform_is_the_plain_exponential() {
        let freqs = crate::bearing::BearingGeometry::from_catalog("skf-6205-2rs")
            .unwrap()
            .fault_frequencies(29.5);
        let model = EnvelopeModel::new(FaultKind::OuterRace, &freqs, Band::new(-1e7, 1e7), 1.0, 10);
        for f in [0.0, 50.0, 500.0] {
            let p = model.impact_envelope_transform(f, 800.0, 3_000.0);
            let expected = Complex64::new(1.0, 0.0) / Complex64::new(1600.0, TAU * f);
            assert!(
                (p - expected).norm() < 1e-3 * expected.norm(),
                "{f}: {p} vs {expected}"
            );
        }
    }

    #[test]
    fn the_envelope_power_is_the_squared_transform() {
        let freqs = crate::bearing::BearingGeometry::from_catalog("skf-6205-2rs")
            .unwrap()
            .fault_frequencies(29.5);
        for band in [Band::new(2_000.0, 4_000.0), Band::new(500.0, 5_800.0)] {
            let model = EnvelopeModel::new(FaultKind::InnerRace, &freqs, band, 0.73, 800);
            for f in [0.0, 3.0, 87.0, 162.2, 590.0, 1_800.0, 3_900.0] {
                for decay in [60.0, 800.0, 4_000.0] {
                    for resonance in [1_000.0, 3_000.0, 5_000.0] {
                        let exact = model
                            .impact_envelope_transform(f, decay, resonance)
                            .norm_sqr();
                        let fast = model.impact_envelope_power(f, decay, resonance);
                        if exact == 0.0 {
                            assert_eq!(fast, 0.0);
                            continue;
                        }
                        let error = (fast - exact).abs() / exact;
                        assert!(error < 1e-9, "{f} {decay} {resonance}: {fast} vs {exact}");
                    }
                }
            }
        }
    }

    /// The grid and the lines kept between calls give what a fresh model gives, bit for bit,
    /// whichever parameters changed since (the fits compare errors to the last digit).
    #[test]
    fn a_reused_model_gives_a_fresh_models_basis() {
        let freqs = crate::bearing::BearingGeometry::from_catalog("skf-6205-2rs")
            .unwrap()
            .fault_frequencies(29.5);
        let band = Band::new(2_000.0, 4_500.0);
        let shape = |f_d: f64, decay: f64, resonance: f64, jitter: f64| ShapeParams {
            impact_rate_hz: f_d,
            decay_per_s: decay,
            resonance_hz: resonance,
            jitter,
        };
        let sequence = [
            shape(162.0, 800.0, 3_000.0, 0.01),
            shape(162.0, 800.0, 3_000.0, 0.02), // jitter only: grid and lines kept
            shape(162.0, 650.0, 3_000.0, 0.02), // decay: the grid changes
            shape(163.5, 650.0, 3_000.0, 0.02), // impact rate: the lines change
            shape(163.5, 650.0, 3_400.0, 0.02), // resonance: the grid changes
            shape(162.0, 800.0, 3_000.0, 0.01), // back to the first
        ];
        for fault in [FaultKind::OuterRace, FaultKind::InnerRace, FaultKind::Ball] {
            let bins = 900;
            let mut reused = EnvelopeModel::new(fault, &freqs, band, 1.83, bins);
            for params in &sequence {
                let (mut twin, mut noise) = (vec![0.0; bins], vec![0.0; bins]);
                reused.basis(params, &mut twin, &mut noise);
                let mut fresh = EnvelopeModel::new(fault, &freqs, band, 1.83, bins);
                let (mut twin_fresh, mut noise_fresh) = (vec![0.0; bins], vec![0.0; bins]);
                fresh.basis(params, &mut twin_fresh, &mut noise_fresh);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&twin), bits(&twin_fresh), "{fault:?} {params:?}");
                assert_eq!(bits(&noise), bits(&noise_fresh), "{fault:?} {params:?}");
                assert!(
                    twin.iter().any(|&t| t > 0.0),
                    "{fault:?}: an empty twin proves nothing"
                );
            }
        }
    }

    #[test]
    fn hann_kernel_values() {
        assert_eq!(hann_kernel(0.0), 1.0);
        assert!((hann_kernel(1.0) - 0.25).abs() < 1e-12);
        assert!((hann_kernel(0.999_999) - 0.25).abs() < 1e-5);
        assert!(hann_kernel(2.0) < 1e-12);
        assert!((hann_kernel(0.5) - (2.0 / PI / 0.75f64).powi(2)).abs() < 1e-12);
    }
}
