//! `[thresholds]`: the fault flags' thresholds and delays.

use super::*;

impl Checker {
    pub(super) fn thresholds(&mut self, raw: &RawThresholds) -> Option<ThresholdConfig> {
        let d = ThresholdConfig::default();
        let watch_score = self.number(
            "thresholds.watch_score",
            &raw.watch_score,
            d.watch_score,
            Limits::above_to(0.0, f64::INFINITY),
            "give the fault score at which a flag rises to watch, e.g. watch_score = 5.0",
        );
        let alarm_fix = "give the fault score at which a flag rises to alarm, above \
                         watch_score, e.g. alarm_score = 10.0";
        let alarm_score = self.number(
            "thresholds.alarm_score",
            &raw.alarm_score,
            d.alarm_score,
            Limits::above_to(0.0, f64::INFINITY),
            alarm_fix,
        );
        let alarm_score = match (watch_score, alarm_score) {
            (Some(watch), Some(alarm)) if alarm <= watch => {
                self.problem(
                    "thresholds.alarm_score",
                    format!(
                        "{alarm} is not above watch_score = {watch}, so a flag could never be \
                         in watch; raise alarm_score above {watch} or lower watch_score"
                    ),
                );
                None
            }
            (_, alarm) => alarm,
        };
        let clear_ratio = self.number(
            "thresholds.clear_ratio",
            &raw.clear_ratio,
            d.clear_ratio,
            Limits::between(0.0, 1.0),
            "give the fraction of its threshold below which a flag clears, between 0 and 1 \
             (exclusive), e.g. clear_ratio = 0.8",
        );
        let on_delay_s = self.number(
            "thresholds.on_delay_s",
            &raw.on_delay_s,
            d.on_delay_s,
            Limits::within(0.0, DAY_S),
            "give how long, in seconds, a score must stay above a threshold before the flag \
             rises, e.g. on_delay_s = 5.0",
        );
        let off_delay_s = self.number(
            "thresholds.off_delay_s",
            &raw.off_delay_s,
            d.off_delay_s,
            Limits::within(0.0, DAY_S),
            "give how long, in seconds, a score must stay below the clear level before the \
             flag falls, e.g. off_delay_s = 30.0",
        );
        let baseline_windows = self
            .integer(
                "thresholds.baseline_windows",
                &raw.baseline_windows,
                i64::try_from(d.baseline_windows).unwrap_or(30),
                5,
                100_000,
                "give how many analysis windows form the health baseline, at least 5, e.g. \
                 baseline_windows = 30",
            )
            .and_then(|n| usize::try_from(n).ok());
        let sigma = self.number(
            "thresholds.sigma",
            &raw.sigma,
            d.sigma,
            Limits::above_to(0.0, 100.0),
            "give how many standard deviations above the baseline mark a new health stage, \
             e.g. sigma = 3.0",
        );
        let trend_point_s = self.number(
            "thresholds.trend_point_s",
            &raw.trend_point_s,
            d.trend_point_s,
            Limits::above_to(0.0, DAY_S),
            "give the sample time per point of the RMS trend in seconds, e.g. trend_point_s = 60.0",
        );
        let trend_points = self
            .integer(
                "thresholds.trend_points",
                &raw.trend_points,
                i64::try_from(d.trend_points).unwrap_or(30),
                4,
                10_000,
                "give how many trend points are fitted, at least 4, e.g. trend_points = 30",
            )
            .and_then(|n| usize::try_from(n).ok());
        Some(ThresholdConfig {
            watch_score: watch_score?,
            alarm_score: alarm_score?,
            clear_ratio: clear_ratio?,
            on_delay_s: on_delay_s?,
            off_delay_s: off_delay_s?,
            baseline_windows: baseline_windows?,
            sigma: sigma?,
            trend_point_s: trend_point_s?,
            trend_points: trend_points?,
        })
    }

    // ------------------------------------------------------------------------------ outputs
}
