//! A strict read of a whole file with the `mcap` crate's own sans-IO reader
//! ([`mcap::sans_io::LinearReader`]): start and end magic, every chunk's CRC, the data and
//! summary section CRCs, the footer, and the statistics record's message count against the
//! messages actually found.
//!
//! Record lengths are bounded as in every reader ([`super::bounds`]).
//!
//! Why a second reader beside [`super::scan`]: recovery writes a copy from what the scanner
//! read; before that copy may replace anything it must pass a reader that did not produce it,
//! with nothing forgiven (the scanner is deliberately lenient, this one is not).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::bounds::{parse_record, MAX_RECORD_BYTES};
use super::error::{io_err, McapLogError, Result};

/// What a strict read found in a file that passed it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StrictRead {
    pub messages: u64,
    pub chunks: u64,
}

/// Reads `path` strictly from end to end; any defect is a [`McapLogError::Corrupt`] naming
/// the byte offset where the reader stood.
pub fn read_back_strictly(path: &Path) -> Result<StrictRead> {
    let mut file = File::open(path).map_err(io_err(path, "open"))?;
    let options = LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_validate_data_section_crc(true)
        .with_validate_summary_section_crc(true)
        .with_check_finishes_after_end_magic(true)
        // The crate applies this limit to a chunk's uncompressed records too, which may be
        // larger than the file itself: the cap, not the file's size.
        .with_record_length_limit(MAX_RECORD_BYTES as usize);
    let mut reader = LinearReader::new_with_options(options);
    let mut found = StrictRead::default();
    let mut statistics: Option<u64> = None;
    let mut footer = false;
    let mut offset = 0u64;
    let corrupt = |offset: u64, reason: String| McapLogError::Corrupt {
        path: path.to_path_buf(),
        offset,
        reason,
    };
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| corrupt(offset, e.to_string()))? {
            LinearReadEvent::ReadRequest(wanted) => {
                let buffer = reader.insert(wanted);
                let read = file.read(buffer).map_err(io_err(path, "read"))?;
                reader.notify_read(read);
                offset += read as u64;
            }
            LinearReadEvent::Record { data, opcode } => {
                match parse_record(opcode, data).map_err(|e| corrupt(offset, e))? {
                    Record::Message { .. } => found.messages += 1,
                    Record::ChunkIndex(_) => found.chunks += 1,
                    Record::Statistics(s) => statistics = Some(s.message_count),
                    Record::Footer(_) => footer = true,
                    _ => {}
                }
            }
        }
    }
    if !footer {
        return Err(corrupt(offset, "no footer".into()));
    }
    match statistics {
        Some(count) if count == found.messages => Ok(found),
        Some(count) => Err(corrupt(
            offset,
            format!(
                "the statistics count {count} messages, the file holds {}",
                found.messages
            ),
        )),
        None => Err(corrupt(
            offset,
            "no statistics record in the summary".into(),
        )),
    }
}
