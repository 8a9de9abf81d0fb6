//! Reading the log back for replay: finished files, and unfinished or damaged ones up to what
//! can be read (see [`super::scan`]). Never panics on any input; memory is bounded by one
//! chunk. What could not be read is counted per file in [`ReadSummary`], not raised as an
//! error, so a replay of a crashed run goes as far as the data goes and says what it missed.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use prost::Message as _;

use super::error::{McapLogError, Result};
use super::scan::{ScanOutcome, ScannedRecord, Scanner};
use super::schema::{JsonKind, RawBlockPb, LOG_SCHEMA, RAW_BLOCK_SCHEMA, STATE_SCHEMA};
use crate::messages::{PipelineMessage, RawBlock};

/// One message read back, with its MCAP envelope.
#[derive(Debug, Clone, PartialEq)]
pub struct LoggedMessage {
    pub topic: String,
    pub sequence: u32,
    pub log_time: u64,
    pub publish_time: u64,
    pub message: PipelineMessage,
}

/// What reading one file gave.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FileReadReport {
    pub path: PathBuf,
    /// Messages decoded into pipeline types.
    pub messages: u64,
    /// Messages read but not decodable (unknown channel or schema, bad payload).
    pub undecodable_messages: u64,
    /// The scanner's account: finished or not, unreadable bytes, skipped chunks, first problem.
    pub scan: ScanOutcome,
    /// The file could not be opened at all.
    pub open_failed: bool,
}

impl FileReadReport {
    /// Why not one message came out of the file, when reading stopped on a defect (see
    /// [`no_message_reason`]); `None` when it yielded messages or is a complete empty log.
    pub fn no_message_reason(&self) -> Option<String> {
        let nothing = self.messages == 0 && self.undecodable_messages == 0;
        self.scan
            .first_problem
            .as_ref()
            .filter(|_| nothing)
            .map(no_message_reason)
    }
}

/// The words for a file from which not one message could be read because reading stopped on
/// a defect at `offset`: said the same by `replay` and `analyze`.
pub fn no_message_reason((offset, why): &(u64, String)) -> String {
    format!(
        "no message could be read: reading stopped at byte {offset} ({why}); the file is not a \
         bearingd log or is truncated before its first message"
    )
}

/// Totals over every file read.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ReadSummary {
    pub files: Vec<FileReadReport>,
}

impl ReadSummary {
    pub fn messages(&self) -> u64 {
        self.files.iter().map(|f| f.messages).sum()
    }
    pub fn undecodable_messages(&self) -> u64 {
        self.files.iter().map(|f| f.undecodable_messages).sum()
    }
    pub fn unreadable_bytes(&self) -> u64 {
        self.files.iter().map(|f| f.scan.unreadable_bytes).sum()
    }
    pub fn unfinished_files(&self) -> usize {
        self.files.iter().filter(|f| !f.scan.finished).count()
    }
}

struct ChannelInfo {
    topic: String,
    decoder: Decoder,
}

#[derive(Clone, Copy)]
enum Decoder {
    Raw,
    Json(JsonKind),
    /// A channel for people and viewers (`/log`, `/state`), not a pipeline message.
    Skip,
    Unknown,
}

/// Iterator over every message of a list of files, in file order then file order of records.
pub struct LogReader {
    paths: std::vec::IntoIter<PathBuf>,
    current: Option<Scanner>,
    schemas: HashMap<u16, Decoder>,
    channels: HashMap<u16, ChannelInfo>,
    report: FileReadReport,
    summary: ReadSummary,
    raw_only: bool,
    /// Bytes of the files finished so far.
    bytes_done: u64,
}

/// Reads every pipeline message of `paths`.
pub fn read_messages<P: AsRef<Path>>(paths: &[P]) -> LogReader {
    LogReader::new(paths, false)
}

/// Reads the raw blocks of `paths` (the replay's input); other topics are skipped undecoded.
pub fn read_raw_blocks<P: AsRef<Path>>(paths: &[P]) -> RawBlocks {
    RawBlocks(LogReader::new(paths, true))
}

/// The iterator of [`read_raw_blocks`].
pub struct RawBlocks(LogReader);

impl RawBlocks {
    /// What was read and what could not be, so far (complete once the iterator is exhausted).
    pub fn summary(&self) -> &ReadSummary {
        self.0.summary()
    }
}

impl Iterator for RawBlocks {
    type Item = Result<RawBlock>;
    fn next(&mut self) -> Option<Self::Item> {
        loop {
            match self.0.next()? {
                Ok(LoggedMessage {
                    message: PipelineMessage::Raw(b),
                    ..
                }) => return Some(Ok(b)),
                Ok(_) => {}
                Err(e) => return Some(Err(e)),
            }
        }
    }
}

impl LogReader {
    fn new<P: AsRef<Path>>(paths: &[P], raw_only: bool) -> Self {
        LogReader {
            paths: paths
                .iter()
                .map(|p| p.as_ref().to_path_buf())
                .collect::<Vec<_>>()
                .into_iter(),
            current: None,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            report: FileReadReport::default(),
            summary: ReadSummary::default(),
            raw_only,
            bytes_done: 0,
        }
    }

    /// What was read and what could not be, so far (complete once the iterator is exhausted).
    pub fn summary(&self) -> &ReadSummary {
        &self.summary
    }

    /// Bytes read so far, over every file (for progress).
    pub fn bytes_read(&self) -> u64 {
        self.bytes_done + self.current.as_ref().map_or(0, Scanner::offset)
    }

    fn close_current(&mut self) {
        if let Some(scanner) = self.current.take() {
            self.bytes_done += scanner.file_len();
            self.report.scan = scanner.outcome().clone();
            self.summary.files.push(std::mem::take(&mut self.report));
        }
    }

    fn decode(&mut self, path: &Path, record: ScannedRecord) -> Option<Result<LoggedMessage>> {
        match record {
            ScannedRecord::Schema {
                id, name, encoding, ..
            } => {
                let decoder = if name == RAW_BLOCK_SCHEMA && encoding == "protobuf" {
                    Decoder::Raw
                } else if name == LOG_SCHEMA || name == STATE_SCHEMA {
                    // The daemon's notes and state snapshots: for people and viewers, not
                    // pipeline messages.
                    Decoder::Skip
                } else if encoding == "jsonschema" {
                    JsonKind::from_schema_name(&name).map_or(Decoder::Unknown, Decoder::Json)
                } else {
                    Decoder::Unknown
                };
                self.schemas.insert(id, decoder);
                None
            }
            ScannedRecord::Channel {
                id,
                schema_id,
                topic,
                message_encoding,
                ..
            } => {
                let decoder = match self.schemas.get(&schema_id) {
                    Some(Decoder::Raw) if message_encoding == "protobuf" => Decoder::Raw,
                    Some(Decoder::Json(k)) if message_encoding == "json" => Decoder::Json(*k),
                    Some(Decoder::Skip) => Decoder::Skip,
                    _ => Decoder::Unknown,
                };
                self.channels.insert(id, ChannelInfo { topic, decoder });
                None
            }
            ScannedRecord::Metadata { .. } => None,
            ScannedRecord::Message {
                channel_id,
                sequence,
                log_time,
                publish_time,
                data,
                offset,
            } => {
                let Some(channel) = self.channels.get(&channel_id) else {
                    self.report.undecodable_messages += 1;
                    return Some(Err(McapLogError::Decode {
                        path: path.to_path_buf(),
                        offset,
                        topic: format!("<channel {channel_id}>"),
                        reason: "message on an unknown channel".into(),
                    }));
                };
                if matches!(channel.decoder, Decoder::Skip)
                    || (self.raw_only && !matches!(channel.decoder, Decoder::Raw))
                {
                    return None;
                }
                let decoded: std::result::Result<PipelineMessage, String> = match channel.decoder {
                    Decoder::Raw => RawBlockPb::decode(data.as_slice())
                        .map_err(|e| e.to_string())
                        .and_then(|pb| {
                            pb.into_block()
                                .ok_or_else(|| "raw block without a channel".to_string())
                        })
                        .map(PipelineMessage::Raw),
                    Decoder::Json(kind) => decode_json(kind, &data).map_err(|e| e.to_string()),
                    Decoder::Unknown => Err("channel has no schema this reader knows".into()),
                    Decoder::Skip => return None,
                };
                match decoded {
                    Ok(message) => {
                        self.report.messages += 1;
                        Some(Ok(LoggedMessage {
                            topic: channel.topic.clone(),
                            sequence,
                            log_time,
                            publish_time,
                            message,
                        }))
                    }
                    Err(reason) => {
                        self.report.undecodable_messages += 1;
                        Some(Err(McapLogError::Decode {
                            path: path.to_path_buf(),
                            offset,
                            topic: channel.topic.clone(),
                            reason,
                        }))
                    }
                }
            }
        }
    }
}

fn decode_json(kind: JsonKind, data: &[u8]) -> serde_json::Result<PipelineMessage> {
    Ok(match kind {
        JsonKind::Spectrum => PipelineMessage::Spectrum(serde_json::from_slice(data)?),
        JsonKind::Indicators => PipelineMessage::Indicators(serde_json::from_slice(data)?),
        JsonKind::Twin => PipelineMessage::Twin(serde_json::from_slice(data)?),
        JsonKind::Hw => PipelineMessage::Hw(serde_json::from_slice(data)?),
        JsonKind::Trend => PipelineMessage::Trend(serde_json::from_slice(data)?),
        JsonKind::Flag => PipelineMessage::Flag(serde_json::from_slice(data)?),
        JsonKind::Health => PipelineMessage::Health(serde_json::from_slice(data)?),
        JsonKind::Ingest => PipelineMessage::Ingest(serde_json::from_slice(data)?),
        JsonKind::Speed => PipelineMessage::Speed(serde_json::from_slice(data)?),
        JsonKind::Detector(kind) => PipelineMessage::Detector((kind.info().decode)(data)?),
    })
}

impl Iterator for LogReader {
    type Item = Result<LoggedMessage>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.current.is_none() {
                let path = self.paths.next()?;
                self.schemas.clear();
                self.channels.clear();
                self.report = FileReadReport {
                    path: path.clone(),
                    ..Default::default()
                };
                match Scanner::open(&path) {
                    Ok(s) => self.current = Some(s),
                    Err(e) => {
                        self.report.open_failed = true;
                        self.summary.files.push(std::mem::take(&mut self.report));
                        return Some(Err(e));
                    }
                }
            }
            let scanner = self.current.as_mut()?;
            match scanner.next_record() {
                Ok(Some(record)) => {
                    let path = scanner.path().to_path_buf();
                    if let Some(item) = self.decode(&path, record) {
                        return Some(item);
                    }
                }
                Ok(None) => self.close_current(),
                Err(e) => {
                    self.close_current();
                    return Some(Err(e));
                }
            }
        }
    }
}
