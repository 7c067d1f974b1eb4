//! Sampling the exact loop components of S_γ, or running a baseline rule on the trajectory.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::keyed::{DrawRun, DrawStats, KeyLayout, KeyedDraw, RunHolder, draw_candidates};
use super::{Sample, Sampler, Samples};
use crate::baseline::baseline_pairs;
use crate::error::Result;
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
/// of the budget as the dispersed σ_ρ does; closest-then-spread takes σ_ρ's counts, each
/// component's first pick its closest pair and the others as the dispersed σ_ρ. σ_α and the gap rules draw over the runs of all of
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
/// [`Error::Interrupted`](crate::Error::Interrupted) when an [`Interrupt`](crate::Interrupt) installed on this thread is interrupted.
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
    sample_loops_where(traj, metric, loops, sampler, &|_| true, KeyLayout::default())
}

/// [`sample_loops`] over the components `keep` accepts only (a fleet's components between
/// sessions), pairs keyed by `keys` (a fleet's by session); the baselines ignore both.
pub(crate) fn sample_loops_where<M: Metric + ?Sized>(
    traj: &Trajectory,
    metric: &M,
    loops: &Loops,
    sampler: &Sampler,
    keep: &(dyn Fn(usize) -> bool + Sync),
    keys: KeyLayout,
) -> Result<Samples> {
    loops.check_trajectory(traj)?;
    check_fits(metric, traj)?;
    metric.check_dim(traj.dim())?;
    let kind = sampler.kind;
    sampler.size.validate(kind)?;
    let mut rng = ChaCha8Rng::seed_from_u64(sampler.seed);
    let mut warnings = Vec::new();
    sampler.check_applicable()?;
    let wanted = |c: usize| keep(c);
    let (pairs, groups, available): (Vec<Picked>, usize, u64) = match (kind, kind.baseline(&sampler.baseline)) {
        (_, Some(baseline)) => {
            let (pairs, proposed, rule_warnings) =
                baseline_pairs(&baseline, traj, metric, loops, sampler.size, &mut rng)?;
            warnings.extend(rule_warnings);
            (pairs.into_iter().map(|p| (p, None)).collect(), 0, proposed)
        }
        (_, None) => {
            let stats = draw_stats(loops);
            let mut draw = KeyedDraw::with_keys(sampler, &stats, &wanted, keys)?;
            let holder = LoopsHolder { traj, metric, loops };
            while let Some(request) = draw.request().cloned() {
                draw.absorb(draw_candidates(&holder, &request)?);
                draw.complete();
            }
            warnings.extend(draw.warnings().iter().cloned());
            let picks = draw.picks().unwrap_or_default();
            let pairs = picks.iter().map(|p| ([p.pair[0] as u32, p.pair[1] as u32], Some(p.component)));
            (try_collect(pairs, "the samples")?, draw.groups(), draw.available())
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
            relative_pose: crate::relative_pose(traj, i, j),
            positions: None,
            sampler: kind,
        }
    });
    let mut samples = Samples::new(kind, try_collect(rows, "the samples")?, groups, available, Some(traj.len()));
    samples.warnings = warnings;
    Ok(samples)
}

/// A pair (i, j) and its component, when the sampler knows it.
type Picked = ([u32; 2], Option<usize>);

/// The keyed draws' statistics of every component of `loops` (by id), from its runs: the first
/// and last row, the pairs off the diagonal, the closest pair. O(runs).
///
/// # Examples
/// ```
/// use loops_core::sample::draw_stats;
/// use loops_core::{Euclidean, Trajectory, find_loops};
/// let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[0.0], [5.0], [0.0]])?;
/// let loops = find_loops(&traj, &Euclidean, 1.0)?;
/// let stats = draw_stats(&loops);
/// let pairs: Vec<u64> = stats.iter().map(|s| s.pairs).collect();
/// assert_eq!(pairs.iter().sum::<u64>(), 1); // (0, 2) is the one pair off the diagonal
/// # Ok::<(), loops_core::Error>(())
/// ```
pub fn draw_stats(loops: &Loops) -> Vec<DrawStats> {
    let mut stats: Vec<DrawStats> = loops
        .components()
        .iter()
        .map(|c| DrawStats { trivial: c.trivial, rows: [usize::MAX, 0], pairs: 0, closest_pair: c.closest_pair })
        .collect();
    for run in loops.runs() {
        let s = &mut stats[run.component];
        s.rows = [s.rows[0].min(run.row), s.rows[1].max(run.row)];
        let first = run.start.max(run.row + 1);
        if first <= run.end {
            s.pairs += (run.end - first + 1) as u64;
        }
    }
    stats
}

/// The runs of loops in memory, for a keyed draw.
struct LoopsHolder<'a, M: Metric + ?Sized> {
    traj: &'a Trajectory,
    metric: &'a M,
    loops: &'a Loops,
}

impl<M: Metric + ?Sized> RunHolder for LoopsHolder<'_, M> {
    fn rows(&self) -> Vec<std::ops::Range<usize>> {
        std::iter::once(0..self.loops.len()).collect()
    }

    fn for_each_run(&self, i: usize, f: &mut dyn FnMut(DrawRun)) {
        let set = self.loops.sublevel_set();
        let offset = set.row_offset(i);
        let labels = self.loops.run_components();
        for (k, run) in set.row(i).iter().enumerate() {
            f(DrawRun {
                start: run.start as usize,
                end: run.end as usize,
                component: labels[offset + k] as usize,
                closest: set.closest_columns()[offset + k] as usize,
            });
        }
    }

    fn measure(&self, i: usize, j: usize) -> (f64, f64) {
        let (x, y) = (self.traj.point(i), self.traj.point(j));
        (self.metric.distance(x, y), self.metric.distance_rank(x, y))
    }

    fn times_s(&self, i: usize, j: usize) -> [f64; 2] {
        let t = self.traj.timestamps_s();
        [t[i], t[j]]
    }

    fn diagonal_end(&self, _i: usize, end: usize) -> usize {
        end
    }

    fn continues_diagonal(&self, _i: usize, _start: usize) -> bool {
        false
    }
}

/// The groups' picks in one buffer, allocated fallibly.
pub(super) fn concat<T: Clone>(parts: Vec<Vec<T>>) -> Result<Vec<T>> {
    let mut all = try_with_capacity(parts.iter().map(Vec::len).sum(), "the samples")?;
    for part in parts {
        all.extend(part);
    }
    Ok(all)
}
