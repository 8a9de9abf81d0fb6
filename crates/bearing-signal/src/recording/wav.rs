//! WAV files, through `hound`. The header gives the sampling rate; chunks other than `fmt ` and
//! `data` (LIST/INFO, vendor chunks) are skipped.
//!
//! Integer samples are scaled to ±1.0 full scale (divided by 2^(bits−1)); float samples are
//! kept as they are. A WAV file carries no scale to g, so the amplitudes are relative and a
//! warning says so. A data chunk that promises more frames than the file holds (a recorder
//! stopped before it could finish) is read up to its last complete frame, with a warning.

use super::{pick_by_name_or_index, Recording, RecordingError, RecordingFormat};
use std::io::Cursor;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

fn open<'a>(
    path: &Path,
    bytes: &'a [u8],
) -> Result<hound::WavReader<Cursor<&'a [u8]>>, RecordingError> {
    hound::WavReader::new(Cursor::new(bytes)).map_err(|e| bad_wav(path, e))
}

fn bad_wav(path: &Path, e: hound::Error) -> RecordingError {
    let detail = match e {
        hound::Error::IoError(_) => {
            "the header ends early (file truncated or not a WAV)".to_string()
        }
        e => e.to_string(),
    };
    RecordingError::BadWav {
        path: path.to_path_buf(),
        detail,
    }
}

fn names(channels: u16) -> Vec<String> {
    (1..=channels).map(|c| c.to_string()).collect()
}

pub(super) fn channels(path: &Path, bytes: &[u8]) -> Result<Vec<String>, RecordingError> {
    Ok(names(open(path, bytes)?.spec().channels))
}

pub(super) fn read(
    path: &Path,
    bytes: &[u8],
    selector: Option<&str>,
) -> Result<Recording, RecordingError> {
    // hound checks its inputs, but "no panic on any input" is a promise, so it gets a backstop.
    catch_unwind(AssertUnwindSafe(|| read_inner(path, bytes, selector))).unwrap_or_else(|_| {
        Err(RecordingError::BadWav {
            path: path.to_path_buf(),
            detail: "the WAV decoder failed on this file (internal panic)".to_string(),
        })
    })
}

fn read_inner(
    path: &Path,
    bytes: &[u8],
    selector: Option<&str>,
) -> Result<Recording, RecordingError> {
    let mut reader = open(path, bytes)?;
    let spec = reader.spec();
    let n = usize::from(spec.channels);
    let names = names(spec.channels);
    let ch = match selector {
        None => 0,
        Some(wanted) => pick_by_name_or_index(path, "channel", wanted, &names, false)?,
    };
    let declared = reader.duration() as usize;
    let block = usize::from(spec.bits_per_sample.div_ceil(8)).max(1) * n;
    let mut samples = Vec::with_capacity(declared.min(bytes.len() / block.max(1)));
    let mut read = 0usize;
    let mut truncated = false;
    match spec.sample_format {
        hound::SampleFormat::Int => {
            let scale = 1.0 / f64::from(1u32 << (spec.bits_per_sample.clamp(1, 32) - 1));
            for s in reader.samples::<i32>() {
                match s {
                    Ok(v) if read % n == ch => samples.push(f64::from(v) * scale),
                    Ok(_) => {}
                    Err(hound::Error::IoError(_)) => {
                        truncated = true;
                        break;
                    }
                    Err(e) => return Err(bad_wav(path, e)),
                }
                read += 1;
            }
        }
        hound::SampleFormat::Float => {
            for s in reader.samples::<f32>() {
                match s {
                    Ok(v) if read % n == ch => samples.push(f64::from(v)),
                    Ok(_) => {}
                    Err(hound::Error::IoError(_)) => {
                        truncated = true;
                        break;
                    }
                    Err(e) => return Err(bad_wav(path, e)),
                }
                read += 1;
            }
        }
    }
    let frames = read / n;
    samples.truncate(frames);
    let mut warnings = vec![
        "WAV samples are in full-scale units (integers scaled to ±1.0, floats as stored), not g: amplitudes are relative".to_string(),
    ];
    if truncated {
        warnings.push(format!(
            "the data chunk declares {declared} frames but the file ends after {frames}; read the {frames} complete frames"
        ));
    }
    let fs_hz = (spec.sample_rate > 0).then_some(f64::from(spec.sample_rate));
    if fs_hz.is_none() {
        warnings.push("the header gives a sampling rate of 0 Hz; treated as unknown".to_string());
    }
    if samples.is_empty() {
        return Err(RecordingError::Empty {
            path: path.to_path_buf(),
            detail: format!(
                "the WAV data chunk holds no complete frame (declared {declared}); the recorder may have stopped before finishing the file"
            ),
        });
    }
    Ok(Recording {
        path: path.to_path_buf(),
        format: RecordingFormat::Wav,
        channel: names[ch].clone(),
        fs_hz,
        rpm: None,
        samples,
        warnings,
    })
}
