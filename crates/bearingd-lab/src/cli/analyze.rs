//! `bearingd-lab analyze FILE... --plot OUT` (also `bearingd analyze ... --plot OUT`, handed
//! over by the service): the service's own `analyze` ([`bearingd::cli::analyze::run_with`],
//! the same arguments, text and JSON), with the figure of each record drawn here.

use crate::report::analysis_figure;
use bearingd::cli::analyze::{run_with, AnalyzeArgs};
use bearingd::cli::CliError;
use bearingd::offline::AnalyzeOutcome;
use std::path::{Path, PathBuf};

pub fn run(args: &AnalyzeArgs) -> Result<(), CliError> {
    let Some(plot) = &args.plot else {
        return run_with(args, &mut |_, _| Ok(()));
    };
    run_with(args, &mut |outcome: &AnalyzeOutcome, records: usize| {
        let path = if records > 1 {
            per_record_path(plot, &outcome.report.file)
        } else {
            plot.clone()
        };
        let figure = analysis_figure(&outcome.report, &outcome.analysis, outcome.twin.as_ref());
        crate::plot::save(&figure, &path).map_err(CliError::input)
    })
}

/// `out.png` + `dir/105.mat` → `out-105.png`.
fn per_record_path(plot: &Path, record: &str) -> PathBuf {
    let stem = plot
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = plot
        .extension()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let record = Path::new(record)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    plot.with_file_name(format!("{stem}-{record}.{ext}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn several_records_get_their_name_before_the_extension() {
        assert_eq!(
            per_record_path(Path::new("out/fig.png"), "data/cwru/105.mat"),
            PathBuf::from("out/fig-105.png")
        );
    }
}
