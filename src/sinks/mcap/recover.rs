//! Start-up recovery of files a crashed run left unfinished. Recovery never destroys.
//!
//! A writer killed with `kill -9` (or a power cut) leaves a file without summary, footer and
//! end magic; strict readers (Python's `make_reader`, Foxglove's indexed loading) refuse it.
//! Every complete chunk in it is still good, so [`recover_directory`] rewrites each such file
//! from its complete records into a finished one.
//!
//! How, for each unfinished `bearingd-*.mcap`:
//! - nothing in it can be read (not MCAP at all, or not one record: a random file named like a
//!   log, a file cut before its first chunk) → it is **moved to `quarantine/`** beside the logs,
//!   untouched, and the report says why; no copy is started for it, and no length it declares
//!   is allocated (every read is bounded: [`crate::mcap_log::bounds`]), so a hostile file can
//!   neither abort the start nor be met again by the next one. An empty (0-byte) file holds
//!   nothing and is removed.
//! - otherwise the readable records are copied to `<name>.recovering`, fsynced, and the copy is
//!   **read back strictly** by the `mcap` crate's own reader
//!   ([`crate::mcap_log::read_back_strictly`]: every CRC, the summary, the message count). Only
//!   then is it renamed over the original and the directory fsynced, so the name holds either
//!   the old bytes or the complete new file at every instant. A copy that fails the check is
//!   deleted and the original goes to `quarantine/`.
//! - when chunks *inside* the file were damaged (skipped, not just a cut-off tail), the
//!   original is first hard-linked into `quarantine/` so that its bytes stay for an expert.
//!   A cut-off tail (the chunk being written at the kill) cannot be decoded by anyone and is
//!   only counted.
//!
//! Only this user's regular files are read, rewritten, moved or deleted: a log-named link
//! (to anything), directory, special file or another user's file is left alone and reported
//! ([`RecoveryAction::Skipped`]); nothing is ever read through a link. The recovered copy is
//! created beside the original (never through a link) with the original's mode, at most 0640.
//!
//! Quarantined files are never deleted by retention; the operator clears `quarantine/`.
//! A leftover `*.recovering` from a crash during recovery is an incomplete copy (its original
//! is still in place): it is deleted and the recovery redone.

use std::collections::HashMap;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions};

use crate::fsafe::{
    create_new_with_mode, open_own_file, own_regular_file, parent_dir, NotOwnFile, FILE_MODE,
};
use crate::mcap_log::error::{io_err, McapLogError, Result};
use crate::mcap_log::files::is_log_file_name;
use crate::mcap_log::scan::{ScanOutcome, ScannedRecord, Scanner};
use crate::mcap_log::verify::read_back_strictly;

/// What recovering one file did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecoveryReport {
    pub path: PathBuf,
    /// Messages copied into the recovered file.
    pub messages_recovered: u64,
    /// Bytes of the original that could not be read (the open chunk, damaged chunks).
    pub unreadable_bytes: u64,
    /// Size of the original before recovery.
    pub original_bytes: u64,
    /// Where and why reading the original stopped, if it did before its end.
    pub problem: Option<(u64, String)>,
    /// What became of the original.
    pub action: RecoveryAction,
}

/// What recovery did with an unfinished file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RecoveryAction {
    /// The recovered copy (read back strictly) replaced it; `original_kept` is the hard link
    /// to the original's bytes in `quarantine/` when chunks inside it were damaged.
    Rewritten { original_kept: Option<PathBuf> },
    /// Nothing could be recovered from it, or the copy failed the strict read: moved, as it
    /// was, to `to` (in `quarantine/`).
    Quarantined { to: PathBuf, reason: String },
    /// It was empty (0 bytes: nothing to keep) and was removed.
    RemovedEmpty,
    /// It is not this user's regular file (a link, a directory, another user's file): left
    /// alone, not read.
    Skipped(NotOwnFile),
}

const TEMP_SUFFIX: &str = ".recovering";
/// The directory beside the logs where files recovery could not use are kept.
pub const QUARANTINE_DIR: &str = "quarantine";

/// Finds `bearingd-*.mcap` files in `dir` that are not finished and recovers each; see the
/// module docs. Call it before opening a new logger in `dir`. Finished files are not touched.
pub fn recover_directory(dir: &Path) -> Result<Vec<RecoveryReport>> {
    let mut names = Vec::new();
    let mut reports = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io_err(dir, "list directory"))? {
        let entry = entry.map_err(io_err(dir, "list directory"))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let leftover =
            name.ends_with(TEMP_SUFFIX) && is_log_file_name(name.trim_end_matches(TEMP_SUFFIX));
        if !leftover && !is_log_file_name(&name) {
            continue;
        }
        if let Err(not_own) = own_regular_file(&entry.path()) {
            reports.push(skipped(not_own));
        } else if leftover {
            std::fs::remove_file(entry.path()).map_err(io_err(entry.path(), "delete"))?;
        } else {
            names.push(name);
        }
    }
    names.sort();
    for name in names {
        let path = dir.join(&name);
        match is_finished(&path) {
            Ok(true) => {}
            Ok(false) => reports.push(recover_file(&path)?),
            Err(McapLogError::NotOwnFile(not_own)) => reports.push(skipped(not_own)),
            Err(e) => return Err(e),
        }
    }
    Ok(reports)
}

/// The report of a name recovery leaves alone.
fn skipped(not_own: NotOwnFile) -> RecoveryReport {
    RecoveryReport {
        path: not_own.path().to_path_buf(),
        messages_recovered: 0,
        unreadable_bytes: 0,
        original_bytes: 0,
        problem: None,
        action: RecoveryAction::Skipped(not_own),
    }
}

/// Has `path` a footer and end magic at its end? (Reads only the last bytes.) A name that is
/// not this user's regular file is refused ([`McapLogError::NotOwnFile`]), not read.
pub fn is_finished(path: &Path) -> Result<bool> {
    use std::io::{Read, Seek, SeekFrom};
    // Footer record: opcode, length (8), summary start (8), summary offset start (8), crc (4);
    // then the 8-byte magic.
    const TAIL: u64 = 1 + 8 + 20 + 8;
    let mut file = open_own_file(path)?;
    let len = file.metadata().map_err(io_err(path, "stat"))?.len();
    if len < 8 + TAIL {
        return Ok(false);
    }
    file.seek(SeekFrom::Start(len - TAIL))
        .map_err(io_err(path, "seek"))?;
    let mut tail = [0u8; TAIL as usize];
    file.read_exact(&mut tail).map_err(io_err(path, "read"))?;
    let mut head = [0u8; 8];
    file.seek(SeekFrom::Start(0))
        .map_err(io_err(path, "seek"))?;
    file.read_exact(&mut head).map_err(io_err(path, "read"))?;
    Ok(head == mcap::MAGIC
        && tail[0] == 0x02
        && tail[1..9] == 20u64.to_le_bytes()
        && tail[29..] == *mcap::MAGIC)
}

/// Recovers one unfinished file as the module docs say: rewritten from its complete records
/// (the copy checked strictly before it replaces the original), or quarantined.
pub fn recover_file(path: &Path) -> Result<RecoveryReport> {
    let original = match own_regular_file(path) {
        Ok(meta) => meta,
        Err(not_own) => return Ok(skipped(not_own)),
    };
    let original_bytes = original.len();
    // The copy keeps the original's mode, never wider than 0640.
    let copy_mode = std::os::unix::fs::PermissionsExt::mode(&original.permissions()) & FILE_MODE;
    let report = |action, messages_recovered, outcome: &ScanOutcome, problem| RecoveryReport {
        path: path.to_path_buf(),
        messages_recovered,
        unreadable_bytes: outcome.unreadable_bytes,
        original_bytes,
        problem,
        action,
    };
    if original_bytes == 0 {
        std::fs::remove_file(path).map_err(io_err(path, "remove empty file"))?;
        return Ok(report(
            RecoveryAction::RemovedEmpty,
            0,
            &ScanOutcome::default(),
            None,
        ));
    }
    let mut temp_name = path.as_os_str().to_owned();
    temp_name.push(TEMP_SUFFIX);
    let temp = PathBuf::from(temp_name);
    let copied = copy_readable_records(path, &temp, copy_mode);
    let (copy, outcome) = match copied {
        Ok(c) => c,
        Err(e) => {
            let _ = std::fs::remove_file(&temp);
            let to = quarantine(path, false)?;
            return Ok(report(
                RecoveryAction::Quarantined {
                    to,
                    reason: format!("the copy could not be written: {e}"),
                },
                0,
                &ScanOutcome::default(),
                None,
            ));
        }
    };
    let mut problem = outcome.first_problem.clone();
    if copy.orphans > 0 && problem.is_none() {
        problem = Some((
            0,
            format!("{} messages on channels without a record", copy.orphans),
        ));
    }
    if copy.records == 0 {
        let _ = std::fs::remove_file(&temp);
        let reason = problem
            .as_ref()
            .map(|(at, why)| format!("nothing readable (byte {at}: {why})"))
            .unwrap_or_else(|| "nothing readable".into());
        let to = quarantine(path, false)?;
        return Ok(report(
            RecoveryAction::Quarantined { to, reason },
            0,
            &outcome,
            problem,
        ));
    }
    match read_back_strictly(&temp) {
        Ok(read) if read.messages == copy.messages => {}
        checked => {
            let _ = std::fs::remove_file(&temp);
            let reason = match checked {
                Ok(read) => format!(
                    "the recovered copy holds {} messages, {} were copied",
                    read.messages, copy.messages
                ),
                Err(e) => format!("the recovered copy failed the strict read: {e}"),
            };
            let to = quarantine(path, false)?;
            return Ok(report(
                RecoveryAction::Quarantined { to, reason },
                0,
                &outcome,
                problem,
            ));
        }
    }
    let original_kept = if outcome.chunks_skipped > 0 {
        Some(quarantine(path, true)?)
    } else {
        None
    };
    std::fs::rename(&temp, path).map_err(io_err(path, "rename recovered file over"))?;
    sync_parent(path);
    Ok(report(
        RecoveryAction::Rewritten { original_kept },
        copy.messages,
        &outcome,
        problem,
    ))
}

/// What [`copy_readable_records`] wrote.
struct Copied {
    /// Schemas, channels and messages copied.
    records: u64,
    messages: u64,
    /// Messages whose channel record was not found (not copied).
    orphans: u64,
}

/// Writes every readable record of `path` into a new finished file `temp` (created with
/// `mode`, never through a link), fsynced.
fn copy_readable_records(path: &Path, temp: &Path, mode: u32) -> Result<(Copied, ScanOutcome)> {
    let werr = |source| McapLogError::Write {
        path: temp.to_path_buf(),
        source,
    };
    let mut copied = Copied {
        records: 0,
        messages: 0,
        orphans: 0,
    };
    let mut scanner = Scanner::open(path)?;
    // The copy is created only once there is something to copy: a file with not one readable
    // record (a hostile or random file) is quarantined with nothing written beside it.
    let Some(first) = scanner.next_record()? else {
        return Ok((copied, scanner.outcome().clone()));
    };
    let file = create_new_with_mode(temp, mode).map_err(io_err(temp, "create"))?;
    let mut writer = WriteOptions::new()
        .profile("")
        .library(concat!("bearingd ", env!("CARGO_PKG_VERSION"), " recovery"))
        .compression(Some(Compression::Zstd))
        .create(BufWriter::new(file))
        .map_err(werr)?;
    let mut schema_ids: HashMap<u16, u16> = HashMap::new();
    let mut channel_ids: HashMap<u16, u16> = HashMap::new();
    let mut first = Some(first);
    while let Some(record) = match first.take() {
        Some(record) => Some(record),
        None => scanner.next_record()?,
    } {
        match record {
            ScannedRecord::Schema {
                id,
                name,
                encoding,
                data,
            } => {
                let new = writer.add_schema(&name, &encoding, &data).map_err(werr)?;
                schema_ids.insert(id, new);
                copied.records += 1;
            }
            ScannedRecord::Channel {
                id,
                schema_id,
                topic,
                message_encoding,
                metadata,
            } => {
                let new_schema = if schema_id == 0 {
                    Some(0)
                } else {
                    schema_ids.get(&schema_id).copied()
                };
                if let Some(s) = new_schema {
                    let new = writer
                        .add_channel(s, &topic, &message_encoding, &metadata)
                        .map_err(werr)?;
                    channel_ids.insert(id, new);
                    copied.records += 1;
                }
            }
            ScannedRecord::Metadata { name, metadata } => {
                writer
                    .write_metadata(&mcap::records::Metadata { name, metadata })
                    .map_err(werr)?;
                copied.records += 1;
            }
            ScannedRecord::Message {
                channel_id,
                sequence,
                log_time,
                publish_time,
                data,
                ..
            } => {
                let Some(&channel_id) = channel_ids.get(&channel_id) else {
                    copied.orphans += 1;
                    continue;
                };
                let header = MessageHeader {
                    channel_id,
                    sequence,
                    log_time,
                    publish_time,
                };
                writer
                    .write_to_known_channel(&header, &data)
                    .map_err(werr)?;
                copied.messages += 1;
                copied.records += 1;
            }
        }
    }
    writer.finish().map_err(werr)?;
    let file = writer
        .into_inner()
        .into_inner()
        .map_err(|e| io_err(temp, "flush")(e.into_error()))?;
    file.sync_all().map_err(io_err(temp, "fsync"))?;
    Ok((copied, scanner.outcome().clone()))
}

/// Moves `path` (or, with `keep_link`, hard-links it) into `quarantine/` beside it, under a
/// name not yet taken there; returns the new path.
fn quarantine(path: &Path, keep_link: bool) -> Result<PathBuf> {
    let dir = parent_dir(path).join(QUARANTINE_DIR);
    crate::fsafe::create_dir_all(&dir).map_err(io_err(&dir, "create the quarantine directory"))?;
    // A link named `quarantine` would send the files elsewhere.
    match std::fs::symlink_metadata(&dir) {
        Ok(meta) if meta.is_dir() => {}
        _ => {
            return Err(io_err(&dir, "use the quarantine directory")(
                std::io::Error::other("not a directory (a link?); remove it"),
            ))
        }
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "unnamed".into());
    let mut to = dir.join(&name);
    let mut n = 1;
    while std::fs::symlink_metadata(&to).is_ok() {
        to = dir.join(format!("{name}.{n}"));
        n += 1;
    }
    if keep_link {
        // A file system without hard links gets a copy.
        if std::fs::hard_link(path, &to).is_err() {
            copy_own_file(path, &to).map_err(io_err(&to, "keep the original in quarantine"))?;
        }
    } else {
        std::fs::rename(path, &to).map_err(io_err(&to, "move into quarantine"))?;
    }
    sync_parent(&to);
    sync_parent(path);
    Ok(to)
}

/// Copies this user's regular file `from` to the new name `to`, never through a link, with
/// `from`'s mode (at most 0640).
fn copy_own_file(from: &Path, to: &Path) -> std::io::Result<()> {
    let mut source = open_own_file(from).map_err(std::io::Error::other)?;
    let mode = std::os::unix::fs::PermissionsExt::mode(&source.metadata()?.permissions());
    let mut copy = create_new_with_mode(to, mode & FILE_MODE)?;
    std::io::copy(&mut source, &mut copy)?;
    copy.sync_all()
}

/// Makes a rename in `path`'s directory durable; a directory that cannot be opened for fsync
/// is not fatal.
pub(super) fn sync_parent(path: &Path) {
    crate::fsafe::sync_dir(parent_dir(path));
}
