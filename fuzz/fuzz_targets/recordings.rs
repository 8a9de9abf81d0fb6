//! The recording readers (.mat, PRONOSTIA and plain CSV, IMS text, WAV): the first input byte
//! picks the file name (which chooses the format, as for a real file), the second the channel
//! asked for; the rest is the file's content.
#![no_main]

use bearing_signal::recording::{list_channels_from_bytes, read_recording_from_bytes, ReadOptions};
use bearingd_fuzz::{default_budget, with_budget};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

/// Names that choose each reader; the last has no extension (format from the content).
const NAMES: [&str; 8] = [
    "12k_Drive_End_B007_0_118.mat",
    "table.csv",
    "acc_00001.csv",
    "signal.wav",
    "table.txt",
    "2003.10.22.12.14.13",
    "recording",
    "sound.wave",
];

/// Channels asked for: none, an index, and names each format knows.
const CHANNELS: [Option<&str>; 6] = [
    None,
    Some("1"),
    Some("2"),
    Some("DE"),
    Some("horizontal"),
    Some("B1x"),
];

/// zlib's largest expansion (1032:1): a compressed MATLAB variable may justify that much.
const ZLIB_MAX_RATIO: usize = 1032;

fuzz_target!(|data: &[u8]| {
    let [name, channel, content @ ..] = data else {
        return;
    };
    let name = NAMES[usize::from(*name) % NAMES.len()];
    let path = Path::new(name);
    let options = ReadOptions {
        channel: CHANNELS[usize::from(*channel) % CHANNELS.len()].map(str::to_string),
        column: None,
        unit: None,
    };
    with_budget(budget(name, content.len()), || {
        if let Err(e) = read_recording_from_bytes(path, content, &options) {
            let _ = e.to_string();
        }
        let _ = list_channels_from_bytes(path, content);
    });
});

/// [`default_budget`], except where MATLAB may be read: there a compressed variable inflates
/// up to zlib's ratio, into a growing buffer (×2), and its smallest element type (1 byte)
/// becomes an 8-byte sample.
fn budget(name: &str, len: usize) -> usize {
    let may_be_matlab = name.ends_with(".mat") || !name.contains('.');
    if may_be_matlab {
        default_budget(len) + 2 * 8 * ZLIB_MAX_RATIO * len
    } else {
        default_budget(len)
    }
}
