//! The config module from the outside: the default file, defaults, and what users see when a
//! file is wrong.
//!
//! One binary: the file as a whole and how problems are reported here, `sections` and
//! `transports_outputs` for the checks of each part.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod sections;
mod transports_outputs;

use bearingd::analysis::BandSelection;
use bearingd::config::{
    self, Config, ConfigError, ConfigProblem, SimFault, Speed, Transport, DEFAULT_TOML,
};

/// A valid sensor, to which tests add mistakes elsewhere.
const SENSOR: &str = r#"
[[sensors]]
id = "motor-de"
transport = "sim"
sample_rate_hz = 25600
bearing = "skf-6205-2rs"
[sensors.speed]
rpm = 1772
"#;

fn problems(text: &str) -> Vec<ConfigProblem> {
    match config::parse(text, "test.toml") {
        Ok(config) => panic!("expected problems, got {config:#?}"),
        Err(error) => {
            assert!(!error.problems.is_empty(), "an error without problems");
            error.problems
        }
    }
}

fn config_of(text: &str) -> Config {
    config::parse(text, "test.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn keys(problems: &[ConfigProblem]) -> Vec<&str> {
    problems.iter().map(|p| p.key.as_str()).collect()
}

fn find<'a>(problems: &'a [ConfigProblem], key: &str) -> &'a ConfigProblem {
    problems
        .iter()
        .find(|p| p.key == key)
        .unwrap_or_else(|| panic!("no problem at {key} in {problems:#?}"))
}

/// The verbs that start the fix part of a message (module docs of `bearingd::config`).
const FIX_VERBS: &[&str] = &[
    "add", "fix", "give", "leave", "lower", "move", "raise", "remove", "rename", "report", "set",
    "use", "write",
];

/// Every message reads `<what is wrong>; <what to do>`, the part after the last "; " starting
/// with an imperative verb, and says more than its key.
fn assert_has_fix(problem: &ConfigProblem) {
    let message = &problem.message;
    assert!(
        message.len() > problem.key.len(),
        "message shorter than its key: {problem}"
    );
    let (what, fix) = message
        .rsplit_once("; ")
        .unwrap_or_else(|| panic!("no '; <fix>' in: {problem}"));
    assert!(
        !what.trim().is_empty(),
        "nothing says what is wrong: {problem}"
    );
    let verb = fix.split_whitespace().next().unwrap_or("");
    assert!(
        FIX_VERBS.contains(&verb),
        "fix does not start with one of {FIX_VERBS:?}: {problem}"
    );
}

#[test]
fn default_file_validates_and_describes_the_demo() {
    let config = Config::default_embedded().unwrap_or_else(|e| panic!("{e}"));
    let [sensor] = config.sensors.as_slice() else {
        panic!("one sensor expected: {:#?}", config.sensors)
    };
    assert_eq!(sensor.id, "motor-de");
    assert_eq!(sensor.sample_rate_hz, 25600.0);
    assert_eq!(sensor.bearing.name, "skf-6205-2rs");
    assert_eq!(sensor.speed, Speed::Fixed { rpm: 1772.0 });
    let Transport::Sim(sim) = &sensor.transport else {
        panic!("a simulated sensor expected: {:?}", sensor.transport)
    };
    assert_eq!(sim.fault, SimFault::Outer);
    assert_eq!(sim.onset_s, 30.0);
    assert_eq!(config.analysis.band_selection, BandSelection::GiniKurtosis);
}

#[test]
fn defaults_in_code_agree_with_the_default_file() {
    let from_file = Config::default_embedded().unwrap_or_else(|e| panic!("{e}"));
    // Only the required keys: everything else comes from the code's defaults.
    let from_code = config::parse(SENSOR, "minimal.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(from_code.analysis, from_file.analysis);
    assert_eq!(from_code.band_period_s, from_file.band_period_s);
    assert_eq!(from_code.twin, from_file.twin);
    assert_eq!(from_code.thresholds, from_file.thresholds);
    assert_eq!(from_code.outputs, from_file.outputs);
    assert_eq!(from_code.severity, from_file.severity);
    // The file's sensor writes out every default too.
    assert_eq!(from_code.sensors, from_file.sensors);
}

#[test]
fn six_independent_mistakes_are_all_reported() {
    let text = r#"
[[sensors]]
id = "motor-de"
transport = "sim"
sample_rate_hz = 0
bearing = "skf-6205-2rs"
[sensors.speed]
rpm = 1772

[[sensors]]
id = "fan-de"
transport = "carrier-pigeon"
sample_rate_hz = 25600
bearing = "skf-6205-2rs"
[sensors.speed]
rpm = -5

[analysis]
overlap = 0.95

[thresholds]
watch_score = 40.0
alarm_score = 30.0

[outputs]
iceoryx2_root = "/tmp/iceoryx2"
"#;
    let found = problems(text);
    let mut got = keys(&found);
    got.sort_unstable();
    assert_eq!(
        got,
        [
            "analysis.overlap",
            "outputs.iceoryx2_root",
            "sensors[0].sample_rate_hz",
            "sensors[1].speed.rpm",
            "sensors[1].transport",
            "thresholds.alarm_score",
        ],
        "{found:#?}"
    );
    assert_eq!(
        find(&found, "sensors[0].sample_rate_hz").message,
        "0 is not a sample rate; give the sensor's sample rate in Hz, e.g. 25600"
    );
    assert!(find(&found, "outputs.iceoryx2_root")
        .message
        .contains("PrivateTmp"));
    found.iter().for_each(assert_has_fix);
}

#[test]
fn display_lists_one_problem_per_line_with_file_and_key() {
    let error = config::parse(
        &format!("{SENSOR}\n[analysis]\nharmonics = 0\naverages = 100\n"),
        "/etc/bearingd/bearingd.toml",
    )
    .unwrap_err();
    let text = error.to_string();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2, "{text}");
    assert!(
        lines[0].starts_with("/etc/bearingd/bearingd.toml: analysis.averages: 100 is out of range")
    );
    assert!(
        lines[1].starts_with("/etc/bearingd/bearingd.toml: analysis.harmonics: 0 is out of range")
    );
}

#[test]
fn unknown_keys_are_named_with_their_line_and_the_known_keys() {
    let text = format!("{SENSOR}[sensors.sim]\nfualt = \"inner\"\n\n[twin]\nrefit_s = 5\n");
    let found = problems(&text);
    let fault = find(&found, "sensors[0].sim.fualt");
    assert!(fault.message.contains("unknown key `fualt`"), "{fault}");
    assert!(fault.message.contains("line 10, column 1"), "{fault}");
    assert!(
        fault
            .message
            .contains("known keys here: fault, onset_s, severity, noise_g, imbalance_g, seed"),
        "{fault}"
    );
    assert!(fault.message.contains("rename it to `fault`"), "{fault}");
    // The second unknown key is reported too, not only the first.
    let twin = find(&found, "twin.refit_s");
    assert!(twin.message.contains("line 13"), "{twin}");
    assert!(twin.message.contains("`refit_period_s`"), "{twin}");
    assert_eq!(found.len(), 2, "{found:#?}");
    found.iter().for_each(assert_has_fix);
}

#[test]
fn unknown_keys_do_not_hide_value_problems() {
    let text = format!("{SENSOR}\n[analysis]\nwindow = 2.0\nharmonics = 11\n");
    let found = problems(&text);
    assert_eq!(
        keys(&found),
        ["analysis.window", "analysis.harmonics"],
        "{found:#?}"
    );
}

#[test]
fn wrong_types_are_collected_with_the_others() {
    let text = r#"
[[sensors]]
id = "motor-de"
transport = "sim"
sample_rate_hz = "fast"
bearing = 6205
axes = "radial"
[sensors.speed]
rpm = 1772
[sensors.sim]
seed = 1.5
[analysis]
refine_band_by_snr = "yes"
"#;
    let found = problems(text);
    assert_eq!(
        keys(&found),
        [
            "sensors[0].sample_rate_hz",
            "sensors[0].axes",
            "sensors[0].bearing",
            "sensors[0].sim.seed",
            "analysis.refine_band_by_snr",
        ],
        "{found:#?}"
    );
    assert!(find(&found, "sensors[0].sample_rate_hz")
        .message
        .starts_with("expected a number, found the string \"fast\"; give"));
    found.iter().for_each(assert_has_fix);
}

#[test]
fn misshapen_tables_are_reported_without_their_consequences() {
    let found = problems("sensors = 5\nanalysis = \"gk\"\n");
    assert_eq!(keys(&found), ["sensors", "analysis"], "{found:#?}");
    assert!(found[0].message.contains("[[sensors]]"), "{}", found[0]);
    assert!(
        found[1].message.contains("[analysis] section"),
        "{}",
        found[1]
    );

    let found = problems("[sensors]\nid = \"motor-de\"\n");
    assert_eq!(keys(&found), ["sensors"], "{found:#?}");
    assert!(found[0].message.contains("double brackets"), "{}", found[0]);
    found.iter().for_each(assert_has_fix);
}

#[test]
fn syntax_errors_give_their_position() {
    let found = problems("[[sensors]]\nid = motor-de\n");
    assert!(found[0].key.starts_with("line 2, column"), "{found:#?}");
    found.iter().for_each(assert_has_fix);

    let found = problems(&format!(
        "{SENSOR}\n[twin]\nwindow_s = 1.0\nwindow_s = 2.0\n"
    ));
    assert!(
        found.iter().any(|p| p.message.contains("duplicate key")),
        "{found:#?}"
    );
    found.iter().for_each(assert_has_fix);
}

/// A CAN sensor, to which tests add a `[sensors.speed]` table.
const CAN_SENSOR: &str = r#"
[[sensors]]
id = "motor-de"
transport = "can"
sample_rate_hz = 25600
bearing = "skf-6205-2rs"
[sensors.can]
interface = "vcan0"
node_id = 1
"#;

#[test]
fn non_finite_numbers_are_refused() {
    let found = problems(&format!(
        "{SENSOR}[analysis]\nwindow_s = nan\n[thresholds]\nsigma = inf\n"
    ));
    assert_eq!(keys(&found), ["analysis.window_s", "thresholds.sigma"]);
    found.iter().for_each(assert_has_fix);
}

#[test]
fn every_key_is_documented_in_the_default_file() {
    // Probe each table with an unknown key: the message lists the table's known keys.
    let tables = [
        "",
        "[[sensors]]\n",
        "[[sensors]]\n[sensors.speed]\n",
        "[[sensors]]\n[sensors.sim]\n",
        "[[sensors]]\n[sensors.can]\n",
        "[[sensors]]\n[sensors.shm]\n",
        "[analysis]\n",
        "[twin]\n",
        "[thresholds]\n",
        "[outputs]\n",
        "[detectors]\n",
        "[detectors.machine_faults]\n",
    ];
    for table in tables {
        let found = problems(&format!("{table}zzz_probe = 1\n"));
        let message = &found[0].message;
        let known = message
            .split("known keys here: ")
            .nth(1)
            .and_then(|rest| rest.split(';').next())
            .unwrap_or_else(|| panic!("no known keys in {message}"));
        for key in known.split(", ") {
            let documented = DEFAULT_TOML.lines().any(|line| {
                let line = line.trim_start_matches(['#', ' ']);
                line.starts_with(&format!("{key} = "))
                    || line.starts_with(&format!("[{key}]"))
                    || line.starts_with(&format!("[[{key}]]"))
                    || line.starts_with(&format!("[sensors.{key}]"))
                    || line.starts_with(&format!("[detectors.{key}]"))
                    // A table of tables, documented by its sections.
                    || line.starts_with(&format!("[{key}."))
            });
            assert!(documented, "{table:?}{key} is not in config/bearingd.toml");
        }
    }
}

#[test]
fn a_missing_file_names_the_file() {
    let error: ConfigError =
        config::load(std::path::Path::new("/nonexistent/bearingd.toml")).unwrap_err();
    let text = error.to_string();
    assert!(
        text.starts_with("/nonexistent/bearingd.toml: cannot read the file"),
        "{text}"
    );
    error.problems.iter().for_each(assert_has_fix);
}

#[test]
fn no_input_makes_it_panic() {
    // Every prefix of the default file, and the file without each of its lines: whatever
    // comes out, it is a config or a non-empty list of problems that each say how to fix.
    let mut inputs: Vec<String> = DEFAULT_TOML
        .char_indices()
        .map(|(i, _)| DEFAULT_TOML[..i].to_string())
        .collect();
    let lines: Vec<&str> = DEFAULT_TOML.lines().collect();
    for skip in 0..lines.len() {
        let mut text = String::new();
        for (i, line) in lines.iter().enumerate() {
            if i != skip {
                text.push_str(line);
                text.push('\n');
            }
        }
        inputs.push(text);
    }
    inputs.extend(
        [
            "\u{0}",
            "[[sensors]]\n[[sensors]]\nid = \"\"\n",
            "sensors = [1, \"a\", {id = 5}]\n",
            "[[sensors]]\nspeed = 3\nsim = []\n",
            "[[sensors]]\naxes = []\nsample_rate_hz = 1e300\n[sensors.speed]\nrpm = 1e400\n",
            "[outputs]\nmcap_max_file_mb = 9223372036854775807\nmcap_disk_budget_mb = -1\n",
            "[analysis]\nband_selection = \"fixed\"\nband_hz = []\n",
            "a.b.c.d = 1\n[x]\n[x.y]\n",
            "[[sensors]]\nid = \"ÄÖÜ\"\n[sensors.sim]\nfault = \"\u{1F600}\"\n",
        ]
        .map(String::from),
    );
    for text in &inputs {
        if let Err(error) = config::parse(text, "fuzz.toml") {
            assert!(!error.problems.is_empty(), "no problems for {text:?}");
            for problem in &error.problems {
                assert_has_fix(problem);
            }
        }
    }
}

/// The learned model the agreement's tests give as the witness (the shipped one).
fn witness() -> String {
    format!(
        "[twin]\nlearned_model = \"{}/models/skf-6205-2rs.safetensors\"\n",
        env!("CARGO_MANIFEST_DIR")
    )
}
