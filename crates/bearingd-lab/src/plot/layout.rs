//! Axis maths shared by both renderers: data ranges, "nice" 1-2-5 ticks, tick labels, the
//! data→pixel mapping (linear or logarithmic) and min/max decimation of long series.
//!
//! Everything here is pure arithmetic on `f64`; nothing panics on NaN, infinities, empty input
//! or reversed ranges.

/// How many decades below the largest value a logarithmic axis shows. Smaller values, zeros and
/// negatives are drawn on this floor.
pub const LOG_AXIS_DECADES: f64 = 6.0;

/// The largest magnitude an axis accepts; beyond it spans overflow.
const MAX_MAGNITUDE: f64 = 1e300;

/// The smallest and largest finite values, or `None` if there is none.
pub fn finite_range(values: impl IntoIterator<Item = f64>) -> Option<(f64, f64)> {
    values
        .into_iter()
        .filter(|v| v.is_finite() && v.abs() <= MAX_MAGNITUDE)
        .fold(None, |range, v| match range {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// A usable interval from a possibly degenerate one: finite, ordered, and of non-zero width.
pub fn sanitize_range(range: Option<(f64, f64)>) -> (f64, f64) {
    let Some((a, b)) = range else {
        return (0.0, 1.0);
    };
    if !a.is_finite() || !b.is_finite() || a.abs() > MAX_MAGNITUDE || b.abs() > MAX_MAGNITUDE {
        return (0.0, 1.0);
    }
    let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
    if hi - lo > f64::EPSILON * lo.abs().max(hi.abs()).max(1e-300) * 16.0 {
        (lo, hi)
    } else if lo == 0.0 {
        (0.0, 1.0)
    } else {
        let half = lo.abs() * 0.5;
        (lo - half, hi + half)
    }
}

/// A value axis: the visible data interval and whether it is logarithmic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axis {
    pub min: f64,
    pub max: f64,
    pub log: bool,
}

impl Axis {
    /// A linear axis over `range` (made usable by [`sanitize_range`]).
    pub fn linear(range: (f64, f64)) -> Self {
        let (min, max) = sanitize_range(Some(range));
        Axis {
            min,
            max,
            log: false,
        }
    }

    /// A linear axis for amplitudes: starts at zero for non-negative data and leaves 5 %
    /// headroom above the largest value.
    pub fn linear_for_data(data: Option<(f64, f64)>) -> Self {
        let (lo, hi) = match data {
            None => (0.0, 1.0),
            Some((lo, hi)) => (lo.min(0.0), hi.max(0.0)),
        };
        let (lo, hi) = sanitize_range(Some((lo, hi)));
        let pad = (hi - lo) * 0.05;
        let lo = if lo < 0.0 { lo - pad } else { lo };
        Axis::linear((lo, hi + pad))
    }

    /// A logarithmic axis for the positive part of `positive_data`, reaching down at most
    /// [`LOG_AXIS_DECADES`] below the largest value.
    pub fn log_for_data(positive_data: Option<(f64, f64)>) -> Self {
        let (lo, hi) = match positive_data {
            Some((lo, hi)) if hi > 0.0 && hi.is_finite() => {
                let floor = hi * 10f64.powf(-LOG_AXIS_DECADES);
                (lo.max(floor).max(f64::MIN_POSITIVE), hi)
            }
            _ => (1e-3, 1.0),
        };
        // A little headroom in log space; a single value gets a decade either side.
        let (lo, hi) = if hi / lo < 1.01 {
            (lo / 10.0, hi * 10.0)
        } else {
            let pad = (hi / lo).log10() * 0.05;
            (lo, hi * 10f64.powf(pad))
        };
        Axis {
            min: lo,
            max: hi,
            log: true,
        }
    }

    /// Where `value` sits along the axis: 0 at `min`, 1 at `max`. Non-positive values on a
    /// log axis sit on the floor (0); non-finite values give `None`.
    pub fn fraction(&self, value: f64) -> Option<f64> {
        if !value.is_finite() {
            return None;
        }
        let f = if self.log {
            let lo = self.min.log10();
            let hi = self.max.log10();
            if value <= 0.0 {
                0.0
            } else {
                (value.log10() - lo) / (hi - lo)
            }
        } else {
            (value - self.min) / (self.max - self.min)
        };
        f.is_finite().then_some(f)
    }

    /// Whether `value` lies within the axis interval.
    pub fn contains(&self, value: f64) -> bool {
        value >= self.min && value <= self.max
    }

    /// Tick positions and their labels, about `target_count` of them.
    pub fn ticks(&self, target_count: usize) -> Vec<Tick> {
        if self.log {
            log_ticks(self.min, self.max, target_count)
        } else {
            linear_ticks(self.min, self.max, target_count)
        }
    }
}

/// Maps an axis onto a pixel interval. For a y axis `start` is the bottom and `end` the top.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelScale {
    pub axis: Axis,
    pub start: f64,
    pub end: f64,
}

impl PixelScale {
    /// The pixel coordinate of `value`; values far outside the axis are pulled in to stay
    /// drawable, and non-finite values give `None`.
    pub fn to_pixel(&self, value: f64) -> Option<f64> {
        let f = self.axis.fraction(value)?.clamp(-10.0, 11.0);
        Some(self.start + f * (self.end - self.start))
    }

    /// Like [`PixelScale::to_pixel`], but values outside the axis land on its nearest end, so
    /// lines never leave the plot (a log axis' floor catches everything below it).
    pub fn to_pixel_clamped(&self, value: f64) -> Option<f64> {
        let f = self.axis.fraction(value)?.clamp(0.0, 1.0);
        Some(self.start + f * (self.end - self.start))
    }
}

/// One tick: where it is and what it says.
#[derive(Debug, Clone, PartialEq)]
pub struct Tick {
    pub value: f64,
    pub label: String,
}

/// The 1-2-5 step (times a power of ten) giving about `target_count` intervals over `span`.
pub fn nice_step(span: f64, target_count: usize) -> f64 {
    let raw = span / target_count.max(1) as f64;
    if !raw.is_finite() || raw <= 0.0 {
        return 1.0;
    }
    let magnitude = 10f64.powf(raw.log10().floor());
    let normalized = raw / magnitude;
    let nice = if normalized <= 1.0 {
        1.0
    } else if normalized <= 2.0 {
        2.0
    } else if normalized <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * magnitude
}

/// Multiples of a 1-2-5 step inside `[min, max]`, labelled to the step's precision.
pub fn linear_ticks(min: f64, max: f64, target_count: usize) -> Vec<Tick> {
    let (min, max) = sanitize_range(Some((min, max)));
    let step = nice_step(max - min, target_count);
    let first = (min / step).ceil();
    let last = (max / step).floor();
    if !(first.is_finite() && last.is_finite()) || last - first > 1000.0 {
        return Vec::new();
    }
    let mut ticks = Vec::new();
    let mut k = first;
    while k <= last {
        let value = k * step;
        // Snap values like 3e-17 to a clean zero.
        let value = if value.abs() < step * 1e-9 {
            0.0
        } else {
            value
        };
        ticks.push(Tick {
            value,
            label: format_number(value, step),
        });
        k += 1.0;
    }
    ticks
}

/// Ticks for a logarithmic axis: powers of ten (every n-th when there are many decades),
/// with 2 and 5 between them when the axis spans two decades or less.
pub fn log_ticks(min: f64, max: f64, target_count: usize) -> Vec<Tick> {
    if !(min > 0.0 && max > min && max.is_finite()) {
        return Vec::new();
    }
    let first_decade = min.log10().floor() as i32;
    let last_decade = max.log10().ceil() as i32;
    let decades = (max / min).log10();
    let multipliers: &[f64] = if decades <= 2.0 {
        &[1.0, 2.0, 5.0]
    } else {
        &[1.0]
    };
    let decade_step = (decades.ceil().max(1.0) as usize)
        .div_ceil(target_count.max(1))
        .max(1);
    let mut ticks = Vec::new();
    for decade in (first_decade..=last_decade).step_by(decade_step) {
        let power = 10f64.powi(decade);
        for &m in multipliers {
            let value = m * power;
            if value >= min * (1.0 - 1e-9) && value <= max * (1.0 + 1e-9) {
                ticks.push(Tick {
                    value,
                    label: format_number(value, value),
                });
            }
        }
    }
    if ticks.len() < 2 {
        // Less than a decade with no round value inside: fall back to linear steps.
        return linear_ticks(min, max, target_count)
            .into_iter()
            .filter(|t| t.value > 0.0)
            .collect();
    }
    ticks
}

/// A short label for `value` shown to the precision of `resolution` (the tick step).
/// Very large or small magnitudes use the compact form `2.5e-4`.
pub fn format_number(value: f64, resolution: f64) -> String {
    if !value.is_finite() {
        return String::from("?");
    }
    if value == 0.0 {
        return String::from("0");
    }
    let magnitude = value.abs();
    if !(1e-3..1e5).contains(&magnitude) {
        return format_scientific(value);
    }
    let resolution = resolution.abs().max(magnitude * 1e-12);
    let decimals = (-resolution.log10().floor()).clamp(0.0, 6.0) as usize;
    format!("{value:.decimals$}")
}

/// `value` as mantissa and exponent with at most two decimals: `1e-5`, `2.5e6`.
fn format_scientific(value: f64) -> String {
    let mut exponent = value.abs().log10().floor() as i32;
    let mut mantissa = value / 10f64.powi(exponent);
    if (mantissa.abs() - 10.0).abs() < 5e-3 {
        mantissa /= 10.0;
        exponent += 1;
    }
    let mantissa = format!("{mantissa:.2}");
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    format!("{mantissa}e{exponent}")
}

/// Thins a series for drawing into `columns` pixel columns over `x_range`, keeping for each
/// column its smallest and largest y in their original order, so a single-sample peak is
/// never lost. A NaN y at a finite x inside `x_range` is a break (a gap, a missing value):
/// it is kept as one `(x, NaN)` point so that the line stops there. Other points with
/// non-finite coordinates or outside `x_range` are skipped; extra values of the longer of
/// `x`/`y` are ignored.
pub fn decimate_min_max(
    x: &[f64],
    y: &[f64],
    x_range: (f64, f64),
    columns: usize,
) -> Vec<(f64, f64)> {
    let (x0, x1) = sanitize_range(Some(x_range));
    let columns = columns.max(1);
    let width = x1 - x0;
    let column_of = |xv: f64| -> usize {
        let c = ((xv - x0) / width * columns as f64).floor();
        if c.is_finite() && c > 0.0 {
            (c as usize).min(columns - 1)
        } else {
            0
        }
    };

    struct Bucket {
        column: usize,
        min: (usize, f64, f64),
        max: (usize, f64, f64),
    }
    fn flush(bucket: &Bucket, out: &mut Vec<(f64, f64)>) {
        let (first, second) = if bucket.min.0 <= bucket.max.0 {
            (bucket.min, bucket.max)
        } else {
            (bucket.max, bucket.min)
        };
        out.push((first.1, first.2));
        if second.0 != first.0 {
            out.push((second.1, second.2));
        }
    }

    let mut out = Vec::new();
    let mut bucket: Option<Bucket> = None;
    for (i, (&xv, &yv)) in x.iter().zip(y).enumerate() {
        if yv.is_nan() && xv.is_finite() && xv >= x0 && xv <= x1 {
            if let Some(b) = bucket.take() {
                flush(&b, &mut out);
            }
            if out.last().is_some_and(|p| !p.1.is_nan()) {
                out.push((xv, f64::NAN));
            }
            continue;
        }
        if !(xv.is_finite() && yv.is_finite()) || xv < x0 || xv > x1 {
            continue;
        }
        let column = column_of(xv);
        match &mut bucket {
            Some(b) if b.column == column => {
                if yv < b.min.2 {
                    b.min = (i, xv, yv);
                }
                if yv > b.max.2 {
                    b.max = (i, xv, yv);
                }
            }
            _ => {
                if let Some(b) = &bucket {
                    flush(b, &mut out);
                }
                bucket = Some(Bucket {
                    column,
                    min: (i, xv, yv),
                    max: (i, xv, yv),
                });
            }
        }
    }
    if let Some(b) = &bucket {
        flush(b, &mut out);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(ticks: &[Tick]) -> Vec<&str> {
        ticks.iter().map(|t| t.label.as_str()).collect()
    }

    #[test]
    fn nice_steps_follow_1_2_5() {
        assert_eq!(nice_step(10.0, 10), 1.0);
        assert_eq!(nice_step(15.0, 10), 2.0);
        assert_eq!(nice_step(40.0, 10), 5.0);
        assert_eq!(nice_step(0.7, 10), 0.1);
        assert_eq!(nice_step(f64::NAN, 10), 1.0);
        assert_eq!(nice_step(0.0, 10), 1.0);
    }

    #[test]
    fn linear_ticks_are_round_and_inside() {
        let ticks = linear_ticks(0.0, 500.0, 10);
        assert_eq!(labels(&ticks)[..3], ["0", "50", "100"]);
        assert!(ticks.iter().all(|t| (0.0..=500.0).contains(&t.value)));
        let ticks = linear_ticks(-0.3, 0.3, 6);
        assert!(labels(&ticks).contains(&"0"));
        assert!(labels(&ticks).contains(&"-0.2"));
    }

    #[test]
    fn log_ticks_are_decades() {
        let ticks = log_ticks(1e-6, 1.0, 8);
        assert_eq!(
            labels(&ticks),
            ["1e-6", "1e-5", "1e-4", "0.001", "0.01", "0.1", "1"]
        );
        let ticks = log_ticks(0.5, 20.0, 8);
        assert_eq!(labels(&ticks), ["0.5", "1", "2", "5", "10", "20"]);
        assert!(log_ticks(0.0, 1.0, 5).is_empty());
        assert!(!log_ticks(2.1, 4.9, 5).is_empty());
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(format_number(105.9, 0.1), "105.9");
        assert_eq!(format_number(2000.0, 500.0), "2000");
        assert_eq!(format_number(2.5e-5, 1e-5), "2.5e-5");
        assert_eq!(format_number(1e6, 1e6), "1e6");
        assert_eq!(format_number(0.0, 1.0), "0");
        assert_eq!(format_number(f64::NAN, 1.0), "?");
    }

    #[test]
    fn degenerate_ranges_become_usable() {
        assert_eq!(sanitize_range(None), (0.0, 1.0));
        assert_eq!(sanitize_range(Some((3.0, 1.0))), (1.0, 3.0));
        assert_eq!(sanitize_range(Some((2.0, 2.0))), (1.0, 3.0));
        assert_eq!(sanitize_range(Some((f64::NAN, 2.0))), (0.0, 1.0));
        assert_eq!(
            finite_range([f64::NAN, 2.0, f64::INFINITY, -1.0]),
            Some((-1.0, 2.0))
        );
        assert_eq!(finite_range([f64::NAN]), None);
    }

    #[test]
    fn log_axis_floors_zeros_and_negatives() {
        let axis = Axis::log_for_data(Some((1e-12, 1.0)));
        assert!(axis.min >= 1e-6 * 0.999);
        assert_eq!(axis.fraction(0.0), Some(0.0));
        assert_eq!(axis.fraction(-5.0), Some(0.0));
        assert_eq!(axis.fraction(f64::NAN), None);
        let empty = Axis::log_for_data(None);
        assert!(empty.min > 0.0 && empty.max > empty.min);
    }

    #[test]
    fn decimation_keeps_single_sample_spike() {
        let n = 100_000;
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut y = vec![0.0; n];
        y[54_321] = 7.0;
        let points = decimate_min_max(&x, &y, (0.0, n as f64), 500);
        assert!(points.len() <= 2 * 500);
        assert!(points.contains(&(54_321.0, 7.0)));
    }

    #[test]
    fn decimation_skips_bad_points_and_keeps_order() {
        let x = [0.0, 1.0, 2.0, f64::NAN, 4.0, 5.0];
        let y = [1.0, f64::INFINITY, 3.0, 4.0, 5.0];
        let points = decimate_min_max(&x, &y, (0.0, 10.0), 100);
        assert_eq!(points, [(0.0, 1.0), (2.0, 3.0), (4.0, 5.0)]);
        assert!(decimate_min_max(&[], &[], (0.0, 1.0), 0).is_empty());
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        assert!(decimate_min_max(&x, &x, (100.0, 200.0), 10).is_empty());
    }

    #[test]
    fn a_nan_value_breaks_the_line_once() {
        let x = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let y = [f64::NAN, 1.0, f64::NAN, f64::NAN, 5.0, 6.0];
        let points = decimate_min_max(&x, &y, (0.0, 10.0), 100);
        assert_eq!(points.len(), 4, "{points:?}");
        assert_eq!(points[0], (1.0, 1.0));
        assert!(points[1].0 == 2.0 && points[1].1.is_nan(), "{points:?}");
        assert_eq!(&points[2..], [(4.0, 5.0), (5.0, 6.0)]);
    }
}
