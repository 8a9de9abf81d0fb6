//! `bearingd alerts`: prints the daemon's active alerts, then each alert as it comes.
//!
//! It finds the service the way the daemon does: from the daemon's config
//! (`outputs.alerts_service` under `outputs.iceoryx2_root`), or, without one, from the
//! embedded default's data directory (`bearingd run` without `--config`). Lost alerts (this
//! subscriber fell behind), daemon restarts and untrusted sequence numbers are printed, never
//! passed over.
//!
//! It runs as the daemon's user and checks that the root, the service and its publisher are
//! that user's (`sinks::alerts::verify`); it never changes its own user (issue 32: it used to
//! become the owner of the root directory, whoever made it). Root is told to use `runuser`.

use super::format::FormatOrJsonArg;
use super::run::embedded_config;
use super::CliError;
use crate::clock::wall_clock_now_ns;
use crate::config;
use crate::fsafe::effective_uid;
use crate::iox::IoxSettings;
use crate::messages::{FaultKind, FlagLevel};
use crate::report::plain::flag_words;
use crate::sinks::alerts::payload::AlertDecodeError;
use crate::sinks::alerts::service::{AlertServiceSettings, AlertSubscriber, Received};
use crate::sinks::alerts::AlertError;
use crate::sinks::alerts::{Alert, AlertState, AlertView};
use clap::Args;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct AlertsArgs {
    /// The daemon's config file (for its alert service and iceoryx2 root); without it, those
    /// of `bearingd run` without a config.
    #[arg(long, conflicts_with = "data_dir")]
    config: Option<PathBuf>,
    /// The `--data-dir` of a `bearingd run` without a config (default ./bearingd-data).
    #[arg(long)]
    data_dir: Option<PathBuf>,
    // With json, one JSON object per line instead of text.
    #[command(flatten)]
    format: FormatOrJsonArg,
    /// Exit after this many alerts (the active alerts printed at start count).
    #[arg(long)]
    count: Option<u64>,
    /// Stop after this many seconds; with --count, an exit status of 1 if fewer came.
    #[arg(long)]
    timeout: Option<f64>,
}

/// How long history takes to arrive after subscribing: the daemon's publisher hands it over
/// within its connection period (50 ms); this leaves room for a busy machine.
const HISTORY_WAIT: Duration = Duration::from_millis(400);

pub fn run(args: &AlertsArgs) -> Result<(), CliError> {
    let config = match &args.config {
        Some(path) => config::load(path).map_err(CliError::input)?,
        None => embedded_config(args.data_dir.as_deref())?,
    };
    let settings = AlertServiceSettings {
        service: config.outputs.alerts_service.clone(),
        iox: IoxSettings::with_root(&config.outputs.iceoryx2_root),
    };
    if let Some(t) = args.timeout {
        if !(t.is_finite() && t >= 0.0) {
            return Err(CliError::input(format!(
                "--timeout {t}: give a number of seconds ≥ 0, e.g. --timeout 60"
            )));
        }
    }
    let deadline = args
        .timeout
        .map(|t| Instant::now() + Duration::from_secs_f64(t));
    let left = || deadline.map(|d| d.saturating_duration_since(Instant::now()));
    let mut printer = Printer {
        json: args.format.json(),
        printed: 0,
    };

    let mut subscriber = open_when_available(&settings, &looked_for(args), &left)?;
    let subscribed_at_ns = wall_clock_now_ns();
    // The history: the alerts active when we subscribed. An alert of a block completed after
    // that came live while the history was read: it is printed as live, after the active ones
    // (else a daemon quick to raise and clear would have both folded away unseen).
    let mut active: BTreeMap<(String, String, u8), Alert> = BTreeMap::new();
    let mut came_live = Vec::new();
    for received in subscriber
        .take_history(HISTORY_WAIT)
        .map_err(CliError::input)?
    {
        match received {
            Received::Alert(alert) if alert.wall_time_ns > subscribed_at_ns => {
                came_live.push(alert);
            }
            Received::Alert(alert) => {
                let view = match alert.view() {
                    Ok(view) => view,
                    Err(e) => {
                        printer.problem(&alert, &e);
                        continue;
                    }
                };
                let key = (view.sensor, view.axis, alert.fault);
                if view.state == AlertState::Cleared {
                    active.remove(&key);
                } else {
                    active.insert(key, alert);
                }
            }
            other => printer.event(&other),
        }
    }
    if !args.format.json() {
        println!(
            "{} active alert(s) on {} (history of {})",
            active.len(),
            settings.service,
            subscriber.history_size
        );
    }
    for alert in active.values() {
        printer.alert(alert, true);
        if printer.done(args.count) {
            return Ok(());
        }
    }
    for alert in &came_live {
        printer.alert(alert, false);
        if printer.done(args.count) {
            return Ok(());
        }
    }
    loop {
        let wait = left().unwrap_or(Duration::from_secs(3600));
        if wait.is_zero() {
            break;
        }
        match subscriber.next(wait).map_err(CliError::input)? {
            Some(Received::Alert(alert)) => {
                printer.alert(&alert, false);
                if printer.done(args.count) {
                    return Ok(());
                }
            }
            Some(other) => printer.event(&other),
            None => {}
        }
    }
    match args.count {
        Some(count) => Err(CliError::failure(format!(
            "{} of {count} alert(s) arrived within --timeout {} s",
            printer.printed,
            args.timeout.unwrap_or(0.0)
        ))),
        None => Ok(()),
    }
}

/// Opens the service, waiting for the daemon to create it (until the deadline, if any). It
/// waits only while the root or the service is missing: a service or root that fails the
/// owner checks is exit 2 at once.
fn open_when_available(
    settings: &AlertServiceSettings,
    looked_for: &str,
    left: &impl Fn() -> Option<Duration>,
) -> Result<AlertSubscriber, CliError> {
    let uid = effective_uid();
    let mut said = false;
    loop {
        match AlertSubscriber::open(settings, uid) {
            Ok(subscriber) => return Ok(subscriber),
            Err(e @ AlertError::Untrusted { .. }) => {
                return Err(CliError::input(match root_owner(settings) {
                    Some(owner) if uid == 0 && owner != 0 => format!(
                        "{e}. The alert service belongs to uid {owner}; iceoryx2 delivers only to \
                         subscribers of that user, and bearingd alerts never changes its user by \
                         itself: run `runuser -u <user of uid {owner}> -- bearingd alerts ...` \
                         (under systemd: runuser -u bearingd -- bearingd alerts ...)"
                    ),
                    _ => e.to_string(),
                }))
            }
            Err(e) => {
                if left().is_some_and(|l| l.is_zero()) {
                    return Err(CliError::failure(format!("{e}; {looked_for}")));
                }
                if !said {
                    eprintln!("bearingd alerts: waiting for the daemon: {e}; {looked_for}");
                    said = true;
                }
                std::thread::sleep(
                    left()
                        .unwrap_or(Duration::from_secs(1))
                        .min(Duration::from_millis(500)),
                );
            }
        }
    }
}

/// Which daemon the alert service was looked for, and how to point at another: a daemon
/// without a config keeps its iceoryx2 root by its data directory, so one started from another
/// directory is not found from here.
fn looked_for(args: &AlertsArgs) -> String {
    let whence = match (&args.config, &args.data_dir) {
        (Some(config), _) => format!("the daemon of --config {}", config.display()),
        (None, given) => {
            let dir = given.clone().unwrap_or_else(|| "bearingd-data".into());
            let absolute = std::path::absolute(&dir).unwrap_or(dir);
            format!(
                "the daemon of `bearingd run` without a config and with the data dir {}{}",
                absolute.display(),
                if given.is_none() {
                    " (the default ./bearingd-data, from this directory)"
                } else {
                    ""
                }
            )
        }
    };
    format!(
        "looked for {whence}; for another, give its --data-dir DIR (as given to `bearingd run`) \
         or its --config FILE (a service: --config /etc/bearingd/bearingd.toml)"
    )
}

/// The owner of the iceoryx2 root (not following a link), if it can be looked at.
fn root_owner(settings: &AlertServiceSettings) -> Option<u32> {
    use std::os::unix::fs::MetadataExt;
    let root = settings.iox.root_path.as_deref()?;
    std::fs::symlink_metadata(root).ok().map(|m| m.uid())
}

/// What a bearing fault's alert means for the technician (`None` for the velocity zone's,
/// whose line already says it in ISO terms).
fn plain_words(view: &AlertView) -> Option<String> {
    let fault = FaultKind::ALL
        .into_iter()
        .find(|k| k.name() == view.fault)?;
    let level = |name: &str| FlagLevel::ALL.into_iter().find(|l| l.name() == name);
    Some(flag_words(
        fault,
        level(view.previous_severity)?,
        level(view.severity)?,
    ))
}

struct Printer {
    json: bool,
    printed: u64,
}

impl Printer {
    fn done(&self, count: Option<u64>) -> bool {
        count.is_some_and(|c| self.printed >= c)
    }

    fn alert(&mut self, alert: &Alert, active_at_start: bool) {
        let view = match alert.view() {
            Ok(view) => view,
            Err(e) => return self.problem(alert, &e),
        };
        self.printed += 1;
        if self.json {
            let mut value = serde_json::to_value(&view).unwrap_or_default();
            if let Some(object) = value.as_object_mut() {
                object.insert("type".into(), "alert".into());
                object.insert("active_at_start".into(), active_at_start.into());
                object.insert("received_wall_ns".into(), wall_clock_now_ns().into());
            }
            println!("{value}");
        } else {
            let prefix = if active_at_start { "ACTIVE" } else { "ALERT " };
            match plain_words(&view) {
                Some(words) => println!("{prefix} {} — {words}", view.line()),
                None => println!("{prefix} {}", view.line()),
            }
        }
    }

    fn problem(&self, alert: &Alert, error: &AlertDecodeError) {
        eprintln!(
            "bearingd alerts: cannot read alert #{}: {error}",
            alert.sequence
        );
    }

    fn event(&self, event: &Received) {
        let (json, text) = match event {
            Received::Lost {
                run_id,
                first,
                last,
            } => (
                serde_json::json!({"type": "lost", "run_id": run_id, "first": first, "last": last}),
                format!(
                    "LOST alerts #{first}..#{last}: this subscriber fell behind and the daemon's \
                     buffer overwrote them (see the MCAP log's /flags topics for what they were)"
                ),
            ),
            Received::NewRun { run_id } => (
                serde_json::json!({"type": "new_run", "run_id": run_id}),
                format!("the daemon restarted (run {run_id}); alert numbers start again"),
            ),
            Received::Untrusted {
                run_id,
                sequence,
                expected,
            } => (
                serde_json::json!({"type": "untrusted", "run_id": run_id, "sequence": sequence, "expected": expected}),
                format!(
                    "UNTRUSTED alert #{sequence} of run {run_id}: #{expected} was next and no \
                     overflow explains the jump (forged or corrupt?); not shown, numbering kept"
                ),
            ),
            Received::Alert(_) => return,
        };
        if self.json {
            println!("{json}");
        } else {
            eprintln!("bearingd alerts: {text}");
        }
    }
}
