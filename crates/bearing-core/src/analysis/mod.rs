//! The sans-IO analysis core (DESIGN.md "Data flow"): samples in, results out.
//!
//! Nothing here reads a clock, a file or a socket, and nothing here is async: the daemon, the
//! replay and `bearingd analyze` drive the same code with samples in sample time, so their
//! results cannot disagree. Buffers are owned and preallocated; the rolling path does not
//! allocate per hop.
//!
//! - [`envelope`]: squared-envelope spectrum, batch (Welch) and rolling.
//! - [`real_fft`]: the real FFT of a window, split in vector instructions.
//! - [`kurtogram`]: the band tree, spectral kurtosis, GK index, per-band spectra.
//! - [`fault_bands`]: fault-frequency scores with slip tolerance and sidebands.
//! - [`modulation`]: shaft- or cage-rate sidebands around a comb's peaks (ball or inner race).
//! - [`diagnosis`]: the verdict and its confidence; [`rolling_element`] its ball-or-inner-race part.
//! - [`indicators`]: RMS, peak, crest factor, kurtosis.
//! - [`record`]: all of the above over one whole record (`bearingd analyze`).
//! - [`speed`]: the shaft speed estimated from the spectrum near a nominal speed.
//! - [`iso`]: velocity severity and zones after ISO 10816-3 / 20816-3.
//! - [`defect_size`]: a race defect's length from its entry and exit events (≥ 40 kHz).
//! - [`degradation`]: the trend of RMS over life with its time to the failure limit (a life
//!   of snapshots is walked by `offline::life`, which also needs the twin).

pub mod agreement;
pub mod band;
pub mod band_search;
pub mod band_selection;
pub mod defect_size;
pub mod degradation;
pub mod detect;
pub mod detectors;
pub mod diagnosis;
pub mod envelope;
pub mod fault_bands;
pub mod flags;
pub mod health;
pub mod indicators;
pub mod iso;
pub mod kurtogram;
pub mod machine;
pub mod modulation;
pub mod monitor;
pub mod real_fft;
pub mod record;
pub mod rolling_element;
pub mod settings;
pub mod speed;
pub mod velocity;

pub use band::Band;
pub use diagnosis::{Diagnosis, Verdict};
pub use fault_bands::FaultScore;
pub use record::{analyze_record, AnalysisError, RecordAnalysis};
pub use settings::{AnalysisSettings, BandSelection};
