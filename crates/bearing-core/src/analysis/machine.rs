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
//! - **In the daemon** ([`MachineDetector`], `[detectors.machine_faults]`): the velocity power
//!   per bin of every envelope window (its unwindowed spectrum, so no FFT of its own), summed
//!   over `averages` windows, then judged as a record is; one flag per kind, raised at the
//!   finding's zone C (watch) or D (alarm) with the fault flags' hysteresis and delays. It
//!   judges nothing while the speed is unknown, or where a half order spans fewer than 4 bins
//!   (the envelope window too short for the shaft rate).
//!
//! Sans-IO and allocation-free per call except the findings it returns.

use super::detect::{ChannelContext, ChannelDetector, RecordFindings, RecordView, WindowView};
use super::flags::FaultFlag;
use super::iso::{band_hz, SeveritySettings, VelocityIntegrator, ZoneLimits};
use crate::machine_fault::MachineFaultKind;
use crate::messages::detect::machine::{machine_flag_of, MachineFlagMessage, MachineMessage};
use crate::messages::detect::FlagSpec;
use crate::messages::{DetectorMessage, FlagLevel, IsoZone};
use serde::{Deserialize, Serialize};

/// The orders looked at: 0.5× to 10× in steps of a half.
pub const ORDERS: usize = 20;

/// Where a machine-fault finding is reported, and how lines are found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
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
    // Allocates only for a finding it reports (the daemon calls this every few windows).
    let finding = |kind, parts: &[OrderLine]| {
        let ms: f64 = parts.iter().map(|l| l.velocity_mm_s.powi(2)).sum();
        let share = if overall_ms > 0.0 {
            ms / overall_ms
        } else {
            0.0
        };
        let velocity_mm_s = ms.sqrt();
        let zone = limits.zone(velocity_mm_s);
        (share >= settings.min_share && zone >= IsoZone::C).then(|| MachineFinding {
            kind,
            zone,
            velocity_mm_s,
            share,
            orders: parts.to_vec(),
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
        let mut standing = [OrderLine {
            order: 0.0,
            velocity_mm_s: 0.0,
            over_floor: 0.0,
        }; ORDERS];
        let mut n = 0;
        for line in lines.iter().filter(|l| stands(l)) {
            standing[n] = *line;
            n += 1;
        }
        finding(MachineFaultKind::Looseness, &standing[..n])
    } else {
        let (v1, v2) = (at(1.0), at(2.0));
        if !stands(&v1) {
            None
        } else if v2.velocity_mm_s >= 0.5 * v1.velocity_mm_s {
            finding(MachineFaultKind::Misalignment, &[v1, v2, at(3.0)])
        } else {
            finding(MachineFaultKind::Unbalance, &[v1])
        }
    };
    found.into_iter().collect()
}

/// The fewest bins a half order must span for its lines to be told from their floor.
const MIN_BINS_PER_HALF_ORDER: f64 = 4.0;

/// Whether spectra of `bin_hz` resolve the half orders of `shaft_hz`.
pub fn orders_resolved(bin_hz: f64, shaft_hz: f64) -> bool {
    bin_hz > 0.0 && 0.5 * shaft_hz >= MIN_BINS_PER_HALF_ORDER * bin_hz
}

impl MachineFaultSettings {
    /// What is wrong with the settings, as `(key, problem and fix)`.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut problems = Vec::new();
        if !(self.order_tolerance > 0.0 && self.order_tolerance <= 0.1) {
            problems.push((
                "order_tolerance",
                format!(
                    "{} is outside (0, 0.1]; use a small fraction, e.g. order_tolerance = 0.01",
                    self.order_tolerance
                ),
            ));
        }
        if !(self.line_over_floor >= 1.0 && self.line_over_floor <= 100.0) {
            problems.push((
                "line_over_floor",
                format!(
                    "{} is outside [1, 100]; set it in that range, e.g. line_over_floor = 4.0",
                    self.line_over_floor
                ),
            ));
        }
        if !(self.min_share > 0.0 && self.min_share <= 1.0) {
            problems.push((
                "min_share",
                format!(
                    "{} is outside (0, 1]; set a share above 0 and at most 1, e.g. min_share = 0.5",
                    self.min_share
                ),
            ));
        }
        problems
    }

    /// The machine faults of a whole record (`analyze`): key `machine_faults`, a list of
    /// findings (empty when none), or null with the reason in the text when the record cannot
    /// be judged: no velocity (no scale to g), or windows too short to resolve half orders.
    pub fn analyze_record(
        &self,
        record: &RecordView<'_>,
        severity: &SeveritySettings,
    ) -> RecordFindings {
        let limits = ZoneLimits::of(severity.group, severity.foundation);
        let judged = match record.velocity {
            None => Err("the record has no velocity (a WAV file holds no scale to g; \
                 export the record in g, as CSV or .mat)"
                .to_string()),
            Some(v) if !orders_resolved(v.bin_hz, record.shaft_hz) => Err(format!(
                "a half order ({:.2} Hz) spans {:.1} bins of {:.2} Hz, needs {MIN_BINS_PER_HALF_ORDER}: \
                 the record is too short for windows that resolve it",
                0.5 * record.shaft_hz,
                0.5 * record.shaft_hz / v.bin_hz.max(f64::MIN_POSITIVE),
                v.bin_hz
            )),
            Some(v) => {
                let lines = order_lines(&v.per_bin_mm2_s2, v.bin_hz, record.shaft_hz, self);
                Ok(machine_faults(&lines, v.rms_mm_s, &limits, self))
            }
        };
        let (json, lines) = match judged {
            Ok(found) => (
                serde_json::to_value(&found).unwrap_or_default(),
                found
                    .iter()
                    .map(|f| {
                        format!(
                            "machine fault: {} ({:.2} mm/s at shaft orders, zone {}, {:.0} % of the velocity)",
                            f.kind.name(),
                            f.velocity_mm_s,
                            f.zone.name(),
                            100.0 * f.share
                        )
                    })
                    .collect(),
            ),
            Err(why) => (
                serde_json::Value::Null,
                vec![format!("machine faults: not judged, {why}")],
            ),
        };
        RecordFindings {
            key: "machine_faults",
            json,
            lines,
        }
    }
}

/// The machine-fault detector of one channel.
pub struct MachineDetector {
    settings: MachineFaultSettings,
    limits: ZoneLimits,
    /// Reads the velocity power of the envelope's windows; `None` when the ISO band cannot be
    /// taken from them (it starts below bin 2).
    integrator: Option<VelocityIntegrator>,
    /// Velocity power per bin, (m/s)², summed over `windows` windows.
    power: Vec<f64>,
    windows: usize,
    averages: usize,
    /// One flag per kind, in [`MachineFaultKind::ALL`] order.
    flags: [FaultFlag; 3],
}

impl MachineDetector {
    pub fn new(
        settings: MachineFaultSettings,
        severity: SeveritySettings,
        context: &mut ChannelContext<'_>,
    ) -> Self {
        let limits = ZoneLimits::of(severity.group, severity.foundation);
        let (lo, hi) = band_hz(context.shaft_hz * 60.0);
        let band = (lo, hi.min(context.fs_hz / 2.0));
        let integrator =
            VelocityIntegrator::new(context.window, context.fs_hz, band, context.plans);
        let integrator = integrator.takes_unwindowed().then_some(integrator);
        let flag = FaultFlag::new(limits.flag_settings(context.flags));
        MachineDetector {
            settings,
            limits,
            power: vec![
                0.0;
                if integrator.is_some() {
                    context.window / 2 + 1
                } else {
                    0
                }
            ],
            integrator,
            windows: 0,
            averages: context.averages.max(1),
            flags: [flag.clone(), flag.clone(), flag],
        }
    }

    /// Judges the summed windows: flag changes, then the reading.
    fn judge(
        &mut self,
        end_sample: u64,
        shaft_hz: f64,
        bin_hz: f64,
        out: &mut dyn FnMut(DetectorMessage),
    ) {
        let scale = 1e6 / self.windows as f64; // (m/s)² → (mm/s)², averaged
        self.power.iter_mut().for_each(|p| *p *= scale);
        let overall_mm_s = self.power.iter().sum::<f64>().sqrt();
        let lines = order_lines(&self.power, bin_hz, shaft_hz, &self.settings);
        let finding = machine_faults(&lines, overall_mm_s, &self.limits, &self.settings)
            .into_iter()
            .next();
        for (kind, flag) in MachineFaultKind::ALL.iter().zip(&mut self.flags) {
            let velocity_mm_s = finding
                .as_ref()
                .filter(|f| f.kind == *kind)
                .map_or(0.0, |f| f.velocity_mm_s);
            if let Some(change) = flag.update(velocity_mm_s, end_sample) {
                out(MachineFlagMessage {
                    channel: Default::default(),
                    end_sample: change.at_sample,
                    kind: *kind,
                    from: change.from,
                    to: change.to,
                    velocity_mm_s,
                    watch_mm_s: self.limits.bc_mm_s,
                    alarm_mm_s: self.limits.cd_mm_s,
                }
                .into());
            }
        }
        let at = |order: usize| lines[2 * order - 1].velocity_mm_s;
        out(MachineMessage {
            channel: Default::default(),
            end_sample,
            shaft_hz,
            overall_mm_s,
            orders_mm_s: [at(1), at(2), at(3)],
            fault: finding.as_ref().map(|f| f.kind),
            fault_mm_s: finding.as_ref().map_or(0.0, |f| f.velocity_mm_s),
            zone: finding.as_ref().map_or(IsoZone::A, |f| f.zone),
            windows_averaged: self.windows,
        }
        .into());
        self.power.iter_mut().for_each(|p| *p = 0.0);
        self.windows = 0;
    }
}

impl ChannelDetector for MachineDetector {
    fn restart_at(&mut self, _first_sample: u64) {
        self.power.iter_mut().for_each(|p| *p = 0.0);
        self.windows = 0;
    }

    fn on_samples(&mut self, _samples: &[f32], _out: &mut dyn FnMut(DetectorMessage)) {}

    fn on_window(&mut self, window: &WindowView<'_>, out: &mut dyn FnMut(DetectorMessage)) {
        let (Some(integrator), Some(shaft_hz)) = (&self.integrator, window.shaft_hz) else {
            return;
        };
        let bin_hz = integrator.bin_hz();
        if !orders_resolved(bin_hz, shaft_hz) {
            return;
        }
        let ms = integrator.mean_square_of_unwindowed(window.spectrum, Some(&mut self.power));
        if !ms.is_finite() {
            // A spectrum of another length: nothing was added.
            return;
        }
        self.windows += 1;
        if self.windows >= self.averages {
            self.judge(window.end_sample, shaft_hz, bin_hz, out);
        }
    }

    fn flag_levels(&self, out: &mut dyn FnMut(&'static FlagSpec, FlagLevel)) {
        for (kind, flag) in MachineFaultKind::ALL.iter().zip(&self.flags) {
            out(machine_flag_of(*kind), flag.level());
        }
    }
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
