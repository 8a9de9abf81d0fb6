//! `[twin]`: the digital twin's re-fit settings.

use super::*;

impl Checker {
    pub(super) fn twin(&mut self, raw: &RawTwin, sensors: &[CheckedSensor]) -> Option<TwinConfig> {
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
        let hw_enabled = self.or_default(
            "twin.hw_enabled",
            &raw.hw_enabled,
            d.hw_enabled,
            "use true to re-identify the Hammerstein–Wiener model with each fit, or false",
        );
        let hw_order = self.integer(
            "twin.hw_order",
            &raw.hw_order,
            0,
            0,
            9,
            "give the HW model's output state order, e.g. hw_order = 0 (the acceleration)",
        );
        let hw_samples = self.integer(
            "twin.hw_samples",
            &raw.hw_samples,
            i64::try_from(d.hw_samples).unwrap_or(2560),
            256,
            65_536,
            "give how many of the newest samples the HW model is identified on, e.g. hw_samples = 2560",
        );
        let hw_baseline_fits = self.integer(
            "twin.hw_baseline_fits",
            &raw.hw_baseline_fits,
            i64::try_from(d.hw_baseline_fits).unwrap_or(10),
            2,
            10_000,
            "give how many HW fits form the healthy baseline, e.g. hw_baseline_fits = 10",
        );
        let learned_model = self.learned_model(&raw.learned_model, sensors);
        Some(TwinConfig {
            refit_period_s: refit_period_s?,
            window_s: window_s?,
            hw_enabled: hw_enabled?,
            hw_order: usize::try_from(hw_order?).ok()?,
            hw_samples: usize::try_from(hw_samples?).ok()?,
            hw_baseline_fits: u64::try_from(hw_baseline_fits?).ok()?,
            learned_model: learned_model?,
        })
    }

    /// The learned model (a file, or a directory of one model per bearing) must load and
    /// have a model for every sensor's bearing.
    fn learned_model(
        &mut self,
        field: &Field<String>,
        sensors: &[CheckedSensor],
    ) -> Option<Option<PathBuf>> {
        let key = "twin.learned_model";
        let fix = "give a model file of `bearingd train` or a directory of them, e.g. \
                   learned_model = \"/usr/share/bearingd/models\", or remove the key";
        let Some(path) = self.optional_text(key, field, fix)?.map(PathBuf::from) else {
            return Some(None);
        };
        let models = match crate::learned::ModelSet::load(&path) {
            Ok(models) => models,
            Err(e) => {
                self.problem(key, format!("{e}"));
                return None;
            }
        };
        let mut fits = true;
        for sensor in sensors.iter().filter_map(|s| s.config.as_ref()) {
            if let Err(e) = models.for_bearing(&sensor.bearing) {
                self.problem(key, format!("sensor {}: {e}", sensor.id));
                fits = false;
            }
        }
        fits.then_some(Some(path))
    }
}
