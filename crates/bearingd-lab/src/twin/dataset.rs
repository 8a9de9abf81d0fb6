//! Labelled synthetic data sets (`bearingd dataset`), for training a learned diagnosis on
//! faults a machine has never had: records per fault drawn from the ranges of a spec, made by
//! the signal model or the physics twin. Each record's draws come from its own seed (the
//! spec's seed and the record's index), so a spec gives the same records on every machine,
//! in any order and on any number of threads.

use crate::bearing::BearingGeometry;
use crate::random::Rng;
use crate::twin::physics::{PhysicsModel, PhysicsParams};
use crate::twin::{Nuisance, SimulatedFault, SimulationParams, Simulator};
use serde::{Deserialize, Serialize};

/// The signal model's resonance when the spec gives none (the simulator's example).
const DEFAULT_RESONANCE_HZ: f64 = 3_000.0;

/// The spec's `bearing` that draws a geometry per record ([`random_bearing`]).
pub const RANDOM_BEARING: &str = "random";

/// Which model makes the records.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DatasetModel {
    /// Decaying impacts on a resonance (fast; severity = impact amplitude).
    Signal,
    /// The 6-DOF contact model (seconds per simulated second; severity = defect width).
    Physics,
}

impl DatasetModel {
    pub fn name(self) -> &'static str {
        match self {
            DatasetModel::Signal => "signal",
            DatasetModel::Physics => "physics",
        }
    }
}

/// What to generate (a TOML file; every key is listed in `config/dataset.toml`).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DatasetSpec {
    /// The seed of the whole set: the same seed, the same records.
    pub seed: u64,
    /// The conditions, each one class; a record's label is its position in this list.
    pub faults: Vec<SimulatedFault>,
    pub records_per_fault: usize,
    pub model: DatasetModel,
    pub duration_s: f64,
    pub fs_hz: f64,
    /// A catalog name, a custom geometry (`z=9,d=7.94mm,D=39.04mm,alpha=0`), or `random`: each
    /// record draws its own geometry (for a model that serves any bearing).
    pub bearing: String,
    /// Each range is `[low, high]`; a record draws uniformly within it.
    pub rpm: [f64; 2],
    /// White noise, g (standard deviation): the signal-to-noise ratio.
    pub noise_g: [f64; 2],
    /// Signal model: the impact amplitude at full load, g.
    pub amplitude_g: [f64; 2],
    /// Physics model: the defect width, mm.
    pub defect_width_mm: [f64; 2],
    /// Physics model: the radial load, N.
    pub load_n: [f64; 2],
    /// Signal model: add what a real machine adds besides the bearing (shaft harmonics, a
    /// gear mesh, random impulses, a 100 Hz tone).
    #[serde(default)]
    pub nuisance: bool,
    /// Signal model: the structural resonance the impacts ring, Hz (optional; 3 kHz when
    /// absent). A range makes the set cover machines with other resonances.
    #[serde(default)]
    pub resonance_hz: Option<[f64; 2]>,
}

/// One record of a set: its label and the conditions drawn for it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DatasetRecord {
    pub index: usize,
    pub fault: SimulatedFault,
    /// The fault's position in the spec's `faults`.
    pub label: usize,
    pub model: DatasetModel,
    pub rpm: f64,
    pub noise_g: f64,
    /// Impact amplitude (g, signal model) or defect width (mm, physics model); 0 when healthy.
    pub severity: f64,
    /// Radial load, N (physics model; 0 for the signal model).
    pub load_n: f64,
    /// The resonance, Hz (signal model; 0 for the physics model).
    pub resonance_hz: f64,
    /// The record's own seed (noise, slip).
    pub seed: u64,
    /// The record's bearing (the spec's, or its own draw with `bearing = "random"`), as a
    /// catalog name or a custom geometry.
    pub bearing: String,
}

impl DatasetSpec {
    /// Reads a spec, listing every problem at once.
    pub fn parse(text: &str) -> Result<DatasetSpec, Vec<String>> {
        let spec: DatasetSpec = toml::from_str(text).map_err(|e| vec![e.to_string()])?;
        let problems = spec.problems();
        if problems.is_empty() {
            Ok(spec)
        } else {
            Err(problems)
        }
    }

    fn problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        let mut check = |ok: bool, text: String| {
            if !ok {
                problems.push(text);
            }
        };
        check(
            !self.faults.is_empty(),
            "faults: give at least one, e.g. faults = [\"none\", \"outer_race\"]".into(),
        );
        check(
            self.records_per_fault >= 1,
            "records_per_fault: give at least 1".into(),
        );
        check(
            self.fs_hz.is_finite() && (1_000.0..=1e6).contains(&self.fs_hz),
            format!(
                "fs_hz = {}: give a sample rate in [1000, 1000000] Hz",
                self.fs_hz
            ),
        );
        check(
            self.duration_s.is_finite()
                && self.duration_s > 0.0
                && self.duration_s * self.fs_hz <= 1e8,
            format!(
                "duration_s = {}: give a positive length, at most 10⁸ samples",
                self.duration_s
            ),
        );
        if self.bearing != RANDOM_BEARING {
            if let Err(e) = BearingGeometry::parse(&self.bearing) {
                check(
                    false,
                    format!("bearing = {:?}: {e}, or \"{RANDOM_BEARING}\"", self.bearing),
                );
            }
        }
        let ranges = [
            ("rpm", self.rpm, f64::MIN_POSITIVE),
            ("noise_g", self.noise_g, 0.0),
            ("amplitude_g", self.amplitude_g, 0.0),
            ("defect_width_mm", self.defect_width_mm, f64::MIN_POSITIVE),
            ("load_n", self.load_n, f64::MIN_POSITIVE),
            (
                "resonance_hz",
                self.resonance_hz.unwrap_or([DEFAULT_RESONANCE_HZ; 2]),
                f64::MIN_POSITIVE,
            ),
        ];
        for (key, [lo, hi], least) in ranges {
            check(
                lo.is_finite() && hi.is_finite() && lo >= least && lo <= hi,
                format!("{key} = [{lo}, {hi}]: give [low, high] with {least} ≤ low ≤ high"),
            );
        }
        problems
    }

    /// Every record of the set, in order (fault by fault), with its drawn conditions.
    pub fn records(&self) -> Vec<DatasetRecord> {
        let mut records = Vec::with_capacity(self.faults.len() * self.records_per_fault);
        for (label, &fault) in self.faults.iter().enumerate() {
            for _ in 0..self.records_per_fault {
                let index = records.len();
                let seed = self.seed.wrapping_mul(1_000_003).wrapping_add(index as u64);
                let mut rng = Rng::new(seed);
                let mut draw = |[lo, hi]: [f64; 2]| lo + (hi - lo) * rng.uniform();
                let rpm = draw(self.rpm);
                let noise_g = draw(self.noise_g);
                let (severity, load_n) = match self.model {
                    DatasetModel::Signal => (draw(self.amplitude_g), 0.0),
                    DatasetModel::Physics => (draw(self.defect_width_mm), draw(self.load_n)),
                };
                let resonance_hz = match (self.model, self.resonance_hz) {
                    (DatasetModel::Signal, Some(range)) => draw(range),
                    (DatasetModel::Signal, None) => DEFAULT_RESONANCE_HZ,
                    (DatasetModel::Physics, _) => 0.0,
                };
                // Drawn last, so that a set with a fixed bearing draws what it always drew.
                let bearing = if self.bearing == RANDOM_BEARING {
                    random_bearing(&mut rng).spec()
                } else {
                    self.bearing.clone()
                };
                records.push(DatasetRecord {
                    index,
                    fault,
                    label,
                    model: self.model,
                    rpm,
                    noise_g,
                    severity: if fault == SimulatedFault::None {
                        0.0
                    } else {
                        severity
                    },
                    load_n,
                    resonance_hz,
                    seed,
                    bearing,
                });
            }
        }
        records
    }

    /// The samples (g) of `record`.
    pub fn generate(&self, record: &DatasetRecord) -> Result<Vec<f32>, String> {
        let bearing = record.geometry()?;
        match self.model {
            DatasetModel::Signal => {
                let params = SimulationParams {
                    fault: record.fault,
                    rpm: record.rpm,
                    bearing,
                    fs_hz: self.fs_hz,
                    amplitude_g: record.severity,
                    noise_g: record.noise_g,
                    nuisance: if self.nuisance {
                        Nuisance::typical()
                    } else {
                        Nuisance::none()
                    },
                    resonance_hz: record.resonance_hz,
                    onset_s: 0.0,
                    ramp_s: 0.0,
                    seed: record.seed,
                    ..SimulationParams::example(record.fault)
                };
                Ok(Simulator::record(params, self.duration_s))
            }
            DatasetModel::Physics => {
                let mut params = PhysicsParams::new(bearing, record.rpm, record.fault);
                params.fs_hz = self.fs_hz;
                params.duration_s = self.duration_s;
                params.noise_g = record.noise_g;
                params.seed = record.seed;
                params.load_n = record.load_n;
                if record.fault != SimulatedFault::None {
                    params.defect_width_mm = record.severity;
                }
                let mut samples = vec![0f32; params.samples()];
                let mut model = PhysicsModel::new(params).map_err(|e| e.to_string())?;
                model.fill(&mut samples).map_err(|e| e.to_string())?;
                Ok(samples)
            }
        }
    }
}

impl DatasetRecord {
    /// The record's bearing geometry.
    pub fn geometry(&self) -> Result<BearingGeometry, String> {
        BearingGeometry::parse(&self.bearing)
            .map_err(|e| format!("bearing {:?}: {e}", self.bearing))
    }
}

/// A deep-groove or angular-contact ball bearing of plausible proportions: 7 to 18 balls, ball
/// over pitch diameter 0.11 to 0.30, pitch 25 to 75 mm, and half of them with a contact angle
/// of 5° to 25°. Its fault orders span those of the catalog's bearings and more (BPFO 2.4–8.1
/// shaft orders, BPFI 3.8–11.7, BSF 1.5–4.5; the catalog's: 3.0–7.1, 4.8–8.9, 2.0–4.2).
pub fn random_bearing(rng: &mut Rng) -> BearingGeometry {
    let balls = 7 + (rng.uniform() * 12.0).floor().min(11.0) as u32;
    let ratio = 0.11 + 0.19 * rng.uniform();
    let pitch_mm = 25.0 + 50.0 * rng.uniform();
    let angular = rng.uniform() < 0.5;
    let contact_angle_deg = if angular {
        5.0 + 20.0 * rng.uniform()
    } else {
        0.0
    };
    // Rounded as a catalog would give them, so that the record's spec reads back the same.
    let round = |v: f64, places: i32| (v * 10f64.powi(places)).round() / 10f64.powi(places);
    BearingGeometry {
        name: "custom".to_string(),
        rolling_elements: balls,
        element_diameter_mm: round(ratio * pitch_mm, 3),
        pitch_diameter_mm: round(pitch_mm, 3),
        contact_angle_deg: round(contact_angle_deg, 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPEC: &str = r#"
seed = 3
faults = ["none", "outer_race", "inner_race"]
records_per_fault = 2
model = "signal"
duration_s = 0.5
fs_hz = 12000
bearing = "skf-6205-2rs"
rpm = [1700, 1800]
noise_g = [0.05, 0.2]
amplitude_g = [0.5, 1.5]
defect_width_mm = [0.1, 0.5]
load_n = [500, 2000]
"#;

    #[test]
    fn a_spec_gives_the_same_labelled_records_whatever_the_order_they_are_made_in() {
        let spec = DatasetSpec::parse(SPEC).unwrap();
        let records = spec.records();
        assert_eq!(records.len(), 6);
        assert_eq!(
            records.iter().map(|r| r.label).collect::<Vec<_>>(),
            [0, 0, 1, 1, 2, 2]
        );
        assert!(records.iter().all(|r| (1700.0..=1800.0).contains(&r.rpm)));
        assert_eq!(records[0].severity, 0.0, "a healthy record has no defect");
        let forwards: Vec<_> = records.iter().map(|r| spec.generate(r).unwrap()).collect();
        let backwards: Vec<_> = records
            .iter()
            .rev()
            .map(|r| spec.generate(r).unwrap())
            .collect();
        assert_eq!(forwards[5], backwards[0]);
        assert_eq!(forwards[0].len(), 6000);
        assert_ne!(forwards[2], forwards[3], "two records of one class differ");
    }

    #[test]
    fn a_bad_spec_lists_every_problem() {
        let bad = SPEC
            .replace("fs_hz = 12000", "fs_hz = 10")
            .replace("rpm = [1700, 1800]", "rpm = [1800, 1700]")
            .replace("bearing = \"skf-6205-2rs\"", "bearing = \"nope\"");
        let problems = DatasetSpec::parse(&bad).unwrap_err();
        assert_eq!(problems.len(), 3, "{problems:?}");
        assert!(problems[0].contains("fs_hz"), "{problems:?}");
        assert!(
            problems.iter().any(|p| p.contains("bearing")),
            "{problems:?}"
        );
        assert!(problems.iter().any(|p| p.contains("rpm")), "{problems:?}");
    }

    #[test]
    fn a_random_bearing_set_draws_a_geometry_per_record_and_keeps_the_rest_of_its_draws() {
        let fixed = DatasetSpec::parse(SPEC).unwrap().records();
        let random = DatasetSpec::parse(&SPEC.replace("\"skf-6205-2rs\"", "\"random\""))
            .unwrap()
            .records();
        assert!(fixed.iter().all(|r| r.bearing == "skf-6205-2rs"));
        for (f, r) in fixed.iter().zip(&random) {
            assert_eq!(
                (f.rpm, f.noise_g, f.severity),
                (r.rpm, r.noise_g, r.severity)
            );
            let geometry = r.geometry().expect("the drawn geometry reads back");
            assert_eq!(geometry.spec(), r.bearing);
        }
        let distinct: std::collections::BTreeSet<_> = random.iter().map(|r| &r.bearing).collect();
        assert_eq!(distinct.len(), random.len(), "{distinct:?}");
        let mut rng = Rng::new(11);
        for _ in 0..2_000 {
            let b = random_bearing(&mut rng);
            let f = b.fault_frequencies(1.0);
            assert!((7..=18).contains(&b.rolling_elements), "{b:?}");
            assert!((2.3..8.2).contains(&f.bpfo), "{b:?} {f:?}");
            assert!((3.8..11.8).contains(&f.bpfi), "{b:?} {f:?}");
            assert!((1.4..4.6).contains(&f.bsf), "{b:?} {f:?}");
            assert_eq!(BearingGeometry::parse(&b.spec()).as_ref(), Ok(&b));
        }
    }
}
