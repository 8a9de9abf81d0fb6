//! The sinks of a run, assembled in one place for `bearingd run` and `bearingd replay`: which
//! sinks a config gets, in which order they start, and which are called at once on the
//! analysis thread rather than behind the sink queue.
//!
//! Order of start: the alert service first, then the fleet bridge, the MCAP log last, so that
//! a start refused by the first two leaves no log file behind (one per restart, issue 32).
//!
//! A new sink: implement [`Sink`], add it in [`assemble`].

use super::events::{DaemonEvent, Events};
use crate::analysis::health::Baseline;
use crate::config::Config;
use crate::mcap_log::McapLogError;
use crate::messages::ChannelId;
use crate::pipeline::Sink;
use crate::sinks::alerts::SummarySlot;
use crate::sinks::fleet::bridge::BridgeError;
use crate::sinks::fleet::FleetSink;
use crate::sinks::mcap::McapSink;
use std::collections::BTreeMap;

/// Which sinks to assemble beyond the MCAP log, which every run and replay writes.
pub struct SinkPlan {
    /// The iceoryx2 alert publisher (without the `shm` feature: said, and left out).
    pub alerts: bool,
    /// The fleet bridge, when the config has `[fleet]`.
    pub fleet: bool,
    /// The caller's own sinks (the command line's printers), queued before the log.
    pub extra: Vec<Box<dyn Sink>>,
}

impl SinkPlan {
    /// `bearingd run`: alerts, fleet bridge, log, and `extra`.
    pub fn run(extra: Vec<Box<dyn Sink>>) -> SinkPlan {
        SinkPlan {
            alerts: true,
            fleet: true,
            extra,
        }
    }

    /// `bearingd replay`: the log and `extra`; nothing leaves the box (the live run already
    /// published its alerts and metrics).
    pub fn replay(extra: Vec<Box<dyn Sink>>) -> SinkPlan {
        SinkPlan {
            alerts: false,
            fleet: false,
            extra,
        }
    }
}

/// What the sinks need to know of the run they serve.
#[derive(Debug, Clone, Copy)]
pub struct SinkStart<'a> {
    /// The run's id (the log's metadata; the pipeline's alerts carry the same).
    pub run_id: u64,
    /// Wall-clock time of sample 0, ns since the epoch: the log's time base and the fleet
    /// bridge's.
    pub origin_ns: u64,
    /// The health baselines the run starts with (recorded in the log).
    pub baselines: &'a BTreeMap<ChannelId, Baseline>,
}

/// The assembled sinks.
pub struct Sinks {
    /// Called on the analysis thread as each input's outputs come, before they go to the sink
    /// queue: the alert publisher (an alert never waits behind the log).
    pub immediate: Vec<Box<dyn Sink>>,
    /// Called on the sink thread, through the bounded sink queue.
    pub queued: Vec<Box<dyn Sink>>,
    /// Where the alert publisher leaves its summary when it finishes (`None`: no publisher).
    pub alerts: Option<SummarySlot>,
}

impl Sinks {
    /// Every sink, immediate ones first: for a caller that runs them all on one thread.
    pub fn all(self) -> Vec<Box<dyn Sink>> {
        self.immediate.into_iter().chain(self.queued).collect()
    }
}

/// Why the sinks could not start.
#[derive(Debug, thiserror::Error)]
pub enum SinkStartError {
    #[error("MCAP log: {0}")]
    Log(#[from] McapLogError),
    #[cfg(feature = "shm")]
    #[error("alerts: {0}")]
    Alerts(#[from] crate::sinks::alerts::AlertError),
    #[error("fleet bridge: {0}")]
    Fleet(#[from] BridgeError),
}

impl From<SinkStartError> for crate::pipeline::SinkError {
    /// For a caller whose sinks are opened during the run (the replay's, per run).
    fn from(e: SinkStartError) -> Self {
        let (sink, first): (&'static str, Box<dyn std::error::Error + Send + Sync>) = match e {
            SinkStartError::Log(e) => ("MCAP log", Box::new(e)),
            #[cfg(feature = "shm")]
            SinkStartError::Alerts(e) => ("alerts", Box::new(e)),
            SinkStartError::Fleet(e) => ("fleet bridge", Box::new(e)),
        };
        crate::pipeline::SinkError {
            sink,
            count: 1,
            first,
        }
    }
}

/// Starts the sinks `plan` asks for with `config`'s settings, for the run `start`; what the
/// operator should know (the alert service, crash recovery, where the log goes) goes to
/// `events`.
pub fn assemble(
    config: &Config,
    plan: SinkPlan,
    start: &SinkStart<'_>,
    events: &Events,
) -> Result<Sinks, SinkStartError> {
    let mut sinks = Sinks {
        immediate: Vec::new(),
        queued: plan.extra,
        alerts: None,
    };
    if plan.alerts {
        if let Some((alerts, summary)) = start_alerts(config, events)? {
            sinks.alerts = Some(summary);
            sinks.immediate.push(alerts);
        }
    }
    let fleet = if plan.fleet {
        start_fleet(config, start.origin_ns, events)?
    } else {
        None
    };
    sinks
        .queued
        .push(Box::new(open_log(config, start, events)?));
    sinks
        .queued
        .extend(fleet.map(|fleet| Box::new(fleet) as Box<dyn Sink>));
    Ok(sinks)
}

/// Recovers what a crash left in the log directory and opens the log, sample 0 at
/// `start.origin_ns`, the run starting with `start.baselines`.
fn open_log(
    config: &Config,
    start: &SinkStart<'_>,
    events: &Events,
) -> Result<McapSink, McapLogError> {
    let (log, recovered) =
        McapSink::for_run(config, start.origin_ns, start.run_id, start.baselines)?;
    let log = {
        let events = events.clone();
        log.on_notice(move |notice| events(DaemonEvent::Log(notice.clone())))
    };
    for report in recovered {
        events(DaemonEvent::Recovered(report));
    }
    if let Some(path) = log.current_path() {
        events(DaemonEvent::LoggingTo(path.to_path_buf()));
    }
    Ok(log)
}

/// The fleet bridge of `[fleet]`, when it is on; its notices become [`DaemonEvent::Fleet`].
fn start_fleet(
    config: &Config,
    origin_ns: u64,
    events: &Events,
) -> Result<Option<FleetSink>, BridgeError> {
    let events = events.clone();
    let notices = std::sync::Arc::new(move |line| events(DaemonEvent::Fleet(line)));
    FleetSink::start(config, origin_ns, notices)
}

/// The publisher of a run and where it leaves its summary.
type AlertsStarted = Option<(Box<dyn Sink>, SummarySlot)>;

/// The alert service `outputs.alerts_service` under `outputs.iceoryx2_root`; its refused
/// alerts become [`DaemonEvent::AlertFailed`].
#[cfg(feature = "shm")]
fn start_alerts(config: &Config, events: &Events) -> Result<AlertsStarted, SinkStartError> {
    let iox = crate::iox::IoxSettings::with_root(&config.outputs.iceoryx2_root);
    // What a killed bearingd (or a killed publisher) left under this root, removed and said
    // before this one creates its nodes.
    match crate::iox::remove_dead_nodes(&iox) {
        Ok(dead) => {
            for node in dead {
                events(DaemonEvent::DeadIoxNode {
                    root: config.outputs.iceoryx2_root.clone(),
                    node,
                });
            }
        }
        Err(e) => events(DaemonEvent::DeadIoxNodesUnknown(e.to_string())),
    }
    let failed = events.clone();
    let alerts = crate::sinks::alerts::AlertSink::start(config, iox, move |e| {
        failed(DaemonEvent::AlertFailed(e))
    })?;
    events(DaemonEvent::AlertsOn {
        service: config.outputs.alerts_service.clone(),
        root: config.outputs.iceoryx2_root.clone(),
        reopened: alerts.reopened(),
    });
    let summary = alerts.summary();
    Ok(Some((Box::new(alerts), summary)))
}

/// Without iceoryx2 (the `shm` feature) there is no alert service; flags still go to the log.
#[cfg(not(feature = "shm"))]
fn start_alerts(_config: &Config, events: &Events) -> Result<AlertsStarted, SinkStartError> {
    events(DaemonEvent::NoAlertService);
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::daemon::events::kept_events;
    use crate::messages::PipelineMessage;
    use crate::pipeline::SinkError;
    use bearingd_testdata::scratch_dir;
    use std::path::Path;

    /// A caller's sink that takes everything and keeps nothing.
    struct Printer;

    impl Sink for Printer {
        fn write(&mut self, _: &PipelineMessage) {}
        fn finish(&mut self) -> Result<(), SinkError> {
            Ok(())
        }
    }

    /// The embedded default with its data and iceoryx2 root under `dir`, and a `[fleet]`
    /// section whose broker listens nowhere.
    fn config_in(dir: &Path) -> Config {
        let mut config = Config::default_embedded().unwrap();
        config.outputs.mcap_dir = dir.join("mcap");
        config.outputs.state_dir = dir.join("state");
        config.outputs.iceoryx2_root = dir.join("iox");
        let fleet = crate::config::FleetConfig::for_broker(
            "mqtt://127.0.0.1:1",
            "unit",
            &config.outputs.state_dir,
        )
        .unwrap();
        config.fleet = Some(fleet);
        config
    }

    fn log_files(config: &Config) -> usize {
        std::fs::read_dir(&config.outputs.mcap_dir).map_or(0, |entries| {
            entries
                .filter(|e| {
                    e.as_ref()
                        .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "mcap"))
                })
                .count()
        })
    }

    fn finish(sinks: Vec<Box<dyn Sink>>) {
        for mut sink in sinks {
            sink.finish().unwrap();
        }
    }

    const NO_BASELINES: &BTreeMap<ChannelId, Baseline> = &BTreeMap::new();

    fn start() -> SinkStart<'static> {
        SinkStart {
            run_id: 5,
            origin_ns: 1_700_000_000_000_000_000,
            baselines: NO_BASELINES,
        }
    }

    #[test]
    fn a_replay_gets_the_callers_sinks_and_the_log_and_nothing_that_leaves_the_box() {
        let config = config_in(&scratch_dir("assemble-replay"));
        let (events, said) = kept_events();
        let sinks = assemble(
            &config,
            SinkPlan::replay(vec![Box::new(Printer)]),
            &start(),
            &events,
        )
        .unwrap();
        assert!(sinks.immediate.is_empty() && sinks.alerts.is_none());
        assert_eq!(sinks.queued.len(), 2, "the printer and the log");
        assert_eq!(log_files(&config), 1);
        let said = said.lock().unwrap().join("\n");
        assert!(said.contains("LoggingTo"), "{said}");
        assert!(!said.contains("Fleet") && !said.contains("Alert"), "{said}");
        finish(sinks.all());
    }

    #[test]
    fn a_run_gets_the_alert_publisher_at_once_and_the_log_and_bridge_behind_the_queue() {
        let config = config_in(&scratch_dir("assemble-run"));
        let (events, said) = kept_events();
        let sinks = assemble(
            &config,
            SinkPlan::run(vec![Box::new(Printer)]),
            &start(),
            &events,
        )
        .unwrap();
        assert_eq!(
            sinks.queued.len(),
            3,
            "the printer, the log and the fleet bridge"
        );
        assert_eq!(log_files(&config), 1);
        let said = said.lock().unwrap().join("\n");
        assert!(
            said.contains("Fleet(\"fleet: publishing 1 channel(s)"),
            "{said}"
        );
        #[cfg(feature = "shm")]
        {
            assert_eq!(sinks.immediate.len(), 1, "the alert publisher");
            assert!(said.contains("AlertsOn"), "{said}");
            let summary = sinks.alerts.clone().unwrap();
            assert_eq!(summary.get(), None, "not before it finishes");
            finish(sinks.all());
            assert_eq!(
                summary.get(),
                Some(&crate::sinks::alerts::PublisherSummary::default())
            );
        }
        #[cfg(not(feature = "shm"))]
        {
            assert!(sinks.immediate.is_empty() && sinks.alerts.is_none());
            assert!(said.contains("NoAlertService"), "{said}");
            finish(sinks.all());
        }
    }

    #[cfg(feature = "shm")]
    #[test]
    fn a_refused_alert_service_stops_the_start_before_the_log_is_opened() {
        let config = config_in(&scratch_dir("assemble-refused"));
        let settings = crate::sinks::alerts::AlertServiceSettings {
            service: config.outputs.alerts_service.clone(),
            iox: crate::iox::IoxSettings::with_root(&config.outputs.iceoryx2_root),
        };
        // Another publisher holds the service's one publisher slot.
        let other = crate::sinks::alerts::AlertPublisher::start(settings, 16).unwrap();
        let (events, _) = kept_events();
        let refused = assemble(&config, SinkPlan::run(Vec::new()), &start(), &events);
        assert!(
            matches!(refused, Err(SinkStartError::Alerts(_))),
            "{:?}",
            refused.err()
        );
        assert_eq!(log_files(&config), 0, "no log file for a refused start");
        other.finish();
    }
}
