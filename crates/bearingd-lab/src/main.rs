//! The `bearingd-lab` binary: a thin shell around [`bearingd_lab::cli`].

fn main() -> std::process::ExitCode {
    bearingd_lab::cli::main()
}
