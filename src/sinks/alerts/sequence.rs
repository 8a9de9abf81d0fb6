//! Sequence numbers as a subscriber checks them (sans-IO): duplicates dropped, losses
//! reported, and a number that cannot be trusted refused instead of believed.
//!
//! Why not simply "a gap is a loss": one alert with a forged huge number would then make every
//! real alert after it look "already seen", and a forged "cleared" would change the active set
//! a late subscriber computes (issue 32). The service's safe overflow tells a real loss apart:
//! a subscriber loses alerts only when its queue was full, so the alert after a real gap comes
//! with its `buffer - 1` successors in the same drain pass. A jump without them is reported as
//! [`Received::Untrusted`] and moves nothing. A new run id (a restarted daemon) starts over.

use super::payload::Alert;

/// What a subscriber takes from the service.
#[derive(Debug, Clone, PartialEq)]
pub enum Received {
    Alert(Alert),
    /// Alerts `first..=last` of the run never arrived: the subscriber's buffer overflowed.
    Lost {
        run_id: u64,
        first: u64,
        last: u64,
    },
    /// The daemon restarted (a new run id); sequence numbers start again.
    NewRun {
        run_id: u64,
    },
    /// An alert numbered `sequence` when `expected` was next, without the successors a real
    /// overflow leaves: not shown as an alert, and the numbering stays where it was.
    Untrusted {
        run_id: u64,
        sequence: u64,
        expected: u64,
    },
}

/// The subscriber's sequence state; feed it one drain pass at a time with [`Self::pass`].
#[derive(Debug, Clone)]
pub struct SequenceCheck {
    /// Run id and sequence of the last accepted alert.
    last: Option<(u64, u64)>,
    /// The next alert is expected to be its run's first (sequence 1).
    expect_first: bool,
    /// The subscriber's queue length: what a real overflow leaves in one pass.
    buffer: usize,
}

impl SequenceCheck {
    /// A check for a subscriber whose queue holds `buffer` alerts.
    pub fn new(buffer: usize) -> SequenceCheck {
        SequenceCheck {
            last: None,
            expect_first: false,
            buffer: buffer.max(1),
        }
    }

    /// The history was empty when we subscribed: the next alert must be number 1.
    pub fn expect_first(&mut self) {
        if self.last.is_none() {
            self.expect_first = true;
        }
    }

    /// Judges the alerts of one drain pass, oldest first, into `out`.
    pub fn pass(&mut self, alerts: &[Alert], out: &mut impl Extend<Received>) {
        for (i, alert) in alerts.iter().enumerate() {
            let (expected, new_run) = match self.last {
                Some((run, seq)) if run == alert.run_id => (Some(seq.saturating_add(1)), false),
                Some(_) => (Some(1), true),
                None => (self.expect_first.then_some(1), false),
            };
            let mut lost = None;
            if let Some(expected) = expected {
                if alert.sequence < expected {
                    continue; // already seen (history handed again)
                }
                if alert.sequence > expected {
                    if !self.overflowed_at(&alerts[i..]) {
                        // Nothing moves: neither the run nor the number.
                        out.extend([Received::Untrusted {
                            run_id: alert.run_id,
                            sequence: alert.sequence,
                            expected,
                        }]);
                        continue;
                    }
                    lost = Some(Received::Lost {
                        run_id: alert.run_id,
                        first: expected,
                        last: alert.sequence - 1,
                    });
                }
            }
            if new_run {
                out.extend([Received::NewRun {
                    run_id: alert.run_id,
                }]);
            }
            out.extend(lost);
            self.last = Some((alert.run_id, alert.sequence));
            self.expect_first = false;
            out.extend([Received::Alert(*alert)]);
        }
    }

    /// Whether `from[0]` begins what a full queue leaves: `buffer` alerts of one run, numbered
    /// consecutively.
    fn overflowed_at(&self, from: &[Alert]) -> bool {
        let first = &from[0];
        from.len() >= self.buffer
            && from[..self.buffer].iter().zip(0u64..).all(|(a, k)| {
                a.run_id == first.run_id && Some(a.sequence) == first.sequence.checked_add(k)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sinks::alerts::payload::test_alert;

    fn alert(run_id: u64, sequence: u64) -> Alert {
        test_alert(run_id, sequence)
    }

    fn judge(check: &mut SequenceCheck, alerts: &[Alert]) -> Vec<Received> {
        let mut out = Vec::new();
        check.pass(alerts, &mut out);
        out
    }

    fn sequences(received: &[Received]) -> Vec<u64> {
        received
            .iter()
            .filter_map(|r| match r {
                Received::Alert(a) => Some(a.sequence),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn duplicates_are_dropped_and_the_next_number_accepted() {
        let mut check = SequenceCheck::new(4);
        let out = judge(&mut check, &[alert(7, 3), alert(7, 4)]);
        assert_eq!(sequences(&out), [3, 4], "history: any start is accepted");
        let out = judge(&mut check, &[alert(7, 3), alert(7, 4), alert(7, 5)]);
        assert_eq!(out, [Received::Alert(alert(7, 5))]);
    }

    #[test]
    fn a_real_overflow_is_a_trusted_loss() {
        let mut check = SequenceCheck::new(4);
        check.expect_first();
        // The queue held the newest 4 of 10: 1..6 were overwritten.
        let batch: Vec<Alert> = (7..=10).map(|s| alert(7, s)).collect();
        let out = judge(&mut check, &batch);
        assert_eq!(
            out[0],
            Received::Lost {
                run_id: 7,
                first: 1,
                last: 6
            }
        );
        assert_eq!(sequences(&out), [7, 8, 9, 10]);
    }

    #[test]
    fn a_lone_jump_is_untrusted_and_does_not_poison_later_alerts() {
        let mut check = SequenceCheck::new(4);
        judge(&mut check, &[alert(7, 1), alert(7, 2)]);
        let out = judge(&mut check, &[alert(7, 1_000_000)]);
        assert_eq!(
            out,
            [Received::Untrusted {
                run_id: 7,
                sequence: 1_000_000,
                expected: 3
            }]
        );
        // Three successors are not enough either (the buffer is 4).
        let forged: Vec<Alert> = (500..503).map(|s| alert(7, s)).collect();
        assert!(judge(&mut check, &forged)
            .iter()
            .all(|r| matches!(r, Received::Untrusted { .. })));
        let out = judge(&mut check, &[alert(7, 3), alert(7, 4)]);
        assert_eq!(sequences(&out), [3, 4], "{out:?}");
    }

    #[test]
    fn an_empty_history_makes_a_lone_high_first_number_untrusted() {
        let mut check = SequenceCheck::new(4);
        check.expect_first();
        let out = judge(&mut check, &[alert(7, u64::MAX)]);
        assert!(matches!(out[..], [Received::Untrusted { expected: 1, .. }]));
        assert_eq!(sequences(&judge(&mut check, &[alert(7, 1)])), [1]);
    }

    #[test]
    fn a_new_run_id_starts_over_at_one() {
        let mut check = SequenceCheck::new(4);
        judge(&mut check, &[alert(7, 40)]);
        let out = judge(&mut check, &[alert(8, 1), alert(8, 2)]);
        assert_eq!(out[0], Received::NewRun { run_id: 8 });
        assert_eq!(sequences(&out), [1, 2]);
        // A forged run with a high number does not move anything; the real run goes on.
        let out = judge(&mut check, &[alert(9, 77)]);
        assert!(matches!(out[..], [Received::Untrusted { expected: 1, .. }]));
        let out = judge(&mut check, &[alert(8, 3)]);
        assert_eq!(sequences(&out), [3], "{out:?}");
    }
}
