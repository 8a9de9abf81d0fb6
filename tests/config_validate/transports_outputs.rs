//! Where samples come from and where results go: transport tables, outputs, the iceoryx2
//! root, the CPU wake-up latency.

use super::{assert_has_fix, config_of, find, keys, problems, SENSOR};
use bearingd::config::{self, CanConfig, Transport};

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
fn cpus_are_kept_awake_during_analysis_unless_turned_off_with_a_boolean() {
    assert!(config_of(SENSOR).outputs.cpu_awake_during_analysis);
    let off = config_of(&format!(
        "{SENSOR}[outputs]\ncpu_awake_during_analysis = false\n"
    ));
    assert!(!off.outputs.cpu_awake_during_analysis);
    for bad in ["0", "\"no\""] {
        let found = problems(&format!(
            "{SENSOR}[outputs]\ncpu_awake_during_analysis = {bad}\n"
        ));
        assert_eq!(
            keys(&found),
            ["outputs.cpu_awake_during_analysis"],
            "{bad}: {found:#?}"
        );
        found.iter().for_each(assert_has_fix);
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
fn an_mqtts_broker_is_used_with_the_tls_feature_and_a_problem_naming_it_without() {
    let fleet = format!(
        "{SENSOR}[fleet]\nenabled = true\nbroker = \"mqtts://broker.plant\"\nnode_id = \"press-7\"\n"
    );
    if config::TLS_BUILT {
        let broker = config_of(&fleet).fleet.map(|f| f.broker.to_string());
        assert_eq!(broker.as_deref(), Some("mqtts://broker.plant:8883"));
    } else {
        let found = problems(&fleet);
        assert_eq!(keys(&found), ["fleet.broker"], "{found:#?}");
        assert!(
            found[0].message.contains("cargo feature `tls`"),
            "{}",
            found[0]
        );
        found.iter().for_each(assert_has_fix);
    }
    let plain = fleet.replace("mqtts://", "mqtt://");
    let broker = config_of(&plain).fleet.map(|f| f.broker.to_string());
    assert_eq!(broker.as_deref(), Some("mqtt://broker.plant:1883"));
}

#[test]
fn a_primary_host_id_with_topic_characters_is_listed_with_the_other_fleet_problems() {
    let text = format!(
        "{SENSOR}[fleet]\nenabled = true\nnode_id = \"press 7\"\npublish_period_s = 0\n\
         primary_host_id = \"plant/scada-#\"\n"
    );
    let found = problems(&text);
    let mut found_keys = keys(&found);
    found_keys.sort_unstable();
    assert_eq!(
        found_keys,
        [
            "fleet.node_id",
            "fleet.primary_host_id",
            "fleet.publish_period_s"
        ],
        "{found:#?}"
    );
    let host = find(&found, "fleet.primary_host_id");
    assert!(host.message.contains("\"plant/scada-#\""), "{host}");
    assert!(host.message.contains("'/', '#'"), "{host}");
    found.iter().for_each(assert_has_fix);

    let fine = format!(
        "{SENSOR}[fleet]\nenabled = true\nnode_id = \"press-7\"\nprimary_host_id = \"scada-1\"\n"
    );
    let fleet = config_of(&fine).fleet.expect("the bridge is on");
    assert_eq!(fleet.primary_host_id.as_deref(), Some("scada-1"));
    let without = fine.replace("primary_host_id = \"scada-1\"\n", "");
    assert_eq!(config_of(&without).fleet.unwrap().primary_host_id, None);
}
