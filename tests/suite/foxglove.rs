//! Foxglove-ready logs (issue 33): the layout in `docs/foxglove/` against the log of a fresh
//! 60 s `bearingd run --fast` (its User Script run by Node.js with TypeScript, every topic and
//! message path it names resolved in the log, no empty spectrum, a frequency per bin), and the
//! numbers docs/MCAP.md states (block length, rates, bins, bytes per day) against the same log.

use bearingd_testdata::{mcap_files, python_mcap, scratch_dir};
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Whether Node.js and TypeScript (`npm ci --prefix tests/foxglove`) are there to run the
/// layout's User Script; under `CI=true` they must be.
fn node_with_typescript() -> bool {
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let node = Command::new("node").arg("--version").output();
    let problem = match node {
        Err(e) => Some(format!("node: {e}")),
        Ok(_) if !repo("tests/foxglove/node_modules/typescript").exists() => {
            Some("TypeScript is not installed: npm ci --prefix tests/foxglove".into())
        }
        Ok(_) => None,
    };
    match problem {
        None => true,
        Some(p) if ci => panic!("the Foxglove layout test needs Node.js and TypeScript: {p}"),
        Some(p) => {
            eprintln!("skipping the Foxglove layout test: {p}");
            false
        }
    }
}

fn python(py: &Path, script: &str, args: &[&Path]) -> String {
    let out = Command::new(py)
        .arg(repo("tests/python").join(script))
        .args(args)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{script}: {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

#[test]
fn foxglove_layout_and_mcap_doc_match_a_daemon_log() {
    let Some(py) = python_mcap() else { return };
    if !node_with_typescript() {
        return;
    }
    let data = scratch_dir("foxglove");
    crate::severity::run_ok(&[
        "run",
        "--fast",
        "--duration",
        "60",
        "--quiet",
        "--data-dir",
        data.to_str().unwrap(),
    ]);
    let logs = mcap_files(&data.join("mcap"));
    assert_eq!(logs.len(), 1, "{logs:?}");
    let layout = repo("docs/foxglove/bearingd.layout.json");
    let script = repo("docs/foxglove/raw_in_g.ts");
    let summary: serde_json::Value = serde_json::from_str(&python(
        &py,
        "foxglove_layout.py",
        &[&layout, &logs[0], &script],
    ))
    .unwrap();
    // The script's output is a message per raw block (600 in 60 s of 0.1 s blocks), and every
    // spectrum has bins (9 of 46 were empty before).
    assert_eq!(summary["user_script"]["messages"], 600, "{summary}");
    assert!(summary["spectra"].as_u64().unwrap() >= 30, "{summary}");
    let doc = python(
        &py,
        "mcap_doc_numbers.py",
        &[&repo("docs/MCAP.md"), &logs[0]],
    );
    assert!(doc.contains("\"log bytes per 60 s\""), "{doc}");
    let _ = std::fs::remove_dir_all(&data);
}
