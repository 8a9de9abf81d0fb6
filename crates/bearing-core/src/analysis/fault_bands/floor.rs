//! The spectrum's local noise floor: a running median of the log amplitude, evaluated at knots
//! and interpolated between them (see the parent module), and the medians it is made of.
//!
//! The knots were the analysis window's largest cost (docs/PERFORMANCE.md): about 120 medians of
//! 83 bins each per prepared spectrum, each a fresh selection. They are now read from one sort:
//! every bin gets its rank in the whole spectrum (ties by bin), a bitset holds the ranks inside
//! the current knot's window, and the windows only move right, so each bin enters and leaves the
//! set once. A knot's median is the set's `⌊len/2⌋`-th rank, found by counting bits. The `m`-th
//! smallest of a multiset is one value whatever order ties take, so every knot is bit-identical
//! to the selection it replaces (kept in the tests as the oracle).

/// Words of the rank bitset per counted group: a knot's median skips whole groups by their
/// counts, then words by their popcounts, so a query costs about `n / 512 + 8` steps.
const GROUP_WORDS: usize = 8;

/// Scratch of the running-median floor, kept by the scorer so that preparing a spectrum
/// allocates nothing once warm.
#[derive(Debug, Default)]
pub(super) struct FloorScratch {
    /// Each bin's sort key ([`sort_key`]).
    keys: Vec<u32>,
    /// The bins in key order, ties by bin, and the radix sort's second buffer.
    order: Vec<u32>,
    spare: Vec<u32>,
    /// Each bin's place in `order`.
    rank: Vec<u32>,
    /// The ranks of the bins inside the current knot's window, one bit each, and how many of
    /// them fall in each group of `GROUP_WORDS` words.
    inside: Vec<u64>,
    group_counts: Vec<u32>,
    /// The medians at the knots.
    knots: Vec<f32>,
}

impl FloorScratch {
    /// Scratch for spectra of up to `bins` bins, reserved at once so that the first spectrum
    /// allocates nothing either.
    pub(super) fn with_capacity(bins: usize) -> Self {
        let words = bins.div_ceil(64);
        FloorScratch {
            keys: Vec::with_capacity(bins),
            order: Vec::with_capacity(bins),
            spare: Vec::with_capacity(bins),
            rank: Vec::with_capacity(bins),
            inside: Vec::with_capacity(words),
            group_counts: Vec::with_capacity(words.div_ceil(GROUP_WORDS)),
            // At most one knot per bin.
            knots: Vec::with_capacity(bins),
        }
    }

    /// The median (upper one of an even count) of each knot window of `values` (see
    /// [`knot_windows`]) into `self.knots`.
    fn knot_medians(&mut self, values: &[f32], half: usize, stride: usize) {
        let n = values.len();
        self.knots.clear();
        if n == 0 {
            return;
        }
        self.rank_bins(values);
        let words = n.div_ceil(64);
        self.inside.clear();
        self.inside.resize(words, 0);
        self.group_counts.clear();
        self.group_counts.resize(words.div_ceil(GROUP_WORDS), 0);
        // Bins `start..end` are inside.
        let (mut start, mut end) = (0, 0);
        for (lo, hi) in knot_windows(n, half, stride) {
            for bin in start..lo.min(end) {
                self.set_inside(bin, false);
            }
            for bin in end.max(lo)..=hi {
                self.set_inside(bin, true);
            }
            (start, end) = (lo, hi + 1);
            let len = hi - lo + 1;
            let rank = self.nth_inside((len / 2) as u32);
            self.knots
                .push(from_sort_key(self.keys[self.order[rank] as usize]));
        }
    }

    /// Sorts the bins of `values` by key (a stable radix sort, one pass per byte that differs
    /// between keys) into `order`, and fills `rank`.
    fn rank_bins(&mut self, values: &[f32]) {
        let n = values.len();
        self.keys.clear();
        self.keys.extend(values.iter().map(|&v| sort_key(v)));
        let mut counts = [[0u32; 256]; 4];
        for &key in &self.keys {
            for (byte, count) in counts.iter_mut().enumerate() {
                count[byte_of(key, byte)] += 1;
            }
        }
        self.order.clear();
        self.order.extend(0..n as u32);
        self.spare.clear();
        self.spare.resize(n, 0);
        for (byte, count) in counts.iter_mut().enumerate() {
            if count[byte_of(self.keys[0], byte)] as usize == n {
                continue; // every key has this byte: the pass would keep the order
            }
            let mut total = 0;
            for c in count.iter_mut() {
                (*c, total) = (total, total + *c);
            }
            for &bin in &self.order {
                let slot = &mut count[byte_of(self.keys[bin as usize], byte)];
                self.spare[*slot as usize] = bin;
                *slot += 1;
            }
            std::mem::swap(&mut self.order, &mut self.spare);
        }
        self.rank.clear();
        self.rank.resize(n, 0);
        for (rank, &bin) in self.order.iter().enumerate() {
            self.rank[bin as usize] = rank as u32;
        }
    }

    /// Puts `bin`'s rank into the window's set, or takes it out.
    fn set_inside(&mut self, bin: usize, inside: bool) {
        let rank = self.rank[bin] as usize;
        let (word, bit) = (rank / 64, 1u64 << (rank % 64));
        let group = &mut self.group_counts[word / GROUP_WORDS];
        if inside {
            self.inside[word] |= bit;
            *group += 1;
        } else {
            self.inside[word] &= !bit;
            *group -= 1;
        }
    }

    /// The `k`-th smallest rank (from 0) in the window's set; `k` must be below its size.
    fn nth_inside(&self, mut k: u32) -> usize {
        let mut group = 0;
        while group + 1 < self.group_counts.len() && k >= self.group_counts[group] {
            k -= self.group_counts[group];
            group += 1;
        }
        let mut word = group * GROUP_WORDS;
        while word + 1 < self.inside.len() && k >= self.inside[word].count_ones() {
            k -= self.inside[word].count_ones();
            word += 1;
        }
        word * 64 + nth_set_bit(self.inside[word], k)
    }
}

/// The place of the `k`-th set bit (from 0, lowest first) of `word`, which has more than `k`.
fn nth_set_bit(mut word: u64, mut k: u32) -> usize {
    let mut base = 0;
    for width in [32, 16, 8] {
        let low = (word & ((1u64 << width) - 1)).count_ones();
        if k >= low {
            k -= low;
            word >>= width;
            base += width;
        }
    }
    for _ in 0..k {
        word &= word - 1;
    }
    base + word.trailing_zeros() as usize
}

/// Byte `byte` (0 = lowest) of `key`.
fn byte_of(key: u32, byte: usize) -> usize {
    ((key >> (8 * byte)) & 0xff) as usize
}

/// The windows `(lo, hi)` (inclusive, clipped to the spectrum of `n ≥ 1` bins) whose medians
/// are the knots: centred on bins `0, stride, 2·stride, …` and last on `n − 1`, ±`half` bins.
fn knot_windows(n: usize, half: usize, stride: usize) -> impl Iterator<Item = (usize, usize)> {
    let mut next_centre = Some(0usize);
    std::iter::from_fn(move || {
        let centre = next_centre?;
        next_centre = (centre < n - 1).then(|| (centre + stride).min(n - 1));
        Some((centre.saturating_sub(half), (centre + half).min(n - 1)))
    })
}

/// `excess -= running median of excess over ±half bins`, the median evaluated every `half/4`
/// bins and interpolated in between (the floor is smooth at that scale; the knots' medians come
/// from one sort, see the module doc).
pub(super) fn subtract_running_median(excess: &mut [f32], half: usize, scratch: &mut FloorScratch) {
    let stride = (half / 4).max(1);
    scratch.knot_medians(excess, half, stride);
    subtract_knots(excess, stride, &scratch.knots);
}

/// `excess -= the floor` linearly interpolated between `knots` (one every `stride` bins, the
/// last on the last bin).
fn subtract_knots(excess: &mut [f32], stride: usize, knots: &[f32]) {
    let n = excess.len();
    for (i, e) in excess.iter_mut().enumerate() {
        let k = i / stride;
        let floor = match (knots.get(k), knots.get(k + 1)) {
            (Some(&a), Some(&b)) => {
                let x0 = k * stride;
                let x1 = ((k + 1) * stride).min(n - 1);
                let t = if x1 > x0 {
                    (i - x0) as f32 / (x1 - x0) as f32
                } else {
                    0.0
                };
                a + (b - a) * t
            }
            (Some(&a), None) => a,
            _ => 0.0,
        };
        *e -= floor;
    }
}

/// The median of `values` (the upper one of an even count; 0 for none), selected on integer
/// keys that order as [`f32::total_cmp`] orders the values: the same median, with one integer
/// compare where `total_cmp` converts both operands at every comparison. `keys` is scratch.
pub(super) fn median_of(values: impl Iterator<Item = f32>, keys: &mut Vec<i32>) -> f32 {
    keys.clear();
    keys.extend(values.map(total_order_key));
    if keys.is_empty() {
        return 0.0;
    }
    let middle = keys.len() / 2;
    // The key transform is its own inverse.
    f32::from_bits(
        total_order_key(f32::from_bits(*keys.select_nth_unstable(middle).1 as u32)) as u32,
    )
}

/// `x`'s bits as an integer that orders as [`f32::total_cmp`] orders floats (negative values
/// have their magnitude bits flipped).
fn total_order_key(x: f32) -> i32 {
    let bits = x.to_bits() as i32;
    bits ^ ((((bits >> 31) as u32) >> 1) as i32)
}

/// [`total_order_key`] as an unsigned integer (same order), for the radix sort.
fn sort_key(x: f32) -> u32 {
    total_order_key(x) as u32 ^ (1 << 31)
}

/// The float whose [`sort_key`] is `key`, bit for bit.
fn from_sort_key(key: u32) -> f32 {
    f32::from_bits(total_order_key(f32::from_bits(key ^ (1 << 31))) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::Rng;

    #[test]
    fn the_median_on_integer_keys_is_the_total_order_median() {
        let mut rng = Rng::new(3);
        let mut keys = Vec::new();
        for len in [1usize, 2, 3, 8, 81, 1_200] {
            let mut values: Vec<f32> = (0..len).map(|_| (rng.normal() * 30.0) as f32).collect();
            values[0] = -0.0;
            if len > 3 {
                values[1] = f32::INFINITY;
                values[2] = f32::NEG_INFINITY;
                values[3] = 0.0;
            }
            let mut sorted = values.clone();
            sorted.sort_by(f32::total_cmp);
            let got = median_of(values.iter().copied(), &mut keys);
            assert_eq!(got.to_bits(), sorted[len / 2].to_bits(), "len {len}");
        }
        assert_eq!(median_of(std::iter::empty(), &mut keys), 0.0);
    }

    /// The oracle: each knot's median selected afresh, as the floor was made before the ranks.
    fn knot_medians_by_selection(values: &[f32], half: usize, stride: usize) -> Vec<f32> {
        let mut keys = Vec::new();
        knot_windows(values.len(), half, stride)
            .map(|(lo, hi)| median_of(values[lo..=hi].iter().copied(), &mut keys))
            .collect()
    }

    /// A spectrum of `n` log amplitudes of the given flavour.
    fn spectrum(rng: &mut Rng, n: usize, flavour: usize) -> Vec<f32> {
        let specials = [
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::NAN,
            -f32::NAN,
            0.0,
            -0.0,
            f32::MIN_POSITIVE.ln(),
        ];
        (0..n)
            .map(|_| match flavour {
                // log amplitudes of noise
                0 => (0.5 * rng.normal() - 1.0) as f32,
                // few distinct values: many ties
                1 => (rng.uniform() * 4.0).floor() as f32 - 1.5,
                // all equal
                2 => 0.25,
                // noise with the special values mixed in
                _ if rng.uniform() < 0.2 => specials[(rng.uniform() * 7.0) as usize % 7],
                _ => (3.0 * rng.normal()) as f32,
            })
            .collect()
    }

    #[test]
    fn every_knot_is_bit_identical_to_the_selected_median() {
        let mut rng = Rng::new(31);
        let mut scratch = FloorScratch::default();
        for &n in &[1usize, 2, 3, 16, 17, 64, 65, 100, 513, 1_165, 4_100] {
            for &half in &[0usize, 1, 3, 8, 41, n / 2, n, 2 * n + 5] {
                for flavour in 0..4 {
                    let values = spectrum(&mut rng, n, flavour);
                    let stride = (half / 4).max(1);
                    let expected = knot_medians_by_selection(&values, half, stride);
                    scratch.knot_medians(&values, half, stride);
                    let got: Vec<u32> = scratch.knots.iter().map(|k| k.to_bits()).collect();
                    let want: Vec<u32> = expected.iter().map(|k| k.to_bits()).collect();
                    assert_eq!(got, want, "n {n}, half {half}, flavour {flavour}");
                }
            }
        }
    }

    #[test]
    fn the_floor_subtracted_is_the_one_of_the_selected_medians() {
        let mut rng = Rng::new(6205);
        let mut scratch = FloorScratch::default();
        for &(n, half) in &[(16usize, 8usize), (340, 31), (1_165, 41), (1_165, 2_000)] {
            for flavour in 0..4 {
                let values = spectrum(&mut rng, n, flavour);
                let stride = (half / 4).max(1);
                let mut expected = values.clone();
                subtract_knots(
                    &mut expected,
                    stride,
                    &knot_medians_by_selection(&values, half, stride),
                );
                let mut got = values.clone();
                subtract_running_median(&mut got, half, &mut scratch);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(&got),
                    bits(&expected),
                    "n {n}, half {half}, flavour {flavour}"
                );
            }
        }
    }

    #[test]
    fn the_nth_set_bit_is_found_in_every_word() {
        let mut rng = Rng::new(9);
        for _ in 0..2_000 {
            let word = rng.next_u64() & rng.next_u64();
            let places: Vec<usize> = (0..64).filter(|b| (word >> b) & 1 == 1).collect();
            for (k, &place) in places.iter().enumerate() {
                assert_eq!(nth_set_bit(word, k as u32), place, "{word:#x}, k {k}");
            }
        }
    }
}
