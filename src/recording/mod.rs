//! Readers for recorded vibration data: CWRU MATLAB v5 `.mat`, PRONOSTIA `acc_NNNNN.csv`,
//! IMS snapshot text files, plain CSV tables and WAV.
//!
//! Why this module exists: every data set stores its samples differently, and each one also
//! says something about itself (sampling rate, shaft speed, which channel is which) in a
//! different place: a file-name prefix, a MATLAB variable, a WAV header, nothing at all. This
//! module turns a file into the samples of one channel plus whatever the file really states,
//! and nothing more: a value the file does not give is `None` (the caller asks the user), a
//! choice the file leaves open is an error that lists the options, and anything read with
//! less than full confidence (a cut-off last row, a truncated WAV) is reported in
//! [`Recording::warnings`]. Nothing is guessed silently.
//!
//! Every error is one line that names the file, the problem and how to fix it. No input, however
//! damaged, makes a reader panic (the third-party MATLAB and WAV parsers run under
//! `catch_unwind` as a backstop).

mod csv;
mod ims;
mod mat;
mod text;
mod wav;

use std::fmt;
use std::path::{Path, PathBuf};

/// A recording read from a file: the samples of one channel plus what the file says about itself.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The file it was read from.
    pub path: PathBuf,
    /// How the file was read.
    pub format: RecordingFormat,
    /// The channel read, as the file names it: `X105_DE_time`, `horizontal`, `B3x`, a CSV
    /// header name or `column 3`, or the 1-based WAV channel `1`.
    pub channel: String,
    /// Sampling rate, when the format or the file name states it; `None` when unknown.
    pub fs_hz: Option<f64>,
    /// Shaft speed, when the file states it (the CWRU `XNNNRPM` variable); `None` otherwise.
    pub rpm: Option<f64>,
    /// The samples, all finite: acceleration in g for the data-set formats; for WAV, full-scale
    /// units (see [`RecordingFormat::Wav`]).
    pub samples: Vec<f64>,
    /// Things the caller should show the user, e.g. a dropped incomplete last row.
    pub warnings: Vec<String>,
}

/// The file formats this module reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RecordingFormat {
    /// MATLAB v5 `.mat`, read with the CWRU naming rules (`XNNN_DE_time`, `XNNNRPM`). The
    /// sampling rate comes from the CWRU file-name prefix: `12k_` is 12 kHz, `48k_` is 48 kHz,
    /// and `normal_*` baseline files are 48 kHz (data README caveat 1); otherwise unknown.
    CwruMat,
    /// PRONOSTIA / PHM 2012 `acc_NNNNN.csv`: hour, minute, second, microsecond, horizontal,
    /// vertical (g), at 25.6 kHz. Recognised by the file name.
    PronostiaCsv,
    /// NASA/IMS snapshot: whitespace-separated columns, 8 (test 1: B1x B1y … B4y) or 4 (tests 2
    /// and 3: B1 … B4), at 20 kHz. Recognised by the name `YYYY.MM.DD.hh.mm.ss`, or by content
    /// for files without an extension.
    ImsText,
    /// A `.csv`, `.tsv` or `.txt` table of numbers, with or without a header row; separator
    /// `;`, tab, `,` or spaces. The sampling rate is unknown.
    PlainCsv,
    /// WAV, integer or float samples. Integers are scaled to ±1.0 full scale, floats are kept
    /// as they are; the file holds no scale to g, so the amplitudes are relative (a warning
    /// says so).
    Wav,
}

impl fmt::Display for RecordingFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RecordingFormat::CwruMat => "CWRU MATLAB v5 (.mat)",
            RecordingFormat::PronostiaCsv => "PRONOSTIA acc CSV",
            RecordingFormat::ImsText => "IMS text",
            RecordingFormat::PlainCsv => "plain CSV",
            RecordingFormat::Wav => "WAV",
        })
    }
}

/// Which channel to read. `channel` and `column` are two names for one choice (users think of
/// channels in `.mat` and WAV files and of columns in CSV tables); give at most one, or both
/// with the same value. `None` means the format's default channel.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// CWRU: `DE`, `FE`, `BA` or a variable name. PRONOSTIA: `horizontal` or `vertical`. IMS:
    /// `B1x` … `B4y` or `1` … `8`. CSV: a header name or a 1-based index. WAV: `1`, `2`, …
    pub channel: Option<String>,
    /// Synonym of `channel`, for tables.
    pub column: Option<String>,
}

/// Why a file could not be read. Each message is one line naming the file.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    #[error("{path}: file not found; check the path (a relative path starts from the current directory)")]
    NotFound { path: PathBuf },
    #[error("{path}: cannot read the file: {source}; check that it is a readable file")]
    Unreadable {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: unknown recording format: {reason}; readable are MATLAB v5 .mat (CWRU), .wav, .csv/.tsv/.txt tables, PRONOSTIA acc_NNNNN.csv and IMS snapshots named like 2003.10.22.12.14.13")]
    UnknownFormat { path: PathBuf, reason: String },
    #[error("{path}: not a MATLAB v5 file: {reason}")]
    NotMatlab { path: PathBuf, reason: String },
    #[error("{path}: file truncated: {what} ends at byte {expected} but the file has only {present} bytes; the copy is incomplete, fetch or copy the file again")]
    Truncated {
        path: PathBuf,
        what: String,
        expected: u64,
        present: u64,
    },
    #[error("{path}: damaged MATLAB file: {detail}; fetch the file again or re-save it in MATLAB with save(file, '-v7')")]
    DamagedMat { path: PathBuf, detail: String },
    #[error("{path}: no variable '{wanted}'; variables present: {}; choose one as the channel", list(.present))]
    VariableNotFound {
        path: PathBuf,
        wanted: String,
        present: Vec<String>,
    },
    #[error("{path}: {problem}; variables present: {}; choose the channel (DE, FE, BA or a variable name)", list(.present))]
    AmbiguousVariable {
        path: PathBuf,
        problem: String,
        present: Vec<String>,
    },
    #[error("{path}: variable '{name}' {problem}; choose a variable that is a vector of samples")]
    UnsupportedVariable {
        path: PathBuf,
        name: String,
        problem: String,
    },
    #[error("{path}: no {kind} '{wanted}'; {kind}s present: {}", list(.available))]
    ChannelNotFound {
        path: PathBuf,
        kind: &'static str,
        wanted: String,
        available: Vec<String>,
    },
    #[error("{path}: the table has {} columns ({}); choose one by header name or 1-based index", .available.len(), list(.available))]
    ColumnRequired {
        path: PathBuf,
        available: Vec<String>,
    },
    #[error("{path}: channel '{channel}' has {count} NaN or infinite sample(s), the first at sample index {index} (0-based){at}; repair the recording or cut that part out")]
    NonFinite {
        path: PathBuf,
        channel: String,
        index: usize,
        count: usize,
        /// Where the first one is in the file, e.g. ` (line 12)`, or empty.
        at: String,
    },
    #[error("{path}: no samples: {detail}")]
    Empty { path: PathBuf, detail: String },
    #[error("{path}: line {line}: {problem}; fix or delete that line")]
    MalformedRow {
        path: PathBuf,
        line: usize,
        problem: String,
    },
    #[error("{path}: cannot read the WAV file: {detail}; re-export it as PCM or 32-bit float WAV")]
    BadWav { path: PathBuf, detail: String },
    #[error("{path}: channel '{channel}' and column '{column}' name different channels; give only one of them")]
    ConflictingSelection {
        path: PathBuf,
        channel: String,
        column: String,
    },
}

/// `a, b, c`, or `(none)`.
fn list(items: &[String]) -> String {
    if items.is_empty() {
        "(none)".to_string()
    } else {
        items.join(", ")
    }
}

/// Reads one channel of a recording. See [`RecordingFormat`] for what each format yields.
pub fn read_recording(path: &Path, options: &ReadOptions) -> Result<Recording, RecordingError> {
    let bytes = read_file(path)?;
    let selector = selector(path, options)?;
    let format = detect_format(path, &bytes)?;
    let recording = match format {
        RecordingFormat::CwruMat => mat::read(path, &bytes, selector)?,
        RecordingFormat::PronostiaCsv => csv::read_pronostia(path, &bytes, selector)?,
        RecordingFormat::ImsText => ims::read(path, &bytes, selector)?,
        RecordingFormat::PlainCsv => csv::read_plain(path, &bytes, selector)?,
        RecordingFormat::Wav => wav::read(path, &bytes, selector)?,
    };
    check_finite(&recording)?;
    Ok(recording)
}

/// The channels a file offers, in file order, as they can be passed in [`ReadOptions`]: MATLAB
/// variable names, table column names, or WAV channel numbers.
pub fn list_channels(path: &Path) -> Result<Vec<String>, RecordingError> {
    let bytes = read_file(path)?;
    match detect_format(path, &bytes)? {
        RecordingFormat::CwruMat => mat::channels(path, &bytes),
        RecordingFormat::PronostiaCsv => Ok(csv::PRONOSTIA_CHANNELS
            .iter()
            .map(|s| s.to_string())
            .collect()),
        RecordingFormat::ImsText => ims::channels(path, &bytes),
        RecordingFormat::PlainCsv => csv::plain_channels(path, &bytes),
        RecordingFormat::Wav => wav::channels(path, &bytes),
    }
}

/// Decides how to read a file from its name and its first bytes.
///
/// `.mat`, `.wav` and `.csv`/`.tsv`/`.txt` are taken at their word (a text file renamed `.mat`
/// then fails as "not a MATLAB v5 file" rather than being read as something else); `acc_NNNNN.csv`
/// is PRONOSTIA; a name like `2003.10.22.12.14.13` is IMS. Files without an extension are
/// recognised by content: MATLAB and WAV headers, or a first line of 4 or 8 tab-separated
/// numbers (IMS).
pub fn detect_format(path: &Path, head: &[u8]) -> Result<RecordingFormat, RecordingError> {
    let name = file_name(path);
    if ims::is_ims_name(&name) {
        return Ok(RecordingFormat::ImsText);
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("mat") => return Ok(RecordingFormat::CwruMat),
        Some("wav") | Some("wave") => return Ok(RecordingFormat::Wav),
        Some("csv") | Some("tsv") | Some("txt") => {
            return Ok(if csv::is_pronostia_name(&name) {
                RecordingFormat::PronostiaCsv
            } else {
                RecordingFormat::PlainCsv
            })
        }
        _ => {}
    }
    if head.starts_with(b"MATLAB") {
        return Ok(RecordingFormat::CwruMat);
    }
    if head.len() >= 12 && head.starts_with(b"RIFF") && &head[8..12] == b"WAVE" {
        return Ok(RecordingFormat::Wav);
    }
    let reason = match ext {
        None if ims::looks_like_ims(head) => return Ok(RecordingFormat::ImsText),
        None => "no extension, and the content is neither MATLAB, WAV nor IMS text".to_string(),
        Some(e) => format!(
            "extension '.{e}' is not known; if the file is a table of numbers, rename it to .csv"
        ),
    };
    Err(RecordingError::UnknownFormat {
        path: path.to_path_buf(),
        reason,
    })
}

/// Reads the whole file: the largest inputs are a few MB, and one read means one consistent
/// snapshot of a file that might be growing.
fn read_file(path: &Path) -> Result<Vec<u8>, RecordingError> {
    let bytes = std::fs::read(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => RecordingError::NotFound {
            path: path.to_path_buf(),
        },
        _ => RecordingError::Unreadable {
            path: path.to_path_buf(),
            source,
        },
    })?;
    if bytes.is_empty() {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
            detail: "the file is empty (0 bytes)".to_string(),
        });
    }
    Ok(bytes)
}

/// The one channel choice from `channel` and `column`.
fn selector<'a>(path: &Path, options: &'a ReadOptions) -> Result<Option<&'a str>, RecordingError> {
    let channel = options.channel.as_deref().map(str::trim);
    let column = options.column.as_deref().map(str::trim);
    match (channel, column) {
        (Some(c), Some(k)) if !c.eq_ignore_ascii_case(k) => {
            Err(RecordingError::ConflictingSelection {
                path: path.to_path_buf(),
                channel: c.to_string(),
                column: k.to_string(),
            })
        }
        (Some(c), _) => Ok(Some(c)),
        (None, k) => Ok(k),
    }
}

/// The file name as text (lossy), or empty.
fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Refuses an empty recording or one with NaN or infinite samples (the text readers check
/// earlier, to name the line).
fn check_finite(recording: &Recording) -> Result<(), RecordingError> {
    if recording.samples.is_empty() {
        return Err(RecordingError::Empty {
            path: recording.path.clone(),
            detail: format!("channel '{}' holds no samples", recording.channel),
        });
    }
    let mut bad = recording
        .samples
        .iter()
        .enumerate()
        .filter(|(_, v)| !v.is_finite());
    if let Some((index, _)) = bad.next() {
        return Err(RecordingError::NonFinite {
            path: recording.path.clone(),
            channel: recording.channel.clone(),
            index,
            count: 1 + bad.count(),
            at: String::new(),
        });
    }
    Ok(())
}

/// Resolves a choice among named channels: a name (case-insensitive) or a 1-based index.
fn pick_by_name_or_index(
    path: &Path,
    kind: &'static str,
    wanted: &str,
    names: &[String],
    allow_index: bool,
) -> Result<usize, RecordingError> {
    if let Some(i) = names.iter().position(|n| n.eq_ignore_ascii_case(wanted)) {
        return Ok(i);
    }
    if allow_index {
        if let Ok(k) = wanted.parse::<usize>() {
            if (1..=names.len()).contains(&k) {
                return Ok(k - 1);
            }
        }
    }
    let mut available = names.to_vec();
    if allow_index && !names.is_empty() {
        available.push(format!("or an index 1..{}", names.len()));
    }
    Err(RecordingError::ChannelNotFound {
        path: path.to_path_buf(),
        kind,
        wanted: wanted.to_string(),
        available,
    })
}
