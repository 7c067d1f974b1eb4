//! Samplers of inexact loops (paper, Sec. 5): σ_1 ∈ O(1), σ_ρ ∈ O(ρ) and σ_α ∈ O(α), a
//! dispersed σ_ρ, and the baselines of deployed SLAM systems, from detection clusters or
//! straight from the exact loop components of S_γ.

use std::collections::BTreeSet;
use std::fmt;
use std::str::FromStr;

use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::baseline::{BaselineParams, baseline_pairs};
use crate::cluster::DetectionClusters;
use crate::detection::{PairSpace, bernoulli_indices, choose_indices, nearest_pose};
use crate::error::{Error, Result};
use crate::loops::Loops;
use crate::metric::Metric;
use crate::trajectory::Trajectory;

/// Which sampler (paper, Sec. 5; DESIGN §4.5). Parsed from and printed as its name.
///
/// | name | sampler |
/// |---|---|
/// | `one` | σ_1 ∈ O(1): c samples per group, uniform within it |
/// | `rho` | σ_ρ ∈ O(ρ): r samples per group per trajectory point (row of the group), uniform within it |
/// | `rho-dispersed` | σ_ρ's counts, spread evenly along each group (stratified over its rows), each the row's closest pair (best score for detections) |
/// | `alpha` | σ_α ∈ O(α): uniform over all detections (or pairs of S_γ), no groups |
/// | `lio-sam`, `hdl-graph-slam`, `cartographer`, `time-gap` | baselines of deployed systems, see [`BaselineParams`] |
///
/// A *group* is a detection cluster ([`sample_clusters`]) or an exact loop component
/// ([`sample_loops`]).
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
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SamplerKind {
    /// σ_1: a constant number per group.
    One,
    /// σ_ρ: a constant number per group per trajectory point. The default: it covers every
    /// component (P1) and samples large ones more (P3) without oversampling them (P2).
    #[default]
    Rho,
    /// σ_ρ spread along each group, preferring each row's closest pair.
    RhoDispersed,
    /// σ_α: uniform over detections (or over S_γ).
    Alpha,
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
    pub const ALL: [Self; 8] = [
        Self::One,
        Self::Rho,
        Self::RhoDispersed,
        Self::Alpha,
        Self::LioSam,
        Self::HdlGraphSlam,
        Self::Cartographer,
        Self::TimeGap,
    ];

    /// The accepted names.
    pub const NAMES: &'static str = "one, rho, rho-dispersed, alpha, lio-sam, hdl-graph-slam, cartographer, time-gap";

    /// The samplers that work on detection clusters.
    pub const CLUSTER_NAMES: &'static str = "one, rho, rho-dispersed, alpha";

    /// The name, as parsed.
    pub fn name(self) -> &'static str {
        match self {
            Self::One => "one",
            Self::Rho => "rho",
            Self::RhoDispersed => "rho-dispersed",
            Self::Alpha => "alpha",
            Self::LioSam => "lio-sam",
            Self::HdlGraphSlam => "hdl-graph-slam",
            Self::Cartographer => "cartographer",
            Self::TimeGap => "time-gap",
        }
    }

    /// Whether this is a baseline of a deployed system (it needs the trajectory).
    pub fn is_baseline(self) -> bool {
        matches!(self, Self::LioSam | Self::HdlGraphSlam | Self::Cartographer | Self::TimeGap)
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

/// How many samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SampleSize {
    /// The sampler's own rate: c per group (σ_1), r per group per trajectory point (σ_ρ), the
    /// probability of keeping each detection or pair (σ_α, baselines; in (0, 1]). σ_1 and σ_ρ
    /// round c and r·rows randomly (keeping the expectation) and keep at least one per group.
    Rate(f64),
    /// Exactly this many samples (fewer only when fewer exist, with a warning). σ_1 and σ_ρ
    /// scale c or r to fit, keeping at least one per group whenever the budget allows it.
    Budget(usize),
}

impl SampleSize {
    /// The budget used when neither a rate nor a budget is given (command-line defaults): enough
    /// for at least one sample per component of a few hours of driving.
    pub const DEFAULT_BUDGET: usize = 1_000;

    /// The size from an optional rate or budget: at most one of them, and
    /// [`Budget`](Self::Budget)`(`[`DEFAULT_BUDGET`](Self::DEFAULT_BUDGET)`)` without either.
    ///
    /// # Errors
    /// [`Error::SampleSizeChoice`] for both.
    ///
    /// # Examples
    /// ```
    /// use loops_core::SampleSize;
    /// assert_eq!(SampleSize::or_default(None, None)?, SampleSize::Budget(SampleSize::DEFAULT_BUDGET));
    /// assert_eq!(SampleSize::or_default(Some(0.5), None)?, SampleSize::Rate(0.5));
    /// assert!(SampleSize::or_default(Some(0.5), Some(10)).is_err());
    /// # Ok::<(), loops_core::Error>(())
    /// ```
    pub fn or_default(rate: Option<f64>, budget: Option<usize>) -> Result<Self> {
        match (rate, budget) {
            (None, None) => Ok(Self::Budget(Self::DEFAULT_BUDGET)),
            _ => Self::from_rate_or_budget(rate, budget),
        }
    }

    /// The size from a rate or a budget, given as options (as a command line or keyword
    /// arguments have them): exactly one must be given.
    ///
    /// # Errors
    /// [`Error::SampleSizeChoice`] for both or neither.
    pub fn from_rate_or_budget(rate: Option<f64>, budget: Option<usize>) -> Result<Self> {
        match (rate, budget) {
            (Some(rate), None) => Ok(Self::Rate(rate)),
            (None, Some(budget)) => Ok(Self::Budget(budget)),
            _ => Err(Error::SampleSizeChoice { rate, budget }),
        }
    }

    fn validate(self, kind: SamplerKind) -> Result<()> {
        match self {
            Self::Budget(0) => {
                Err(Error::InvalidParameter { name: "budget", value: 0.0, expected: "at least 1 sample" })
            }
            Self::Budget(_) => Ok(()),
            Self::Rate(rate) => {
                let (ok, expected) = match kind {
                    SamplerKind::One => (rate > 0.0, "a positive number of samples per group"),
                    SamplerKind::Rho | SamplerKind::RhoDispersed => {
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
    /// Leave out the trivial loop components ([`sample_loops`] with σ_1, σ_ρ and σ_α). A
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
    /// to refuse a bad combination up front; [`sample_loops`] calls it too.
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
                         rho-dispersed or alpha",
            });
        }
        Ok(())
    }
}

/// One sampled loop: a candidate pair for the scan matcher.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Pose indices (i, j), i ≤ j, when known (always from [`sample_loops`]; from
    /// [`sample_clusters`] when the detections are placed on a trajectory).
    pub pair: Option<[usize; 2]>,
    /// The earlier time, seconds (the detection's own time for detections).
    pub t_s: f64,
    /// The later time, seconds.
    pub t_prime_s: f64,
    /// The exact loop component holding (i, j), when known.
    pub component: Option<usize>,
    /// The detection cluster it was drawn from (detections only).
    pub cluster: Option<usize>,
    /// The index of the detection (detections only).
    pub detection: Option<usize>,
    /// δ(x_i, x_j) in the metric's unit, when measured.
    pub distance: Option<f64>,
    /// The detection's score, when it has one.
    pub score: Option<f64>,
    /// The sampler that chose it.
    pub sampler: SamplerKind,
}

/// Something to know about a sample that is still valid.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SampleWarning {
    /// A budget smaller than the number of groups: some groups get no sample, so P1 cannot
    /// hold. Groups got one sample each, chosen with probability ∝ their weight.
    BudgetBelowGroups {
        /// The budget.
        budget: usize,
        /// The number of groups.
        groups: usize,
    },
    /// Fewer candidates than the budget: all of them were returned.
    BudgetAboveAvailable {
        /// The budget.
        budget: usize,
        /// The number of candidates.
        available: u64,
    },
}

impl fmt::Display for SampleWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BudgetBelowGroups { budget, groups } => write!(
                f,
                "budget {budget} is smaller than the {groups} groups: {} groups get no sample (P1 cannot hold)",
                groups - budget
            ),
            Self::BudgetAboveAvailable { budget, available } => {
                write!(f, "budget {budget} is more than the {available} candidates: all of them were returned")
            }
        }
    }
}

/// The samples a sampler chose, in order of (t, t′), with what it knew.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    sampler: SamplerKind,
    rows: Vec<Sample>,
    groups: usize,
    available: u64,
    poses: Option<usize>,
    warnings: Vec<SampleWarning>,
}

impl Samples {
    /// The samples, ordered by (t, t′).
    pub fn rows(&self) -> &[Sample] {
        &self.rows
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether there are none (a baseline may find nothing).
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The sampler.
    pub fn sampler(&self) -> SamplerKind {
        self.sampler
    }

    /// Number of groups sampled from (clusters or components with a pair to sample; 0 for σ_α
    /// and the baselines, which do not group).
    pub fn groups(&self) -> usize {
        self.groups
    }

    /// Number of candidates the sampler chose from (detections, pairs, or the rule's pairs).
    pub fn available(&self) -> u64 {
        self.available
    }

    /// Number of poses of the trajectory the pairs index, when known.
    pub fn poses(&self) -> Option<usize> {
        self.poses
    }

    /// Warnings (budget below the number of groups, or above the candidates).
    pub fn warnings(&self) -> &[SampleWarning] {
        &self.warnings
    }

    /// Fills in pose pairs (placing times on the nearest poses where missing) and the exact
    /// component of every sample. O(samples · log).
    ///
    /// # Errors
    /// [`Error::TrajectoryMismatch`] when the samples index another trajectory;
    /// [`Error::DetectionOutsideSpan`] for a time outside the loops' trajectory.
    pub fn locate(&mut self, loops: &Loops) -> Result<()> {
        let pairs = self.pairs_on(loops.timestamps_s())?;
        for (row, pair) in self.rows.iter_mut().zip(pairs) {
            row.pair = Some(pair);
            row.component = loops.component_of(pair[0], pair[1]);
        }
        self.poses = Some(loops.len());
        Ok(())
    }

    /// Fills in the distance δ(x_i, x_j) of every sample (placing times on the nearest poses
    /// where pairs are missing). O(samples) distances.
    ///
    /// # Errors
    /// As [`locate`](Self::locate), for `traj`; the metric's dimension error.
    pub fn measure<M: Metric + ?Sized>(&mut self, traj: &Trajectory, metric: &M) -> Result<()> {
        metric.check_dim(traj.dim())?;
        let pairs = self.pairs_on(traj.timestamps_s())?;
        for (row, pair) in self.rows.iter_mut().zip(pairs) {
            row.pair = Some(pair);
            row.distance = Some(metric.distance(traj.point(pair[0]), traj.point(pair[1])));
        }
        self.poses = Some(traj.len());
        Ok(())
    }

    /// The pose pair of every sample on a trajectory with these timestamps.
    pub(crate) fn pairs_on(&self, times: &[f64]) -> Result<Vec<[usize; 2]>> {
        if let Some(poses) = self.poses
            && poses != times.len()
        {
            return Err(Error::TrajectoryMismatch {
                what: "samples",
                index: poses.min(times.len()),
                poses,
                loops_poses: times.len(),
            });
        }
        self.rows
            .iter()
            .enumerate()
            .map(|(k, row)| match row.pair {
                Some(pair) => Ok(pair),
                None => Ok([nearest_pose(times, row.t_s, k)?, nearest_pose(times, row.t_prime_s, k)?]),
            })
            .collect()
    }

    fn new(sampler: SamplerKind, mut rows: Vec<Sample>, groups: usize, available: u64, poses: Option<usize>) -> Self {
        rows.sort_by(|a, b| {
            a.t_s.total_cmp(&b.t_s).then(a.t_prime_s.total_cmp(&b.t_prime_s)).then(a.detection.cmp(&b.detection))
        });
        Self { sampler, rows, groups, available, poses, warnings: Vec::new() }
    }
}

/// Samples detections, grouped by their ε-graph clusters (paper, Sec. 5.3–5.5): σ_1, σ_ρ, the
/// dispersed σ_ρ, or σ_α. "Trajectory points" of a cluster (σ_ρ) are its distinct times t.
///
/// Within a group, picks are uniform without replacement (σ_1, σ_ρ) or spread evenly over the
/// group's rows in time order (dispersed σ_ρ: the best-scored detection of a row, or its middle
/// one without scores). Groups are visited in parallel, each with its own ChaCha8 stream, and
/// detections are taken in (cluster, t, t′) order, so the result depends on neither the thread
/// count nor (without duplicates) the order of the detections. O(n log n).
///
/// # Errors
/// [`Error::UnknownName`] for a baseline (they need the trajectory: [`sample_loops`]);
/// [`Error::InvalidParameter`] for a budget of 0 or a rate out of range;
/// [`Error::NotApplicable`] for [`Sampler::skip_trivial`] (clusters do not know the trivial
/// components).
///
/// # Examples
/// ```
/// use loops_core::{Detections, SampleSize, Sampler, SamplerKind, cluster_detections, sample_clusters};
/// let det = Detections::new(vec![0.0, 1.0, 2.0, 500.0], vec![100.0, 100.0, 100.0, 900.0])?;
/// let clusters = cluster_detections(&det, 30.0)?;
/// let samples = sample_clusters(&clusters, &Sampler::new(SamplerKind::One, SampleSize::Budget(2), 0))?;
/// assert_eq!(samples.len(), 2);
/// assert_eq!(samples.rows()[1].detection, Some(3)); // one per cluster (P1)
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn sample_clusters(clusters: &DetectionClusters, sampler: &Sampler) -> Result<Samples> {
    let kind = sampler.kind;
    if kind.is_baseline() {
        return Err(Error::UnknownName {
            kind: "sampler of detection clusters",
            name: kind.name().to_owned(),
            expected: SamplerKind::CLUSTER_NAMES,
        });
    }
    if sampler.skip_trivial {
        return Err(Error::NotApplicable {
            option: "skip_trivial",
            to: "detection clusters".to_owned(),
            reason: "clusters do not know which loop components are trivial; sample the exact components, \
                     or leave out detections near t′ = t before clustering",
        });
    }
    sampler.size.validate(kind)?;
    let det = clusters.detections();
    let (xs, ys) = (det.t_s(), det.t_prime_s());
    let labels = clusters.labels();
    // Detections in (cluster, t, t′, index) order, and where each cluster starts.
    let mut order: Vec<u32> = (0..det.len() as u32).collect();
    order.par_sort_unstable_by(|&a, &b| {
        let (a, b) = (a as usize, b as usize);
        (labels[a], xs[a], ys[a], a).partial_cmp(&(labels[b], xs[b], ys[b], b)).unwrap_or(std::cmp::Ordering::Equal)
    });
    let mut offsets = vec![0usize; clusters.len() + 1];
    for &label in labels {
        offsets[label as usize + 1] += 1;
    }
    for g in 0..clusters.len() {
        offsets[g + 1] += offsets[g];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(sampler.seed);
    let mut warnings = Vec::new();
    let (chosen, groups): (Vec<u32>, usize) = if kind == SamplerKind::Alpha {
        let n = det.len() as u64;
        let positions = draw_numbers(n, sampler.size, &mut rng, &mut warnings);
        (positions.into_iter().map(|p| order[p as usize]).collect(), 0)
    } else {
        let members: Vec<&[u32]> = (0..clusters.len()).map(|g| &order[offsets[g]..offsets[g + 1]]).collect();
        let rows_of = |m: &[u32]| 1 + m.windows(2).filter(|w| xs[w[0] as usize] != xs[w[1] as usize]).count();
        let weights: Vec<f64> = match kind {
            SamplerKind::One => vec![1.0; members.len()],
            _ => members.par_iter().map(|m| rows_of(m) as f64).collect(),
        };
        let caps: Vec<u64> = members.iter().map(|m| m.len() as u64).collect();
        let quotas = group_quotas(&weights, &caps, sampler.size, &mut rng, &mut warnings);
        let scores = det.scores();
        let picks: Vec<Vec<u32>> = members
            .par_iter()
            .zip(&quotas)
            .enumerate()
            .map(|(g, (m, &q))| {
                let mut rng = group_rng(sampler.seed, g);
                if kind == SamplerKind::RhoDispersed {
                    disperse_detections(m, q, xs, scores, &mut rng)
                } else {
                    choose_indices(m.len() as u64, q, &mut rng).into_iter().map(|p| m[p as usize]).collect()
                }
            })
            .collect();
        (picks.concat(), clusters.len())
    };
    let pairs = det.pairs();
    let rows = chosen
        .iter()
        .map(|&k| {
            let k = k as usize;
            Sample {
                pair: pairs.map(|p| [p[k][0] as usize, p[k][1] as usize]),
                t_s: xs[k],
                t_prime_s: ys[k],
                component: None,
                cluster: Some(labels[k] as usize),
                detection: Some(k),
                distance: None,
                score: det.scores().map(|s| s[k]),
                sampler: kind,
            }
        })
        .collect();
    let mut samples = Samples::new(kind, rows, groups, det.len() as u64, det.poses());
    samples.warnings = warnings;
    Ok(samples)
}

/// Samples straight from the exact loop components of `loops` (beyond the paper: no detection
/// step, so no component can be missed by clustering), or runs a baseline rule on the
/// trajectory. A sample is a lattice pair (i, j), i < j, of S_γ (the diagonal is no loop); every
/// sample carries its component and its distance.
///
/// Groups are the components with at least one such pair; "trajectory points" of a component
/// (σ_ρ) are its rows i. Uniform picks within a component choose pair numbers over its runs
/// (runs weighted by length, then a column); the dispersed σ_ρ takes evenly spaced rows and the
/// closest pair of each (from the runs' closest columns; in a run on the diagonal, whose closest
/// pair is the pose itself, the closest column after the run's farthest point: a return along
/// the same way, or the run's last column). σ_α and the gap rules draw over the runs of all of
/// S_γ. With [`Sampler::skip_trivial`], σ_1, σ_ρ and σ_α leave out the trivial components.
/// Never a list of all pairs: memory O(runs + samples); time O(runs + samples · log runs),
/// plus the baselines' neighbour searches.
///
/// # Errors
/// [`Error::TrajectoryMismatch`] unless `loops` was found on `traj`; [`Error::InvalidParameter`]
/// for a budget of 0, a rate out of range or a bad baseline parameter; [`Error::NotApplicable`]
/// for `skip_trivial` with a baseline.
///
/// # Examples
/// ```
/// use loops_core::{Euclidean, SampleSize, Sampler, SamplerKind, UrbanDrive, find_loops, sample_loops};
/// let drive = UrbanDrive { duration_s: 900.0, ..UrbanDrive::default() }.generate()?;
/// let loops = find_loops(&drive.trajectory, &Euclidean, 40.0)?;
/// let sampler = Sampler::new(SamplerKind::Rho, SampleSize::Budget(200), 1);
/// let samples = sample_loops(&drive.trajectory, &Euclidean, &loops, &sampler)?;
/// assert_eq!(samples.len(), 200);
/// let groups = samples.groups();
/// let covered: std::collections::BTreeSet<_> = samples.rows().iter().map(|s| s.component).collect();
/// assert_eq!(covered.len(), groups); // at least one sample per component (P1)
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn sample_loops<M: Metric + ?Sized>(
    traj: &Trajectory,
    metric: &M,
    loops: &Loops,
    sampler: &Sampler,
) -> Result<Samples> {
    check_same_trajectory(traj, loops)?;
    metric.check_dim(traj.dim())?;
    let kind = sampler.kind;
    sampler.size.validate(kind)?;
    let mut rng = ChaCha8Rng::seed_from_u64(sampler.seed);
    let mut warnings = Vec::new();
    sampler.check_applicable()?;
    let components = loops.components();
    let wanted = |c: usize| !(sampler.skip_trivial && components[c].trivial);
    let (pairs, groups, available): (Vec<Picked>, usize, u64) = match kind {
        SamplerKind::Alpha => {
            // The off-diagonal pairs (j > i) of the wanted components.
            let mut space = PairSpace::default();
            for run in loops.runs().filter(|run| wanted(run.component)) {
                space.push(run.row, run.start, run.end, run.row + 1);
            }
            let numbers = draw_numbers(space.len(), sampler.size, &mut rng, &mut warnings);
            (space.pairs_at(&numbers).into_iter().map(|p| (p, None)).collect(), 0, space.len())
        }
        SamplerKind::One | SamplerKind::Rho | SamplerKind::RhoDispersed => {
            let mut spaces = vec![PairSpace::default(); loops.components().len()];
            for run in loops.runs().filter(|run| wanted(run.component)) {
                spaces[run.component].push(run.row, run.start, run.end, run.row + 1);
            }
            let ids: Vec<usize> = (0..spaces.len()).filter(|&c| spaces[c].len() > 0).collect();
            let spaces: Vec<PairSpace> = ids.iter().map(|&c| std::mem::take(&mut spaces[c])).collect();
            let rows_of = |s: &PairSpace| 1 + s.segments().windows(2).filter(|w| w[0].row != w[1].row).count();
            let weights: Vec<f64> = match kind {
                SamplerKind::One => vec![1.0; spaces.len()],
                _ => spaces.iter().map(|s| rows_of(s) as f64).collect(),
            };
            let caps: Vec<u64> = spaces.iter().map(PairSpace::len).collect();
            let quotas = group_quotas(&weights, &caps, sampler.size, &mut rng, &mut warnings);
            let picks: Vec<Vec<Picked>> = spaces
                .par_iter()
                .zip(&quotas)
                .zip(&ids)
                .map(|((space, &q), &c)| {
                    let mut rng = group_rng(sampler.seed, c);
                    let pairs = if kind == SamplerKind::RhoDispersed {
                        disperse_pairs(space, q, traj, metric, loops, &mut rng)
                    } else {
                        space.pairs_at(&space.choose(q, &mut rng))
                    };
                    pairs.into_iter().map(|p| (p, Some(c))).collect()
                })
                .collect();
            (picks.concat(), ids.len(), caps.iter().sum())
        }
        _ => {
            let (pairs, proposed, rule_warnings) =
                baseline_pairs(kind, traj, metric, loops, &sampler.baseline, sampler.size, &mut rng)?;
            warnings.extend(rule_warnings);
            (pairs.into_iter().map(|p| (p, None)).collect(), 0, proposed)
        }
    };
    let times = traj.timestamps_s();
    let rows = pairs
        .into_iter()
        .map(|([i, j], component)| {
            let (i, j) = (i as usize, j as usize);
            Sample {
                pair: Some([i, j]),
                t_s: times[i],
                t_prime_s: times[j],
                component: component.or_else(|| loops.component_of(i, j)),
                cluster: None,
                detection: None,
                distance: Some(metric.distance(traj.point(i), traj.point(j))),
                score: None,
                sampler: kind,
            }
        })
        .collect();
    let mut samples = Samples::new(kind, rows, groups, available, Some(traj.len()));
    samples.warnings = warnings;
    Ok(samples)
}

/// A pair (i, j) and its component, when the sampler knows it.
type Picked = ([u32; 2], Option<usize>);

/// Errors unless `loops` was found on a trajectory with the timestamps of `traj`.
pub(crate) fn check_same_trajectory(traj: &Trajectory, loops: &Loops) -> Result<()> {
    let (a, b) = (traj.timestamps_s(), loops.timestamps_s());
    let differ = a.iter().zip(b).position(|(x, y)| x != y);
    match differ {
        None if a.len() == b.len() => Ok(()),
        _ => Err(Error::TrajectoryMismatch {
            what: "trajectory",
            index: differ.unwrap_or(a.len().min(b.len())),
            poses: a.len(),
            loops_poses: b.len(),
        }),
    }
}

/// The ChaCha8 stream of group `g` (stream 0 is the sampler's own).
fn group_rng(seed: u64, g: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(1 + g as u64);
    rng
}

/// Numbers of the items kept out of `len` (σ_α): each with probability p, or exactly `budget`.
fn draw_numbers<R: Rng + ?Sized>(
    len: u64,
    size: SampleSize,
    rng: &mut R,
    warnings: &mut Vec<SampleWarning>,
) -> Vec<u64> {
    match size {
        SampleSize::Rate(rate) => bernoulli_indices(len, rate, rng),
        SampleSize::Budget(budget) => {
            if budget as u64 > len {
                warnings.push(SampleWarning::BudgetAboveAvailable { budget, available: len });
            }
            choose_indices(len, (budget as u64).min(len), rng)
        }
    }
}

/// Samples per group for σ_1 (`weights` all 1) and σ_ρ (`weights` = rows): quotas
/// `q_g = clamp(s · w_g, lo, cap_g)`, rounded at random to integers with the same expectation.
///
/// Rate mode: s is the rate, lo = 1, each group rounded independently. Budget mode: s solves
/// Σ q_g = B exactly (a sweep over the breakpoints of the piecewise linear sum), lo = 1 when
/// B ≥ #groups (P1), else 0 with a warning; then systematic sampling of the fractional parts
/// gives integers summing to exactly B (all caps when B exceeds them, with a warning).
pub(crate) fn group_quotas<R: Rng + ?Sized>(
    weights: &[f64],
    caps: &[u64],
    size: SampleSize,
    rng: &mut R,
    warnings: &mut Vec<SampleWarning>,
) -> Vec<u64> {
    let groups = weights.len();
    match size {
        SampleSize::Rate(rate) => weights
            .iter()
            .zip(caps)
            .map(|(&w, &cap)| {
                let q = (rate * w).clamp(1.0, cap as f64);
                let floor = q.floor();
                let up = rng.random::<f64>() < q - floor;
                (floor as u64 + u64::from(up)).min(cap)
            })
            .collect(),
        SampleSize::Budget(budget) => {
            let available: u64 = caps.iter().sum();
            if budget as u64 >= available {
                if budget as u64 > available {
                    warnings.push(SampleWarning::BudgetAboveAvailable { budget, available });
                }
                return caps.to_vec();
            }
            let lo = if budget >= groups {
                1.0
            } else {
                warnings.push(SampleWarning::BudgetBelowGroups { budget, groups });
                0.0
            };
            let scale = solve_scale(weights, caps, lo, budget as f64);
            let quotas: Vec<f64> =
                weights.iter().zip(caps).map(|(&w, &cap)| (scale * w).clamp(lo, cap as f64)).collect();
            round_to_total(&quotas, caps, budget as u64, rng)
        }
    }
}

/// The s ≥ 0 with Σ clamp(s · w_g, lo, cap_g) = total, for lo · #groups ≤ total < Σ cap.
fn solve_scale(weights: &[f64], caps: &[u64], lo: f64, total: f64) -> f64 {
    // F(s) = constant + slope · s between breakpoints: a group enters the linear part at lo / w
    // and leaves it (saturated) at cap / w.
    let mut events: Vec<(f64, bool, usize)> = Vec::with_capacity(2 * weights.len());
    for (g, (&w, &cap)) in weights.iter().zip(caps).enumerate() {
        events.push((lo / w, true, g));
        events.push((cap as f64 / w, false, g));
    }
    events.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
    let (mut constant, mut slope) = (lo * weights.len() as f64, 0.0);
    let mut last = 0.0;
    for (s, enter, g) in events {
        let value = constant + slope * s;
        if value >= total {
            // F is continuous and non-decreasing: the crossing is in [last, s].
            return if slope > 0.0 { ((total - constant) / slope).clamp(last, s) } else { last };
        }
        if enter {
            constant -= lo;
            slope += weights[g];
        } else {
            constant += caps[g] as f64;
            slope -= weights[g];
        }
        last = s;
    }
    last
}

/// Integers k_g ∈ [⌊q_g⌋, ⌈q_g⌉] ∩ [0, cap_g] with Σ k_g = total, k_g = ⌈q_g⌉ with probability
/// about the fractional part (systematic sampling); Σ q_g ≈ total.
fn round_to_total<R: Rng + ?Sized>(quotas: &[f64], caps: &[u64], total: u64, rng: &mut R) -> Vec<u64> {
    let mut counts: Vec<u64> = quotas.iter().zip(caps).map(|(&q, &cap)| (q.floor() as u64).min(cap)).collect();
    let assigned: u64 = counts.iter().sum();
    let mut deficit = total.saturating_sub(assigned);
    let fractions: Vec<f64> =
        quotas.iter().zip(&counts).zip(caps).map(|((&q, &k), &cap)| if k < cap { q - k as f64 } else { 0.0 }).collect();
    let sum: f64 = fractions.iter().sum();
    if deficit > 0 && sum > 0.0 {
        let step = sum / deficit as f64;
        let mut point = rng.random::<f64>() * step;
        let mut start = 0.0;
        for (g, &fraction) in fractions.iter().enumerate() {
            let end = start + fraction;
            let mut hit = false;
            while point < end && deficit > 0 {
                hit = true;
                point += step;
            }
            if hit {
                counts[g] += 1;
                deficit -= 1;
            }
            start = end;
        }
    }
    // Rounding left something over: the largest remaining fractions, then any room left.
    if deficit > 0 {
        let mut open: Vec<usize> = (0..counts.len()).filter(|&g| counts[g] < caps[g]).collect();
        open.sort_by(|&a, &b| {
            (quotas[b] - counts[b] as f64).total_cmp(&(quotas[a] - counts[a] as f64)).then(a.cmp(&b))
        });
        for g in open.into_iter().cycle().take(4 * counts.len() + deficit as usize) {
            if deficit == 0 {
                break;
            }
            if counts[g] < caps[g] {
                counts[g] += 1;
                deficit -= 1;
            }
        }
    }
    debug_assert_eq!(counts.iter().sum::<u64>(), total);
    counts
}

/// Evenly spaced picks along a cluster: `q` positions stratified over its rows (distinct t,
/// time order), each the best-scored detection of its row (the middle one without scores);
/// beyond one per row, the rest evenly over the remaining detections.
fn disperse_detections<R: Rng + ?Sized>(
    members: &[u32],
    q: u64,
    xs: &[f64],
    scores: Option<&[f64]>,
    rng: &mut R,
) -> Vec<u32> {
    let mut rows = vec![0usize];
    rows.extend((1..members.len()).filter(|&p| xs[members[p] as usize] != xs[members[p - 1] as usize]));
    rows.push(members.len());
    let row_count = rows.len() - 1;
    let preferred = |r: usize| -> usize {
        let (a, b) = (rows[r], rows[r + 1]);
        match scores {
            Some(s) => {
                (a..b).fold(a, |best, p| if s[members[p] as usize] > s[members[best] as usize] { p } else { best })
            }
            None => a + (b - a - 1) / 2,
        }
    };
    let positions = spread(row_count, members.len(), q, preferred, rng);
    positions.into_iter().map(|p| members[p as usize]).collect()
}

/// `q` of `total` items: stratified over `rows` rows (the `preferred` item of each picked row),
/// and beyond one per row, the rest evenly spaced over the items not yet picked.
fn spread<R: Rng + ?Sized>(
    rows: usize,
    total: usize,
    q: u64,
    preferred: impl Fn(usize) -> usize,
    rng: &mut R,
) -> Vec<u64> {
    let q = q as usize;
    let offset = rng.random::<f64>();
    if q <= rows {
        return (0..q)
            .map(|k| {
                let r = (((k as f64 + offset) * rows as f64 / q as f64) as usize).min(rows - 1);
                preferred(r) as u64
            })
            .collect();
    }
    let mut chosen: BTreeSet<u64> = (0..rows).map(|r| preferred(r) as u64).collect();
    let extra = q - rows;
    for k in 0..extra {
        let mut p = (((k as f64 + offset) * total as f64 / extra as f64) as usize).min(total - 1) as u64;
        while chosen.contains(&p) {
            p = (p + 1) % total as u64;
        }
        chosen.insert(p);
    }
    chosen.into_iter().collect()
}

/// In a run on the diagonal (whose closest pair is the pose itself): the closest column after
/// the run's farthest point from x_i, i.e. where the path comes back along the same way (the
/// last column when it never does).
fn return_column<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, i: usize, start: u32, end: u32) -> u32 {
    let x = traj.point(i);
    let distances: Vec<f64> = (start..=end).map(|j| metric.distance(x, traj.point(j as usize))).collect();
    let farthest = distances.iter().enumerate().fold(0, |best, (k, &d)| if d > distances[best] { k } else { best });
    let back = distances[farthest..]
        .iter()
        .enumerate()
        .fold(farthest, |best, (k, &d)| if d < distances[best] { farthest + k } else { best });
    start + back as u32
}

/// The dispersed σ_ρ on one exact component: rows evenly spaced, each its closest pair.
fn disperse_pairs<M: Metric + ?Sized, R: Rng + ?Sized>(
    space: &PairSpace,
    q: u64,
    traj: &Trajectory,
    metric: &M,
    loops: &Loops,
    rng: &mut R,
) -> Vec<[u32; 2]> {
    let segments = space.segments();
    let mut rows = vec![0usize];
    rows.extend((1..segments.len()).filter(|&s| segments[s].row != segments[s - 1].row));
    rows.push(segments.len());
    let set = loops.sublevel_set();
    let closest = set.closest_columns();
    // The closest pair of a row of the component, as its number in `space`.
    let mut numbers = Vec::with_capacity(segments.len() + 1);
    numbers.push(0u64);
    for segment in segments {
        numbers.push(numbers[numbers.len() - 1] + (segment.end - segment.start) as u64 + 1);
    }
    let preferred = |r: usize| -> usize {
        let mut best: Option<(f64, usize, u64)> = None;
        for s in rows[r]..rows[r + 1] {
            let segment = segments[s];
            let i = segment.row as usize;
            let column = match set.run_index(i, segment.start as usize) {
                Some(run) if set.runs()[run].start as usize > i => closest[run],
                _ => return_column(traj, metric, i, segment.start, segment.end),
            };
            let d = metric.distance(traj.point(i), traj.point(column as usize));
            let number = numbers[s] + (column - segment.start) as u64;
            if best.is_none_or(|(b, c, _)| (d, column as usize) < (b, c)) {
                best = Some((d, column as usize, number));
            }
        }
        best.map_or(numbers[rows[r]] as usize, |(_, _, number)| number as usize)
    };
    let total = space.len() as usize;
    let mut picked = spread(rows.len() - 1, total, q, preferred, rng);
    picked.sort_unstable();
    space.pairs_at(&picked)
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
            "unknown sampler \"sigma_rho\": expected one of one, rho, rho-dispersed, alpha, lio-sam, hdl-graph-slam, cartographer, time-gap"
        );
    }

    #[test]
    fn budget_quotas_sum_exactly_and_cover() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let weights: Vec<f64> = (1..=50).map(|k| (k * k) as f64).collect();
        let caps: Vec<u64> = (1..=50).map(|k| 3 * k as u64).collect();
        for budget in [50, 51, 77, 400, 1000, 3824] {
            let mut warnings = Vec::new();
            let q = group_quotas(&weights, &caps, SampleSize::Budget(budget), &mut rng, &mut warnings);
            assert_eq!(q.iter().sum::<u64>(), budget as u64);
            assert!(q.iter().zip(&caps).all(|(&k, &cap)| k >= 1 && k <= cap), "{q:?}");
            assert!(warnings.is_empty());
        }
        let mut warnings = Vec::new();
        let q = group_quotas(&weights, &caps, SampleSize::Budget(20), &mut rng, &mut warnings);
        assert_eq!(q.iter().sum::<u64>(), 20);
        assert!(matches!(warnings[..], [SampleWarning::BudgetBelowGroups { budget: 20, groups: 50 }]));
        let mut warnings = Vec::new();
        let q = group_quotas(&weights, &caps, SampleSize::Budget(5000), &mut rng, &mut warnings);
        assert_eq!(q, caps);
        assert!(matches!(warnings[..], [SampleWarning::BudgetAboveAvailable { budget: 5000, available: 3825 }]));
    }

    #[test]
    fn quotas_follow_weights() {
        // Uncapped: proportional to the weights; randomised rounding keeps the expectation.
        let weights = [1.0, 2.0, 3.5];
        let caps = [1000, 1000, 1000];
        let mut mean = [0.0; 3];
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        for _ in 0..2000 {
            let q = group_quotas(&weights, &caps, SampleSize::Budget(13), &mut rng, &mut Vec::new());
            assert_eq!(q.iter().sum::<u64>(), 13);
            for g in 0..3 {
                mean[g] += q[g] as f64 / 2000.0;
            }
        }
        for (g, expected) in [2.0, 4.0, 7.0].iter().enumerate() {
            assert!((mean[g] - expected).abs() < 0.05, "{mean:?}");
        }
        // Rate mode: at least one, rounded at random.
        let q = group_quotas(&[0.1, 10.0], &[5, 5], SampleSize::Rate(0.5), &mut rng, &mut Vec::new());
        assert_eq!(q, [1, 5]);
    }

    #[test]
    fn spread_is_even() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let picks = spread(100, 100, 10, |r| r, &mut rng);
        assert_eq!(picks.len(), 10);
        assert!(picks.windows(2).all(|w| w[1] - w[0] == 10), "{picks:?}");
        let picks = spread(3, 10, 6, |r| 3 * r, &mut rng);
        assert_eq!(picks.len(), 6);
        assert!([0, 3, 6].iter().all(|p| picks.contains(p)));
    }
}
