//! When a snapshot was taken, from what its file name states: a series of snapshots
//! (`bearingd trend`) is put in time order with it.
//!
//! - PRONOSTIA `acc_NNNNN.csv`: snapshot N of a test that takes one every 10 s (the data set's
//!   documentation), so `(N − 1) · 10 s` after the first.
//! - IMS `YYYY.MM.DD.hh.mm.ss`: the time of day it was taken.
//! - bearingd logs `bearingd-YYYYMMDDTHHMMSSZ-NNNNNN.mcap`: the UTC time the file was opened.
//!
//! Other names state no time; the caller places them by another rule (or refuses them).

use std::path::Path;

/// PRONOSTIA's snapshot period.
pub const PRONOSTIA_PERIOD_S: f64 = 10.0;

/// A time read from a file name, in seconds on the name's own scale (seconds since 1970 for
/// dates, since the first snapshot for PRONOSTIA numbers); only differences matter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NamedTime {
    pub seconds: f64,
    /// What the name was read as.
    pub kind: NamedTimeKind,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NamedTimeKind {
    PronostiaIndex,
    ImsDate,
    BearingdLog,
}

/// The time `path`'s name states, if any.
pub fn time_from_name(path: &Path) -> Option<NamedTime> {
    let name = path.file_name()?.to_str()?;
    pronostia(name)
        .map(|seconds| NamedTime {
            seconds,
            kind: NamedTimeKind::PronostiaIndex,
        })
        .or_else(|| {
            ims(name).map(|seconds| NamedTime {
                seconds,
                kind: NamedTimeKind::ImsDate,
            })
        })
        .or_else(|| {
            bearingd_log(name).map(|seconds| NamedTime {
                seconds,
                kind: NamedTimeKind::BearingdLog,
            })
        })
}

fn pronostia(name: &str) -> Option<f64> {
    let lower = name.to_ascii_lowercase();
    let digits = lower.strip_prefix("acc_")?.strip_suffix(".csv")?;
    let index: u32 = all_digits(digits)?.parse().ok()?;
    Some(f64::from(index.max(1) - 1) * PRONOSTIA_PERIOD_S)
}

/// `2003.10.22.12.14.13`.
fn ims(name: &str) -> Option<f64> {
    let parts: Vec<&str> = name.split('.').collect();
    let [y, mo, d, h, mi, s] = parts.as_slice() else {
        return None;
    };
    let fields = [y, mo, d, h, mi, s].map(|p| all_digits(p).and_then(|p| p.parse::<i64>().ok()));
    let [Some(y), Some(mo), Some(d), Some(h), Some(mi), Some(s)] = fields else {
        return None;
    };
    seconds_of(y, mo, d, h, mi, s)
}

/// `bearingd-20261123T172233Z-000001.mcap`.
fn bearingd_log(name: &str) -> Option<f64> {
    let rest = name.strip_prefix("bearingd-")?.strip_suffix(".mcap")?;
    let (stamp, seq) = rest.split_once('-')?;
    all_digits(seq)?;
    let (date, time) = stamp.strip_suffix('Z')?.split_once('T')?;
    if date.len() != 8 || time.len() != 6 {
        return None;
    }
    let num = |s: &str| all_digits(s).and_then(|s| s.parse::<i64>().ok());
    seconds_of(
        num(&date[..4])?,
        num(&date[4..6])?,
        num(&date[6..])?,
        num(&time[..2])?,
        num(&time[2..4])?,
        num(&time[4..])?,
    )
}

fn all_digits(s: &str) -> Option<&str> {
    (!s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())).then_some(s)
}

fn seconds_of(y: i64, mo: i64, d: i64, h: i64, mi: i64, s: i64) -> Option<f64> {
    if !((1..=12).contains(&mo)
        && (1..=31).contains(&d)
        && (0..24).contains(&h)
        && (0..60).contains(&mi)
        && (0..=60).contains(&s))
    {
        return None;
    }
    Some((days_from_civil(y, mo, d) * 86_400 + h * 3600 + mi * 60 + s) as f64)
}

/// Days since 1970-01-01 of a Gregorian date (the era/day-of-era method).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(name: &str) -> Option<(f64, NamedTimeKind)> {
        time_from_name(Path::new(name)).map(|t| (t.seconds, t.kind))
    }

    #[test]
    fn names_that_state_a_time() {
        assert_eq!(
            at("dir/acc_00011.csv"),
            Some((100.0, NamedTimeKind::PronostiaIndex))
        );
        let a = at("2003.10.22.12.14.13").unwrap();
        let b = at("2003.10.22.13.04.13").unwrap();
        assert_eq!(b.0 - a.0, 3000.0);
        assert_eq!(a.1, NamedTimeKind::ImsDate);
        // 2003-10-22T12:14:13Z is 1066824853 s after the epoch.
        assert_eq!(a.0, 1_066_824_853.0);
        let log = at("bearingd-20031022T121413Z-000003.mcap").unwrap();
        assert_eq!(log, (1_066_824_853.0, NamedTimeKind::BearingdLog));
    }

    #[test]
    fn names_that_do_not() {
        for name in [
            "manifest.csv",
            "acc_.csv",
            "acc_12a.csv",
            "2003.13.22.12.14.13",
            "2003.10.22.12.14",
            "bearingd-2003T1214Z-1.mcap",
            "run.mcap",
        ] {
            assert_eq!(at(name), None, "{name}");
        }
    }
}
