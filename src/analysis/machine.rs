//! Machine faults from the velocity spectrum at shaft orders: unbalance, misalignment and
//! mechanical looseness, the three a condition monitor is expected to name besides the
//! bearing (issue 31 item 2; the patterns of `bearing_signal::machine_fault`).
//!
//! Why from velocity: the charts plant engineers read these faults from are velocity spectra
//! in mm/s, and the ISO 10816-3 zones judge how bad a vibration is in the same unit, so a
//! finding's level is the zone of its own lines' velocity, not a score of our own.
//!
//! Method (choices, calibrated on the simulator only; docs/DIAGNOSIS.md §4 "Machine faults at
//! shaft orders"):
//! - **Lines.** From the velocity power per bin (the ISO integrator's, (mm/s)² per bin), each
//!   order `k = 0.5, 1, 1.5, …, 10` of the shaft rate is the strongest bin within ±1 % of
//!   `k·fr` (at least ±1 bin) with its two neighbours (a Hann window's main lobe holds a tone's
//!   power in three bins); its floor is the median bin power of the ±`fr/4` around it without
//!   those three, so a line stands out by `√(line / (3·floor))`.
//! - **Patterns**, over the overall velocity `v` of the band (what the ISO zone is judged on):
//!   - looseness: at least 3 integer orders of 3…10 and 2 half orders standing out; its
//!     velocity is the RMS of every standing line;
//!   - misalignment: 2× at least half of 1× (`V2 ≥ 0.5·V1`); its velocity `√(V1² + V2² + V3²)`;
//!   - unbalance: 1× dominant (`V2 < 0.5·V1`); its velocity `V1`;
//!   - each needs its velocity to hold at least half the overall mean square (`P² ≥ 0.5·v²`):
//!     the shaft orders must be what makes the machine vibrate.
//! - **Level** = the ISO zone of the finding's own velocity: zone C asks for watch, D for alarm,
//!   A and B for nothing (a healthy machine always has some 1×). Only findings at C or D are
//!   reported.
//!
//! Sans-IO and allocation-free per call except the findings it returns.

use super::iso::ZoneLimits;
use crate::machine_fault::MachineFaultKind;
use crate::messages::IsoZone;
use serde::{Deserialize, Serialize};

/// The orders looked at: 0.5× to 10× in steps of a half.
pub const ORDERS: usize = 20;

/// Where a machine-fault finding is reported, and how lines are found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MachineFaultSettings {
    /// Half-width of the search around each order, relative to its frequency.
    pub order_tolerance: f64,
    /// A line "stands out" when its amplitude is this many times its floor's.
    pub line_over_floor: f64,
    /// The share of the overall velocity mean square a pattern must hold.
    pub min_share: f64,
}

impl Default for MachineFaultSettings {
    fn default() -> Self {
        MachineFaultSettings {
            order_tolerance: 0.01,
            line_over_floor: 4.0,
            min_share: 0.5,
        }
    }
}

/// One order's line in the velocity spectrum.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OrderLine {
    /// Multiple of the shaft rate.
    pub order: f64,
    /// The line's velocity RMS, mm/s.
    pub velocity_mm_s: f64,
    /// Its amplitude over the floor's around it.
    pub over_floor: f64,
}

/// A machine fault found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MachineFinding {
    pub kind: MachineFaultKind,
    /// The ISO zone of the pattern's own velocity: C asks for watch, D for alarm.
    pub zone: IsoZone,
    /// The pattern's velocity RMS, mm/s.
    pub velocity_mm_s: f64,
    /// Its share of the overall velocity mean square.
    pub share: f64,
    /// The lines it rests on.
    pub orders: Vec<OrderLine>,
}

/// The lines at orders 0.5× … 10× of `shaft_hz` in a velocity power spectrum
/// (`per_bin_mm2_s2[k]` at `k · bin_hz`, 0 outside the band). Orders above the spectrum, or
/// whose neighbourhood is empty, have velocity 0.
pub fn order_lines(
    per_bin_mm2_s2: &[f64],
    bin_hz: f64,
    shaft_hz: f64,
    settings: &MachineFaultSettings,
) -> [OrderLine; ORDERS] {
    std::array::from_fn(|i| {
        let order = 0.5 * (i + 1) as f64;
        let (velocity_mm_s, over_floor) =
            line_at(per_bin_mm2_s2, bin_hz, order * shaft_hz, shaft_hz, settings)
                .unwrap_or((0.0, 0.0));
        OrderLine {
            order,
            velocity_mm_s,
            over_floor,
        }
    })
}

/// (velocity RMS, amplitude over floor) of the line near `f_hz`.
fn line_at(
    power: &[f64],
    bin_hz: f64,
    f_hz: f64,
    shaft_hz: f64,
    settings: &MachineFaultSettings,
) -> Option<(f64, f64)> {
    if !(bin_hz > 0.0 && f_hz > 0.0 && shaft_hz > 0.0) {
        return None;
    }
    let centre = f_hz / bin_hz;
    let reach = (settings.order_tolerance * centre).max(1.0);
    let lo = (centre - reach).floor().max(1.0) as usize;
    let hi = ((centre + reach).ceil() as usize).min(power.len().checked_sub(2)?);
    if lo > hi {
        return None;
    }
    let peak = (lo..=hi).max_by(|&a, &b| power[a].total_cmp(&power[b]))?;
    let line: f64 = power[peak - 1..=peak + 1].iter().sum();
    if line <= 0.0 {
        return None;
    }
    // The floor: median bin of ±fr/4 around the line, its own three bins left out.
    let span = ((0.25 * shaft_hz / bin_hz).round() as usize).max(4);
    let mut around = [0.0f64; 64];
    let mut n = 0;
    let from = peak.saturating_sub(span);
    let to = (peak + span).min(power.len() - 1);
    let stride = ((to - from) / around.len()).max(1);
    for k in (from..=to).step_by(stride) {
        if k.abs_diff(peak) > 1 && n < around.len() {
            around[n] = power[k];
            n += 1;
        }
    }
    let floor = median(&mut around[..n]);
    let over_floor = if floor > 0.0 {
        (line / (3.0 * floor)).sqrt()
    } else {
        f64::INFINITY
    };
    Some((line.sqrt(), over_floor))
}

fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The machine faults `lines` show, at zone C or D of `limits`, for an overall velocity RMS of
/// `overall_mm_s` in the band.
pub fn machine_faults(
    lines: &[OrderLine; ORDERS],
    overall_mm_s: f64,
    limits: &ZoneLimits,
    settings: &MachineFaultSettings,
) -> Vec<MachineFinding> {
    let at = |order: f64| lines[((order / 0.5) as usize).saturating_sub(1)];
    let stands = |l: &OrderLine| l.over_floor >= settings.line_over_floor;
    let overall_ms = overall_mm_s * overall_mm_s;
    let finding = |kind, parts: Vec<OrderLine>| {
        let ms: f64 = parts.iter().map(|l| l.velocity_mm_s.powi(2)).sum();
        let share = if overall_ms > 0.0 {
            ms / overall_ms
        } else {
            0.0
        };
        let velocity_mm_s = ms.sqrt();
        let zone = limits.zone(velocity_mm_s);
        (share >= settings.min_share && zone >= IsoZone::C).then_some(MachineFinding {
            kind,
            zone,
            velocity_mm_s,
            share,
            orders: parts,
        })
    };
    let integer_high = lines
        .iter()
        .filter(|l| l.order >= 3.0 && l.order.fract() == 0.0 && stands(l))
        .count();
    let halves = lines
        .iter()
        .filter(|l| l.order.fract() == 0.5 && stands(l))
        .count();
    let found = if integer_high >= 3 && halves >= 2 {
        let standing = lines.iter().copied().filter(stands).collect();
        finding(MachineFaultKind::Looseness, standing)
    } else {
        let (v1, v2) = (at(1.0), at(2.0));
        if !stands(&v1) {
            None
        } else if v2.velocity_mm_s >= 0.5 * v1.velocity_mm_s {
            finding(MachineFaultKind::Misalignment, vec![v1, v2, at(3.0)])
        } else {
            finding(MachineFaultKind::Unbalance, vec![v1])
        }
    };
    found.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::envelope::FftPlans;
    use crate::analysis::iso::{record_severity, SeveritySettings};
    use crate::machine_fault::MachineFault;
    use bearing_signal::simulate::{Nuisance, SimulatedFault, SimulationParams, Simulator};

    const RPM: f64 = 1772.0;

    /// A machine in fair condition ([`Nuisance::typical`], a 1× of 0.05 g), or with nothing
    /// at shaft orders but the machine fault (`clean`).
    fn findings(
        fault: SimulatedFault,
        machine: Option<MachineFault>,
        clean: bool,
    ) -> Vec<MachineFinding> {
        let example = SimulationParams::example(fault);
        let params = SimulationParams {
            fs_hz: 25_600.0,
            nuisance: Nuisance {
                machine_fault: machine,
                ..if clean {
                    Nuisance::none()
                } else {
                    Nuisance::typical()
                }
            },
            shaft_tone_g: if clean { 0.0 } else { example.shaft_tone_g },
            ..example
        };
        let signal = Simulator::record(params, 10.0);
        let severity = record_severity(
            &mut FftPlans::default(),
            &signal,
            25_600.0,
            RPM,
            SeveritySettings::default(),
        )
        .expect("a 10 s record has a velocity");
        let settings = MachineFaultSettings::default();
        let lines = order_lines(
            &severity.per_bin_mm2_s2,
            severity.bin_hz,
            RPM / 60.0,
            &settings,
        );
        machine_faults(&lines, severity.rms_mm_s, &severity.limits, &settings)
    }

    #[test]
    fn each_simulated_machine_fault_is_named_on_a_machine_in_fair_condition() {
        for kind in MachineFaultKind::ALL {
            for velocity_mm_s in [3.5, 8.0] {
                let machine = Some(MachineFault {
                    kind,
                    velocity_mm_s,
                });
                let found = findings(SimulatedFault::None, machine, false);
                let kinds: Vec<_> = found.iter().map(|f| f.kind).collect();
                assert_eq!(
                    kinds,
                    [kind],
                    "{} at {velocity_mm_s}: {found:?}",
                    kind.name()
                );
            }
        }
    }

    #[test]
    fn a_machine_faults_velocity_and_zone_are_its_lines() {
        for kind in MachineFaultKind::ALL {
            for (velocity_mm_s, zone) in [(3.5, IsoZone::C), (8.0, IsoZone::D)] {
                let machine = Some(MachineFault {
                    kind,
                    velocity_mm_s,
                });
                let found = findings(SimulatedFault::None, machine, true);
                assert_eq!(
                    found.len(),
                    1,
                    "{} at {velocity_mm_s}: {found:?}",
                    kind.name()
                );
                let f = &found[0];
                assert_eq!(f.kind, kind, "{found:?}");
                // The pattern's velocity is its simulated lines' (within 5 %: leakage, noise).
                let simulated = velocity_mm_s
                    * kind
                        .orders()
                        .iter()
                        .filter(|(order, _)| f.orders.iter().any(|l| l.order == *order))
                        .map(|(_, relative)| relative * relative)
                        .sum::<f64>()
                        .sqrt();
                assert!(
                    (f.velocity_mm_s / simulated - 1.0).abs() < 0.05,
                    "{}: {:.2} mm/s found, {simulated:.2} simulated",
                    kind.name(),
                    f.velocity_mm_s
                );
                assert!(f.zone >= zone, "{found:?}");
            }
        }
    }

    #[test]
    fn a_healthy_machine_and_bearing_faults_raise_no_machine_fault() {
        for fault in SimulatedFault::ALL {
            let found = findings(fault, None, false);
            assert!(found.is_empty(), "{}: {found:?}", fault.name());
        }
    }

    #[test]
    fn a_weak_pattern_in_zone_b_is_not_reported() {
        let found = findings(
            SimulatedFault::None,
            Some(MachineFault {
                kind: MachineFaultKind::Unbalance,
                velocity_mm_s: 1.0,
            }),
            false,
        );
        assert!(found.is_empty(), "{found:?}");
    }

    #[test]
    fn empty_or_degenerate_spectra_give_no_line() {
        let settings = MachineFaultSettings::default();
        for (power, bin_hz, shaft_hz) in [
            (vec![], 1.0, 30.0),
            (vec![0.0; 10], 1.0, 30.0),
            (vec![1.0; 4096], 0.0, 30.0),
            (vec![1.0; 4096], 1.0, f64::NAN),
        ] {
            let lines = order_lines(&power, bin_hz, shaft_hz, &settings);
            assert!(lines.iter().all(|l| l.velocity_mm_s == 0.0), "{lines:?}");
            let limits = ZoneLimits::of(
                crate::analysis::iso::MachineGroup::Medium,
                crate::analysis::iso::Foundation::Rigid,
            );
            assert!(machine_faults(&lines, 0.0, &limits, &settings).is_empty());
        }
    }
}
