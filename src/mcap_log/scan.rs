//! A bounded, chunk-at-a-time scanner of an MCAP file that survives any input.
//!
//! Why not the `mcap` crate's readers alone: a replay or a recovery needs to know *where*
//! reading stopped and how many bytes were lost, to read a file that is still truncated, and to
//! hold at most one chunk in memory. So this walks the top-level records itself (opcode, length,
//! body: the MCAP framing), checks every length against what is left of the file and a hard
//! limit before allocating ([`super::bounds`]), decompresses each chunk itself with the output
//! bounded by the declared size, checks the chunk's CRC, and only then parses the records in it
//! with [`super::bounds::parse_record`], which checks every length inside a record first. (The
//! crate's `ChunkReader` trusts inner record lengths before the CRC is checked, and its record
//! parser reserves a string's declared length, up to 4 GiB, before reading it.) A chunk is
//! taken whole or not at all.
//!
//! A chunk that fails (bad CRC, bad compression) but whose framing is intact is skipped and
//! counted; a record whose framing is broken (a length past the end of the file: the open chunk
//! of a writer killed with `kill -9`) ends the scan, and everything from there is unread.

use std::collections::{BTreeMap, VecDeque};
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use mcap::records::Record;

pub use super::bounds::MAX_RECORD_BYTES;
use super::bounds::{parse_record, record_length_limit};
use super::error::{io_err, McapLogError, Result};

const OP_DATA_END: u8 = 0x0F;
const OP_FOOTER: u8 = 0x02;
const OP_SCHEMA: u8 = 0x03;
const OP_CHANNEL: u8 = 0x04;
const OP_MESSAGE: u8 = 0x05;
const OP_CHUNK: u8 = 0x06;
const OP_METADATA: u8 = 0x0C;

/// A schema, channel or message read from a file, owned.
#[derive(Debug, Clone)]
pub enum ScannedRecord {
    Schema {
        id: u16,
        name: String,
        encoding: String,
        data: Vec<u8>,
    },
    Channel {
        id: u16,
        schema_id: u16,
        topic: String,
        message_encoding: String,
        metadata: BTreeMap<String, String>,
    },
    /// A metadata record (top level, between chunks).
    Metadata {
        name: String,
        metadata: BTreeMap<String, String>,
    },
    Message {
        channel_id: u16,
        sequence: u32,
        log_time: u64,
        publish_time: u64,
        data: Vec<u8>,
        /// Byte offset in the file of the top-level record (chunk) that held it.
        offset: u64,
    },
}

/// How a scan of one file ended.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ScanOutcome {
    /// The file has a footer followed by the end magic, and nothing after it.
    pub finished: bool,
    /// Bytes of the file that no record could be read from (skipped chunks and the tail).
    pub unreadable_bytes: u64,
    /// Chunks skipped because they did not decode (framing intact).
    pub chunks_skipped: u64,
    /// Where and why reading stopped early or skipped, first occurrence.
    pub first_problem: Option<(u64, String)>,
}

/// Reads one file record by record; see the module docs.
pub struct Scanner {
    path: PathBuf,
    reader: BufReader<File>,
    file_len: u64,
    offset: u64,
    pending: VecDeque<ScannedRecord>,
    in_summary: bool,
    done: bool,
    outcome: ScanOutcome,
}

impl Scanner {
    /// Opens `path` and checks the start magic. A file too short for it, or with other bytes,
    /// scans as wholly unreadable (no error: the caller reports it).
    pub fn open(path: &Path) -> Result<Self> {
        let file = File::open(path).map_err(io_err(path, "open"))?;
        let file_len = file.metadata().map_err(io_err(path, "stat"))?.len();
        let mut scanner = Scanner {
            path: path.to_path_buf(),
            reader: BufReader::with_capacity(64 * 1024, file),
            file_len,
            offset: 0,
            pending: VecDeque::new(),
            in_summary: false,
            done: false,
            outcome: ScanOutcome::default(),
        };
        let mut magic = [0u8; 8];
        match scanner.read_exact_or_eof(&mut magic) {
            Ok(true) if magic == mcap::MAGIC => scanner.offset = 8,
            Ok(_) => scanner.stop(0, "no MCAP start magic"),
            Err(e) => return Err(e),
        }
        Ok(scanner)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The file's size when it was opened.
    pub fn file_len(&self) -> u64 {
        self.file_len
    }

    /// Bytes read so far (the end of the last top-level record).
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// The outcome so far (final once [`Scanner::next_record`] returned `Ok(None)`).
    pub fn outcome(&self) -> &ScanOutcome {
        &self.outcome
    }

    fn stop(&mut self, offset: u64, reason: impl Into<String>) {
        self.done = true;
        self.outcome.unreadable_bytes += self.file_len.saturating_sub(offset);
        if self.outcome.first_problem.is_none() {
            self.outcome.first_problem = Some((offset, reason.into()));
        }
    }

    /// Fills `buf`; `Ok(false)` if the file ended first.
    fn read_exact_or_eof(&mut self, buf: &mut [u8]) -> Result<bool> {
        let mut filled = 0;
        while filled < buf.len() {
            match self.reader.read(&mut buf[filled..]) {
                Ok(0) => return Ok(false),
                Ok(n) => filled += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(io_err(&self.path, "read")(e)),
            }
        }
        Ok(true)
    }

    /// The next schema, channel or message of the data section; `Ok(None)` at the end of what
    /// can be read. I/O errors are returned; malformed content never is (it ends or skips, and
    /// is counted in [`Scanner::outcome`]).
    pub fn next_record(&mut self) -> Result<Option<ScannedRecord>> {
        loop {
            if let Some(record) = self.pending.pop_front() {
                return Ok(Some(record));
            }
            if self.done {
                return Ok(None);
            }
            self.read_top_level()?;
        }
    }

    fn read_top_level(&mut self) -> Result<()> {
        let start = self.offset;
        let mut head = [0u8; 9];
        if !self.read_exact_or_eof(&mut head)? {
            if start == self.file_len {
                // Clean end of the bytes, but without a footer: an unfinished file.
                self.done = true;
                if self.outcome.first_problem.is_none() {
                    self.outcome.first_problem =
                        Some((start, "no footer (unfinished file)".into()));
                }
            } else {
                self.stop(start, "record header cut off (truncated file)");
            }
            return Ok(());
        }
        let opcode = head[0];
        let mut len_bytes = [0u8; 8];
        len_bytes.copy_from_slice(&head[1..]);
        let len = u64::from_le_bytes(len_bytes);
        let remaining = self.file_len.saturating_sub(start + 9);
        if len > record_length_limit(remaining) {
            let why = if len > remaining {
                format!("record (opcode {opcode:#04x}) of {len} bytes runs past the end of the file ({remaining} bytes left): truncated")
            } else {
                format!("record of {len} bytes exceeds the {MAX_RECORD_BYTES}-byte limit")
            };
            self.stop(start, why);
            return Ok(());
        }
        let mut body = vec![0u8; len as usize];
        if !self.read_exact_or_eof(&mut body)? {
            self.stop(start, "file shrank while reading");
            return Ok(());
        }
        self.offset = start + 9 + len;

        if opcode == OP_FOOTER {
            let mut magic = [0u8; 8];
            let has_magic = self.read_exact_or_eof(&mut magic)? && magic == mcap::MAGIC;
            let end = self.offset + 8;
            if has_magic && end == self.file_len {
                self.outcome.finished = true;
                self.done = true;
            } else if has_magic {
                self.stop(end, "bytes after the end magic");
            } else {
                self.stop(self.offset, "no end magic after the footer");
            }
            return Ok(());
        }
        if opcode == OP_DATA_END {
            // Summary records repeat the data section's schemas and channels: skip them.
            self.in_summary = true;
            return Ok(());
        }
        if self.in_summary {
            return Ok(());
        }
        match opcode {
            OP_CHUNK => match decode_chunk(&body) {
                Ok(records) => {
                    for (op, rec) in records {
                        match own(op, &rec, start) {
                            Ok(Some(r)) => self.pending.push_back(r),
                            Ok(None) => {}
                            Err(e) => {
                                self.pending.clear();
                                self.skip_chunk(start, len, &e);
                                return Ok(());
                            }
                        }
                    }
                }
                Err(reason) => self.skip_chunk(start, len, &reason),
            },
            OP_SCHEMA | OP_CHANNEL | OP_MESSAGE | OP_METADATA => match own(opcode, &body, start) {
                Ok(Some(r)) => self.pending.push_back(r),
                Ok(None) => {}
                Err(e) => {
                    // Framing held (the length fit) but the body is not a valid record: skip it.
                    self.outcome.unreadable_bytes += 9 + len;
                    if self.outcome.first_problem.is_none() {
                        self.outcome.first_problem = Some((start, e));
                    }
                }
            },
            // Indexes, statistics, attachments: not needed to read messages in order.
            _ => {}
        }
        Ok(())
    }

    fn skip_chunk(&mut self, start: u64, len: u64, reason: &str) {
        self.outcome.unreadable_bytes += 9 + len;
        self.outcome.chunks_skipped += 1;
        if self.outcome.first_problem.is_none() {
            self.outcome.first_problem = Some((start, reason.to_string()));
        }
    }
}

/// Parses one schema, channel or message record body; other opcodes give `Ok(None)`.
fn own(opcode: u8, body: &[u8], offset: u64) -> std::result::Result<Option<ScannedRecord>, String> {
    if !matches!(opcode, OP_SCHEMA | OP_CHANNEL | OP_MESSAGE | OP_METADATA) {
        return Ok(None);
    }
    let record = parse_record(opcode, body)?;
    Ok(match record {
        Record::Schema { header, data } => Some(ScannedRecord::Schema {
            id: header.id,
            name: header.name,
            encoding: header.encoding,
            data: data.into_owned(),
        }),
        Record::Channel(c) => Some(ScannedRecord::Channel {
            id: c.id,
            schema_id: c.schema_id,
            topic: c.topic,
            message_encoding: c.message_encoding,
            metadata: c.metadata,
        }),
        Record::Metadata(m) => Some(ScannedRecord::Metadata {
            name: m.name,
            metadata: m.metadata,
        }),
        Record::Message { header, data } => Some(ScannedRecord::Message {
            channel_id: header.channel_id,
            sequence: header.sequence,
            log_time: header.log_time,
            publish_time: header.publish_time,
            data: data.into_owned(),
            offset,
        }),
        _ => None,
    })
}

fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(
        b.get(at..at.checked_add(4)?)?.try_into().ok()?,
    ))
}

fn le_u64(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(
        b.get(at..at.checked_add(8)?)?.try_into().ok()?,
    ))
}

/// Decompresses a chunk record's body, checks its CRC and splits it into (opcode, body)
/// records, all before anything is released: a chunk is taken whole or not at all. Every
/// length is checked against the bytes at hand; the output never grows past the declared
/// uncompressed size (itself at most [`MAX_RECORD_BYTES`]).
///
/// Layout (MCAP spec): message_start_time u64, message_end_time u64, uncompressed_size u64,
/// uncompressed_crc u32, compression (u32 length + bytes), compressed_size u64, records.
fn decode_chunk(body: &[u8]) -> std::result::Result<Vec<(u8, Vec<u8>)>, String> {
    let bad = |what: &str| format!("chunk: {what}");
    let uncompressed_size = le_u64(body, 16).ok_or_else(|| bad("header cut off"))?;
    let crc = le_u32(body, 24).ok_or_else(|| bad("header cut off"))?;
    let name_len = le_u32(body, 28).ok_or_else(|| bad("header cut off"))? as usize;
    let name_end = 32usize
        .checked_add(name_len)
        .ok_or_else(|| bad("compression name length"))?;
    let name = body
        .get(32..name_end)
        .ok_or_else(|| bad("compression name runs past the record"))?;
    let compressed_size = le_u64(body, name_end).ok_or_else(|| bad("header cut off"))?;
    let data_start = name_end + 8;
    let available = (body.len() - data_start.min(body.len())) as u64;
    if compressed_size > available {
        return Err(bad(&format!(
            "compressed size {compressed_size} > {available} bytes in the record"
        )));
    }
    if uncompressed_size > MAX_RECORD_BYTES {
        return Err(bad(&format!(
            "uncompressed size {uncompressed_size} over the limit"
        )));
    }
    let data = &body[data_start..data_start + compressed_size as usize];
    let limit = uncompressed_size + 1;
    let mut out = Vec::new();
    match name {
        b"" => out.extend_from_slice(data),
        b"zstd" => {
            let decoder =
                zstd::stream::read::Decoder::new(data).map_err(|e| bad(&format!("zstd: {e}")))?;
            decoder
                .take(limit)
                .read_to_end(&mut out)
                .map_err(|e| bad(&format!("zstd: {e}")))?;
        }
        b"lz4" => {
            let decoder = lz4::Decoder::new(data).map_err(|e| bad(&format!("lz4: {e}")))?;
            decoder
                .take(limit)
                .read_to_end(&mut out)
                .map_err(|e| bad(&format!("lz4: {e}")))?;
        }
        other => {
            return Err(bad(&format!(
                "unsupported compression {:?}",
                String::from_utf8_lossy(other)
            )))
        }
    }
    if out.len() as u64 != uncompressed_size {
        return Err(bad(&format!(
            "{} bytes decompressed, {uncompressed_size} declared",
            out.len()
        )));
    }
    if crc != 0 && crc32fast::hash(&out) != crc {
        return Err(bad("CRC mismatch"));
    }
    let mut records = Vec::new();
    let mut at = 0usize;
    while at < out.len() {
        let op = out[at];
        let len =
            le_u64(&out, at + 1).ok_or_else(|| bad("record header cut off inside the chunk"))?;
        let start = at + 9;
        if len > (out.len() - start) as u64 {
            return Err(bad("record runs past the end of the chunk"));
        }
        let end = start + len as usize;
        if matches!(op, OP_SCHEMA | OP_CHANNEL | OP_MESSAGE) {
            records.push((op, out[start..end].to_vec()));
        }
        at = end;
    }
    Ok(records)
}

/// Error for a file that could not be scanned at all (used by callers that need one).
pub fn corrupt(path: &Path, offset: u64, reason: impl Into<String>) -> McapLogError {
    McapLogError::Corrupt {
        path: path.to_path_buf(),
        offset,
        reason: reason.into(),
    }
}
