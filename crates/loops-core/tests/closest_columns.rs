//! The closest column of every run against the brute force's argmin over all of its cells, on
//! paths that pass by their own poses again and again: straight passes at a few offsets (the
//! closest cell inside the run, at its edge, or two cells tied), laps that wrap around a torus,
//! rotations that sweep through the half turn, and SE(3) poses whose heading turns as they pass.
//! The engine measures only the cells that the distances its scan measured leave open; a bound
//! that skipped a cell it should not shows here as a closest column other than the brute force's.

use std::f64::consts::{PI, TAU};

use loops_core::{
    Euclidean, Metric, RotationDistance, Se3, Separation, So3, SublevelSet, Torus, Trajectory, with_threads,
};

/// Pose times 0, 1, 2, … s.
fn times(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64).collect()
}

/// Checks the set of `traj` under `metric` at `gamma` against the brute force (runs and closest
/// columns, with and without a separation) on one and two threads, and returns how many runs
/// off the diagonal have at least 16 cells (those whose closest column the scan's bounds prune).
fn check(what: &str, traj: &Trajectory, metric: &dyn Metric, gamma: f64) -> usize {
    let brute = SublevelSet::brute_force(traj, metric, gamma).unwrap();
    for threads in [1, 2] {
        let set = with_threads(Some(threads), || SublevelSet::compute(traj, metric, gamma)).unwrap().unwrap();
        for i in 0..traj.len() {
            assert_eq!(set.row(i), brute.row(i), "{what}, {threads} threads: runs of row {i}");
        }
        let first_wrong = set.closest_columns().iter().zip(brute.closest_columns()).position(|(a, b)| a != b);
        assert_eq!(first_wrong, None, "{what}, {threads} threads: closest columns differ");
        assert_eq!(set, brute, "{what}, {threads} threads");
    }
    let separation = Separation { path: 2.0 * gamma, time_s: 0.0 };
    let set = SublevelSet::compute_separated(traj, metric, gamma, separation).unwrap();
    assert_eq!(set, SublevelSet::brute_force_separated(traj, metric, gamma, separation).unwrap(), "{what}, separated");
    let mut long = 0;
    for i in 0..traj.len() {
        long += brute.row(i).iter().filter(|run| run.start as usize != i && run.len() >= 16).count();
    }
    long
}

/// Straight passes along y = 0 and back at offsets 0, 0.5, 1 and 3 (x on whole and half
/// metres, so a pose of one pass lies midway between two of another: exact ties), passes that
/// end where they come closest (a turn away at the closest point), and one at γ exactly.
#[test]
fn passes_on_the_plane() {
    let mut points: Vec<[f64; 2]> = Vec::new();
    let mut pass = |y: f64, from: f64, to: f64, step: f64| {
        let count = ((to - from) / step).abs().round() as usize;
        let sign = (to - from).signum();
        points.extend((0..=count).map(|k| [from + sign * step * k as f64, y]));
    };
    pass(0.0, -30.0, 30.0, 1.0);
    pass(0.5, 30.5, -30.5, 1.0);
    pass(1.0, -29.5, 29.5, 1.0);
    pass(3.0, 30.0, -30.0, 0.5);
    pass(0.0, -30.5, 0.0, 1.0);
    pass(20.0, 0.0, 0.0, 1.0);
    pass(20.0, 5.0, -30.0, 1.0);
    pass(-10.0, -30.0, 30.0, 2.0);
    pass(0.0, 30.0, -30.0, 1.0);
    let traj = Trajectory::from_points(times(points.len()), &points).unwrap();
    for gamma in [10.0, 3.0, 0.5] {
        let long = check(&format!("plane, gamma {gamma}"), &traj, &Euclidean, gamma);
        assert!(gamma < 5.0 || long > 100, "gamma {gamma}: {long} long runs");
    }
}

/// Slow passes, whose runs hold hundreds of cells in a few metres of path, so that the columns
/// the scan's bounds leave open go to the ball hierarchy: a fast pass along y = 0, then a crawl
/// at 5 cm a step along y = 4 and back over the same points (every pose of the way back ties
/// with one of the way out, in another ball, and the earlier must win), with a stop of 300
/// poses at one point where it comes closest to some rows, and a creep of 400 steps of 1 nm,
/// where the path length barely grows; then a crawl at y = 2, closer than the first for
/// some rows and farther for others. The closest column of a long run lies between the
/// stretches its bounds rule out.
#[test]
fn slow_passes_with_stops_and_creeps() {
    let mut points: Vec<[f64; 2]> = (0..=60).map(|k| [-30.0 + k as f64, 0.0]).collect();
    let crawl = |from: i32, to: i32| -> Vec<i32> {
        if from <= to { (from..=to).collect() } else { (to..=from).rev().collect() }
    };
    // x = k × 5 cm, the same bits on the way out and back.
    let at = |k: i32, y: f64| [f64::from(k) * 0.05, y];
    points.extend(crawl(-500, 40).into_iter().map(|k| at(k, 4.0)));
    points.extend(std::iter::repeat_n(at(40, 4.0), 300));
    points.extend((1..=400).map(|k| [2.0 + f64::from(k) * 1e-9, 4.0]));
    points.extend(crawl(40, 200).into_iter().map(|k| at(k, 4.0)));
    points.extend(crawl(200, -500).into_iter().map(|k| at(k, 4.0)));
    points.extend(crawl(-300, 300).into_iter().map(|k| at(k, 2.0 + 0.001 * f64::from(k % 3))));
    let traj = Trajectory::from_points(times(points.len()), &points).unwrap();
    for gamma in [12.0, 6.0] {
        let long = check(&format!("slow passes, gamma {gamma}"), &traj, &Euclidean, gamma);
        assert!(long > 100, "gamma {gamma}: {long} long runs");
    }
}

/// Laps around a torus of two angles: the first angle winds through ±π again and again at
/// steps of π/16 (half a step apart on alternate laps), the second oscillates, so passes cross
/// the wrap and lie midway between poses of other passes.
#[test]
fn laps_around_a_torus() {
    let mut angles = Vec::new();
    for lap in 0..6 {
        let phase = if lap % 2 == 0 { 0.0 } else { PI / 32.0 };
        let direction = if lap % 3 == 2 { -1.0 } else { 1.0 };
        for k in 0..64 {
            let a = direction * (phase + k as f64 * PI / 16.0) - PI;
            let b = 0.2 * (lap as f64) * (a * 2.0).sin();
            angles.extend([a, b]);
        }
    }
    let traj = Trajectory::torus(times(angles.len() / 2), &angles, 2).unwrap();
    for gamma in [1.5, 0.6, 0.2] {
        let long = check(&format!("torus, gamma {gamma}"), &traj, &Torus, gamma);
        assert!(gamma < 1.0 || long > 100, "gamma {gamma}: {long} long runs");
    }
}

/// Rotations about z sweeping through the half turn, where the rotation angle wraps, and
/// back, on whole and half steps; a tilt on some sweeps moves them off the others.
#[test]
fn rotations_sweeping_through_the_half_turn() {
    let mut vectors: Vec<[f64; 3]> = Vec::new();
    for sweep in 0..6 {
        let offset = if sweep % 2 == 0 { 0.0 } else { 0.5 };
        let tilt = [0.0, 0.05, 0.0, 0.2, 0.0, 0.01][sweep];
        for k in 0..48 {
            let step = if sweep % 2 == 0 { k as f64 } else { 47.0 - k as f64 };
            // From 0.6 π up through π (the same rotation as −π) and on to 1.4 π.
            let angle = 0.6 * PI + (step + offset) * 0.8 * PI / 48.0;
            let angle = if angle > PI { angle - TAU } else { angle };
            vectors.push([tilt, 0.0, angle]);
        }
    }
    let traj = Trajectory::so3_from_rotation_vectors(times(vectors.len()), &vectors).unwrap();
    for rotation in [RotationDistance::Geodesic, RotationDistance::Chordal] {
        let metric = So3 { rotation };
        for gamma in [0.8, 0.3] {
            let long = check(&format!("SO(3) {rotation:?}, gamma {gamma}"), &traj, &metric, gamma);
            assert!(gamma < 0.5 || long > 50, "SO(3) {rotation:?}, gamma {gamma}: {long} long runs");
        }
    }
}

/// SE(3) passes along a line at offsets, the heading turning through the half turn on the way
/// (so the rotation part, wrapped, decides which pose is closest), under rotation weights 0 to 10
/// m/rad.
#[test]
fn poses_turning_as_they_pass() {
    let (mut positions, mut quaternions): (Vec<[f64; 3]>, Vec<[f64; 4]>) = (Vec::new(), Vec::new());
    for pass in 0..5 {
        let y = [0.0, 0.5, 1.0, 0.0, 2.0][pass];
        let backwards = pass % 2 == 1;
        for k in 0..60 {
            let x = if backwards { 29.5 - k as f64 } else { k as f64 - 30.0 };
            let yaw = PI * (1.0 + x / 60.0) + if pass == 3 { 0.3 } else { 0.0 };
            positions.push([x, y, 0.0]);
            quaternions.push([0.0, 0.0, (0.5 * yaw).sin(), (0.5 * yaw).cos()]);
        }
    }
    let traj = Trajectory::se3(times(positions.len()), &positions, &quaternions).unwrap();
    // γ grows with the weight, so that runs stay tens of poses long.
    for (weight, gamma) in [(0.0, 8.0), (1.0, 8.0), (10.0, 24.0)] {
        for rotation in [RotationDistance::Geodesic, RotationDistance::Chordal] {
            let metric = Se3 { rotation_weight_m_per_rad: weight, rotation };
            let long = check(&format!("SE(3) {weight} m/rad {rotation:?}"), &traj, &metric, gamma);
            assert!(long > 20, "SE(3) {weight} m/rad: {long} long runs");
        }
    }
}
