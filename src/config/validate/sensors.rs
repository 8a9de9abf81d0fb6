//! `[[sensors]]`: each sensor's id, rate, axes, bearing and speed; ids unique.

use super::*;

impl Checker {
    pub(super) fn sensors(&mut self, raw: &[RawSensor]) -> Vec<CheckedSensor> {
        if raw.is_empty() {
            self.problem(
                "sensors",
                "no sensor is configured; add a [[sensors]] section with at least id, \
                 transport, sample_rate_hz, bearing and [sensors.speed] rpm, e.g. the one in \
                 config/bearingd.toml (`bearingd run` without --config runs it)",
            );
        }
        let checked: Vec<CheckedSensor> = raw
            .iter()
            .enumerate()
            .map(|(i, sensor)| self.sensor(i, sensor))
            .collect();
        self.unique_sensor_ids(&checked);
        self.unique_can_nodes(&checked);
        self.unique_shm_services(&checked);
        checked
    }

    pub(super) fn sensor(&mut self, i: usize, raw: &RawSensor) -> CheckedSensor {
        let at = |key: &str| format!("sensors[{i}].{key}");

        let id = self.sensor_id(&at("id"), &raw.id);
        let transport_fix = "use \"sim\", \"can\" or \"shm\", e.g. transport = \"can\"";
        let kind = self
            .required(
                &at("transport"),
                &raw.transport,
                " (how the samples arrive)",
                transport_fix,
            )
            .and_then(|name| {
                self.choice(
                    &at("transport"),
                    &name,
                    "transport",
                    &[("sim", Kind::Sim), ("can", Kind::Can), ("shm", Kind::Shm)],
                    transport_fix,
                )
            });

        let sample_rate_hz = self.sample_rate(&at("sample_rate_hz"), &raw.sample_rate_hz);

        let scale_g_per_count = self.number(
            &at("scale_g_per_count"),
            &raw.scale_g_per_count,
            DEFAULT_SCALE_G_PER_COUNT,
            Limits::above_to(0.0, 1000.0),
            "give the acceleration in g of one count on the wire, e.g. 0.000488 for ±16 g over \
             16 bits",
        );

        let axes = self.axes(&at("axes"), &raw.axes);

        let bearing = self.bearing(&at("bearing"), &raw.bearing);

        let speed = self.speed(&at("speed"), raw.speed.as_ref(), kind);

        let transport = match kind {
            Some(kind) => self.transport(i, kind, id.as_deref(), raw),
            None => {
                // The transport is unusable; still check whatever transport tables are there,
                // so that their mistakes surface in this round too.
                if let Some(sim) = &raw.sim {
                    self.sim(&at("sim"), Some(sim));
                }
                if let Some(can) = &raw.can {
                    self.can(&at("can"), can);
                }
                if raw.shm.is_some() {
                    self.shm(&at("shm"), id.as_deref(), raw.shm.as_ref());
                }
                None
            }
        };
        let shm_service = match &transport {
            Some(Transport::Shm(shm)) => Some(shm.service.clone()),
            _ => None,
        };

        let config = (|| {
            Some(SensorConfig {
                id: id.clone()?,
                transport: transport?,
                sample_rate_hz: sample_rate_hz?,
                scale_g_per_count: scale_g_per_count?,
                axes: axes?,
                bearing: bearing?,
                speed: speed?,
            })
        })();
        CheckedSensor {
            index: i,
            config,
            id,
            sample_rate_hz,
            shm_service,
        }
    }

    pub(super) fn sensor_id(&mut self, key: &str, field: &Field<String>) -> Option<String> {
        let fix = "give a short name of lowercase letters, digits, '-' and '_', e.g. id = \
                   \"motor-de\"";
        let id = self.required(
            key,
            field,
            " (it names the sensor's MCAP channels and iceoryx2 services)",
            fix,
        )?;
        let length = id.chars().count();
        if id.is_empty() {
            self.problem(key, format!("the id is empty; {fix}"));
            None
        } else if length > MAX_ID_LEN {
            self.problem(
                key,
                format!("{id:?} has {length} characters, more than {MAX_ID_LEN}; {fix}"),
            );
            None
        } else if !id.chars().all(is_name_char) {
            self.problem(
                key,
                format!(
                    "{id:?} contains characters other than a-z, 0-9, '-' and '_' (the id is \
                     used in MCAP channel and iceoryx2 service names); {fix}"
                ),
            );
            None
        } else {
            Some(id)
        }
    }

    pub(super) fn sample_rate(&mut self, key: &str, field: &Field<f64>) -> Option<f64> {
        let fix = "give the sensor's sample rate in Hz, e.g. 25600";
        let rate = self.required(
            key,
            field,
            " (a wrong rate shifts every fault frequency, so there is no default)",
            fix,
        )?;
        if !rate.is_finite() || rate <= 0.0 {
            self.problem(key, format!("{rate} is not a sample rate; {fix}"));
            None
        } else if rate > 1_000_000.0 {
            self.problem(
                key,
                format!("{rate} Hz is above the limit of 1000000 Hz; {fix}"),
            );
            None
        } else {
            Some(rate)
        }
    }

    pub(super) fn axes(&mut self, key: &str, field: &Field<Vec<String>>) -> Option<Vec<String>> {
        let fix = "give 1 to 3 distinct axis names of lowercase letters, digits, '-' and '_', \
                   e.g. axes = [\"radial\"] or axes = [\"x\", \"y\", \"z\"]";
        let axes = self.or_default(key, field, vec![DEFAULT_AXIS.to_string()], fix)?;
        let mut ok = true;
        if axes.is_empty() || axes.len() > 3 {
            self.problem(
                key,
                format!("{} axes given, but a sensor has 1 to 3; {fix}", axes.len()),
            );
            ok = false;
        }
        for (j, axis) in axes.iter().enumerate() {
            if axis.is_empty()
                || axis.chars().count() > MAX_ID_LEN
                || !axis.chars().all(is_name_char)
            {
                self.problem(
                    format!("{key}[{j}]"),
                    format!(
                        "{axis:?} is not an axis name (1 to {MAX_ID_LEN} of a-z, 0-9, '-', '_'); \
                         {fix}"
                    ),
                );
                ok = false;
            } else if let Some(first) = axes[..j].iter().position(|a| a == axis) {
                self.problem(
                    format!("{key}[{j}]"),
                    format!("{axis:?} is already {key}[{first}]; {fix}"),
                );
                ok = false;
            }
        }
        ok.then_some(axes)
    }

    pub(super) fn bearing(&mut self, key: &str, field: &Field<String>) -> Option<BearingGeometry> {
        let example = "\"z=9,d=7.94mm,D=39.04mm,alpha=0\"";
        let catalog = BearingGeometry::catalog_names().join(", ");
        let fix =
            format!("use a catalog name ({catalog}) or custom geometry, e.g. bearing = {example}");
        let text = self.required(
            key,
            field,
            " (its geometry sets the fault frequencies)",
            &fix,
        )?;
        match BearingGeometry::parse(&text) {
            Ok(geometry) => Some(geometry),
            Err(BearingError::UnknownName { name, .. }) => {
                self.problem(key, format!("unknown bearing {name:?}; {fix}"));
                None
            }
            Err(BearingError::BadGeometry { text, problem }) => {
                self.problem(
                    key,
                    format!(
                        "bad custom geometry {text:?}: {problem}; give z (rolling elements), \
                         d and D (element and pitch diameters, mm or in) and alpha (contact \
                         angle, degrees), e.g. bearing = {example}"
                    ),
                );
                None
            }
        }
    }

    pub(super) fn speed(
        &mut self,
        key: &str,
        raw: Option<&RawSpeed>,
        kind: Option<Kind>,
    ) -> Option<Speed> {
        let rpm_key = format!("{key}.rpm");
        let rpm_fix = "give the shaft speed in revolutions per minute under [sensors.speed], \
                       e.g. rpm = 1772";
        let Some(raw) = raw else {
            self.problem(
                rpm_key,
                format!(
                    "missing (the fault frequencies scale with the shaft speed, so there is no \
                     default); {rpm_fix}"
                ),
            );
            return None;
        };
        let source_key = format!("{key}.source");
        let source_fix = "use source = \"fixed\" with rpm = the shaft speed, \"can\" for the \
                          sensor's speed frames, or \"estimate\" with rpm = the nominal speed";
        let source = self.or_default(&source_key, &raw.source, "fixed".to_string(), source_fix)?;
        let speed_limits = Limits::between(0.0, 100_000.0);
        // A key the chosen source does not read would be silently ignored: refuse it.
        let unused = |check: &mut Self, name: &str, present: bool, readers: &str| {
            if present {
                check.problem(
                    format!("{key}.{name}"),
                    format!(
                        "{name} is read only with {readers}, so with source = {source:?} it \
                         would be ignored; remove it or change the source"
                    ),
                );
            }
        };
        match source.as_str() {
            "fixed" => {
                unused(self, "max_rpm", raw.max_rpm.is_some(), "source = \"can\"");
                unused(
                    self,
                    "search",
                    raw.search.is_some(),
                    "source = \"estimate\"",
                );
                let rpm = self.required(
                    &rpm_key,
                    &raw.rpm,
                    " (source = \"fixed\" needs the speed)",
                    rpm_fix,
                )?;
                let rpm = self.in_limits(&rpm_key, rpm, speed_limits, rpm_fix)?;
                (raw.max_rpm.is_none() && raw.search.is_none()).then_some(Speed::Fixed { rpm })
            }
            "can" => {
                unused(
                    self,
                    "search",
                    raw.search.is_some(),
                    "source = \"estimate\"",
                );
                if kind == Some(Kind::Sim) {
                    self.problem(
                        &source_key,
                        "the simulated sensor (transport = \"sim\") sends no speed frames; use \
                         source = \"fixed\" or \"estimate\", or a \"can\" or \"shm\" sensor",
                    );
                }
                let nominal_fix = "give the speed to assume until the first speed frame, e.g. \
                                   rpm = 1772, or leave rpm out to score nothing until then";
                let nominal = match self.get(&rpm_key, &raw.rpm, nominal_fix) {
                    Got::Missing => Some(None),
                    Got::Invalid => None,
                    Got::Value(rpm) => self
                        .in_limits(&rpm_key, rpm, speed_limits, nominal_fix)
                        .map(Some),
                };
                let max_key = format!("{key}.max_rpm");
                let max_fix = "give the highest shaft speed the machine runs at, e.g. max_rpm = \
                               3600 (the envelope spectrum is sized for its fault harmonics)";
                let max_rpm = match (self.get(&max_key, &raw.max_rpm, max_fix), nominal) {
                    (Got::Value(max), _) => self.in_limits(&max_key, max, speed_limits, max_fix),
                    (Got::Missing, Some(Some(rpm))) => Some(rpm * DEFAULT_MAX_RPM_FACTOR),
                    (Got::Missing, Some(None)) => {
                        self.problem(
                            &max_key,
                            format!(
                                "missing: without a nominal rpm there is no default for the \
                                 highest speed; {max_fix}"
                            ),
                        );
                        None
                    }
                    _ => None,
                };
                let (nominal_rpm, max_rpm) = (nominal?, max_rpm?);
                if let Some(rpm) = nominal_rpm.filter(|&rpm| rpm >= max_rpm) {
                    self.problem(
                        &max_key,
                        format!(
                            "max_rpm {max_rpm} is not above the nominal rpm {rpm}; raise max_rpm \
                             or lower rpm"
                        ),
                    );
                    return None;
                }
                (kind != Some(Kind::Sim) && raw.search.is_none()).then_some(Speed::Frames {
                    nominal_rpm,
                    max_rpm,
                })
            }
            "estimate" => {
                unused(self, "max_rpm", raw.max_rpm.is_some(), "source = \"can\"");
                let rpm = self.required(
                    &rpm_key,
                    &raw.rpm,
                    " (source = \"estimate\" searches near the nominal speed)",
                    "give the nominal shaft speed in revolutions per minute, e.g. rpm = 1772",
                )?;
                let rpm = self.in_limits(&rpm_key, rpm, speed_limits, rpm_fix)?;
                let search = self.number(
                    &format!("{key}.search"),
                    &raw.search,
                    DEFAULT_SPEED_SEARCH,
                    Limits::above_to(0.0, 0.3),
                    "give the relative half-width of the search around rpm, e.g. search = 0.05 \
                     for ±5 %",
                )?;
                raw.max_rpm
                    .is_none()
                    .then_some(Speed::Estimate { rpm, search })
            }
            other => {
                self.problem(
                    source_key,
                    format!("unknown speed source {other:?}; {source_fix}"),
                );
                None
            }
        }
    }
}
