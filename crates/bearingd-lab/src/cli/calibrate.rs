//! `bearingd calibrate REC`: fit the physics twin's resonator stiffness and damping, contact
//! stiffness and defect width to a measured record (MODELS.md §5), show the fit as numbers and
//! as a picture of the measured and simulated spectra, and save the calibrated parameters for
//! `bearingd simulate --model physics --calibrated FILE`.

use super::twin_args::{DofArg, FaultArg};
use crate::analysis::band::Band;
use crate::analysis::record::analyze_record;
use crate::analysis::AnalysisSettings;
use crate::messages::FaultKind;
use crate::offline::{resolve_conditions, AnalyzeRequest};
use crate::plot::{self, Color, Figure, Series, Shade, SpectrumPanel};
use crate::recording::read_recording;
use crate::twin::physics::{calibrate, Calibration, CalibrationSettings, Dof, PhysicsParams};
use crate::twin::SimulatedFault;
use bearingd::cli::format::{FormatArg, Remarks};
use bearingd::cli::{CliError, RecordingArgs};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct CalibrateArgs {
    /// The measured record: CWRU .mat, PRONOSTIA/IMS/plain CSV or WAV.
    file: PathBuf,
    #[command(flatten)]
    recording: RecordingArgs,
    /// The defect to model; default: the envelope diagnosis of the record.
    #[arg(long, value_enum)]
    fault: Option<FaultArg>,
    /// The band compared, as LO-HI in Hz; default: the band the envelope analysis chose for
    /// the fault.
    #[arg(long)]
    band: Option<String>,
    /// Radial load on the bearing, N.
    #[arg(long, default_value_t = 1000.0)]
    load: f64,
    /// The model: six degrees of freedom (seed 001) or five (seed 003).
    #[arg(long, value_enum, default_value = "six")]
    dof: DofArg,
    /// Candidates per generation of the differential evolution.
    #[arg(long, default_value_t = 20)]
    population: usize,
    /// Generations of the differential evolution.
    #[arg(long, default_value_t = 25)]
    generations: usize,
    /// Seconds simulated per candidate.
    #[arg(long, default_value_t = 0.2)]
    simulated: f64,
    /// Seed of the search: the same seed gives the same calibration.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Draw the measured, calibrated and default spectra to this file (.png or .svg).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Write the calibrated parameters as JSON (for `simulate --model physics --calibrated`).
    #[arg(long)]
    save: Option<PathBuf>,
    // With json, the result as one JSON document on stdout, the notes and warnings in it.
    #[command(flatten)]
    format: FormatArg,
}

/// The physics twin's defect for an envelope verdict (it has no cage fault).
fn modelled(kind: FaultKind) -> Option<SimulatedFault> {
    match kind {
        FaultKind::OuterRace => Some(SimulatedFault::OuterRace),
        FaultKind::InnerRace => Some(SimulatedFault::InnerRace),
        FaultKind::Ball => Some(SimulatedFault::Ball),
        FaultKind::Cage => None,
    }
}

fn parse_band(text: &str) -> Option<Band> {
    let (lo, hi) = text.split_once('-')?;
    let (lo, hi) = (
        lo.trim().parse::<f64>().ok()?,
        hi.trim().parse::<f64>().ok()?,
    );
    (lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi).then(|| Band::new(lo, hi))
}

pub fn run(args: &CalibrateArgs) -> Result<(), CliError> {
    let band_given = match &args.band {
        Some(text) => Some(parse_band(text).ok_or_else(|| {
            CliError::input(format!(
                "--band {text} is not a band; give LO-HI in Hz, e.g. --band 2000-4000"
            ))
        })?),
        None => None,
    };
    if args.population < 4 || args.generations < 1 {
        return Err(CliError::input(
            "--population must be at least 4 and --generations at least 1, e.g. --population 24 --generations 24",
        ));
    }
    let recording =
        read_recording(&args.file, &args.recording.read_options()).map_err(CliError::input)?;
    let request = AnalyzeRequest {
        file: Some(args.file.clone()),
        fs_hz: args.recording.fs,
        rpm: args.recording.rpm,
        bearing: args.recording.bearing.clone(),
        ..AnalyzeRequest::default()
    };
    let conditions = resolve_conditions(&recording, &request, false).map_err(CliError::input)?;
    let mut remarks = Remarks::new("bearingd", args.format.json());
    remarks.extend(&conditions.notes, &conditions.warnings);
    let file = args.file.display().to_string();
    let samples: Vec<f32> = recording.samples.iter().map(|&x| x as f32).collect();
    let freqs = conditions.bearing.fault_frequencies(conditions.rpm / 60.0);
    let analysis = analyze_record(
        &samples,
        conditions.fs_hz,
        &freqs,
        &AnalysisSettings::default(),
    )
    .map_err(|e| CliError::input(format!("{file}: {e}")))?;
    let fault = match args.fault {
        Some(fault) => fault.into(),
        None => match analysis.diagnosis.verdict.fault() {
            Some(kind) => match modelled(kind) {
                Some(fault) => {
                    let said = format!(
                        "--fault not given: modelling the envelope diagnosis, {}",
                        analysis.diagnosis.verdict.name()
                    );
                    if args.format.json() {
                        remarks.notes.push(said);
                    } else {
                        eprintln!("bearingd: {said}");
                    }
                    fault
                }
                None => {
                    return Err(CliError::input(format!(
                        "{file}: the envelope diagnosis is {}, which the physics twin does not model; give --fault outer|inner|ball|none",
                        analysis.diagnosis.verdict.name()
                    )))
                }
            },
            None => {
                return Err(CliError::input(format!(
                    "{file}: the envelope analysis finds no fault; give the defect to model with --fault outer|inner|ball (or --fault none)"
                )))
            }
        },
    };
    let band = band_given.unwrap_or_else(|| {
        fault
            .kind()
            .and_then(|kind| analysis.hypotheses.iter().find(|h| h.score.fault == kind))
            .map_or(analysis.selected_band(), |h| {
                analysis.scan.bands[h.band_index].band
            })
    });
    let mut base = PhysicsParams::new(conditions.bearing.clone(), conditions.rpm, fault);
    base.fs_hz = conditions.fs_hz;
    base.load_n = args.load;
    base.dof = args.dof.into();
    let mut settings = CalibrationSettings::for_band(band, conditions.fs_hz);
    settings.population = args.population;
    settings.generations = args.generations;
    settings.simulated_s = args.simulated;
    settings.seed = args.seed;
    eprintln!(
        "bearingd: calibrating the physics twin ({} model, {:?} fault, {:.0} rpm, {} N) to {file} in {:.0}–{:.0} Hz: up to {} simulations of {} s on {} threads",
        match base.dof { Dof::Six => "6-DOF", Dof::Five => "5-DOF" },
        fault,
        base.rpm,
        base.load_n,
        band.lo_hz,
        band.hi_hz,
        settings.population * (settings.generations + 1),
        settings.simulated_s,
        rayon::current_num_threads()
    );
    // Compute time is reported, not used: the clock stays outside the calibration.
    let started = Instant::now();
    let calibration = calibrate(&samples, &base, band, &settings, |p| {
        eprintln!(
            "  generation {:>3}/{}: best error {:.2} dB ({} simulations, {:.1} s)",
            p.generation,
            settings.generations,
            p.best_value,
            p.evaluations,
            started.elapsed().as_secs_f64()
        );
    })
    .map_err(|e| CliError::input(format!("{file}: {e}")))?;
    let seconds = started.elapsed().as_secs_f64();
    if args.format.json() {
        println!(
            "{}",
            serde_json::json!({
                "file": file,
                "band_hz": [calibration.band.lo_hz, calibration.band.hi_hz],
                "evaluations": calibration.evaluations,
                "generations": calibration.generations,
                "seconds": seconds,
                "params": calibration.params,
                "error_db": calibration.error_db,
                "initial_error_db": calibration.initial_error_db,
                "noise_floor_g_per_sqrt_hz": calibration.noise_floor_g_per_sqrt_hz,
                "notes": remarks.notes,
                "warnings": remarks.warnings,
            })
        );
    } else {
        print_result(&file, &calibration, &base, seconds);
    }
    if let Some(path) = &args.plot {
        plot::save(&figure(&file, &calibration), path)
            .map_err(|e| CliError::failure(e.to_string()))?;
        eprintln!("bearingd: plot written to {}", path.display());
    }
    if let Some(path) = &args.save {
        let json = serde_json::to_string_pretty(&calibration.params)
            .map_err(|e| CliError::failure(format!("cannot encode the parameters: {e}")))?;
        std::fs::write(path, json + "\n")
            .map_err(|e| CliError::failure(format!("{}: cannot write: {e}", path.display())))?;
        eprintln!(
            "bearingd: parameters written to {}; simulate with: bearingd simulate --model physics --calibrated {} --out sim.wav",
            path.display(),
            path.display()
        );
    }
    Ok(())
}

fn print_result(file: &str, fit: &Calibration, base: &PhysicsParams, seconds: f64) {
    let s = &fit.params.structure;
    let d = &base.structure;
    println!("physics twin calibrated to {file}");
    println!(
        "  band {:.0}–{:.0} Hz, {} simulations in {} generations, {seconds:.1} s",
        fit.band.lo_hz, fit.band.hi_hz, fit.evaluations, fit.generations
    );
    println!(
        "  {:<34} {:>14} {:>14}",
        "parameter", "calibrated", "default"
    );
    println!(
        "  {:<34} {:>14.4e} {:>14.4e}",
        "k_r resonator stiffness (N/m)", s.resonator_stiffness, d.resonator_stiffness
    );
    println!(
        "  {:<34} {:>14.0} {:>14.0}",
        "  = resonance (Hz)",
        s.resonance_hz(),
        d.resonance_hz()
    );
    println!(
        "  {:<34} {:>14.1} {:>14.1}",
        "c_r resonator damping (N·s/m)", s.resonator_damping, d.resonator_damping
    );
    println!(
        "  {:<34} {:>14.4} {:>14.4}",
        "  = damping ratio",
        s.resonator_damping_ratio(),
        d.resonator_damping_ratio()
    );
    println!(
        "  {:<34} {:>14.4e} {:>14.4e}",
        "k_b contact stiffness (N/m^1.5)", s.contact_stiffness, d.contact_stiffness
    );
    if base.fault != SimulatedFault::None {
        println!(
            "  {:<34} {:>14.3} {:>14.3}",
            "defect width (mm)", fit.params.defect_width_mm, base.defect_width_mm
        );
    }
    println!(
        "  fit error (in-band RMS of the spectra's difference): {:.2} dB (defaults: {:.2} dB)",
        fit.error_db, fit.initial_error_db
    );
    println!(
        "  noise floor fitted beside the model: {:.3e} g/√Hz",
        fit.noise_floor_g_per_sqrt_hz
    );
}

fn figure(file: &str, fit: &Calibration) -> Figure {
    let x: Vec<f64> = (0..fit.measured.len())
        .map(|k| k as f64 * fit.bin_hz)
        .collect();
    let per_sqrt_hz = |a: &[f64]| -> Vec<f64> { a.iter().map(|v| v / fit.bin_hz.sqrt()).collect() };
    let mut panel = SpectrumPanel::new("frequency (Hz)", "amplitude (g/sqrt(Hz))", x);
    panel.log_y = true;
    panel.series.push(Series {
        label: "measured".into(),
        y: per_sqrt_hz(&fit.measured),
        color: Color::BLACK,
    });
    panel.series.push(Series {
        label: format!("calibrated twin ({:.1} dB)", fit.error_db),
        y: per_sqrt_hz(&fit.fitted),
        color: Color::VERMILLION,
    });
    panel.series.push(Series {
        label: format!("default twin ({:.1} dB)", fit.initial_error_db),
        y: per_sqrt_hz(&fit.initial),
        color: Color::SKY_BLUE,
    });
    panel.shaded.push(Shade {
        x0: fit.band.lo_hz,
        x1: fit.band.hi_hz,
        color: Color::YELLOW.with_alpha(60),
    });
    let s = &fit.params.structure;
    Figure::new(format!("Physics twin calibration: {file}"))
        .with_note(format!(
            "fitted in {:.0}–{:.0} Hz (shaded): resonance {:.0} Hz (k_r {:.3e} N/m), damping ratio {:.3} (c_r {:.0} N·s/m), k_b {:.3e} N/m^1.5, defect {:.3} mm",
            fit.band.lo_hz,
            fit.band.hi_hz,
            s.resonance_hz(),
            s.resonator_stiffness,
            s.resonator_damping_ratio(),
            s.resonator_damping,
            s.contact_stiffness,
            fit.params.defect_width_mm
        ))
        .with_panel(panel)
}
