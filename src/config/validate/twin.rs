//! `[twin]`: the digital twin's re-fit settings.

use super::*;

impl Checker {
    pub(super) fn twin(&mut self, raw: &RawTwin) -> Option<TwinConfig> {
        let d = TwinConfig::default();
        let refit_period_s = self.number(
            "twin.refit_period_s",
            &raw.refit_period_s,
            d.refit_period_s,
            Limits::above_to(0.0, DAY_S),
            "give the sample time between twin re-fits in seconds, e.g. refit_period_s = 10.0",
        );
        let window_s = self.number(
            "twin.window_s",
            &raw.window_s,
            d.window_s,
            Limits::above_to(0.05, 10.0),
            "give the length of signal each twin fit uses in seconds, e.g. window_s = 1.0",
        );
        Some(TwinConfig {
            refit_period_s: refit_period_s?,
            window_s: window_s?,
        })
    }
}
