//! `[fleet]`: the fleet bridge over MQTT Sparkplug B (`src/sinks/fleet`, `docs/FLEET.md`).

use crate::config::ConfigError;

use super::super::raw::RawFleet;
use super::super::types::{Broker, FleetConfig};
use super::*;

impl FleetConfig {
    /// The bridge with its defaults for `broker` (`mqtt://…` or `mqtts://…`), node id
    /// `node_id` and the queue under `state_dir`: `bearingd run --fleet BROKER`, a first look
    /// without writing a config. Problems are those `[fleet]` would report for the same keys.
    pub fn for_broker(
        broker: &str,
        node_id: &str,
        state_dir: &Path,
    ) -> Result<FleetConfig, ConfigError> {
        let raw = RawFleet {
            enabled: Some(Loose::Value(true)),
            broker: Some(Loose::Value(broker.to_string())),
            node_id: Some(Loose::Value(node_id.to_string())),
            ..RawFleet::default()
        };
        let mut check = Checker::default();
        match check.fleet(&raw, Some(state_dir)) {
            Some(Some(config)) if check.problems.is_empty() => Ok(config),
            _ => Err(ConfigError {
                file: "--fleet".into(),
                problems: check.problems,
            }),
        }
    }
}

pub(crate) const DEFAULT_BROKER: &str = "mqtt://localhost:1883";

/// Whether this build can speak TLS to a broker (the `tls` cargo feature, on by default).
pub const TLS_BUILT: bool = cfg!(feature = "tls");

/// Why an `mqtts://` broker cannot be used by a build without the `tls` feature, and the fix.
pub const TLS_NOT_BUILT: &str = "this bearingd was built without TLS (the cargo feature `tls`, \
     on by default, was left out); use a bearingd built with it (`cargo build --profile service \
     -p bearingd --locked --features tls`) or a plain mqtt:// broker";

const DEFAULT_GROUP: &str = "bearingd";
const DEFAULT_PERIOD_S: f64 = 1.0;
const DEFAULT_KEEP_ALIVE_S: f64 = 30.0;
const DEFAULT_QUEUE_MB: f64 = 64.0;
const MAX_SPARKPLUG_ID_LEN: usize = 64;
/// Far below MQTT's 65 535-byte topic limit, far above any host id in use.
const MAX_HOST_ID_LEN: usize = 256;

impl Checker {
    /// `Some(None)`: the bridge is off; `None`: a problem was reported.
    pub(super) fn fleet(
        &mut self,
        raw: &RawFleet,
        state_dir: Option<&Path>,
    ) -> Option<Option<FleetConfig>> {
        let enabled = self.or_default(
            "fleet.enabled",
            &raw.enabled,
            false,
            "set enabled = true to publish to an MQTT broker, or leave it out",
        )?;
        let broker = self
            .or_default(
                "fleet.broker",
                &raw.broker,
                DEFAULT_BROKER.to_string(),
                "give the broker as mqtt://HOST:PORT or mqtts://HOST:PORT, e.g. broker = \
                 \"mqtts://broker.plant:8883\"",
            )
            .and_then(|text| self.broker(&text, TLS_BUILT));
        let group_id = self.sparkplug_id("fleet.group_id", &raw.group_id, Some(DEFAULT_GROUP));
        let node_id = if enabled {
            self.sparkplug_id("fleet.node_id", &raw.node_id, None)
        } else {
            self.sparkplug_id("fleet.node_id", &raw.node_id, Some("unused"))
        };
        let client_id = match (&raw.client_id, &node_id) {
            (None, Some(node)) => Some(format!("bearingd-{node}")),
            (None, None) => None,
            (field, _) => self.text(
                "fleet.client_id",
                field,
                "give the MQTT client id, unique on the broker, e.g. client_id = \
                 \"bearingd-press-7\"",
            ),
        };
        let username = self.optional_text(
            "fleet.username",
            &raw.username,
            "give the MQTT user name, e.g. username = \"press-7\"",
        );
        let file_fix =
            |what: &str, example: &str| format!("give the path of {what}, e.g. {example}");
        let password_file = self.file(
            "fleet.password_file",
            &raw.password_file,
            &file_fix(
                "a file whose first line is the password",
                "password_file = \"/etc/bearingd/mqtt-password\"",
            ),
        );
        let ca_file = self.file(
            "fleet.ca_file",
            &raw.ca_file,
            &file_fix(
                "the CA certificates (PEM) that signed the broker's certificate",
                "ca_file = \"/etc/bearingd/ca.pem\"",
            ),
        );
        let client_cert_file = self.file(
            "fleet.client_cert_file",
            &raw.client_cert_file,
            &file_fix(
                "this node's certificate chain (PEM)",
                "client_cert_file = \"/etc/bearingd/node.pem\"",
            ),
        );
        let client_key_file = self.file(
            "fleet.client_key_file",
            &raw.client_key_file,
            &file_fix(
                "this node's private key (PEM)",
                "client_key_file = \"/etc/bearingd/node.key\"",
            ),
        );
        let publish_period_s = self.number(
            "fleet.publish_period_s",
            &raw.publish_period_s,
            DEFAULT_PERIOD_S,
            Limits::within(0.01, 3600.0),
            "give the seconds between two data messages of a channel, e.g. publish_period_s = 1.0",
        );
        let keep_alive_s = self.number(
            "fleet.keep_alive_s",
            &raw.keep_alive_s,
            DEFAULT_KEEP_ALIVE_S,
            Limits::within(5.0, 3600.0),
            "give the MQTT keep-alive in seconds, e.g. keep_alive_s = 30",
        );
        let queue_dir = match (&raw.queue_dir, state_dir) {
            (None, Some(state)) => Some(state.join("fleet")),
            (None, None) => None,
            (field, _) => self
                .text(
                    "fleet.queue_dir",
                    field,
                    "give the directory of the store-and-forward queue, e.g. queue_dir = \
                     \"/var/lib/bearingd/fleet\"",
                )
                .map(PathBuf::from),
        };
        let queue_max_mb = self.number(
            "fleet.queue_max_mb",
            &raw.queue_max_mb,
            DEFAULT_QUEUE_MB,
            Limits::within(0.01, 1_048_576.0),
            "give the queue's size limit in MiB, e.g. queue_max_mb = 64",
        );
        let primary_host_id = self.primary_host_id(&raw.primary_host_id);

        // Checks across keys, each only when its keys passed on their own.
        let mut consistent = true;
        if let (Some(Some(_)), Some(None)) = (&password_file, &username) {
            self.problem(
                "fleet.password_file",
                "a password without a user name is never sent; add username = \"…\" or remove \
                 password_file",
            );
            consistent = false;
        }
        match (&client_cert_file, &client_key_file) {
            (Some(Some(_)), Some(None)) => {
                self.problem(
                    "fleet.client_key_file",
                    "missing: client_cert_file needs its private key; give it, e.g. \
                     client_key_file = \"/etc/bearingd/node.key\"",
                );
                consistent = false;
            }
            (Some(None), Some(Some(_))) => {
                self.problem(
                    "fleet.client_cert_file",
                    "missing: client_key_file needs its certificate; give it, e.g. \
                     client_cert_file = \"/etc/bearingd/node.pem\"",
                );
                consistent = false;
            }
            _ => {}
        }
        if let Some(broker) = &broker {
            let tls_files = [
                ("fleet.ca_file", &ca_file),
                ("fleet.client_cert_file", &client_cert_file),
            ];
            for (key, file) in tls_files {
                if !broker.tls && matches!(file, Some(Some(_))) {
                    self.problem(
                        key,
                        format!(
                            "a TLS setting, but broker {broker} is plain MQTT; use \
                             mqtts://{}:8883 (or the broker's TLS port) in broker, or remove \
                             {}",
                            broker.host,
                            key.trim_start_matches("fleet.")
                        ),
                    );
                    consistent = false;
                }
            }
        }
        if !enabled {
            // Checked all the same (a mistake shows before the bridge is switched on).
            return consistent.then_some(None);
        }
        Some(Some(FleetConfig {
            broker: broker?,
            group_id: group_id?,
            node_id: node_id?,
            client_id: client_id?,
            username: username?,
            password_file: password_file?,
            ca_file: ca_file?,
            client_cert_file: client_cert_file?,
            client_key_file: client_key_file?,
            publish_period_s: publish_period_s?,
            keep_alive_s: keep_alive_s?,
            queue_dir: queue_dir?,
            queue_max_mb: queue_max_mb?,
            primary_host_id: primary_host_id?,
        }))
        .filter(|_| consistent)
    }

    /// `tls_built`: whether `mqtts://` can be served ([`TLS_BUILT`]; a parameter so that the
    /// tests see both builds' answers).
    fn broker(&mut self, text: &str, tls_built: bool) -> Option<Broker> {
        let key = "fleet.broker";
        let fix = "give it as mqtt://HOST:PORT or mqtts://HOST:PORT, e.g. broker = \
                   \"mqtts://broker.plant:8883\"";
        let (tls, rest) = if let Some(rest) = text.strip_prefix("mqtts://") {
            (true, rest)
        } else if let Some(rest) = text.strip_prefix("mqtt://") {
            (false, rest)
        } else {
            self.problem(
                key,
                format!("{text:?} has no mqtt:// or mqtts:// scheme; {fix}"),
            );
            return None;
        };
        if tls && !tls_built {
            self.problem(
                key,
                format!("{text:?} is a TLS broker, but {TLS_NOT_BUILT}"),
            );
            return None;
        }
        let default_port = if tls { 8883 } else { 1883 };
        let rest = rest.trim_end_matches('/');
        let (host, port) = match rest.rsplit_once(':') {
            Some((host, port)) if !host.ends_with(']') || rest.starts_with('[') => {
                match port.parse::<u16>() {
                    Ok(p) if p > 0 => (host, p),
                    _ => {
                        self.problem(key, format!("{port:?} is not a port number; {fix}"));
                        return None;
                    }
                }
            }
            _ => (rest, default_port),
        };
        let host = host.trim_start_matches('[').trim_end_matches(']');
        if host.is_empty() || host.contains(['/', ' ', '@']) {
            self.problem(key, format!("{text:?} has no usable host name; {fix}"));
            return None;
        }
        Some(Broker {
            tls,
            host: host.to_string(),
            port,
        })
    }

    /// A Sparkplug id: 1 to 64 of `A-Z a-z 0-9 - _ .` (the specification forbids `/ + #`;
    /// the narrower set keeps topics safe in every broker's ACL syntax).
    fn sparkplug_id(
        &mut self,
        key: &str,
        field: &Field<String>,
        default: Option<&str>,
    ) -> Option<String> {
        let name = key.trim_start_matches("fleet.");
        let fix = format!(
            "give 1 to {MAX_SPARKPLUG_ID_LEN} of A-Z, a-z, 0-9, '-', '_' and '.', e.g. {name} = \"press-7\""
        );
        let value = match default {
            Some(d) => self.or_default(key, field, d.to_string(), &fix)?,
            None => match self.get(key, field, &fix) {
                Got::Value(v) => v,
                Got::Invalid => return None,
                Got::Missing => {
                    self.problem(
                        key,
                        format!(
                            "missing: with enabled = true the bridge needs this node's id in \
                             the fleet (it names every topic); {fix}"
                        ),
                    );
                    return None;
                }
            },
        };
        let ok = !value.is_empty()
            && value.len() <= MAX_SPARKPLUG_ID_LEN
            && value
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
        if ok {
            Some(value)
        } else {
            self.problem(
                key,
                format!("{value:?} is not a usable Sparkplug id; {fix}"),
            );
            None
        }
    }

    /// The Sparkplug 3.0 primary host id: any text but the MQTT topic separator and wildcards
    /// (`/`, `+`, `#`, the specification's reserved characters) and control characters, since it
    /// names the topic `spBv1.0/STATE/<id>`. `Some(None)`: not set.
    fn primary_host_id(&mut self, field: &Field<String>) -> Option<Option<String>> {
        let key = "fleet.primary_host_id";
        let fix = format!(
            "give the host application id its STATE topic spBv1.0/STATE/<id> carries (1 to \
             {MAX_HOST_ID_LEN} bytes, without '/', '+', '#' or control characters), e.g. \
             primary_host_id = \"scada-1\", or leave it out to publish whenever connected"
        );
        let value = self.optional_text(key, field, &fix)?;
        let Some(id) = value else {
            return Some(None);
        };
        let mut wrong: Vec<String> = ['/', '+', '#']
            .into_iter()
            .filter(|c| id.contains(*c))
            .map(|c| format!("'{c}'"))
            .collect();
        if id.chars().any(char::is_control) {
            wrong.push("a control character".into());
        }
        if id.trim() != id {
            wrong.push("leading or trailing blanks".into());
        }
        if id.len() > MAX_HOST_ID_LEN {
            wrong.push(format!("{} bytes", id.len()));
        }
        if wrong.is_empty() {
            return Some(Some(id));
        }
        self.problem(
            key,
            format!(
                "{id:?} cannot name an MQTT topic: it has {}; {fix}",
                wrong.join(", ")
            ),
        );
        None
    }

    fn text(&mut self, key: &str, field: &Field<String>, fix: &str) -> Option<String> {
        self.optional_text(key, field, fix).flatten()
    }

    /// `Some(None)`: absent; `None`: a problem was reported.
    pub(super) fn optional_text(
        &mut self,
        key: &str,
        field: &Field<String>,
        fix: &str,
    ) -> Option<Option<String>> {
        match self.get(key, field, fix) {
            Got::Missing => Some(None),
            Got::Invalid => None,
            Got::Value(v) if v.trim().is_empty() || v.contains('\0') => {
                self.problem(key, format!("{v:?} is empty; {fix}"));
                None
            }
            Got::Value(v) => Some(Some(v)),
        }
    }

    /// An optional path to an existing file.
    fn file(&mut self, key: &str, field: &Field<String>, fix: &str) -> Option<Option<PathBuf>> {
        let Some(path) = self.optional_text(key, field, fix)? else {
            return Some(None);
        };
        let path = PathBuf::from(path);
        if path.is_file() {
            Some(Some(path))
        } else {
            self.problem(key, format!("{}: no such file; {fix}", path.display()));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_mqtts_broker_without_the_tls_feature_is_a_problem_naming_the_feature_and_the_build() {
        let mut check = Checker::default();
        assert_eq!(check.broker("mqtts://broker.plant:8883", false), None);
        assert_eq!(check.problems.len(), 1);
        let problem = check.problems[0].to_string();
        assert!(problem.contains("fleet.broker"), "{problem}");
        assert!(
            problem.contains("\"mqtts://broker.plant:8883\" is a TLS broker"),
            "{problem}"
        );
        assert!(problem.contains("cargo feature `tls`"), "{problem}");
        assert!(problem.contains("--features tls"), "{problem}");

        let mut check = Checker::default();
        let plain = check.broker("mqtt://broker.plant", false);
        assert_eq!(plain.map(|b| (b.tls, b.port)), Some((false, 1883)));
        assert!(check.problems.is_empty());
    }

    #[test]
    fn a_primary_host_id_is_optional_and_may_not_hold_topic_characters() {
        let id = |text: &str| Some(Loose::Value(text.to_string()));
        let mut check = Checker::default();
        assert_eq!(check.primary_host_id(&None), Some(None));
        assert_eq!(
            check.primary_host_id(&id("scada-1")),
            Some(Some("scada-1".into()))
        );
        assert_eq!(
            check.primary_host_id(&id("Ignition Gateway (hall 3)")),
            Some(Some("Ignition Gateway (hall 3)".into()))
        );
        assert!(check.problems.is_empty(), "{:?}", check.problems);
        for (bad, said) in [
            ("", "is empty"),
            ("   ", "is empty"),
            ("plant/scada", "'/'"),
            ("scada+", "'+'"),
            ("#", "'#'"),
            ("a/b+c#", "'/', '+', '#'"),
            ("scada\u{1}", "a control character"),
            (" scada", "leading or trailing blanks"),
        ] {
            let mut check = Checker::default();
            assert_eq!(check.primary_host_id(&id(bad)), None, "{bad:?}");
            assert_eq!(check.problems.len(), 1, "{bad:?}");
            let problem = check.problems[0].to_string();
            assert!(problem.contains("fleet.primary_host_id"), "{problem}");
            assert!(problem.contains(said), "{bad:?}: {problem}");
            assert!(problem.contains("e.g. primary_host_id = "), "{problem}");
        }
        let mut check = Checker::default();
        assert_eq!(check.primary_host_id(&id(&"h".repeat(300))), None);
        assert!(check.problems[0].to_string().contains("300 bytes"));
        let mut check = Checker::default();
        let wrong_type = Some(Loose::WrongType {
            found: "an integer".into(),
        });
        assert_eq!(check.primary_host_id(&wrong_type), None);
        assert_eq!(check.problems.len(), 1);
    }

    #[test]
    fn a_bad_primary_host_id_is_listed_with_the_other_problems_even_when_disabled() {
        for enabled in [true, false] {
            let raw = RawFleet {
                enabled: Some(Loose::Value(enabled)),
                node_id: Some(Loose::Value("press/7".into())),
                primary_host_id: Some(Loose::Value("scada/#".into())),
                publish_period_s: Some(Loose::Value(-1.0)),
                ..RawFleet::default()
            };
            let mut check = Checker::default();
            let _ = check.fleet(&raw, Some(Path::new("/tmp")));
            let keys: Vec<String> = check.problems.iter().map(|p| p.to_string()).collect();
            assert_eq!(keys.len(), 3, "{keys:?}");
            assert!(
                keys.iter().any(|p| p.contains("fleet.primary_host_id")),
                "{keys:?}"
            );
        }
        let raw = RawFleet {
            enabled: Some(Loose::Value(true)),
            node_id: Some(Loose::Value("press-7".into())),
            primary_host_id: Some(Loose::Value("scada-1".into())),
            ..RawFleet::default()
        };
        let mut check = Checker::default();
        let config = check
            .fleet(&raw, Some(Path::new("/tmp")))
            .flatten()
            .unwrap();
        assert_eq!(config.primary_host_id.as_deref(), Some("scada-1"));
    }

    #[test]
    fn an_mqtts_broker_with_the_tls_feature_is_tls_on_8883() {
        let mut check = Checker::default();
        let broker = check.broker("mqtts://broker.plant", true);
        assert_eq!(broker.map(|b| (b.tls, b.port)), Some((true, 8883)));
        assert!(check.problems.is_empty());
    }
}
