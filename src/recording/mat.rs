//! MATLAB v5 `.mat` files, read with the CWRU conventions.
//!
//! CWRU files hold column vectors `XNNN_DE_time`, `XNNN_FE_time`, `XNNN_BA_time` (drive end,
//! fan end, base; g) and `XNNNRPM` (measured shaft speed), NNN being the CWRU record number,
//! which the file name repeats at its end (`…_105.mat`). Some files also carry another record's
//! variables, so the default channel is the drive-end variable of the file's own record, never
//! "the first one found".
//!
//! Decoding is done by `matfile`, but not trusted blindly: it can panic on odd input and it
//! silently drops a variable cut off by the end of the file. So this module checks the header and
//! walks the top-level data elements itself first (a truncated file is reported with byte
//! counts), then hands `matfile` one element at a time under `catch_unwind`. An element that
//! cannot be decoded is skipped with a warning and shown as such in variable lists.

use super::{file_name, Recording, RecordingError, RecordingFormat};
use std::ops::Range;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

const MAGIC: &[u8] = b"MATLAB 5.0 MAT-file";
const HEADER_LEN: usize = 128;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Endian {
    Little,
    Big,
}

fn u32_at(bytes: &[u8], at: usize, endian: Endian) -> Option<u32> {
    let b: [u8; 4] = bytes.get(at..at.checked_add(4)?)?.try_into().ok()?;
    Some(match endian {
        Endian::Little => u32::from_le_bytes(b),
        Endian::Big => u32::from_be_bytes(b),
    })
}

/// Checks the 128-byte header: text starting with `MATLAB 5.0 MAT-file`, version 0x0100,
/// endian indicator `IM` or `MI`.
fn check_header(path: &Path, bytes: &[u8]) -> Result<Endian, RecordingError> {
    let not_matlab = |reason: String| RecordingError::NotMatlab {
        path: path.to_path_buf(),
        reason,
    };
    let n = bytes.len().min(MAGIC.len());
    if bytes[..n] != MAGIC[..n] {
        let reason = if bytes.starts_with(b"MATLAB 7.3") {
            "it is a MATLAB 7.3 (HDF5) file; save it again in MATLAB with save(file, '-v7')"
                .to_string()
        } else if bytes.starts_with(b"RIFF") {
            "it starts like a WAV file; rename it to .wav".to_string()
        } else {
            let start: String = String::from_utf8_lossy(&bytes[..bytes.len().min(24)])
                .chars()
                .map(|c| if c.is_control() { ' ' } else { c })
                .collect();
            format!(
                "it starts with \"{}\" instead of \"MATLAB 5.0 MAT-file\"; check that it is the right file (a .mat from MATLAB 5 to 7.2)",
                start.trim_end()
            )
        };
        return Err(not_matlab(reason));
    }
    if bytes.len() < HEADER_LEN {
        return Err(RecordingError::Truncated {
            path: path.to_path_buf(),
            what: "the MATLAB header".to_string(),
            expected: HEADER_LEN as u64,
            present: bytes.len() as u64,
        });
    }
    let endian = match &bytes[126..128] {
        b"IM" => Endian::Little,
        b"MI" => Endian::Big,
        other => {
            return Err(not_matlab(format!(
                "the endian indicator at byte 126 is {other:?}, not \"IM\" or \"MI\"; the header is damaged"
            )))
        }
    };
    let version = match endian {
        Endian::Little => u16::from_le_bytes([bytes[124], bytes[125]]),
        Endian::Big => u16::from_be_bytes([bytes[124], bytes[125]]),
    };
    if version != 0x0100 {
        return Err(not_matlab(format!(
            "the header gives version 0x{version:04x}, not 0x0100; save it again in MATLAB with save(file, '-v7')"
        )));
    }
    Ok(endian)
}

/// A top-level data element: where it starts and the bytes it covers (tag included).
struct Element {
    offset: usize,
    bytes: Range<usize>,
    compressed: bool,
}

/// Walks the top-level data elements, checking that each fits in the file.
fn elements(
    path: &Path,
    bytes: &[u8],
    endian: Endian,
    warnings: &mut Vec<String>,
) -> Result<Vec<Element>, RecordingError> {
    let truncated = |what: String, expected: usize| RecordingError::Truncated {
        path: path.to_path_buf(),
        what,
        expected: expected as u64,
        present: bytes.len() as u64,
    };
    let mut out = Vec::new();
    let mut off = HEADER_LEN;
    while off < bytes.len() {
        let (Some(kind), Some(size)) = (u32_at(bytes, off, endian), u32_at(bytes, off + 4, endian))
        else {
            return Err(truncated(
                format!("the data element tag at byte {off}"),
                off + 8,
            ));
        };
        if kind & 0xFFFF_0000 != 0 {
            return Err(RecordingError::DamagedMat {
                path: path.to_path_buf(),
                detail: format!("the data element tag at byte {off} is not valid here"),
            });
        }
        let end = off.saturating_add(8).saturating_add(size as usize);
        if end > bytes.len() {
            let what = match element_header(&bytes[off..], endian) {
                Some(h) if kind == MI_MATRIX => format!("variable '{}' (at byte {off})", h.name),
                _ => format!("the data element at byte {off}"),
            };
            return Err(truncated(what, end));
        }
        match kind {
            MI_MATRIX | MI_COMPRESSED => out.push(Element {
                offset: off,
                bytes: off..end,
                compressed: kind == MI_COMPRESSED,
            }),
            _ => warnings.push(format!(
                "skipped a data element of type {kind} at byte {off}: not a variable"
            )),
        }
        // Uncompressed elements are padded to 8 bytes; compressed ones are not.
        off = if kind == MI_COMPRESSED {
            end
        } else {
            end.checked_next_multiple_of(8).unwrap_or(end)
        };
    }
    Ok(out)
}

/// What an uncompressed matrix element says about itself, read straight from its bytes: its
/// name (for messages about elements `matfile` cannot decode) and whether its dimensions fit
/// in an `i32` product (`matfile` multiplies them unchecked, which panics in debug builds).
struct ElementHeader {
    name: String,
    dims_ok: bool,
}

fn element_header(el: &[u8], endian: Endian) -> Option<ElementHeader> {
    // Tag (8), array flags (16), then the dimensions and the name sub-elements.
    let mut at = 24;
    let mut parts = [(0usize, 0usize); 2];
    for part in &mut parts {
        let tag = u32_at(el, at, endian)?;
        let (data_at, len, next) = if tag & 0xFFFF_0000 != 0 {
            (at + 4, (tag >> 16) as usize, at + 8)
        } else {
            let len = u32_at(el, at + 4, endian)? as usize;
            let next = at.checked_add(len.checked_next_multiple_of(8)?.checked_add(8)?)?;
            (at + 8, len, next)
        };
        *part = (data_at, len);
        at = next;
    }
    let [(dims_at, dims_len), (name_at, name_len)] = parts;
    let name = el.get(name_at..name_at.checked_add(name_len)?)?;
    let dims_ok = (0..dims_len / 4)
        .map(|k| u32_at(el, dims_at.checked_add(4 * k)?, endian).map(|d| d as i32))
        .try_fold(1i32, |acc, d| acc.checked_mul(d?).filter(|p| *p >= 0))
        .is_some();
    Some(ElementHeader {
        name: String::from_utf8_lossy(name).into_owned(),
        dims_ok,
    })
}

/// What a file holds: the numeric arrays, and descriptions of the variables that are not.
struct Contents {
    arrays: Vec<matfile::Array>,
    others: Vec<String>,
    warnings: Vec<String>,
}

impl Contents {
    /// Everything, for error messages.
    fn listing(&self) -> Vec<String> {
        let mut all: Vec<String> = self.arrays.iter().map(|a| a.name().to_string()).collect();
        all.extend(self.others.iter().cloned());
        all
    }
}

fn decode(path: &Path, bytes: &[u8]) -> Result<Contents, RecordingError> {
    let endian = check_header(path, bytes)?;
    let mut warnings = Vec::new();
    let elements = elements(path, bytes, endian, &mut warnings)?;
    let mut arrays = Vec::new();
    let mut others = Vec::new();
    for el in elements {
        let mut buf = Vec::with_capacity(HEADER_LEN + el.bytes.len());
        buf.extend_from_slice(&bytes[..HEADER_LEN]);
        buf.extend_from_slice(&bytes[el.bytes.clone()]);
        let header = element_header(&bytes[el.bytes.clone()], endian).filter(|_| !el.compressed);
        let what = match &header {
            Some(h) => format!("'{}'", h.name),
            None => format!("at byte {}", el.offset),
        };
        if header.as_ref().is_some_and(|h| !h.dims_ok) {
            warnings.push(format!(
                "skipped the variable {what}: its dimensions are invalid"
            ));
            others.push(format!("{what} (cannot be decoded)"));
            continue;
        }
        match catch_unwind(AssertUnwindSafe(|| matfile::MatFile::parse(buf.as_slice()))) {
            Ok(Ok(file)) if !file.arrays().is_empty() => {
                arrays.extend(file.arrays().iter().cloned())
            }
            Ok(Ok(_)) => others.push(format!("{what} (not a numeric array)")),
            Ok(Err(e)) => {
                warnings.push(format!(
                    "skipped the variable {what}: it cannot be decoded ({e})"
                ));
                others.push(format!("{what} (cannot be decoded)"));
            }
            Err(_) => {
                warnings.push(format!(
                    "skipped the variable {what}: the MATLAB decoder failed on it (internal panic)"
                ));
                others.push(format!("{what} (cannot be decoded)"));
            }
        }
    }
    Ok(Contents {
        arrays,
        others,
        warnings,
    })
}

pub(super) fn channels(path: &Path, bytes: &[u8]) -> Result<Vec<String>, RecordingError> {
    let contents = decode(path, bytes)?;
    Ok(contents
        .arrays
        .iter()
        .map(|a| a.name().to_string())
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
    contents: &Contents,
    kind: Kind,
    warnings: &mut Vec<String>,
) -> Result<usize, RecordingError> {
    let record = file_record(path);
    let candidates: Vec<(usize, u32)> = contents
        .arrays
        .iter()
        .enumerate()
        .filter_map(|(i, a)| match cwru_name(a.name()) {
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

fn choose(
    path: &Path,
    contents: &Contents,
    selector: Option<&str>,
    warnings: &mut Vec<String>,
) -> Result<usize, RecordingError> {
    let names: Vec<&str> = contents.arrays.iter().map(|a| a.name()).collect();
    let Some(wanted) = selector else {
        // A non-CWRU file with a single variable has nothing to choose from.
        let no_de = names
            .iter()
            .all(|n| !matches!(cwru_name(n), Some((_, Kind::DriveEnd))));
        if no_de && names.len() == 1 {
            return Ok(0);
        }
        return by_kind(path, contents, Kind::DriveEnd, warnings);
    };
    if let Some(i) = names.iter().position(|n| *n == wanted) {
        return Ok(i);
    }
    if let Some(kind) = Kind::keyword(wanted) {
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

/// The real values of an array as f64, or why not.
fn values(array: &matfile::Array) -> Result<Vec<f64>, &'static str> {
    macro_rules! convert {
        ($($variant:ident),*) => {
            match array.data() {
                $(matfile::NumericData::$variant { real, imag: None } => {
                    Ok(real.iter().map(|&v| v as f64).collect())
                })*
                _ => Err("is complex"),
            }
        };
    }
    convert!(Double, Single, Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64)
}

/// The samples of the chosen variable: it must be a real vector.
fn vector(path: &Path, array: &matfile::Array) -> Result<Vec<f64>, RecordingError> {
    let unsupported = |problem: String| RecordingError::UnsupportedVariable {
        path: path.to_path_buf(),
        name: array.name().to_string(),
        problem,
    };
    let size = array.size();
    if size.iter().filter(|&&d| d > 1).count() > 1 {
        let dims: Vec<String> = size.iter().map(|d| d.to_string()).collect();
        return Err(unsupported(format!(
            "is a {} matrix, not a vector",
            dims.join("x")
        )));
    }
    values(array).map_err(|p| unsupported(p.to_string()))
}

/// The shaft speed from `XNNNRPM` of the chosen variable's record, when present and sensible.
fn rpm(contents: &Contents, channel: &str, warnings: &mut Vec<String>) -> Option<f64> {
    let (record, _) = cwru_name(channel)?;
    let array = contents
        .arrays
        .iter()
        .find(|a| cwru_name(a.name()) == Some((record, Kind::Rpm)))?;
    match values(array).ok().and_then(|v| v.first().copied()) {
        Some(v) if v.is_finite() && v > 0.0 => Some(v),
        _ => {
            warnings.push(format!(
                "variable {} does not hold a positive speed; rpm unknown",
                array.name()
            ));
            None
        }
    }
}

pub(super) fn read(
    path: &Path,
    bytes: &[u8],
    selector: Option<&str>,
) -> Result<Recording, RecordingError> {
    let contents = decode(path, bytes)?;
    let mut warnings = contents.warnings.clone();
    let index = choose(path, &contents, selector, &mut warnings)?;
    let array = &contents.arrays[index];
    let samples = vector(path, array)?;
    let rpm = rpm(&contents, array.name(), &mut warnings);
    Ok(Recording {
        path: path.to_path_buf(),
        format: RecordingFormat::CwruMat,
        channel: array.name().to_string(),
        fs_hz: fs_from_name(path),
        rpm,
        samples,
        warnings,
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
