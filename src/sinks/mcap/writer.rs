//! [`McapLogger`]: the daemon's MCAP sink.
//!
//! Blocking by design (file I/O and zstd): the daemon runs it on its own thread behind a bounded
//! queue. One file at a time is open; it is chunked and zstd-compressed, and the daemon calls
//! [`McapLogger::flush`] periodically (about every second of data) so that a crash loses at
//! most the open chunk. Files rotate by size and by log-time duration; each is finished cleanly
//! (summary and indexes, so strict readers open it); after each rotation the oldest finished
//! files are deleted until the directory fits the disk budget.
//!
//! Time: the logger never reads a clock. The caller passes the opening time and every
//! message's `log_time`/`publish_time` (nanoseconds since the Unix epoch; the daemon maps sample
//! time to wall time), so that tests stay deterministic.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{self, BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions};

use crate::fsafe::{check_own_regular, NotOwnFile};
use crate::mcap_log::error::{io_err, McapLogError, Result};
use crate::mcap_log::files::{file_name, is_log_file_name};
use crate::mcap_log::schema::{self, encode, JsonKind, RAW_BLOCK_SCHEMA};
use crate::messages::PipelineMessage;

/// Where and how to log.
#[derive(Debug, Clone, PartialEq)]
pub struct LoggerConfig {
    /// Directory of the log files (created if missing).
    pub dir: PathBuf,
    /// Target uncompressed chunk size in bytes: a chunk is closed when it grows past this (and at
    /// every [`McapLogger::flush`]).
    pub chunk_size: u64,
    /// Rotate once the open file reaches this many bytes (checked before each message, so a file
    /// overshoots by at most one message plus the compressor's pending output).
    pub max_file_bytes: u64,
    /// Rotate once a message's log time is this far past the file's first message.
    pub max_file_duration_ns: u64,
    /// Total bytes of `bearingd-*.mcap` files the directory may hold; the oldest finished files
    /// are deleted after each rotation to stay within it. The open file is never deleted.
    pub disk_budget_bytes: u64,
    /// zstd level (1..=19); 3 is zstd's default and keeps up easily on an edge CPU.
    pub zstd_level: u32,
    /// MCAP metadata records written at the start of every file (what makes a file
    /// self-describing: see [`super::metadata`]); each file also gets a `bearingd.file` record
    /// with its sequence number in the run.
    pub metadata: Vec<(String, BTreeMap<String, String>)>,
    /// Log time between two forced writes of the open file to the disk (fsync), for the owner
    /// to schedule [`McapLogger::sync`]; `None`: never forced (the OS writes back when it
    /// will), as in tests and tools.
    pub fsync_every_ns: Option<u64>,
}

impl LoggerConfig {
    /// Defaults for a directory: 4 MiB chunks, 256 MiB or 1 h files, 4 GiB budget (the
    /// config's default `mcap_disk_budget_mb = 4096`), zstd 3, no metadata.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        LoggerConfig {
            dir: dir.into(),
            chunk_size: 4 * 1024 * 1024,
            max_file_bytes: 256 * 1024 * 1024,
            max_file_duration_ns: 3600 * 1_000_000_000,
            disk_budget_bytes: 4 * 1024 * 1024 * 1024,
            zstd_level: 3,
            metadata: Vec::new(),
            fsync_every_ns: None,
        }
    }

    fn check(&self) -> Result<()> {
        let mut problems = Vec::new();
        if self.chunk_size == 0 {
            problems.push("chunk_size must be > 0");
        }
        if self.max_file_bytes == 0 {
            problems.push("max_file_bytes must be > 0");
        }
        if self.max_file_duration_ns == 0 {
            problems.push("max_file_duration_ns must be > 0");
        }
        if self.disk_budget_bytes < self.max_file_bytes {
            problems.push("disk_budget_bytes must be at least max_file_bytes");
        }
        if !(1..=19).contains(&self.zstd_level) {
            problems.push("zstd_level must be within 1..=19");
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(McapLogError::Config(problems.join("; ")))
        }
    }
}

/// What was written to one topic (payload bytes: before MCAP framing and compression).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TopicStats {
    pub messages: u64,
    pub payload_bytes: u64,
}

/// Counters of a logger's life.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LogStats {
    pub topics: BTreeMap<String, TopicStats>,
    pub files_opened: u64,
    pub files_finished: u64,
    /// Bytes of the files this logger finished (final sizes).
    pub finished_file_bytes: u64,
    pub flushes: u64,
    /// Times the open file was forced to the disk ([`McapLogger::sync`]).
    pub syncs: u64,
    pub files_deleted: u64,
    pub bytes_deleted: u64,
}

impl LogStats {
    pub fn messages(&self) -> u64 {
        self.topics.values().map(|t| t.messages).sum()
    }
    pub fn payload_bytes(&self) -> u64 {
        self.topics.values().map(|t| t.payload_bytes).sum()
    }
}

/// What one retention pass did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RetentionReport {
    pub deleted: Vec<PathBuf>,
    pub bytes_deleted: u64,
    /// Bytes of `bearingd-*.mcap` files left in the directory, the open file included.
    pub total_bytes_after: u64,
    /// Log-named entries that are not this user's regular files (a link, a directory, another
    /// user's file): neither counted nor deleted.
    pub skipped: Vec<NotOwnFile>,
}

/// Tracks the logical position and length of a seekable stream, so the open file's size is
/// known without a syscall per message. `mcap::Writer` does not lend out its stream, so the
/// length is shared through an atomic (the logger may move between threads).
///
/// After the first failed write (a full disk) it refuses every later write, so that the file
/// stays a prefix of what the writer produced (what recovery reads) and the `mcap` writer's
/// drop, which tries to finish the file, adds nothing after a hole.
struct Counting<W> {
    inner: W,
    pos: u64,
    len: Arc<AtomicU64>,
    failed: bool,
}

impl<W> Counting<W> {
    fn note(&self) {
        self.len.fetch_max(self.pos, Ordering::Relaxed);
    }
}

impl<W: Write> Write for Counting<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.failed {
            return Err(io::Error::other("an earlier write to this file failed"));
        }
        let n = self.inner.write(buf).inspect_err(|_| self.failed = true)?;
        self.pos += n as u64;
        self.note();
        Ok(n)
    }
    fn flush(&mut self) -> io::Result<()> {
        if self.failed {
            return Err(io::Error::other("an earlier write to this file failed"));
        }
        self.inner.flush().inspect_err(|_| self.failed = true)
    }
}

impl<W: Seek> Seek for Counting<W> {
    fn seek(&mut self, pos: SeekFrom) -> io::Result<u64> {
        if self.failed {
            return Err(io::Error::other("an earlier write to this file failed"));
        }
        self.pos = self.inner.seek(pos).inspect_err(|_| self.failed = true)?;
        self.note();
        Ok(self.pos)
    }
}

type FileWriter = mcap::Writer<Counting<BufWriter<File>>>;

struct OpenFile {
    path: PathBuf,
    writer: FileWriter,
    /// A second handle on the same file, for fsync: the writer owns the first.
    disk: File,
    len: Arc<AtomicU64>,
    first_log_time: Option<u64>,
    /// topic → (channel id, next sequence)
    channels: HashMap<String, (u16, u32)>,
    raw_schema: Option<u16>,
    json_schemas: HashMap<JsonKind, u16>,
    /// `/log` and `/state`: (channel id, next sequence), on first use.
    side_channels: HashMap<Side, (u16, u32)>,
}

/// The channels beside the pipeline's topics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Side {
    Log,
    State,
}

impl OpenFile {
    fn bytes(&self) -> u64 {
        self.len.load(Ordering::Relaxed)
    }

    fn create(
        dir: &Path,
        opened_at_ns: u64,
        seq: &mut u32,
        file_in_run: u64,
        config: &LoggerConfig,
    ) -> Result<Self> {
        // Never overwrite: a restart within the same second reuses a name, so bump the sequence.
        let mut tries = 0;
        let (path, file) = loop {
            let path = dir.join(file_name(opened_at_ns, *seq));
            *seq = seq.wrapping_add(1);
            match crate::fsafe::create_new(&path) {
                Ok(f) => break (path, f),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && tries < 10_000 => tries += 1,
                Err(e) => return Err(io_err(&path, "create")(e)),
            }
        };
        // The new name must survive a power cut as well as the data written under it.
        super::recover::sync_parent(&path);
        let disk = file
            .try_clone()
            .map_err(io_err(&path, "open a second handle"))?;
        let len = Arc::new(AtomicU64::new(0));
        let stream = Counting {
            inner: BufWriter::with_capacity(256 * 1024, file),
            pos: 0,
            len: Arc::clone(&len),
            failed: false,
        };
        let werr = |source| McapLogError::Write {
            path: path.clone(),
            source,
        };
        let mut writer = WriteOptions::new()
            .profile("")
            .library(concat!("bearingd ", env!("CARGO_PKG_VERSION")))
            .compression(Some(Compression::Zstd))
            .compression_level(config.zstd_level)
            // Single-threaded zstd on the sink thread: the crate's default (one worker per
            // physical CPU) allocated about 50 MB of compression context for a few hundred
            // kB/s of log and competed with the analysis thread for the cores (issue 12).
            .compression_threads(0)
            .chunk_size(Some(config.chunk_size))
            .create(stream)
            .map_err(werr)?;
        let file_record = super::metadata::file_record(file_in_run, opened_at_ns);
        for (name, metadata) in config.metadata.iter().chain(std::iter::once(&file_record)) {
            writer
                .write_metadata(&mcap::records::Metadata {
                    name: name.clone(),
                    metadata: metadata.clone(),
                })
                .map_err(werr)?;
        }
        Ok(OpenFile {
            path,
            writer,
            disk,
            len,
            first_log_time: None,
            channels: HashMap::new(),
            raw_schema: None,
            json_schemas: HashMap::new(),
            side_channels: HashMap::new(),
        })
    }

    /// A channel beside the pipeline's (`/log`, `/state`), registered with its JSON schema on
    /// first use.
    fn side_channel(&mut self, side: Side) -> Result<&mut (u16, u32)> {
        if !self.side_channels.contains_key(&side) {
            let werr = |source| McapLogError::Write {
                path: self.path.clone(),
                source,
            };
            let (topic, name, schema) = match side {
                Side::Log => (
                    schema::LOG_TOPIC,
                    schema::LOG_SCHEMA,
                    schema::log_json_schema(),
                ),
                Side::State => (
                    schema::STATE_TOPIC,
                    schema::STATE_SCHEMA,
                    schema::StateSnapshot::json_schema(),
                ),
            };
            let data = schema.to_string();
            let schema_id = self
                .writer
                .add_schema(name, "jsonschema", data.as_bytes())
                .map_err(werr)?;
            let id = self
                .writer
                .add_channel(schema_id, topic, "json", &BTreeMap::new())
                .map_err(werr)?;
            self.side_channels.insert(side, (id, 0));
        }
        self.side_channels
            .get_mut(&side)
            .ok_or_else(|| McapLogError::Config("a side channel vanished".into()))
    }

    /// Writes `payload` on a side channel at `log_time_ns`.
    fn write_side(&mut self, side: Side, payload: &[u8], log_time_ns: u64) -> Result<()> {
        let entry = self.side_channel(side)?;
        let header = MessageHeader {
            channel_id: entry.0,
            sequence: entry.1,
            log_time: log_time_ns,
            publish_time: log_time_ns,
        };
        entry.1 = entry.1.wrapping_add(1);
        self.writer
            .write_to_known_channel(&header, payload)
            .map_err(|source| McapLogError::Write {
                path: self.path.clone(),
                source,
            })?;
        self.first_log_time.get_or_insert(log_time_ns);
        Ok(())
    }

    /// Writes the summary, flushes and fsyncs; returns the final size.
    fn finish(mut self) -> Result<u64> {
        let path = self.path.clone();
        self.writer.finish().map_err(|source| McapLogError::Write {
            path: path.clone(),
            source,
        })?;
        let counting = self.writer.into_inner();
        let file = counting
            .inner
            .into_inner()
            .map_err(|e| io_err(&path, "flush")(e.into_error()))?;
        file.sync_all().map_err(io_err(&path, "fsync"))?;
        Ok(self.len.load(Ordering::Relaxed))
    }

    /// The channel of `topic`, registering its schema and channel on first use.
    fn channel(&mut self, topic: &str, kind: Option<JsonKind>) -> Result<&mut (u16, u32)> {
        if !self.channels.contains_key(topic) {
            let werr = |path: &Path| {
                let path = path.to_path_buf();
                move |source| McapLogError::Write { path, source }
            };
            let (schema_id, encoding) = match kind {
                None => {
                    let id = match self.raw_schema {
                        Some(id) => id,
                        None => {
                            let id = self
                                .writer
                                .add_schema(
                                    RAW_BLOCK_SCHEMA,
                                    "protobuf",
                                    &schema::raw_block_descriptor_set(),
                                )
                                .map_err(werr(&self.path))?;
                            self.raw_schema = Some(id);
                            id
                        }
                    };
                    (id, "protobuf")
                }
                Some(kind) => {
                    let id = match self.json_schemas.get(&kind) {
                        Some(&id) => id,
                        None => {
                            let data = kind.json_schema().to_string();
                            let id = self
                                .writer
                                .add_schema(kind.schema_name(), "jsonschema", data.as_bytes())
                                .map_err(werr(&self.path))?;
                            self.json_schemas.insert(kind, id);
                            id
                        }
                    };
                    (id, "json")
                }
            };
            let id = self
                .writer
                .add_channel(schema_id, topic, encoding, &BTreeMap::new())
                .map_err(werr(&self.path))?;
            self.channels.insert(topic.to_string(), (id, 0));
        }
        // Present: inserted above if it was missing.
        self.channels
            .get_mut(topic)
            .ok_or_else(|| McapLogError::Config(format!("channel {topic} vanished")))
    }
}

/// The MCAP log sink. See the module docs.
pub struct McapLogger {
    config: LoggerConfig,
    open: Option<OpenFile>,
    seq: u32,
    stats: LogStats,
    topic: String,
    payload: Vec<u8>,
    /// What the retention pass at creation deleted, until the owner takes it.
    startup_retention: Option<RetentionReport>,
    /// A file whose finishing failed in a rotation (a full disk), until [`Self::abandon`].
    unfinished: Option<PathBuf>,
}

impl McapLogger {
    /// Creates the directory if needed, applies the disk budget to what is already there and
    /// opens the first file, named after `opened_at_ns` (ns since the Unix epoch, UTC).
    ///
    /// Run [`super::recover_directory`] before this at start-up: an unfinished file from a
    /// crash is recovered there, not here.
    pub fn create(config: LoggerConfig, opened_at_ns: u64) -> Result<Self> {
        config.check()?;
        crate::fsafe::create_dir_all(&config.dir)
            .map_err(io_err(&config.dir, "create directory"))?;
        super::recover::sync_parent(&config.dir);
        let mut logger = McapLogger {
            config,
            open: None,
            seq: 0,
            stats: LogStats::default(),
            topic: String::with_capacity(64),
            payload: Vec::with_capacity(64 * 1024),
            startup_retention: None,
            unfinished: None,
        };
        logger.open_file(opened_at_ns)?;
        logger.startup_retention = Some(logger.apply_retention()?);
        Ok(logger)
    }

    fn open_file(&mut self, opened_at_ns: u64) -> Result<()> {
        let file = OpenFile::create(
            &self.config.dir,
            opened_at_ns,
            &mut self.seq,
            self.stats.files_opened + 1,
            &self.config,
        )?;
        self.open = Some(file);
        self.stats.files_opened += 1;
        Ok(())
    }

    /// What the retention pass at creation did (once; `None` afterwards).
    pub fn take_startup_retention(&mut self) -> Option<RetentionReport> {
        self.startup_retention.take()
    }

    /// The file being written.
    pub fn current_path(&self) -> Option<&Path> {
        self.open.as_ref().map(|f| f.path.as_path())
    }

    /// Bytes of the open file so far (what has left the compressor).
    pub fn current_file_bytes(&self) -> u64 {
        self.open.as_ref().map_or(0, OpenFile::bytes)
    }

    pub fn stats(&self) -> &LogStats {
        &self.stats
    }

    pub fn config(&self) -> &LoggerConfig {
        &self.config
    }

    /// Whether a message logged at `log_time_ns` would rotate the open file first (it is full
    /// or spans `max_file_duration_ns`), so that a caller can rotate itself and begin the next
    /// file with what it must start with.
    pub fn needs_rotation(&self, log_time_ns: u64) -> bool {
        self.open.as_ref().is_some_and(|f| {
            f.bytes() >= self.config.max_file_bytes
                || f.first_log_time.is_some_and(|t0| {
                    log_time_ns.saturating_sub(t0) >= self.config.max_file_duration_ns
                })
        })
    }

    /// Log time of the open file's first message (its start), if it has one.
    pub fn current_file_start(&self) -> Option<u64> {
        self.open.as_ref().and_then(|f| f.first_log_time)
    }

    /// Writes an operator note on the `/log` topic (Foxglove's `foxglove.Log`, JSON) of the
    /// open file: what the daemon did to the logs (retention, a pause for a full disk), kept
    /// in the log itself and not only in the journal.
    pub fn note(&mut self, level: schema::LogLevel, text: &str, log_time_ns: u64) -> Result<()> {
        let payload = schema::log_note(level, text, log_time_ns);
        self.open_mut()?
            .write_side(Side::Log, &payload, log_time_ns)
    }

    /// Writes the state snapshot on `/state` ([`schema::StateSnapshot`]) of the open file.
    pub fn write_state(
        &mut self,
        snapshot: &schema::StateSnapshot,
        log_time_ns: u64,
    ) -> Result<()> {
        let payload = serde_json::to_vec(snapshot)
            .map_err(|e| McapLogError::Config(format!("state snapshot: {e}")))?;
        self.open_mut()?
            .write_side(Side::State, &payload, log_time_ns)
    }

    fn open_mut(&mut self) -> Result<&mut OpenFile> {
        self.open
            .as_mut()
            .ok_or_else(|| McapLogError::Config("no open file".into()))
    }

    /// Gives up the open file after a write failed (a full disk): nothing more is written to
    /// it, it is left unfinished (a prefix of what was written, which
    /// [`super::recover_file`] makes whole) and its path returned. [`Self::log`] then opens
    /// the next file; [`Self::reopen`] does so explicitly.
    pub fn abandon(&mut self) -> Option<PathBuf> {
        if let Some(path) = self.unfinished.take() {
            return Some(path);
        }
        self.open.take().map(|file| {
            let path = file.path.clone();
            // Its stream refuses writes after the failure, so the writer's drop (which tries
            // to finish the file) writes nothing.
            drop(file);
            path
        })
    }

    /// Opens a new file named after `opened_at_ns` if none is open (after [`Self::abandon`]).
    pub fn reopen(&mut self, opened_at_ns: u64) -> Result<()> {
        if self.open.is_none() {
            self.open_file(opened_at_ns)?;
        }
        Ok(())
    }

    /// Logs one pipeline message on its topic. `log_time_ns`/`publish_time_ns` are wall time in
    /// ns since the epoch, mapped from sample time by the caller. Rotates first if the open file
    /// is full or spans `max_file_duration_ns`; the new file is named after `log_time_ns`.
    /// Returns the retention report of that rotation, if one happened.
    pub fn log(
        &mut self,
        message: &PipelineMessage,
        log_time_ns: u64,
        publish_time_ns: u64,
    ) -> Result<Option<RetentionReport>> {
        self.log_encoded(message, log_time_ns, publish_time_ns, encode)
    }

    /// [`log`](Self::log) for a flag change or health event decided while logging was paused
    /// and written when it resumed: `log_time_ns` is the resume, `publish_time_ns` the
    /// decision, and the message carries `"late": true` ([`schema::encode_late`]).
    pub fn log_late(
        &mut self,
        message: &PipelineMessage,
        log_time_ns: u64,
        decided_ns: u64,
    ) -> Result<Option<RetentionReport>> {
        self.log_encoded(message, log_time_ns, decided_ns, schema::encode_late)
    }

    fn log_encoded(
        &mut self,
        message: &PipelineMessage,
        log_time_ns: u64,
        publish_time_ns: u64,
        encoder: fn(&PipelineMessage, &mut String, &mut Vec<u8>) -> Option<JsonKind>,
    ) -> Result<Option<RetentionReport>> {
        let rotation = match &self.open {
            Some(f) => {
                let too_big = f.bytes() >= self.config.max_file_bytes;
                let too_long = f.first_log_time.is_some_and(|t0| {
                    log_time_ns.saturating_sub(t0) >= self.config.max_file_duration_ns
                });
                if too_big || too_long {
                    Some(self.rotate(log_time_ns)?)
                } else {
                    None
                }
            }
            None => {
                self.open_file(log_time_ns)?;
                None
            }
        };

        self.topic.clear();
        let kind = encoder(message, &mut self.topic, &mut self.payload);
        let Some(file) = self.open.as_mut() else {
            return Err(McapLogError::Config("no open file".into()));
        };
        let entry = file.channel(&self.topic, kind)?;
        let header = MessageHeader {
            channel_id: entry.0,
            sequence: entry.1,
            log_time: log_time_ns,
            publish_time: publish_time_ns,
        };
        entry.1 = entry.1.wrapping_add(1);
        file.writer
            .write_to_known_channel(&header, &self.payload)
            .map_err(|source| McapLogError::Write {
                path: file.path.clone(),
                source,
            })?;
        file.first_log_time.get_or_insert(log_time_ns);
        let bytes = self.payload.len() as u64;
        match self.stats.topics.get_mut(&self.topic) {
            Some(s) => {
                s.messages += 1;
                s.payload_bytes += bytes;
            }
            None => {
                let s = TopicStats {
                    messages: 1,
                    payload_bytes: bytes,
                };
                self.stats.topics.insert(self.topic.clone(), s);
            }
        }
        Ok(rotation)
    }

    /// [`flush`](Self::flush), then forces the open file to the disk (fsync of its data), which
    /// bounds what a power cut can lose as `flush` bounds what a process crash can.
    pub fn sync(&mut self) -> Result<()> {
        self.flush()?;
        if let Some(file) = self.open.as_mut() {
            file.disk.sync_data().map_err(io_err(&file.path, "fsync"))?;
            self.stats.syncs += 1;
        }
        Ok(())
    }

    /// Closes the open chunk and hands it to the OS, bounding what a crash can lose. (No fsync:
    /// a process crash loses nothing that was flushed; a power loss is the file system's call,
    /// bounded by [`sync`](Self::sync).)
    pub fn flush(&mut self) -> Result<()> {
        if let Some(file) = self.open.as_mut() {
            file.writer.flush().map_err(|source| McapLogError::Write {
                path: file.path.clone(),
                source,
            })?;
            self.stats.flushes += 1;
        }
        Ok(())
    }

    /// Finishes the open file, opens the next (named after `opened_at_ns`) and applies the disk
    /// budget.
    pub fn rotate(&mut self, opened_at_ns: u64) -> Result<RetentionReport> {
        if let Some(file) = self.open.take() {
            let path = file.path.clone();
            let bytes = file
                .finish()
                .inspect_err(|_| self.unfinished = Some(path))?;
            self.stats.files_finished += 1;
            self.stats.finished_file_bytes += bytes;
        }
        self.open_file(opened_at_ns)?;
        self.apply_retention()
    }

    /// Deletes the oldest finished `bearingd-*.mcap` files (by name: opening time, then
    /// sequence) until the directory's log files fit `disk_budget_bytes`. Never the open file.
    pub fn apply_retention(&mut self) -> Result<RetentionReport> {
        let open = self.open.as_ref().map(|f| f.path.clone());
        let report = enforce_budget(
            &self.config.dir,
            self.config.disk_budget_bytes,
            open.as_deref(),
        )?;
        self.stats.files_deleted += report.deleted.len() as u64;
        self.stats.bytes_deleted += report.bytes_deleted;
        Ok(report)
    }

    /// Finishes the open file (summary, index, fsync) and returns the counters.
    pub fn finish(mut self) -> Result<LogStats> {
        if let Some(file) = self.open.take() {
            let bytes = file.finish()?;
            self.stats.files_finished += 1;
            self.stats.finished_file_bytes += bytes;
        }
        Ok(std::mem::take(&mut self.stats))
    }
}

/// Retention over a directory: see [`McapLogger::apply_retention`].
pub fn enforce_budget(dir: &Path, budget: u64, open: Option<&Path>) -> Result<RetentionReport> {
    let mut files: Vec<(String, PathBuf, u64)> = Vec::new();
    let mut report = RetentionReport::default();
    let entries = std::fs::read_dir(dir).map_err(io_err(dir, "list directory"))?;
    for entry in entries {
        let entry = entry.map_err(io_err(dir, "list directory"))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if !is_log_file_name(&name) {
            continue;
        }
        let path = entry.path();
        // The entry's own metadata: a link is seen as a link, never followed.
        let len = match entry.metadata() {
            Ok(m) => match check_own_regular(&path, m) {
                Ok(m) => m.len(),
                Err(not_own) => {
                    report.skipped.push(not_own);
                    continue;
                }
            },
            // Deleted meanwhile (another pass): nothing to count.
            Err(e) if e.kind() == io::ErrorKind::NotFound => continue,
            Err(e) => return Err(io_err(&path, "stat")(e)),
        };
        files.push((name, path, len));
    }
    files.sort();
    let mut total: u64 = files.iter().map(|f| f.2).sum();
    for (_, path, len) in &files {
        if total <= budget {
            break;
        }
        if open == Some(path.as_path()) {
            continue;
        }
        match std::fs::remove_file(path) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(io_err(path, "delete")(e)),
        }
        total -= len;
        report.deleted.push(path.clone());
        report.bytes_deleted += len;
    }
    report.total_bytes_after = total;
    Ok(report)
}
