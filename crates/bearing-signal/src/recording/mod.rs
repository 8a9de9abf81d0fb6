//! Readers for recorded vibration data: MATLAB `.mat` (CWRU's vectors, structs such as the
//! MFPT set's), PRONOSTIA `acc_NNNNN.csv`, IMS snapshot text files, plain CSV tables, WAV, and,
//! through a [`LogReader`] the caller gives, the MCAP logs `bearingd run` writes (their format
//! is bearingd's).
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
//! damaged, makes a reader panic (the MATLAB decoder is our own and bounds-checked; the
//! third-party WAV parser runs under `catch_unwind` as a backstop).

mod csv;
mod ims;
mod mat;
mod mat5;
mod snapshot_time;
mod text;
mod wav;

pub use snapshot_time::{time_from_name, NamedTime, NamedTimeKind, PRONOSTIA_PERIOD_S};
pub use wav::ixml_track_names;

use std::fmt;
use std::path::{Path, PathBuf};

/// A recording read from a file: the samples of one channel plus what the file says about itself.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The file it was read from.
    pub path: PathBuf,
    /// How the file was read.
    pub format: RecordingFormat,
    /// The channel read, as the file names it: `X105_DE_time`, `bearing.gs`, `horizontal`,
    /// `B3x`, a CSV header name or `column 3`, the 1-based WAV channel `1`, or an MCAP log's
    /// `sensor/axis`.
    pub channel: String,
    /// Sampling rate, when the format or the file name states it; `None` when unknown.
    pub fs_hz: Option<f64>,
    /// Shaft speed, when the file states it (the CWRU `XNNNRPM` variable, a MATLAB `rpm` or
    /// `rate` scalar, an MCAP log's speed topic); `None` otherwise.
    pub rpm: Option<f64>,
    /// The samples, all finite, in [`Recording::unit`].
    pub samples: Vec<f64>,
    /// What the samples are in: g for the data sets, logs, tables and float WAVs; fractions of
    /// full scale for an integer WAV (unless the user stated its unit).
    pub unit: SampleUnit,
    /// Things the caller should show the user as wrong or doubtful, e.g. a dropped incomplete
    /// last row.
    pub warnings: Vec<String>,
    /// What was assumed about the file and why, e.g. that a float WAV holds g: information.
    pub notes: Vec<String>,
}

/// What a recording's sample values are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleUnit {
    /// Acceleration in g: what velocity severity and the daemon's thresholds need.
    G,
    /// Fractions of the recorder's full scale (an integer WAV): amplitudes are relative, so
    /// spectra and scores hold but no velocity in mm/s can be computed.
    FullScale,
}

impl fmt::Display for SampleUnit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SampleUnit::G => "g",
            SampleUnit::FullScale => "full scale",
        })
    }
}

/// The unit a user states for a file's values (`--unit`), for the formats that do not document
/// theirs: WAV, plain CSV tables and MATLAB files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StatedUnit {
    /// The values are g (for an integer WAV: ±1.0 full scale is ±1 g).
    G,
    /// The values are m/s²; they are divided by standard gravity to give g.
    MetresPerSecondSquared,
    /// The values are relative: no velocity is computed from them.
    FullScale,
}

/// Standard gravity (m/s² per g), ISO 80000-3.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// The file formats this module reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RecordingFormat {
    /// MATLAB v5 to v7.2 `.mat` (also `scipy.io.savemat`), structs included. CWRU files
    /// (`XNNN_DE_time`, `XNNNRPM`) take their sampling rate from the file-name prefix: `12k_`
    /// is 12 kHz, `48k_` is 48 kHz, and `normal_*` baseline files are 48 kHz (data README
    /// caveat 1). Other files state it, if at all, in a scalar beside the signal (`fs`, `sr`,
    /// ...; see the `mat` module).
    Matlab,
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
    /// WAV, integer or float samples. Floats are read as the values they hold, taken as g (what
    /// `bearingd simulate` writes; a note says so); integers are scaled to ±1.0 full scale,
    /// relative amplitudes (a warning says so). `--unit` states otherwise. Channels are named
    /// by the file's iXML chunk (`TRACK_LIST`, as field recorders and `bearingd simulate` write
    /// it), else numbered from 1.
    Wav,
    /// An MCAP log written by `bearingd run` (or `import`): the raw blocks of one channel
    /// (`sensor/axis`), in g, at the rate the blocks carry; the shaft speed from its speed or
    /// indicators topic.
    McapLog,
}

impl fmt::Display for RecordingFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RecordingFormat::Matlab => "MATLAB (.mat)",
            RecordingFormat::PronostiaCsv => "PRONOSTIA acc CSV",
            RecordingFormat::ImsText => "IMS text",
            RecordingFormat::PlainCsv => "plain CSV",
            RecordingFormat::Wav => "WAV",
            RecordingFormat::McapLog => "bearingd MCAP log",
        })
    }
}

/// Which channel to read. `channel` and `column` are two names for one choice (users think of
/// channels in `.mat` and WAV files and of columns in CSV tables); give at most one, or both
/// with the same value. `None` means the format's default channel.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// CWRU: `DE`, `FE`, `BA` or a variable name. Other MATLAB files: a variable or a field
    /// path (`bearing.gs`, `s(2).x`, `c{1}`). PRONOSTIA: `horizontal` or `vertical`. IMS:
    /// `B1x` … `B4y` or `1` … `8`. CSV: a header name or a 1-based index. WAV: an iXML track name or `1`, `2`, …
    /// MCAP log: `sensor/axis`.
    pub channel: Option<String>,
    /// Synonym of `channel`, for tables.
    pub column: Option<String>,
    /// The unit of the values, when the user states it; `None` keeps the format's own.
    pub unit: Option<StatedUnit>,
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
    #[error("{path}: unknown recording format: {reason}; readable are MATLAB .mat (v5 to v7.2), .wav, .csv/.tsv/.txt tables, PRONOSTIA acc_NNNNN.csv, IMS snapshots named like 2003.10.22.12.14.13 and bearingd's .mcap logs")]
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
    #[error("{path}: no variable '{wanted}'; variables present: {}; choose one with --channel", list(.present))]
    VariableNotFound {
        path: PathBuf,
        wanted: String,
        present: Vec<String>,
    },
    #[error("{path}: {problem}: {}; choose one with --channel (DE, FE or BA for CWRU files, else a variable or field path, e.g. --channel {})", list(.present), example_channel(.present))]
    AmbiguousVariable {
        path: PathBuf,
        problem: String,
        present: Vec<String>,
    },
    #[error("{path}: variable '{name}' {problem}; choose a vector of samples with --channel")]
    UnsupportedVariable {
        path: PathBuf,
        name: String,
        problem: String,
    },
    #[error("{path}: no {kind} '{wanted}'; {kind}s present: {}; choose one with --{kind}", list(.available))]
    ChannelNotFound {
        path: PathBuf,
        kind: &'static str,
        wanted: String,
        available: Vec<String>,
    },
    #[error("{path}: the table has {} columns ({}); choose one with --column, by header name or 1-based index, e.g. --column {}", .available.len(), list(.available), .available.last().map_or("1", String::as_str))]
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
    #[error("{path}: no variable holds a vector of samples; variables present: {}; save the signal as a vector, or choose one with --channel", list(.present))]
    NoSignal { path: PathBuf, present: Vec<String> },
    #[error("{path}: cannot read the MCAP log: {detail}")]
    BadLog { path: PathBuf, detail: String },
    #[error("{path}: the log holds {} channels ({}); choose one with --channel, e.g. --channel {}", .channels.len(), list(.channels), .channels.first().map_or("sensor/axis", String::as_str))]
    AmbiguousLogChannel {
        path: PathBuf,
        channels: Vec<String>,
    },
    #[error("{path}: --unit does not apply: a {format} file is in g by {why}; --unit is for WAV, plain CSV and .mat files, whose unit is not documented")]
    UnitDocumented {
        path: PathBuf,
        format: RecordingFormat,
        why: &'static str,
    },
    #[error("{path}: channel '{channel}' and column '{column}' name different channels; give only one of them")]
    ConflictingSelection {
        path: PathBuf,
        channel: String,
        column: String,
    },
}

/// The first listed name without its description (`s.x (100x1)` → `s.x`), for an example.
fn example_channel(present: &[String]) -> &str {
    present
        .first()
        .and_then(|p| p.split(' ').next())
        .unwrap_or("bearing.gs")
}

/// `a, b, c`, or `(none)`.
fn list(items: &[String]) -> String {
    if items.is_empty() {
        "(none)".to_string()
    } else {
        items.join(", ")
    }
}

/// The reader of bearingd's MCAP logs, which this crate recognises but does not read (their
/// format is bearingd's): `bearingd::recording` gives its own.
pub trait LogReader {
    /// One channel of the log at `path` (`selector`: the channel asked for, if any).
    fn read(&self, path: &Path, selector: Option<&str>) -> Result<Recording, RecordingError>;
    /// The channels the log offers, as `sensor/axis`.
    fn channels(&self, path: &Path) -> Result<Vec<String>, RecordingError>;
}

/// No log reader: an MCAP log is refused, saying what reads it.
pub struct NoLogs;

impl LogReader for NoLogs {
    fn read(&self, path: &Path, _: Option<&str>) -> Result<Recording, RecordingError> {
        Err(no_log_reader(path))
    }
    fn channels(&self, path: &Path) -> Result<Vec<String>, RecordingError> {
        Err(no_log_reader(path))
    }
}

fn no_log_reader(path: &Path) -> RecordingError {
    RecordingError::UnknownFormat {
        path: path.to_path_buf(),
        reason: "a bearingd MCAP log; read it with bearingd (bearingd analyze or replay), or \
                 convert it to CSV or WAV first"
            .to_string(),
    }
}

/// The first bytes of every MCAP file.
pub const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// Reads one channel of a recording, MCAP logs refused ([`NoLogs`]). See [`RecordingFormat`]
/// for what each format yields.
pub fn read_recording(path: &Path, options: &ReadOptions) -> Result<Recording, RecordingError> {
    read_recording_with(path, options, &NoLogs)
}

/// [`read_recording`], MCAP logs read by `logs`.
pub fn read_recording_with(
    path: &Path,
    options: &ReadOptions,
    logs: &dyn LogReader,
) -> Result<Recording, RecordingError> {
    let selector = selector(path, options)?;
    if is_log(path)? {
        // A log can be large: it is read message by message, one channel kept.
        let recording = with_stated_unit(logs.read(path, selector)?, options.unit)?;
        check_finite(&recording)?;
        return Ok(recording);
    }
    let bytes = read_file(path)?;
    decode_recording(path, &bytes, selector, options.unit, logs)
}

/// Reads one channel of a recording from bytes already in memory; `path` only names the file
/// (its name and extension choose the format, as in [`read_recording`]). An MCAP log is
/// refused ([`NoLogs`]). What the fuzz target `recordings` drives: the same decoders as a file,
/// without the file system.
pub fn read_recording_from_bytes(
    path: &Path,
    bytes: &[u8],
    options: &ReadOptions,
) -> Result<Recording, RecordingError> {
    let selector = selector(path, options)?;
    check_not_empty(path, bytes)?;
    decode_recording(path, bytes, selector, options.unit, &NoLogs)
}

/// The decoder [`detect_format`] picks, the unit the user stated, then the finiteness check.
fn decode_recording(
    path: &Path,
    bytes: &[u8],
    selector: Option<&str>,
    unit: Option<StatedUnit>,
    logs: &dyn LogReader,
) -> Result<Recording, RecordingError> {
    let recording = match detect_format(path, bytes)? {
        RecordingFormat::Matlab => mat::read(path, bytes, selector)?,
        RecordingFormat::PronostiaCsv => csv::read_pronostia(path, bytes, selector)?,
        RecordingFormat::ImsText => ims::read(path, bytes, selector)?,
        RecordingFormat::PlainCsv => csv::read_plain(path, bytes, selector)?,
        RecordingFormat::Wav => wav::read(path, bytes, selector)?,
        RecordingFormat::McapLog => logs.read(path, selector)?,
    };
    let recording = with_stated_unit(recording, unit)?;
    check_finite(&recording)?;
    Ok(recording)
}

/// The channels a file offers, in file order, as they can be passed in [`ReadOptions`]: MATLAB
/// variable names, table column names, or WAV channel numbers.
pub fn list_channels(path: &Path) -> Result<Vec<String>, RecordingError> {
    list_channels_with(path, &NoLogs)
}

/// [`list_channels`], MCAP logs read by `logs`.
pub fn list_channels_with(
    path: &Path,
    logs: &dyn LogReader,
) -> Result<Vec<String>, RecordingError> {
    if is_log(path)? {
        return logs.channels(path);
    }
    let bytes = read_file(path)?;
    decode_channels(path, &bytes, logs)
}

/// [`list_channels`] of bytes already in memory (`path` only names them); an MCAP log is
/// refused ([`NoLogs`]).
pub fn list_channels_from_bytes(path: &Path, bytes: &[u8]) -> Result<Vec<String>, RecordingError> {
    check_not_empty(path, bytes)?;
    decode_channels(path, bytes, &NoLogs)
}

fn decode_channels(
    path: &Path,
    bytes: &[u8],
    logs: &dyn LogReader,
) -> Result<Vec<String>, RecordingError> {
    match detect_format(path, bytes)? {
        RecordingFormat::Matlab => mat::channels(path, bytes),
        RecordingFormat::PronostiaCsv => Ok(csv::PRONOSTIA_CHANNELS
            .iter()
            .map(|s| s.to_string())
            .collect()),
        RecordingFormat::ImsText => ims::channels(path, bytes),
        RecordingFormat::PlainCsv => csv::plain_channels(path, bytes),
        RecordingFormat::Wav => wav::channels(path, bytes),
        RecordingFormat::McapLog => logs.channels(path),
    }
}

/// Decides how to read a file from its name and its first bytes.
///
/// `.mat`, `.wav` and `.csv`/`.tsv`/`.txt` are taken at their word (a text file renamed `.mat`
/// then fails as "not a MATLAB v5 file" rather than being read as something else); `acc_NNNNN.csv`
/// is PRONOSTIA; a name like `2003.10.22.12.14.13` is IMS. Files without an extension are
/// recognised by content: MATLAB, WAV and MCAP headers, or a first line of 4 or 8
/// tab-separated numbers (IMS). `.mcap` is an MCAP log.
pub fn detect_format(path: &Path, head: &[u8]) -> Result<RecordingFormat, RecordingError> {
    let name = file_name(path);
    if ims::is_ims_name(&name) {
        return Ok(RecordingFormat::ImsText);
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("mat") => return Ok(RecordingFormat::Matlab),
        Some("mcap") => return Ok(RecordingFormat::McapLog),
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
        return Ok(RecordingFormat::Matlab);
    }
    if head.starts_with(MCAP_MAGIC) {
        return Ok(RecordingFormat::McapLog);
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

/// Whether `path` is an MCAP log (by name or first bytes), read without loading the file.
fn is_log(path: &Path) -> Result<bool, RecordingError> {
    Ok(matches!(
        detect_format(path, &read_head(path)?),
        Ok(RecordingFormat::McapLog)
    ))
}

/// The first bytes of a file, enough to recognise its format.
fn read_head(path: &Path) -> Result<Vec<u8>, RecordingError> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|source| io_error(path, source))?;
    let mut head = Vec::with_capacity(HEAD_LEN);
    file.take(HEAD_LEN as u64)
        .read_to_end(&mut head)
        .map_err(|source| io_error(path, source))?;
    Ok(head)
}

/// Bytes [`read_head`] reads: a MATLAB header (128) and an IMS first line.
const HEAD_LEN: usize = 512;

fn io_error(path: &Path, source: std::io::Error) -> RecordingError {
    match source.kind() {
        std::io::ErrorKind::NotFound => RecordingError::NotFound {
            path: path.to_path_buf(),
        },
        _ => RecordingError::Unreadable {
            path: path.to_path_buf(),
            source,
        },
    }
}

/// Reads the whole file: the largest inputs are a few MB, and one read means one consistent
/// snapshot of a file that might be growing.
fn read_file(path: &Path) -> Result<Vec<u8>, RecordingError> {
    let bytes = std::fs::read(path).map_err(|source| io_error(path, source))?;
    check_not_empty(path, &bytes)?;
    Ok(bytes)
}

fn check_not_empty(path: &Path, bytes: &[u8]) -> Result<(), RecordingError> {
    if bytes.is_empty() {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
            detail: "the file is empty (0 bytes)".to_string(),
        });
    }
    Ok(())
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
/// The recording in the unit the user stated (`--unit`), said in a note; refused for the
/// formats whose unit is documented (the data sets' files and bearingd's logs are in g).
fn with_stated_unit(
    mut recording: Recording,
    stated: Option<StatedUnit>,
) -> Result<Recording, RecordingError> {
    let Some(stated) = stated else {
        return Ok(recording);
    };
    let documented = match recording.format {
        RecordingFormat::PronostiaCsv | RecordingFormat::ImsText => {
            Some("its data set's documentation")
        }
        RecordingFormat::McapLog => Some("bearingd's log format"),
        RecordingFormat::Matlab | RecordingFormat::PlainCsv | RecordingFormat::Wav => None,
    };
    if let Some(why) = documented {
        return Err(RecordingError::UnitDocumented {
            path: recording.path,
            format: recording.format,
            why,
        });
    }
    // The format's own assumption about the unit no longer holds: its note goes.
    recording.notes.retain(|n| !n.starts_with(UNIT_NOTE_PREFIX));
    recording
        .warnings
        .retain(|w| !w.starts_with(UNIT_NOTE_PREFIX));
    let note = match stated {
        StatedUnit::G => {
            recording.unit = SampleUnit::G;
            "values taken as g, as --unit g says".to_string()
        }
        StatedUnit::MetresPerSecondSquared => {
            recording.unit = SampleUnit::G;
            for s in &mut recording.samples {
                *s /= STANDARD_GRAVITY;
            }
            format!("values in m/s², as --unit m/s2 says: divided by {STANDARD_GRAVITY} to give g")
        }
        StatedUnit::FullScale => {
            recording.unit = SampleUnit::FullScale;
            "values taken as relative (full scale), as --unit full-scale says: no velocity in mm/s"
                .to_string()
        }
    };
    recording.notes.push(format!("{UNIT_NOTE_PREFIX}{note}"));
    Ok(recording)
}

/// How every note or warning about a recording's unit starts, so a stated unit can replace the
/// format's assumption.
pub const UNIT_NOTE_PREFIX: &str = "unit: ";

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_and_file_read_alike() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("table.csv");
        let text = b"x,y\n1,2\n3,4\n5,6\n";
        std::fs::write(&path, text).unwrap();
        let options = ReadOptions {
            channel: Some("y".to_string()),
            column: None,
            unit: None,
        };
        let from_file = read_recording(&path, &options).unwrap();
        let from_bytes = read_recording_from_bytes(&path, text, &options).unwrap();
        assert_eq!(from_bytes, from_file);
        assert_eq!(from_bytes.samples, vec![2.0, 4.0, 6.0]);
        assert_eq!(
            list_channels_from_bytes(&path, text).unwrap(),
            list_channels(&path).unwrap()
        );
        let empty = read_recording_from_bytes(&path, b"", &ReadOptions::default());
        assert!(matches!(empty, Err(RecordingError::Empty { .. })));
        let log = read_recording_from_bytes(Path::new("x.mcap"), MCAP_MAGIC, &options);
        assert!(matches!(log, Err(RecordingError::UnknownFormat { .. })));
    }
}
