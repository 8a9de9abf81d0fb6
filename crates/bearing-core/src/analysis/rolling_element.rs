//! Which rolling-element part: a damaged ball against an inner-race defect (docs/DIAGNOSIS.md,
//! "Rolling element or inner race").
//!
//! Why a rule of its own: on some bearings the two combs land on the same peaks (the 61804:
//! BPFI 7.375·fr, 2·BSF 7.294·fr, found at a common slip 1.1 % apart), so their sizes tie and
//! the larger one, named by size, is a coin toss; explaining it away then floors the shared
//! peaks and the rival keeps nothing. Only the sidebands can tell them apart: ±fr for an inner
//! race, ±FTF for a ball ([`super::modulation`]). And where each comb shows its own pattern,
//! both may be there. So, for a named inner-race or ball leader and its rival:
//!
//! | case | verdict |
//! |---|---|
//! | shared combs, the leader's contrast ≥ [`SEPARATION_Z`] | the leader |
//! | shared combs, the leader's contrast ≤ −[`SEPARATION_Z`] | the rival leads instead ([`rival_leads`]) |
//! | shared combs, otherwise | either (ball or inner race) |
//! | not shared: the rival detected on its own (the rule's size and significance) and its own contrast ≥ [`RIVAL_CONTRAST_Z`] | either |
//! | not shared, otherwise | the leader |
//!
//! Why the rival must be detected, not merely beyond noise: shaft-rate sidebands are not the
//! inner race's alone (anything the shaft modulates makes them). On the simulator's 6205 at
//! 0.6× speed the machine's nuisance makes an inner comb of 1.9–2.9 with a contrast of +5 to +8,
//! healthy or beside a damaged ball; asked only to be beyond noise at ten times the false-alarm
//! rate and ≥ 1.8, it turned 8 named balls of the full sweep into "either" (docs/DIAGNOSIS.md).
//!
//! The rule never asks for the leader's own modulation (real spectra are cluttered, and CWRU's
//! ball records show no cage-rate sidebands at all), and it only ever turns a named fault into
//! a named pair: it never adds a fault to `none`.

use super::fault_bands::FaultScore;
use crate::messages::FaultKind;

/// (choice, on the simulator; docs/DIAGNOSIS.md) How far a shared comb's contrast must lean to
/// name one of the pair. Noise alone reaches |z| 0.85 at its 99.9 % point (the modulation
/// tests); the simulator's 61804 (tests/suite/rolling_element.rs) gives |z| ≤ 1.2 on its
/// uniform-load ties and healthy records, and 5.7–13 on the modulated faults it names: 2.5
/// lies between them (their geometric middle).
pub const SEPARATION_Z: f64 = 2.5;

/// (choice) The contrast a rival's own modulation must show for "both patterns show": well
/// above noise (never reached in 3000 noise spectra) and above what cluttered real spectra put
/// beside a named leader by coincidence (CWRU: ≤ 0.8 beside named inner races, up to 2.0 beside
/// weak combs).
pub const RIVAL_CONTRAST_Z: f64 = 3.0;

/// The other of the rolling-element pair: the ball for an inner race and back; `None` for the
/// outer race and the cage.
pub fn rolling_rival(fault: FaultKind) -> Option<FaultKind> {
    match fault {
        FaultKind::InnerRace => Some(FaultKind::Ball),
        FaultKind::Ball => Some(FaultKind::InnerRace),
        FaultKind::OuterRace | FaultKind::Cage => None,
    }
}

/// `score`'s rival among `scores`, when it has one.
fn rival_of<'a>(score: &FaultScore, scores: &'a [FaultScore]) -> Option<&'a FaultScore> {
    let kind = rolling_rival(score.fault)?;
    scores.iter().find(|s| s.fault == kind)
}

/// Whether two combs found the same lines: within a bin of each other on all of their
/// harmonics but one (at least two). Geometry-free: it holds on the 61804 and on any custom
/// bearing whose faults share lines, and never on a 6205 (BPFI 5.4·fr, 2·BSF 4.7·fr).
pub fn shared_combs(a: &FaultScore, b: &FaultScore) -> bool {
    let bin = a.bin_hz().max(b.bin_hz());
    let harmonics = a.peaks().len().min(b.peaks().len());
    if bin <= 0.0 || harmonics < 2 {
        return false;
    }
    let same = a
        .peaks()
        .iter()
        .zip(b.peaks())
        .filter(|(p, q)| (p.found_hz - q.found_hz).abs() <= 1.5 * bin)
        .count();
    same + 1 >= harmonics
}

fn contrast_z(score: &FaultScore) -> Option<f64> {
    score.modulation.map(|m| m.contrast_z)
}

/// The rival that leads instead of `top` (the tallest comb): when the two share their lines
/// and the sidebands speak for the rival (`top`'s contrast ≤ −[`SEPARATION_Z`]).
pub fn rival_leads<'a>(top: &FaultScore, scores: &'a [FaultScore]) -> Option<&'a FaultScore> {
    let rival = rival_of(top, scores)?;
    let against = contrast_z(top).is_some_and(|z| z <= -SEPARATION_Z);
    (against && shared_combs(top, rival)).then_some(rival)
}

/// The rival a named `leader` cannot be told apart from (see the module docs), `None` when the
/// leader stands. `detected`: whether a comb is detected on its own (the decision rule's).
pub fn ball_or_inner<'a>(
    leader: &FaultScore,
    scores: &'a [FaultScore],
    detected: impl Fn(&FaultScore) -> bool,
) -> Option<&'a FaultScore> {
    let rival = rival_of(leader, scores)?;
    if shared_combs(leader, rival) {
        let separated = contrast_z(leader).is_some_and(|z| z >= SEPARATION_Z);
        return (!separated).then_some(rival);
    }
    let both_show = detected(rival) && contrast_z(rival).is_some_and(|z| z >= RIVAL_CONTRAST_Z);
    both_show.then_some(rival)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::diagnosis::tests::scores;
    use crate::analysis::modulation::Modulation;

    /// Detected: as the default rule, score ≥ 5 and p ≤ 10^-3.
    fn detected(s: &FaultScore) -> bool {
        s.score >= 5.0 && s.significance >= 3.0
    }

    /// Inner race and ball with `inner`'s and `ball`'s (score, significance, contrast z), their
    /// peaks at `inner_hz` and `ball_hz` (× k) on 1 Hz bins.
    fn pair(
        inner: (f64, f64, f64),
        ball: (f64, f64, f64),
        inner_hz: f64,
        ball_hz: f64,
    ) -> Vec<FaultScore> {
        let mut all = scores([(1.2, 0.5), (inner.0, inner.1), (ball.0, ball.1), (1.1, 0.2)]);
        for (s, (z, hz)) in all[1..3]
            .iter_mut()
            .zip([(inner.2, inner_hz), (ball.2, ball_hz)])
        {
            *s = s.with_found_peaks(1.0, &[hz, 2.0 * hz, 3.0 * hz, 4.0 * hz, 5.0 * hz]);
            s.modulation = Some(Modulation {
                own: 1.0,
                other: 1.0,
                contrast_z: z,
            });
        }
        all
    }

    #[test]
    fn combs_on_the_same_lines_are_shared_and_a_6205s_are_not() {
        let all = pair((5.3, 20.0, 0.2), (5.3, 20.0, -0.2), 221.0, 221.0);
        assert!(shared_combs(&all[1], &all[2]));
        // One harmonic off by 3 bins: still shared (all but one).
        let mut one_off = all.clone();
        one_off[2] = one_off[2].with_found_peaks(1.0, &[221.0, 442.0, 666.0, 884.0, 1105.0]);
        assert!(shared_combs(&one_off[1], &one_off[2]));
        // A 6205: BPFI 162 Hz, 2·BSF 141 Hz.
        let apart = pair((5.3, 20.0, 0.2), (3.0, 5.0, -0.2), 162.0, 141.0);
        assert!(!shared_combs(&apart[1], &apart[2]));
    }

    #[test]
    fn a_shared_comb_goes_where_its_sidebands_point_or_is_either() {
        // Cage-rate sidebands on shared lines: the ball leads, and stands.
        let all = pair((5.4, 20.0, -2.5), (5.3, 20.0, 2.5), 221.0, 221.0);
        let top = &all[1];
        let rival = rival_leads(top, &all).expect("the ball leads");
        assert_eq!(rival.fault, FaultKind::Ball);
        assert!(ball_or_inner(rival, &all, detected).is_none());
        // Shaft-rate sidebands: the inner race stands.
        let all = pair((5.4, 20.0, 2.5), (5.3, 20.0, -2.5), 221.0, 221.0);
        assert!(rival_leads(&all[1], &all).is_none());
        assert!(ball_or_inner(&all[1], &all, detected).is_none());
        // No modulation (a uniform load): either.
        let all = pair((5.4, 20.0, 0.4), (5.3, 20.0, -0.4), 221.0, 221.0);
        assert!(rival_leads(&all[1], &all).is_none());
        let rival = ball_or_inner(&all[1], &all, detected).expect("a tie");
        assert_eq!(rival.fault, FaultKind::Ball);
    }

    #[test]
    fn apart_combs_are_either_only_when_both_patterns_show() {
        // CWRU 224-like (the leader, inner 4.3 at 10^-19, z 3.7; ball 2.3 at 10^-3.2, z 0.2):
        // the ball shows no pattern of its own: the inner race stands.
        let all = pair((4.3, 19.0, 3.7), (2.3, 3.2, 0.2), 162.0, 141.0);
        assert!(ball_or_inner(&all[1], &all, detected).is_none());
        // CWRU 105-like (inner 15, z 1.3; ball 4.9, z 0.1): the inner race.
        let all = pair((15.0, 14.7, 1.3), (4.9, 6.4, 0.1), 162.0, 141.0);
        assert!(ball_or_inner(&all[1], &all, detected).is_none());
        // A detected ball comb with its own cage-rate sidebands beside a named inner race:
        // either.
        let all = pair((20.0, 30.0, 1.0), (6.0, 6.0, 3.5), 162.0, 141.0);
        let rival = ball_or_inner(&all[1], &all, detected).expect("both show");
        assert_eq!(rival.fault, FaultKind::Ball);
        // ... but not when the rival is not detected on its own (small, or not beyond noise):
        // the 6205 at 0.6× speed, an inner comb of 2.9 at +6 beside a damaged ball.
        let all = pair((2.9, 6.0, 6.0), (13.0, 20.0, 1.0), 162.0, 141.0);
        assert!(ball_or_inner(&all[2], &all, detected).is_none());
        let all = pair((20.0, 30.0, 1.0), (6.0, 1.0, 3.5), 162.0, 141.0);
        assert!(ball_or_inner(&all[1], &all, detected).is_none());
    }

    #[test]
    fn the_outer_race_and_the_cage_have_no_rolling_rival() {
        let all = pair((5.4, 20.0, 0.0), (5.3, 20.0, 0.0), 221.0, 221.0);
        assert!(ball_or_inner(&all[0], &all, detected).is_none());
        assert!(ball_or_inner(&all[3], &all, detected).is_none());
        assert!(rival_leads(&all[3], &all).is_none());
    }
}
