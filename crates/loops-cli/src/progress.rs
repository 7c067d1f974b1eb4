//! What `loops run` tells the user while it works: progress bars on a terminal (indicatif),
//! one plain line per finished log otherwise, nothing with `--quiet`. All of it goes to stderr,
//! so stdout stays the result (the table, or JSON).

use std::io::IsTerminal;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    /// Bars and spinners (stderr is a terminal).
    Bars,
    /// A line per finished log (stderr is a file or a pipe).
    Lines,
    /// Errors only.
    Quiet,
}

impl Mode {
    /// Bars on a terminal, lines elsewhere, nothing when `quiet`.
    pub(crate) fn detect(quiet: bool) -> Self {
        if quiet {
            Self::Quiet
        } else if std::io::stderr().is_terminal() {
            Self::Bars
        } else {
            Self::Lines
        }
    }
}

/// Progress of a batch of `total` logs.
#[derive(Debug)]
pub(crate) struct Batch {
    mode: Mode,
    total: usize,
    finished: AtomicUsize,
    bars: Option<(MultiProgress, ProgressBar)>,
}

/// Progress of one log: a spinner with its stage, on a terminal.
#[derive(Debug)]
pub(crate) struct Log<'a> {
    batch: &'a Batch,
    name: String,
    spinner: Option<ProgressBar>,
}

impl Batch {
    /// Starts showing progress of `total` logs.
    pub(crate) fn new(mode: Mode, total: usize) -> Self {
        let bars = (mode == Mode::Bars).then(|| {
            let multi = MultiProgress::with_draw_target(ProgressDrawTarget::stderr());
            let overall = multi.add(ProgressBar::new(total as u64));
            overall.set_style(
                ProgressStyle::with_template("{elapsed_precise} [{bar:32.cyan/blue}] {pos}/{len} logs {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            overall.enable_steady_tick(Duration::from_millis(200));
            (multi, overall)
        });
        Self { mode, total, finished: AtomicUsize::new(0), bars }
    }

    /// A plain line (not with `--quiet`), printed above the bars on a terminal.
    pub(crate) fn println(&self, line: &str) {
        match (&self.bars, self.mode) {
            (_, Mode::Quiet) => {}
            (Some((multi, _)), _) => {
                let _ = multi.println(line);
            }
            (None, _) => eprintln!("{line}"),
        }
    }

    /// A log starts.
    pub(crate) fn start(&self, name: &str) -> Log<'_> {
        let spinner = self.bars.as_ref().map(|(multi, overall)| {
            let spinner = multi.insert_before(overall, ProgressBar::new_spinner());
            spinner.set_style(
                ProgressStyle::with_template("  {spinner} {prefix:.bold} {msg} ({elapsed})")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            spinner.set_prefix(name.to_owned());
            spinner.enable_steady_tick(Duration::from_millis(120));
            spinner
        });
        Log { batch: self, name: name.to_owned(), spinner }
    }

    /// Clears the bars (before the final table).
    pub(crate) fn finish(&self) {
        if let Some((multi, overall)) = &self.bars {
            overall.finish_and_clear();
            let _ = multi.clear();
        }
    }
}

impl Log<'_> {
    /// The stage the log is in ("reading", "finding loops", ...).
    pub(crate) fn stage(&self, stage: &str) {
        if let Some(spinner) = &self.spinner {
            spinner.set_message(stage.to_owned());
        }
    }

    /// A warning about the log's result: on stderr (above the bars), even with `--quiet`.
    pub(crate) fn warn(&self, warning: &str) {
        let line = format!("loops: warning: {}: {warning}", self.name);
        match &self.batch.bars {
            Some((multi, _)) => {
                let _ = multi.println(&line);
            }
            None => eprintln!("{line}"),
        }
    }

    /// The log is done: `outcome` is its one-line result (or error).
    pub(crate) fn finish(self, ok: bool, outcome: &str) {
        let done = self.batch.finished.fetch_add(1, Ordering::SeqCst) + 1;
        let line =
            format!("loops: [{done}/{}] {}: {}{outcome}", self.batch.total, self.name, if ok { "" } else { "error: " });
        if let Some(spinner) = &self.spinner {
            spinner.finish_and_clear();
        }
        if let Some((_, overall)) = &self.batch.bars {
            overall.inc(1);
        }
        match self.batch.mode {
            Mode::Quiet if ok => {}
            Mode::Quiet => eprintln!("{line}"),
            _ => self.batch.println(&line),
        }
    }
}
