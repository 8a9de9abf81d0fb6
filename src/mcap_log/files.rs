//! The log's file names: `bearingd-YYYYMMDDTHHMMSSZ-NNNNNN.mcap`, fixed width so that sorting
//! names sorts files by opening time. Retention and recovery only ever touch names of this form.

/// File name prefix of every log file; retention only ever touches `bearingd-*.mcap`.
pub const FILE_PREFIX: &str = "bearingd-";
/// File name suffix.
pub const FILE_SUFFIX: &str = ".mcap";

/// `bearingd-YYYYMMDDTHHMMSSZ-NNNNNN.mcap` for a UTC time in ns since the epoch: fixed width,
/// so sorting names sorts files by opening time, then sequence.
pub fn file_name(opened_at_ns: u64, seq: u32) -> String {
    let secs = opened_at_ns / 1_000_000_000;
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let (y, m, d) = civil_from_days(days);
    format!(
        "{FILE_PREFIX}{y:04}{m:02}{d:02}T{:02}{:02}{:02}Z-{seq:06}{FILE_SUFFIX}",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60
    )
}

/// `YYYY-MM-DDTHH:MM:SS.mmmZ` (RFC 3339, UTC) for a time in ns since the epoch.
pub fn utc_text(ns: u64) -> String {
    let secs = ns / 1_000_000_000;
    let rem = secs % 86_400;
    let (y, m, d) = civil_from_days((secs / 86_400) as i64);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}.{:03}Z",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60,
        (ns % 1_000_000_000) / 1_000_000
    )
}

/// Gregorian date of a day count since 1970-01-01 (the well-known era/day-of-era method).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

/// Is this a log file name this module wrote (and so may delete)?
pub fn is_log_file_name(name: &str) -> bool {
    name.starts_with(FILE_PREFIX) && name.ends_with(FILE_SUFFIX)
}
