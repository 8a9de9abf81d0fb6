//! systemd's notify protocol (`sd_notify`), written by hand: `READY=1`, `STATUS=…`,
//! `WATCHDOG=1`, `STOPPING=1`.
//!
//! Ours stays, not the `sd-notify` crate (0.5): it reads `$NOTIFY_SOCKET` only from the
//! environment (tests would have to mutate it), cannot reach abstract `@name` sockets, and sends
//! blocking on a new socket per call; the protocol is one non-blocking datagram, a few lines here.
//!
//! Rules kept here:
//! - Without `$NOTIFY_SOCKET` every call is a no-op, so `bearingd run` in a terminal, in tests
//!   and under other supervisors behaves exactly as before.
//! - Notification never stops or slows the daemon: the socket is non-blocking, and the first
//!   failure is returned once (the daemon reports it in the journal), later ones are only
//!   counted.
//! - The watchdog interval comes from `$WATCHDOG_USEC`; when `$WATCHDOG_PID` is set it must be
//!   our pid (the variables may have been inherited from a parent that is supervised itself).
//! - [`keep_alive`] pings the watchdog only while the caller says the pipeline is alive; the
//!   rule for "alive" belongs to the caller (see `daemon/run.rs`), the timing belongs here.
//! - [`status_text`]: the one-line `STATUS=` shown by `systemctl status`.

use crate::pipeline::ChannelStatus;
use std::os::unix::net::{SocketAddr, UnixDatagram};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

/// Why a notification could not be sent (reported once; the daemon goes on without).
#[derive(Debug, thiserror::Error)]
pub enum NotifyError {
    #[error("NOTIFY_SOCKET={socket}: cannot use it ({source}); no systemd notifications")]
    Socket {
        socket: String,
        source: std::io::Error,
    },
    #[error("cannot notify systemd ({0}); the daemon goes on, later failures are not reported")]
    Send(std::io::Error),
}

/// Where notifications go, if anywhere, and the watchdog interval systemd asked for.
#[derive(Debug)]
pub struct Notifier {
    target: Option<(UnixDatagram, SocketAddr)>,
    watchdog: Option<Duration>,
    /// Whether a failure has been reported already (later ones are only counted).
    warned: AtomicBool,
    failures: AtomicU64,
}

impl Notifier {
    /// The notifier systemd set up for this process through its environment; a no-op one when
    /// `$NOTIFY_SOCKET` is unset or unusable (then with the reason).
    pub fn from_env() -> (Notifier, Option<NotifyError>) {
        let socket = std::env::var_os("NOTIFY_SOCKET");
        let usec = std::env::var("WATCHDOG_USEC").ok();
        let pid = std::env::var("WATCHDOG_PID").ok();
        Notifier::from_parts(
            socket.as_ref().and_then(|s| s.to_str()),
            usec.as_deref(),
            pid.as_deref(),
            std::process::id(),
        )
    }

    /// A notifier from the three variables' values and our pid (separate from the environment
    /// so tests need not mutate it); with the reason when the socket is set but unusable.
    pub fn from_parts(
        notify_socket: Option<&str>,
        watchdog_usec: Option<&str>,
        watchdog_pid: Option<&str>,
        our_pid: u32,
    ) -> (Notifier, Option<NotifyError>) {
        let mut problem = None;
        let target = notify_socket
            .filter(|s| !s.is_empty())
            .and_then(|s| match open(s) {
                Ok(target) => Some(target),
                Err(source) => {
                    problem = Some(NotifyError::Socket {
                        socket: s.to_string(),
                        source,
                    });
                    None
                }
            });
        let for_us = watchdog_pid.is_none_or(|p| p.trim().parse::<u32>() == Ok(our_pid));
        let watchdog = watchdog_usec
            .and_then(|u| u.trim().parse::<u64>().ok())
            .filter(|&u| u > 0 && for_us)
            .map(Duration::from_micros);
        let notifier = Notifier {
            target,
            watchdog,
            warned: AtomicBool::new(false),
            failures: AtomicU64::new(0),
        };
        (notifier, problem)
    }

    /// A notifier that sends nothing.
    pub fn disabled() -> Notifier {
        Notifier::from_parts(None, None, None, 0).0
    }

    /// Whether notifications go anywhere.
    pub fn is_enabled(&self) -> bool {
        self.target.is_some()
    }

    /// The watchdog interval systemd enforces (`WatchdogSec=`), if any and if meant for us.
    pub fn watchdog_interval(&self) -> Option<Duration> {
        self.watchdog.filter(|_| self.is_enabled())
    }

    /// Start-up is complete: `Type=notify` units become active now.
    pub fn ready(&self) -> Result<(), NotifyError> {
        self.send("READY=1")
    }

    /// A one-line status shown by `systemctl status`. Line breaks are replaced, since a newline
    /// would start another assignment in the datagram.
    pub fn status(&self, text: &str) -> Result<(), NotifyError> {
        let line: String = text
            .chars()
            .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
            .collect();
        self.send(&format!("STATUS={line}"))
    }

    /// Resets systemd's watchdog timer.
    pub fn watchdog(&self) -> Result<(), NotifyError> {
        self.send("WATCHDOG=1")
    }

    /// Shutdown has begun.
    pub fn stopping(&self) -> Result<(), NotifyError> {
        self.send("STOPPING=1")
    }

    /// How many notifications could not be sent.
    pub fn failures(&self) -> u64 {
        self.failures.load(Ordering::Relaxed)
    }

    /// Sends one datagram. The first failure is returned; later ones are only counted
    /// ([`failures`](Self::failures)), so the caller reports a broken socket once.
    pub fn send(&self, message: &str) -> Result<(), NotifyError> {
        let Some((socket, address)) = &self.target else {
            return Ok(());
        };
        match socket.send_to_addr(message.as_bytes(), address) {
            Ok(_) => Ok(()),
            Err(e) => {
                self.failures.fetch_add(1, Ordering::Relaxed);
                if self.warned.swap(true, Ordering::Relaxed) {
                    Ok(())
                } else {
                    Err(NotifyError::Send(e))
                }
            }
        }
    }
}

/// An unbound, non-blocking datagram socket and the address `NOTIFY_SOCKET` names.
fn open(name: &str) -> std::io::Result<(UnixDatagram, SocketAddr)> {
    let address = match name.strip_prefix('@') {
        Some(abstract_name) => {
            use std::os::linux::net::SocketAddrExt;
            SocketAddr::from_abstract_name(abstract_name.as_bytes())?
        }
        None if name.starts_with('/') => SocketAddr::from_pathname(name)?,
        None => {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "neither an absolute path nor an abstract name starting with '@'",
            ))
        }
    };
    let socket = UnixDatagram::unbound()?;
    // A full receive queue at systemd must not stall the daemon: drop the datagram instead.
    socket.set_nonblocking(true)?;
    Ok((socket, address))
}

/// Sends `STATUS=` every `status_every` and `WATCHDOG=1` every half watchdog interval while
/// `alive()` says the pipeline made progress (or has nothing to do); the first failure goes to
/// `problem`. Never resolves; with no notify socket it only waits.
///
/// When `alive()` says no, the ping is skipped: if that lasts for the whole watchdog interval,
/// systemd kills and (with `Restart=on-failure`) restarts the daemon, which is the point.
pub async fn keep_alive(
    notifier: &Notifier,
    status_every: Duration,
    mut status: impl FnMut() -> String,
    mut alive: impl FnMut() -> bool,
    mut problem: impl FnMut(NotifyError),
) {
    if !notifier.is_enabled() {
        return std::future::pending().await;
    }
    let mut status_ticker = tokio::time::interval(status_every.max(Duration::from_millis(100)));
    status_ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    // Half the interval, as sd_watchdog_enabled(3) recommends; a day when there is no watchdog,
    // so the branch below never fires in practice.
    let half = notifier
        .watchdog_interval()
        .map(|w| (w / 2).max(Duration::from_millis(10)));
    let mut watchdog_ticker = tokio::time::interval(half.unwrap_or(Duration::from_secs(24 * 3600)));
    watchdog_ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        let sent = tokio::select! {
            _ = status_ticker.tick() => notifier.status(&status()),
            _ = watchdog_ticker.tick() => {
                if half.is_some() && alive() {
                    notifier.watchdog()
                } else {
                    Ok(())
                }
            }
        };
        if let Err(e) = sent {
            problem(e);
        }
    }
}

/// The one-line `STATUS=` for systemd (`systemctl status`): channel count, then per channel its
/// sample time, health stage and raised flags; shorter than the command line's status lines.
pub fn status_text(board: &[ChannelStatus]) -> String {
    let channels: Vec<String> = board
        .iter()
        .map(|s| {
            let lost = if s.sensor_lost { " SENSOR LOST" } else { "" };
            format!(
                "{} t={:.1}s {} {}{lost}",
                s.channel,
                s.seconds,
                s.stage,
                s.flags_summary()
            )
        })
        .collect();
    let plural = if board.len() == 1 { "" } else { "s" };
    format!("{} channel{plural}; {}", board.len(), channels.join("; "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unset_socket_is_a_no_op() {
        let notifier = Notifier::from_parts(None, Some("30000000"), None, 1).0;
        assert!(!notifier.is_enabled());
        assert_eq!(notifier.watchdog_interval(), None);
        let _ = notifier.ready();
        assert_eq!(notifier.failures(), 0);
    }

    #[test]
    fn relative_path_is_refused() {
        let notifier = Notifier::from_parts(Some("relative/sock"), None, None, 1).0;
        assert!(!notifier.is_enabled());
    }

    #[test]
    fn abstract_socket_receives_every_message() -> std::io::Result<()> {
        use std::os::linux::net::SocketAddrExt;
        let name = format!("bearingd-notify-test-{}", std::process::id());
        let listener = UnixDatagram::bind_addr(&SocketAddr::from_abstract_name(name.as_bytes())?)?;
        listener.set_read_timeout(Some(Duration::from_secs(5)))?;
        let pid = std::process::id();
        let notifier = Notifier::from_parts(
            Some(&format!("@{name}")),
            Some("2000000"),
            Some(&pid.to_string()),
            pid,
        )
        .0;
        assert!(notifier.is_enabled());
        assert_eq!(notifier.watchdog_interval(), Some(Duration::from_secs(2)));
        let _ = notifier.ready();
        let _ = notifier.status("1 channel;\nmotor-de/radial ok");
        let _ = notifier.watchdog();
        let _ = notifier.stopping();
        let mut received = Vec::new();
        let mut buffer = [0u8; 4096];
        for _ in 0..4 {
            let n = listener.recv(&mut buffer)?;
            received.push(String::from_utf8_lossy(&buffer[..n]).into_owned());
        }
        assert_eq!(
            received,
            [
                "READY=1",
                "STATUS=1 channel; motor-de/radial ok",
                "WATCHDOG=1",
                "STOPPING=1"
            ]
        );
        assert_eq!(notifier.failures(), 0);
        Ok(())
    }

    #[test]
    fn watchdog_for_another_pid_is_ignored() {
        let notifier = Notifier::from_parts(Some("@x"), Some("2000000"), Some("1"), 2).0;
        assert!(notifier.is_enabled());
        assert_eq!(notifier.watchdog_interval(), None);
    }

    #[test]
    fn missing_listener_is_counted_not_fatal() {
        let path = std::env::temp_dir().join(format!("bearingd-no-such-{}", std::process::id()));
        let notifier = Notifier::from_parts(path.to_str(), None, None, 1).0;
        let _ = notifier.ready();
        let _ = notifier.ready();
        assert_eq!(notifier.failures(), 2);
    }
}
