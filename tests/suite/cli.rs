//! The `bearingd` binary as a user meets it: outputs and one-line errors with exit
//! code 2 for every kind of bad input (the pictures, drawn by the lab: crates/bearingd-lab/tests).

use bearingd_testdata::{scratch_dir, shared_data_dir};
use std::path::Path;
use std::process::{Command, Output};

pub fn bearingd(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd"), args)
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `args`, expects exit code 2 and a one-line error containing every `needle`.
fn expect_input_error(args: &[&str], needles: &[&str]) {
    let out = bearingd(args);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "{args:?}: not one line: {err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    for needle in needles {
        assert!(err.contains(needle), "{args:?}: '{err}' lacks '{needle}'");
    }
}

#[test]
fn demo_json_has_every_documented_key_and_finds_the_simulated_fault() {
    let out = bearingd(&["analyze", "--demo", "--format", "json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    for key in [
        "file",
        "channel",
        "fs_hz",
        "rpm",
        "bearing",
        "duration_s",
        "band_hz",
        "fault_frequencies_hz",
        "scores",
        "diagnosis",
        "confidence",
        "indicators",
    ] {
        assert!(json.get(key).is_some(), "missing key {key}");
    }
    for key in ["bpfo", "bpfi", "bsf", "ftf"] {
        assert!(
            json["fault_frequencies_hz"][key].as_f64().unwrap() > 0.0,
            "{key}"
        );
    }
    for key in ["outer_race", "inner_race", "ball", "cage"] {
        assert!(json["scores"][key].is_number(), "{key}");
    }
    for key in ["rms", "peak", "crest", "kurtosis"] {
        assert!(json["indicators"][key].as_f64().unwrap() > 0.0, "{key}");
    }
    assert_eq!(json["band_hz"].as_array().unwrap().len(), 2);
    assert_eq!(json["diagnosis"], "outer_race");
}

/// The text report opens with the verdict in a technician's words (what, how sure, what to do;
/// no statistics), and the per-fault list marks each fault named or says why not; the JSON
/// carries the same line and marks.
#[test]
fn analyze_opens_with_the_plain_verdict_and_says_why_a_fault_is_not_named() {
    let Some(dir) = shared_data_dir("cwru") else {
        return;
    };
    for (file, opening, named) in [
        (
            "12k_Drive_End_OR007@6_0_130.mat",
            "VERDICT: Outer race defect, clear (",
            Some("outer_race"),
        ),
        ("normal_0_97.mat", "VERDICT: No bearing fault found", None),
    ] {
        let path = dir.join(file);
        let path = path.to_str().unwrap();
        let out = bearingd(&["analyze", path]);
        assert!(out.status.success(), "{}", stderr(&out));
        let text = String::from_utf8_lossy(&out.stdout);
        let first = text.lines().next().unwrap_or_default();
        assert!(first.starts_with(opening), "{file}: {text}");
        for jargon in ["p=", "10^", "comb", "GK", "_race"] {
            assert!(!first.contains(jargon), "{file}: '{jargon}' in {first}");
        }
        let marks: Vec<&str> = text
            .lines()
            .filter(|l| l.ends_with("  named") || l.contains("  not named: "))
            .collect();
        assert_eq!(marks.len(), 4, "{file}: one mark per fault:\n{text}");

        let out = bearingd(&["analyze", path, "--format", "json"]);
        assert!(out.status.success(), "{}", stderr(&out));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(
            format!("VERDICT: {}", json["summary"].as_str().unwrap()),
            first,
            "{file}"
        );
        for h in json["hypotheses"].as_array().unwrap() {
            let is_named = named == h["fault"].as_str();
            assert_eq!(h["named"], is_named, "{file}: {h}");
            assert_eq!(h["why_not"].is_string(), !is_named, "{file}: {h}");
        }
    }
}

#[test]
fn bad_recordings_give_one_line_errors_naming_the_file() {
    let dir = scratch_dir("cli-bad");
    let p = |name: &str| dir.join(name).to_string_lossy().into_owned();

    std::fs::write(
        dir.join("notes.mat"),
        "this is a text file, not MATLAB\n".repeat(10),
    )
    .unwrap();
    expect_input_error(
        &["analyze", &p("notes.mat")],
        &["notes.mat", "not a MATLAB"],
    );

    let nan: String = (0..20_000)
        .map(|i| {
            if i == 1234 {
                "NaN\n".to_string()
            } else {
                format!("{}\n", (i % 7) as f64 * 0.1)
            }
        })
        .collect();
    std::fs::write(dir.join("nan.csv"), nan).unwrap();
    expect_input_error(
        &[
            "analyze",
            &p("nan.csv"),
            "--fs",
            "12000",
            "--rpm",
            "1797",
            "--bearing",
            "skf-6205-2rs",
        ],
        &["nan.csv", "1234"],
    );

    let short: String = (0..500).map(|i| format!("{}\n", (i % 5) as f64)).collect();
    std::fs::write(dir.join("short.csv"), short).unwrap();
    expect_input_error(
        &[
            "analyze",
            &p("short.csv"),
            "--fs",
            "12000",
            "--rpm",
            "1797",
            "--bearing",
            "skf-6205-2rs",
        ],
        &["short.csv", "500 samples"],
    );

    expect_input_error(
        &[
            "analyze",
            &p("short.csv"),
            "--rpm",
            "1797",
            "--bearing",
            "skf-6205-2rs",
        ],
        &["short.csv", "--fs"],
    );
    expect_input_error(
        &[
            "analyze",
            &p("short.csv"),
            "--fs",
            "12000",
            "--bearing",
            "skf-6205-2rs",
        ],
        &["short.csv", "--rpm"],
    );
    expect_input_error(
        &["analyze", &p("short.csv"), "--fs", "12000", "--rpm", "1797"],
        &["short.csv", "--bearing"],
    );
    expect_input_error(
        &["analyze", &p("missing.mat")],
        &["missing.mat", "not found"],
    );
    expect_input_error(
        &["analyze", "--demo", "--bearing", "z=9,d=7.94mm"],
        &["D (pitch diameter) is missing"],
    );

    let Some(cwru) = shared_data_dir("cwru") else {
        return;
    };
    let real = cwru.join("12k_Drive_End_IR007_0_105.mat");
    let bytes = std::fs::read(&real).unwrap();
    std::fs::write(dir.join("cut.mat"), &bytes[..bytes.len() / 3]).unwrap();
    expect_input_error(&["analyze", &p("cut.mat")], &["cut.mat", "truncated"]);
    expect_input_error(
        &[
            "analyze",
            real.to_str().unwrap(),
            "--channel",
            "X999_DE_time",
        ],
        &["105", "X999_DE_time", "X105_DE_time"],
    );
}

#[test]
fn validate_lists_every_problem_and_config_default_is_valid() {
    let out = bearingd(&["config", "default"]);
    assert!(out.status.success());
    let committed =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/bearingd.toml"))
            .unwrap();
    assert_eq!(String::from_utf8_lossy(&out.stdout), committed);

    let dir = scratch_dir("cli-validate");
    let good = dir.join("good.toml");
    std::fs::write(&good, &committed).unwrap();
    let out = bearingd(&["validate", good.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));

    let bad = dir.join("bad.toml");
    let text = committed
        .replace("sample_rate_hz = 25600", "sample_rate_hz = 0")
        .replace("overlap = 0.5", "overlap = 2.0")
        .replace("harmonics = 5", "harmonics = 0");
    std::fs::write(&bad, text).unwrap();
    let out = bearingd(&["validate", bad.to_str().unwrap()]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for key in [
        "sensors[0].sample_rate_hz",
        "analysis.overlap",
        "analysis.harmonics",
    ] {
        assert!(err.contains(key), "'{err}' lacks {key}");
    }
}

#[test]
fn a_simulated_record_is_diagnosed_and_the_twin_reported() {
    let dir = scratch_dir("cli-simulate");
    for (out, extra) in [("outer.wav", vec![]), ("outer.csv", vec!["--fs", "12000"])] {
        let path = dir.join(out);
        let path = path.to_str().unwrap();
        let made = bearingd(&[
            "simulate",
            "--fault",
            "outer",
            "--rpm",
            "1772",
            "--bearing",
            "skf-6205-2rs",
            "--duration",
            "10s",
            "--out",
            path,
        ]);
        assert!(made.status.success(), "{}", stderr(&made));
        let mut args = vec![
            "analyze",
            path,
            "--rpm",
            "1772",
            "--bearing",
            "skf-6205-2rs",
            "--twin",
            "--format",
            "json",
        ];
        args.extend(extra);
        let out = bearingd(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(json["diagnosis"], "outer_race", "{json}");
        let twin = &json["twin"];
        assert_eq!(twin["hypothesis"], "outer_race");
        for key in ["a", "B", "f_n"] {
            assert!(twin["params"][key].as_f64().unwrap() > 0.0, "{key}");
        }
        for key in ["outer_race", "inner_race", "ball"] {
            assert!(twin["errors"][key].as_f64().unwrap() >= 0.0, "{key}");
        }
        assert!(
            twin["error"].as_f64().unwrap() < 0.1 && twin["margin"].as_f64().unwrap() > 0.1,
            "{twin}"
        );
        assert!(twin["fit_ms"].as_f64().unwrap() > 0.0);
    }
    expect_input_error(
        &["simulate", "--out", dir.join("x.mp3").to_str().unwrap()],
        &["x.mp3", ".csv"],
    );
    expect_input_error(
        &[
            "simulate",
            "--duration",
            "ten",
            "--out",
            dir.join("x.csv").to_str().unwrap(),
        ],
        &["--duration ten"],
    );
}

#[test]
fn output_into_a_pipe_closed_early_ends_without_a_panic() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    // `bearingd analyze --demo | head -0`: the reader is gone before the first line is written.
    let mut child = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(["analyze", "--demo"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run bearingd");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("bearingd ends");
    let err = stderr(&out);
    assert!(
        !err.contains("panicked"),
        "a closed pipe made a panic: {err}"
    );
    assert_eq!(
        out.status.signal(),
        Some(libc::SIGPIPE),
        "expected the end of a Unix tool whose reader left (SIGPIPE), got {:?}: {err}",
        out.status
    );
}

/// `bearingd completions bash` offers every command the service's clap command has, read off the
/// command and not a list (a new command without its completion fails here); every shell gets a
/// script; an unknown shell is bad input.
#[test]
fn completions_offer_every_command_of_the_service() {
    let out = bearingd(&["completions", "bash"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let script = String::from_utf8(out.stdout).expect("UTF-8 script");
    // The top level's words: the `opts=` line right after the `bearingd)` case.
    let lines: Vec<&str> = script.lines().collect();
    let case = lines
        .iter()
        .position(|line| line.trim() == "bearingd)")
        .expect("the script has no `bearingd)` case");
    let opts = lines[case + 1].trim();
    assert!(opts.starts_with("opts=\""), "{opts}");
    let words: Vec<&str> = opts["opts=\"".len()..]
        .trim_end_matches('"')
        .split_whitespace()
        .collect();
    let command = bearingd::cli::command();
    let names: Vec<&str> = command.get_subcommands().map(|c| c.get_name()).collect();
    assert!(names.len() >= 10, "{names:?}");
    for name in &names {
        assert!(
            words.contains(name),
            "bash completion lacks `{name}`: {opts}"
        );
    }
    for shell in ["zsh", "fish", "elvish", "powershell"] {
        let out = bearingd(&["completions", shell]);
        assert!(out.status.success(), "{shell}: {}", stderr(&out));
        let script = String::from_utf8_lossy(&out.stdout);
        for name in &names {
            assert!(script.contains(name), "{shell} completion lacks `{name}`");
        }
    }
    let out = bearingd(&["completions", "tcsh"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("tcsh") && err.contains("bash"), "{err}");
}

/// `analyze --hw` (the HW model of seed 003 at orders 0–9, the layout of its Table A1) honours
/// `--format json`, and in a pipe its progress is one plain line per record.
#[test]
fn analyze_hw_prints_json_when_asked_and_plain_progress_in_a_pipe() {
    let Some(femto) = shared_data_dir("femto") else {
        return;
    };
    let snapshot = femto.join("Bearing1_2/acc_00001.csv");
    let snapshot = snapshot.to_str().unwrap();
    let out = bearingd(&["analyze", "--hw", "--format", "json", snapshot]);
    assert!(out.status.success(), "{}", stderr(&out));
    let table: serde_json::Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&out.stdout)));
    let orders = table["records"][0]["orders"].as_array().unwrap();
    assert_eq!(orders.len(), 10, "{table:#}");
    for (n, order) in orders.iter().enumerate() {
        assert_eq!(order["order"], n);
        let accuracy = order["simulation_accuracy_pct"].as_f64().unwrap();
        assert!(accuracy > 50.0 && accuracy <= 100.0, "{order}");
    }
    assert_eq!(table["bearings"][0]["bearing"], "Bearing1_2");
    assert_eq!(table["bearings"][0]["records"], 1);
    assert_eq!(table["states"], "raw_once");
    assert_eq!(table["failures"], serde_json::json!([]));
    let progress = stderr(&out);
    assert!(
        progress.contains("analyze --hw: 1/1 records (") && !progress.contains('\r'),
        "{progress:?}"
    );

    let text = bearingd(&["analyze", "--hw", snapshot]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.starts_with("| record | n=0 |"), "{text}");
}
