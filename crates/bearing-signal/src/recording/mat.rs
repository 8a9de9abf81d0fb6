//! MATLAB `.mat` files (v5 to v7.2, and `scipy.io.savemat`): which array is the signal, and
//! what the file says about its sample rate and shaft speed.
//!
//! The format itself is decoded by [`super::mat5`] into a tree of variables; this module
//! flattens it into numeric arrays named by their path (`bearing.gs`, `s(2).x`, `c{1}`) and
//! applies two sets of conventions:
//!
//! - **CWRU**: column vectors `XNNN_DE_time`, `XNNN_FE_time`, `XNNN_BA_time` (drive end, fan
//!   end, base; g) and `XNNNRPM` (measured shaft speed), NNN being the CWRU record number,
//!   which the file name repeats at its end (`…_105.mat`). Some files also carry another
//!   record's variables, so the default channel is the drive-end variable of the file's own
//!   record, never "the first one found". The rate comes from the file-name prefix.
//! - **Everything else** (the MFPT set's struct `bearing` with `gs`, `sr`, `rate`, `load`; a
//!   file saved as `save(f, 'x', 'fs')`): without `--channel`, the one vector of samples in
//!   the file; with several, an error listing them. The sample rate and the shaft speed come
//!   from scalars named as below, looked up beside the signal, then in each enclosing struct
//!   out to the top level (nearest first):
//!   - sample rate in Hz: `fs`, `sr`, `fs_hz`, `sample_rate`, `sample_rate_hz`,
//!     `sampling_rate`, `samplerate`, `sampling_frequency`;
//!   - shaft speed in rpm: `rpm`, `speed_rpm`, `shaft_rpm`;
//!   - shaft speed in Hz: `shaft_hz`, `fr`, and `rate` when a sample rate `sr` sits beside it
//!     (the MFPT convention: `rate` is the shaft rate; a warning says it was read so).
//!
//! Every name is matched without regard to case.

use super::mat5::{self, dims_text, NumericArray, Value};
use super::{file_name, Recording, RecordingError, RecordingFormat};
use std::path::Path;

/// A numeric array of the file, named by its path.
struct Leaf<'a> {
    path: String,
    array: &'a NumericArray,
}

impl Leaf<'_> {
    /// The path of the struct holding it (`""` at top level).
    fn parent(&self) -> &str {
        self.path.rfind('.').map_or("", |i| &self.path[..i])
    }

    /// Its own name, the last path component.
    fn field(&self) -> &str {
        self.path
            .rfind('.')
            .map_or(self.path.as_str(), |i| &self.path[i + 1..])
    }

    fn is_vector(&self) -> bool {
        self.array.real.len() > 1 && self.array.dims.iter().filter(|&&d| d > 1).count() == 1
    }

    fn scalar(&self) -> Option<f64> {
        match (self.array.real.as_slice(), self.array.complex) {
            ([v], false) => Some(*v),
            _ => None,
        }
    }
}

/// What a file holds: its numeric arrays by path, descriptions of everything else.
struct Contents<'a> {
    leaves: Vec<Leaf<'a>>,
    others: Vec<String>,
}

impl Contents<'_> {
    /// Everything, for error messages.
    fn listing(&self) -> Vec<String> {
        let mut all: Vec<String> = self.leaves.iter().map(|l| l.path.clone()).collect();
        all.extend(self.others.iter().cloned());
        all
    }

    /// The vectors of samples, for "which one?" messages.
    fn vectors(&self) -> Vec<String> {
        self.leaves
            .iter()
            .filter(|l| l.is_vector())
            .map(|l| format!("{} ({})", l.path, dims_text(&l.array.dims)))
            .collect()
    }
}

fn contents(file: &mat5::MatFile) -> Contents<'_> {
    let mut out = Contents {
        leaves: Vec::new(),
        others: Vec::new(),
    };
    for var in &file.variables {
        flatten(&var.value, var.name.clone(), &mut out);
    }
    out.others.extend(file.undecodable.iter().cloned());
    out
}

/// `s` for a 1x1 struct, `s(k)` (1-based, column-major) for element k of a struct array.
fn element_path(path: &str, k: usize, count: usize) -> String {
    if count == 1 {
        path.to_string()
    } else {
        format!("{path}({})", k + 1)
    }
}

fn flatten<'a>(value: &'a Value, path: String, out: &mut Contents<'a>) {
    match value {
        Value::Numeric(array) => out.leaves.push(Leaf { path, array }),
        Value::Struct(s) => {
            for (k, element) in s.elements.iter().enumerate() {
                let base = element_path(&path, k, s.elements.len());
                for (field, value) in s.fields.iter().zip(element) {
                    flatten(value, format!("{base}.{field}"), out);
                }
            }
            if s.elements.is_empty() {
                out.others.push(format!("{path} (empty struct)"));
            }
        }
        Value::Cell(cells) => {
            for (k, value) in cells.iter().enumerate() {
                flatten(value, format!("{path}{{{}}}", k + 1), out);
            }
        }
        Value::Other { dims, kind } if dims.is_empty() => {
            out.others.push(format!("{path} ({kind})"))
        }
        Value::Other { dims, kind } => out
            .others
            .push(format!("{path} ({} {kind})", dims_text(dims))),
    }
}

pub(super) fn channels(path: &Path, bytes: &[u8]) -> Result<Vec<String>, RecordingError> {
    let file = mat5::parse(path, bytes)?;
    Ok(contents(&file)
        .leaves
        .iter()
        .map(|l| l.path.clone())
        .collect())
}

/// The CWRU channel kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    DriveEnd,
    FanEnd,
    Base,
    Rpm,
}

impl Kind {
    fn suffix(self) -> &'static str {
        match self {
            Kind::DriveEnd => "_DE_time",
            Kind::FanEnd => "_FE_time",
            Kind::Base => "_BA_time",
            Kind::Rpm => "RPM",
        }
    }

    fn keyword(word: &str) -> Option<Kind> {
        [Kind::DriveEnd, Kind::FanEnd, Kind::Base]
            .into_iter()
            .find(|k| k.suffix()[1..3].eq_ignore_ascii_case(word))
    }
}

/// `X105_DE_time` → (105, DriveEnd); `X105RPM` → (105, Rpm).
fn cwru_name(name: &str) -> Option<(u32, Kind)> {
    let rest = name.strip_prefix('X')?;
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let record = rest[..digits].parse().ok()?;
    [Kind::DriveEnd, Kind::FanEnd, Kind::Base, Kind::Rpm]
        .into_iter()
        .find(|k| &rest[digits..] == k.suffix())
        .map(|k| (record, k))
}

/// The record number at the end of the file name: `…_IR007_0_105.mat` → 105.
fn file_record(path: &Path) -> Option<u32> {
    let stem = path.file_stem()?.to_str()?;
    let last = stem.rsplit('_').next()?;
    (!last.is_empty() && last.bytes().all(|b| b.is_ascii_digit()))
        .then(|| last.parse().ok())
        .flatten()
}

/// Sampling rate from the CWRU file-name conventions (data README caveat 1 for `normal_`).
fn fs_from_name(path: &Path) -> Option<f64> {
    let name = file_name(path).to_ascii_lowercase();
    if name.starts_with("12k_") {
        Some(12_000.0)
    } else if name.starts_with("48k_") || name.starts_with("normal_") {
        Some(48_000.0)
    } else {
        None
    }
}

/// Picks the variable of `kind` for the file's own record: the one whose number matches the
/// file name, else the only one of that kind, else an error.
fn by_kind(
    path: &Path,
    contents: &Contents<'_>,
    kind: Kind,
    warnings: &mut Vec<String>,
) -> Result<usize, RecordingError> {
    let record = file_record(path);
    let candidates: Vec<(usize, u32)> = contents
        .leaves
        .iter()
        .enumerate()
        .filter_map(|(i, a)| match cwru_name(&a.path) {
            Some((r, k)) if k == kind => Some((i, r)),
            _ => None,
        })
        .collect();
    if let Some(&(i, _)) = candidates.iter().find(|(_, r)| Some(*r) == record) {
        return Ok(i);
    }
    match (candidates.as_slice(), record) {
        ([(i, r)], Some(file_r)) => {
            warnings.push(format!(
                "the file name says record {file_r}, but the only {} variable is of record {r}; read it",
                &kind.suffix()[1..3]
            ));
            Ok(*i)
        }
        ([(i, _)], None) => Ok(*i),
        ([], _) => Err(RecordingError::VariableNotFound {
            path: path.to_path_buf(),
            wanted: match record {
                Some(r) => format!("X{r:03}{}", kind.suffix()),
                None => format!("XNNN{}", kind.suffix()),
            },
            present: contents.listing(),
        }),
        (many, _) => Err(RecordingError::AmbiguousVariable {
            path: path.to_path_buf(),
            problem: format!(
                "{} {} variables and none of them has the record number at the end of the file name",
                many.len(),
                &kind.suffix()[1..3]
            ),
            present: contents.listing(),
        }),
    }
}

/// The default channel of a file that is not CWRU's: its one vector of samples.
fn only_vector(path: &Path, contents: &Contents<'_>) -> Result<usize, RecordingError> {
    let vectors: Vec<usize> = (0..contents.leaves.len())
        .filter(|&i| contents.leaves[i].is_vector())
        .collect();
    match vectors.as_slice() {
        [i] => Ok(*i),
        [] if contents.leaves.len() == 1 => Ok(0),
        [] => Err(RecordingError::NoSignal {
            path: path.to_path_buf(),
            present: contents.listing(),
        }),
        _ => Err(RecordingError::AmbiguousVariable {
            path: path.to_path_buf(),
            problem: format!("{} vectors of samples", vectors.len()),
            present: contents.vectors(),
        }),
    }
}

fn choose(
    path: &Path,
    contents: &Contents<'_>,
    selector: Option<&str>,
    warnings: &mut Vec<String>,
) -> Result<usize, RecordingError> {
    let names: Vec<&str> = contents.leaves.iter().map(|l| l.path.as_str()).collect();
    let cwru = names.iter().any(|n| cwru_name(n).is_some());
    let Some(wanted) = selector else {
        return if cwru {
            by_kind(path, contents, Kind::DriveEnd, warnings)
        } else {
            only_vector(path, contents)
        };
    };
    if let Some(i) = names.iter().position(|n| *n == wanted) {
        return Ok(i);
    }
    if let Some(kind) = Kind::keyword(wanted).filter(|_| cwru) {
        return by_kind(path, contents, kind, warnings);
    }
    if let Some(i) = names.iter().position(|n| n.eq_ignore_ascii_case(wanted)) {
        return Ok(i);
    }
    Err(RecordingError::VariableNotFound {
        path: path.to_path_buf(),
        wanted: wanted.to_string(),
        present: contents.listing(),
    })
}

/// The samples of the chosen array: it must be a real vector.
fn vector(path: &Path, leaf: &Leaf<'_>) -> Result<Vec<f64>, RecordingError> {
    let unsupported = |problem: String| RecordingError::UnsupportedVariable {
        path: path.to_path_buf(),
        name: leaf.path.clone(),
        problem,
    };
    let dims = &leaf.array.dims;
    if dims.iter().filter(|&&d| d > 1).count() > 1 {
        return Err(unsupported(format!(
            "is a {} matrix, not a vector",
            dims_text(dims)
        )));
    }
    if leaf.array.complex {
        return Err(unsupported("is complex".to_string()));
    }
    Ok(leaf.array.real.clone())
}

/// The shaft speed from `XNNNRPM` of the chosen variable's record, when present and sensible.
fn cwru_rpm(contents: &Contents<'_>, channel: &str, warnings: &mut Vec<String>) -> Option<f64> {
    let (record, _) = cwru_name(channel)?;
    let leaf = contents
        .leaves
        .iter()
        .find(|l| cwru_name(&l.path) == Some((record, Kind::Rpm)))?;
    match leaf.array.real.first().copied() {
        Some(v) if v.is_finite() && v > 0.0 && !leaf.array.complex => Some(v),
        _ => {
            warnings.push(format!(
                "variable {} does not hold a positive speed; rpm unknown",
                leaf.path
            ));
            None
        }
    }
}

const RATE_NAMES: [&str; 8] = [
    "fs",
    "sr",
    "fs_hz",
    "sample_rate",
    "sample_rate_hz",
    "sampling_rate",
    "samplerate",
    "sampling_frequency",
];
const RPM_NAMES: [&str; 3] = ["rpm", "speed_rpm", "shaft_rpm"];
const SHAFT_HZ_NAMES: [&str; 2] = ["shaft_hz", "fr"];

/// The scalar named one of `names` nearest to the chosen signal: beside it, then in each
/// enclosing struct out to the top level.
fn nearest_scalar<'c>(
    contents: &'c Contents<'_>,
    chosen: &Leaf<'_>,
    names: &[&str],
) -> Option<(&'c Leaf<'c>, f64)> {
    let home = chosen.parent();
    contents
        .leaves
        .iter()
        .filter(|l| names.iter().any(|n| l.field().eq_ignore_ascii_case(n)))
        .filter(|l| {
            let p = l.parent();
            p.is_empty() || home == p || home.starts_with(&format!("{p}."))
        })
        .filter_map(|l| l.scalar().map(|v| (l, v)))
        .max_by_key(|(l, _)| l.parent().len())
}

/// Sample rate and shaft speed a non-CWRU file states beside its signal (see the module docs).
fn stated_conditions(
    contents: &Contents<'_>,
    chosen: &Leaf<'_>,
    warnings: &mut Vec<String>,
) -> (Option<f64>, Option<f64>) {
    let usable = |what: &str, leaf: &Leaf<'_>, v: f64, warnings: &mut Vec<String>| {
        if v.is_finite() && v > 0.0 {
            Some(v)
        } else {
            warnings.push(format!(
                "{} = {v} is not a usable {what}; ignored",
                leaf.path
            ));
            None
        }
    };
    let fs = nearest_scalar(contents, chosen, &RATE_NAMES)
        .and_then(|(l, v)| usable("sample rate", l, v, warnings));
    let rpm = if let Some((l, v)) = nearest_scalar(contents, chosen, &RPM_NAMES) {
        usable("speed in rpm", l, v, warnings)
    } else if let Some((l, v)) = nearest_scalar(contents, chosen, &SHAFT_HZ_NAMES) {
        usable("shaft speed in Hz", l, v, warnings).map(|hz| hz * 60.0)
    } else {
        // MFPT: `rate` (shaft Hz) beside `sr` (sample rate).
        nearest_scalar(contents, chosen, &["rate"])
            .filter(|(l, _)| {
                contents.leaves.iter().any(|s| {
                    s.parent() == l.parent() && s.field().eq_ignore_ascii_case("sr")
                })
            })
            .and_then(|(l, v)| {
                let hz = usable("shaft speed in Hz", l, v, warnings)?;
                warnings.push(format!(
                    "shaft speed read from {} = {hz} as a shaft rate in Hz ({} rpm), the MFPT data set's convention; give --rpm if that is not what it means",
                    l.path,
                    hz * 60.0
                ));
                Some(hz * 60.0)
            })
    };
    (fs, rpm)
}

pub(super) fn read(
    path: &Path,
    bytes: &[u8],
    selector: Option<&str>,
) -> Result<Recording, RecordingError> {
    let file = mat5::parse(path, bytes)?;
    let contents = contents(&file);
    let mut warnings = file.warnings.clone();
    let index = choose(path, &contents, selector, &mut warnings)?;
    let leaf = &contents.leaves[index];
    let samples = vector(path, leaf)?;
    let (fs_hz, rpm) = if cwru_name(&leaf.path).is_some() {
        (
            fs_from_name(path),
            cwru_rpm(&contents, &leaf.path, &mut warnings),
        )
    } else {
        stated_conditions(&contents, leaf, &mut warnings)
    };
    Ok(Recording {
        path: path.to_path_buf(),
        format: RecordingFormat::Matlab,
        channel: leaf.path.clone(),
        fs_hz,
        rpm,
        samples,
        warnings,
        unit: super::SampleUnit::G,
        notes: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cwru_names() {
        assert_eq!(cwru_name("X105_DE_time"), Some((105, Kind::DriveEnd)));
        assert_eq!(cwru_name("X097RPM"), Some((97, Kind::Rpm)));
        assert_eq!(cwru_name("X_DE_time"), None);
        assert_eq!(cwru_name("X105_DE_timex"), None);
        assert_eq!(cwru_name("Y105_DE_time"), None);
        assert_eq!(Kind::keyword("fe"), Some(Kind::FanEnd));
        assert_eq!(Kind::keyword("RPM"), None);
    }

    #[test]
    fn names_of_files() {
        let p = Path::new("d/12k_Drive_End_OR007@6_0_130.mat");
        assert_eq!(
            (file_record(p), fs_from_name(p)),
            (Some(130), Some(12_000.0))
        );
        let p = Path::new("normal_0_97.mat");
        assert_eq!(
            (file_record(p), fs_from_name(p)),
            (Some(97), Some(48_000.0))
        );
        let p = Path::new("mine.mat");
        assert_eq!((file_record(p), fs_from_name(p)), (None, None));
    }
}
