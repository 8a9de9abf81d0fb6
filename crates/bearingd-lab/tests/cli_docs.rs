//! The man pages and completion scripts of both command lines (`bearingd-lab man`,
//! `bearingd-lab completions`), the committed copies in docs/cli that the service embeds and
//! `make install` installs, and that install itself into a DESTDIR.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::cli::completions::Shell;
use bearingd_lab::cli::docs::{completion_script, man_pages, Program};
use bearingd_testdata::{binary_beside, run_binary, scratch_dir};
use std::path::{Path, PathBuf};
use std::process::Command;

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

/// `make install` into a DESTDIR puts both programs' pages and scripts where man, bash, zsh and
/// fish look; `make install-service` the service's alone; `make uninstall` takes them away.
#[test]
fn make_install_puts_pages_and_completions_under_destdir() {
    let service = binary_beside(LAB, "bearingd");
    let make = |target: &str, root: &Path| {
        let out = Command::new("make")
            .arg("-s")
            .arg("-C")
            .arg(repo_root())
            .arg(target)
            .arg(format!("DESTDIR={}", root.display()))
            .arg(format!("BIN={}", service.display()))
            .arg(format!("LAB_BIN={LAB}"))
            .output()
            .expect("cannot run make: apt-get install make");
        assert!(out.status.success(), "make {target}: {}", stderr(&out));
    };
    let share = |root: &Path, rel: &str| root.join("usr/share").join(rel);
    let service_files = [
        "man/man1/bearingd.1",
        "man/man1/bearingd-run.1",
        "man/man1/bearingd-config-default.1",
        "bash-completion/completions/bearingd",
        "zsh/vendor-completions/_bearingd",
        "fish/vendor_completions.d/bearingd.fish",
    ];
    let lab_files = [
        "man/man1/bearingd-lab.1",
        "man/man1/bearingd-lab-train.1",
        "bash-completion/completions/bearingd-lab",
        "zsh/vendor-completions/_bearingd-lab",
        "fish/vendor_completions.d/bearingd-lab.fish",
    ];

    let root = scratch_dir("cli-docs-install");
    make("install", &root);
    for rel in service_files.iter().chain(&lab_files) {
        assert!(share(&root, rel).is_file(), "make install left out {rel}");
    }
    let bash = std::fs::read(share(&root, "bash-completion/completions/bearingd")).unwrap();
    assert_eq!(bash, Shell::Bash.script().as_bytes());
    let pages = std::fs::read_dir(share(&root, "man/man1")).unwrap().count();
    assert_eq!(
        pages,
        std::fs::read_dir(repo_root().join("docs/cli/man"))
            .unwrap()
            .count()
    );
    make("uninstall", &root);
    for rel in service_files.iter().chain(&lab_files) {
        assert!(!share(&root, rel).exists(), "make uninstall left {rel}");
    }

    let root = scratch_dir("cli-docs-install-service");
    make("install-service", &root);
    for rel in service_files {
        assert!(
            share(&root, rel).is_file(),
            "make install-service left out {rel}"
        );
    }
    for rel in lab_files {
        assert!(
            !share(&root, rel).exists(),
            "install-service installed {rel}"
        );
    }
}

/// Every `--bearing` option of both programs (any command, at any depth) and the help text it
/// shows: its choices must be the ones an unknown name's error lists (the catalog).
fn bearing_options(command: &clap::Command, path: &str, out: &mut Vec<(String, String)>) {
    for arg in command.get_arguments() {
        if arg.get_long() == Some("bearing") {
            let help = arg.get_long_help().or(arg.get_help());
            out.push((
                path.to_string(),
                help.map(|h| h.to_string()).unwrap_or_default(),
            ));
        }
    }
    for sub in command.get_subcommands() {
        bearing_options(sub, &format!("{path} {}", sub.get_name()), out);
    }
}

#[test]
fn every_bearing_option_lists_the_catalog_its_error_lists() {
    let mut options = Vec::new();
    bearing_options(&bearingd::cli::command(), "bearingd", &mut options);
    bearing_options(&bearingd_lab::cli::command(), "bearingd-lab", &mut options);
    let commands: Vec<&str> = options.iter().map(|(path, _)| path.as_str()).collect();
    for wanted in [
        "bearingd analyze",
        "bearingd import",
        "bearingd-lab simulate",
    ] {
        assert!(
            commands.contains(&wanted),
            "no --bearing in {wanted}: {commands:?}"
        );
    }
    let catalog = bearingd::bearing::BearingGeometry::catalog_names();
    for (path, help) in &options {
        let missing: Vec<_> = catalog
            .iter()
            .filter(|name| !help.contains(*name))
            .collect();
        assert!(
            missing.is_empty(),
            "{path} --bearing: its help leaves out {missing:?}, which an unknown name's error \
             lists: {help}"
        );
    }
}
