//! Loop-candidate rules of deployed SLAM systems, as samplers under the same
//! budget as σ_1, σ_ρ and σ_α, so that users can see which revisits they would miss.
//!
//! Each rule is run with perfect knowledge of the trajectory: its radius is γ (the threshold of
//! the loops), its distance test is the metric, and where the real system would keep the best
//! scan match of several candidates, the closest pair stands in for it.

use rand::Rng;

use crate::ball_tree::BallTree;
use crate::draw::{PairSpace, SampleSize, SampleWarning, draw_numbers};
use crate::error::{Error, Result};
use crate::interrupt::Interrupt;
use crate::loops::Loops;
use crate::metric::Metric;
use crate::trajectory::Trajectory;

/// LIO-SAM's loop-candidate rule: every `period_s` (1 s, `loopClosureFrequency`), the latest
/// keyframe (one per `keyframe_step` of motion, 1 m) is matched with its nearest keyframe within
/// γ that is older than `min_age_s` (30 s, `historyKeyframeSearchTimeDiff`); a keyframe is
/// searched once.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LioSam {
    /// Distance moved between keyframes, in the metric's unit (1 m).
    pub keyframe_step: f64,
    /// Seconds between loop searches (1 s: 1 Hz); positive.
    pub period_s: f64,
    /// A candidate keyframe is more than this many seconds older (30 s).
    pub min_age_s: f64,
}

impl Default for LioSam {
    fn default() -> Self {
        Self { keyframe_step: 1.0, period_s: 1.0, min_age_s: 30.0 }
    }
}

/// hdl_graph_slam's loop-candidate rule: at each keyframe (one per `keyframe_step`, 2 m,
/// `keyframe_delta_trans`), if it has travelled `edge_spacing` since the last loop edge
/// (`distance_from_last_edge_thresh`), the candidates are the keyframes within γ at least
/// `min_travel` of travel back (`accum_distance_thresh`); the closest one is kept, so there is at
/// most one loop per stretch of travel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HdlGraphSlam {
    /// Distance moved between keyframes, in the metric's unit (2 m).
    pub keyframe_step: f64,
    /// Least travel (path length) between the two keyframes of a loop; `None`: 2γ, so that no
    /// pair on one straight stretch qualifies.
    pub min_travel: Option<f64>,
    /// Least travel between two loop edges; `None`: γ.
    pub edge_spacing: Option<f64>,
}

impl Default for HdlGraphSlam {
    fn default() -> Self {
        Self { keyframe_step: 2.0, min_travel: None, edge_spacing: None }
    }
}

/// Cartographer's loop-candidate rule: every pair within γ, except those closer in time than
/// `min_gap_s` (the node's own submaps), kept at a fixed random ratio (`sampling_ratio`: the
/// sampler's rate).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cartographer {
    /// Pairs closer in time than this are within the node's own submaps (10 s).
    pub min_gap_s: f64,
}

impl Default for Cartographer {
    fn default() -> Self {
        Self { min_gap_s: 10.0 }
    }
}

/// The time-gap rule: every pair within γ and at least `gap_s` apart in time, randomly thinned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeGap {
    /// The least time between the two poses of a candidate (30 s).
    pub gap_s: f64,
}

impl Default for TimeGap {
    fn default() -> Self {
        Self { gap_s: 30.0 }
    }
}

/// One baseline rule with its parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Baseline {
    /// [`LioSam`].
    LioSam(LioSam),
    /// [`HdlGraphSlam`].
    HdlGraphSlam(HdlGraphSlam),
    /// [`Cartographer`].
    Cartographer(Cartographer),
    /// [`TimeGap`].
    TimeGap(TimeGap),
}

impl Baseline {
    /// Checks the parameters: finite, ≥ 0 (the LIO-SAM period > 0). The names in errors are
    /// those of the flat keyword arguments (`lio_sam_period_s`, ...).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first bad parameter.
    pub fn validate(&self) -> Result<()> {
        let checks: &[(&'static str, f64, bool)] = match self {
            Self::LioSam(p) => &[
                ("lio_sam_keyframe_step", p.keyframe_step, false),
                ("lio_sam_period_s", p.period_s, true),
                ("lio_sam_min_age_s", p.min_age_s, false),
            ],
            Self::HdlGraphSlam(p) => &[
                ("hdl_keyframe_step", p.keyframe_step, false),
                ("hdl_min_travel", p.min_travel.unwrap_or(0.0), false),
                ("hdl_edge_spacing", p.edge_spacing.unwrap_or(0.0), false),
            ],
            Self::Cartographer(p) => &[("cartographer_min_gap_s", p.min_gap_s, false)],
            Self::TimeGap(p) => &[("time_gap_s", p.gap_s, false)],
        };
        for &(name, value, positive) in checks {
            let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
            if !ok {
                let expected = if positive { "a positive finite number" } else { "a finite number >= 0" };
                return Err(Error::InvalidParameter { name, value, expected });
            }
        }
        Ok(())
    }
}

/// The parameters of every baseline rule, as a [`Sampler`](crate::Sampler) carries them (it
/// uses those of its kind). Distances are in the metric's unit (metres for positions); the
/// defaults are those of the systems' own configurations, with the search radius set to γ.
///
/// # Examples
/// ```
/// use loops_core::{BaselineParams, LioSam};
/// let params = BaselineParams { lio_sam: LioSam { min_age_s: 60.0, ..LioSam::default() }, ..BaselineParams::default() };
/// assert_eq!(params.lio_sam.period_s, 1.0);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BaselineParams {
    /// For the `lio-sam` sampler.
    pub lio_sam: LioSam,
    /// For the `hdl-graph-slam` sampler.
    pub hdl_graph_slam: HdlGraphSlam,
    /// For the `cartographer` sampler.
    pub cartographer: Cartographer,
    /// For the `time-gap` sampler.
    pub time_gap: TimeGap,
}

/// The pairs (i < j) a baseline rule proposes, thinned to `size`; the number of pairs the rule
/// proposed before thinning; warnings.
pub(crate) fn baseline_pairs<M: Metric + ?Sized, R: Rng + ?Sized>(
    baseline: &Baseline,
    traj: &Trajectory,
    metric: &M,
    loops: &Loops,
    size: SampleSize,
    rng: &mut R,
) -> Result<(Vec<[u32; 2]>, u64, Vec<SampleWarning>)> {
    baseline.validate()?;
    let gamma = loops.gamma();
    let mut warnings = Vec::new();
    let interrupt = Interrupt::current();
    let (space, rule) = match baseline {
        Baseline::Cartographer(p) => (PairSpace::of_loops(loops, p.min_gap_s, &interrupt)?, None),
        Baseline::TimeGap(p) => (PairSpace::of_loops(loops, p.gap_s, &interrupt)?, None),
        Baseline::LioSam(p) => (PairSpace::default(), Some(lio_sam(traj, metric, gamma, p))),
        Baseline::HdlGraphSlam(p) => (PairSpace::default(), Some(hdl_graph_slam(traj, metric, gamma, p))),
    };
    Ok(match rule {
        None => {
            let indices = draw_numbers(space.len(), size, rng, &mut warnings)?;
            (space.pairs_at(&indices)?, space.len(), warnings)
        }
        Some(rule) => {
            let indices = draw_numbers(rule.len() as u64, size, rng, &mut warnings)?;
            (indices.into_iter().map(|k| rule[k as usize]).collect(), rule.len() as u64, warnings)
        }
    })
}

/// Keyframes: the first pose, then every pose at least `step` from the previous keyframe.
fn keyframes<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, step: f64) -> Vec<usize> {
    let mut out = vec![0];
    for k in 1..traj.len() {
        let last = out[out.len() - 1];
        if metric.distance(traj.point(last), traj.point(k)) >= step {
            out.push(k);
        }
    }
    out
}

/// Nearest keyframe to pose `query` among poses `0..limit` within γ (ties to the earliest).
struct NearestKeyframe<'a, M: ?Sized> {
    traj: &'a Trajectory,
    metric: &'a M,
    tree: BallTree,
    is_keyframe: Vec<bool>,
    gamma: f64,
    reach: f64,
}

impl<'a, M: Metric + ?Sized> NearestKeyframe<'a, M> {
    fn new(traj: &'a Trajectory, metric: &'a M, keyframes: &[usize], gamma: f64) -> Self {
        let mut is_keyframe = vec![false; traj.len()];
        keyframes.iter().for_each(|&k| is_keyframe[k] = true);
        let largest = traj.coords().iter().fold(0.0_f64, |m, c| m.max(c.abs()));
        // The ball bounds are only used to prune; a margin for their rounding keeps them safe.
        let reach = gamma + 64.0 * f64::EPSILON * (gamma + largest + 1.0);
        // The baselines hold per-pose buffers of their own, allocated as usual: out of memory,
        // the hierarchy panics with the error rather than returning it.
        let tree = BallTree::new(traj, metric, 64).unwrap_or_else(|error| panic!("{error}"));
        Self { traj, metric, tree, is_keyframe, gamma, reach }
    }

    fn find(&self, query: usize, limit: usize) -> Option<usize> {
        let x = self.traj.point(query);
        let mut best: Option<(f64, usize)> = None;
        self.tree.for_each_near_leaf(self.metric, x, 0, self.reach, |lo, hi| {
            for j in lo..hi.min(limit) {
                if self.is_keyframe[j] {
                    let d = self.metric.distance(x, self.traj.point(j));
                    if d <= self.gamma && best.is_none_or(|(b, _)| d < b) {
                        best = Some((d, j));
                    }
                }
            }
        });
        best.map(|(_, j)| j)
    }
}

fn lio_sam<M: Metric + ?Sized>(traj: &Trajectory, metric: &M, gamma: f64, params: &LioSam) -> Vec<[u32; 2]> {
    let times = traj.timestamps_s();
    let keyframes = keyframes(traj, metric, params.keyframe_step);
    let search = NearestKeyframe::new(traj, metric, &keyframes, gamma);
    let mut out = Vec::new();
    let (start, end) = (times[0], times[times.len() - 1]);
    let period = params.period_s;
    let tick = |m: f64| start + m * period;
    // The search runs at ticks start + m · period (m ≥ 1) on the latest keyframe; a keyframe is
    // searched when a tick falls before the next keyframe (searching it again finds the same).
    // O(keyframes) whatever the period.
    for (p, &current) in keyframes.iter().enumerate() {
        let next = keyframes.get(p + 1).map_or(f64::INFINITY, |&k| times[k]);
        let mut m = ((times[current] - start) / period).ceil().max(1.0);
        while tick(m) < times[current] {
            m += 1.0;
        }
        while m > 1.0 && tick(m - 1.0) >= times[current] {
            m -= 1.0;
        }
        let now = tick(m);
        if now >= next || now > end {
            continue;
        }
        let limit = times.partition_point(|&t| times[current] - t > params.min_age_s);
        if let Some(j) = search.find(current, limit) {
            out.push([j as u32, current as u32]);
        }
    }
    out
}

fn hdl_graph_slam<M: Metric + ?Sized>(
    traj: &Trajectory,
    metric: &M,
    gamma: f64,
    params: &HdlGraphSlam,
) -> Vec<[u32; 2]> {
    let keyframes = keyframes(traj, metric, params.keyframe_step);
    let mut travel = Vec::with_capacity(keyframes.len());
    travel.push(0.0);
    for w in keyframes.windows(2) {
        travel.push(travel[travel.len() - 1] + metric.distance(traj.point(w[0]), traj.point(w[1])));
    }
    let min_travel = params.min_travel.unwrap_or(2.0 * gamma);
    let edge_spacing = params.edge_spacing.unwrap_or(gamma);
    let search = NearestKeyframe::new(traj, metric, &keyframes, gamma);
    let mut out = Vec::new();
    let mut last_edge = f64::NEG_INFINITY;
    for (p, &current) in keyframes.iter().enumerate() {
        if travel[p] - last_edge < edge_spacing {
            continue;
        }
        // Keyframes q with travel[p] − travel[q] ≥ min_travel come first (travel increases).
        let q = travel.partition_point(|&s| travel[p] - s >= min_travel);
        if q == 0 {
            continue;
        }
        let limit = keyframes.get(q).copied().unwrap_or(traj.len());
        if let Some(j) = search.find(current, limit) {
            out.push([j as u32, current as u32]);
            last_edge = travel[p];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::Euclidean;
    use crate::{find_loops, loops::Loops};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Out along x for 100 m at 1 m/s, a 20 m detour, and back along the same line.
    fn out_and_back() -> (Trajectory, Loops) {
        let mut points = Vec::new();
        for k in 0..=100 {
            points.push([k as f64, 0.0]);
        }
        for k in 1..=20 {
            points.push([100.0, k as f64]);
        }
        for k in (0..=100).rev() {
            points.push([k as f64, 20.0]);
        }
        let times = (0..points.len()).map(|k| k as f64).collect();
        let traj = Trajectory::from_points(times, &points).unwrap();
        let loops = find_loops(&traj, &Euclidean, 25.0).unwrap();
        (traj, loops)
    }

    /// `baseline`'s pairs (and proposed count, warnings) on `traj` under the Euclidean metric.
    fn pairs_of(
        baseline: &Baseline,
        traj: &Trajectory,
        loops: &Loops,
        size: SampleSize,
        rng: &mut ChaCha8Rng,
    ) -> (Vec<[u32; 2]>, u64, Vec<SampleWarning>) {
        baseline_pairs(baseline, traj, &Euclidean, loops, size, rng).unwrap()
    }

    #[test]
    fn lio_sam_matches_nearest_old_keyframe() {
        let (traj, loops) = out_and_back();
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let (pairs, _, warnings) =
            pairs_of(&Baseline::LioSam(LioSam::default()), &traj, &loops, SampleSize::Rate(1.0), &mut rng);
        assert!(warnings.is_empty());
        assert!(!pairs.is_empty());
        let times = traj.timestamps_s();
        for &[j, i] in &pairs {
            let (i, j) = (i as usize, j as usize);
            assert!(times[i] - times[j] > 30.0);
            assert!(loops.component_of(i, j).is_some());
        }
        // On the way back, pose (x, 20) is matched with (x, 0): the nearest old keyframe.
        assert!(pairs.contains(&[50, 171]), "{pairs:?}");
    }

    #[test]
    fn hdl_keeps_one_per_stretch() {
        let (traj, loops) = out_and_back();
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let (pairs, proposed, _) =
            pairs_of(&Baseline::HdlGraphSlam(HdlGraphSlam::default()), &traj, &loops, SampleSize::Rate(1.0), &mut rng);
        assert!(!pairs.is_empty());
        assert_eq!(proposed, pairs.len() as u64);
        // Consecutive edges are at least γ = 25 m of travel apart (1 m per pose here).
        for w in pairs.windows(2) {
            assert!(w[1][1] - w[0][1] >= 25, "{pairs:?}");
        }
        let budget = pairs_of(
            &Baseline::HdlGraphSlam(HdlGraphSlam::default()),
            &traj,
            &loops,
            SampleSize::Budget(1000),
            &mut rng,
        );
        assert_eq!(budget.0.len(), pairs.len());
        assert!(matches!(budget.2[..], [SampleWarning::BudgetAboveAvailable { budget: 1000, .. }]));
    }

    #[test]
    fn gap_rules_stay_beyond_the_gap() {
        let (traj, loops) = out_and_back();
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let (pairs, _, _) =
            pairs_of(&Baseline::TimeGap(TimeGap::default()), &traj, &loops, SampleSize::Budget(50), &mut rng);
        assert_eq!(pairs.len(), 50);
        assert!(pairs.iter().all(|&[i, j]| j - i >= 30 && loops.component_of(i as usize, j as usize).is_some()));
        let bad = Baseline::LioSam(LioSam { period_s: 0.0, ..LioSam::default() });
        assert!(baseline_pairs(&bad, &traj, &Euclidean, &loops, SampleSize::Rate(1.0), &mut rng).is_err());
    }
}
