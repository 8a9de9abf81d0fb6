//! Virtual states (seed 003, MODELS.md §6): the acceleration and its derivatives by finite
//! differences, each median-filtered (window 5) against the impulse noise that differencing
//! makes of measurement noise.
//!
//! `a⁽⁰⁾` is the measured signal as it is. The differences form one chain on the unfiltered
//! data, `d⁽ⁱ⁾[k] = (d⁽ⁱ⁻¹⁾[k+1] − d⁽ⁱ⁻¹⁾[k])·fs`, `d⁽⁰⁾ = a`, and each order is filtered on its
//! own: `a⁽ⁱ⁾ = median₅(d⁽ⁱ⁾)`. (choice) The seed filters "the finite-difference data" without
//! saying whether the next difference is taken before or after the filter. After: a running
//! median turns a signal into short constant runs, whose difference is mostly zero, whose
//! median is then zero; on PRONOSTIA snapshots every order from 4 up was exactly 0 that way.
//! So the chain runs on the raw data and the filter only cleans each order's output. The
//! median window shrinks symmetrically at the ends (1, 3, 5, …, 5, 3, 1 samples), so no
//! padding value enters the data. Every order is cut to the length of the highest one,
//! sample `k` of every order at the same time.

use super::HwError;

/// Width of the median filter applied to each difference (seed 003).
pub const MEDIAN_WINDOW: usize = 5;

/// Orders `0..=max_order` of the virtual states of one record, all of the same length.
#[derive(Debug, Clone, PartialEq)]
pub struct VirtualStates {
    pub fs_hz: f64,
    /// `states[i]` is `a⁽ⁱ⁾`, in g/sⁱ.
    pub states: Vec<Vec<f64>>,
}

impl VirtualStates {
    /// Builds orders `0..=max_order` of `samples`.
    ///
    /// Errors: a NaN or infinite sample (named by its index), a sample rate that is not a
    /// positive number, fewer than `max_order + min_len` samples.
    pub fn new(
        samples: &[f64],
        fs_hz: f64,
        max_order: usize,
        min_len: usize,
    ) -> Result<Self, HwError> {
        if !(fs_hz.is_finite() && fs_hz > 0.0) {
            return Err(HwError::SampleRate { fs_hz });
        }
        if let Some(index) = samples.iter().position(|x| !x.is_finite()) {
            return Err(HwError::NonFinite { index });
        }
        let needed = max_order + min_len;
        if samples.len() < needed {
            return Err(HwError::TooShort {
                got: samples.len(),
                needed,
            });
        }
        let mut states = Vec::with_capacity(max_order + 1);
        states.push(samples.to_vec());
        let mut difference = samples.to_vec();
        for _ in 1..=max_order {
            difference = difference
                .windows(2)
                .map(|w| (w[1] - w[0]) * fs_hz)
                .collect();
            states.push(median_filter(&difference));
        }
        let len = samples.len() - max_order;
        for state in &mut states {
            state.truncate(len);
        }
        Ok(VirtualStates { fs_hz, states })
    }

    /// Samples per state.
    pub fn len(&self) -> usize {
        self.states.first().map_or(0, Vec::len)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The highest order held.
    pub fn max_order(&self) -> usize {
        self.states.len().saturating_sub(1)
    }
}

/// Centred running median of width [`MEDIAN_WINDOW`], the window shrinking symmetrically at the
/// ends.
pub fn median_filter(x: &[f64]) -> Vec<f64> {
    let half = MEDIAN_WINDOW / 2;
    let n = x.len();
    let mut window = [0.0f64; MEDIAN_WINDOW];
    (0..n)
        .map(|k| {
            let reach = half.min(k).min(n - 1 - k);
            let part = &mut window[..2 * reach + 1];
            part.copy_from_slice(&x[k - reach..=k + reach]);
            part.sort_unstable_by(f64::total_cmp);
            part[reach]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_removes_a_single_spike_and_keeps_ends() {
        let x = [1.0, 2.0, 3.0, 100.0, 5.0, 6.0, 7.0];
        assert_eq!(median_filter(&x), [1.0, 2.0, 3.0, 5.0, 6.0, 6.0, 7.0]);
        assert_eq!(median_filter(&[]), Vec::<f64>::new());
        assert_eq!(median_filter(&[4.0]), [4.0]);
    }

    #[test]
    fn differences_of_a_ramp_and_a_parabola() {
        let fs = 10.0;
        // a = t², t = k/fs: a' = (2k+1)/fs, a'' = 2 (exact for forward differences).
        let a: Vec<f64> = (0..50).map(|k| (k as f64 / fs).powi(2)).collect();
        let s = VirtualStates::new(&a, fs, 3, 10).unwrap();
        assert_eq!(s.len(), 47);
        assert!((s.states[1][10] - 21.0 / fs).abs() < 1e-9);
        assert!(s.states[2].iter().all(|&v| (v - 2.0).abs() < 1e-9));
        assert!(s.states[3].iter().all(|&v| v.abs() < 1e-6));
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        assert!(matches!(
            VirtualStates::new(&[1.0, f64::NAN, 2.0], 1.0, 0, 1),
            Err(HwError::NonFinite { index: 1 })
        ));
        assert!(matches!(
            VirtualStates::new(&[1.0; 5], 1.0, 3, 10),
            Err(HwError::TooShort { got: 5, needed: 13 })
        ));
        assert!(matches!(
            VirtualStates::new(&[1.0; 50], 0.0, 3, 10),
            Err(HwError::SampleRate { .. })
        ));
    }
}
