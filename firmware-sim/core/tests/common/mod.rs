//! Helpers shared by the integration tests.
#![allow(dead_code)]

use bearing_wire::frame::SAMPLES_CAPACITY;
use bearing_wire::{DataFrame, Frame, FrameKind};

/// xorshift64*: a tiny deterministic PRNG, so the tests need no `rand` and always see the same
/// inputs.
pub struct XorShift(u64);

impl XorShift {
    pub fn new(seed: u64) -> Self {
        XorShift(seed.max(1))
    }

    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    pub fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    /// Uniform-ish in `0..n` (n > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }

    pub fn fill(&mut self, bytes: &mut [u8]) {
        for b in bytes {
            *b = self.next_u64() as u8;
        }
    }
}

pub fn data(node: u8, axis: u8, sequence: u16, first_sample: u32, samples: &[i16]) -> DataFrame {
    DataFrame {
        node,
        axis,
        sequence,
        first_sample,
        samples: heapless::Vec::<i16, SAMPLES_CAPACITY>::from_slice(samples).unwrap(),
    }
}

/// `frame` as the receiver sees it after a trip through `kind`'s layout: counters truncated to
/// the bits that travel.
pub fn truncated(frame: &Frame, kind: FrameKind) -> Frame {
    match frame {
        Frame::Data(d) if kind == FrameKind::Classic => Frame::Data(DataFrame {
            sequence: d.sequence & 0xFF,
            first_sample: d.first_sample & 0x00FF_FFFF,
            ..d.clone()
        }),
        other => other.clone(),
    }
}
