//! CAN frames as a bus delivers them: `[id u32 LE][len u8][≤64 bytes]` repeated. Each goes to
//! the wire decoder, the identifier parser and the daemon's assembler (sequence tracking,
//! metadata pages, sample blocks). A frame that decodes must encode back to itself.
#![no_main]

use bearing_wire::{decode, encode, CanId, FrameKind, MessageKind};
use bearingd::sources::assemble::Assembler;
use bearingd_fuzz::{default_budget, next_can_frame, with_budget, Bytes};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    with_budget(default_budget(data.len()), || {
        let mut bytes = Bytes::new(data);
        let mut assembler = Assembler::new();
        let mut events = Vec::new();
        while let Some((id, frame)) = next_can_frame(&mut bytes) {
            round_trip(id, frame);
            assembler.push(id, frame, &mut events);
            if events.len() > 64 {
                events.clear();
            }
        }
        let _ = assembler.stats();
        let _ = assembler.streams();
    });
});

fn round_trip(id: u32, data: &[u8]) {
    let Ok(frame) = decode(id, data) else {
        return;
    };
    let kind = match CanId::parse(id).map(|c| c.message) {
        Some(MessageKind::Data { kind, .. }) => kind,
        _ => FrameKind::Classic,
    };
    let mut out = [0u8; 64];
    let (raw, len) = match encode(&frame, kind, &mut out) {
        Ok(encoded) => encoded,
        Err(e) => panic!("frame {id:#x} decoded but does not encode back: {e}"),
    };
    assert_eq!(
        u32::from(raw),
        id,
        "a decoded frame encodes under another id"
    );
    assert_eq!(
        decode(id, &out[..len]).ok(),
        Some(frame),
        "frame {id:#x} changes in a decode-encode-decode round trip"
    );
}
