//! Which rolling-element part: a damaged ball against an inner-race defect (docs/DIAGNOSIS.md).
//!
//! The thresholds of the anchored sideband contrast ([`super::modulation`]).

/// (not calibrated yet) How far a shared comb's contrast must lean to name one of the pair:
/// noise and unmodulated (uniform-load) shared combs stay below it.
pub const SEPARATION_Z: f64 = 1.5;

/// (not calibrated yet) The contrast a rival's own modulation must show for "both patterns
/// show": noise alone reaches it in well under 0.5 % of spectra (the modulation tests).
pub const RIVAL_CONTRAST_Z: f64 = 3.0;
