//! Plain CSV tables and PRONOSTIA `acc_NNNNN.csv` snapshots.
//!
//! A plain table says nothing about its sampling rate, so `fs_hz` is `None`; with more than one
//! column the caller must say which one (no silent "first column"). PRONOSTIA files have no
//! header; their layout and rate (25.6 kHz) are fixed by the data set and recognised by name.

use super::text::{self, Layout};
use super::{pick_by_name_or_index, Recording, RecordingError, RecordingFormat};
use std::path::Path;

/// PRONOSTIA column names, in file order.
const PRONOSTIA_COLUMNS: [&str; 6] = [
    "hour",
    "minute",
    "second",
    "microsecond",
    "horizontal",
    "vertical",
];
/// The channels a PRONOSTIA file offers.
pub(super) const PRONOSTIA_CHANNELS: [&str; 2] = ["horizontal", "vertical"];
const PRONOSTIA_FS_HZ: f64 = 25_600.0;

/// `acc_` + digits + `.csv`, any case.
pub(super) fn is_pronostia_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    lower
        .strip_prefix("acc_")
        .and_then(|r| r.strip_suffix(".csv"))
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

pub(super) fn read_pronostia(
    path: &Path,
    bytes: &[u8],
    selector: Option<&str>,
) -> Result<Recording, RecordingError> {
    let text = text::as_text(path, bytes)?;
    let mut layout = text::layout(path, text, None)?;
    if layout.names.len() != PRONOSTIA_COLUMNS.len() {
        return Err(RecordingError::MalformedRow {
            path: path.to_path_buf(),
            line: layout.first_line,
            problem: format!(
                "{} field(s), but a PRONOSTIA acc file has 6 (hour, minute, second, microsecond, horizontal, vertical); if this is another kind of table, rename it so it does not start with acc_",
                layout.names.len()
            ),
        });
    }
    layout.names = PRONOSTIA_COLUMNS.iter().map(|s| s.to_string()).collect();
    let channels: Vec<String> = PRONOSTIA_CHANNELS.iter().map(|s| s.to_string()).collect();
    let pick = match selector {
        None => 0,
        Some(wanted) => pick_by_name_or_index(path, "channel", wanted, &channels, false)?,
    };
    let col = 4 + pick;
    let column = text::read_column(path, text, &layout, col)?;
    Ok(Recording {
        path: path.to_path_buf(),
        format: RecordingFormat::PronostiaCsv,
        channel: channels[pick].clone(),
        fs_hz: Some(PRONOSTIA_FS_HZ),
        rpm: None,
        samples: column.samples,
        warnings: column.warnings,
        unit: super::SampleUnit::G,
        notes: Vec::new(),
    })
}

pub(super) fn read_plain(
    path: &Path,
    bytes: &[u8],
    selector: Option<&str>,
) -> Result<Recording, RecordingError> {
    let text = text::as_text(path, bytes)?;
    let layout = text::layout(path, text, None)?;
    let col = plain_column(path, &layout, selector)?;
    let column = text::read_column(path, text, &layout, col)?;
    Ok(Recording {
        path: path.to_path_buf(),
        format: RecordingFormat::PlainCsv,
        channel: layout.names[col].clone(),
        fs_hz: None,
        rpm: None,
        samples: column.samples,
        warnings: column.warnings,
        unit: super::SampleUnit::G,
        notes: Vec::new(),
    })
}

pub(super) fn plain_channels(path: &Path, bytes: &[u8]) -> Result<Vec<String>, RecordingError> {
    let text = text::as_text(path, bytes)?;
    Ok(text::layout(path, text, None)?.names)
}

fn plain_column(
    path: &Path,
    layout: &Layout,
    selector: Option<&str>,
) -> Result<usize, RecordingError> {
    match selector {
        Some(wanted) => pick_by_name_or_index(path, "column", wanted, &layout.names, true),
        None if layout.names.len() == 1 => Ok(0),
        None => Err(RecordingError::ColumnRequired {
            path: path.to_path_buf(),
            available: layout.names.clone(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pronostia_names() {
        assert!(is_pronostia_name("acc_00001.csv"));
        assert!(is_pronostia_name("ACC_7.CSV"));
        assert!(!is_pronostia_name("acc_.csv"));
        assert!(!is_pronostia_name("acc_1a.csv"));
        assert!(!is_pronostia_name("temp_00001.csv"));
    }

    #[test]
    fn semicolon_pronostia_and_vertical() {
        let p = Path::new("acc_00001.csv");
        let r = read_pronostia(
            p,
            b"8;47;5;1.9691e+05;0.05;-0.253\n8;47;5;1.97e+05;0.1;0.2\n",
            Some("Vertical"),
        )
        .unwrap();
        assert_eq!(r.samples, [-0.253, 0.2]);
        assert_eq!(r.channel, "vertical");
        let e = read_pronostia(p, b"1,2,3\n", None).unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("has 6"), "{e}");
    }

    #[test]
    fn plain_column_choice() {
        let p = Path::new("x.csv");
        let data = b"time;a;b\n0;1;2\n1;3;4\n";
        assert_eq!(read_plain(p, data, Some("B")).unwrap().samples, [2.0, 4.0]);
        assert_eq!(read_plain(p, data, Some("2")).unwrap().samples, [1.0, 3.0]);
        let e = read_plain(p, data, None).unwrap_err().to_string();
        assert!(e.contains("3 columns (time, a, b)"), "{e}");
        let e = read_plain(p, data, Some("c")).unwrap_err().to_string();
        assert!(
            e.contains("no column 'c'") && e.contains("index 1..3"),
            "{e}"
        );
        assert_eq!(
            read_plain(p, b"1.5\n2.5", None).unwrap().channel,
            "column 1"
        );
    }
}
