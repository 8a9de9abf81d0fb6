//! The sections of the file that describe the machine and its analysis: bearings and their
//! geometry, bands, sensors, speed, the velocity severity, the learned agreement.

use super::{assert_has_fix, config_of, find, keys, problems, witness, CAN_SENSOR, SENSOR};
use bearingd::analysis::BandSelection;
use bearingd::config::{self, Speed};

/// The speed source the one sensor of `text` is configured with.
fn speed_of(text: &str) -> Speed {
    config::parse(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .sensors[0]
        .speed
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
