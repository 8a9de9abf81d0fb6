//! `bearingd simulate`: write a synthetic record of a bearing fault, so that anyone can produce
//! a known fault and check what bearingd makes of it: from the twin's signal model (impacts
//! ringing a resonance, MODELS.md §4) or from the physics twin (the 6-DOF contact model,
//! MODELS.md §5, optionally with parameters calibrated to a real machine).

use super::progress::Progress;
use super::twin_args::{DofArg, FaultArg, MachineFaultArg};
use crate::bearing::BearingGeometry;
use crate::machine_fault::MachineFault;
use crate::twin::physics::{PhysicsModel, PhysicsParams};
use crate::twin::{Nuisance, SimulationParams, Simulator};
use bearingd::cli::format::FormatArg;
use bearingd::cli::CliError;
use clap::{Args, ValueEnum};
use std::io::Write;
use std::path::PathBuf;

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelArg {
    /// The signal model: decaying impacts on a resonance (fast, every shape parameter free).
    Signal,
    /// The physics twin: masses, springs and Hertz contacts integrated in time.
    Physics,
}

#[derive(Args)]
pub struct SimulateArgs {
    /// Which model makes the record.
    #[arg(long, value_enum, default_value = "signal")]
    model: ModelArg,
    /// The defect.
    #[arg(long, value_enum, default_value = "outer")]
    fault: FaultArg,
    /// Shaft speed, rpm.
    #[arg(long, default_value_t = 1772.0)]
    rpm: f64,
    /// Bearing: a catalog name (skf-6205-2rs, skf-6203-2rs, skf-61804, pronostia, mfpt,
    /// rexnord-za-2115) or custom geometry "z=9,d=7.94mm,D=39.04mm,alpha=0".
    #[arg(long, default_value = "skf-6205-2rs")]
    bearing: String,
    /// Length of the record: seconds, e.g. 10 or 10s.
    #[arg(long, default_value = "10s")]
    duration: String,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 12_000.0)]
    fs: f64,
    /// Output file: .csv (one column, accel_g, in g) or .wav (32-bit float in g; an iXML chunk
    /// names its channel accel_g).
    #[arg(long)]
    out: PathBuf,
    /// Physics model: radial load, N.
    #[arg(long, default_value_t = 1000.0)]
    load: f64,
    /// Physics model: defect width, mm (CWRU: 0.178, 0.356, 0.533).
    #[arg(long, default_value_t = 0.178)]
    defect_width: f64,
    /// Physics model: damping ratio of the resonator (its resonance is --resonance).
    #[arg(long, default_value_t = 0.05)]
    damping_ratio: f64,
    /// Physics model: six degrees of freedom (seed 001) or five (seed 003).
    #[arg(long, value_enum, default_value = "six")]
    dof: DofArg,
    /// Physics model: parameters saved by `bearingd calibrate --save` (JSON); they replace the
    /// structure (k_r, c_r, k_b, …), the defect width, the load and the model; --fault, --rpm,
    /// --fs, --duration, --noise, --jitter and --seed still apply.
    #[arg(long)]
    calibrated: Option<PathBuf>,
    /// Signal model: impact amplitude a at full load, g.
    #[arg(long, default_value_t = 1.0)]
    amplitude: f64,
    /// Signal model: decay rate B of each impact, 1/s.
    #[arg(long, default_value_t = 800.0)]
    decay: f64,
    /// Structural resonance f_n, Hz (physics model: the resonator's, which sets k_r).
    #[arg(long, default_value_t = 3_000.0)]
    resonance: f64,
    /// Signal model: Stribeck load-zone factor ε (0.5: half the bearing loaded).
    #[arg(long, default_value_t = 0.5)]
    load_zone: f64,
    /// Impact-time jitter (slip), as a fraction of the impact period (physics model: the cage's
    /// slip per ball pass).
    #[arg(long, default_value_t = 0.01)]
    jitter: f64,
    /// Signal model: defect length in mm (0: one impact per passage; above: entry and exit
    /// impacts).
    #[arg(long, default_value_t = 0.0)]
    defect_length: f64,
    /// White noise, g (standard deviation).
    #[arg(long, default_value_t = 0.2)]
    noise: f64,
    /// Signal model: add what a real machine adds besides the bearing (shaft harmonics,
    /// shaft-modulated noise, random impulses, a gear mesh and a 100 Hz tone; see
    /// docs/DIAGNOSIS.md).
    #[arg(long)]
    nuisance: bool,
    /// Signal model: add a fault of the machine (not of the bearing) at shaft orders.
    #[arg(long, value_enum)]
    machine_fault: Option<MachineFaultArg>,
    /// RMS velocity of the machine fault's 1× line, mm/s.
    #[arg(long, default_value_t = 4.0, requires = "machine_fault")]
    machine_fault_velocity: f64,
    /// Signal model: the fault appears at this time, s.
    #[arg(long, default_value_t = 0.0)]
    onset: f64,
    /// Random seed: the same seed gives the same record.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    format: FormatArg,
}

fn parse_seconds(text: &str) -> Option<f64> {
    let t = text.trim();
    let value = t
        .strip_suffix("ms")
        .map(|v| v.trim().parse::<f64>().ok().map(|ms| ms / 1e3))
        .unwrap_or_else(|| t.strip_suffix('s').unwrap_or(t).trim().parse::<f64>().ok())?;
    (value.is_finite() && value > 0.0).then_some(value)
}

pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    let duration = parse_seconds(&args.duration).ok_or_else(|| {
        CliError::input(format!(
            "--duration {} is not a length of time; give seconds, e.g. --duration 10s",
            args.duration
        ))
    })?;
    let bearing = BearingGeometry::parse(&args.bearing).map_err(CliError::input)?;
    let checks = [
        (
            args.rpm > 0.0 && args.rpm.is_finite(),
            "--rpm must be a positive speed, e.g. --rpm 1772",
        ),
        (
            args.fs >= 1_000.0 && args.fs <= 1e6,
            "--fs must be a sample rate in [1000, 1000000] Hz, e.g. --fs 12000",
        ),
        (
            args.resonance > 0.0 && args.resonance < args.fs / 2.0,
            "--resonance must lie below half the sample rate",
        ),
        (
            args.decay > 0.0,
            "--decay must be positive, e.g. --decay 800",
        ),
        (
            args.load_zone > 0.0,
            "--load-zone must be positive, e.g. --load-zone 0.5",
        ),
        (
            (0.0..0.5).contains(&args.jitter),
            "--jitter must be in [0, 0.5), e.g. --jitter 0.01",
        ),
        (
            args.noise >= 0.0 && args.amplitude >= 0.0 && args.defect_length >= 0.0,
            "--noise, --amplitude and --defect-length must not be negative",
        ),
        (
            duration * args.fs <= 1e9,
            "--duration × --fs must stay below 10⁹ samples",
        ),
    ];
    let problems: Vec<&str> = checks
        .iter()
        .filter(|(ok, _)| !ok)
        .map(|(_, why)| *why)
        .collect();
    if !problems.is_empty() {
        return Err(CliError::input(problems.join("; ")));
    }
    let samples = match args.model {
        ModelArg::Signal => {
            let params = SimulationParams {
                fault: args.fault.into(),
                rpm: args.rpm,
                bearing: bearing.clone(),
                fs_hz: args.fs,
                amplitude_g: args.amplitude,
                decay_per_s: args.decay,
                resonance_hz: args.resonance,
                load_zone: args.load_zone,
                load_exponent: 1.5,
                jitter: args.jitter,
                defect_length_mm: args.defect_length,
                noise_g: args.noise,
                shaft_tone_g: 0.05,
                nuisance: Nuisance {
                    machine_fault: args.machine_fault.map(|kind| MachineFault {
                        kind: kind.into(),
                        velocity_mm_s: args.machine_fault_velocity,
                    }),
                    ..if args.nuisance {
                        Nuisance::typical()
                    } else {
                        Nuisance::none()
                    }
                },
                onset_s: args.onset,
                ramp_s: 0.0,
                seed: args.seed,
            };
            Simulator::record(params, duration)
        }
        ModelArg::Physics => simulate_physics(args, bearing, duration)?,
    };
    let extension = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let written = match extension.as_deref() {
        Some("wav") => write_wav(&args.out, args.fs, &samples),
        Some("csv") => write_csv(&args.out, &samples),
        _ => {
            return Err(CliError::input(format!(
                "{}: unsupported output; use a .csv or .wav file name",
                args.out.display()
            )))
        }
    };
    written.map_err(|e| CliError::failure(format!("{}: cannot write: {e}", args.out.display())))?;
    let analyze = format!(
        "bearingd analyze {}{} --rpm {} --bearing {}",
        args.out.display(),
        if extension.as_deref() == Some("csv") {
            format!(" --fs {}", args.fs)
        } else {
            String::new()
        },
        args.rpm,
        args.bearing
    );
    if args.format.json() {
        println!(
            "{}",
            serde_json::json!({
                "samples": samples.len(),
                "duration_s": duration,
                "fs_hz": args.fs,
                "out": args.out.display().to_string(),
                "analyze": analyze,
            })
        );
    } else {
        eprintln!(
            "wrote {} samples ({duration} s at {} Hz) to {}; analyse with: {analyze}",
            samples.len(),
            args.fs,
            args.out.display(),
        );
    }
    Ok(())
}

/// The physics twin's record, block by block with progress on stderr (it takes seconds per
/// simulated second).
fn simulate_physics(
    args: &SimulateArgs,
    bearing: BearingGeometry,
    duration: f64,
) -> Result<Vec<f32>, CliError> {
    if args.machine_fault.is_some() {
        return Err(CliError::input(
            "--machine-fault is made by the signal model: use `--model signal` (the physics twin \
             models the bearing and its housing only)",
        ));
    }
    let mut params = match &args.calibrated {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| {
                CliError::input(format!(
                    "{}: cannot read the calibrated parameters: {e}",
                    path.display()
                ))
            })?;
            let mut saved: PhysicsParams = serde_json::from_str(&text).map_err(|e| {
                CliError::input(format!(
                    "{}: not a parameter file written by `bearingd calibrate --save`: {e}",
                    path.display()
                ))
            })?;
            saved.fault = args.fault.into();
            saved
        }
        None => {
            let mut params = PhysicsParams::new(bearing, args.rpm, args.fault.into());
            params.load_n = args.load;
            params.defect_width_mm = args.defect_width;
            params.dof = args.dof.into();
            let s = &mut params.structure;
            s.resonator_stiffness =
                s.resonator_mass_kg * (std::f64::consts::TAU * args.resonance).powi(2);
            s.resonator_damping =
                2.0 * args.damping_ratio * (s.resonator_stiffness * s.resonator_mass_kg).sqrt();
            params
        }
    };
    params.rpm = args.rpm;
    params.fs_hz = args.fs;
    params.duration_s = duration;
    params.noise_g = args.noise;
    params.slip = args.jitter;
    params.seed = args.seed;
    let total = params.samples();
    let mut model = PhysicsModel::new(params).map_err(CliError::input)?;
    let mut samples = vec![0f32; total];
    // One block per second of signal: progress counts the seconds simulated.
    let block = (args.fs as usize).max(1);
    let progress = Progress::start("simulate", "s of signal", total.div_ceil(block) as u64);
    for chunk in samples.chunks_mut(block) {
        model.fill(chunk).map_err(CliError::failure)?;
        progress.inc("physics twin");
    }
    progress.finish("physics twin");
    Ok(samples)
}

fn write_wav(path: &PathBuf, fs: f64, samples: &[f32]) -> std::io::Result<()> {
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: fs.round() as u32,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let mut writer = hound::WavWriter::create(path, spec).map_err(std::io::Error::other)?;
    for &s in samples {
        writer.write_sample(s).map_err(std::io::Error::other)?;
    }
    writer.finalize().map_err(std::io::Error::other)?;
    name_the_channel(path)
}

/// Appends an iXML chunk naming the one channel as the CSV column is named (`accel_g`), and
/// grows the RIFF size to hold it: readers that honour iXML (ours, field-recorder software)
/// show the name, the others skip the chunk.
fn name_the_channel(path: &PathBuf) -> std::io::Result<()> {
    use std::io::{Seek, SeekFrom};
    let chunk = bearingd::recording::ixml_track_names(&[CHANNEL_NAME]);
    let mut file = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)?;
    let end = file.seek(SeekFrom::End(0))?;
    file.write_all(&chunk)?;
    let riff_size = u32::try_from(end + chunk.len() as u64 - 8)
        .map_err(|_| std::io::Error::other("the WAV file exceeds 4 GiB"))?;
    file.seek(SeekFrom::Start(4))?;
    file.write_all(&riff_size.to_le_bytes())?;
    file.sync_all()
}

/// The name of the simulated channel in both output formats: acceleration in g.
const CHANNEL_NAME: &str = "accel_g";

fn write_csv(path: &PathBuf, samples: &[f32]) -> std::io::Result<()> {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(out, "{CHANNEL_NAME}")?;
    for s in samples {
        writeln!(out, "{s}")?;
    }
    out.flush()
}
