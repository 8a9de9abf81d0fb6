//! iceoryx2 names, the file prefix and the root: one place.
//!
//! The conventions themselves live in the `bearing-iox` crate, shared with the publishers
//! (`firmware-sim`), so the two ends cannot disagree; this module is bearingd's door to them.
//! Every node bearingd creates (the iceoryx2 source, the alert service, `bearingd alerts`)
//! takes its settings from [`IoxSettings::with_root`]: the config's `outputs.iceoryx2_root`
//! and the file prefix from `$BEARINGD_IOX_PREFIX` ([`PREFIX_ENV`]).

pub use bearing_iox::*;
