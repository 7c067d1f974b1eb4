//! A robot that parks twice at one place: two or three stationary stretches whose poses are
//! nearly, but not exactly, the same point (10⁻¹⁴ m apart, γ/2, γ − 10⁻⁹, γ, just beyond γ),
//! joined by drives. Every row of one stop meets the other stop's many poses, all at one distance
//! (none at 0, which would end a closest-column search at once), and the path length within a
//! stop is 0, so the arc-length bounds jump over none of them.
//!
//! Exactness: the batch (with and without separation), the fleet engine (the stops in two
//! sessions, both prunings) and the online engine equal the brute force on every such case,
//! closest columns included, also with jitter within the stops. Cost: the distances measured and
//! the ranks taken per run stay bounded (counted by a metric, so the test is deterministic)
//! where they once grew with the length of the stops.

mod support;

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

use loops_core::{
    Euclidean, Metric, MetricSpec, Run, Separation, SublevelSet, Trajectory, find_loops,
    fleet::{Fleet, FleetOptions, Pruning, find_fleet_loops},
    online::OnlineLoops,
    path_length,
};
use support::check_against_dense;

/// Poses of a robot parked at `origin + (offset, 0)` for each offset, `stop_len` poses each
/// (jittered by up to `noise` on each axis), with a drive between two stops: out along y to 3γ
/// and back in steps of γ/7, so that some drive poses come within γ of the stops. 10 Hz.
fn stops(origin: [f64; 2], offsets: &[f64], stop_len: usize, gamma: f64, noise: f64, seed: u64) -> Vec<[f64; 2]> {
    let mut state = seed ^ 0x9E37_79B9_7F4A_7C15;
    let mut jitter = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        noise * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
    };
    let mut points = Vec::new();
    for (k, &offset) in offsets.iter().enumerate() {
        let place = [origin[0] + offset, origin[1]];
        if k > 0 {
            let steps = 21;
            for s in 1..2 * steps {
                let out = if s <= steps { s } else { 2 * steps - s };
                points.push([place[0], place[1] + out as f64 * gamma / 7.0]);
            }
        }
        for _ in 0..stop_len {
            points.push([place[0] + jitter(), place[1] + jitter()]);
        }
    }
    points
}

fn trajectory(points: &[[f64; 2]]) -> Trajectory {
    Trajectory::from_points((0..points.len()).map(|i| i as f64 * 0.1).collect(), points).unwrap()
}

/// The offsets of the second stop from the first, for γ: the same place, 10⁻¹⁴ m, half of γ,
/// just inside γ, γ, and just beyond (one ulp, and 10⁻⁹).
fn offsets(gamma: f64) -> [f64; 7] {
    [0.0, 1e-14, 0.5 * gamma, gamma - 1e-9, gamma, gamma.next_up(), gamma + 1e-9]
}

/// The separations the batch is checked with: none, along the path, in time only (a stop has
/// no path length but its time goes on), both.
fn separations(gamma: f64) -> [Separation; 4] {
    [
        Separation::NONE,
        Separation { path: gamma, time_s: 0.0 },
        Separation { path: 0.0, time_s: 7.0 },
        Separation { path: 0.5 * gamma, time_s: 3.0 },
    ]
}

/// The batch set equals the brute force's, runs and closest columns, with every separation.
fn check_batch(traj: &Trajectory, gamma: f64, what: &str) {
    for separation in separations(gamma) {
        let set = SublevelSet::compute_separated(traj, &Euclidean, gamma, separation).unwrap();
        let brute = SublevelSet::brute_force_separated(traj, &Euclidean, gamma, separation).unwrap();
        for i in 0..traj.len() {
            assert_eq!(set.row(i), brute.row(i), "{what}, {separation}: row {i}");
        }
        assert_eq!(set.closest_columns(), brute.closest_columns(), "{what}, {separation}: closest columns");
        assert_eq!(set, brute, "{what}, {separation}");
    }
}

/// The rows of a fleet's joint set from every pair: pairs of one session within γ and separated
/// along that session's own path and clock, pairs of two sessions within γ; runs cut where a
/// session starts; closest column the argmin of the rank over the run, the earliest on ties.
fn fleet_rows(sessions: &[Trajectory], gamma: f64, separation: Separation) -> Vec<Vec<(Run, u32)>> {
    let mut session_of = Vec::new();
    let mut joint: Vec<&[f64]> = Vec::new();
    let (mut s, mut t) = (Vec::new(), Vec::new());
    let mut starts = Vec::new();
    for (a, traj) in sessions.iter().enumerate() {
        starts.push(joint.len());
        s.extend(path_length(traj, &Euclidean));
        t.extend_from_slice(traj.timestamps_s());
        for k in 0..traj.len() {
            session_of.push(a);
            joint.push(traj.point(k));
        }
    }
    let n = joint.len();
    let inside = |i: usize, j: usize| {
        let kept = session_of[i] != session_of[j]
            || separation.is_none()
            || (j > i && s[j] - s[i] >= separation.path && t[j] - t[i] >= separation.time_s);
        kept && Euclidean.distance(joint[i], joint[j]) <= gamma
    };
    (0..n)
        .map(|i| {
            let mut row: Vec<(Run, u32)> = Vec::new();
            let mut best = f64::INFINITY;
            for j in i..n {
                if !inside(i, j) {
                    continue;
                }
                let rank = Euclidean.distance_rank(joint[i], joint[j]);
                match row.last_mut() {
                    Some((run, closest)) if run.end as usize + 1 == j && !starts.contains(&j) => {
                        run.end = j as u32;
                        if rank < best {
                            (best, *closest) = (rank, j as u32);
                        }
                    }
                    _ => {
                        row.push((Run { start: j as u32, end: j as u32 }, j as u32));
                        best = rank;
                    }
                }
            }
            row
        })
        .collect()
}

/// The fleet engine's joint set equals [`fleet_rows`], with both prunings.
fn check_fleet(sessions: &[Trajectory], gamma: f64, separation: Separation, what: &str) {
    let named = sessions.iter().enumerate().map(|(k, t)| (format!("s{k}"), t.clone())).collect();
    let fleet = Fleet::new(named).unwrap();
    let expected = fleet_rows(sessions, gamma, separation);
    for pruning in [Pruning::Hierarchy, Pruning::KdTree] {
        let options = FleetOptions { separation, pruning, chunk_radius: None };
        let loops = find_fleet_loops(&fleet, &Euclidean, gamma, &options).unwrap();
        let set = loops.loops().sublevel_set();
        let mut offset = 0;
        for (i, row) in expected.iter().enumerate() {
            let found: Vec<(Run, u32)> =
                set.row(i).iter().enumerate().map(|(k, &run)| (run, set.closest_columns()[offset + k])).collect();
            assert_eq!(&found, row, "{what}, {pruning:?}, {separation}: row {i}");
            offset += set.row(i).len();
        }
    }
}

/// Each pushed row equals the brute force's column (runs and closest columns), and the
/// snapshot equals the batch.
fn check_online(traj: &Trajectory, gamma: f64, what: &str) {
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, 2, gamma).unwrap();
    for n in 0..traj.len() {
        let update = online.push(traj.timestamps_s()[n], traj.point(n)).unwrap();
        let found: Vec<(Run, usize)> = update.runs.iter().map(|r| (r.run, r.closest)).collect();
        let mut expected: Vec<(Run, usize)> = Vec::new();
        let mut best = f64::INFINITY;
        for j in 0..=n {
            if Euclidean.distance(traj.point(j), traj.point(n)) > gamma {
                continue;
            }
            let rank = Euclidean.distance_rank(traj.point(j), traj.point(n));
            match expected.last_mut() {
                Some((run, closest)) if run.end as usize + 1 == j => {
                    run.end = j as u32;
                    if rank < best {
                        (best, *closest) = (rank, j);
                    }
                }
                _ => {
                    expected.push((Run { start: j as u32, end: j as u32 }, j));
                    best = rank;
                }
            }
        }
        assert_eq!(found, expected, "{what}: online row {n}");
    }
    assert!(online.to_loops().unwrap() == find_loops(traj, &Euclidean, gamma).unwrap(), "{what}: snapshot");
}

/// Two and three stops at every offset, near the origin and far from it (where the offsets
/// round), exactly parked: batch, separated batch, fleet and the dense reference of the loops.
#[test]
fn two_and_three_stops_at_one_place_equal_the_brute_force() {
    let gamma: f64 = 1.5;
    for origin in [[0.0, 0.0], [1000.0, -3000.0]] {
        for offset in offsets(gamma) {
            for places in [&[0.0, offset][..], &[0.0, offset, -offset][..]] {
                let points = stops(origin, places, 300, gamma, 0.0, 1);
                let traj = trajectory(&points);
                let what = format!("stops at {places:?} from {origin:?}");
                check_batch(&traj, gamma, &what);
                // The stops in two sessions, cut halfway along the first drive.
                let cut = 300 + 20;
                let sessions = [trajectory(&points[..cut]), trajectory(&points[cut..])];
                for separation in [Separation::NONE, Separation { path: gamma, time_s: 0.0 }] {
                    check_fleet(&sessions, gamma, separation, &what);
                }
                if places.len() == 2 {
                    check_against_dense(&traj, gamma, (0.1, 0.9)).unwrap_or_else(|e| panic!("{what}: {e}"));
                }
            }
        }
    }
}

/// Stops jittered by 10⁻⁹ m and by a tenth of γ: no two poses alike.
#[test]
fn jittered_stops_equal_the_brute_force() {
    let gamma: f64 = 1.5;
    for noise in [1e-9, 0.1 * gamma] {
        for (seed, offset) in offsets(gamma).into_iter().enumerate() {
            let points = stops([0.0, 0.0], &[0.0, offset, 0.5 * offset], 300, gamma, noise, seed as u64);
            let traj = trajectory(&points);
            let what = format!("stops jittered by {noise} at offset {offset}");
            check_batch(&traj, gamma, &what);
            let sessions = [trajectory(&points[..320]), trajectory(&points[320..])];
            check_fleet(&sessions, gamma, Separation::NONE, &what);
        }
    }
}

/// The online engine, pose by pose, on two stops at every offset, and on jittered ones.
#[test]
fn online_rows_at_two_stops_equal_the_brute_force() {
    let gamma: f64 = 1.5;
    for offset in offsets(gamma) {
        for noise in [0.0, 1e-9] {
            let traj = trajectory(&stops([0.0, 0.0], &[0.0, offset], 300, gamma, noise, 5));
            check_online(&traj, gamma, &format!("offset {offset}, jitter {noise}"));
        }
    }
}

/// The Euclidean metric, counting the distances measured and the ranks taken (one per cell
/// that `closest_in` ranks).
#[derive(Default)]
struct Counting {
    evaluations: AtomicU64,
}

impl Counting {
    fn take(&self) -> u64 {
        self.evaluations.swap(0, Relaxed)
    }
}

impl Metric for Counting {
    fn name(&self) -> String {
        Euclidean.name()
    }
    fn check_dim(&self, dim: usize) -> loops_core::Result<()> {
        Euclidean.check_dim(dim)
    }
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.evaluations.fetch_add(1, Relaxed);
        Euclidean.distance(a, b)
    }
    fn rounding_scale(&self, traj: &Trajectory) -> f64 {
        Euclidean.rounding_scale(traj)
    }
    fn is_coordinate_euclidean(&self) -> bool {
        true
    }
    fn distance_rank(&self, a: &[f64], b: &[f64]) -> f64 {
        self.evaluations.fetch_add(1, Relaxed);
        Euclidean.distance_rank(a, b)
    }
    fn closest_in(&self, x: &[f64], points: &[f64]) -> usize {
        self.evaluations.fetch_add((points.len() / x.len()) as u64, Relaxed);
        Euclidean.closest_in(x, points)
    }
}

/// Distances and ranks per row and run (a row beyond γ of the other stop has no run there, but
/// a scan may still measure it) that the scans may spend on stops: the first row of each block
/// of rows walks the hierarchy and ranks a closest column (O(log n), ending at the other stop's
/// first pose), the others repeat it. About 2 to 4 today; 30 to 100 with either half undone.
const EVALUATIONS_PER_RUN: f64 = 8.0;

/// Two stops of 4,000 poses each at 10⁻¹⁴ m, γ and one ulp beyond γ apart (and, for scale, at
/// the same place): the batch, the separated batch and the fleet (both prunings) measure a
/// bounded number of distances per row and run. The engine once measured every pose of the other stop
/// for every row of one: thousands per run.
#[test]
fn two_stops_cost_a_bounded_number_of_distances_per_run() {
    let gamma: f64 = 1.5;
    let counting = Counting::default();
    let mut costs = Vec::new();
    for offset in [0.0, 1e-14, gamma, gamma.next_up()] {
        let points = stops([0.0, 0.0], &[0.0, offset], 4000, gamma, 0.0, 0);
        let traj = trajectory(&points);
        for separation in [Separation::NONE, Separation { path: gamma, time_s: 0.0 }] {
            counting.take();
            let set = SublevelSet::compute_separated(&traj, &counting, gamma, separation).unwrap();
            let per_run = counting.take() as f64 / (set.rows() + set.runs().len()) as f64;
            costs.push((format!("offset {offset}, {separation}"), per_run));
        }
        let cut = 4000 + 20;
        let named = vec![("a".to_owned(), trajectory(&points[..cut])), ("b".to_owned(), trajectory(&points[cut..]))];
        let fleet = Fleet::new(named).unwrap();
        for pruning in [Pruning::Hierarchy, Pruning::KdTree] {
            counting.take();
            let options = FleetOptions { pruning, ..FleetOptions::default() };
            let loops = find_fleet_loops(&fleet, &counting, gamma, &options).unwrap();
            let set = loops.loops().sublevel_set();
            let per_run = counting.take() as f64 / (set.rows() + set.runs().len()) as f64;
            costs.push((format!("fleet, offset {offset}, {pruning:?}"), per_run));
        }
    }
    let report: Vec<String> = costs.iter().map(|(what, per_run)| format!("{what}: {per_run:.1}")).collect();
    assert!(costs.iter().all(|&(_, per_run)| per_run <= EVALUATIONS_PER_RUN), "per run: {report:#?}");
}
