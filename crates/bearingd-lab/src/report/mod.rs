//! What the lab shows of the service's results, beside the service's own text and JSON
//! ([`bearingd::report`]): the figure of one analysed record (`analyze --plot`) and a bearing's
//! life of snapshots (`trend`) as text, JSON and a figure. The figure is drawn from the same
//! [`bearingd::report::AnalyzeReport`] as the text, so the two cannot disagree.

mod figure;
mod life;

pub use figure::analysis_figure;
pub use life::{
    duration_text, life_figure, render_life_text, LifeGap, LifeReport, LifeSettingsReport,
    SkippedFile,
};
