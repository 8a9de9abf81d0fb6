//! The config module from the outside: the default file, defaults, and what users see when a
//! file is wrong.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::analysis::BandSelection;
use bearingd::config::{
    self, CanConfig, Config, ConfigError, ConfigProblem, SimFault, Speed, Transport, DEFAULT_TOML,
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

#[test]
fn custom_bearing_geometry_is_resolved() {
    let text = SENSOR.replace(
        "bearing = \"skf-6205-2rs\"",
        "bearing = \"z=8, d=6.75mm, D=28.5mm, alpha=0\"",
    );
    let config = config::parse(&text, "custom.toml").unwrap_or_else(|e| panic!("{e}"));
    let bearing = &config.sensors[0].bearing;
    assert_eq!(bearing.name, "custom");
    assert_eq!(bearing.rolling_elements, 8);
    assert_eq!(bearing.element_diameter_mm, 6.75);
    assert_eq!(bearing.pitch_diameter_mm, 28.5);

    let bad = SENSOR.replace(
        "bearing = \"skf-6205-2rs\"",
        "bearing = \"z=2,d=9mm,D=8mm\"",
    );
    let found = problems(&bad);
    let problem = find(&found, "sensors[0].bearing");
    assert!(problem.message.contains("z=2"), "{problem}");
    assert!(problem.message.contains("smaller than D"), "{problem}");
    assert_has_fix(problem);

    let unknown = SENSOR.replace("skf-6205-2rs", "skf-9999");
    let found = problems(&unknown);
    let problem = find(&found, "sensors[0].bearing");
    assert!(problem.message.contains("skf-61804"), "{problem}");
    assert_has_fix(problem);
}

#[test]
fn a_band_above_nyquist_names_the_sensor() {
    let text = format!(
        r#"{SENSOR}
[[sensors]]
id = "fan-de"
transport = "sim"
sample_rate_hz = 8000
bearing = "skf-6203-2rs"
[sensors.speed]
rpm = 1772

[analysis]
band_selection = "fixed"
band_hz = [2000.0, 5000.0]
"#
    );
    let found = problems(&text);
    let [problem] = found.as_slice() else {
        panic!("one problem expected: {found:#?}")
    };
    assert_eq!(problem.key, "analysis.band_hz");
    assert!(
        problem
            .message
            .contains("of sensor \"fan-de\" (sensors[1], sampled at 8000 Hz)"),
        "{problem}"
    );
    assert!(problem.message.contains("4000 Hz"), "{problem}");
    assert!(!problem.message.contains("motor-de"), "{problem}");
    assert_has_fix(problem);

    let fixed = text.replace("5000.0", "3500.0");
    let config = config::parse(&fixed, "fixed.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        config.analysis.band_selection,
        BandSelection::Fixed {
            lo_hz: 2000.0,
            hi_hz: 3500.0
        }
    );
}

#[test]
fn band_hz_goes_with_fixed_selection_only() {
    let found = problems(&format!("{SENSOR}[analysis]\nband_hz = [1000.0, 2000.0]\n"));
    assert_eq!(keys(&found), ["analysis.band_hz"]);
    let found = problems(&format!("{SENSOR}[analysis]\nband_selection = \"fixed\"\n"));
    assert_eq!(keys(&found), ["analysis.band_hz"]);
    assert!(found[0].message.starts_with("missing"), "{}", found[0]);
    let found = problems(&format!(
        "{SENSOR}[analysis]\nband_selection = \"fixed\"\nband_hz = [3000.0, 2000.0, 1.0]\n"
    ));
    assert_eq!(keys(&found), ["analysis.band_hz"]);
}

#[test]
fn sensors_are_required_and_their_ids_unique() {
    let found = problems("[analysis]\nwindow_s = 1.0\n");
    assert_eq!(keys(&found), ["sensors"]);
    assert!(found[0].message.contains("add a [[sensors]] section"));

    let found = problems(&format!("{SENSOR}{SENSOR}"));
    assert_eq!(keys(&found), ["sensors[1].id"], "{found:#?}");
    assert!(found[0].message.contains("sensors[0]"), "{}", found[0]);

    let found = problems("[[sensors]]\n");
    assert_eq!(
        keys(&found),
        [
            "sensors[0].id",
            "sensors[0].transport",
            "sensors[0].sample_rate_hz",
            "sensors[0].bearing",
            "sensors[0].speed.rpm",
        ],
        "{found:#?}"
    );
    found.iter().for_each(assert_has_fix);
}

#[test]
fn transport_tables_must_match_the_transport() {
    let can_on_sim = format!("{SENSOR}[sensors.can]\nnode_id = 1\n");
    let found = problems(&can_on_sim);
    assert_eq!(keys(&found), ["sensors[0].can"]);
    assert!(
        found[0].message.contains("transport is \"sim\""),
        "{}",
        found[0]
    );

    let can_without_table = SENSOR.replace("\"sim\"", "\"can\"");
    let found = problems(&can_without_table);
    assert_eq!(keys(&found), ["sensors[0].can"]);

    let can = format!(
        "{}[sensors.can]\ninterface = \"vcan0\"\nnode_id = 3\nfd = true\n",
        SENSOR.replace("\"sim\"", "\"can\"")
    );
    let config = config::parse(&can, "can.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        config.sensors[0].transport,
        Transport::Can(CanConfig {
            interface: "vcan0".into(),
            node_id: 3,
            fd: true
        })
    );

    let two_nodes = format!("{can}{}", can.replace("motor-de", "fan-de"));
    let found = problems(&two_nodes);
    assert_eq!(keys(&found), ["sensors[1].can.node_id"], "{found:#?}");

    let shm = SENSOR.replace("\"sim\"", "\"shm\"");
    let config = config::parse(&shm, "shm.toml").unwrap_or_else(|e| panic!("{e}"));
    let Transport::Shm(shm_config) = &config.sensors[0].transport else {
        panic!("{:?}", config.sensors[0].transport)
    };
    assert_eq!(shm_config.service, "bearingd/accel/motor-de");

    let outside = format!("{shm}[sensors.shm]\nservice = \"accel/motor-de\"\n");
    let found = problems(&outside);
    assert_eq!(keys(&found), ["sensors[0].shm.service"]);
    found.iter().for_each(assert_has_fix);

    let on_alerts = format!("{shm}[sensors.shm]\nservice = \"bearingd/alerts\"\n");
    let found = problems(&on_alerts);
    assert_eq!(keys(&found), ["sensors[0].shm.service"]);
    assert!(found[0].message.contains("alerts_service"), "{}", found[0]);
    assert!(
        found[0].message.contains("\"bearingd/accel/motor-de\""),
        "{}",
        found[0]
    );
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

fn speed_of(text: &str) -> Speed {
    config::parse(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .sensors[0]
        .speed
}

#[test]
fn speed_from_frames_and_estimated_speed_are_configured_with_their_defaults() {
    let can = |table: &str| format!("{CAN_SENSOR}[sensors.speed]\n{table}");
    assert_eq!(
        speed_of(&can("source = \"can\"\nrpm = 1772\n")),
        Speed::Frames {
            nominal_rpm: Some(1772.0),
            max_rpm: 1772.0 * 1.5
        }
    );
    assert_eq!(
        speed_of(&can("source = \"can\"\nmax_rpm = 3600\n")),
        Speed::Frames {
            nominal_rpm: None,
            max_rpm: 3600.0
        }
    );
    assert_eq!(
        speed_of(&can("source = \"estimate\"\nrpm = 1772\n")),
        Speed::Estimate {
            rpm: 1772.0,
            search: 0.05
        }
    );
    assert_eq!(
        speed_of(&SENSOR.replace(
            "rpm = 1772",
            "source = \"estimate\"\nrpm = 1772\nsearch = 0.1"
        )),
        Speed::Estimate {
            rpm: 1772.0,
            search: 0.1
        }
    );
}

#[test]
fn speed_mistakes_are_listed_at_once_with_their_fix() {
    // A simulated sensor sends no speed frames; a key of another source would be ignored;
    // without a nominal rpm max_rpm has no default; an estimate needs its nominal rpm; a
    // search range out of bounds; max_rpm not above the nominal speed.
    let text = format!(
        "{}{}{}{}",
        SENSOR.replace("rpm = 1772", "source = \"can\"\nrpm = 1772\nsearch = 0.05"),
        CAN_SENSOR
            .replace("motor-de", "b")
            .replace("node_id = 1", "node_id = 2")
            + "[sensors.speed]\nsource = \"can\"\n",
        CAN_SENSOR
            .replace("motor-de", "c")
            .replace("node_id = 1", "node_id = 3")
            + "[sensors.speed]\nsource = \"estimate\"\nsearch = 0.5\nmax_rpm = 2000\n",
        CAN_SENSOR
            .replace("motor-de", "d")
            .replace("node_id = 1", "node_id = 4")
            + "[sensors.speed]\nsource = \"can\"\nrpm = 1800\nmax_rpm = 1700\n",
    );
    let found = problems(&text);
    assert_eq!(
        keys(&found),
        [
            "sensors[0].speed.search",
            "sensors[0].speed.source",
            "sensors[1].speed.max_rpm",
            "sensors[2].speed.max_rpm",
            "sensors[2].speed.rpm",
            "sensors[3].speed.max_rpm",
        ],
        "{found:#?}"
    );
    assert!(found[1].message.contains("no speed frames"), "{}", found[1]);
    found.iter().for_each(assert_has_fix);
    let unknown = problems(&SENSOR.replace("rpm = 1772", "source = \"tacho\""));
    assert_eq!(keys(&unknown), ["sensors[0].speed.source"]);
    assert_has_fix(&unknown[0]);
}

#[test]
fn output_checks_say_why() {
    let text = format!(
        "{SENSOR}[outputs]\nmcap_max_file_mb = 512\nmcap_disk_budget_mb = 600\n\
         iceoryx2_root = \"run/iceoryx2\"\nalerts_service = \"alerts\"\n"
    );
    let found = problems(&text);
    assert_eq!(
        keys(&found),
        [
            "outputs.mcap_disk_budget_mb",
            "outputs.alerts_service",
            "outputs.iceoryx2_root",
        ],
        "{found:#?}"
    );
    assert!(found[0].message.contains("open file"), "{}", found[0]);
    assert!(found[2].message.contains("absolute"), "{}", found[2]);
    found.iter().for_each(assert_has_fix);

    let found = problems(&format!(
        "{SENSOR}[outputs]\niceoryx2_root = \"/var/tmp/x\"\n"
    ));
    assert!(found[0].message.contains("PrivateTmp"), "{}", found[0]);
}

#[test]
fn the_cpu_wakeup_latency_is_off_unless_given_and_then_within_0_to_1_s() {
    assert_eq!(config_of(SENSOR).outputs.cpu_wakeup_latency_us, None);
    let given = config_of(&format!("{SENSOR}[outputs]\ncpu_wakeup_latency_us = 0\n"));
    assert_eq!(given.outputs.cpu_wakeup_latency_us, Some(0));
    for bad in ["-1", "1000001", "\"low\""] {
        let found = problems(&format!(
            "{SENSOR}[outputs]\ncpu_wakeup_latency_us = {bad}\n"
        ));
        assert_eq!(
            keys(&found),
            ["outputs.cpu_wakeup_latency_us"],
            "{bad}: {found:#?}"
        );
        found.iter().for_each(assert_has_fix);
    }
}

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

#[test]
fn transport_tables_are_checked_even_when_the_transport_is_wrong() {
    let text = SENSOR.replace("\"sim\"", "\"cam\"") + "[sensors.can]\nnode_id = 99\n";
    let found = problems(&text);
    assert_eq!(
        keys(&found),
        ["sensors[0].transport", "sensors[0].can.node_id"],
        "{found:#?}"
    );
}

#[test]
fn an_iceoryx2_root_too_long_for_its_sockets_is_refused() {
    let long = format!("/srv/{}", "r".repeat(60));
    let text = format!("{SENSOR}[outputs]\niceoryx2_root = \"{long}\"\n");
    let problems = bearingd::config::parse(&text, "t.toml")
        .unwrap_err()
        .problems;
    let problem = problems
        .iter()
        .find(|p| p.key == "outputs.iceoryx2_root")
        .unwrap_or_else(|| panic!("{problems:?}"));
    assert!(problem.message.contains("108 bytes"), "{}", problem.message);
}

#[test]
fn severity_names_the_machine_group_and_foundation_and_refuses_others() {
    use bearingd::analysis::iso::{Foundation, MachineGroup};
    let config = config::parse(
        &format!("{SENSOR}[severity]\nmachine_group = 1\nfoundation = \"flexible\"\n"),
        "test.toml",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (config.severity.group, config.severity.foundation),
        (MachineGroup::Large, Foundation::Flexible)
    );
    let found = problems(&format!(
        "{SENSOR}[sensors.sim]\nimbalance_g = -1.0\n[severity]\nmachine_group = 3\nfoundation = \"concrete\"\n"
    ));
    assert_eq!(
        keys(&found),
        [
            "sensors[0].sim.imbalance_g",
            "severity.machine_group",
            "severity.foundation"
        ],
        "{found:#?}"
    );
    found.iter().for_each(assert_has_fix);
}

/// The learned model the agreement's tests give as the witness (the shipped one).
fn witness() -> String {
    format!(
        "[twin]\nlearned_model = \"{}/models/skf-6205-2rs.safetensors\"\n",
        env!("CARGO_MANIFEST_DIR")
    )
}

#[test]
fn the_learned_agreement_is_off_unless_its_four_keys_are_given() {
    use bearingd::analysis::agreement::Agreement;
    assert_eq!(config_of(SENSOR).analysis.agreement, None);
    let all = "[analysis]\nagreement_probability = 0.9\nagreement_fault_score = 3.0\n\
               agreement_score_ratio = 2.0\nagreement_significance_relief = 1.0\n";
    let witness = witness();
    assert_eq!(
        config_of(&format!("{SENSOR}{all}{witness}"))
            .analysis
            .agreement,
        Some(Agreement {
            min_probability: 0.9,
            min_score: 3.0,
            min_lead: 2.0,
            significance_relief_decades: 1.0,
        })
    );
    // Half of them: the other two are missing, each with its fix.
    let found = problems(&format!(
        "{SENSOR}[analysis]\nagreement_probability = 0.9\nagreement_score_ratio = 2.0\n"
    ));
    assert_eq!(
        keys(&found),
        [
            "analysis.agreement_fault_score",
            "analysis.agreement_significance_relief"
        ]
    );
    for problem in &found {
        assert!(problem.message.starts_with("missing"), "{problem}");
        assert_has_fix(problem);
    }
    // Out of range, or a relief that waives all of the significance false_alarm_rate asks
    // (3 decades at 0.001).
    for (key, bad) in [
        ("agreement_probability", "0.3"),
        ("agreement_score_ratio", "0.5"),
        ("agreement_significance_relief", "3.0"),
    ] {
        let text = all.replace(&format!("{key} = "), &format!("{key} = {bad}\n# was "));
        let found = problems(&format!("{SENSOR}{text}{witness}"));
        assert_eq!(keys(&found), [format!("analysis.{key}")], "{found:?}");
        assert_has_fix(&found[0]);
    }
    // All four without a model to agree with: refused, naming the key that gives one.
    let found = problems(&format!("{SENSOR}{all}"));
    assert_eq!(
        keys(&found),
        ["analysis.agreement_probability"],
        "{found:?}"
    );
    assert!(
        found[0].message.contains("twin.learned_model"),
        "{}",
        found[0]
    );
    assert_has_fix(&found[0]);
}

#[test]
fn a_logged_config_from_before_the_agreement_reads_as_off() {
    let mut logged = config_of(&format!(
        "{SENSOR}[analysis]\nagreement_probability = 0.9\nagreement_fault_score = 3.0\n\
         agreement_score_ratio = 2.0\nagreement_significance_relief = 1.0\n{}",
        witness()
    ));
    let json = serde_json::to_string(&logged).unwrap();
    assert_eq!(config::config_from_log(&json).unwrap(), logged);
    // An older log's record has no `agreement` key at all.
    let mut value: serde_json::Value = serde_json::from_str(&json).unwrap();
    let removed = value["analysis"]
        .as_object_mut()
        .and_then(|analysis| analysis.remove("agreement"));
    assert!(removed.is_some(), "the logged analysis holds the agreement");
    let older = config::config_from_log(&value.to_string()).unwrap();
    logged.analysis.agreement = None;
    assert_eq!(older, logged);
}
