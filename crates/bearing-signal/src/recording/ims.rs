//! NASA/IMS bearing snapshots: one file per snapshot, named by its time stamp
//! (`2003.10.22.12.14.13`), no extension, no header, whitespace-separated columns at 20 kHz.
//! Test 1 has 8 columns (two accelerometers per bearing: B1x B1y … B4y), tests 2 and 3 have 4
//! (B1 … B4). The shaft speed (2000 rpm) is not in the file, so `rpm` stays `None`.

use super::text::{self, Sep};
use super::{pick_by_name_or_index, Recording, RecordingError, RecordingFormat};
use std::path::Path;

const IMS_FS_HZ: f64 = 20_000.0;
const NAMES_8: [&str; 8] = ["B1x", "B1y", "B2x", "B2y", "B3x", "B3y", "B4x", "B4y"];
const NAMES_4: [&str; 4] = ["B1", "B2", "B3", "B4"];

/// `YYYY.MM.DD.hh.mm.ss`, all digits.
pub(super) fn is_ims_name(name: &str) -> bool {
    let parts: Vec<&str> = name.split('.').collect();
    parts.len() == 6
        && parts
            .iter()
            .zip([4, 2, 2, 2, 2, 2])
            .all(|(p, n)| p.len() == n && p.bytes().all(|b| b.is_ascii_digit()))
}

/// A first line of 4 or 8 tab-separated numbers.
pub(super) fn looks_like_ims(head: &[u8]) -> bool {
    let first = head.split(|&b| b == b'\n').next().unwrap_or_default();
    let Ok(line) = std::str::from_utf8(first) else {
        return false;
    };
    let fields: Vec<&str> = line.trim().split('\t').collect();
    matches!(fields.len(), 4 | 8) && fields.iter().all(|f| f.trim().parse::<f64>().is_ok())
}

fn layout(path: &Path, text: &str) -> Result<text::Layout, RecordingError> {
    let mut layout = text::layout(path, text, Some(Sep::Whitespace))?;
    let names: &[&str] = match layout.names.len() {
        8 => &NAMES_8,
        4 => &NAMES_4,
        n => {
            return Err(RecordingError::MalformedRow {
                path: path.to_path_buf(),
                line: layout.first_line,
                problem: format!(
                    "{n} column(s), but an IMS snapshot has 8 (test 1) or 4 (tests 2 and 3)"
                ),
            })
        }
    };
    layout.names = names.iter().map(|s| s.to_string()).collect();
    Ok(layout)
}

pub(super) fn read(
    path: &Path,
    bytes: &[u8],
    selector: Option<&str>,
) -> Result<Recording, RecordingError> {
    let text = text::as_text(path, bytes)?;
    let layout = layout(path, text)?;
    let col = match selector {
        None => 0,
        Some(wanted) => pick_by_name_or_index(path, "channel", wanted, &layout.names, true)?,
    };
    let column = text::read_column(path, text, &layout, col)?;
    Ok(Recording {
        path: path.to_path_buf(),
        format: RecordingFormat::ImsText,
        channel: layout.names[col].clone(),
        fs_hz: Some(IMS_FS_HZ),
        rpm: None,
        samples: column.samples,
        warnings: column.warnings,
        unit: super::SampleUnit::G,
        notes: Vec::new(),
    })
}

pub(super) fn channels(path: &Path, bytes: &[u8]) -> Result<Vec<String>, RecordingError> {
    Ok(layout(path, text::as_text(path, bytes)?)?.names)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_content() {
        assert!(is_ims_name("2003.10.22.12.14.13"));
        assert!(!is_ims_name("2003.10.22.12.14"));
        assert!(!is_ims_name("2003.10.22.12.14.1x"));
        assert!(looks_like_ims(b"-0.054\t-0.049\t0.1\t0.2\n"));
        assert!(!looks_like_ims(b"a\tb\tc\td\n"));
        assert!(!looks_like_ims(b"1,2,3,4\n"));
    }

    #[test]
    fn four_column_files_and_channel_by_index() {
        let p = Path::new("2004.02.12.10.32.39");
        let r = read(p, b"1\t2\t3\t4\n5\t6\t7\t8\n", Some("3")).unwrap();
        assert_eq!(
            (r.channel.as_str(), r.samples.as_slice()),
            ("B3", &[3.0, 7.0][..])
        );
        let e = read(p, b"1\t2\t3\n", None).unwrap_err().to_string();
        assert!(e.contains("3 column(s)"), "{e}");
    }
}
