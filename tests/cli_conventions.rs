//! The service's command-line conventions (issue 33 item 3): `validate`, `config default`,
//! `import`, `run` and `replay` honour `--format json` (text stays the default); `run` prints one
//! JSON object per line (NDJSON), each with its "type"; `replay` keeps `--json` as an alias.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd_testdata::{mcap_files, scratch_dir, sine_g, write_csv};
use serde_json::Value;
use std::process::Output;

fn bearingd(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd"), args)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn json(out: &Output) -> Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not one JSON document ({e}): {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

#[test]
fn config_default_and_validate_print_json() {
    let out = bearingd(&["config", "default", "--format", "json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let config = json(&out);
    let toml_text = String::from_utf8(bearingd(&["config", "default"]).stdout).unwrap();
    let from_toml: toml::Table = toml::from_str(&toml_text).unwrap();
    let mut keys: Vec<&String> = from_toml.keys().collect();
    let mut json_keys: Vec<&String> = config.as_object().unwrap().keys().collect();
    keys.sort();
    json_keys.sort();
    assert_eq!(json_keys, keys, "the JSON holds the TOML's tables");
    assert!(config["sensors"].is_array(), "{config}");

    let dir = scratch_dir("cli-json-validate");
    let good = dir.join("good.toml");
    std::fs::write(&good, &toml_text).unwrap();
    let out = bearingd(&["validate", good.to_str().unwrap(), "--format", "json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let said = json(&out);
    assert_eq!(said["ok"], true, "{said}");
    assert_eq!(said["sensors"], 1, "{said}");
    assert_eq!(said["problems"], serde_json::json!([]), "{said}");

    let bad = dir.join("bad.toml");
    let text = toml_text
        .replace("overlap = 0.5", "overlap = 2.0")
        .replace("harmonics = 5", "harmonics = 0");
    std::fs::write(&bad, text).unwrap();
    let out = bearingd(&["validate", bad.to_str().unwrap(), "--format", "json"]);
    assert_eq!(out.status.code(), Some(2), "exit code as in text");
    let said = json(&out);
    assert_eq!(said["ok"], false, "{said}");
    let keys: Vec<&str> = said["problems"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["key"].as_str().unwrap())
        .collect();
    assert_eq!(keys, ["analysis.overlap", "analysis.harmonics"], "{said}");
    assert!(said["problems"][0]["message"]
        .as_str()
        .unwrap()
        .contains("; "));
}

#[test]
fn import_run_and_replay_print_json() {
    let dir = scratch_dir("cli-json-service");
    let csv = dir.join("tone.csv");
    write_csv(&csv, sine_g(0.5, 157.0, 12_000.0, 24_000));
    let logs = dir.join("imported");
    let out = bearingd(&[
        "import",
        csv.to_str().unwrap(),
        "--out",
        logs.to_str().unwrap(),
        "--fs",
        "12000",
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
        "--format",
        "json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let imported = json(&out);
    assert_eq!(imported["samples"], 24_000, "{imported}");
    assert_eq!(imported["seconds"], 2.0, "{imported}");
    assert!(
        imported["log"].as_str().unwrap().ends_with(".mcap"),
        "{imported}"
    );
    assert!(imported["notes"].is_array() && imported["warnings"].is_array());

    let data = dir.join("data");
    let out = bearingd(&[
        "run",
        "--fast",
        "--duration",
        "45",
        "--data-dir",
        data.to_str().unwrap(),
        "--format",
        "json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let lines: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|line| serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {line}")))
        .collect();
    let types: Vec<&str> = lines.iter().map(|l| l["type"].as_str().unwrap()).collect();
    assert_eq!(types.last(), Some(&"summary"), "{types:?}");
    assert!(
        types.contains(&"flag"),
        "the fault after 30 s is flagged: {types:?}"
    );
    let summary = lines.last().unwrap();
    assert!(summary["messages"].as_u64().unwrap() > 0, "{summary}");
    assert_eq!(
        summary["channels"].as_array().unwrap().len(),
        1,
        "{summary}"
    );

    let files = mcap_files(&data.join("mcap"));
    let replayed = |format: &[&str]| {
        let out_dir = dir.join(format!("replay{}", format.len()));
        let mut args = vec!["replay", "--quiet", "--out", out_dir.to_str().unwrap()];
        args.extend_from_slice(format);
        args.extend(files.iter().map(|f| f.to_str().unwrap()));
        let out = bearingd(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        json(&out)
    };
    let by_format = replayed(&["--format", "json"]);
    let by_alias = replayed(&["--json"]);
    assert!(by_format["samples"].as_u64().unwrap() > 0, "{by_format}");
    assert_eq!(by_format["samples"], by_alias["samples"]);
    assert_eq!(by_format["flags"], by_alias["flags"]);
}
