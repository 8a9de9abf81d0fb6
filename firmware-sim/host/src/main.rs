//! `firmware-sim`: simulated bearingd sensor nodes on a host.
//!
//! Runs the node's real `no_std` core (`bearing_wire::SensorNode`: sampling state machine and
//! frame packing over a heapless queue) on a host, fed by the bearingd twin simulator (fault
//! type and onset, speed, noise) or by a recording (CWRU `.mat`, CSV, …), and sends the frames
//! over SocketCAN (classic or FD, paced at the bus bit rate) or iceoryx2 (the same frames in
//! `FrameBatch`es on `bearingd/accel/<sensor>`). Several nodes can share one bus. For tests it
//! can inject malformed frames and a node restart, and it prints what it sent so a receiver's
//! counts can be checked exactly.

mod pacing;
mod transport;

use bearing_signal::recording::{read_recording, ReadOptions, SampleUnit};
use bearing_signal::simulate::{SimulatedFault, SimulationParams, Simulator};
use bearing_wire::{
    encode, AxisSet, FirmwareVersion, FrameKind, NodeConfig, SensorNode, SpeedSource,
};
use clap::{Parser, ValueEnum};
use pacing::{BusPacer, SampleClock};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;
use transport::Transport;

/// Frames a simulated node can queue (the node drains it after every few samples).
const NODE_QUEUE: usize = 64;

/// Shaft speed when neither `--rpm` nor the recording gives one (CWRU's 0 hp speed).
const DEFAULT_RPM: f64 = 1772.0;

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("CAN interface {interface}: {detail}")]
    Interface { interface: String, detail: String },
    #[error("frame {can_id:#05x}: {detail}")]
    Frame { can_id: u32, detail: String },
    #[error("iceoryx2: {0}")]
    Shm(String),
    #[error("{0}")]
    Input(String),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum TransportKind {
    Can,
    Shm,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum FaultArg {
    None,
    Outer,
    Inner,
    Ball,
}

#[derive(Debug, Parser)]
#[command(
    name = "firmware-sim",
    version,
    about = "Simulated bearingd sensor nodes over SocketCAN or iceoryx2"
)]
struct Args {
    #[arg(long, value_enum, default_value = "can")]
    transport: TransportKind,
    /// CAN interface.
    #[arg(long, default_value = "vcan0")]
    interface: String,
    /// Create the interface as a vcan with FD MTU first (needs CAP_NET_ADMIN; for test VMs).
    #[arg(long)]
    create_vcan: bool,
    /// CAN FD data frames (64 bytes, 28 samples) instead of classic (8 bytes, 2 samples).
    #[arg(long)]
    fd: bool,
    /// Nominal bus bit rate, bit/s (0: no bus pacing).
    #[arg(long, default_value_t = 1_000_000)]
    bitrate: u32,
    /// CAN FD data-phase bit rate, bit/s.
    #[arg(long, default_value_t = 5_000_000)]
    data_bitrate: u32,
    /// Id of the first node (0..=15).
    #[arg(long, default_value_t = 1)]
    node: u8,
    /// Number of nodes (ids node, node+1, …).
    #[arg(long, default_value_t = 1)]
    nodes: u8,
    /// Axes per node (1..=4).
    #[arg(long, default_value_t = 1)]
    axes: u8,
    #[arg(long, value_enum, default_value = "outer")]
    fault: FaultArg,
    /// Fault onset, s of sample time.
    #[arg(long, default_value_t = 0.0)]
    onset: f64,
    /// Shaft speed, rpm (twin, and the speed frames); default: the recording's own, else 1772.
    #[arg(long)]
    rpm: Option<f64>,
    /// White noise, g (standard deviation).
    #[arg(long, default_value_t = 0.05)]
    noise: f64,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sample rate, Hz (a recording's own rate wins unless this is given explicitly).
    #[arg(long)]
    fs: Option<u32>,
    /// Seconds of sample time to send.
    #[arg(long, default_value_t = 10.0)]
    duration: f64,
    /// A speed frame (tachometer, --rpm) from every node every S seconds of sample time, the
    /// first before the first sample; 0 = none.
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    speed_every: f64,
    /// Sample time runs this many times faster than real time; 0 = as fast as the bus allows.
    #[arg(long, default_value_t = 1.0)]
    speed_factor: f64,
    /// Simulate only the first S seconds of each stream and send them over and over (a
    /// throughput bench: the twin's simulation, not the transport, would otherwise be the
    /// limit). 0 = simulate everything.
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    loop_after: f64,
    /// Send a recording (CWRU .mat, CSV, …) instead of the twin.
    #[arg(long)]
    recording: Option<PathBuf>,
    /// Channel or column of the recording.
    #[arg(long)]
    channel: Option<String>,
    /// g per ADC count.
    #[arg(long, default_value_t = 1.0 / 2048.0)]
    scale: f32,
    /// Send a malformed frame after every N frames (0 = never).
    #[arg(long, default_value_t = 0)]
    inject_malformed_every: u64,
    /// Restart every node once its per-axis sample count reaches N.
    #[arg(long)]
    restart_at_sample: Option<u64>,
    /// iceoryx2 sensor name: service bearingd/accel/<sensor>.
    #[arg(long, default_value = "sim")]
    sensor: String,
    #[arg(long)]
    iox_prefix: Option<String>,
    #[arg(long)]
    iox_root: Option<String>,
    /// iceoryx2: wait up to S seconds for a subscriber's ready event before sending.
    #[arg(long, value_name = "S")]
    wait_ready: Option<f64>,
    /// iceoryx2: discard batches when the subscriber's buffer is full (a live sensor) instead
    /// of waiting for it (lossless, the default for tests).
    #[arg(long)]
    shm_discard: bool,
}

/// Where samples come from.
enum Signal {
    Twin(Vec<Simulator>),
    /// Each stream's first samples, repeated (`--loop-after`).
    Looped(Vec<Vec<f32>>),
    Recording {
        samples: Vec<f64>,
        next: usize,
    },
}

#[derive(Debug, Default)]
struct Totals {
    frames: u64,
    data_frames: u64,
    malformed: u64,
    restarts: u64,
    samples_lost_on_reset: u64,
    frames_dropped_in_node: u64,
    /// Samples that left in data frames, per (node, axis).
    on_wire: BTreeMap<(u8, u8), u64>,
}

fn main() -> ExitCode {
    let args = Args::parse();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("firmware-sim: error: {e}");
            ExitCode::from(2)
        }
    }
}

fn run(args: &Args) -> Result<(), SimError> {
    if args.nodes == 0 || u16::from(args.node) + u16::from(args.nodes) > 16 {
        return Err(SimError::Input(format!(
            "--node {} --nodes {}: node ids must lie in 0..=15",
            args.node, args.nodes
        )));
    }
    if !(1..=4).contains(&args.axes) {
        return Err(SimError::Input(format!(
            "--axes {}: 1 to 4 axes",
            args.axes
        )));
    }
    let mut transport = open_transport(args)?;
    if args.duration <= 0.0 {
        return Ok(());
    }
    let (mut signal, fs, rpm) = open_signal(args)?;
    let kind = if args.fd {
        FrameKind::Fd
    } else {
        FrameKind::Classic
    };
    let axes: Vec<u8> = (0..args.axes).collect();
    let mut nodes: Vec<SensorNode<NODE_QUEUE>> = (0..args.nodes)
        .map(|k| {
            SensorNode::new(NodeConfig {
                node: args.node + k,
                axes: AxisSet::from_axes(&axes).unwrap_or_default(),
                data_kind: kind,
                sample_rate_hz: fs,
                scale_g_per_count: args.scale,
                firmware: FirmwareVersion {
                    major: 0,
                    minor: 1,
                    patch: 0,
                },
                metadata_period_samples: fs,
            })
            .map_err(|e| SimError::Input(format!("node {}: {e:?}", args.node + k)))
        })
        .collect::<Result<_, _>>()?;
    let total = (args.duration * f64::from(fs)).round() as u64;
    let total = match &signal {
        Signal::Recording { samples, .. } => total.min(samples.len() as u64),
        Signal::Twin(_) | Signal::Looped(_) => total,
    };
    let chunk = u64::from((fs / 100).max(28));
    let mut pacer = BusPacer::new(
        if args.transport == TransportKind::Can {
            args.bitrate
        } else {
            0
        },
        args.data_bitrate,
    );
    let clock = SampleClock::new(args.speed_factor, f64::from(fs));
    let mut totals = Totals::default();
    let mut restarted = false;
    let mut block = vec![0f32; chunk as usize];
    let mut counts = vec![0i16; chunk as usize];
    let mut frames: Vec<(u16, Vec<u8>, bool)> = Vec::with_capacity(NODE_QUEUE);
    let started = Instant::now();
    let mut done = 0u64;
    let mut next_speed = 0u64;
    // Samples between speed frames (0: none); a speed frame goes out at a chunk's start.
    let speed_period = (args.speed_every.max(0.0) * f64::from(fs)).round() as u64;
    while done < total {
        let mut n = chunk.min(total - done);
        if let Some(at) = args.restart_at_sample {
            if !restarted && done < at {
                n = n.min(at - done);
            } else if !restarted && done >= at {
                for node in nodes.iter_mut() {
                    node.reset();
                }
                restarted = true;
                totals.restarts += nodes.len() as u64;
            }
        }
        clock.wait_for_sample(done);
        let send_speed = speed_period > 0 && done >= next_speed;
        if send_speed {
            next_speed += speed_period;
        }
        for (k, node) in nodes.iter_mut().enumerate() {
            if send_speed {
                let _ = node.push_speed(SpeedSource::Tachometer, Some((rpm * 100.0) as u32));
            }
            for &axis in &axes {
                let source = k * usize::from(args.axes) + usize::from(axis);
                fill(&mut signal, source, &mut block[..n as usize], done);
                for (c, g) in counts.iter_mut().zip(&block[..n as usize]) {
                    *c = (f64::from(*g) / f64::from(args.scale))
                        .round()
                        .clamp(f64::from(i16::MIN), f64::from(i16::MAX))
                        as i16;
                }
                // Small pieces, drained after each, so the node's queue never overflows.
                for piece in counts[..n as usize].chunks(kind.max_samples() * 8) {
                    let _ = node.push_samples(axis, piece);
                    drain(node, kind, &mut frames)?;
                    send_all(args, &mut transport, &mut pacer, &mut frames, &mut totals)?;
                }
            }
        }
        transport.flush()?;
        done += n;
    }
    for node in nodes.iter_mut() {
        let _ = node.flush();
        drain(node, kind, &mut frames)?;
        send_all(args, &mut transport, &mut pacer, &mut frames, &mut totals)?;
        let stats = node.stats();
        totals.samples_lost_on_reset += stats.samples_lost_on_reset;
        totals.frames_dropped_in_node += stats.frames_dropped;
    }
    transport.flush()?;
    let wall = started.elapsed().as_secs_f64();
    let per_stream: Vec<String> = totals
        .on_wire
        .iter()
        .map(|((node, axis), n)| format!("{node}/{axis}={n}"))
        .collect();
    println!(
        "FIRMWARE-SIM DONE transport={:?} kind={} fs={fs} samples_per_axis={total} on_wire={} frames={} data_frames={} malformed={} restarts={} lost_on_reset={} node_drops={} wall={wall:.2}s frames_per_s={:.0} bus_busy={:.2}s",
        args.transport,
        if args.fd { "fd" } else { "classic" },
        per_stream.join(","),
        totals.frames,
        totals.data_frames,
        totals.malformed,
        totals.restarts,
        totals.samples_lost_on_reset,
        totals.frames_dropped_in_node,
        totals.frames as f64 / wall.max(1e-9),
        pacer.busy.as_secs_f64(),
    );
    Ok(())
}

fn open_transport(args: &Args) -> Result<Box<dyn Transport>, SimError> {
    match args.transport {
        TransportKind::Can => {
            #[cfg(feature = "can")]
            {
                if args.create_vcan {
                    transport::can::create_vcan(&args.interface)?;
                }
                Ok(Box::new(transport::can::CanTransport::open(
                    &args.interface,
                )?))
            }
            #[cfg(not(feature = "can"))]
            Err(SimError::Input("built without the `can` feature".into()))
        }
        TransportKind::Shm => {
            #[cfg(feature = "shm")]
            {
                let iox = bearing_iox::IoxSettings {
                    prefix: args.iox_prefix.clone(),
                    root_path: args.iox_root.clone(),
                };
                let shm =
                    transport::shm::ShmTransport::open(&args.sensor, &iox, !args.shm_discard)?;
                if let Some(seconds) = args.wait_ready {
                    shm.wait_ready(std::time::Duration::from_secs_f64(seconds.max(0.0)))?;
                }
                Ok(Box::new(shm))
            }
            #[cfg(not(feature = "shm"))]
            Err(SimError::Input("built without the `shm` feature".into()))
        }
    }
}

/// The sample source, its sample rate (Hz) and the shaft speed (rpm) to report.
fn open_signal(args: &Args) -> Result<(Signal, u32, f64), SimError> {
    if let Some(path) = &args.recording {
        let recording = read_recording(
            path,
            &ReadOptions {
                channel: args.channel.clone(),
                column: None,
                unit: None,
            },
        )
        .map_err(|e| SimError::Input(e.to_string()))?;
        if recording.unit == SampleUnit::FullScale {
            eprintln!(
                "firmware-sim: warning: {}: the samples are fractions of full scale, not g; they are sent as if g",
                path.display()
            );
        }
        let fs = match (args.fs, recording.fs_hz) {
            (Some(fs), _) => fs,
            (None, Some(fs)) => fs.round() as u32,
            (None, None) => {
                return Err(SimError::Input(format!(
                    "{}: the file does not say its sample rate; give --fs",
                    path.display()
                )))
            }
        };
        let rpm = args.rpm.or(recording.rpm).unwrap_or(DEFAULT_RPM);
        return Ok((
            Signal::Recording {
                samples: recording.samples,
                next: 0,
            },
            fs,
            rpm,
        ));
    }
    let fs = args.fs.unwrap_or(25_600);
    if fs == 0 {
        return Err(SimError::Input(
            "--fs 0: the sample rate must be positive".into(),
        ));
    }
    let fault = match args.fault {
        FaultArg::None => SimulatedFault::None,
        FaultArg::Outer => SimulatedFault::OuterRace,
        FaultArg::Inner => SimulatedFault::InnerRace,
        FaultArg::Ball => SimulatedFault::Ball,
    };
    let rpm = args.rpm.unwrap_or(DEFAULT_RPM);
    let streams = usize::from(args.nodes) * usize::from(args.axes);
    let simulators: Vec<Simulator> = (0..streams)
        .map(|i| {
            let mut params = SimulationParams::example(fault);
            params.rpm = rpm;
            params.fs_hz = f64::from(fs);
            params.noise_g = args.noise;
            params.onset_s = args.onset;
            params.seed = args.seed.wrapping_add(i as u64);
            Simulator::new(params)
        })
        .collect();
    let loop_len = (args.loop_after.max(0.0) * f64::from(fs)).round() as usize;
    if loop_len > 0 {
        let looped = simulators
            .into_iter()
            .map(|mut sim| {
                let mut samples = vec![0f32; loop_len];
                for chunk in samples.chunks_mut((fs / 100).max(28) as usize) {
                    sim.fill(chunk);
                }
                samples
            })
            .collect();
        return Ok((Signal::Looped(looped), fs, rpm));
    }
    Ok((Signal::Twin(simulators), fs, rpm))
}

/// The next `out.len()` samples (g) of stream `source`, starting at sample `at`.
fn fill(signal: &mut Signal, source: usize, out: &mut [f32], at: u64) {
    match signal {
        Signal::Twin(simulators) => {
            if let Some(sim) = simulators.get_mut(source) {
                sim.fill(out);
            }
        }
        Signal::Looped(streams) => {
            if let Some(samples) = streams.get(source).filter(|s| !s.is_empty()) {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = samples[(at as usize + i) % samples.len()];
                }
            }
        }
        Signal::Recording { samples, next } => {
            // Every stream sends the same recording.
            let start = at as usize;
            for (i, o) in out.iter_mut().enumerate() {
                *o = samples.get(start + i).copied().unwrap_or(0.0) as f32;
            }
            *next = start + out.len();
        }
    }
}

fn drain(
    node: &mut SensorNode<NODE_QUEUE>,
    kind: FrameKind,
    frames: &mut Vec<(u16, Vec<u8>, bool)>,
) -> Result<(), SimError> {
    let mut bytes = [0u8; 64];
    while let Some(frame) = node.pop_frame() {
        let (id, len) = encode(&frame, kind, &mut bytes).map_err(|e| SimError::Frame {
            can_id: 0,
            detail: format!("encode: {e}"),
        })?;
        frames.push((id, bytes[..len].to_vec(), len > 8));
    }
    Ok(())
}

fn send_all(
    args: &Args,
    transport: &mut Box<dyn Transport>,
    pacer: &mut BusPacer,
    frames: &mut Vec<(u16, Vec<u8>, bool)>,
    totals: &mut Totals,
) -> Result<(), SimError> {
    for (id, bytes, fd) in frames.drain(..) {
        pacer.wait_for_bus(bytes.len(), fd);
        transport.send(id, &bytes, fd)?;
        totals.frames += 1;
        if let Some(cid) = bearing_wire::CanId::parse(u32::from(id)) {
            if let bearing_wire::MessageKind::Data { axis, .. } = cid.message {
                totals.data_frames += 1;
                let samples = data_samples(&bytes, fd);
                *totals.on_wire.entry((cid.node, axis)).or_insert(0) += samples;
            }
            if args.inject_malformed_every > 0
                && totals.frames.is_multiple_of(args.inject_malformed_every)
            {
                let (bad_id, bad_bytes) = malformed(cid.node, totals.malformed);
                pacer.wait_for_bus(bad_bytes.len(), false);
                transport.send(bad_id, &bad_bytes, false)?;
                totals.malformed += 1;
            }
        }
    }
    Ok(())
}

/// Samples a data frame holds (FD: byte 6; classic: from the length).
fn data_samples(bytes: &[u8], fd: bool) -> u64 {
    if fd {
        u64::from(bytes.get(6).copied().unwrap_or(0))
    } else {
        (bytes.len().saturating_sub(4) / 2) as u64
    }
}

/// The `n`-th malformed frame of `node`, rotating through three kinds a receiver must refuse:
/// a data frame of the wrong length, metadata of an unknown protocol version, an id in the
/// bearingd block that no frame uses.
fn malformed(node: u8, n: u64) -> (u16, Vec<u8>) {
    let node = u16::from(node);
    match n % 3 {
        0 => (0x100 + node, vec![0; 7]),
        1 => (0x1F0 + node, vec![0x20, 0, 0x64, 0, 0, 1, 1, 0]),
        _ => (0x190 + node, vec![0; 8]),
    }
}
