//! The defect-size estimator ([`crate::analysis::defect_size`]) checked where the truth is
//! known: records of the physics twin at 48 kHz with a defect of given width, at several speeds,
//! loads and resonances, through the whole record analysis as `analyze` runs it.
//!
//! Why the physics twin and not the signal model: the signal model draws the entry and exit
//! events by construction (`SimulationParams::defect_length_mm`), so it would only test the
//! estimator against its own assumption. The physics twin computes them: the contact force
//! drops as the ball runs into the defect's half-sine profile and recovers as it leaves, through
//! masses, Hertz contacts and a resonator (docs/PHYSICS.md).
//!
//! The grid ([`full_grid`]) is what `cargo run --release -p bearingd-lab --example defect_size_grid` prints
//! and docs/DIAGNOSIS.md §5 reports; [`ci_cases`] is the subset the test runs.

use super::physics::{simulate, PhysicsError, PhysicsParams};
use super::SimulatedFault;
use crate::analysis::defect_size::{measure_for_fault, DefectSize, NotMeasured};
use crate::analysis::record::RecordAnalyzer;
use crate::analysis::{AnalysisError, AnalysisSettings, Verdict};
use crate::bearing::{BearingError, BearingGeometry, FaultKind};

/// The resonator's damping ratio in every case (the `simulate` command's default).
const DAMPING_RATIO: f64 = 0.05;

/// One validation record: a physics-twin defect and the conditions it runs under.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizingCase {
    /// Outer or inner race.
    pub fault: FaultKind,
    pub width_mm: f64,
    pub rpm: f64,
    pub load_n: f64,
    /// The resonator's natural frequency, Hz.
    pub resonance_hz: f64,
    pub noise_g: f64,
    pub fs_hz: f64,
    pub duration_s: f64,
    pub seed: u64,
}

impl SizingCase {
    /// A case with the grid's common settings: 48 kHz, 2 s, 1 % cage slip (in the parameters),
    /// 0.05 g of noise, seed 5.
    pub fn new(fault: FaultKind, width_mm: f64, rpm: f64, load_n: f64, resonance_hz: f64) -> Self {
        SizingCase {
            fault,
            width_mm,
            rpm,
            load_n,
            resonance_hz,
            noise_g: 0.05,
            fs_hz: 48_000.0,
            duration_s: 2.0,
            seed: 5,
        }
    }

    /// The physics twin's parameters: the SKF 6205 (CWRU's drive end) with this defect.
    pub fn params(&self) -> Result<PhysicsParams, BearingError> {
        let fault = match self.fault {
            FaultKind::InnerRace => SimulatedFault::InnerRace,
            _ => SimulatedFault::OuterRace,
        };
        let mut params = PhysicsParams::new(
            BearingGeometry::from_catalog("skf-6205-2rs")?,
            self.rpm,
            fault,
        );
        params.load_n = self.load_n;
        params.defect_width_mm = self.width_mm;
        let s = &mut params.structure;
        s.resonator_stiffness =
            s.resonator_mass_kg * (std::f64::consts::TAU * self.resonance_hz).powi(2);
        s.resonator_damping =
            2.0 * DAMPING_RATIO * (s.resonator_stiffness * s.resonator_mass_kg).sqrt();
        params.fs_hz = self.fs_hz;
        params.duration_s = self.duration_s;
        params.noise_g = self.noise_g;
        params.slip = 0.01;
        params.seed = self.seed;
        Ok(params)
    }

    /// Simulates the record, analyses it as `analyze` does, and sizes the simulated race defect
    /// in its hypothesis's band at its fitted frequency (whatever the verdict says).
    pub fn run(&self) -> Result<SizingOutcome, SizingError> {
        let params = self.params()?;
        let record = simulate(&params)?;
        let freqs = params.bearing.fault_frequencies(self.rpm / 60.0);
        let analysis = RecordAnalyzer::default().analyze(
            &record,
            self.fs_hz,
            &freqs,
            &AnalysisSettings::default(),
        )?;
        let size = measure_for_fault(&record, &analysis, self.fault, &params.bearing);
        Ok(SizingOutcome {
            case: *self,
            verdict: analysis.diagnosis.verdict,
            size,
        })
    }
}

/// Why a validation record could not be made or analysed.
#[derive(Debug, thiserror::Error)]
pub enum SizingError {
    #[error(transparent)]
    Bearing(#[from] BearingError),
    #[error("the physics twin failed: {0}")]
    Physics(#[from] PhysicsError),
    #[error("the analysis failed: {0}")]
    Analysis(#[from] AnalysisError),
}

/// What one case gave.
#[derive(Debug, Clone)]
pub struct SizingOutcome {
    pub case: SizingCase,
    /// What `analyze` would have said: the size is reported only when this names the fault.
    pub verdict: Verdict,
    pub size: Result<DefectSize, NotMeasured>,
}

impl SizingOutcome {
    /// (estimate − true) / true, when a size was measured.
    pub fn relative_error(&self) -> Option<f64> {
        self.size
            .as_ref()
            .ok()
            .map(|s| (s.value_mm - self.case.width_mm) / self.case.width_mm)
    }

    /// Whether the verdict names the simulated fault (only then does `analyze` report a size).
    pub fn named(&self) -> bool {
        matches!(
            (self.case.fault, self.verdict),
            (FaultKind::OuterRace, Verdict::OuterRace) | (FaultKind::InnerRace, Verdict::InnerRace)
        )
    }
}

/// The widths the issue asks for, mm.
pub const WIDTHS_MM: [f64; 6] = [0.1, 0.2, 0.3, 0.5, 0.7, 1.0];

/// Outer and inner race × [`WIDTHS_MM`] × 1200 and 1797 rpm × 500 and 2000 N × resonance 3 kHz
/// (the CWRU drive end's) and 15 kHz (the literature's default) = 96 records; with `noise_g`.
pub fn full_grid(noise_g: f64) -> Vec<SizingCase> {
    let mut cases = Vec::new();
    for fault in [FaultKind::OuterRace, FaultKind::InnerRace] {
        for resonance_hz in [3_000.0, 15_000.0] {
            for rpm in [1200.0, 1797.0] {
                for load_n in [500.0, 2000.0] {
                    for width_mm in WIDTHS_MM {
                        let mut case = SizingCase::new(fault, width_mm, rpm, load_n, resonance_hz);
                        case.noise_g = noise_g;
                        cases.push(case);
                    }
                }
            }
        }
    }
    cases
}

/// The test's subset: both races, both resonances, both speeds and loads, the widths the
/// estimator must size and two it must not size wrongly.
pub fn ci_cases() -> Vec<SizingCase> {
    use FaultKind::{InnerRace, OuterRace};
    vec![
        SizingCase::new(OuterRace, 0.5, 1797.0, 2000.0, 3_000.0),
        SizingCase::new(OuterRace, 1.0, 1200.0, 500.0, 15_000.0),
        SizingCase::new(InnerRace, 0.7, 1200.0, 2000.0, 3_000.0),
        SizingCase::new(InnerRace, 0.5, 1797.0, 500.0, 15_000.0),
        SizingCase::new(OuterRace, 0.1, 1797.0, 2000.0, 3_000.0),
        SizingCase::new(InnerRace, 0.2, 1200.0, 2000.0, 15_000.0),
    ]
}

/// The errors over a set of outcomes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizingSummary {
    pub cases: usize,
    pub sized: usize,
    /// Largest and mean |relative error| of the sized cases (0 when none).
    pub max_abs_error: f64,
    pub mean_abs_error: f64,
    /// Sized cases whose error lies within twice the reported uncertainty.
    pub within_two_sigma: usize,
}

pub fn summarize(outcomes: &[SizingOutcome]) -> SizingSummary {
    let sized: Vec<(f64, f64)> = outcomes
        .iter()
        .filter_map(|o| {
            let size = o.size.as_ref().ok()?;
            Some((size.value_mm - o.case.width_mm, size.uncertainty_mm))
        })
        .zip(outcomes.iter().filter_map(SizingOutcome::relative_error))
        .map(|((error, sigma), relative)| (relative.abs(), error.abs() / sigma.max(1e-12)))
        .collect();
    let n = sized.len();
    SizingSummary {
        cases: outcomes.len(),
        sized: n,
        max_abs_error: sized.iter().map(|s| s.0).fold(0.0, f64::max),
        mean_abs_error: if n == 0 {
            0.0
        } else {
            sized.iter().map(|s| s.0).sum::<f64>() / n as f64
        },
        within_two_sigma: sized.iter().filter(|s| s.1 <= 2.0).count(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 30's target on the physics twin: every size reported within ±50 % (the full grid
    /// gives 17 % at most at 0.05 g, 23 % at 0.2 g; DIAGNOSIS.md §5), the widths the estimator resolves sized, the ones
    /// below its resolution refused rather than sized wrongly. About 2 s in release.
    #[test]
    fn sizes_on_the_physics_twin_stay_within_half_the_true_width() {
        let outcomes: Vec<SizingOutcome> =
            ci_cases().iter().map(|case| case.run().unwrap()).collect();
        let mut report = String::new();
        for o in &outcomes {
            report += &format!(
                "\n  {:?} {} mm at {} rpm, {} N, {} Hz: {:?} (verdict {:?})",
                o.case.fault,
                o.case.width_mm,
                o.case.rpm,
                o.case.load_n,
                o.case.resonance_hz,
                o.size,
                o.verdict
            );
        }
        for o in &outcomes {
            if let Some(error) = o.relative_error() {
                assert!(error.abs() <= 0.5, "error {error:.2}:{report}");
            }
            if o.case.width_mm >= 0.5 {
                assert!(o.size.is_ok() && o.named(), "not sized:{report}");
            }
        }
        let summary = summarize(&outcomes);
        assert!(summary.sized >= 4, "{summary:?}:{report}");
        assert_eq!(summary.within_two_sigma, summary.sized, "{report}");
    }

    #[test]
    fn the_grid_is_the_one_the_issue_asks_for() {
        let grid = full_grid(0.05);
        assert_eq!(grid.len(), 2 * 6 * 2 * 2 * 2);
        assert!(grid
            .iter()
            .all(|c| c.fs_hz == 48_000.0 && c.noise_g == 0.05));
        for case in ci_cases() {
            assert!(grid.contains(&case), "{case:?} is not in the grid");
        }
    }
}
