//! How fast a health indicator is getting worse, and when it will reach a threshold (issue 13
//! item 5): an exponential trend fitted over a sliding window, with a regression prediction
//! interval turned into an interval of threshold-crossing times.
//!
//! Why exponential: spall growth feeds on itself, so vibration RMS in the degradation stage
//! grows roughly exponentially (a straight line in `ln y`); fitting `ln y = a + b·t` by
//! ordinary least squares is the simplest model that captures it, and its textbook prediction
//! interval is an honest first statement of the uncertainty.
//!
//! The band at time `t` is `a + b·t ± q·s·√(1 + 1/n + (t − t̄)²/Sxx)` (Student-t quantile `q`
//! with `n − 2` degrees of freedom, `s` the residual standard deviation). The crossing time is
//! where the fit meets `ln threshold`; the earliest is where the upper band first does, the
//! latest where the lower band does. (Limits, said plainly: the residuals of successive
//! snapshots are correlated and the growth is not truly exponential, so the band is too narrow
//! when the indicator jumps; a step change that no trend announced cannot be foreseen.)
//!
//! Pure maths on `(time, value)` pairs: no clock, no I/O, no allocation beyond the result.

use serde::Serialize;

/// A trend fitted over a window, and the threshold crossing it predicts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TrendFit {
    /// Time of the newest point of the window (s).
    pub now_s: f64,
    /// Points fitted.
    pub points: usize,
    /// Growth rate of `ln value` per second (`b`).
    pub rate_per_s: f64,
    /// Time for the value to double at that rate; `None` when it is not growing.
    pub doubling_s: Option<f64>,
    /// The threshold the crossing is predicted for (the indicator's unit).
    pub threshold: f64,
    /// Two-sided coverage of the band, e.g. 0.9.
    pub confidence: f64,
    /// Predicted crossing times (absolute, s); `None`: not within the horizon.
    pub crossing_s: Option<f64>,
    pub earliest_s: Option<f64>,
    pub latest_s: Option<f64>,
    /// The latest time looked at (crossings later than this are `None`).
    pub horizon_s: f64,
    // The fit itself, for `band_at`.
    intercept: f64,
    mean_t: f64,
    sxx: f64,
    residual_std: f64,
    quantile: f64,
}

impl TrendFit {
    /// Fits `ln value` over `times` (seconds, increasing) and predicts when it reaches
    /// `threshold`, looking ahead up to `horizon_factor` × the window's span past its last
    /// point. `None` with fewer than 4 points, a non-positive value or threshold, or a
    /// window with no time span.
    pub fn fit(
        times: &[f64],
        values: &[f64],
        threshold: f64,
        confidence: f64,
        horizon_factor: f64,
    ) -> Option<TrendFit> {
        let n = times.len().min(values.len());
        if n < 4
            || !(threshold.is_finite() && threshold > 0.0)
            || values[..n].iter().any(|v| !(v.is_finite() && *v > 0.0))
            || times[..n].iter().any(|t| !t.is_finite())
        {
            return None;
        }
        let (times, logs): (&[f64], Vec<f64>) =
            (&times[..n], values[..n].iter().map(|v| v.ln()).collect());
        let nf = n as f64;
        let mean_t = times.iter().sum::<f64>() / nf;
        let mean_y = logs.iter().sum::<f64>() / nf;
        let sxx: f64 = times.iter().map(|t| (t - mean_t).powi(2)).sum();
        if sxx <= 0.0 || sxx.is_nan() {
            return None;
        }
        let sxy: f64 = times
            .iter()
            .zip(&logs)
            .map(|(t, y)| (t - mean_t) * (y - mean_y))
            .sum();
        let slope = sxy / sxx;
        let intercept = mean_y - slope * mean_t;
        let sse: f64 = times
            .iter()
            .zip(&logs)
            .map(|(t, y)| (y - intercept - slope * t).powi(2))
            .sum();
        let residual_std = (sse / (nf - 2.0)).sqrt();
        let confidence = confidence.clamp(0.5, 0.999);
        let now_s = times[n - 1];
        let span = now_s - times[0];
        let mut fit = TrendFit {
            now_s,
            points: n,
            rate_per_s: slope,
            doubling_s: (slope > 0.0).then(|| std::f64::consts::LN_2 / slope),
            threshold,
            confidence,
            crossing_s: None,
            earliest_s: None,
            latest_s: None,
            horizon_s: now_s + horizon_factor.max(0.0) * span,
            intercept,
            mean_t,
            sxx,
            residual_std,
            quantile: student_t_quantile(0.5 + confidence / 2.0, nf - 2.0),
        };
        let level = threshold.ln();
        fit.crossing_s = fit.first_time(|t| fit.log_band_at(t).0 >= level);
        fit.earliest_s = fit.first_time(|t| fit.log_band_at(t).2 >= level);
        fit.latest_s = fit.first_time(|t| fit.log_band_at(t).1 >= level);
        Some(fit)
    }

    /// Predicted time left until the crossing, from the newest point (s).
    pub fn time_to_threshold_s(&self) -> Option<f64> {
        self.crossing_s.map(|t| t - self.now_s)
    }

    /// (fit, lower, upper) of the indicator at time `t`, in its own unit.
    pub fn band_at(&self, t: f64) -> (f64, f64, f64) {
        let (fit, lo, hi) = self.log_band_at(t);
        (fit.exp(), lo.exp(), hi.exp())
    }

    fn log_band_at(&self, t: f64) -> (f64, f64, f64) {
        let fit = self.intercept + self.rate_per_s * t;
        let half = self.quantile
            * self.residual_std
            * (1.0 + 1.0 / self.points as f64 + (t - self.mean_t).powi(2) / self.sxx).sqrt();
        (fit, fit - half, fit + half)
    }

    /// The first time in `[now, horizon]` where `reached` holds, to 1/4096 of the look-ahead:
    /// a scan on a coarse grid, then bisection inside the step where it first holds.
    fn first_time(&self, reached: impl Fn(f64) -> bool) -> Option<f64> {
        if reached(self.now_s) {
            return Some(self.now_s);
        }
        let ahead = self.horizon_s - self.now_s;
        if ahead <= 0.0 || ahead.is_nan() {
            return None;
        }
        const STEPS: usize = 256;
        let step = ahead / STEPS as f64;
        let mut before = self.now_s;
        for i in 1..=STEPS {
            let after = self.now_s + step * i as f64;
            if reached(after) {
                let (mut lo, mut hi) = (before, after);
                for _ in 0..12 {
                    let mid = 0.5 * (lo + hi);
                    if reached(mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                return Some(hi);
            }
            before = after;
        }
        None
    }
}

/// The daemon's trend of RMS (issue 13 item 5, published with the health stage): the window
/// RMS values of each span of sample time become one point (their median, so a lone transient
/// does not move it), and the newest `max_points` points are fitted by [`TrendFit`] against
/// the failure limit once the bearing is degrading: the same fit `bearingd trend` draws.
///
/// Bounded and allocation-free per window: the span's values and the points live in buffers
/// sized at construction; only the fit itself, once per span while degrading, allocates.
#[derive(Debug, Clone)]
pub struct RmsTrend {
    span_samples: u64,
    fs_hz: f64,
    max_points: usize,
    confidence: f64,
    span: Vec<f64>,
    span_capacity: usize,
    span_ends_at: Option<u64>,
    times: std::collections::VecDeque<f64>,
    values: std::collections::VecDeque<f64>,
}

/// A new point of the trend.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrendPoint {
    pub end_sample: u64,
    /// The span's median window RMS.
    pub rms: f64,
    /// Points in the fit's window so far.
    pub points: usize,
    /// The fit and its threshold crossing; `None` without a threshold or with too few points.
    pub fit: Option<TrendFit>,
    /// Two-sided coverage of the fit's band.
    pub confidence: f64,
}

impl RmsTrend {
    /// One point per `span_s` of sample time at `fs_hz`, with at most `windows_per_span`
    /// windows in a span (more are ignored: the span's first ones are kept), the newest
    /// `max_points` points fitted with a band of two-sided coverage `confidence`.
    pub fn new(
        span_s: f64,
        fs_hz: f64,
        windows_per_span: usize,
        max_points: usize,
        confidence: f64,
    ) -> Self {
        let max_points = max_points.max(4);
        RmsTrend {
            span_samples: (span_s * fs_hz).round().max(1.0) as u64,
            fs_hz,
            max_points,
            confidence,
            span: Vec::with_capacity(windows_per_span.max(1)),
            span_capacity: windows_per_span.max(1),
            span_ends_at: None,
            times: std::collections::VecDeque::with_capacity(max_points),
            values: std::collections::VecDeque::with_capacity(max_points),
        }
    }

    /// One window's RMS ending at `end_sample`; a point when a span is complete. `threshold`:
    /// the RMS the crossing is predicted for (the failure limit), `None` before it is known.
    pub fn push(
        &mut self,
        rms: f64,
        end_sample: u64,
        threshold: Option<f64>,
    ) -> Option<TrendPoint> {
        let ends_at = *self
            .span_ends_at
            .get_or_insert(end_sample + self.span_samples);
        if rms.is_finite() && rms > 0.0 && self.span.len() < self.span_capacity {
            self.span.push(rms);
        }
        if end_sample < ends_at {
            return None;
        }
        self.span_ends_at = Some(end_sample + self.span_samples);
        if self.span.is_empty() {
            return None;
        }
        self.span.sort_unstable_by(f64::total_cmp);
        let mid = self.span.len() / 2;
        let median = if self.span.len() % 2 == 1 {
            self.span[mid]
        } else {
            0.5 * (self.span[mid - 1] + self.span[mid])
        };
        self.span.clear();
        if self.times.len() == self.max_points {
            self.times.pop_front();
            self.values.pop_front();
        }
        self.times.push_back(end_sample as f64 / self.fs_hz);
        self.values.push_back(median);
        let fit = threshold.and_then(|threshold| {
            TrendFit::fit(
                self.times.make_contiguous(),
                self.values.make_contiguous(),
                threshold,
                self.confidence,
                HORIZON_SPANS,
            )
        });
        Some(TrendPoint {
            end_sample,
            rms: median,
            points: self.times.len(),
            fit,
            confidence: self.confidence,
        })
    }
}

/// How far ahead of the newest point a crossing is looked for, in spans of the fitted window
/// (`bearingd trend` looks as far).
pub const HORIZON_SPANS: f64 = 10.0;

/// The `p` quantile of Student's t with `df` degrees of freedom (`p` in [0.5, 1)): the normal
/// quantile corrected by the Cornish–Fisher expansion (error below 1 % from 3 degrees of
/// freedom on, which is far below the uncertainty it describes).
pub fn student_t_quantile(p: f64, df: f64) -> f64 {
    let z = normal_quantile(p);
    let df = df.max(1.0);
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * df)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * df * df)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * df.powi(3))
}

/// The standard normal quantile (Acklam's rational approximation, relative error < 1.2e-9).
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383_577_518_672_69e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let p = p.clamp(1e-12, 1.0 - 1e-12);
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::RmsTrend;

    #[test]
    fn the_daemon_trend_makes_a_point_per_span_from_the_median_and_predicts_the_crossing() {
        // Windows every 0.5 s; RMS growing as e^{t/100}; one point per 10 s; limit 0.5 g.
        let fs = 1000.0;
        let mut trend = RmsTrend::new(10.0, fs, 22, 12, 0.9);
        let mut points = Vec::new();
        for w in 1..=300u64 {
            let t = w as f64 * 0.5;
            let mut rms = 0.1 * (t / 100.0).exp();
            if w % 7 == 0 {
                rms *= 50.0; // a lone transient: the median of its span drops it
            }
            let threshold = (t >= 60.0).then_some(0.5);
            points.extend(trend.push(rms, (t * fs) as u64, threshold));
        }
        assert_eq!(points.len(), 14, "one point per 10 s after the first span");
        assert!(points.iter().all(|p| p.points <= 12));
        for p in &points {
            let t = p.end_sample as f64 / fs;
            let expected = 0.1 * ((t - 5.0) / 100.0).exp();
            assert!((p.rms / expected - 1.0).abs() < 0.05, "{} at {t}", p.rms);
        }
        assert!(
            points.iter().take(5).all(|p| p.fit.is_none()),
            "no limit yet"
        );
        let last = points.last().unwrap().fit.unwrap();
        // ln(0.5/0.1)·100 + 5 ≈ 166 s: the crossing predicted within a few seconds.
        let crossing = last.crossing_s.unwrap();
        assert!((crossing - 166.0).abs() < 5.0, "{crossing}");
        assert!((last.rate_per_s - 0.01).abs() < 5e-4, "{}", last.rate_per_s);
    }

    use super::*;
    use crate::random::Rng;

    #[test]
    fn quantiles_match_the_tables() {
        assert!((normal_quantile(0.975) - 1.959964).abs() < 1e-6);
        assert!((normal_quantile(0.05) + 1.644854).abs() < 1e-6);
        // t tables: t(0.95, 10) = 1.812, t(0.975, 5) = 2.571, t(0.95, 30) = 1.697.
        assert!((student_t_quantile(0.95, 10.0) - 1.8125).abs() < 0.005);
        assert!((student_t_quantile(0.975, 5.0) - 2.5706).abs() < 0.03);
        assert!((student_t_quantile(0.95, 30.0) - 1.6973).abs() < 0.002);
    }

    /// `y = 0.3·exp(t/1000)` reaches 1.2 at `t = 1000·ln 4 = 1386.29 s`.
    const TRUE_CROSSING: f64 = 1_386.294_361;

    #[test]
    fn an_exact_exponential_crosses_where_it_should() {
        let times: Vec<f64> = (0..12).map(|i| f64::from(i) * 50.0).collect();
        let values: Vec<f64> = times.iter().map(|t| 0.3 * (t / 1000.0).exp()).collect();
        let fit = TrendFit::fit(&times, &values, 1.2, 0.9, 10.0).unwrap();
        assert!((fit.rate_per_s - 1e-3).abs() < 1e-12);
        assert!((fit.doubling_s.unwrap() - 693.147).abs() < 0.01);
        let crossing = fit.crossing_s.unwrap();
        assert!((crossing - TRUE_CROSSING).abs() < 0.5, "{crossing}");
        assert!((fit.time_to_threshold_s().unwrap() - (TRUE_CROSSING - 550.0)).abs() < 0.5);
        // No noise: the band has no width.
        assert!((fit.earliest_s.unwrap() - crossing).abs() < 0.5);
        assert!((fit.latest_s.unwrap() - crossing).abs() < 0.5);
    }

    #[test]
    fn a_noisy_exponential_brackets_the_true_crossing() {
        // 5 % multiplicative noise; over many seeds the 90 % band should hold the true
        // crossing most of the time and the estimate should be close on average.
        let mut covered = 0;
        let mut errors = Vec::new();
        for seed in 0..200u64 {
            let mut rng = Rng::new(seed);
            let times: Vec<f64> = (0..20).map(|i| f64::from(i) * 40.0).collect();
            let values: Vec<f64> = times
                .iter()
                .map(|t| 0.3 * (t / 1000.0 + 0.05 * rng.normal()).exp())
                .collect();
            let fit = TrendFit::fit(&times, &values, 1.2, 0.9, 10.0).unwrap();
            let (Some(lo), Some(hi), Some(mid)) = (fit.earliest_s, fit.latest_s, fit.crossing_s)
            else {
                continue;
            };
            assert!(lo <= mid && mid <= hi);
            if (lo..=hi).contains(&TRUE_CROSSING) {
                covered += 1;
            }
            errors.push(mid - TRUE_CROSSING);
        }
        assert!(errors.len() >= 190, "almost every fit predicts a crossing");
        let bias = errors.iter().sum::<f64>() / errors.len() as f64;
        assert!(bias.abs() < 40.0, "bias {bias} s");
        assert!(
            covered >= 150,
            "{covered} of 200 bands held the true crossing"
        );
    }

    #[test]
    fn a_flat_or_falling_indicator_predicts_no_crossing() {
        let times: Vec<f64> = (0..10).map(f64::from).collect();
        let flat = vec![0.5; 10];
        let fit = TrendFit::fit(&times, &flat, 1.0, 0.9, 10.0).unwrap();
        assert_eq!(fit.crossing_s, None);
        assert_eq!(fit.doubling_s, None);
        let falling: Vec<f64> = times.iter().map(|t| 1.0 - 0.05 * t).collect();
        assert_eq!(
            TrendFit::fit(&times, &falling, 2.0, 0.9, 10.0)
                .unwrap()
                .crossing_s,
            None
        );
    }

    #[test]
    fn already_above_the_threshold_is_now() {
        let times: Vec<f64> = (0..6).map(f64::from).collect();
        let values = vec![2.0, 2.1, 2.2, 2.3, 2.4, 2.5];
        let fit = TrendFit::fit(&times, &values, 1.0, 0.9, 10.0).unwrap();
        assert_eq!(fit.crossing_s, Some(5.0));
        assert_eq!(fit.time_to_threshold_s(), Some(0.0));
    }

    #[test]
    fn unusable_inputs_give_no_fit() {
        let t = [0.0, 1.0, 2.0, 3.0];
        assert!(TrendFit::fit(&t, &[1.0, 1.0, 0.0, 1.0], 2.0, 0.9, 10.0).is_none());
        assert!(TrendFit::fit(&t, &[1.0, 1.0, f64::NAN, 1.0], 2.0, 0.9, 10.0).is_none());
        assert!(TrendFit::fit(&t[..3], &[1.0, 1.0, 1.0], 2.0, 0.9, 10.0).is_none());
        assert!(TrendFit::fit(&[1.0; 4], &[1.0, 2.0, 3.0, 4.0], 2.0, 0.9, 10.0).is_none());
        assert!(TrendFit::fit(&t, &[1.0, 2.0, 3.0, 4.0], -1.0, 0.9, 10.0).is_none());
    }
}
