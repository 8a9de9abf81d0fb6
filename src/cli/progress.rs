//! The progress line `replay` draws on a terminal's stderr: a bar over the bytes read, redrawn
//! in place, cleared for any other line and at the end. Small enough that the service binary
//! needs no progress-bar crate; elsewhere (not a terminal) `replay` prints plain lines instead.

use std::io::Write;
use std::sync::{Mutex, MutexGuard};

/// Cells of the bar.
const BAR_CELLS: usize = 20;

/// One progress line on stderr; shared by the events callback and the command that ends it.
#[derive(Default)]
pub struct ProgressLine {
    /// Characters of the line drawn now (0: none).
    drawn: Mutex<usize>,
}

impl ProgressLine {
    /// Draws `done` of `total` bytes with `note` after them, in place of the line drawn before.
    pub fn show(&self, done: u64, total: u64, note: &str) {
        let text = render(done, total, note);
        let mut drawn = self.lock();
        let mut stderr = std::io::stderr().lock();
        let width = text.chars().count();
        let pad = drawn.saturating_sub(width);
        // A terminal that went away is no reason to stop a replay.
        let _ = write!(stderr, "\r{text}{:pad$}", "");
        let _ = stderr.flush();
        *drawn = width;
    }

    /// Prints `line` on a line of its own; the progress line is drawn again by the next `show`.
    pub fn print_above(&self, line: &str) {
        let mut drawn = self.lock();
        erase(&mut drawn);
        eprintln!("{line}");
    }

    /// Removes the progress line (at the end of the replay).
    pub fn clear(&self) {
        erase(&mut self.lock());
    }

    fn lock(&self) -> MutexGuard<'_, usize> {
        // A panic elsewhere while drawing leaves a width, still usable.
        self.drawn
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

fn erase(drawn: &mut usize) {
    if *drawn > 0 {
        let mut stderr = std::io::stderr().lock();
        let _ = write!(stderr, "\r{:width$}\r", "", width = *drawn);
        let _ = stderr.flush();
        *drawn = 0;
    }
}

/// The line's text: `replay [#####---------------] 1.2 MiB/4.8 MiB NOTE`.
fn render(done: u64, total: u64, note: &str) -> String {
    let filled = (BAR_CELLS as f64 * done as f64 / total.max(1) as f64).round() as usize;
    let filled = filled.min(BAR_CELLS);
    format!(
        "replay [{}{}] {}/{} {note}",
        "#".repeat(filled),
        "-".repeat(BAR_CELLS - filled),
        mebibytes(done),
        mebibytes(total)
    )
}

fn mebibytes(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1024.0 * 1024.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bar_fills_with_the_bytes_read_and_never_overflows() {
        let mib = 1024 * 1024;
        assert_eq!(
            render(mib, 4 * mib, "3 s, 0 flag changes"),
            "replay [#####---------------] 1.0 MiB/4.0 MiB 3 s, 0 flag changes"
        );
        assert!(render(0, 0, "").starts_with("replay [--------------------] 0.0 MiB/0.0 MiB"));
        assert!(render(9 * mib, 4 * mib, "").starts_with("replay [####################] 9.0"));
    }

    #[test]
    fn a_cleared_line_has_no_width_left() {
        let line = ProgressLine::default();
        line.clear();
        assert_eq!(*line.lock(), 0);
    }
}
