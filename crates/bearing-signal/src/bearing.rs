//! Bearing geometry, the named-bearing catalog, and the kinematic fault frequencies
//! (MODELS.md §1).
//!
//! Why here and not in the config: the catalog and the equations are used by `analyze`, the
//! twin and the daemon alike; the config only names a bearing or gives custom geometry.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Geometry of a rolling-element bearing, in millimetres and degrees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BearingGeometry {
    /// Catalog name, or `custom` for geometry given by hand.
    pub name: String,
    /// Number of rolling elements.
    pub rolling_elements: u32,
    /// Rolling-element diameter `d` (mm).
    pub element_diameter_mm: f64,
    /// Pitch diameter `D` (mm).
    pub pitch_diameter_mm: f64,
    /// Contact angle `α` (degrees).
    pub contact_angle_deg: f64,
}

/// Why a bearing name or a custom geometry string was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BearingError {
    #[error("unknown bearing '{name}'; known bearings: {known}, or custom geometry such as \"z=9,d=7.94mm,D=39.04mm,alpha=0\"")]
    UnknownName { name: String, known: String },
    #[error("bad bearing geometry '{text}': {problem}; expected e.g. \"z=8,d=5.97mm,D=31.62mm,alpha=0\"")]
    BadGeometry { text: String, problem: String },
}

/// Which race of a bearing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Race {
    Outer,
    Inner,
}

/// One catalog entry: names it answers to, and its geometry.
struct CatalogEntry {
    names: &'static [&'static str],
    z: u32,
    d_mm: f64,
    pitch_mm: f64,
    alpha_deg: f64,
}

/// The named bearings. Geometry from the data sets' documentation
/// (../shared/data/README.md, MODELS.md §1) and the makers' tables.
const CATALOG: &[CatalogEntry] = &[
    // CWRU drive end.
    CatalogEntry {
        names: &["skf-6205-2rs", "6205-2rs", "6205", "cwru-de"],
        z: 9,
        d_mm: 7.94,
        pitch_mm: 39.04,
        alpha_deg: 0.0,
    },
    // CWRU fan end.
    CatalogEntry {
        names: &["skf-6203-2rs", "6203-2rs", "6203", "cwru-fe"],
        z: 8,
        d_mm: 6.7462,
        pitch_mm: 28.4988,
        alpha_deg: 0.0,
    },
    // Seed 002 (Siegen test stand).
    CatalogEntry {
        names: &["skf-61804", "61804"],
        z: 13,
        d_mm: 3.5,
        pitch_mm: 26.0,
        alpha_deg: 0.0,
    },
    // PRONOSTIA / PHM 2012.
    CatalogEntry {
        names: &["pronostia", "femto"],
        z: 13,
        d_mm: 3.5,
        pitch_mm: 25.6,
        alpha_deg: 0.0,
    },
    // MFPT data set (Society for Machinery Failure Prevention Technology): the NICE bearing,
    // roller diameter 0.235 in, pitch diameter 1.245 in, 8 elements, contact angle 0.
    CatalogEntry {
        names: &["mfpt", "nice-mfpt"],
        z: 8,
        d_mm: 5.969,
        pitch_mm: 31.623,
        alpha_deg: 0.0,
    },
    // IMS test rig.
    CatalogEntry {
        names: &["rexnord-za-2115", "za-2115", "ims"],
        z: 16,
        d_mm: 8.407,
        pitch_mm: 71.501,
        alpha_deg: 15.17,
    },
];

impl BearingGeometry {
    /// Looks a bearing up by catalog name (case-insensitive; `_` and ` ` count as `-`).
    pub fn from_catalog(name: &str) -> Result<Self, BearingError> {
        let wanted = name.trim().to_ascii_lowercase().replace(['_', ' '], "-");
        CATALOG
            .iter()
            .find(|entry| entry.names.contains(&wanted.as_str()))
            .map(|entry| BearingGeometry {
                name: entry.names[0].to_string(),
                rolling_elements: entry.z,
                element_diameter_mm: entry.d_mm,
                pitch_diameter_mm: entry.pitch_mm,
                contact_angle_deg: entry.alpha_deg,
            })
            .ok_or_else(|| BearingError::UnknownName {
                name: name.to_string(),
                known: Self::catalog_names().join(", "),
            })
    }

    /// The primary name of every catalog entry.
    pub fn catalog_names() -> Vec<&'static str> {
        CATALOG.iter().map(|entry| entry.names[0]).collect()
    }

    /// Either a catalog name or a custom geometry string (it contains `=`).
    pub fn parse(text: &str) -> Result<Self, BearingError> {
        if text.contains('=') {
            Self::parse_custom(text)
        } else {
            Self::from_catalog(text)
        }
    }

    /// Parses `z=8,d=5.97mm,D=31.62mm,alpha=0` (lengths in mm, or with an `in` suffix; the
    /// contact angle in degrees). Every problem is reported, not only the first.
    pub fn parse_custom(text: &str) -> Result<Self, BearingError> {
        let mut z = None;
        let mut d = None;
        let mut pitch = None;
        let mut alpha = 0.0;
        let mut problems = Vec::new();
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let Some((key, value)) = part.split_once('=') else {
                problems.push(format!("'{part}' is not key=value"));
                continue;
            };
            let value = value.trim();
            match key.trim() {
                "z" | "Z" => match value.parse::<u32>() {
                    Ok(n) if n >= 3 => z = Some(n),
                    _ => problems.push(format!(
                        "z={value} must be a whole number of rolling elements, at least 3"
                    )),
                },
                "d" => match parse_length_mm(value) {
                    Some(v) => d = Some(v),
                    None => problems.push(format!(
                        "d={value} is not a positive length (e.g. 7.94mm or 0.3125in)"
                    )),
                },
                "D" | "pitch" => match parse_length_mm(value) {
                    Some(v) => pitch = Some(v),
                    None => {
                        problems.push(format!("D={value} is not a positive length (e.g. 39.04mm)"))
                    }
                },
                "alpha" | "angle" => match value.trim_end_matches("deg").parse::<f64>() {
                    Ok(a) if (0.0..90.0).contains(&a) => alpha = a,
                    _ => problems.push(format!(
                        "alpha={value} must be an angle in degrees in [0, 90)"
                    )),
                },
                other => problems.push(format!("unknown key '{other}' (use z, d, D, alpha)")),
            }
        }
        if z.is_none() {
            problems.push("z (number of rolling elements) is missing".into());
        }
        if d.is_none() {
            problems.push("d (rolling-element diameter) is missing".into());
        }
        if pitch.is_none() {
            problems.push("D (pitch diameter) is missing".into());
        }
        if let (Some(d), Some(pitch)) = (d, pitch) {
            if d >= pitch {
                problems.push(format!("d={d} mm must be smaller than D={pitch} mm"));
            }
        }
        if !problems.is_empty() {
            return Err(BearingError::BadGeometry {
                text: text.to_string(),
                problem: problems.join("; "),
            });
        }
        Ok(BearingGeometry {
            name: "custom".into(),
            rolling_elements: z.unwrap_or_default(),
            element_diameter_mm: d.unwrap_or_default(),
            pitch_diameter_mm: pitch.unwrap_or_default(),
            contact_angle_deg: alpha,
        })
    }

    /// `d/D · cos α`, the ratio every fault frequency depends on.
    fn diameter_ratio(&self) -> f64 {
        self.element_diameter_mm / self.pitch_diameter_mm
            * self.contact_angle_deg.to_radians().cos()
    }

    /// Fault frequencies as multiples of the shaft rate (i.e. for `fr = 1 Hz`).
    pub fn fault_orders(&self) -> FaultFrequencies {
        self.fault_frequencies(1.0)
    }

    /// Radius of the path the rolling elements run on: the outer race `(D + d)/2` or the inner
    /// race `(D − d)/2`, mm (MODELS.md §4).
    pub fn race_radius_mm(&self, race: Race) -> f64 {
        match race {
            Race::Outer => (self.pitch_diameter_mm + self.element_diameter_mm) / 2.0,
            Race::Inner => (self.pitch_diameter_mm - self.element_diameter_mm) / 2.0,
        }
    }

    /// Time between the entry and the exit event of a race defect `length_mm` long, whose
    /// impacts repeat at `fault_hz` (BPFO or BPFI): `Δt = Z·L / (2π r f_d)` (MODELS.md §4).
    /// [`Self::defect_length_mm`] is its inverse.
    pub fn entry_exit_delay_s(&self, race: Race, length_mm: f64, fault_hz: f64) -> f64 {
        f64::from(self.rolling_elements) * length_mm
            / (std::f64::consts::TAU * self.race_radius_mm(race) * fault_hz)
    }

    /// The defect length whose entry and exit are `delay_s` apart: `L = Δt·2π r f_d / Z`.
    pub fn defect_length_mm(&self, race: Race, delay_s: f64, fault_hz: f64) -> f64 {
        delay_s * std::f64::consts::TAU * self.race_radius_mm(race) * fault_hz
            / f64::from(self.rolling_elements.max(1))
    }

    /// Fault frequencies at shaft rate `shaft_hz` (MODELS.md §1).
    pub fn fault_frequencies(&self, shaft_hz: f64) -> FaultFrequencies {
        let ratio = self.diameter_ratio();
        let z = f64::from(self.rolling_elements);
        let bsf = self.pitch_diameter_mm / (2.0 * self.element_diameter_mm)
            * shaft_hz
            * (1.0 - ratio * ratio);
        FaultFrequencies {
            shaft: shaft_hz,
            ftf: shaft_hz / 2.0 * (1.0 - ratio),
            bpfo: z * shaft_hz / 2.0 * (1.0 - ratio),
            bpfi: z * shaft_hz / 2.0 * (1.0 + ratio),
            bsf,
            two_bsf: 2.0 * bsf,
        }
    }

    /// The text [`BearingGeometry::parse`] reads back as this bearing: its catalog name when it
    /// is the catalog's entry, else the custom form `z=9,d=7.94mm,D=39.04mm,alpha=0`.
    pub fn spec(&self) -> String {
        match BearingGeometry::from_catalog(&self.name) {
            Ok(entry) if entry == *self => self.name.clone(),
            _ => format!(
                "z={},d={}mm,D={}mm,alpha={}",
                self.rolling_elements,
                self.element_diameter_mm,
                self.pitch_diameter_mm,
                self.contact_angle_deg
            ),
        }
    }
}

impl fmt::Display for BearingGeometry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} (z={}, d={} mm, D={} mm, alpha={} deg)",
            self.name,
            self.rolling_elements,
            self.element_diameter_mm,
            self.pitch_diameter_mm,
            self.contact_angle_deg
        )
    }
}

fn parse_length_mm(value: &str) -> Option<f64> {
    let (number, factor) = if let Some(n) = value.strip_suffix("mm") {
        (n, 1.0)
    } else if let Some(n) = value.strip_suffix("in") {
        (n, 25.4)
    } else {
        (value, 1.0)
    };
    number
        .trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(|v| v * factor)
}

/// The characteristic frequencies of a bearing at one shaft speed, in Hz.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FaultFrequencies {
    /// Shaft rotation frequency `fr`.
    pub shaft: f64,
    /// Cage (fundamental train) frequency.
    pub ftf: f64,
    /// Ball pass frequency, outer race.
    pub bpfo: f64,
    /// Ball pass frequency, inner race.
    pub bpfi: f64,
    /// Ball spin frequency.
    pub bsf: f64,
    /// Twice the ball spin frequency: the impact rate of a ball defect.
    pub two_bsf: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn custom_geometry_reports_every_problem() {
        let err = BearingGeometry::parse_custom("z=two,d=-1mm,alpha=95")
            .unwrap_err()
            .to_string();
        for needle in [
            "z=two",
            "d=-1mm",
            "alpha=95",
            "D (pitch diameter) is missing",
        ] {
            assert!(err.contains(needle), "{err} lacks {needle}");
        }
    }

    #[test]
    fn custom_geometry_accepts_inches() {
        let b = BearingGeometry::parse("z=9,d=0.3126in,D=1.537in,alpha=0").unwrap();
        assert!((b.element_diameter_mm - 7.94).abs() < 0.01);
    }
}

/// The fault classes that have a characteristic frequency.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize, JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    OuterRace,
    InnerRace,
    Ball,
    Cage,
}

impl FaultKind {
    pub const ALL: [FaultKind; 4] = [
        FaultKind::OuterRace,
        FaultKind::InnerRace,
        FaultKind::Ball,
        FaultKind::Cage,
    ];

    /// The wire name: `outer_race`, `inner_race`, `ball`, `cage`.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::OuterRace => "outer_race",
            FaultKind::InnerRace => "inner_race",
            FaultKind::Ball => "ball",
            FaultKind::Cage => "cage",
        }
    }

    /// Position in [`FaultKind::ALL`] (the order of every per-fault array).
    pub fn index(self) -> usize {
        self as usize
    }

    /// The short label engineers use for the frequency: BPFO, BPFI, 2BSF (twice the ball spin frequency), FTF.
    pub fn frequency_label(self) -> &'static str {
        match self {
            FaultKind::OuterRace => "BPFO",
            FaultKind::InnerRace => "BPFI",
            FaultKind::Ball => "2BSF",
            FaultKind::Cage => "FTF",
        }
    }

    /// The repetition frequency of this fault's impacts.
    pub fn frequency(self, f: &FaultFrequencies) -> f64 {
        match self {
            FaultKind::OuterRace => f.bpfo,
            FaultKind::InnerRace => f.bpfi,
            FaultKind::Ball => f.two_bsf,
            FaultKind::Cage => f.ftf,
        }
    }

    /// The modulation that makes sidebands around this fault's harmonics, if any.
    pub fn sideband_spacing(self, f: &FaultFrequencies) -> Option<f64> {
        match self {
            FaultKind::InnerRace => Some(f.shaft),
            FaultKind::Ball => Some(f.ftf),
            FaultKind::OuterRace | FaultKind::Cage => None,
        }
    }
}

impl fmt::Display for FaultKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
