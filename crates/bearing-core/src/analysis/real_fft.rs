//! The forward FFT of a real signal of N samples, as the daemon's window transform needs it.
//!
//! For an even N (every window the daemon takes), the N samples are read as N/2 complex pairs,
//! transformed by one complex FFT of N/2 points (rustfft), and one pass splits that into the
//! N/2 + 1 bins of the real signal: bin k and bin N/2 − k come from the same two values.
//! (why) realfft does the same, but its pass is a scalar loop walking the two halves towards
//! each other; on the daemon's 32,768-sample window it took more instructions than the complex
//! FFT itself (callgrind, docs/PERFORMANCE.md). This pass does realfft's arithmetic in
//! realfft's order, on 64 pairs at a time laid out so that the compiler makes vector
//! instructions of it. An odd N is transformed as realfft does it, by a complex FFT of N
//! points. Its bins equal realfft's bit for bit (tested below), so no decision can change.

use rustfft::num_complex::Complex32;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// Pairs handled together by the split pass: the loops over them are what the compiler vectorises.
const LANES: usize = 64;

/// A planned forward real FFT.
pub struct RealForwardFft {
    len: usize,
    /// The complex FFT of `len / 2` points (even `len`), or of `len` points (odd `len`, which
    /// has no pairs: the samples are transformed as they are, as realfft does).
    inner: Arc<dyn Fft<f32>>,
    /// `½ e^{-2πik/N}` for k = 1 … the last pair before the middle, real and imaginary parts
    /// apart (computed in f64 and rounded, as realfft does).
    twiddle_re: Vec<f32>,
    twiddle_im: Vec<f32>,
}

/// The buffers of one user of a [`RealForwardFft`]: nothing is allocated per transform.
pub struct RealFftBuffers {
    input: Vec<Complex32>,
    output: Vec<Complex32>,
    scratch: Vec<Complex32>,
}

impl RealFftBuffers {
    /// The bins of the last transform.
    pub fn spectrum(&self) -> &[Complex32] {
        &self.output
    }
}

impl RealForwardFft {
    /// The transform of `len` real samples (at least 1).
    pub fn new(len: usize, planner: &mut FftPlanner<f32>) -> Self {
        let len = len.max(1);
        if !len.is_multiple_of(2) {
            return RealForwardFft {
                len,
                inner: planner.plan_fft_forward(len),
                twiddle_re: Vec::new(),
                twiddle_im: Vec::new(),
            };
        }
        // Pairs (k, N/2 − k) with 0 < k < N/2 − k; the middle bin (k = N/4) pairs with itself.
        let pairs = len.div_ceil(4) - 1;
        let step = -std::f64::consts::TAU / len as f64;
        let angle = |k: usize| step * k as f64;
        RealForwardFft {
            len,
            inner: planner.plan_fft_forward(len / 2),
            twiddle_re: (1..=pairs).map(|k| angle(k).cos() as f32 * 0.5).collect(),
            twiddle_im: (1..=pairs).map(|k| angle(k).sin() as f32 * 0.5).collect(),
        }
    }

    /// The number of real samples it transforms (never 0).
    pub fn samples(&self) -> usize {
        self.len
    }

    fn is_even(&self) -> bool {
        self.len.is_multiple_of(2)
    }

    /// Buffers for [`Self::transform`].
    pub fn buffers(&self) -> RealFftBuffers {
        let zeros = |n: usize| vec![Complex32::default(); n];
        let (input, scratch) = if self.is_even() {
            (self.len / 2, self.inner.get_outofplace_scratch_len())
        } else {
            (self.len, self.inner.get_inplace_scratch_len())
        };
        RealFftBuffers {
            input: zeros(input),
            output: zeros(self.len / 2 + 1),
            scratch: zeros(scratch),
        }
    }

    /// The `len / 2 + 1` bins of the samples `older` followed by `newer` (the two halves of a
    /// ring buffer, or one slice and an empty one), in `buffers` (from [`Self::buffers`]).
    ///
    /// # Panics
    /// When the two slices do not hold `len` samples together, or `buffers` were made for
    /// another length (a programming error, never an input's).
    pub fn transform<'a>(
        &self,
        older: &[f32],
        newer: &[f32],
        buffers: &'a mut RealFftBuffers,
    ) -> &'a [Complex32] {
        assert_eq!(older.len() + newer.len(), self.len, "window length");
        let RealFftBuffers {
            input,
            output,
            scratch,
        } = buffers;
        if !self.is_even() {
            let samples = older.iter().chain(newer);
            for (value, sample) in input.iter_mut().zip(samples) {
                *value = Complex32::new(*sample, 0.0);
            }
            self.inner.process_with_scratch(input, scratch);
            let bins = output.len();
            output.copy_from_slice(&input[..bins]);
            output[0].im = 0.0;
            return output;
        }
        let samples: &mut [f32] = bytemuck::cast_slice_mut(input.as_mut_slice());
        samples[..older.len()].copy_from_slice(older);
        samples[older.len()..].copy_from_slice(newer);
        let half = self.len / 2;
        self.inner
            .process_outofplace_with_scratch(input, &mut output[..half], scratch);
        let first = output[0];
        output[0] = Complex32::new(first.re + first.im, 0.0);
        output[half] = Complex32::new(first.re - first.im, 0.0);
        if half.is_multiple_of(2) {
            // The middle bin of the complex transform is its own partner: conjugated.
            output[half / 2].im = -output[half / 2].im;
        }
        let pairs = self.twiddle_re.len();
        let (low, high) = output[1..half].split_at_mut(pairs);
        // `high` ends with bin N/2 − 1, the partner of bin 1; the middle bin, when there is
        // one, comes first and is left out.
        let high_start = high.len() - pairs;
        split_pairs(
            low,
            &mut high[high_start..],
            &self.twiddle_re,
            &self.twiddle_im,
        );
        output
    }
}

/// realfft's split of each pair (`low[j]`, bin j + 1, with `high[pairs − 1 − j]`, bin
/// N/2 − j − 1): [`LANES`] pairs at a time gathered into arrays the compiler vectorises, the
/// rest one by one, the same arithmetic in both.
fn split_pairs(low: &mut [Complex32], high: &mut [Complex32], tw_re: &[f32], tw_im: &[f32]) {
    let low_chunks = low.chunks_exact_mut(LANES);
    let high_chunks = high.rchunks_exact_mut(LANES);
    let twiddles = tw_re.chunks_exact(LANES).zip(tw_im.chunks_exact(LANES));
    for ((lo, hi), (tr, ti)) in low_chunks.zip(high_chunks).zip(twiddles) {
        // Real and imaginary parts in arrays of their own, and `split_one`'s steps one at a
        // time over all lanes, each a loop of its own: the compiler vectorises each loop
        // (written per pair, it vectorised each pair's re/im instead, no faster than scalar).
        let mut a_re = [0f32; LANES];
        let mut a_im = [0f32; LANES];
        let mut b_re = [0f32; LANES];
        let mut b_im = [0f32; LANES];
        for (i, c) in lo.iter().enumerate() {
            a_re[i] = c.re;
            a_im[i] = c.im;
        }
        for (i, c) in hi.iter().rev().enumerate() {
            b_re[i] = c.re;
            b_im[i] = c.im;
        }
        let mut low_re = [0f32; LANES];
        let mut low_im = [0f32; LANES];
        let mut high_re = [0f32; LANES];
        let mut high_im = [0f32; LANES];
        for i in 0..LANES {
            let a = Complex32::new(a_re[i], a_im[i]);
            let b = Complex32::new(b_re[i], b_im[i]);
            let (low_bin, high_bin) = split_one(a, b, tr[i], ti[i]);
            (low_re[i], low_im[i]) = (low_bin.re, low_bin.im);
            (high_re[i], high_im[i]) = (high_bin.re, high_bin.im);
        }
        for (i, c) in lo.iter_mut().enumerate() {
            *c = Complex32::new(low_re[i], low_im[i]);
        }
        for (i, c) in hi.iter_mut().rev().enumerate() {
            *c = Complex32::new(high_re[i], high_im[i]);
        }
    }
    let done = low.len() - low.len() % LANES;
    let rest = low.len() - done;
    let low_rest = &mut low[done..];
    let high_rest = &mut high[..rest];
    for (j, (lo, hi)) in low_rest
        .iter_mut()
        .zip(high_rest.iter_mut().rev())
        .enumerate()
    {
        (*lo, *hi) = split_one(*lo, *hi, tw_re[done + j], tw_im[done + j]);
    }
}

/// One pair: `a` = Z[k], `b` = Z[N/2 − k] of the half-length transform Z, `(tr, ti)` =
/// ½ e^{-2πik/N}; returns bins k and N/2 − k of the real signal. realfft's expressions, in its
/// order, so that the rounding is the same.
#[inline(always)]
fn split_one(a: Complex32, b: Complex32, tr: f32, ti: f32) -> (Complex32, Complex32) {
    let (sum_re, sum_im) = (a.re + b.re, a.im + b.im);
    let (diff_re, diff_im) = (a.re - b.re, a.im - b.im);
    let half_sum_re = 0.5 * sum_re;
    let half_diff_im = 0.5 * diff_im;
    let twiddled_re = sum_im * tr + diff_re * ti;
    let twiddled_im = sum_im * ti - diff_re * tr;
    (
        Complex32::new(half_sum_re + twiddled_re, half_diff_im + twiddled_im),
        Complex32::new(half_sum_re - twiddled_re, twiddled_im - half_diff_im),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use realfft::RealFftPlanner;

    /// Bit for bit realfft's bins, on even lengths with and without a middle pair and with
    /// remainders of the 64-pair loop (32,768: 127 groups and 63 pairs), on odd lengths, on noise
    /// with a DC offset, split in two slices at an odd and at an even place.
    #[test]
    fn its_bins_equal_realffts_bit_for_bit() {
        let mut planner = FftPlanner::new();
        let mut reference = RealFftPlanner::<f32>::new();
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let lengths = [
            1, 2, 3, 4, 6, 10, 18, 34, 64, 70, 96, 216, 243, 1024, 4098, 32768,
        ];
        for len in lengths {
            let ours = RealForwardFft::new(len, &mut planner);
            let theirs = reference.plan_fft_forward(len);
            let samples: Vec<f32> = (0..len)
                .map(|_| {
                    seed ^= seed << 13;
                    seed ^= seed >> 7;
                    seed ^= seed << 17;
                    (seed >> 40) as f32 / (1u64 << 24) as f32 - 0.3
                })
                .collect();
            let mut their_input = samples.clone();
            let mut expected = theirs.make_output_vec();
            theirs.process(&mut their_input, &mut expected).unwrap();
            let mut buffers = ours.buffers();
            for split in [0, len / 3, len / 2] {
                let (older, newer) = samples.split_at(split);
                let output = ours.transform(older, newer, &mut buffers);
                assert_eq!(output.len(), expected.len());
                for (k, (o, e)) in output.iter().zip(&expected).enumerate() {
                    assert!(
                        o.re.to_bits() == e.re.to_bits() && o.im.to_bits() == e.im.to_bits(),
                        "len {len}, split {split}, bin {k}: {o} vs {e}"
                    );
                }
            }
        }
    }
}
