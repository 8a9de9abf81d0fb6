//! Offline analysis of one recording: `bearingd analyze` as a library call.
//!
//! Resolves what the analysis needs and the file may not state (sample rate, shaft speed,
//! bearing) from, in order: the caller's overrides, the file itself, and the data set's own
//! documentation (IMS runs at 2000 rpm on Rexnord ZA-2115 bearings, CWRU's drive end is an
//! SKF 6205-2RS). Every assumption is written into the report's warnings; what cannot be
//! resolved is an error that says which option gives it.

use crate::analysis::defect_size::measure_for_verdict;
use crate::analysis::detect::RecordView;
use crate::analysis::detectors::DetectorSettings;
use crate::analysis::iso::{record_severity, SeveritySettings};
use crate::analysis::record::RecordAnalyzer;
use crate::analysis::{AnalysisError, AnalysisSettings, RecordAnalysis};
use crate::bearing::{BearingError, BearingGeometry};
use crate::learned::{combined as combined_with_learned, ModelError, ModelSet};
use crate::messages::FaultKind;
use crate::recording::{
    read_recording, ReadOptions, Recording, RecordingError, RecordingFormat, SampleUnit,
};
use crate::report::{AnalyzeReport, RecordContext, SpeedSource, TwinReport};
use crate::twin::diagnose::{combine, fit_record, TwinDiagnosis};
use crate::twin::fit::{TwinFitter, HYPOTHESES};
use crate::twin::{SimulatedFault, SimulationParams, Simulator};
use std::path::PathBuf;

/// What to analyse and how.
#[derive(Debug, Clone, Default)]
pub struct AnalyzeRequest {
    /// The recording; `None` analyses the built-in simulated record.
    pub file: Option<PathBuf>,
    pub read: ReadOptions,
    pub fs_hz: Option<f64>,
    pub rpm: Option<f64>,
    /// A catalog name or custom geometry; `None`: the data set's bearing, if known.
    pub bearing: Option<String>,
    pub settings: AnalysisSettings,
    /// Also fit the signal-model twin for every fault hypothesis.
    pub twin: bool,
    /// The machine group and foundation the ISO 10816-3 velocity zones are judged for.
    pub severity: SeveritySettings,
    /// A learned model's second opinion, combined with the envelope diagnosis
    /// (`analyze --learned`): the second witness of [`crate::analysis::agreement::decide`].
    /// One model per bearing: the record's is picked by its bearing.
    pub learned: Option<std::sync::Arc<ModelSet>>,
}

/// Why a recording could not be analysed. Each message names the file and the fix.
#[derive(Debug, thiserror::Error)]
pub enum OfflineError {
    #[error(transparent)]
    Recording(#[from] RecordingError),
    #[error("{file}: {source}")]
    Analysis { file: String, source: AnalysisError },
    #[error(transparent)]
    Bearing(#[from] BearingError),
    #[error("{file}: the learned opinion failed: {source}")]
    Learned { file: String, source: ModelError },
    #[error("{file}: the sample rate is unknown ({format} files do not state it); give it with --fs, e.g. --fs 12000")]
    UnknownSampleRate {
        file: String,
        format: RecordingFormat,
    },
    #[error("{file}: the shaft speed is unknown (the file does not state it); give it with --rpm RPM ({hint})")]
    UnknownSpeed { file: String, hint: String },
    #[error("{file}: which bearing is it? give --bearing with a catalog name ({known}) or custom geometry \"z=8,d=5.97mm,D=31.62mm,alpha=0\"")]
    UnknownBearing { file: String, known: String },
    #[error("{what} {value} is not usable; {fix}")]
    BadOverride {
        what: &'static str,
        value: f64,
        fix: &'static str,
    },
}

/// The outcome: the full analysis and the report made from it.
pub struct AnalyzeOutcome {
    pub analysis: RecordAnalysis,
    pub report: AnalyzeReport,
    pub twin: Option<TwinDiagnosis>,
}

/// What a data set's documentation says when the file itself does not.
#[derive(Default)]
struct DataSetFacts {
    /// The constant shaft speed, and where it comes from.
    rpm: Option<(f64, String)>,
    /// Where the speed of a file of this kind can be found, for the error when it is unknown.
    rpm_hint: Option<String>,
    /// The bearing, and why it is assumed.
    bearing: Option<(BearingGeometry, String)>,
}

/// A catalog bearing with the reason it is assumed.
fn catalog(name: &str, why: &str) -> Option<(BearingGeometry, String)> {
    BearingGeometry::from_catalog(name)
        .ok()
        .map(|b| (b, format!("{name} ({why})")))
}

/// PRONOSTIA's operating conditions (the IEEE PHM 2012 challenge's): condition, shaft rpm.
const PRONOSTIA_CONDITIONS: [(u32, f64); 3] = [(1, 1800.0), (2, 1650.0), (3, 1500.0)];

/// The speed of a PRONOSTIA snapshot's operating condition, read from the directory its
/// bearing's files lie in (`Bearing1_2/acc_00001.csv`: condition 1), as the data set names them.
fn pronostia_condition_rpm(path: &std::path::Path) -> Option<(f64, String)> {
    let dir = path.parent()?.file_name()?.to_str()?;
    let condition: u32 = dir
        .strip_prefix("Bearing")?
        .split('_')
        .next()?
        .parse()
        .ok()?;
    let (_, rpm) = PRONOSTIA_CONDITIONS.iter().find(|(c, _)| *c == condition)?;
    Some((
        *rpm,
        format!("PRONOSTIA's operating condition {condition} (the directory {dir})"),
    ))
}

/// `X105_DE_time` and the like: a CWRU variable of the drive end, fan end or base.
fn is_cwru_channel(channel: &str) -> bool {
    channel.starts_with('X')
        && ["_DE_time", "_FE_time", "_BA_time"]
            .iter()
            .any(|s| channel.ends_with(s))
}

fn data_set_facts(recording: &Recording) -> DataSetFacts {
    match recording.format {
        RecordingFormat::Matlab if is_cwru_channel(&recording.channel) => DataSetFacts {
            rpm: None,
            rpm_hint: Some("a CWRU record states it in its XNNNRPM variable (1797 rpm at 0 hp, down to 1720 rpm at 3 hp)".into()),
            bearing: if recording.channel.contains("_FE_") {
                catalog("skf-6203-2rs", "the CWRU fan-end bearing")
            } else {
                catalog("skf-6205-2rs", "the CWRU drive-end bearing")
            },
        },
        // The MFPT data set: struct `bearing` with the signal in `gs`.
        RecordingFormat::Matlab if recording.channel == "bearing.gs" => DataSetFacts {
            rpm: None,
            rpm_hint: Some("an MFPT record states it in its `bearing.rate` field (shaft rate in Hz: 25 Hz is 1500 rpm)".into()),
            bearing: catalog("mfpt", "the MFPT data set's NICE bearing"),
        },
        RecordingFormat::PronostiaCsv => DataSetFacts {
            rpm: pronostia_condition_rpm(&recording.path),
            rpm_hint: Some(format!(
                "PRONOSTIA's speed is its operating condition's: {}",
                PRONOSTIA_CONDITIONS
                    .iter()
                    .map(|(c, rpm)| format!("{rpm} rpm for Bearing{c}_N"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
            bearing: catalog("pronostia", "the PRONOSTIA test bearing"),
        },
        RecordingFormat::ImsText => DataSetFacts {
            rpm: Some((2000.0, "the IMS test rig's constant speed".into())),
            rpm_hint: None,
            bearing: catalog("rexnord-za-2115", "the IMS test rig's bearing"),
        },
        RecordingFormat::McapLog => DataSetFacts {
            rpm: None,
            rpm_hint: Some("a bearingd log states it in its /speed messages or its config's [sensors.speed]".into()),
            bearing: logged_bearing(&recording.path, &recording.channel)
                .or_else(|| embedded_default_bearing(&recording.channel)),
        },
        RecordingFormat::Matlab | RecordingFormat::PlainCsv | RecordingFormat::Wav => {
            DataSetFacts::default()
        }
    }
}

/// The bearing of sensor `sensor/axis` in the config a log records (its `bearingd.config`
/// record: logs of `bearingd run`, `import` and `dataset`).
fn logged_bearing(path: &std::path::Path, channel: &str) -> Option<(BearingGeometry, String)> {
    let sensor = channel.split('/').next()?;
    let json = crate::mcap_log::read_header(path).ok()?.config_json?;
    let config = crate::config::config_from_log(&json).ok()?;
    let found = config.sensors.into_iter().find(|s| s.id == sensor)?;
    let name = found.bearing.name.clone();
    Some((
        found.bearing,
        format!("{name}, the bearing of sensor '{sensor}' in the config the log records"),
    ))
}

/// The bearing of sensor `sensor/axis` in the embedded default config, for logs that record
/// no config (written before logs carried it).
fn embedded_default_bearing(channel: &str) -> Option<(BearingGeometry, String)> {
    let sensor = channel.split('/').next()?;
    let config = crate::config::Config::default_embedded().ok()?;
    let found = config.sensors.into_iter().find(|s| s.id == sensor)?;
    let name = found.bearing.name.clone();
    Some((
        found.bearing,
        format!(
            "{name}, the bearing of sensor '{sensor}' in the embedded default config: the log does not record its bearing"
        ),
    ))
}

/// Ten seconds of the twin's outer-race fault: needs no data and no hardware.
pub fn demo_recording() -> Recording {
    let params = SimulationParams::example(SimulatedFault::OuterRace);
    let samples = Simulator::record(params.clone(), 10.0)
        .into_iter()
        .map(f64::from)
        .collect();
    Recording {
        path: PathBuf::from(format!("demo:outer_race(seed {})", params.seed)),
        format: RecordingFormat::Wav,
        channel: "simulated".into(),
        fs_hz: Some(params.fs_hz),
        rpm: Some(params.rpm),
        samples,
        unit: SampleUnit::G,
        warnings: Vec::new(),
        notes: vec![format!(
            "simulated record: outer-race fault on {}, resonance {:.0} Hz, noise {} g, seed {}",
            params.bearing.name, params.resonance_hz, params.noise_g, params.seed
        )],
    }
}

/// What a recording was taken under, resolved from the caller's overrides, the file and the
/// data set's documentation.
#[derive(Debug, Clone)]
pub struct Conditions {
    pub fs_hz: f64,
    pub rpm: f64,
    pub rpm_source: SpeedSource,
    pub bearing: BearingGeometry,
    /// What was assumed and why (a bearing or a speed from the data set's documentation, a
    /// simulated record's settings): information, shown as `note:`.
    pub notes: Vec<String>,
    /// What is wrong with the file as read (the reader's own findings), shown as `warning:`.
    pub warnings: Vec<String>,
}

/// Resolves sample rate, speed and bearing for `recording` (`request.fs_hz`, `.rpm`,
/// `.bearing` override); used by `analyze` and `import`.
pub fn resolve_conditions(
    recording: &Recording,
    request: &AnalyzeRequest,
    simulated: bool,
) -> Result<Conditions, OfflineError> {
    let facts = if simulated {
        DataSetFacts {
            rpm: None,
            rpm_hint: None,
            bearing: catalog("skf-6205-2rs", "the simulated bearing"),
        }
    } else {
        data_set_facts(recording)
    };
    let file = recording.path.display().to_string();
    let fs_hz = match request.fs_hz {
        Some(fs) if !(fs.is_finite() && fs > 0.0) => {
            return Err(OfflineError::BadOverride {
                what: "--fs",
                value: fs,
                fix: "give the sample rate in Hz, e.g. --fs 12000",
            })
        }
        Some(fs) => fs,
        None => recording
            .fs_hz
            .ok_or_else(|| OfflineError::UnknownSampleRate {
                file: file.clone(),
                format: recording.format,
            })?,
    };
    let (rpm, rpm_source) = match (request.rpm, recording.rpm, &facts.rpm) {
        (Some(rpm), _, _) if !(rpm.is_finite() && rpm > 0.0) => {
            return Err(OfflineError::BadOverride {
                what: "--rpm",
                value: rpm,
                fix: "give the shaft speed in rpm, a positive number, e.g. --rpm 1500",
            })
        }
        (Some(rpm), _, _) => (rpm, SpeedSource::Given),
        (None, Some(rpm), _) => (
            rpm,
            if simulated {
                SpeedSource::Simulation
            } else {
                SpeedSource::File
            },
        ),
        (None, None, Some((rpm, _))) => (*rpm, SpeedSource::DataSetDefault),
        (None, None, None) => {
            return Err(OfflineError::UnknownSpeed {
                file,
                hint: facts
                    .rpm_hint
                    .unwrap_or_else(|| "the motor's nameplate or a tachometer gives it".into()),
            })
        }
    };
    let mut notes = recording.notes.clone();
    let warnings = recording.warnings.clone();
    let bearing = match (&request.bearing, facts.bearing) {
        (Some(text), _) => BearingGeometry::parse(text)?,
        (None, Some((bearing, why))) => {
            if !simulated {
                notes.push(format!(
                    "bearing not given: assumed {why}; give --bearing to change"
                ));
            }
            bearing
        }
        (None, None) => {
            return Err(OfflineError::UnknownBearing {
                file,
                known: BearingGeometry::catalog_names().join(", "),
            });
        }
    };
    if rpm_source == SpeedSource::DataSetDefault {
        let why = facts.rpm.map(|(_, why)| why).unwrap_or_default();
        notes.push(format!(
            "speed not in the file: assumed {rpm} rpm, {why}; give --rpm to change"
        ));
    }
    Ok(Conditions {
        fs_hz,
        rpm,
        rpm_source,
        bearing,
        notes,
        warnings,
    })
}

/// Reads (or simulates) the record, resolves its conditions, analyses it.
pub fn analyze(
    request: &AnalyzeRequest,
    analyzer: &mut RecordAnalyzer,
) -> Result<AnalyzeOutcome, OfflineError> {
    match &request.file {
        Some(path) => {
            let recording = read_recording(path, &request.read)?;
            analyze_recording(&recording, false, request, analyzer)
        }
        None => analyze_recording(&demo_recording(), true, request, analyzer),
    }
}

/// [`analyze`] of a recording already read (`simulated`: the demo record); `request.file` and
/// `request.read` are not looked at. For callers that also need the samples, such as
/// `evaluate --recordings`, which imports the same recording for the daemon.
pub fn analyze_recording(
    recording: &Recording,
    simulated: bool,
    request: &AnalyzeRequest,
    analyzer: &mut RecordAnalyzer,
) -> Result<AnalyzeOutcome, OfflineError> {
    let Conditions {
        fs_hz,
        rpm,
        rpm_source,
        bearing,
        notes,
        warnings,
    } = resolve_conditions(recording, request, simulated)?;
    let file = recording.path.display().to_string();
    let freqs = bearing.fault_frequencies(rpm / 60.0);
    let samples: Vec<f32> = recording.samples.iter().map(|&x| x as f32).collect();
    let mut analysis = analyzer
        .analyze(&samples, fs_hz, &freqs, &request.settings)
        .map_err(|source| OfflineError::Analysis {
            file: file.clone(),
            source,
        })?;
    // The learned model is the second witness of the same samples: the verdict hears it
    // before the report is made from it, so the report shows the band of what it names.
    let envelope_verdict = analysis.diagnosis.verdict;
    let learned = match &request.learned {
        Some(models) => {
            let learned_error = |source| OfflineError::Learned {
                file: file.clone(),
                source,
            };
            let model = models.for_bearing(&bearing).map_err(learned_error)?;
            let opinion = model
                .opinion_of_checked(&samples, fs_hz, &freqs)
                .map_err(learned_error)?;
            analysis.hear_witness(opinion.as_witness(), &request.settings);
            Some((model, opinion))
        }
        None => None,
    };
    let context = RecordContext {
        file,
        channel: recording.channel.clone(),
        rpm,
        rpm_source,
        bearing,
        selection: request.settings.band_selection,
        unit: recording.unit,
        notes,
        warnings,
    };
    let mut report = AnalyzeReport::new(&context, &analysis, &request.settings);
    // Velocity needs acceleration in physical units, not fractions of a recorder's full scale.
    if recording.unit == SampleUnit::FullScale {
        report.notes.push(
            "no ISO 10816-3 velocity: the samples are fractions of full scale, not g; give --unit g or --unit m/s2 if the recorder's full scale is known".to_string(),
        );
    } else {
        report.velocity =
            record_severity(&mut analyzer.plans, &samples, fs_hz, rpm, request.severity);
    }
    let record = RecordView {
        shaft_hz: rpm / 60.0,
        velocity: report.velocity.as_ref(),
    };
    let detectors = DetectorSettings::for_records().with_severity(request.severity);
    for found in detectors.analyze_record(&record) {
        report.detectors.insert(found.key.to_string(), found.json);
        report.detector_lines.extend(found.lines);
    }
    let twin = request.twin.then(|| {
        let band_of = |kind: FaultKind| {
            analysis
                .hypotheses
                .iter()
                .find(|h| h.score.fault == kind)
                .map_or(analysis.band(), |h| analysis.scan.bands[h.band_index].band)
        };
        let bands = HYPOTHESES.map(band_of);
        // Compute time is reported, not used: the clock stays outside the analysis.
        let started = std::time::Instant::now();
        let twin = fit_record(
            &mut analyzer.plans,
            &mut TwinFitter::default(),
            &samples,
            fs_hz,
            &freqs,
            &bands,
            analysis.window,
            request.settings.overlap,
            None,
        );
        let fit_ms = started.elapsed().as_secs_f64() * 1e3;
        let (combined, agrees, note) = combine(&analysis.diagnosis, &twin);
        report.set_twin(TwinReport::new(&twin, fit_ms, agrees, note), &combined);
        twin
    });
    if let Some((model, opinion)) = learned {
        if opinion.segments == 0 {
            let segment = model.card.features.segment_revolutions;
            report.warnings.push(format!(
                "no learned opinion: the record is shorter than one segment of {segment} shaft revolutions ({:.2} s at {rpm:.0} rpm)",
                segment * 60.0 / rpm
            ));
        }
        let combined = combined_with_learned(&analysis.diagnosis, &opinion);
        report.set_learned(opinion, combined, envelope_verdict);
    }
    let verdict = analysis.diagnosis.verdict;
    // After the verdict is final: only a named race fault is sized. Not in the daemon's
    // per-window path: it needs the whole record's impacts.
    report.set_defect_size(measure_for_verdict(
        &samples,
        &analysis,
        verdict,
        &report.bearing_geometry,
    ));
    Ok(AnalyzeOutcome {
        analysis,
        report,
        twin,
    })
}
