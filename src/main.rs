//! The `bearingd` binary: a thin shell around [`bearingd::cli`].

fn main() -> std::process::ExitCode {
    bearingd::cli::main()
}
