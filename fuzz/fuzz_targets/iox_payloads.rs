//! iceoryx2 payloads as another process could write them: the input is cut into
//! `FrameBatch`-sized pieces (4616 bytes, zero-padded), each checked with `valid_frames()` and
//! its frames fed to the assembler, as the shm source does; its first 144 bytes are also read as
//! an `Alert` and decoded with `view()` (what `bearingd alerts` prints).
//!
//! The alert subscriber's sequence check is not driven here yet (being written on another
//! branch; to be added to this target when it lands).
#![no_main]

use bearing_iox::{FrameBatch, WireFrame, FRAMES_PER_BATCH, MAX_FRAME_LEN};
use bearingd::sinks::alerts::payload::NAME_BYTES;
use bearingd::sinks::alerts::Alert;
use bearingd::sources::assemble::Assembler;
use bearingd_fuzz::{default_budget, with_budget, Bytes};
use libfuzzer_sys::fuzz_target;

/// `size_of::<FrameBatch>()`: version, count, 64 frames of 72 bytes.
const BATCH_BYTES: usize = 8 + FRAMES_PER_BATCH * 72;

fuzz_target!(|data: &[u8]| {
    with_budget(default_budget(data.len()), || {
        let alert = alert_from(&mut Bytes::new(data));
        if let Ok(view) = alert.view() {
            let _ = view.line();
        }
        let mut assembler = Assembler::new();
        let mut events = Vec::new();
        for piece in data.chunks(BATCH_BYTES) {
            let batch = batch_from(&mut Bytes::new(piece));
            match batch.valid_frames() {
                Ok(frames) => {
                    for frame in frames {
                        assembler.push(frame.can_id, frame.bytes(), &mut events);
                    }
                }
                Err(e) => assembler.refuse_batch(e.to_string(), &mut events),
            }
            events.clear();
        }
    });
});

/// A `FrameBatch` from its `#[repr(C)]` little-endian bytes.
fn batch_from(bytes: &mut Bytes) -> FrameBatch {
    let mut batch = FrameBatch {
        version: bytes.u32(),
        count: bytes.u32(),
        ..FrameBatch::default()
    };
    for slot in batch.frames.iter_mut() {
        *slot = WireFrame {
            can_id: bytes.u32(),
            len: bytes.u8(),
            reserved: bytes.array(),
            data: bytes.array::<MAX_FRAME_LEN>(),
        };
    }
    batch
}

/// An `Alert` from its `#[repr(C)]` little-endian bytes (docs/ALERTS.md's layout).
fn alert_from(bytes: &mut Bytes) -> Alert {
    Alert {
        sequence: bytes.u64(),
        run_id: bytes.u64(),
        end_sample: bytes.u64(),
        wall_time_ns: bytes.u64(),
        sample_rate_hz: bytes.f64(),
        fault_frequency_hz: bytes.f64(),
        score: bytes.f64(),
        confidence: bytes.f64(),
        twin_error: bytes.f64(),
        version: bytes.u32(),
        state: bytes.u8(),
        fault: bytes.u8(),
        severity: bytes.u8(),
        previous_severity: bytes.u8(),
        sensor: bytes.array::<NAME_BYTES>(),
        axis: bytes.array::<NAME_BYTES>(),
    }
}
