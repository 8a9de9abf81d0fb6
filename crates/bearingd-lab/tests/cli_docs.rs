//! The man pages and completion scripts of both command lines (`bearingd-lab man`,
//! `bearingd-lab completions`), and the committed copies in docs/cli that the service embeds.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::cli::completions::Shell;
use bearingd_lab::cli::docs::{completion_script, man_pages, Program};
use bearingd_testdata::{run_binary, scratch_dir};
use std::path::{Path, PathBuf};

const LAB: &str = env!("CARGO_BIN_EXE_bearingd-lab");

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Every (display name, about) of a command and its subcommands, recursively (no hidden
/// command, no `help`), as the man pages are named: `bearingd-config-default`.
fn pages_wanted(command: clap::Command) -> Vec<(String, String)> {
    fn walk(command: &clap::Command, prefix: &str, out: &mut Vec<(String, String)>) {
        for sub in command.get_subcommands().filter(|sub| !sub.is_hide_set()) {
            let name = format!("{prefix}-{}", sub.get_name());
            let about = sub.get_about().map(|a| a.to_string()).unwrap_or_default();
            out.push((name.clone(), about));
            walk(sub, &name, out);
        }
    }
    let about = command
        .get_about()
        .map(|a| a.to_string())
        .unwrap_or_default();
    let mut out = vec![(command.get_name().to_string(), about)];
    walk(&command, command.get_name(), &mut out);
    out
}

/// The roff's text with clap_mangen's escapes undone and lines joined, to look prose up in.
fn roff_text(roff: &str) -> String {
    roff.replace("\\-", "-")
        .replace("\\*(Aq", "'")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// `bearingd-lab man --out DIR` writes a page for every command of both programs (read off
/// their clap commands, the service's own and not the lab's graft), each with its about text.
#[test]
fn man_writes_a_page_for_every_command_with_its_description() {
    let dir = scratch_dir("cli-docs-man");
    let out = run_binary(LAB, &["man", "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let mut wanted = pages_wanted(bearingd::cli::command());
    wanted.extend(pages_wanted(bearingd_lab::cli::command()));
    assert!(wanted.len() > 20, "{wanted:?}");
    for (name, about) in wanted {
        let path = dir.join(format!("{name}.1"));
        let roff = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("no man page {}: {e}", path.display()));
        let text = roff_text(&roff);
        assert!(
            roff.starts_with(".ie") || roff.contains(".TH"),
            "{name}: not roff"
        );
        let about = about.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            text.contains(&about),
            "{name}.1 lacks its about text '{about}'"
        );
    }
    // A directory that cannot be made is bad input that names it.
    let file = dir.join("bearingd.1");
    let bad = file.join("sub");
    let out = run_binary(LAB, &["man", "--out", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(bad.to_str().unwrap()),
        "{}",
        stderr(&out)
    );
}

/// The lab's own bash script offers each of its commands.
#[test]
fn lab_completions_offer_every_lab_command() {
    let out = run_binary(LAB, &["completions", "bash"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let script = String::from_utf8(out.stdout).unwrap();
    let top = script
        .lines()
        .skip_while(|line| line.trim() != "bearingd__lab)")
        .nth(1)
        .expect("no top-level case in the lab's bash script");
    for sub in bearingd_lab::cli::command().get_subcommands() {
        let name = sub.get_name();
        assert!(
            top.split(['"', ' ']).any(|word| word == name),
            "lacks `{name}`: {top}"
        );
    }
}

/// docs/cli is what the current command lines give: the service prints these scripts and
/// `make install` installs these pages, so a command line changed without `make cli-docs`
/// fails here.
#[test]
fn committed_docs_are_up_to_date() {
    let docs = repo_root().join("docs/cli");
    let fix = "run `make cli-docs` (then rebuild bearingd, which embeds the scripts)";
    for program in Program::ALL {
        let name = program.command().get_name().to_string();
        for shell in Shell::ALL {
            let path = docs.join("completions").join(shell.file_name(&name));
            let committed = std::fs::read(&path).unwrap_or_default();
            assert!(
                committed == completion_script(program, shell),
                "{} is stale: {fix}",
                path.display()
            );
        }
    }
    let mut generated: Vec<String> = Vec::new();
    for program in Program::ALL {
        for (file, roff) in man_pages(program).unwrap() {
            let path = docs.join("man").join(&file);
            let committed = std::fs::read(&path).unwrap_or_default();
            assert!(committed == roff, "{} is stale: {fix}", path.display());
            generated.push(file);
        }
    }
    for entry in std::fs::read_dir(docs.join("man")).unwrap() {
        let file = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            generated.contains(&file),
            "docs/cli/man/{file} is no command's page: {fix}"
        );
    }
    // The service embeds the same text.
    for shell in Shell::ALL {
        assert_eq!(
            shell.script().as_bytes(),
            completion_script(Program::Bearingd, shell),
            "the service's embedded {shell:?} script is stale: {fix}"
        );
    }
}
