//! Progress of the lab's long commands, on stderr only (stdout is the result's): on a terminal
//! an indicatif bar, elsewhere (a pipe, a log file) plain lines such as
//! `evaluate: 40/240 runs, 12.0 s`, at each quarter of the work and at least every 5 s.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Longest time between two plain lines.
const LINE_EVERY: Duration = Duration::from_secs(5);

/// The progress of one command over `total` items (files, runs, records, seconds); shared by
/// worker threads.
pub struct Progress {
    bar: Option<ProgressBar>,
    command: &'static str,
    unit: &'static str,
    total: u64,
    done: AtomicU64,
    started: Instant,
    last_line: Mutex<Instant>,
}

impl Progress {
    /// A bar on a terminal's stderr, plain lines elsewhere; `unit` names the items (`files`).
    pub fn start(command: &'static str, unit: &'static str, total: u64) -> Self {
        Self::with_terminal(command, unit, total, std::io::stderr().is_terminal())
    }

    fn with_terminal(
        command: &'static str,
        unit: &'static str,
        total: u64,
        terminal: bool,
    ) -> Self {
        let bar = terminal.then(|| {
            let bar =
                ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr_with_hz(4));
            let template =
                format!("{command} {{bar:30}} {{pos}}/{{len}} {unit}, {{eta}} left {{wide_msg}}");
            if let Ok(style) = ProgressStyle::with_template(&template) {
                bar.set_style(style);
            }
            bar
        });
        let now = Instant::now();
        Progress {
            bar,
            command,
            unit,
            total,
            done: AtomicU64::new(0),
            started: now,
            last_line: Mutex::new(now),
        }
    }

    /// `done` items finished so far; `detail` (e.g. `40 snapshots`) is shown after the count.
    pub fn set(&self, done: u64, detail: &str) {
        let before = self.done.swap(done, Ordering::Relaxed);
        self.show(before, done, detail);
    }

    /// One more item finished.
    pub fn inc(&self, detail: &str) {
        let before = self.done.fetch_add(1, Ordering::Relaxed);
        self.show(before, before + 1, detail);
    }

    /// Removes the bar, or prints the last plain line (when it was not printed already).
    pub fn finish(&self, detail: &str) {
        match &self.bar {
            Some(bar) => bar.finish_and_clear(),
            None => self.line(self.done.load(Ordering::Relaxed), detail),
        }
    }

    fn show(&self, before: u64, done: u64, detail: &str) {
        if let Some(bar) = &self.bar {
            bar.set_position(done);
            bar.set_message(detail.to_string());
            return;
        }
        let total = self.total.max(1);
        let quarter = done * 4 / total != before * 4 / total;
        let due = self.lock_last().elapsed() >= LINE_EVERY;
        if (quarter && done < self.total) || due {
            self.line(done, detail);
        }
    }

    fn line(&self, done: u64, detail: &str) {
        eprintln!("{}", self.line_text(done, detail));
        *self.lock_last() = Instant::now();
    }

    fn line_text(&self, done: u64, detail: &str) -> String {
        let detail = if detail.is_empty() {
            String::new()
        } else {
            format!(", {detail}")
        };
        format!(
            "{}: {done}/{} {}{detail}, {:.1} s",
            self.command,
            self.total,
            self.unit,
            self.started.elapsed().as_secs_f64()
        )
    }

    fn lock_last(&self) -> std::sync::MutexGuard<'_, Instant> {
        self.last_line
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plain_line_names_the_command_the_count_and_the_detail() {
        let progress = Progress::with_terminal("trend", "files", 8, false);
        let text = progress.line_text(2, "40 snapshots");
        assert!(
            text.starts_with("trend: 2/8 files, 40 snapshots, "),
            "{text}"
        );
        assert!(text.ends_with(" s"), "{text}");
        assert!(progress
            .line_text(3, "")
            .starts_with("trend: 3/8 files, 0."));
    }

    #[test]
    fn counts_add_up_across_threads() {
        let progress = Progress::with_terminal("dataset", "records", 400, false);
        std::thread::scope(|scope| {
            for _ in 0..4 {
                scope.spawn(|| (0..100).for_each(|_| progress.inc("")));
            }
        });
        assert_eq!(progress.done.load(Ordering::Relaxed), 400);
    }
}
