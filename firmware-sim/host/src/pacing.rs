//! When the next frame may leave: at the bus bit rate, and no earlier than sample time allows.
//!
//! A real node cannot send faster than its bus, and vcan has no bit rate at all, so the
//! simulator keeps a virtual bus: each frame occupies the bus for its bit time (arbitration at
//! the nominal rate; for CAN FD with bit-rate switch, the data phase at the data rate), with a
//! worst-case estimate of stuff bits. Besides realism this is the flow control a test needs:
//! SocketCAN (vcan included) drops frames silently when the reader falls behind, and a sender
//! paced at the bus rate cannot outrun a reader that keeps up with the real bus.

use std::time::{Duration, Instant};

/// Longest the sender may run ahead of the virtual bus before it sleeps (fewer, longer
/// sleeps; the bus rate still holds on average over this window).
const SLACK: Duration = Duration::from_millis(2);

/// Bits a frame occupies on the bus: `(nominal_bits, data_phase_bits)`. Classic frames and the
/// arbitration/ack phases of FD frames are at the nominal rate; the FD data phase (with BRS)
/// at the data rate. Stuff bits: worst case, one per four bits of the stuffed region.
pub fn frame_bits(len: usize, fd: bool) -> (u32, u32) {
    let data_bits = 8 * len as u32;
    if !fd {
        // SOF, 11-bit id, RTR, IDE, r0, DLC(4), data, CRC(15), CRC delimiter, ACK slot and
        // delimiter, EOF(7), interframe space(3); 34 + data bits are subject to stuffing.
        let stuffed = 34 + data_bits;
        (47 + data_bits + (stuffed - 1) / 4, 0)
    } else {
        // Nominal: SOF, id(11), RRS, IDE, FDF, res, BRS, then CRC delimiter, ACK, ACK
        // delimiter, EOF(7), IFS(3): 29 bits (+ ~3 stuff bits in the arbitration field).
        // Data phase: ESI, DLC(4), data, stuff count(4), CRC (17 up to 16 bytes, else 21)
        // with its fixed stuff bits (one per 4), plus dynamic stuffing of ESI..data.
        let crc = if len <= 16 { 17 } else { 21 };
        let data_phase = 1 + 4 + data_bits + 4 + crc + crc.div_ceil(4) + (5 + data_bits) / 4;
        (32, data_phase)
    }
}

/// A virtual bus of a given nominal and data bit rate (bit/s; 0 = no limit).
#[derive(Debug)]
pub struct BusPacer {
    nominal_bps: u32,
    data_bps: u32,
    free_at: Instant,
    /// Sum of frame times, for the report.
    pub busy: Duration,
}

impl BusPacer {
    pub fn new(nominal_bps: u32, data_bps: u32) -> BusPacer {
        BusPacer {
            nominal_bps,
            data_bps: if data_bps == 0 { nominal_bps } else { data_bps },
            free_at: Instant::now(),
            busy: Duration::ZERO,
        }
    }

    /// Time the frame occupies the bus.
    pub fn frame_time(&self, len: usize, fd: bool) -> Duration {
        if self.nominal_bps == 0 {
            return Duration::ZERO;
        }
        let (nominal, data) = frame_bits(len, fd);
        let seconds = f64::from(nominal) / f64::from(self.nominal_bps)
            + f64::from(data) / f64::from(self.data_bps);
        Duration::from_secs_f64(seconds)
    }

    /// Waits until the bus can take a frame of `len` bytes, and books it. Never bursts to catch
    /// up: a late sender continues from now, at the bus rate.
    pub fn wait_for_bus(&mut self, len: usize, fd: bool) {
        let frame = self.frame_time(len, fd);
        if frame.is_zero() {
            return;
        }
        self.busy += frame;
        let now = Instant::now();
        self.free_at = self.free_at.max(now) + frame;
        let ahead = self.free_at.saturating_duration_since(now);
        if ahead > SLACK {
            std::thread::sleep(ahead - SLACK / 2);
        }
    }
}

/// Holds the sender to `speed_factor` × real time (0 = as fast as the bus allows).
#[derive(Debug)]
pub struct SampleClock {
    start: Instant,
    speed_factor: f64,
    sample_rate_hz: f64,
}

impl SampleClock {
    pub fn new(speed_factor: f64, sample_rate_hz: f64) -> SampleClock {
        SampleClock {
            start: Instant::now(),
            speed_factor,
            sample_rate_hz,
        }
    }

    /// Sleeps until sample `index` is due.
    pub fn wait_for_sample(&self, index: u64) {
        if self.speed_factor <= 0.0 || self.sample_rate_hz <= 0.0 {
            return;
        }
        let due = self.start
            + Duration::from_secs_f64(index as f64 / self.sample_rate_hz / self.speed_factor);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_times_match_the_documented_bus_load() {
        // docs/WIRE_FORMAT.md: classic 8-byte frames 111..=135 bits, FD 64-byte frames about
        // 29 nominal bits and 545..=650 data-phase bits.
        assert_eq!(frame_bits(8, false).0, 135);
        let (nominal, data) = frame_bits(64, true);
        assert!((29..=35).contains(&nominal));
        assert!((545..=700).contains(&data), "{data}");
        let pacer = BusPacer::new(1_000_000, 5_000_000);
        let fd = pacer.frame_time(64, true).as_secs_f64();
        assert!(fd > 1.0 / 7_200.0 && fd < 1.0 / 5_500.0, "{fd}");
    }
}
