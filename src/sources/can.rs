//! SocketCAN source: classic and CAN FD frames from one interface, on tokio.
//!
//! The socket is a tokio `CanFdSocket`, which receives classic and FD frames alike, with a
//! kernel filter for the bearingd id block (`0x100/0x700`) so other traffic on a shared bus is
//! not mistaken for malformed frames. Its receive buffer is raised (default 4 MiB) because a
//! starved reader on SocketCAN loses frames silently in the kernel; such losses still show as
//! exact sequence gaps, but a larger buffer keeps a short stall from becoming one.
//!
//! Frames are read one by one when the socket is quiet and drained in batches of up to
//! [`READ_BATCH`] when it is busy, so the assembler merges a batch into one block per stream.

use super::{
    node_of, Assembler, EventSender, IngestEvent, SilenceWatch, SourceSummary, StatsTimer,
};
use socketcan::tokio::CanFdSocket;
use socketcan::{CanAnyFrame, CanFilter, EmbeddedFrame, Frame, SocketOptions};
use std::future::Future;
use std::io::Write;
use std::time::Duration;
use tokio::time::Instant;

/// Frames read without yielding, at most, when the socket has many waiting.
pub const READ_BATCH: usize = 256;

/// How the CAN source is set up.
pub struct CanSourceConfig {
    /// Interface name, e.g. `can0` or `vcan0`.
    pub interface: String,
    /// A node silent for longer than this is reported lost.
    pub silence_timeout: Duration,
    /// Requested socket receive buffer, bytes (0 = kernel default). Uses `SO_RCVBUFFORCE`
    /// when privileged, else `SO_RCVBUF` (capped by `net.core.rmem_max`).
    pub receive_buffer_bytes: usize,
    /// Writes the first `capture_frames` frames received, in `candump -l` format, to this
    /// writer (for checking what was on the bus with standard tools such as cantools).
    pub capture: Option<Box<dyn Write + Send>>,
    pub capture_frames: usize,
    /// Report the counters ([`IngestEvent::Stats`]) this often and when stopping; `None`: never.
    pub stats_interval: Option<Duration>,
}

/// Why the CAN source could not run.
#[derive(Debug, thiserror::Error)]
pub enum CanSourceError {
    #[error("CAN interface {interface}: cannot open a CAN FD raw socket: {source}; check that it exists and is up (`ip link show {interface}`; a virtual bus for tests: `ip link add {interface} type vcan && ip link set {interface} up`) or name another interface in sensors[].can.interface; nothing was written")]
    Open {
        interface: String,
        source: std::io::Error,
    },
    #[error("CAN interface {interface}: cannot set the receive filter: {source}")]
    Filter {
        interface: String,
        source: std::io::Error,
    },
    #[error("CAN interface {interface}: read failed: {source}")]
    Read {
        interface: String,
        source: std::io::Error,
    },
}

/// Opens the socket now (so a caller can tell a sender it is ready) and returns the source.
pub fn open(config: CanSourceConfig) -> Result<CanSource, CanSourceError> {
    let interface = config.interface.clone();
    let socket = CanFdSocket::open(&interface).map_err(|source| CanSourceError::Open {
        interface: interface.clone(),
        source,
    })?;
    socket
        .set_filters(&[CanFilter::new(
            u32::from(bearing_wire::id::FILTER_ID),
            u32::from(bearing_wire::id::FILTER_MASK),
        )])
        .map_err(|source| CanSourceError::Filter {
            interface: interface.clone(),
            source,
        })?;
    if config.receive_buffer_bytes > 0 {
        let size = i32::try_from(config.receive_buffer_bytes).unwrap_or(i32::MAX);
        let bytes = size.to_ne_bytes();
        // Privileged first (ignores rmem_max); a refusal there is not an error, the plain
        // option then gives what the system allows.
        if socket
            .set_socket_option_bytes(libc::SOL_SOCKET, libc::SO_RCVBUFFORCE, &bytes)
            .is_err()
        {
            let _ = socket.set_socket_option_bytes(libc::SOL_SOCKET, libc::SO_RCVBUF, &bytes);
        }
    }
    Ok(CanSource { config, socket })
}

/// An open CAN source; [`CanSource::run`] reads until shutdown.
pub struct CanSource {
    config: CanSourceConfig,
    socket: CanFdSocket,
}

impl CanSource {
    /// Reads frames and sends events until `shutdown` completes, the event receiver is
    /// dropped, or the socket fails. Returns the counters.
    pub async fn run(
        mut self,
        events: EventSender,
        shutdown: impl Future<Output = ()>,
    ) -> Result<SourceSummary, CanSourceError> {
        let mut assembler = Assembler::new();
        let mut watch = SilenceWatch::new(self.config.silence_timeout);
        let mut out: Vec<IngestEvent> = Vec::with_capacity(64);
        let mut tick = tokio::time::interval((watch.timeout() / 4).max(Duration::from_millis(10)));
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        let mut captured = 0usize;
        let mut stats = StatsTimer::new(self.config.stats_interval);
        tokio::pin!(shutdown);
        loop {
            tokio::select! {
                biased;
                () = &mut shutdown => break,
                read = self.socket.read_frame() => {
                    let frame = read.map_err(|source| CanSourceError::Read {
                        interface: self.config.interface.clone(),
                        source,
                    })?;
                    let now = Instant::now();
                    self.take(&frame, now, &mut assembler, &mut watch, &mut out, &mut captured);
                    for _ in 1..READ_BATCH {
                        match self.socket.try_read_frame() {
                            Ok(frame) => self.take(&frame, now, &mut assembler, &mut watch, &mut out, &mut captured),
                            Err(_) => break,
                        }
                    }
                }
                _ = tick.tick() => watch.check(Instant::now(), &mut assembler, &mut out),
                () = stats.tick() => out.push(IngestEvent::Stats(assembler.stats())),
            }
            for event in out.drain(..) {
                if events.send(event).await.is_err() {
                    return Ok(summary(&assembler));
                }
            }
        }
        if let Some(capture) = self.config.capture.as_mut() {
            let _ = capture.flush();
        }
        if stats.enabled() {
            // The final counters; a consumer already gone needs none.
            let _ = events.send(IngestEvent::Stats(assembler.stats())).await;
        }
        Ok(summary(&assembler))
    }

    fn take(
        &mut self,
        frame: &CanAnyFrame,
        now: Instant,
        assembler: &mut Assembler,
        watch: &mut SilenceWatch,
        out: &mut Vec<IngestEvent>,
        captured: &mut usize,
    ) {
        // Extended ids are not ours even if their number is small: mark them so that `decode`
        // refuses them as unknown.
        let id = if frame.is_extended() {
            frame.raw_id() | 0x8000_0000
        } else {
            frame.raw_id()
        };
        let (bytes, fd): (&[u8], bool) = match frame {
            CanAnyFrame::Normal(f) => (f.data(), false),
            CanAnyFrame::Fd(f) => (f.data(), true),
            CanAnyFrame::Remote(_) | CanAnyFrame::Error(_) => (&[], false),
        };
        if *captured < self.config.capture_frames {
            if let Some(capture) = self.config.capture.as_mut() {
                let _ = writeln!(
                    capture,
                    "{}",
                    candump_line(&self.config.interface, id, bytes, fd)
                );
                *captured += 1;
            }
        }
        if let Some(node) = node_of(id) {
            watch.heard(node, now);
        }
        assembler.push(id, bytes, out);
    }
}

fn summary(assembler: &Assembler) -> SourceSummary {
    SourceSummary {
        stats: assembler.stats(),
        streams: assembler.streams(),
    }
}

/// One frame in `candump -l` log format: `(seconds) iface ID#DATA`, `ID##<flags>DATA` for FD
/// (flags 1 = bit-rate switch). The timestamp is wall-clock time, for people reading the log.
pub fn candump_line(interface: &str, can_id: u32, bytes: &[u8], fd: bool) -> String {
    use std::fmt::Write as _;
    let since_epoch = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default();
    let mut line = format!(
        "({}.{:06}) {interface} {:03X}#",
        since_epoch.as_secs(),
        since_epoch.subsec_micros(),
        can_id & 0x1FFF_FFFF
    );
    if fd {
        line.push_str("#1");
    }
    for byte in bytes {
        let _ = write!(line, "{byte:02X}");
    }
    line
}
