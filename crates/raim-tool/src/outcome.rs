//! How a run of `raim` ends: the exit codes (documented in `raim --help`
//! and docs/FORMATS.md "Exit codes") and the count of refused epochs.
//!
//! A refused epoch (a typed core error such as `DuplicateSatellite`, or an
//! input line that is not an epoch) does not stop the run: it is answered
//! in the output like any other epoch, counted here, and the run then ends
//! with [`EXIT_REFUSED`] so a script can tell, unless `--keep-going`.

use std::io::Write;
use std::process::ExitCode;

/// Every epoch was answered with a decision (alarms included: an alarm is
/// a result, not a failure of the tool).
pub const EXIT_OK: u8 = 0;
/// The run could not be done: a missing, truncated or corrupt file, a bad
/// configuration, a fault spec that matches nothing, QEMU gone.
pub const EXIT_ERROR: u8 = 1;
/// The command line is wrong (clap's usage errors).
pub const EXIT_USAGE: u8 = 2;
/// The run finished but at least one epoch was refused (see stderr).
pub const EXIT_REFUSED: u8 = 3;

/// The text of the exit codes for `raim --help`.
pub const HELP: &str = "Exit codes:
  0  every epoch answered (alarms included)
  1  error: missing, truncated or corrupt input, bad configuration, a fault that matches nothing
  2  usage error (bad command line)
  3  finished, but some epochs were refused (count on stderr; --keep-going gives 0)

Formats, exit codes and examples: docs/FORMATS.md; replay and scenario files: docs/REPLAY.md.";

/// Epochs seen and refused in one run.
#[derive(Debug, Default, Clone)]
pub struct Tally {
    pub epochs: usize,
    pub refused: usize,
    /// The first refusal, for the stderr report.
    pub first_refusal: Option<String>,
}

impl Tally {
    pub fn answered(&mut self) {
        self.epochs += 1;
    }

    pub fn refuse(&mut self, what: impl FnOnce() -> String) {
        self.epochs += 1;
        self.refused += 1;
        if self.first_refusal.is_none() {
            self.first_refusal = Some(what());
        }
    }

    /// The one-line stderr report of refused epochs, if any.
    pub fn report(&self, keep_going: bool) -> Option<String> {
        (self.refused > 0).then(|| {
            format!(
                "raim: {} of {} epochs refused (first: {}){}",
                self.refused,
                self.epochs,
                self.first_refusal.as_deref().unwrap_or("-"),
                if keep_going {
                    ""
                } else {
                    "; exit code 3 (--keep-going for 0)"
                }
            )
        })
    }

    /// Report on stderr and give the exit code.
    pub fn finish(&self, keep_going: bool) -> ExitCode {
        if let Some(msg) = self.report(keep_going) {
            // stderr closed too: nothing more to say.
            let _ = writeln!(std::io::stderr(), "{msg}");
            if !keep_going {
                return ExitCode::from(EXIT_REFUSED);
            }
        }
        ExitCode::from(EXIT_OK)
    }
}

/// Whether the error is stdout closed under us (`raim ... | head`): the
/// reader has what it wanted, so the run ends quietly, as Unix tools do.
pub fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Print a fatal error on stderr (the message and its causes, one line,
/// never a backtrace) and give [`EXIT_ERROR`].
pub fn fail(e: &anyhow::Error) -> ExitCode {
    let _ = writeln!(std::io::stderr(), "raim: error: {e:#}");
    ExitCode::from(EXIT_ERROR)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_counts_and_names_the_first_refusal() {
        let mut t = Tally::default();
        t.answered();
        t.refuse(|| "line 2".into());
        t.refuse(|| "line 3".into());
        let r = t.report(false).unwrap();
        assert_eq!(
            r,
            "raim: 2 of 3 epochs refused (first: line 2); exit code 3 (--keep-going for 0)"
        );
        assert!(Tally::default().report(false).is_none());
    }

    #[test]
    fn broken_pipe_is_found_through_context() {
        let io = std::io::Error::new(std::io::ErrorKind::BrokenPipe, "x");
        let e = anyhow::Error::new(io).context("writing");
        assert!(is_broken_pipe(&e));
        assert!(!is_broken_pipe(&anyhow::anyhow!("other")));
    }
}
