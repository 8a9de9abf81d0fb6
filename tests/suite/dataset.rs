//! `bearingd dataset` (issue 14 item 3): a labelled synthetic set read by NumPy, the same on a
//! second run, and each record an MCAP log that `bearingd replay` reads without a config and
//! diagnoses as its label says.

use crate::cli::{bearingd, stderr};
use crate::replay::replay_json;
use bearingd_testdata::{mcap_files, python_scipy, scratch_dir};
use std::path::Path;
use std::process::Command;

const SPEC: &str = r#"
seed = 11
faults = ["none", "outer_race", "inner_race"]
records_per_fault = 2
model = "signal"
duration_s = 8.0
fs_hz = 12000
bearing = "skf-6205-2rs"
rpm = [1730, 1797]
noise_g = [0.05, 0.1]
amplitude_g = [1.0, 1.5]
defect_width_mm = [0.178, 0.533]
load_n = [500, 2000]
"#;

/// Writes `spec` as `dir/NAME.toml` and runs `bearingd dataset` on it into `dir/NAME`.
pub fn make(dir: &Path, name: &str, spec: &str, mcap: bool) -> std::path::PathBuf {
    let spec_path = dir.join(format!("{name}.toml"));
    std::fs::write(&spec_path, spec).unwrap();
    let out = dir.join(name);
    let mut args = vec![
        "dataset",
        "--spec",
        spec_path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    if mcap {
        args.push("--mcap");
    }
    let made = bearingd(&args);
    assert!(made.status.success(), "{}", stderr(&made));
    out
}

/// What NumPy reads from a set: shapes, labels and the manifest's labels, as one line of JSON.
fn numpy_view(py: &Path, out: &Path) -> serde_json::Value {
    let script = r#"
import csv, json, sys
import numpy as np
d = np.load(sys.argv[1] + "/dataset.npz")
rows = list(csv.DictReader(open(sys.argv[1] + "/manifest.csv")))
print(json.dumps({
    "x": list(d["x"].shape), "dtype": str(d["x"].dtype), "y": d["y"].tolist(),
    "fs_hz": float(d["fs_hz"]), "rpm": d["rpm"].tolist(),
    "manifest_labels": [int(r["label"]) for r in rows],
    "manifest_faults": [r["fault"] for r in rows],
    "x_sum": float(np.abs(d["x"]).sum()),
}))
"#;
    let out = Command::new(py)
        .args(["-c", script, out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn a_dataset_is_read_by_numpy_the_same_twice_and_each_record_replays_as_labelled() {
    let dir = scratch_dir("dataset");
    let first = make(&dir, "first", SPEC, true);
    let second = make(&dir, "second", SPEC, false);
    if let Some(py) = python_scipy() {
        let view = numpy_view(&py, &first);
        assert_eq!(view["x"], serde_json::json!([6, 96_000]), "{view}");
        assert_eq!(view["dtype"], "float32");
        assert_eq!(view["y"], serde_json::json!([0, 0, 1, 1, 2, 2]));
        assert_eq!(view["manifest_labels"], view["y"]);
        assert_eq!(
            view["manifest_faults"],
            serde_json::json!([
                "none",
                "none",
                "outer_race",
                "outer_race",
                "inner_race",
                "inner_race"
            ])
        );
        assert_eq!(view["fs_hz"], 12_000.0);
        assert!(view["x_sum"].as_f64().unwrap() > 0.0);
        // The same spec, the same data.
        assert_eq!(numpy_view(&py, &second), view);
    }
    // Each record's log replays without a config; the faulty ones raise their fault's flag and
    // nothing else, the healthy ones nothing.
    for (index, expected) in [(0, None), (2, Some("outer_race")), (4, Some("inner_race"))] {
        let log = mcap_files(&first.join(format!("mcap/{index:05}")));
        let (summary, _) = replay_json(&log, &dir.join(format!("replay-{index}")), &[]);
        assert_eq!(summary["settings_from"], "log", "{summary}");
        assert_eq!(summary["samples"], 96_000, "{summary}");
        let raised: Vec<&str> = summary["flags"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|f| f["from"] == "ok")
            .map(|f| f["fault"].as_str().unwrap())
            .collect();
        match expected {
            None => assert!(raised.is_empty(), "record {index}: {raised:?}"),
            Some(fault) => assert!(
                !raised.is_empty() && raised.iter().all(|f| *f == fault),
                "record {index}: expected only {fault}, raised {raised:?}"
            ),
        }
    }
}

#[test]
fn a_physics_dataset_is_made_and_a_bad_spec_lists_every_problem() {
    let dir = scratch_dir("dataset-physics");
    let physics = SPEC
        .replace("model = \"signal\"", "model = \"physics\"")
        .replace("duration_s = 8.0", "duration_s = 0.25")
        .replace("records_per_fault = 2", "records_per_fault = 1");
    let out = make(&dir, "physics", &physics, false);
    let manifest = std::fs::read_to_string(out.join("manifest.csv")).unwrap();
    assert_eq!(manifest.lines().count(), 4, "{manifest}");
    assert!(manifest.contains(",outer_race,physics,"), "{manifest}");

    let bad = SPEC
        .replace("fs_hz = 12000", "fs_hz = 10")
        .replace("noise_g = [0.05, 0.1]", "noise_g = [0.1, 0.05]");
    let spec = dir.join("bad.toml");
    std::fs::write(&spec, bad).unwrap();
    let refused = bearingd(&[
        "dataset",
        "--spec",
        spec.to_str().unwrap(),
        "--out",
        dir.join("bad").to_str().unwrap(),
    ]);
    let err = stderr(&refused);
    assert_eq!(refused.status.code(), Some(2), "{err}");
    assert!(
        err.contains("2 problem(s)") && err.contains("fs_hz") && err.contains("noise_g"),
        "{err}"
    );
    assert!(
        !dir.join("bad").exists(),
        "a refused spec must write nothing"
    );

    // `--bearing` simulates another bearing with the same spec, says so in the spec.toml it
    // writes, and is checked like the spec's own key.
    let mut args = vec!["--bearing", "skf-6203-2rs"];
    let spec = dir.join("physics.toml");
    let with = |args: &[&str], out: &str| {
        let mut all = vec!["dataset", "--spec", spec.to_str().unwrap(), "--out", out];
        all.extend_from_slice(args);
        bearingd(&all)
    };
    let other = dir.join("other-bearing");
    let made = with(&args, other.to_str().unwrap());
    assert!(made.status.success(), "{}", stderr(&made));
    let written: toml::Table = std::fs::read_to_string(other.join("spec.toml"))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(
        written["bearing"].as_str(),
        Some("skf-6203-2rs"),
        "{written}"
    );
    args[1] = "no-such-bearing";
    let refused = with(&args, dir.join("refused").to_str().unwrap());
    let err = stderr(&refused);
    assert_eq!(refused.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--bearing \"no-such-bearing\"") && err.contains("skf-6203-2rs"),
        "{err}"
    );
}
