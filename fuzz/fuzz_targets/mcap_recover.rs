//! The start-up recovery of an unfinished log: the input is written as a log file in a scratch
//! directory and recovered (rewritten from its complete records, checked strictly, or
//! quarantined); the directory is emptied after each input.
#![no_main]

use bearingd::mcap_log::bounds::MAX_RECORD_BYTES;
use bearingd::mcap_log::file_name;
use bearingd::sinks::mcap::recover::recover_file;
use bearingd_fuzz::{default_budget, empty_dir, scratch_dir, with_budget, write_scratch};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = scratch_dir("mcap_recover");
    let path = write_scratch(&dir, &file_name(0, 1), data);
    with_budget(
        MAX_RECORD_BYTES as usize + default_budget(data.len()),
        || {
            if let Err(e) = recover_file(&path) {
                let _ = e.to_string();
            }
        },
    );
    empty_dir(&dir);
});
