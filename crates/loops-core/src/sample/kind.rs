//! Which sampler, how many samples, the seed: [`SamplerKind`] and [`Sampler`].

use std::fmt;
use std::str::FromStr;

use crate::baseline::{Baseline, BaselineParams};
use crate::draw::{SAMPLE_BYTES, SampleSize, SampleWarning, check_count, first_then_quotas, group_quotas};
use crate::error::{Error, Result};

/// Which sampler (paper, Sec. 5). Parsed from and printed as its name.
///
/// | name | sampler |
/// |---|---|
/// | `one` | σ_1 ∈ O(1): c samples per group, uniform within it |
/// | `rho` | σ_ρ ∈ O(ρ): r samples per group per trajectory point (row of the group), uniform within it |
/// | `rho-dispersed` | σ_ρ's counts, spread evenly along each group (stratified over its rows), each the row's closest pair (best score for detections) |
/// | `alpha` | σ_α ∈ O(α): uniform over all detections (or pairs of S_γ), no groups |
/// | `closest-first` | one sample per group first, its closest pair (best score for detections: the likeliest match); the rest as `rho-dispersed` |
/// | `closest-then-spread` | σ_ρ's counts (at least one per group), the first of each group its closest pair, the rest spread along the group as `rho-dispersed` |
/// | `nearest-then-uniform` | **the default**: each group's closest pair, then rows' closest pairs spread along the groups up to one row in six, the rest of the budget uniform over each group's pairs |
/// | `lio-sam`, `hdl-graph-slam`, `cartographer`, `time-gap` | baselines of deployed systems, see [`BaselineParams`] |
///
/// A *group* is a detection cluster ([`sample_clusters`](crate::sample_clusters)) or an exact loop component
/// ([`sample_loops`](crate::sample_loops)).
///
/// # Examples
/// ```
/// use loops_core::SamplerKind;
/// let kind: SamplerKind = "rho".parse()?;
/// assert_eq!(kind, SamplerKind::Rho);
/// assert_eq!(SamplerKind::LioSam.to_string(), "lio-sam");
/// let err = "sigma".parse::<SamplerKind>().unwrap_err();
/// assert!(err.to_string().contains("one, rho, rho-dispersed, alpha"));
/// # Ok::<(), loops_core::Error>(())
/// ```
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SamplerKind {
    /// σ_1: a constant number per group.
    One,
    /// σ_ρ: a constant number per group per trajectory point: it covers every component (P1)
    /// and samples large ones more (P3) without oversampling them (P2).
    Rho,
    /// σ_ρ spread along each group, preferring each row's closest pair.
    RhoDispersed,
    /// σ_α: uniform over detections (or over S_γ).
    Alpha,
    /// Every group first with its closest pair (the likeliest match; for detections the
    /// best-scored one), then the rest of the budget as [`RhoDispersed`](Self::RhoDispersed):
    /// in proportion to the rows, spread along each group, each the row's closest pair.
    ClosestFirst,
    /// σ_ρ's counts per group (at least one each when the budget allows, P1; in proportion to
    /// the rows beyond that, P2 and P3); the first of each group its closest pair (the
    /// likeliest match, the best-scored detection), the others the closest pairs of rows
    /// stratified along the group. At a budget near the number of groups it is closest-first;
    /// at large budgets it is the dispersed σ_ρ, whose counts give a small group no more than
    /// its share. A group's first sample counts towards its share: the rest of the budget goes
    /// where the share is still lacking. The default before `nearest-then-uniform`.
    ClosestThenSpread,
    /// The default ([`DEFAULT`](Self::DEFAULT)): rows' closest pairs first, then uniform
    /// picks. Each group's closest pair (P1), then the closest pairs of rows stratified along
    /// the groups in proportion to their rows (as LIO-SAM matches each keyframe with its
    /// nearest revisit), up to one row in six of each group; the budget beyond that uniform
    /// over each group's other pairs, in proportion to them (as the time-gap rule draws over
    /// all pairs: spread in time along both poses of a pair). On detection clusters, whose
    /// detections are a uniform draw already, it is
    /// [`ClosestThenSpread`](Self::ClosestThenSpread).
    #[default]
    NearestThenUniform,
    /// LIO-SAM: nearest keyframe within γ older than a time gap, searched at 1 Hz.
    LioSam,
    /// hdl_graph_slam: a keyframe within γ after a minimum travel, one per stretch of travel.
    HdlGraphSlam,
    /// Cartographer: a fixed random ratio of the pairs within γ.
    Cartographer,
    /// All pairs within γ beyond a time gap, randomly thinned.
    TimeGap,
}

impl SamplerKind {
    /// Every sampler, in the order of [`NAMES`](Self::NAMES).
    pub const ALL: [Self; 11] = [
        Self::One,
        Self::Rho,
        Self::RhoDispersed,
        Self::Alpha,
        Self::ClosestFirst,
        Self::ClosestThenSpread,
        Self::NearestThenUniform,
        Self::LioSam,
        Self::HdlGraphSlam,
        Self::Cartographer,
        Self::TimeGap,
    ];

    /// The sampler used when none is named: by the command line, Python, Dask, fleets and
    /// (its per-keyframe rule) the online sampler.
    pub const DEFAULT: Self = Self::NearestThenUniform;

    /// The accepted names.
    pub const NAMES: &'static str = "one, rho, rho-dispersed, alpha, closest-first, closest-then-spread, \
                                     nearest-then-uniform, lio-sam, hdl-graph-slam, cartographer, time-gap";

    /// The samplers that work on detection clusters.
    pub const CLUSTER_NAMES: &'static str =
        "one, rho, rho-dispersed, alpha, closest-first, closest-then-spread, nearest-then-uniform";

    /// The name, as parsed.
    pub fn name(self) -> &'static str {
        match self {
            Self::One => "one",
            Self::Rho => "rho",
            Self::RhoDispersed => "rho-dispersed",
            Self::Alpha => "alpha",
            Self::ClosestFirst => "closest-first",
            Self::ClosestThenSpread => "closest-then-spread",
            Self::NearestThenUniform => "nearest-then-uniform",
            Self::LioSam => "lio-sam",
            Self::HdlGraphSlam => "hdl-graph-slam",
            Self::Cartographer => "cartographer",
            Self::TimeGap => "time-gap",
        }
    }

    /// The symbol of the sampler in the paper (σ_1, σ_ρ, σ_α), or the name of the system whose
    /// rule a baseline follows: for figures and reports.
    ///
    /// # Examples
    /// ```
    /// use loops_core::SamplerKind;
    /// assert_eq!(SamplerKind::Rho.symbol(), "σ_ρ");
    /// assert_eq!(SamplerKind::LioSam.symbol(), "LIO-SAM");
    /// ```
    pub fn symbol(self) -> &'static str {
        match self {
            Self::One => "σ_1",
            Self::Rho => "σ_ρ",
            Self::RhoDispersed => "σ_ρ dispersed",
            Self::Alpha => "σ_α",
            Self::ClosestFirst => "closest-first σ_ρ",
            Self::ClosestThenSpread => "closest-then-spread σ_ρ",
            Self::NearestThenUniform => "nearest-then-uniform",
            Self::LioSam => "LIO-SAM",
            Self::HdlGraphSlam => "hdl_graph_slam",
            Self::Cartographer => "Cartographer",
            Self::TimeGap => "time gap",
        }
    }

    /// Whether the sampler takes a row's closest pair (the dispersed σ_ρ, closest-first,
    /// closest-then-spread, nearest-then-uniform) rather than a uniform one: what the online
    /// sampler's [`closest_in_row`](crate::online::OnlineSamplerOptions::closest_in_row) follows.
    pub fn picks_closest_in_row(self) -> bool {
        matches!(self, Self::RhoDispersed | Self::ClosestFirst | Self::ClosestThenSpread | Self::NearestThenUniform)
    }

    /// Whether this is a baseline of a deployed system (it needs the trajectory).
    pub fn is_baseline(self) -> bool {
        self.baseline(&BaselineParams::default()).is_some()
    }

    /// The baseline rule this sampler runs, with its parameters taken from `params`; `None` for
    /// σ_1, σ_ρ, the dispersed σ_ρ, σ_α and the closest-first, closest-then-spread and
    /// nearest-then-uniform samplers.
    pub fn baseline(self, params: &BaselineParams) -> Option<Baseline> {
        match self {
            Self::One
            | Self::Rho
            | Self::RhoDispersed
            | Self::Alpha
            | Self::ClosestFirst
            | Self::ClosestThenSpread
            | Self::NearestThenUniform => None,
            Self::LioSam => Some(Baseline::LioSam(params.lio_sam)),
            Self::HdlGraphSlam => Some(Baseline::HdlGraphSlam(params.hdl_graph_slam)),
            Self::Cartographer => Some(Baseline::Cartographer(params.cartographer)),
            Self::TimeGap => Some(Baseline::TimeGap(params.time_gap)),
        }
    }
}

impl fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SamplerKind {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name).ok_or_else(|| Error::UnknownName {
            kind: "sampler",
            name: name.to_owned(),
            expected: Self::NAMES,
        })
    }
}

impl SampleSize {
    /// Checks the size for a sampler of this kind.
    pub(crate) fn validate(self, kind: SamplerKind) -> Result<()> {
        match self {
            Self::Budget(0) => {
                Err(Error::InvalidParameter { name: "budget", value: 0.0, expected: "at least 1 sample" })
            }
            Self::Budget(_) => Ok(()),
            Self::Rate(rate) => {
                let (ok, expected) = match kind {
                    SamplerKind::One => (rate > 0.0, "a positive number of samples per group"),
                    SamplerKind::Rho
                    | SamplerKind::RhoDispersed
                    | SamplerKind::ClosestFirst
                    | SamplerKind::ClosestThenSpread
                    | SamplerKind::NearestThenUniform => {
                        (rate > 0.0, "a positive number of samples per group per trajectory point")
                    }
                    _ => (rate > 0.0 && rate <= 1.0, "a probability in (0, 1]"),
                };
                if ok && rate.is_finite() {
                    Ok(())
                } else {
                    Err(Error::InvalidParameter { name: "rate", value: rate, expected })
                }
            }
        }
    }
}

/// A sampler: which one, how many, the seed, and the parameters of the baselines.
///
/// Seeded with ChaCha8: the same sampler on the same input gives the same samples on every
/// machine and any number of threads.
#[derive(Debug, Clone, PartialEq)]
pub struct Sampler {
    /// Which sampler.
    pub kind: SamplerKind,
    /// How many samples.
    pub size: SampleSize,
    /// The seed.
    pub seed: u64,
    /// Parameters of the baselines (ignored by σ_1, σ_ρ, σ_α).
    pub baseline: BaselineParams,
    /// Leave out the trivial loop components ([`sample_loops`](crate::sample_loops) with σ_1, σ_ρ and σ_α). A
    /// trivial component holds the diagonal: its pairs are simple loops (the trajectory stayed
    /// within γ between t and t′, e.g. the next poses, or a stop), which odometry already ties
    /// together. σ_ρ on S_γ gives it a weight equal to all the rows of the drive, so it would
    /// otherwise take a large share of the budget (about a third on the default drive) for
    /// pairs a scan matcher does not need. Off by default: the paper's samplers cover all of
    /// S_γ.
    pub skip_trivial: bool,
}

impl Sampler {
    /// The seed used when none is given (command-line defaults).
    pub const DEFAULT_SEED: u64 = 0;

    /// A sampler with the default baseline parameters.
    pub fn new(kind: SamplerKind, size: SampleSize, seed: u64) -> Self {
        Self { kind, size, seed, baseline: BaselineParams::default(), skip_trivial: false }
    }

    /// Checks that its options apply to its kind, before any input is seen: front ends call it
    /// to refuse a bad combination up front; [`sample_loops`](crate::sample_loops) calls it too.
    ///
    /// # Errors
    /// [`Error::NotApplicable`] for [`Sampler::skip_trivial`] with a baseline, which keeps its
    /// own candidate rule.
    ///
    /// # Examples
    /// ```
    /// use loops_core::{SampleSize, Sampler, SamplerKind};
    /// let rho = Sampler { skip_trivial: true, ..Sampler::new(SamplerKind::Rho, SampleSize::Budget(10), 0) };
    /// assert!(rho.check_applicable().is_ok());
    /// let lio_sam = Sampler { kind: SamplerKind::LioSam, ..rho };
    /// assert!(lio_sam.check_applicable().is_err());
    /// ```
    pub fn check_applicable(&self) -> Result<()> {
        if self.skip_trivial && self.kind.is_baseline() {
            return Err(Error::NotApplicable {
                option: "skip_trivial",
                to: format!("the {} baseline", self.kind),
                reason: "a baseline keeps its own candidate rule (its time gap or travel); use one, rho, \
                         rho-dispersed, alpha, closest-first, closest-then-spread or nearest-then-uniform",
            });
        }
        Ok(())
    }

    /// Samples per group for the samplers of groups, from each group's rows (`rows`, used by
    /// all but σ_1, which weighs every group 1) and its number of candidates (`caps`): the
    /// closest-first sampler takes each group's closest pair first and shares the rest by rows
    /// ([`first_then_quotas`]), the others (closest-then-spread too: its first pick counts
    /// towards the group's share; nearest-then-uniform on detection clusters, where it is
    /// closest-then-spread) share by weight ([`group_quotas`]); `numbers` round the quotas
    /// ([`Numbers`](crate::draw::Numbers)).
    ///
    /// # Errors
    /// [`Error::TooManySamples`] when the quotas make more samples than one call returns.
    pub(crate) fn group_quotas(
        &self,
        rows: impl FnOnce() -> Vec<f64>,
        caps: &[u64],
        numbers: &crate::draw::Numbers,
        warnings: &mut Vec<SampleWarning>,
    ) -> Result<Vec<u64>> {
        let weights = match self.kind {
            SamplerKind::One => vec![1.0; caps.len()],
            _ => rows(),
        };
        let quotas = if self.kind == SamplerKind::ClosestFirst {
            first_then_quotas(&weights, caps, self.size, numbers, warnings)
        } else {
            group_quotas(&weights, caps, self.size, numbers, warnings)
        };
        check_count("samples", self.size, quotas.iter().sum::<u64>() as f64, SAMPLE_BYTES)?;
        Ok(quotas)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for kind in SamplerKind::ALL {
            assert_eq!(kind.name().parse::<SamplerKind>().unwrap(), kind);
        }
        let err = "sigma_rho".parse::<SamplerKind>().unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown sampler \"sigma_rho\": expected one of one, rho, rho-dispersed, alpha, closest-first, \
             closest-then-spread, nearest-then-uniform, lio-sam, hdl-graph-slam, cartographer, time-gap"
        );
    }
}
