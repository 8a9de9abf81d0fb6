//! The limits every read of a log file keeps, so that no declared length in a hostile or
//! broken file is ever allocated before the bytes behind it are known to exist.
//!
//! Why here and not left to the `mcap` crate: its record parser (binrw) reserves a string's
//! declared length (a u32, up to 4 GiB) before it reads the string, so a 60-byte metadata record
//! whose key says "4 GiB follow" aborts the process on an address-space limit (issue 32: the
//! daemon's start-up recovery then crash-looped under systemd). Two checks close that:
//!
//! - a top-level record's length must fit in the bytes left in the file and under
//!   [`MAX_RECORD_BYTES`] ([`record_length_limit`], the scanner's check; the strict reader gives
//!   the crate's `LinearReaderOptions` the cap);
//! - inside a record, every length-prefixed field (strings, string maps, byte arrays) must fit
//!   in the record before [`parse_record`] hands the body to the crate.
//!
//! Every reader of the log (replay, analyze, recovery, the strict read-back) parses records
//! only through [`parse_record`].

use mcap::records::Record;

/// No record or chunk larger than this is ever read into memory (the logger writes chunks of a
/// few MiB; anything larger is corruption).
pub const MAX_RECORD_BYTES: u64 = 64 * 1024 * 1024;

/// The largest record body a file of `file_len` bytes can hold: never more than the file, nor
/// than [`MAX_RECORD_BYTES`].
pub fn record_length_limit(file_len: u64) -> u64 {
    file_len.min(MAX_RECORD_BYTES)
}

/// One field of a record's layout, as far as lengths go (MCAP spec, "Records").
#[derive(Clone, Copy)]
enum Field {
    /// Fixed-size integers: this many bytes.
    Fixed(usize),
    /// u32 length, then that many bytes (a string).
    Str,
    /// u32 byte length, then key/value strings filling it exactly.
    StrMap,
    /// u32 byte length, then that many bytes.
    Bytes32,
    /// u32 byte length, then entries of this many bytes each (a map of integers): a length
    /// that is not a whole number of entries would make the crate read the last entry past the
    /// field, and every later field from the wrong place.
    Entries32(usize),
    /// u64 byte length, then that many bytes.
    Bytes64,
}

use Field::{Bytes32, Bytes64, Entries32, Fixed, Str, StrMap};

/// The length-prefixed fields of each record kind, up to the last one (what follows, such as a
/// message's payload or a chunk's records, is not parsed by the crate's record parser). Kinds
/// not listed are fixed-size.
fn layout(opcode: u8) -> &'static [Field] {
    match opcode {
        0x01 => &[Str, Str],                                // header: profile, library
        0x03 => &[Fixed(2), Str, Str, Bytes32],             // schema
        0x04 => &[Fixed(4), Str, Str, StrMap],              // channel
        0x06 => &[Fixed(28), Str, Bytes64],                 // chunk
        0x07 => &[Fixed(2), Entries32(16)],                 // message index: (u64, u64)
        0x08 => &[Fixed(32), Entries32(10), Fixed(8), Str], // chunk index: (u16, u64)
        0x09 => &[Fixed(16), Str, Str, Bytes64],            // attachment
        0x0A => &[Fixed(40), Str, Str],                     // attachment index
        0x0B => &[Fixed(42), Entries32(10)],                // statistics: (u16, u64)
        0x0C => &[Str, StrMap],                             // metadata
        0x0D => &[Fixed(16), Str],                          // metadata index
        _ => &[],
    }
}

/// Walks a record body field by field, checking each declared length against what is left.
struct Cursor<'a> {
    body: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn skip(&mut self, len: u64, what: &str) -> Result<(), String> {
        let left = self.body.len() - self.at;
        if len > left as u64 {
            return Err(format!(
                "{what} of {len} bytes at byte {} of the record runs past its end ({left} bytes left)",
                self.at
            ));
        }
        self.at += len as usize;
        Ok(())
    }

    fn length(&mut self, width: usize, what: &str) -> Result<u64, String> {
        let bytes = self
            .body
            .get(self.at..self.at + width)
            .ok_or_else(|| format!("{what} length cut off at byte {} of the record", self.at))?;
        self.at += width;
        let mut le = [0u8; 8];
        le[..width].copy_from_slice(bytes);
        Ok(u64::from_le_bytes(le))
    }

    fn prefixed(&mut self, width: usize, what: &str) -> Result<(), String> {
        let len = self.length(width, what)?;
        self.skip(len, what)
    }

    fn field(&mut self, field: Field) -> Result<(), String> {
        match field {
            Fixed(n) => self.skip(n as u64, "fixed fields"),
            Str => self.prefixed(4, "string"),
            Bytes32 => self.prefixed(4, "array"),
            Bytes64 => self.prefixed(8, "data"),
            Entries32(entry) => {
                let len = self.length(4, "map")?;
                if len % entry as u64 != 0 {
                    return Err(format!(
                        "map of {len} bytes before byte {} of the record is not a whole number of \
                         {entry}-byte entries",
                        self.at
                    ));
                }
                self.skip(len, "map")
            }
            StrMap => {
                let len = self.length(4, "map")?;
                let start = self.at;
                self.skip(len, "map")?;
                let mut entries = Cursor {
                    body: &self.body[..self.at],
                    at: start,
                };
                while entries.at < entries.body.len() {
                    entries.prefixed(4, "map key")?;
                    entries.prefixed(4, "map value")?;
                }
                Ok(())
            }
        }
    }
}

/// Checks that every length-prefixed field of a record fits in `body`; the reason otherwise.
pub fn check_field_lengths(opcode: u8, body: &[u8]) -> Result<(), String> {
    let mut cursor = Cursor { body, at: 0 };
    for &field in layout(opcode) {
        cursor.field(field)?;
    }
    Ok(())
}

/// Parses one record body with the `mcap` crate once [`check_field_lengths`] passed; every
/// reader of the log parses records through here. The error names the opcode and the reason.
pub fn parse_record(opcode: u8, body: &[u8]) -> Result<Record<'_>, String> {
    check_field_lengths(opcode, body)
        .and_then(|()| mcap::parse_record(opcode, body).map_err(|e| e.to_string()))
        .map_err(|e| format!("record (opcode {opcode:#04x}): {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn string(s: &str) -> Vec<u8> {
        let mut out = (s.len() as u32).to_le_bytes().to_vec();
        out.extend_from_slice(s.as_bytes());
        out
    }

    fn metadata_body(key_len: u32) -> Vec<u8> {
        let mut body = string("bearingd.run");
        let mut map = key_len.to_le_bytes().to_vec();
        map.extend_from_slice(b"k");
        map.extend(string("v"));
        body.extend((map.len() as u32).to_le_bytes());
        body.extend(map);
        body
    }

    #[test]
    fn a_string_declaring_4_gib_inside_a_small_record_is_refused_before_the_crate_parses_it() {
        let body = metadata_body(u32::MAX);
        let err = parse_record(0x0C, &body).unwrap_err();
        assert!(err.contains("map key of 4294967295 bytes"), "{err}");
        assert!(err.contains("opcode 0x0c"), "{err}");
    }

    #[test]
    fn well_formed_records_of_every_kind_the_writer_makes_pass_and_parse() {
        let body = metadata_body(1);
        match parse_record(0x0C, &body).unwrap() {
            Record::Metadata(m) => {
                assert_eq!(m.name, "bearingd.run");
                assert_eq!(m.metadata, BTreeMap::from([("k".into(), "v".into())]));
            }
            other => panic!("{other:?}"),
        }
        let mut channel = vec![1, 0, 2, 0];
        channel.extend(string("/raw/a/x"));
        channel.extend(string("protobuf"));
        channel.extend(0u32.to_le_bytes());
        assert!(matches!(
            parse_record(0x04, &channel).unwrap(),
            Record::Channel(c) if c.topic == "/raw/a/x"
        ));
    }

    /// Fuzzing found it (fuzz/regressions/mcap_read/chunk-index-map-not-whole-entries.mcap):
    /// a chunk index whose offsets map held 7 bytes made the crate read a 10-byte entry past
    /// the map, then the compression string's length (4 GiB - 1) from the wrong bytes.
    #[test]
    fn a_map_of_integers_that_is_not_whole_entries_is_refused_before_the_crate_parses_it() {
        let mut body = vec![0u8; 32];
        body.extend(7u32.to_le_bytes());
        body.extend([0u8; 7]);
        body.extend(0u64.to_le_bytes());
        body.extend(string("zstd"));
        body.extend([0u8; 16]);
        let err = parse_record(0x08, &body).unwrap_err();
        assert!(
            err.contains("not a whole number of 10-byte entries"),
            "{err}"
        );
        // The same map with a whole entry parses.
        let mut body = vec![0u8; 32];
        body.extend(10u32.to_le_bytes());
        body.extend([0u8; 10]);
        body.extend(0u64.to_le_bytes());
        body.extend(string("zstd"));
        body.extend([0u8; 16]);
        assert!(
            matches!(parse_record(0x08, &body), Ok(Record::ChunkIndex(c)) if c.compression == "zstd")
        );
    }

    #[test]
    fn a_cut_off_length_or_a_map_entry_past_the_map_is_refused() {
        assert!(check_field_lengths(0x01, &[5, 0]).is_err());
        // The map says 4 bytes, its key says 8: the key would run out of the map.
        let mut body = string("n");
        body.extend(4u32.to_le_bytes());
        body.extend(8u32.to_le_bytes());
        body.extend(string("abcd"));
        let err = check_field_lengths(0x0C, &body).unwrap_err();
        assert!(err.contains("map"), "{err}");
    }

    #[test]
    fn the_record_limit_is_the_file_size_up_to_the_cap() {
        assert_eq!(record_length_limit(100), 100);
        assert_eq!(record_length_limit(u64::MAX), MAX_RECORD_BYTES);
    }
}
