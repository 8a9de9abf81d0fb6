//! Explaining away ([`super::FaultScorer::score_explained`]): the bins a winning fault's comb
//! explains are set to the floor before a runner-up is scored on what is left.

use super::{is_positive, FaultScore, LINE_HALF_WIDTH};
use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;

/// Sets to the floor (0) the bins of `excess` (spaced `bin_hz`) that `winner`'s comb explains
/// (see [`FaultScorer::score_explained`]); a cage comb has `cage_harmonics` harmonics.
pub(super) fn floor_comb(
    excess: &mut [f32],
    bin_hz: f64,
    cage_harmonics: usize,
    winner: &FaultScore,
    freqs: &FaultFrequencies,
) {
    let n = excess.len();
    let f = winner.frequency_hz;
    if !is_positive(f) {
        return;
    }
    let shaft = freqs.shaft * (1.0 + winner.slip);
    let cage = freqs.ftf * (1.0 + winner.slip);
    let mut offsets = [0.0; 9];
    let mut count = 0;
    for o in [0.0, -2.0, -1.0, 1.0, 2.0] {
        offsets[count] = o * shaft;
        count += 1;
    }
    if winner.fault == FaultKind::Ball {
        for o in [-2.0, -1.0, 1.0, 2.0] {
            offsets[count] = o * cage;
            count += 1;
        }
    }
    // A cage comb is only its first harmonics (its higher ones are other faults' lines:
    // BPFO is a multiple of FTF).
    let last_order = if winner.fault == FaultKind::Cage {
        cage_harmonics as f64
    } else {
        f64::INFINITY
    };
    let mut order = 1.0;
    while (order * f - 2.0 * shaft) / bin_hz < n as f64 && order <= last_order {
        for offset in &offsets[..count] {
            floor_line(excess, order * f + offset, order * f, bin_hz);
        }
        order += 1.0;
    }
    // An outer-race fault is a ball passing a defect; balls differ, so its impacts repeat
    // with the cage as well. A damaged ball is carried by the cage through the load zone
    // once per cage turn, so its impacts swell and fade at FTF. Either way the cage comb
    // is part of what the winner explains.
    if matches!(winner.fault, FaultKind::OuterRace | FaultKind::Ball) {
        for order in 1..=cage_harmonics {
            let line = order as f64 * cage;
            floor_line(excess, line, line, bin_hz);
        }
    }
}

/// Sets to the floor the bins of a line at `at_hz` whose harmonic sits at `harmonic_hz` (its
/// width grows with the harmonic, as the scorer's search window does), plus one bin of leakage
/// each side.
fn floor_line(excess: &mut [f32], at_hz: f64, harmonic_hz: f64, bin_hz: f64) {
    let Some(last) = excess.len().checked_sub(1) else {
        return;
    };
    let centre = at_hz / bin_hz;
    let half = (LINE_HALF_WIDTH * harmonic_hz / bin_hz).max(1.5) + 1.0;
    let lo = (centre - half).max(0.0) as usize;
    let hi = ((centre + half).max(0.0) as usize).min(last);
    for e in excess.iter_mut().take(hi + 1).skip(lo) {
        *e = 0.0;
    }
}
