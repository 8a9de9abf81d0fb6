//! The spectrum's local noise floor: a running median of the log amplitude, evaluated at knots
//! and interpolated between them (see the parent module), and the medians it is made of.
//!
//! Split from the scorer because it is the analysis window's largest cost (docs/PERFORMANCE.md):
//! the code that makes it fast lives here, with the tests that hold it to the plain median.

/// `excess -= running median of excess over ±half bins`, the median evaluated every `half/4`
/// bins and interpolated in between (the floor is smooth at that scale; this keeps the cost
/// per spectrum near `bins × 8` instead of `bins × half`).
pub(super) fn subtract_running_median(
    excess: &mut [f32],
    half: usize,
    keys: &mut Vec<i32>,
    knots: &mut Vec<f32>,
) {
    let n = excess.len();
    let stride = (half / 4).max(1);
    knots.clear();
    let mut centre: usize = 0;
    loop {
        let lo = centre.saturating_sub(half);
        let hi = (centre + half).min(n - 1);
        knots.push(median_of(excess[lo..=hi].iter().copied(), keys));
        if centre >= n - 1 {
            break;
        }
        centre = (centre + stride).min(n - 1);
    }
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
}
