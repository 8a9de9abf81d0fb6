//! Each sensor's transport (`sim`, `can`, `shm`) and its table; nodes and services unique.

use super::*;

impl Checker {
    /// The transport and its table; tables of other transports are refused.
    pub(super) fn transport(
        &mut self,
        i: usize,
        kind: Kind,
        id: Option<&str>,
        raw: &RawSensor,
    ) -> Option<Transport> {
        let present = [
            (Kind::Sim, raw.sim.is_some()),
            (Kind::Can, raw.can.is_some()),
            (Kind::Shm, raw.shm.is_some()),
        ];
        let mut misplaced = false;
        for (other, is_present) in present {
            if is_present && other != kind {
                self.problem(
                    format!("sensors[{i}].{}", other.name()),
                    format!(
                        "[sensors.{table}] {purpose}, but this sensor's transport is {kind:?}, \
                         so it would be ignored; remove [sensors.{table}] or set transport = \
                         \"{table}\"",
                        table = other.name(),
                        purpose = other.purpose(),
                        kind = kind.name(),
                    ),
                );
                misplaced = true;
            }
        }
        let transport = match kind {
            Kind::Sim => self
                .sim(&format!("sensors[{i}].sim"), raw.sim.as_ref())
                .map(Transport::Sim),
            Kind::Can => match &raw.can {
                Some(can) => self
                    .can(&format!("sensors[{i}].can"), can)
                    .map(Transport::Can),
                None => {
                    self.problem(
                        format!("sensors[{i}].can"),
                        "missing: transport = \"can\" needs to know which bus and node to \
                         listen to; add a [sensors.can] section after this sensor's lines, \
                         e.g. interface = \"can0\" and node_id = 1",
                    );
                    None
                }
            },
            Kind::Shm => self
                .shm(&format!("sensors[{i}].shm"), id, raw.shm.as_ref())
                .map(Transport::Shm),
        };
        if misplaced {
            None
        } else {
            transport
        }
    }

    pub(super) fn can(&mut self, key: &str, raw: &RawCan) -> Option<CanConfig> {
        let interface_key = format!("{key}.interface");
        let interface_fix = "give the SocketCAN interface name, e.g. interface = \"can0\" (or \
                             \"vcan0\" for a virtual bus)";
        let interface = self
            .or_default(
                &interface_key,
                &raw.interface,
                DEFAULT_CAN_INTERFACE.to_string(),
                interface_fix,
            )
            .and_then(|name| {
                let fine = !name.is_empty()
                    && name.len() <= MAX_CAN_INTERFACE_LEN
                    && name != "."
                    && name != ".."
                    && !name.contains(['/', ':'])
                    && !name.chars().any(|c| c.is_whitespace() || c.is_control());
                if fine {
                    Some(name)
                } else {
                    self.problem(
                        &interface_key,
                        format!(
                            "{name:?} is not a network interface name (1 to \
                             {MAX_CAN_INTERFACE_LEN} bytes, no '/', ':' or spaces); \
                             {interface_fix}"
                        ),
                    );
                    None
                }
            });

        let node_key = format!("{key}.node_id");
        let node_fix = "give the sensor node's id on the bus, 0 to 15, e.g. node_id = 1";
        let node_id = self
            .required(
                &node_key,
                &raw.node_id,
                " (nodes on one bus must differ, so there is no default)",
                node_fix,
            )
            .and_then(|n| self.integer_in(&node_key, n, 0, 15, node_fix))
            .and_then(|n| u8::try_from(n).ok());

        let fd = self.or_default(
            &format!("{key}.fd"),
            &raw.fd,
            false,
            "use fd = true for CAN FD frames or fd = false for classic CAN",
        );
        Some(CanConfig {
            interface: interface?,
            node_id: node_id?,
            fd: fd?,
        })
    }

    pub(super) fn shm(
        &mut self,
        key: &str,
        id: Option<&str>,
        raw: Option<&RawShm>,
    ) -> Option<ShmConfig> {
        let service_key = format!("{key}.service");
        let fix = "give an iceoryx2 service name under bearingd/, e.g. service = \
                   \"bearingd/accel/motor-de\", or leave it out for bearingd/accel/<id>";
        let field = raw.and_then(|raw| raw.service.clone());
        let service = match self.get(&service_key, &field, fix) {
            Got::Missing => crate::iox::sensor_service(id?),
            Got::Invalid => return None,
            Got::Value(service) => service,
        };
        self.service_name(&service_key, service, fix)
            .map(|service| ShmConfig { service })
    }

    pub(super) fn sim(&mut self, key: &str, raw: Option<&RawSim>) -> Option<SimConfig> {
        let defaults = SimConfig::default();
        let empty = RawSim::default();
        let raw = raw.unwrap_or(&empty);
        let fault_key = format!("{key}.fault");
        let fault_fix = "use \"none\", \"outer\", \"inner\" or \"ball\", e.g. fault = \"outer\"";
        let fault = self
            .or_default(
                &fault_key,
                &raw.fault,
                name_of(SIM_FAULTS, defaults.fault).to_string(),
                fault_fix,
            )
            .and_then(|name| {
                self.choice(&fault_key, &name, "simulated fault", SIM_FAULTS, fault_fix)
            });
        let onset_s = self.number(
            &format!("{key}.onset_s"),
            &raw.onset_s,
            defaults.onset_s,
            Limits::within(0.0, f64::INFINITY),
            "give the sample time, in seconds from the start, at which the fault appears, \
             e.g. onset_s = 30.0",
        );
        let severity = self.number(
            &format!("{key}.severity"),
            &raw.severity,
            defaults.severity,
            Limits::within(0.0, 100.0),
            "give the impact amplitude relative to the nominal fault, e.g. severity = 1.0 \
             (0 = no impacts)",
        );
        let noise_g = self.number(
            &format!("{key}.noise_g"),
            &raw.noise_g,
            defaults.noise_g,
            Limits::within(0.0, 100.0),
            "give the standard deviation of the added noise in g, e.g. noise_g = 0.05",
        );
        let imbalance_g = self.number(
            &format!("{key}.imbalance_g"),
            &raw.imbalance_g,
            defaults.imbalance_g,
            Limits::within(0.0, 100.0),
            "give the amplitude of the once-per-revolution tone in g, e.g. imbalance_g = 0.05",
        );
        let seed_fix = "give a whole number of 0 or more, e.g. seed = 1";
        let seed = self
            .integer(
                &format!("{key}.seed"),
                &raw.seed,
                i64::try_from(defaults.seed).unwrap_or(i64::MAX),
                0,
                i64::MAX,
                seed_fix,
            )
            .and_then(|s| u64::try_from(s).ok());
        Some(SimConfig {
            fault: fault?,
            onset_s: onset_s?,
            severity: severity?,
            noise_g: noise_g?,
            imbalance_g: imbalance_g?,
            seed: seed?,
        })
    }

    /// iceoryx2 service names: under `bearingd/`, segments of `[A-Za-z0-9_.-]`.
    pub(super) fn service_name(&mut self, key: &str, service: String, fix: &str) -> Option<String> {
        let why = if !service.starts_with("bearingd/") {
            Some("does not start with bearingd/ (every bearingd service lives there)")
        } else if service.len() > MAX_SERVICE_LEN {
            Some("is longer than 255 bytes")
        } else if service.split('/').any(str::is_empty) {
            Some("has an empty segment (a doubled or trailing '/')")
        } else if !service
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.-/".contains(c))
        {
            Some("contains characters other than A-Z, a-z, 0-9, '_', '.', '-' and '/'")
        } else {
            None
        };
        match why {
            Some(why) => {
                self.problem(key, format!("{service:?} {why}; {fix}"));
                None
            }
            None => Some(service),
        }
    }

    pub(super) fn unique_sensor_ids(&mut self, sensors: &[CheckedSensor]) {
        let mut first: HashMap<&str, usize> = HashMap::new();
        for (i, sensor) in sensors.iter().enumerate() {
            let Some(id) = sensor.id.as_deref() else {
                continue;
            };
            match first.get(id) {
                Some(&earlier) => self.problem(
                    format!("sensors[{i}].id"),
                    format!(
                        "{id:?} is also the id of sensors[{earlier}]; give each sensor its own \
                         id, e.g. id = \"{id}-2\""
                    ),
                ),
                None => {
                    first.insert(id, i);
                }
            }
        }
    }

    pub(super) fn unique_can_nodes(&mut self, sensors: &[CheckedSensor]) {
        let mut first: HashMap<(&str, u8), usize> = HashMap::new();
        for (i, sensor) in sensors.iter().enumerate() {
            let Some(Transport::Can(can)) = sensor.config.as_ref().map(|c| &c.transport) else {
                continue;
            };
            match first.get(&(can.interface.as_str(), can.node_id)) {
                Some(&earlier) => self.problem(
                    format!("sensors[{i}].can.node_id"),
                    format!(
                        "node {} on {} is also sensors[{earlier}]'s node, and their frames \
                         could not be told apart; give each sensor on one bus its own node_id",
                        can.node_id, can.interface
                    ),
                ),
                None => {
                    first.insert((can.interface.as_str(), can.node_id), i);
                }
            }
        }
    }

    pub(super) fn unique_shm_services(&mut self, sensors: &[CheckedSensor]) {
        let mut first: HashMap<&str, usize> = HashMap::new();
        for (i, sensor) in sensors.iter().enumerate() {
            let Some(service) = sensor.shm_service.as_deref() else {
                continue;
            };
            match first.get(service) {
                Some(&earlier) => self.problem(
                    format!("sensors[{i}].shm.service"),
                    format!(
                        "{service:?} is also sensors[{earlier}]'s service, so their samples \
                         would mix; give each sensor its own service, e.g. service = {:?}",
                        if sensor.default_service() == service {
                            format!("{service}-2")
                        } else {
                            sensor.default_service()
                        }
                    ),
                ),
                None => {
                    first.insert(service, i);
                }
            }
        }
    }

    // ---------------------------------------------------------------------------- analysis
}
