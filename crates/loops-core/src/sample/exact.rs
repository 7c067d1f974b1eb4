//! Sampling the exact loop components of S_γ, or running a baseline rule on the trajectory.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::disperse::disperse_pairs;
use super::{Sample, Sampler, SamplerKind, Samples, group_rng};
use crate::baseline::baseline_pairs;
use crate::draw::{PairSpace, SAMPLE_BYTES, check_count, check_every, draw_numbers, first_then_quotas, group_quotas};
use crate::error::Result;
use crate::interrupt::Interrupt;
use crate::loops::Loops;
use crate::memory::{try_collect, try_with_capacity};
use crate::metric::Metric;
use crate::spec::{MetricSpec, check_fits, with_metric};
use crate::trajectory::Trajectory;

impl MetricSpec {
    /// [`sample_loops`] under this metric.
    ///
    /// # Errors
    /// As [`sample_loops`].
    pub fn sample_loops(&self, traj: &Trajectory, loops: &Loops, sampler: &Sampler) -> Result<Samples> {
        with_metric!(self, m => sample_loops(traj, m, loops, sampler))
    }
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
/// the same way, or the run's last column). The closest-first sampler takes each component's
/// closest pair (the closest of those row pairs) first, one per component, and shares the rest
/// of the budget as the dispersed σ_ρ does. σ_α and the gap rules draw over the runs of all of
/// S_γ. With [`Sampler::skip_trivial`], the samplers other than the baselines leave out the
/// trivial components.
/// Never a list of all pairs: memory O(runs + samples); time O(runs + samples · log runs),
/// plus the baselines' neighbour searches.
///
/// # Errors
/// [`Error::TrajectoryMismatch`](crate::Error::TrajectoryMismatch) unless `loops` was found on `traj`; [`Error::InvalidParameter`](crate::Error::InvalidParameter)
/// for a budget of 0, a rate out of range or a bad baseline parameter; [`Error::NotApplicable`](crate::Error::NotApplicable)
/// for `skip_trivial` with a baseline; [`Error::TooManySamples`](crate::Error::TooManySamples) for a size that makes more than
/// [`MAX_SAMPLES`](crate::MAX_SAMPLES) samples, before any is drawn; [`Error::OutOfMemory`](crate::Error::OutOfMemory);
/// [`Error::Interrupted`](crate::Error::Interrupted) when an [`Interrupt`] installed on this thread is interrupted.
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
    sample_loops_where(traj, metric, loops, sampler, &|_| true)
}

/// [`sample_loops`] over the components `keep` accepts only (a fleet's components between
/// sessions); the baselines ignore it.
pub(crate) fn sample_loops_where<M: Metric + ?Sized>(
    traj: &Trajectory,
    metric: &M,
    loops: &Loops,
    sampler: &Sampler,
    keep: &(dyn Fn(usize) -> bool + Sync),
) -> Result<Samples> {
    loops.check_trajectory(traj)?;
    check_fits(metric, traj)?;
    metric.check_dim(traj.dim())?;
    let kind = sampler.kind;
    sampler.size.validate(kind)?;
    let mut rng = ChaCha8Rng::seed_from_u64(sampler.seed);
    let mut warnings = Vec::new();
    sampler.check_applicable()?;
    let interrupt = Interrupt::current();
    let components = loops.components();
    let wanted = |c: usize| keep(c) && !(sampler.skip_trivial && components[c].trivial);
    let (pairs, groups, available): (Vec<Picked>, usize, u64) = match (kind, kind.baseline(&sampler.baseline)) {
        (_, Some(baseline)) => {
            let (pairs, proposed, rule_warnings) =
                baseline_pairs(&baseline, traj, metric, loops, sampler.size, &mut rng)?;
            warnings.extend(rule_warnings);
            (pairs.into_iter().map(|p| (p, None)).collect(), 0, proposed)
        }
        (SamplerKind::Alpha, None) => {
            // The off-diagonal pairs (j > i) of the wanted components.
            let mut space = PairSpace::default();
            for (k, run) in loops.runs().filter(|run| wanted(run.component)).enumerate() {
                check_every(&interrupt, k)?;
                space.push(run.row, run.start, run.end, run.row + 1)?;
            }
            let numbers = draw_numbers(space.len(), sampler.size, &mut rng, &mut warnings)?;
            let pairs = space.pairs_at(&numbers)?;
            (try_collect(pairs.into_iter().map(|p| (p, None)), "the samples")?, 0, space.len())
        }
        (_, None) => {
            let mut spaces = vec![PairSpace::default(); loops.components().len()];
            for (k, run) in loops.runs().filter(|run| wanted(run.component)).enumerate() {
                check_every(&interrupt, k)?;
                spaces[run.component].push(run.row, run.start, run.end, run.row + 1)?;
            }
            let ids: Vec<usize> = (0..spaces.len()).filter(|&c| spaces[c].len() > 0).collect();
            let spaces: Vec<PairSpace> = ids.iter().map(|&c| std::mem::take(&mut spaces[c])).collect();
            let rows_of = |s: &PairSpace| 1 + s.segments().windows(2).filter(|w| w[0].row != w[1].row).count();
            let weights: Vec<f64> = match kind {
                SamplerKind::One => vec![1.0; spaces.len()],
                _ => spaces.iter().map(|s| rows_of(s) as f64).collect(),
            };
            let caps: Vec<u64> = spaces.iter().map(PairSpace::len).collect();
            let quotas = if kind == SamplerKind::ClosestFirst {
                first_then_quotas(&weights, &caps, sampler.size, &mut rng, &mut warnings)
            } else {
                group_quotas(&weights, &caps, sampler.size, &mut rng, &mut warnings)
            };
            check_count("samples", sampler.size, quotas.iter().sum::<u64>() as f64, SAMPLE_BYTES)?;
            let picks: Vec<Vec<Picked>> = spaces
                .par_iter()
                .zip(&quotas)
                .zip(&ids)
                .map(|((space, &q), &c)| {
                    interrupt.check()?;
                    let mut rng = group_rng(sampler.seed, c);
                    let pairs = if matches!(kind, SamplerKind::RhoDispersed | SamplerKind::ClosestFirst) {
                        let first = kind == SamplerKind::ClosestFirst;
                        disperse_pairs(space, q, traj, metric, loops, first, &mut rng)?
                    } else {
                        space.pairs_at(&space.choose(q, &mut rng))?
                    };
                    try_collect(pairs.into_iter().map(|p| (p, Some(c))), "the samples")
                })
                .collect::<Result<_>>()?;
            (concat(picks)?, ids.len(), caps.iter().sum())
        }
    };
    let times = traj.timestamps_s();
    let rows = pairs.into_iter().map(|([i, j], component)| {
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
    });
    let mut samples = Samples::new(kind, try_collect(rows, "the samples")?, groups, available, Some(traj.len()));
    samples.warnings = warnings;
    Ok(samples)
}

/// A pair (i, j) and its component, when the sampler knows it.
type Picked = ([u32; 2], Option<usize>);

/// The groups' picks in one buffer, allocated fallibly.
pub(super) fn concat<T: Clone>(parts: Vec<Vec<T>>) -> Result<Vec<T>> {
    let mut all = try_with_capacity(parts.iter().map(Vec::len).sum(), "the samples")?;
    for part in parts {
        all.extend(part);
    }
    Ok(all)
}
