//! `bearingd ingest`: run one source alone and report what arrived ("is my sensor reaching
//! the box?"), with optional expectations for tests and a non-zero exit when one fails.

use super::CliError;
use crate::sources::{IngestEvent, SourceSummary};
use clap::Args;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Duration;
use tokio::sync::{mpsc, oneshot};
use tokio::time::Instant;

/// Events between the source and this command; the source waits when it is full.
const EVENT_CHANNEL: usize = 256;

#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("source").required(true).args(["can", "shm"])))]
pub struct IngestArgs {
    /// Read SocketCAN interface IFACE (classic and FD frames).
    #[arg(long, value_name = "IFACE")]
    can: Option<String>,
    /// Subscribe to iceoryx2 service bearingd/accel/SENSOR.
    #[arg(long, value_name = "SENSOR")]
    shm: Option<String>,
    /// iceoryx2 resource prefix (isolates test runs); default: iceoryx2's.
    #[arg(long)]
    iox_prefix: Option<String>,
    /// iceoryx2 root path; default: iceoryx2's.
    #[arg(long)]
    iox_root: Option<String>,
    /// Stop after this many seconds.
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    /// Stop once nothing arrived for this many seconds (after the first frame).
    #[arg(long, value_name = "S")]
    until_idle: Option<f64>,
    /// A node silent this long is reported lost (ms).
    #[arg(long, default_value_t = 2000)]
    sensor_timeout_ms: u64,
    /// CAN socket receive buffer, bytes.
    #[arg(long, default_value_t = 4 << 20)]
    rcvbuf: usize,
    /// iceoryx2: when the hand-off queue is full, wait (push back into iceoryx2) instead of
    /// dropping the oldest batch.
    #[arg(long)]
    block_when_full: bool,
    /// Write this file once the source is listening.
    #[arg(long)]
    ready_file: Option<PathBuf>,
    /// CAN: write the first --capture-frames frames in candump -l format here ("-": stdout).
    #[arg(long)]
    capture: Option<String>,
    #[arg(long, default_value_t = 1000)]
    capture_frames: usize,
    /// Expect exactly N samples in every stream (node, axis).
    #[arg(long, value_name = "N")]
    expect_samples: Option<u64>,
    /// Expect exactly N streams.
    #[arg(long, value_name = "N")]
    expect_streams: Option<usize>,
    /// Expect exactly N gaps in total.
    #[arg(long, value_name = "N")]
    expect_gaps: Option<u64>,
    /// Expect exactly N malformed frames in total.
    #[arg(long, value_name = "N")]
    expect_malformed: Option<u64>,
    /// Expect exactly N restarts in total (one per restarted stream).
    #[arg(long, value_name = "N")]
    expect_restarts: Option<u64>,
    /// Expect exactly N sensor-lost reports in total (a sender that stops is lost once).
    #[arg(long, value_name = "N")]
    expect_sensor_lost: Option<u64>,
    // With json, the report as JSON.
    #[command(flatten)]
    format: super::format::FormatOrJsonArg,
}

#[derive(Debug, serde::Serialize)]
struct Report {
    source: String,
    wall_seconds: f64,
    samples_per_second: f64,
    summary: SourceSummary,
    /// Blocks whose first sample did not continue the stream without a gap or restart event
    /// in between (must be 0: a gap is never bridged silently).
    unannounced_discontinuities: u64,
    failures: Vec<String>,
}

pub fn run(args: &IngestArgs) -> Result<(), CliError> {
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| CliError::failure(format!("cannot start the async runtime: {e}")))?;
    let report = runtime.block_on(ingest(args))?;
    if args.format.json() {
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| CliError::failure(format!("report: {e}")))?;
        println!("{text}");
    } else {
        print_text(&report);
    }
    if report.failures.is_empty() {
        println!("INGEST RESULT: PASS");
        Ok(())
    } else {
        println!("INGEST RESULT: FAIL");
        Err(CliError::failure(report.failures.join("; ")))
    }
}

async fn ingest(args: &IngestArgs) -> Result<Report, CliError> {
    let (events_tx, mut events_rx) = mpsc::channel::<IngestEvent>(EVENT_CHANNEL);
    let (stop_tx, stop_rx) = oneshot::channel::<()>();
    let shutdown = async move {
        let _ = stop_rx.await;
    };
    let timeout = Duration::from_millis(args.sensor_timeout_ms);
    let (name, source) = start_source(args, timeout, events_tx, shutdown)?;
    if let Some(path) = &args.ready_file {
        std::fs::write(path, b"ready\n")
            .map_err(|e| CliError::input(format!("{}: cannot write: {e}", path.display())))?;
    }
    let started = Instant::now();
    let deadline = args
        .duration
        .map(|s| started + Duration::from_secs_f64(s.max(0.0)));
    let idle = args.until_idle.map(|s| Duration::from_secs_f64(s.max(0.0)));
    let mut first_event: Option<Instant> = None;
    let mut last_event = started;
    let mut last_block = started;
    let mut stop_tx = Some(stop_tx);
    // Where each stream's next block must start unless a gap or restart is announced.
    let mut expected_next: BTreeMap<(u8, u8), u64> = BTreeMap::new();
    let mut discontinuities = 0u64;
    let ctrl_c = tokio::signal::ctrl_c();
    tokio::pin!(ctrl_c);
    loop {
        let check = tokio::time::sleep(Duration::from_millis(50));
        tokio::select! {
            event = events_rx.recv() => {
                let Some(event) = event else { break };
                let now = Instant::now();
                first_event.get_or_insert(now);
                last_event = now;
                match event {
                    IngestEvent::Samples(block) => {
                        // "While data arrived": from the first event to the last sample block
                        // (a sensor-lost report comes a timeout after the data).
                        last_block = now;
                        let key = (block.node, block.axis);
                        if let Some(&next) = expected_next.get(&key) {
                            if next != block.first_sample {
                                discontinuities += 1;
                            }
                        }
                        expected_next.insert(key, block.first_sample + block.samples.len() as u64);
                    }
                    IngestEvent::Gap { node, axis, at_sample, missing_samples, .. } => {
                        expected_next.insert((node, axis), at_sample + missing_samples);
                    }
                    IngestEvent::Restart { node, axis, .. } => {
                        expected_next.remove(&(node, axis));
                    }
                    IngestEvent::SensorLost { node } => {
                        expected_next.retain(|&(n, _), _| n != node);
                    }
                    _ => {}
                }
            }
            _ = &mut ctrl_c => { stop_tx.take().map(|tx| tx.send(())); }
            () = check => {}
        }
        let now = Instant::now();
        let over = deadline.is_some_and(|d| now >= d)
            || (first_event.is_some() && idle.is_some_and(|i| now - last_event >= i));
        if over {
            if let Some(tx) = stop_tx.take() {
                let _ = tx.send(());
            }
        }
    }
    let summary = source
        .await
        .map_err(|e| CliError::failure(format!("source task: {e}")))??;
    let busy = match first_event {
        Some(first) => last_block.saturating_duration_since(first).as_secs_f64(),
        None => 0.0,
    };
    let failures = check_expectations(args, &summary, discontinuities);
    Ok(Report {
        source: name,
        wall_seconds: started.elapsed().as_secs_f64(),
        samples_per_second: if busy > 0.0 {
            summary.stats.samples as f64 / busy
        } else {
            0.0
        },
        summary,
        unannounced_discontinuities: discontinuities,
        failures,
    })
}

type SourceTask = tokio::task::JoinHandle<Result<SourceSummary, CliError>>;

fn start_source(
    args: &IngestArgs,
    timeout: Duration,
    events: mpsc::Sender<IngestEvent>,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(String, SourceTask), CliError> {
    if let Some(interface) = &args.can {
        #[cfg(feature = "can")]
        {
            use crate::sources::can;
            let capture: Option<Box<dyn std::io::Write + Send>> = match args.capture.as_deref() {
                None => None,
                Some("-") => Some(Box::new(std::io::stdout())),
                Some(path) => Some(Box::new(std::io::BufWriter::new(
                    std::fs::File::create(path)
                        .map_err(|e| CliError::input(format!("{path}: cannot create: {e}")))?,
                ))),
            };
            let source = can::open(can::CanSourceConfig {
                interface: interface.clone(),
                silence_timeout: timeout,
                receive_buffer_bytes: args.rcvbuf,
                capture,
                capture_frames: args.capture_frames,
                stats_interval: None,
            })
            .map_err(CliError::input)?;
            let task = tokio::spawn(async move {
                source
                    .run(events, shutdown)
                    .await
                    .map_err(CliError::failure)
            });
            return Ok((format!("can {interface}"), task));
        }
        #[cfg(not(feature = "can"))]
        {
            let _ = (timeout, events, shutdown);
            return Err(CliError::input(format!(
                "--can {interface}: this bearingd was built without the `can` feature"
            )));
        }
    }
    let sensor = args.shm.clone().unwrap_or_default();
    #[cfg(feature = "shm")]
    {
        use crate::sources::{handoff::WhenFull, shm};
        let config = shm::ShmSourceConfig {
            sensor: sensor.clone(),
            iox: crate::iox::IoxSettings {
                prefix: args.iox_prefix.clone(),
                root_path: args.iox_root.clone(),
            },
            silence_timeout: timeout,
            handoff_capacity: 64,
            when_full: if args.block_when_full {
                WhenFull::Block
            } else {
                WhenFull::DropOldest
            },
            stats_interval: None,
        };
        let task = tokio::spawn(async move {
            shm::run(config, events, shutdown)
                .await
                .map_err(CliError::failure)
        });
        Ok((format!("shm bearingd/accel/{sensor}"), task))
    }
    #[cfg(not(feature = "shm"))]
    {
        let _ = (timeout, events, shutdown);
        Err(CliError::input(format!(
            "--shm {sensor}: this bearingd was built without the `shm` feature"
        )))
    }
}

fn check_expectations(
    args: &IngestArgs,
    summary: &SourceSummary,
    discontinuities: u64,
) -> Vec<String> {
    let mut failures = Vec::new();
    let stats = &summary.stats;
    if discontinuities > 0 {
        failures.push(format!(
            "{discontinuities} blocks did not continue their stream and no gap or restart was reported"
        ));
    }
    if let Some(n) = args.expect_samples {
        for s in &summary.streams {
            if s.samples != n {
                failures.push(format!(
                    "node {} axis {}: {} samples, expected {n}",
                    s.node, s.axis, s.samples
                ));
            }
        }
        if summary.streams.is_empty() {
            failures.push(format!(
                "no stream arrived, expected {n} samples per stream"
            ));
        }
    }
    let totals = [
        (
            "streams",
            args.expect_streams.map(|n| n as u64),
            summary.streams.len() as u64,
        ),
        ("gaps", args.expect_gaps, stats.gaps),
        (
            "malformed frames",
            args.expect_malformed,
            stats.malformed.total(),
        ),
        ("restarts", args.expect_restarts, stats.restarts),
        (
            "sensor-lost reports",
            args.expect_sensor_lost,
            stats.sensor_lost,
        ),
    ];
    for (what, expected, got) in totals {
        if let Some(expected) = expected {
            if got != expected {
                failures.push(format!("{got} {what}, expected {expected}"));
            }
        }
    }
    failures
}

fn print_text(report: &Report) {
    let s = &report.summary.stats;
    println!(
        "ingest: {} for {:.1} s, {:.0} samples/s while data arrived",
        report.source, report.wall_seconds, report.samples_per_second
    );
    for stream in &report.summary.streams {
        println!(
            "stream node {} axis {} ({}): {} samples, next position {}, {} gaps ({} samples missing), {} restarts",
            stream.node,
            stream.axis,
            if stream.fd { "fd" } else { "classic" },
            stream.samples,
            stream.next_sample.map_or("-".to_string(), |n| n.to_string()),
            stream.gaps,
            stream.missing_samples,
            stream.restarts,
        );
    }
    println!(
        "frames {} (data {}, metadata {}, speed {}), samples {}, gaps {}, missing samples {}, restarts {}, duplicates {}, old {}, before metadata {}, sensor lost {}, back {}, hand-off drops {}",
        s.frames, s.data_frames, s.metadata_frames, s.speed_frames, s.samples, s.gaps,
        s.missing_samples, s.restarts, s.duplicates, s.old_frames, s.frames_before_metadata,
        s.sensor_lost, s.sensor_back, s.handoff_dropped
    );
    let m = &s.malformed;
    println!(
        "malformed {} (unknown id {}, wrong length {}, bad sample count {}, bad metadata {}, bad speed {}, unannounced axis {}, bad batch {})",
        m.total(), m.unknown_id, m.wrong_length, m.bad_sample_count, m.bad_metadata, m.bad_speed,
        m.unannounced_axis, m.bad_batch
    );
    println!(
        "unannounced discontinuities {}",
        report.unannounced_discontinuities
    );
    for failure in &report.failures {
        println!("expectation failed: {failure}");
    }
}
