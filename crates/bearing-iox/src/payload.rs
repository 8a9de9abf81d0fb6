//! The iceoryx2 payload: the same (CAN id, length, bytes) triples that travel on a CAN bus,
//! batched into one fixed-size shared-memory sample.
//!
//! Why CAN frames over shared memory instead of a sample array: both transports then decode
//! with `bearing_wire::decode` and track loss with the same `SequenceTracker`, so a local
//! acquisition process and a CAN node cannot disagree on scale, sample rate or what a gap is.
//! The layout is `#[repr(C)]`, fixed-size and versioned, with an explicit iceoryx2 type name
//! so that a publisher written in another crate or language matches it (docs/WIRE_FORMAT.md,
//! "iceoryx2 payload").

#[cfg(feature = "iceoryx2")]
use iceoryx2::prelude::ZeroCopySend;

/// Layout version of [`FrameBatch`]; a receiver refuses any other value.
pub const FRAME_BATCH_VERSION: u32 = 1;

/// Frames one [`FrameBatch`] holds.
pub const FRAMES_PER_BATCH: usize = 64;

/// Largest frame payload (CAN FD).
pub const MAX_FRAME_LEN: usize = 64;

/// One CAN frame as it would appear on the bus: 11-bit id, data length, data bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(
    feature = "iceoryx2",
    derive(ZeroCopySend),
    type_name("bearingd::WireFrame")
)]
#[repr(C)]
pub struct WireFrame {
    /// CAN identifier (standard 11-bit; flag bits must be clear).
    pub can_id: u32,
    /// Valid bytes in `data`, 0..=64.
    pub len: u8,
    /// Sent as 0, ignored on receipt.
    pub reserved: [u8; 3],
    /// Frame data; bytes at `len..` are 0.
    pub data: [u8; MAX_FRAME_LEN],
}

impl WireFrame {
    /// An empty frame (id 0, no data).
    pub const EMPTY: WireFrame = WireFrame {
        can_id: 0,
        len: 0,
        reserved: [0; 3],
        data: [0; MAX_FRAME_LEN],
    };

    /// A frame holding `bytes`, or `None` if there are more than 64 of them.
    pub fn new(can_id: u32, bytes: &[u8]) -> Option<WireFrame> {
        let len = u8::try_from(bytes.len()).ok()?;
        let mut frame = WireFrame {
            can_id,
            len,
            ..WireFrame::EMPTY
        };
        frame.data.get_mut(..bytes.len())?.copy_from_slice(bytes);
        Some(frame)
    }

    /// The valid bytes; a `len` above 64 (a corrupt sample) gives all 64, and the decoder then
    /// refuses the frame by its length instead of this code panicking.
    pub fn bytes(&self) -> &[u8] {
        let len = usize::from(self.len).min(MAX_FRAME_LEN);
        &self.data[..len]
    }
}

/// Up to 64 frames in one shared-memory sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(
    feature = "iceoryx2",
    derive(ZeroCopySend),
    type_name("bearingd::FrameBatch")
)]
#[repr(C)]
pub struct FrameBatch {
    /// [`FRAME_BATCH_VERSION`].
    pub version: u32,
    /// Valid frames in `frames`, 0..=64.
    pub count: u32,
    /// The frames, in the order the node produced them.
    pub frames: [WireFrame; FRAMES_PER_BATCH],
}

impl Default for FrameBatch {
    fn default() -> Self {
        FrameBatch {
            version: FRAME_BATCH_VERSION,
            count: 0,
            frames: [WireFrame::EMPTY; FRAMES_PER_BATCH],
        }
    }
}

/// Why a received batch cannot be used as a whole.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum BatchError {
    #[error(
        "iceoryx2 frame batch: version {0}, this receiver reads version {FRAME_BATCH_VERSION} only"
    )]
    Version(u32),
    #[error("iceoryx2 frame batch: count {0} at byte offset 4 exceeds the {FRAMES_PER_BATCH} frames a batch holds")]
    Count(u32),
}

impl FrameBatch {
    /// Appends a frame; `false` when the batch is full.
    pub fn push(&mut self, frame: WireFrame) -> bool {
        let index = self.count as usize;
        match self.frames.get_mut(index) {
            Some(slot) => {
                *slot = frame;
                self.count += 1;
                true
            }
            None => false,
        }
    }

    /// Whether no more frames fit.
    pub fn is_full(&self) -> bool {
        self.count as usize >= FRAMES_PER_BATCH
    }

    /// Empties the batch.
    pub fn clear(&mut self) {
        self.count = 0;
    }

    /// The valid frames, after checking the header.
    pub fn valid_frames(&self) -> Result<&[WireFrame], BatchError> {
        if self.version != FRAME_BATCH_VERSION {
            return Err(BatchError::Version(self.version));
        }
        let count = self.count as usize;
        self.frames
            .get(..count)
            .ok_or(BatchError::Count(self.count))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_fixed() {
        assert_eq!(std::mem::size_of::<WireFrame>(), 72);
        assert_eq!(std::mem::size_of::<FrameBatch>(), 8 + 64 * 72);
    }

    #[test]
    fn corrupt_headers_are_refused_not_panicked_on() {
        let mut batch = FrameBatch {
            count: 65,
            ..FrameBatch::default()
        };
        assert_eq!(batch.valid_frames(), Err(BatchError::Count(65)));
        batch.count = 1;
        batch.version = 7;
        assert_eq!(batch.valid_frames(), Err(BatchError::Version(7)));
        let frame = WireFrame {
            len: 200,
            ..WireFrame::EMPTY
        };
        assert_eq!(frame.bytes().len(), 64);
        assert!(WireFrame::new(0x100, &[0; 65]).is_none());
    }

    #[test]
    fn push_until_full() {
        let mut batch = FrameBatch::default();
        for i in 0..FRAMES_PER_BATCH {
            assert!(batch.push(WireFrame::new(0x100 + i as u32, &[1, 2]).unwrap()));
        }
        assert!(batch.is_full());
        assert!(!batch.push(WireFrame::EMPTY));
        assert_eq!(batch.valid_frames().unwrap()[3].bytes(), &[1, 2]);
    }
}
