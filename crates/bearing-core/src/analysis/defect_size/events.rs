//! The entry and exit read off the whitened average: the two most prominent peaks of its
//! Wiener-weighted envelope, kept only when they are clear (steps 4–5 of the parent module's
//! documentation).

use super::{
    argmax, bin_frequency, mean_of, median, vertex, Fft, NotMeasured, HIGH_PASS_HZ,
    MAX_THIRD_RATIO, MIN_PROMINENCE_OVER_MEDIAN, MIN_PROMINENCE_RATIO, MIN_SUB_EVENT_OVER_MEDIAN,
    SUB_AVERAGES,
};

/// A resolved entry and exit, in samples of the segment.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pair {
    pub(super) entry: f64,
    pub(super) exit: f64,
    /// Half-width at half maximum of the stronger event, samples.
    pub(super) half_width: f64,
}

/// How the events are read off a whitened average.
pub(super) struct Events<'a> {
    pub(super) fs_hz: f64,
    pub(super) weights: &'a [f64],
    pub(super) max_delay: usize,
    pub(super) min_separation: usize,
}

impl Events<'_> {
    /// The smoothed envelope of `x`, Wiener-weighted, above [`HIGH_PASS_HZ`].
    pub(super) fn envelope(&self, fft: &mut Fft, x: &[f64]) -> Vec<f64> {
        let n = x.len();
        let mut buf = fft.of_real(x);
        for (k, v) in buf.iter_mut().enumerate() {
            let f = bin_frequency(k, n);
            let keep = f > 0.0 && f * self.fs_hz >= HIGH_PASS_HZ;
            *v *= if keep { 2.0 * self.weights[k] } else { 0.0 };
        }
        fft.inverse(&mut buf);
        let magnitude: Vec<f64> = buf.iter().map(|v| v.norm()).collect();
        let sigma = self.fs_hz / 48_000.0;
        let reach = (3.0 * sigma) as isize;
        let kernel: Vec<f64> = (-reach..=reach)
            .map(|i| (-0.5 * (i as f64 / sigma).powi(2)).exp())
            .collect();
        let total: f64 = kernel.iter().sum();
        (0..n as isize)
            .map(|i| {
                kernel
                    .iter()
                    .zip(-reach..)
                    .filter_map(|(w, d)| {
                        usize::try_from(i + d)
                            .ok()
                            .and_then(|j| magnitude.get(j))
                            .map(|m| w * m)
                    })
                    .sum::<f64>()
                    / total
            })
            .collect()
    }

    /// The entry and exit: the two most prominent peaks within the longest delay of the
    /// strongest event, if they are clear (module documentation, step 5).
    pub(super) fn pair(&self, envelope: &[f64]) -> Result<Pair, NotMeasured> {
        let n = envelope.len();
        let strongest = argmax(envelope, n / 4, 3 * n / 4);
        let from = strongest.saturating_sub(self.max_delay).max(1);
        let to = (strongest + self.max_delay + 1).min(n - 1);
        let mut peaks: Vec<(usize, f64)> = (from..to)
            .filter(|&i| envelope[i] >= envelope[i - 1] && envelope[i] > envelope[i + 1])
            .map(|i| (i, prominence(&envelope[from - 1..=to], i + 1 - from)))
            .collect();
        peaks.sort_by(|a, b| b.1.total_cmp(&a.1));
        let Some(&(first, first_prominence)) = peaks.first() else {
            return Err(NotMeasured::NotResolved("no event in the average".into()));
        };
        let mut others = peaks
            .iter()
            .filter(|(i, _)| i.abs_diff(first) >= self.min_separation);
        let floor = median(envelope);
        if first_prominence < MIN_PROMINENCE_OVER_MEDIAN * floor {
            return Err(NotMeasured::NotResolved(format!(
                "no event stands out of the noise (the strongest {:.1}× the envelope's median, needs {MIN_PROMINENCE_OVER_MEDIAN})",
                first_prominence / floor
            )));
        }
        let Some(&(second, second_prominence)) = others.next() else {
            return Err(NotMeasured::NotResolved(
                "one event only (the entry and exit merge: the defect is shorter than the time resolution)".into(),
            ));
        };
        if second_prominence < MIN_PROMINENCE_RATIO * first_prominence
            || second_prominence < MIN_PROMINENCE_OVER_MEDIAN * floor
        {
            return Err(NotMeasured::NotResolved(format!(
                "one event only: the next one stands {:.1}× the strongest and {:.1}× the noise (needs {MIN_PROMINENCE_RATIO} and {MIN_PROMINENCE_OVER_MEDIAN})",
                second_prominence / first_prominence,
                second_prominence / floor
            )));
        }
        if let Some(&(_, third)) = others.next() {
            if third > MAX_THIRD_RATIO * second_prominence {
                return Err(NotMeasured::NotResolved(format!(
                    "a third event as strong ({:.0} % of the second) makes the pair ambiguous",
                    100.0 * third / second_prominence
                )));
            }
        }
        let half = 0.5 * envelope[first];
        let left = (0..first).rev().find(|&i| envelope[i] < half).unwrap_or(0);
        let right = (first..n).find(|&i| envelope[i] < half).unwrap_or(n - 1);
        let (a, b) = (first.min(second), first.max(second));
        Ok(Pair {
            entry: vertex(envelope, a),
            exit: vertex(envelope, b),
            half_width: 0.5 * (right - left) as f64,
        })
    }

    /// The spacing in each interleaved sub-average: the envelope's maximum within ±half the
    /// minimum separation of each event, both standing clear of that sub-average's noise.
    pub(super) fn sub_average_spacings(
        &self,
        fft: &mut Fft,
        whitened: &[Vec<f64>],
        pair: Pair,
    ) -> Result<Vec<f64>, NotMeasured> {
        let reach = (self.min_separation / 2).max(2);
        (0..SUB_AVERAGES)
            .map(|k| {
                let envelope =
                    self.envelope(fft, &mean_of(whitened.iter().skip(k).step_by(SUB_AVERAGES)));
                let near = |at: f64| {
                    let centre = at.round() as usize;
                    argmax(&envelope, centre.saturating_sub(reach), centre + reach + 1)
                };
                let (entry, exit) = (near(pair.entry), near(pair.exit));
                let floor = median(&envelope);
                if envelope[entry].min(envelope[exit]) < MIN_SUB_EVENT_OVER_MEDIAN * floor {
                    return Err(NotMeasured::NotResolved(format!(
                        "the events do not stand out in every sub-average ({:.1}× the noise in one, needs {MIN_SUB_EVENT_OVER_MEDIAN})",
                        envelope[entry].min(envelope[exit]) / floor
                    )));
                }
                Ok(vertex(&envelope, exit) - vertex(&envelope, entry))
            })
            .collect()
    }
}

/// Prominence of the peak at `i` of `values`: its height above the higher of the lowest points
/// on either side before a higher value (or the slice's end).
fn prominence(values: &[f64], i: usize) -> f64 {
    let height = values[i];
    let mut left_base = height;
    for &v in values[..i].iter().rev() {
        if v > height {
            break;
        }
        left_base = left_base.min(v);
    }
    let mut right_base = height;
    for &v in &values[i + 1..] {
        if v > height {
            break;
        }
        right_base = right_base.min(v);
    }
    height - left_base.max(right_base)
}
