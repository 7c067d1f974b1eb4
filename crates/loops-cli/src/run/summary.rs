//! What `loops run` and `loops fleet` write to `summary.json`: a log's summary, the batch's, and
//! the settings every one of them (and the fleet's) states with the same keys.

use loops_core::{Loops, SampleSize, Sampler, Samples, Separation};
use loops_io::{QualitySummary, SeparationReport};
use serde::Serialize;

/// The settings of a result as summary.json states them, flattened into a log's
/// ([`LogSummary`]), the batch's ([`BatchSummary`]) and the fleet's summary: one set of keys.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct SettingsSummary {
    pub(crate) gamma: f64,
    pub(crate) metric: String,
    pub(crate) separation: SeparationReport,
    pub(crate) sampler: &'static str,
    pub(crate) sample_size: String,
    pub(crate) seed: u64,
    pub(crate) skip_trivial: bool,
    pub(crate) epsilon_s: f64,
}

impl SettingsSummary {
    /// The settings of a result found under `metric` (its name) at `gamma` with `separation`,
    /// sampled by `sampler`, P2 measured within `epsilon_s`.
    pub(crate) fn new(metric: String, gamma: f64, separation: Separation, sampler: &Sampler, epsilon_s: f64) -> Self {
        Self {
            gamma,
            metric,
            separation: separation.into(),
            sampler: sampler.kind.name(),
            sample_size: size_text(sampler.size),
            seed: sampler.seed,
            skip_trivial: sampler.skip_trivial,
            epsilon_s,
        }
    }
}

/// A sample size as the summaries and progress lines say it: `budget 1000`, `rate 0.5`.
pub(crate) fn size_text(size: SampleSize) -> String {
    match size {
        SampleSize::Budget(b) => format!("budget {b}"),
        SampleSize::Rate(r) => format!("rate {r}"),
    }
}

/// The warnings of a result and of its sampling, as sentences.
pub(crate) fn warnings(loops: &Loops, samples: &Samples) -> Vec<String> {
    loops.warnings().iter().map(ToString::to_string).chain(samples.warnings().iter().map(ToString::to_string)).collect()
}

/// What `loops run` knows after one log: summary.json of its folder.
#[derive(Debug, Serialize)]
pub(crate) struct LogSummary {
    pub(crate) name: String,
    pub(crate) source: String,
    pub(crate) poses: usize,
    pub(crate) t0_s: f64,
    pub(crate) span_s: f64,
    #[serde(flatten)]
    pub(crate) settings: SettingsSummary,
    pub(crate) components: usize,
    pub(crate) nontrivial_components: usize,
    pub(crate) holes: u64,
    /// Cells of S_γ in the full plane ((i, j) and (j, i) both).
    pub(crate) pair_count: u64,
    /// Pose pairs {i, j}, i < j: the count the pages print.
    pub(crate) pose_pair_count: u64,
    pub(crate) loop_area_s2: f64,
    pub(crate) loop_density_s: f64,
    pub(crate) samples: usize,
    pub(crate) quality: QualitySummary,
    pub(crate) comparison: Vec<QualitySummary>,
    pub(crate) seconds: Seconds,
    pub(crate) warnings: Vec<String>,
    pub(crate) files: Vec<&'static str>,
}

/// Where a log's time went, seconds.
#[derive(Debug, Default, Serialize)]
pub(crate) struct Seconds {
    pub(crate) read: f64,
    pub(crate) find_loops: f64,
    pub(crate) sample: f64,
    pub(crate) write: f64,
    pub(crate) total: f64,
}

/// One line of the batch summary.
#[derive(Debug, Serialize)]
pub(crate) struct LogOutcome {
    pub(crate) name: String,
    pub(crate) source: String,
    pub(crate) ok: bool,
    pub(crate) error: Option<String>,
    pub(crate) summary: Option<LogSummary>,
}

/// summary.json of the batch, at the top of --out.
#[derive(Debug, Serialize)]
pub(crate) struct BatchSummary<'a> {
    pub(crate) out: String,
    #[serde(flatten)]
    pub(crate) settings: SettingsSummary,
    pub(crate) logs: usize,
    pub(crate) succeeded: usize,
    pub(crate) failed: usize,
    pub(crate) seconds: f64,
    pub(crate) results: &'a [LogOutcome],
}
