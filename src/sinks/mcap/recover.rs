//! Start-up recovery of files a crashed run left unfinished.
//!
//! A writer killed with `kill -9` (or a power cut) leaves a file without summary, footer and
//! end magic; strict readers (Python's `make_reader`, Foxglove's indexed loading) refuse it.
//! Every complete chunk in it is still good, so [`recover_directory`] rewrites each such file
//! from its complete records into a finished one.
//!
//! Choice: the recovered file **replaces the original under the same name**. It is written to
//! `<name>.recovering`, fsynced, renamed over the original, and the directory is fsynced, so
//! at every instant the name holds either the old bytes or the complete new file. The dropped
//! bytes are exactly those no reader can decode (the open chunk, a damaged chunk); keeping
//! them would cost disk budget for nothing. The report says how many there were.
//! A leftover `*.recovering` from a crash during recovery is deleted and redone.

use std::collections::HashMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions};

use crate::mcap_log::error::{io_err, McapLogError, Result};
use crate::mcap_log::files::is_log_file_name;
use crate::mcap_log::scan::{ScannedRecord, Scanner};

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
}

const TEMP_SUFFIX: &str = ".recovering";

/// Finds `bearingd-*.mcap` files in `dir` that are not finished and recovers each; see the
/// module docs. Call it before opening a new logger in `dir`. Finished files are not touched.
pub fn recover_directory(dir: &Path) -> Result<Vec<RecoveryReport>> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io_err(dir, "list directory"))? {
        let entry = entry.map_err(io_err(dir, "list directory"))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.ends_with(TEMP_SUFFIX) && is_log_file_name(name.trim_end_matches(TEMP_SUFFIX)) {
            std::fs::remove_file(entry.path()).map_err(io_err(entry.path(), "delete"))?;
        } else if is_log_file_name(&name) {
            names.push(name);
        }
    }
    names.sort();
    let mut reports = Vec::new();
    for name in names {
        let path = dir.join(&name);
        if !is_finished(&path)? {
            reports.push(recover_file(&path)?);
        }
    }
    Ok(reports)
}

/// Has `path` a footer and end magic at its end? (Reads only the last bytes.)
pub fn is_finished(path: &Path) -> Result<bool> {
    use std::io::{Read, Seek, SeekFrom};
    // Footer record: opcode, length (8), summary start (8), summary offset start (8), crc (4);
    // then the 8-byte magic.
    const TAIL: u64 = 1 + 8 + 20 + 8;
    let mut file = File::open(path).map_err(io_err(path, "open"))?;
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

/// Rewrites one file from its complete records (whether or not it was finished).
pub fn recover_file(path: &Path) -> Result<RecoveryReport> {
    let original_bytes = std::fs::metadata(path).map_err(io_err(path, "stat"))?.len();
    let mut temp_name = path.as_os_str().to_owned();
    temp_name.push(TEMP_SUFFIX);
    let temp = PathBuf::from(temp_name);
    let werr = |source| McapLogError::Write {
        path: temp.clone(),
        source,
    };

    let mut scanner = Scanner::open(path)?;
    let file = File::create(&temp).map_err(io_err(&temp, "create"))?;
    let mut writer = WriteOptions::new()
        .profile("")
        .library(concat!("bearingd ", env!("CARGO_PKG_VERSION"), " recovery"))
        .compression(Some(Compression::Zstd))
        .create(BufWriter::new(file))
        .map_err(werr)?;
    let mut schema_ids: HashMap<u16, u16> = HashMap::new();
    let mut channel_ids: HashMap<u16, u16> = HashMap::new();
    let mut messages = 0u64;
    let mut orphans = 0u64;
    while let Some(record) = scanner.next_record()? {
        match record {
            ScannedRecord::Schema {
                id,
                name,
                encoding,
                data,
            } => {
                let new = writer.add_schema(&name, &encoding, &data).map_err(werr)?;
                schema_ids.insert(id, new);
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
                }
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
                    orphans += 1;
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
                messages += 1;
            }
        }
    }
    writer.finish().map_err(werr)?;
    let file = writer
        .into_inner()
        .into_inner()
        .map_err(|e| io_err(&temp, "flush")(e.into_error()))?;
    file.sync_all().map_err(io_err(&temp, "fsync"))?;
    drop(file);
    std::fs::rename(&temp, path).map_err(io_err(path, "rename recovered file over"))?;
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        // Make the rename durable; a directory that cannot be opened for fsync is not fatal.
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    let outcome = scanner.outcome();
    let mut problem = outcome.first_problem.clone();
    if orphans > 0 && problem.is_none() {
        problem = Some((
            0,
            format!("{orphans} messages on channels without a record"),
        ));
    }
    Ok(RecoveryReport {
        path: path.to_path_buf(),
        messages_recovered: messages,
        unreadable_bytes: outcome.unreadable_bytes,
        original_bytes,
        problem,
    })
}
