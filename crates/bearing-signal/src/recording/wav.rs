//! WAV files, through `hound`. The header gives the sampling rate; chunks other than `fmt `,
//! `data` and `iXML` (LIST/INFO, vendor chunks) are skipped.
//!
//! Float samples are read as the values they hold and taken as g: that is what `bearingd
//! simulate` writes, and a note says so (`--unit` states another unit). Integer samples are
//! scaled to ±1.0 full scale (divided by 2^(bits−1)): a recorder's counts carry no scale to g,
//! so those amplitudes are relative and a warning says so. Channels take their names from an
//! iXML chunk's `TRACK_LIST` (the convention of field recorders, which `simulate` follows),
//! else they are numbered from 1. A data chunk that promises more frames than the file holds
//! (a recorder stopped before it could finish) is read up to its last complete frame, with a
//! warning.

use super::{
    pick_by_name_or_index, Recording, RecordingError, RecordingFormat, SampleUnit, UNIT_NOTE_PREFIX,
};
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

/// The channel names: the iXML track names when the file gives one for every channel, unique
/// and non-empty; else `1`, `2`, …
fn names(bytes: &[u8], channels: u16) -> Vec<String> {
    let numbered = || (1..=channels).map(|c| c.to_string()).collect();
    let Some(ixml) = riff_chunk(bytes, b"iXML") else {
        return numbered();
    };
    let text = String::from_utf8_lossy(ixml);
    let mut named = vec![None; usize::from(channels)];
    for track in elements(&text, "TRACK") {
        let index = element(track, "CHANNEL_INDEX").and_then(|i| i.trim().parse::<usize>().ok());
        let name = element(track, "NAME").map(|n| unescape(n.trim()));
        if let (Some(index), Some(name)) = (index, name) {
            if let Some(slot) = index.checked_sub(1).and_then(|i| named.get_mut(i)) {
                *slot = Some(name);
            }
        }
    }
    let names: Option<Vec<String>> = named.into_iter().collect();
    match names {
        Some(names) if is_usable(&names) => names,
        _ => numbered(),
    }
}

/// Names a user can pick: none empty, none a number (that would shadow an index), no two alike.
fn is_usable(names: &[String]) -> bool {
    let mut seen = std::collections::HashSet::new();
    names.iter().all(|n| {
        !n.is_empty() && n.parse::<usize>().is_err() && seen.insert(n.to_ascii_lowercase())
    })
}

/// The body of the first top-level RIFF chunk `id` of a WAVE file, as far as the file holds it.
fn riff_chunk<'a>(bytes: &'a [u8], id: &[u8; 4]) -> Option<&'a [u8]> {
    if bytes.get(0..4)? != b"RIFF" || bytes.get(8..12)? != b"WAVE" {
        return None;
    }
    let mut at = 12usize;
    while let Some(header) = bytes.get(at..at.checked_add(8)?) {
        let size = u32::from_le_bytes(header[4..8].try_into().ok()?) as usize;
        let start = at + 8;
        let end = start.saturating_add(size).min(bytes.len());
        if &header[0..4] == id {
            return bytes.get(start..end);
        }
        // Chunks are padded to an even length.
        at = start.checked_add(size)?.checked_add(size % 2)?;
    }
    None
}

/// The contents of every `<tag>…</tag>` in `text`, in order (iXML has no attributes on these).
fn elements<'a>(text: &'a str, tag: &str) -> Vec<&'a str> {
    let (open, close) = (format!("<{tag}>"), format!("</{tag}>"));
    let mut found = Vec::new();
    let mut rest = text;
    while let Some(start) = rest.find(&open) {
        let after = &rest[start + open.len()..];
        let Some(end) = after.find(&close) else { break };
        found.push(&after[..end]);
        rest = &after[end + close.len()..];
    }
    found
}

/// XML's five predefined entities, `&amp;` last so that `&amp;lt;` stays `&lt;`.
fn unescape(text: &str) -> String {
    text.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

fn element<'a>(text: &'a str, tag: &str) -> Option<&'a str> {
    elements(text, tag).into_iter().next()
}

/// An iXML chunk (id, size and body, padded) naming the channels of a WAV file in order: what
/// a writer appends after the data chunk so that readers, ours included, name the channels.
pub fn ixml_track_names(names: &[&str]) -> Vec<u8> {
    let escape = |n: &str| {
        n.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut xml = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<BWFXML><IXML_VERSION>1.61</IXML_VERSION><TRACK_LIST>");
    xml.push_str(&format!("<TRACK_COUNT>{}</TRACK_COUNT>", names.len()));
    for (i, name) in names.iter().enumerate() {
        xml.push_str(&format!(
            "<TRACK><CHANNEL_INDEX>{0}</CHANNEL_INDEX><INTERLEAVE_INDEX>{0}</INTERLEAVE_INDEX><NAME>{1}</NAME></TRACK>",
            i + 1,
            escape(name)
        ));
    }
    xml.push_str("</TRACK_LIST></BWFXML>");
    let mut chunk = b"iXML".to_vec();
    chunk.extend_from_slice(&(xml.len() as u32).to_le_bytes());
    chunk.extend_from_slice(xml.as_bytes());
    if xml.len() % 2 == 1 {
        chunk.push(0);
    }
    chunk
}

pub(super) fn channels(path: &Path, bytes: &[u8]) -> Result<Vec<String>, RecordingError> {
    Ok(names(bytes, open(path, bytes)?.spec().channels))
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
    let names = names(bytes, spec.channels);
    let ch = match selector {
        None => 0,
        // Named tracks can also be picked by number; numbered ones are their own index.
        Some(wanted) => {
            let named = names.iter().any(|n| n.parse::<usize>().is_err());
            pick_by_name_or_index(path, "channel", wanted, &names, named)?
        }
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
    let (unit, mut warnings, notes) = match spec.sample_format {
        hound::SampleFormat::Float => (
            SampleUnit::G,
            Vec::new(),
            vec![format!("{UNIT_NOTE_PREFIX}float WAV samples taken as g, as bearingd simulate writes them; if they are m/s² or relative, say so with --unit m/s2 or --unit full-scale")],
        ),
        hound::SampleFormat::Int => (
            SampleUnit::FullScale,
            vec![format!("{UNIT_NOTE_PREFIX}integer WAV samples are fractions of full scale, not g: amplitudes are relative and there is no velocity in mm/s; if ±1.0 full scale is a known acceleration, say so with --unit g or --unit m/s2")],
            Vec::new(),
        ),
    };
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
        unit,
        warnings,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A float WAV of `channels` channels, 4 frames, with `extra` chunks appended after the data.
    fn wav_with(channels: u16, extra: &[u8]) -> Vec<u8> {
        let spec = hound::WavSpec {
            channels,
            sample_rate: 1000,
            bits_per_sample: 32,
            sample_format: hound::SampleFormat::Float,
        };
        let mut bytes = Cursor::new(Vec::new());
        let mut w = hound::WavWriter::new(&mut bytes, spec).unwrap();
        for i in 0..4 * channels {
            w.write_sample(f32::from(i)).unwrap();
        }
        w.finalize().unwrap();
        let mut bytes = bytes.into_inner();
        bytes.extend_from_slice(extra);
        let riff = (bytes.len() - 8) as u32;
        bytes[4..8].copy_from_slice(&riff.to_le_bytes());
        bytes
    }

    #[test]
    fn track_names_written_are_read_back_and_pick_the_channel() {
        let bytes = wav_with(2, &ixml_track_names(&["de <drive end>", "fe & fan"]));
        let path = Path::new("two.wav");
        assert_eq!(
            channels(path, &bytes).unwrap(),
            ["de <drive end>", "fe & fan"]
        );
        let fe = read(path, &bytes, Some("FE & FAN")).unwrap();
        assert_eq!(fe.channel, "fe & fan");
        assert_eq!(fe.samples, [1.0, 3.0, 5.0, 7.0]);
        assert_eq!(fe.unit, SampleUnit::G);
        // By number too.
        assert_eq!(
            read(path, &bytes, Some("1")).unwrap().channel,
            "de <drive end>"
        );
    }

    #[test]
    fn names_that_cannot_be_picked_fall_back_to_numbers() {
        for names in [&["a", "A"][..], &["a", ""], &["a", "2"], &["only one"]] {
            let bytes = wav_with(2, &ixml_track_names(names));
            assert_eq!(
                channels(Path::new("x.wav"), &bytes).unwrap(),
                ["1", "2"],
                "{names:?}"
            );
        }
    }

    #[test]
    fn chunks_are_walked_past_odd_sizes_and_a_cut_chunk_is_read_as_far_as_it_goes() {
        // An odd-sized vendor chunk (one pad byte) before the iXML chunk.
        let mut extra = b"vend\x03\x00\x00\x00abc\x00".to_vec();
        extra.extend_from_slice(&ixml_track_names(&["accel_g"]));
        assert_eq!(
            channels(Path::new("x.wav"), &wav_with(1, &extra)).unwrap(),
            ["accel_g"]
        );
        // An iXML chunk that claims more than the file holds: no name is complete, numbers.
        let mut cut = ixml_track_names(&["accel_g"]);
        cut.truncate(cut.len() / 2);
        assert_eq!(
            channels(Path::new("x.wav"), &wav_with(1, &cut)).unwrap(),
            ["1"]
        );
        // A size field that runs past the end of memory's range does not overflow.
        let huge = b"junk\xff\xff\xff\xff".to_vec();
        assert_eq!(
            channels(Path::new("x.wav"), &wav_with(1, &huge)).unwrap(),
            ["1"]
        );
    }
}
