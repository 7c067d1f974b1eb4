//! The example trajectories of the paper's Fig. 2 (ξ : [0, 1] → R², L2 metric, γ = 1 and 3),
//! with the structure of S_γ derived from their geometry, and every case also checked against
//! the dense reference.

mod support;

use std::f64::consts::{PI, TAU};

use loops_core::{Euclidean, LoopComponent, Loops, Trajectory, find_loops};
use support::{check_against_dense, sampled};

/// Engine result after checking it against the dense reference.
fn loops_checked(traj: &Trajectory, gamma: f64) -> Loops {
    check_against_dense(traj, gamma, (0.25, 0.75))
        .unwrap_or_else(|e| panic!("γ = {gamma}: engine and dense reference differ: {e}"));
    find_loops(traj, &Euclidean, gamma).unwrap()
}

fn split(loops: &Loops) -> (Vec<&LoopComponent>, Vec<&LoopComponent>) {
    loops.components().iter().partition(|c| c.trivial)
}

/// Sample index of time t ∈ [0, 1] on n even samples (rounded down).
fn index_of(t: f64, n: usize) -> usize {
    (t * (n - 1) as f64).floor() as usize
}

/// Angle subtended by a chord of length `gamma` on a circle of radius `radius`.
fn chord_angle(gamma: f64, radius: f64) -> f64 {
    2.0 * (gamma / (2.0 * radius)).asin()
}

/// Fig. 2a: a 95% circle. Two points θ apart are within γ iff θ ≤ Δ or θ ≥ 2π − Δ, with Δ the
/// angle of a chord γ. With the circle much bigger than γ (Δ ≪ π) but its end gap below γ, S_γ
/// is the band |θ − θ′| ≤ Δ along the diagonal (the trivial component) and the triangle
/// θ′ − θ ≥ 2π − Δ at (0, 1): one non-trivial component, closest at its corner (0, 1).
#[test]
fn fig_2a_circle_95_percent() {
    let n = 1200;
    let sweep = 0.95 * TAU;
    for (gamma, radius) in [(1.0, 2.5), (3.0, 7.5)] {
        let gap = 2.0 * radius * (0.05 * PI).sin();
        assert!(gap < gamma && 2.0 * radius >= 5.0 * gamma);
        let traj = sampled(n, |t| {
            let theta = sweep * t;
            [radius * theta.cos(), radius * theta.sin()]
        });
        let loops = loops_checked(&traj, gamma);
        let (trivial, others) = split(&loops);
        assert_eq!((trivial.len(), others.len()), (1, 1), "γ = {gamma}: {:?}", loops.components());
        let (band, corner) = (trivial[0], others[0]);
        assert_eq!(band.holes, 0);
        assert_eq!(corner.holes, 0);

        // The corner triangle: rows θ ≤ sweep − (2π − Δ), columns θ′ ≥ 2π − Δ.
        let delta = chord_angle(gamma, radius);
        let leg = (sweep - (TAU - delta)) / sweep; // in t
        assert!(leg > 10.0 / n as f64, "the triangle spans several samples");
        assert_eq!(corner.i_range[0], 0, "rows start at t = 0");
        assert_eq!(corner.j_range[1], n - 1, "columns end at t = 1");
        assert!(corner.i_range[1].abs_diff(index_of(leg, n)) <= 1, "{corner:?}");
        assert!(corner.j_range[0].abs_diff(index_of(1.0 - leg, n) + 1) <= 1, "{corner:?}");
        // Area of the half triangle, s², up to the lattice's staircase.
        let triangle_s2 = 0.5 * leg * leg;
        assert!((corner.area_s2 - triangle_s2).abs() <= 0.15 * triangle_s2, "{} vs {triangle_s2}", corner.area_s2);
        // Closest where the ends of the circle meet.
        assert_eq!(corner.closest_pair, [0, n - 1]);
        assert!((corner.closest_distance - gap).abs() < 1e-9);

        // The band |t − t′| ≤ d has area 1 − (1 − d)².
        let d = delta / sweep;
        let band_s2 = 1.0 - (1.0 - d) * (1.0 - d);
        assert!((band.area_s2 - band_s2).abs() <= 0.02 * band_s2, "{} vs {band_s2}", band.area_s2);
        assert_eq!(band.i_range, [0, n - 1]);
    }
}

/// Fig. 2b: a double loop. The path comes in along the x axis, goes twice around a circle of
/// diameter 2.4 tangent to the axis at the origin, and leaves along the axis.
///
/// γ = 1 < 2.4: points of the loops are within γ only at nearly the same angle, so the pairs
/// one lap apart form one non-trivial component (a band from lap 1 to lap 2) and the pairs two
/// laps apart another, towards the corner (0, 1); the straight parts pass within γ of the
/// loops' lower left and right and extend both to the way in and the way out.
/// γ = 3 > 2.4: every pair of loop points is within γ, a block touching the diagonal, so
/// both merge into the trivial component and only that one is left.
#[test]
fn fig_2b_double_loop_merges_into_the_trivial_component() {
    let n = 1200;
    let (radius, stick, lead) = (1.2, 6.0, 0.2); // lead: the time spent on each straight part
    let path = |t: f64| {
        if t < lead {
            [-stick * (1.0 - t / lead), 0.0]
        } else if t > 1.0 - lead {
            [stick * (t - (1.0 - lead)) / lead, 0.0]
        } else {
            let phi = 2.0 * TAU * (t - lead) / (1.0 - 2.0 * lead);
            [radius * phi.sin(), radius * (1.0 - phi.cos())]
        }
    };
    let traj = sampled(n, path);
    let lap = (1.0 - 2.0 * lead) / 2.0;

    let loops = loops_checked(&traj, 1.0);
    let (trivial, others) = split(&loops);
    assert_eq!((trivial.len(), others.len()), (1, 2), "{:?}", loops.components());
    let (one_lap, two_laps): (Vec<&LoopComponent>, Vec<&LoopComponent>) =
        others.iter().partition(|c| c.i_range[1] > index_of(lead + lap / 2.0, n));
    let (one_lap, two_laps) = (one_lap[0], two_laps[0]);
    let gap_in_t = |c: &LoopComponent| (c.closest_pair[1] - c.closest_pair[0]) as f64 / (n - 1) as f64;
    // One lap apart: rows over lap 1, columns over lap 2; closest where the laps coincide.
    assert!(one_lap.i_range[0] <= index_of(lead, n) && one_lap.i_range[1] >= index_of(lead + lap, n));
    assert!(one_lap.j_range[0] <= index_of(lead + lap, n) && one_lap.j_range[1] >= index_of(1.0 - lead, n));
    assert!((gap_in_t(one_lap) - lap).abs() < 0.01, "{one_lap:?}");
    // Two laps apart: from the way in (before lap 1) to the way out (after lap 2).
    assert!(two_laps.i_range[0] < index_of(lead, n) && two_laps.j_range[1] > index_of(1.0 - lead, n));
    assert!(two_laps.i_range[1] < index_of(lead + lap / 2.0, n));
    assert!(two_laps.j_range[0] > index_of(1.0 - lead - lap / 2.0, n));
    assert!((gap_in_t(two_laps) - 2.0 * lap).abs() < 0.01, "{two_laps:?}");
    for c in [one_lap, two_laps] {
        assert_eq!(c.holes, 0);
        assert!(c.closest_distance < 0.05, "the laps meet: {c:?}");
    }

    let merged = loops_checked(&traj, 3.0);
    assert_eq!(merged.components().len(), 1, "{:?}", merged.components());
    assert!(merged.components()[0].trivial);
    for c in [one_lap, two_laps] {
        let [i, j] = c.closest_pair;
        assert_eq!(merged.component_of(i, j), Some(0));
    }
}

/// Fig. 2c: an outward spiral r = r0 + bφ with turns 2πb = 4.4 apart (more than 3) and radius
/// at least 6. Points of different turns are farther apart than 3; points of one turn within γ
/// are within an arc below π, whose chord shrinks as they slide together. So at γ = 1 and γ = 3
/// every loop is simple: S_γ is a band along the diagonal, one run per row, one trivial
/// component without holes.
#[test]
fn fig_2c_spiral_loops_are_all_simple() {
    let n = 1000;
    let (r0, b, turns) = (6.0, 0.7, 3.0);
    assert!(TAU * b > 3.0);
    let traj = sampled(n, |t| {
        let phi = turns * TAU * t;
        let r = r0 + b * phi;
        [r * phi.cos(), r * phi.sin()]
    });
    for gamma in [1.0, 3.0] {
        let loops = loops_checked(&traj, gamma);
        assert_eq!(loops.components().len(), 1, "γ = {gamma}: {:?}", loops.components());
        let band = &loops.components()[0];
        assert!(band.trivial);
        assert_eq!(band.holes, 0);
        assert!(loops.warnings().is_empty());
        for i in 0..n {
            assert_eq!(loops.sublevel_set().row(i).len(), 1, "γ = {gamma}, row {i}");
        }
    }
}

/// Fig. 2d: a trivial component with holes. Out along a line, back along it, and out again
/// (three passes of length 10, 0.3 apart). The pairs (pass 1, pass 2) form an anti-diagonal band
/// through the first turn, (pass 2, pass 3) one through the second, and (pass 1, pass 3) a band
/// parallel to the diagonal; with the diagonal they enclose the pairs (end of pass 1, start of
/// pass 3), 10 apart. Hence one hole in each half of the plane, at γ = 1 and γ = 3.
#[test]
fn fig_2d_three_passes_make_the_trivial_component_multiply_connected() {
    let n = 900;
    let (length, offset) = (10.0, 0.3);
    let traj = sampled(n, |t| {
        let pass = (3.0 * t).floor().min(2.0);
        let s = 3.0 * t - pass; // progress along this pass
        let x = if pass == 1.0 { length * (1.0 - s) } else { length * s };
        [x, offset * (pass + s)]
    });
    for gamma in [1.0, 3.0] {
        let loops = loops_checked(&traj, gamma);
        assert_eq!(loops.components().len(), 1, "γ = {gamma}: {:?}", loops.components());
        let ring = &loops.components()[0];
        assert!(ring.trivial);
        assert_eq!(ring.holes, 2, "γ = {gamma}");
        // The enclosed pairs are not in S_γ; the bands around them are in the trivial component.
        let (end_1, start_3) = (index_of(1.0 / 3.0, n), index_of(2.0 / 3.0, n) + 1);
        assert_eq!(loops.component_of(end_1, start_3), None);
        assert_eq!(loops.component_of(0, index_of(2.0 / 3.0, n)), Some(0));
        assert_eq!(loops.component_of(end_1, n - 1), Some(0));
    }
}

/// The "lollipop" (out along a stick, once around a circle of radius 4 > γ, back along the
/// stick) is not multiply connected: the pairs (way out, way back) are an anti-diagonal band
/// from the circle's closing point (t₁, t₂) to (0, 1), and sliding such a pair together would
/// take one point around the circle, farther than γ from the other. So they form a non-trivial
/// component, and the trivial one is a simple band.
#[test]
fn lollipop_out_and_back_is_a_non_trivial_loop_not_a_hole() {
    let n = 900;
    let (stick, radius, lead) = (8.0, 4.0, 0.3);
    let traj = sampled(n, |t| {
        if t < lead {
            [-stick * (1.0 - t / lead), 0.0]
        } else if t > 1.0 - lead {
            [-stick * (t - (1.0 - lead)) / lead, 0.0]
        } else {
            let phi = TAU * (t - lead) / (1.0 - 2.0 * lead);
            [radius * phi.sin(), radius * (1.0 - phi.cos())]
        }
    });
    for gamma in [1.0, 3.0] {
        let loops = loops_checked(&traj, gamma);
        let (trivial, others) = split(&loops);
        assert_eq!((trivial.len(), others.len()), (1, 1), "γ = {gamma}: {:?}", loops.components());
        assert_eq!(trivial[0].holes, 0);
        let back = others[0];
        assert_eq!(back.holes, 0);
        assert_eq!((back.i_range[0], back.j_range[1]), (0, n - 1));
        assert_eq!(back.closest_distance, 0.0);
    }
}
