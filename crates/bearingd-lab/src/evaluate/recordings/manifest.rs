//! A data set's `manifest.csv` (the format of `../shared/data/{cwru,ims,femto}`): one record
//! per row, its file relative to the manifest's folder, and what the row says about the
//! truth and the conditions the file may not state.
//!
//! Why a module of its own: the truth of a real recording is not a column every data set has.
//! CWRU names the fault, IMS says "early life (healthy)" in a note, FEMTO only gives the
//! fraction of the bearing's life; [`Truth::of_row`] turns each into one answer (or
//! "unknown", which is counted but never judged), and says where it came from.

use crate::messages::FaultKind;
use serde::Serialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// What a record really is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Truth {
    /// The bearing is healthy: any fault named is a false alarm.
    Healthy,
    Fault(FaultKind),
    /// The manifest does not say: the record is not judged (the two paths are still compared).
    Unknown,
}

impl Truth {
    /// `Some(the fault)`, `Some(None)` when healthy; `None` when unknown (not judged).
    pub fn judged(self) -> Option<Option<FaultKind>> {
        match self {
            Truth::Healthy => Some(None),
            Truth::Fault(kind) => Some(Some(kind)),
            Truth::Unknown => None,
        }
    }

    /// The row name of a confusion matrix.
    pub fn name(self) -> &'static str {
        match self {
            Truth::Healthy => "none",
            Truth::Fault(kind) => kind.name(),
            Truth::Unknown => "unknown",
        }
    }

    /// The rows of a confusion matrix, in order.
    pub const ROWS: [Truth; 6] = [
        Truth::Healthy,
        Truth::Fault(FaultKind::OuterRace),
        Truth::Fault(FaultKind::InnerRace),
        Truth::Fault(FaultKind::Ball),
        Truth::Fault(FaultKind::Cage),
        Truth::Unknown,
    ];

    /// The truth a manifest row states, and why: its `fault` column, else a `note` saying
    /// "healthy", else `life_frac` below one half (early life), else unknown. A `fault` value
    /// that names nothing known is an error (a typo must not turn into "unknown").
    pub fn of_row(row: &HashMap<String, String>) -> Result<(Truth, String), String> {
        let cell = |name: &str| row.get(name).map(|v| v.trim()).filter(|v| !v.is_empty());
        if let Some(fault) = cell("fault") {
            return match fault_of(fault) {
                Some(truth) => Ok((truth, format!("fault column '{fault}'"))),
                None => Err(format!(
                    "fault '{fault}' is not a fault this harness knows; write one of none \
                     (normal, healthy), inner, outer, ball, cage"
                )),
            };
        }
        if let Some(note) = cell("note").filter(|n| n.to_ascii_lowercase().contains("healthy")) {
            return Ok((Truth::Healthy, format!("note '{note}'")));
        }
        if let Some(text) = cell("life_frac") {
            let fraction: f64 = text.parse().map_err(|_| {
                format!("life_frac '{text}' is not a number; write a fraction such as 0.25")
            })?;
            return Ok(if fraction < EARLY_LIFE {
                (
                    Truth::Healthy,
                    format!("life_frac {fraction} < {EARLY_LIFE} (early life)"),
                )
            } else {
                (
                    Truth::Unknown,
                    format!("life_frac {fraction} >= {EARLY_LIFE}: the fault is not labelled"),
                )
            });
        }
        Ok((
            Truth::Unknown,
            "no fault, note or life_frac column says".to_string(),
        ))
    }
}

/// Below this fraction of its life a run-to-failure bearing counts as healthy.
pub const EARLY_LIFE: f64 = 0.5;

/// A `fault` value: the data sets' words and their obvious synonyms, in any case, with `-`
/// or a space for `_`.
fn fault_of(text: &str) -> Option<Truth> {
    let word = text.to_ascii_lowercase().replace(['-', ' '], "_");
    Some(match word.as_str() {
        "none" | "normal" | "healthy" | "ok" | "baseline" | "no_fault" => Truth::Healthy,
        "inner" | "inner_race" | "ir" | "bpfi" => Truth::Fault(FaultKind::InnerRace),
        "outer" | "outer_race" | "or" | "bpfo" => Truth::Fault(FaultKind::OuterRace),
        "ball" | "b" | "roller" | "rolling_element" | "re" | "bsf" => Truth::Fault(FaultKind::Ball),
        "cage" | "train" | "ftf" => Truth::Fault(FaultKind::Cage),
        _ => return None,
    })
}

/// One row of a manifest.
#[derive(Debug, Clone, Serialize)]
pub struct ManifestRecord {
    /// The row's line in the file (1: the header).
    pub line: usize,
    /// The file as the manifest names it, and resolved against the manifest's folder.
    pub name: String,
    pub file: PathBuf,
    /// `channel_var` (CWRU) or `channel`: the channel to analyse.
    pub channel: Option<String>,
    /// `fs_hz` and `rpm`: used only where the file does not state them.
    pub fs_hz: Option<f64>,
    pub rpm: Option<f64>,
    /// `bearing_geometry`: a catalog name or custom geometry, as `analyze --bearing` takes it;
    /// needed where neither the file nor its data set says (a user's own CSV or WAV). Not
    /// `bearing`: FEMTO and IMS manifests use that column for which bearing of the rig
    /// (`Bearing1_2`, `Rexnord ZA-2115`), a name, not a geometry.
    pub bearing: Option<String>,
    pub truth: Truth,
    pub truth_from: String,
    /// `sensor_location`: where the faulty bearing is (CWRU: `drive_end`).
    pub location: Option<String>,
}

impl ManifestRecord {
    /// The truth for `channel`: the record's, on every channel. (why) A channel's analysis
    /// names the kind of defect whose frequencies it sees, not which bearing makes them: the
    /// fault orders of CWRU's two bearings (SKF 6205 at the drive end, 6203 at the fan end) lie
    /// within 0.4 % of each other, inside the analysis's slip tolerance, so a drive-end defect
    /// seen from the fan end is, to the fan-end channel, the same defect. This is how the
    /// developer-set table counts them too (docs/results/developer-set.md).
    pub fn truth_on(&self, channel: &str) -> (Truth, String) {
        let seen_from = match self.location.as_deref() {
            Some(at) if !at.is_empty() => format!(
                "{}; seen on {channel} (the defect is at the {})",
                self.truth_from,
                at.replace('_', " ")
            ),
            _ => self.truth_from.clone(),
        };
        (self.truth, seen_from)
    }
}

/// A manifest read.
#[derive(Debug, Clone, Serialize)]
pub struct Manifest {
    pub path: PathBuf,
    pub records: Vec<ManifestRecord>,
}

/// Why a manifest cannot be used. Each message names the file and the fix.
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    #[error("{path}: cannot read the manifest: {source}; give the path of a manifest.csv")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: no `file` column in the header; the first line must name the columns, one of them `file`")]
    NoFileColumn { path: PathBuf },
    #[error("{path}: no records (only a header, or nothing); add one row per recording")]
    Empty { path: PathBuf },
    #[error("{path} line {line}: {problem}")]
    Row {
        path: PathBuf,
        line: usize,
        problem: String,
    },
}

impl Manifest {
    pub fn read(path: &Path) -> Result<Manifest, ManifestError> {
        let text = std::fs::read_to_string(path).map_err(|source| ManifestError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Manifest::parse(path, &text)
    }

    /// Parses `text` as the manifest at `path` (whose folder the file names are relative to).
    pub fn parse(path: &Path, text: &str) -> Result<Manifest, ManifestError> {
        let dir = path.parent().unwrap_or(Path::new(""));
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let header = lines.next().map(|(_, l)| split_csv(l)).unwrap_or_default();
        if !header.iter().any(|h| h == "file") {
            return Err(ManifestError::NoFileColumn {
                path: path.to_path_buf(),
            });
        }
        let records = lines
            .map(|(index, line)| {
                let row: HashMap<String, String> =
                    header.iter().cloned().zip(split_csv(line)).collect();
                record_of(dir, index + 1, &row).map_err(|problem| ManifestError::Row {
                    path: path.to_path_buf(),
                    line: index + 1,
                    problem,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        if records.is_empty() {
            return Err(ManifestError::Empty {
                path: path.to_path_buf(),
            });
        }
        Ok(Manifest {
            path: path.to_path_buf(),
            records,
        })
    }
}

fn record_of(
    dir: &Path,
    line: usize,
    row: &HashMap<String, String>,
) -> Result<ManifestRecord, String> {
    let cell = |name: &str| row.get(name).map(|v| v.trim()).filter(|v| !v.is_empty());
    let number = |name: &str| -> Result<Option<f64>, String> {
        cell(name)
            .map(|text| {
                text.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .ok_or_else(|| format!("{name} '{text}' is not a positive number"))
            })
            .transpose()
    };
    let name = cell("file").ok_or("the `file` cell is empty; name the recording")?;
    let (truth, truth_from) = Truth::of_row(row)?;
    Ok(ManifestRecord {
        line,
        name: name.to_string(),
        file: dir.join(name),
        channel: cell("channel_var").or(cell("channel")).map(String::from),
        fs_hz: number("fs_hz")?,
        rpm: number("rpm")?,
        bearing: cell("bearing_geometry").map(String::from),
        truth,
        truth_from,
        location: cell("sensor_location").map(String::from),
    })
}

/// One CSV line's fields, trimmed; a field in double quotes may hold commas and `""`.
fn split_csv(line: &str) -> Vec<String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(std::mem::take(&mut field).trim().to_string()),
            _ => field.push(c),
        }
    }
    fields.push(field.trim().to_string());
    fields
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth(pairs: &[(&str, &str)]) -> Result<Truth, String> {
        let row = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        Truth::of_row(&row).map(|(t, _)| t)
    }

    #[test]
    fn truth_comes_from_fault_then_note_then_life_fraction() {
        use FaultKind::*;
        for (fault, want) in [
            ("normal", Truth::Healthy),
            ("None", Truth::Healthy),
            ("healthy", Truth::Healthy),
            ("inner", Truth::Fault(InnerRace)),
            ("Inner-Race", Truth::Fault(InnerRace)),
            ("outer", Truth::Fault(OuterRace)),
            ("outer race", Truth::Fault(OuterRace)),
            ("ball", Truth::Fault(Ball)),
            ("rolling_element", Truth::Fault(Ball)),
            ("cage", Truth::Fault(Cage)),
        ] {
            assert_eq!(truth(&[("fault", fault)]), Ok(want), "{fault}");
        }
        // The fault column wins over a note.
        assert_eq!(
            truth(&[("fault", "outer"), ("note", "healthy")]),
            Ok(Truth::Fault(OuterRace))
        );
        assert_eq!(
            truth(&[("note", "early life (healthy)")]),
            Ok(Truth::Healthy)
        );
        assert_eq!(truth(&[("life_frac", "0.0011")]), Ok(Truth::Healthy));
        assert_eq!(truth(&[("life_frac", "0.97")]), Ok(Truth::Unknown));
        assert_eq!(truth(&[("note", "run 2")]), Ok(Truth::Unknown));
        assert_eq!(truth(&[]), Ok(Truth::Unknown));
        // A typo is an error naming the accepted words, never "unknown".
        let error = truth(&[("fault", "iner")]).unwrap_err();
        assert!(
            error.contains("'iner'") && error.contains("inner"),
            "{error}"
        );
        assert!(truth(&[("life_frac", "half")]).is_err());
    }

    #[test]
    fn rows_resolve_against_the_manifest_folder() {
        let text = "file,fault,fs_hz,rpm,channel_var,note,bearing_geometry,bearing\n\
                    a.mat,inner,12000,1797,X105_DE_time,,,Bearing1_2\n\
                    \n\
                    \"b, c.csv\",,,1800,,\"early life (healthy)\",skf-61804,\n";
        let manifest = Manifest::parse(Path::new("/data/set/manifest.csv"), text).unwrap();
        let [a, b] = manifest.records.as_slice() else {
            panic!("{manifest:?}")
        };
        assert_eq!(a.file, Path::new("/data/set/a.mat"));
        assert_eq!(a.channel.as_deref(), Some("X105_DE_time"));
        assert_eq!((a.fs_hz, a.rpm), (Some(12000.0), Some(1797.0)));
        assert_eq!(a.truth, Truth::Fault(FaultKind::InnerRace));
        assert_eq!(b.file, Path::new("/data/set/b, c.csv"));
        assert_eq!((b.line, b.channel.as_deref(), b.fs_hz), (4, None, None));
        assert_eq!(b.truth, Truth::Healthy);
        assert_eq!(
            (a.bearing.as_deref(), b.bearing.as_deref()),
            (None, Some("skf-61804"))
        );

        // Every channel sees the record's defect (the two bearings' fault orders coincide),
        // and says where it is.
        let drive_end = ManifestRecord {
            location: Some("drive_end".into()),
            ..a.clone()
        };
        for channel in ["X105_DE_time", "X105_BA_time", "X105_FE_time"] {
            let (truth, from) = drive_end.truth_on(channel);
            assert_eq!(truth, a.truth);
            assert!(
                from.contains("drive end") && from.contains(channel),
                "{from}"
            );
        }
        assert_eq!(a.truth_on("X105_FE_time"), (a.truth, a.truth_from.clone()));

        let bad = Manifest::parse(Path::new("m.csv"), "file,rpm\nx.mat,fast\n").unwrap_err();
        assert!(
            bad.to_string().contains("m.csv line 2: rpm 'fast'"),
            "{bad}"
        );
        assert!(matches!(
            Manifest::parse(Path::new("m.csv"), "name,rpm\n"),
            Err(ManifestError::NoFileColumn { .. })
        ));
        assert!(matches!(
            Manifest::parse(Path::new("m.csv"), "file,rpm\n"),
            Err(ManifestError::Empty { .. })
        ));
    }
}
