//! MCAP logs as `replay`, `analyze` and `verify` read them: the input is written to a scratch
//! file, then read by the log reader (every message), the bounded scanner, the log header
//! reader, the recording reader of logs and the strict read-back. The hostile files (a
//! 4 GiB string length, magic then random bytes) are in fuzz/regressions/mcap_read.
#![no_main]

use bearingd::mcap_log::bounds::MAX_RECORD_BYTES;
use bearingd::mcap_log::scan::Scanner;
use bearingd::mcap_log::{read_back_strictly, read_header, read_messages};
use bearingd::recording::{read_recording, ReadOptions};
use bearingd_fuzz::{default_budget, scratch_dir, with_budget, write_scratch};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let dir = scratch_dir("mcap_read");
    let path = write_scratch(&dir, "bearingd-fuzz.mcap", data);
    with_budget(mcap_budget(data.len()), || {
        read_every_way(&path, data.len() as u64)
    });
});

/// A chunk may decompress up to [`MAX_RECORD_BYTES`] whatever its compressed size.
fn mcap_budget(len: usize) -> usize {
    MAX_RECORD_BYTES as usize + default_budget(len)
}

fn read_every_way(path: &Path, file_len: u64) {
    let mut reader = read_messages(&[path]);
    for message in reader.by_ref() {
        if let Err(e) = message {
            let _ = e.to_string();
        }
    }
    for file in &reader.summary().files {
        let _ = file.no_message_reason();
        assert!(
            file.scan.unreadable_bytes <= file_len,
            "{} unreadable bytes counted in a file of {file_len}",
            file.scan.unreadable_bytes
        );
    }
    if let Ok(mut scanner) = Scanner::open(path) {
        while let Ok(Some(_)) = scanner.next_record() {}
        let _ = scanner.outcome();
    }
    let _ = read_header(path);
    let _ = read_recording(path, &ReadOptions::default());
    let _ = read_back_strictly(path);
}
