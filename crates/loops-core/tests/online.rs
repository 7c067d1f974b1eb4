//! The online engine against the batch engine: after pushes one at a time or in
//! batches of random sizes, `to_loops` equals `find_loops` on the same poses bit for bit, and
//! the live components (after every push, on small inputs) have the batch's statistics; each
//! pushed row is the brute force's column; ids, creations and merges are consistent; rebuilds
//! continue correctly; under several metrics; bad input is refused naming the pose; real data
//! (KITTI 00, TUC Corridor, MulRan KAIST 01) when `../shared/data` is present.

mod support;

use std::path::{Path, PathBuf};

use loops_core::{
    Error, Loops, MetricSpec, RotationDistance, Run, Scale, Se2, Se3, Selection, Side, Sphere, Trajectory,
    online::{ComponentId, OnlineComponent, OnlineLoops, Update},
};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use support::{any_case, config};

/// The first `n` poses of `traj`, as a plain coordinate trajectory (the online engine's).
fn prefix(traj: &Trajectory, n: usize) -> Trajectory {
    let dim = traj.dim();
    Trajectory::new(traj.timestamps_s()[..n].to_vec(), traj.coords()[..n * dim].to_vec(), dim).unwrap()
}

/// How far the online engine's sums of time cells may be from the batch's: both take widths of
/// runs as differences of running sums, rounded relative to the span, and group them
/// differently (see `OnlineLoops`).
fn tolerance(traj: &Trajectory) -> f64 {
    let shortest = traj.cell_widths_s().iter().copied().fold(f64::INFINITY, f64::min);
    (8.0 * traj.span_s() / shortest + 4.0 * traj.len() as f64) * f64::EPSILON / 2.0
}

fn close(a: f64, b: f64, relative: f64) -> bool {
    (a - b).abs() <= relative * a.abs().max(b.abs())
}

/// The live components and τ of `online` against the batch's `loops` of the same poses: a
/// one-to-one map (through each live component's closest pair), integers, closest pairs and
/// their distances exactly, areas and τ within `tolerance`.
fn check_live(online: &OnlineLoops, loops: &Loops, tolerance: f64) -> Result<(), TestCaseError> {
    let live: Vec<(ComponentId, &OnlineComponent)> = online.components().collect();
    prop_assert_eq!(live.len(), loops.components().len(), "number of components");
    let mut seen = vec![false; live.len()];
    for (id, c) in live {
        prop_assert_eq!(c.id, id);
        prop_assert_eq!(online.resolve(id), id);
        let [i, j] = c.closest_pair;
        let k = loops.component_of(i, j).ok_or_else(|| TestCaseError::fail(format!("{c:?} off S_gamma")))?;
        prop_assert!(!seen[k], "two live components are batch component {}", k);
        seen[k] = true;
        let b = &loops.components()[k];
        prop_assert_eq!(
            (c.trivial, c.pair_count, c.run_count, c.holes, c.i_range, c.j_range, c.closest_pair),
            (b.trivial, b.pair_count, b.run_count, b.holes, b.i_range, b.j_range, b.closest_pair),
            "live component {} against batch component {}",
            id,
            k
        );
        prop_assert_eq!(c.closest_distance.to_bits(), b.closest_distance.to_bits());
        prop_assert!(close(c.area_s2, b.area_s2, tolerance), "area {} against {}", c.area_s2, b.area_s2);
        prop_assert!(c.first_pose <= c.j_range[0].max(c.i_range[0]) || c.trivial);
        prop_assert!(c.last_pose == c.j_range[1], "{:?}", c);
    }
    let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds).unwrap();
    for (i, &expected) in tau.iter().enumerate() {
        let found = online.loop_duration_s(i).unwrap();
        prop_assert!(close(found, expected, tolerance), "tau({}) = {} against {}", i, found, expected);
    }
    Ok(())
}

/// Row n as the brute force sees it: the columns j ≤ n within γ of pose n (δ measured earlier
/// pose first), as runs, each with its closest column (the earliest on ties).
fn brute_row(traj: &Trajectory, metric: &MetricSpec, gamma: f64, n: usize) -> Vec<(Run, usize)> {
    let mut row: Vec<(Run, usize)> = Vec::new();
    let mut best = f64::INFINITY;
    for j in 0..=n {
        let d = metric.distance(traj.point(j), traj.point(n));
        if d > gamma {
            continue;
        }
        let rank = metric.as_metric().distance_rank(traj.point(j), traj.point(n));
        match row.last_mut() {
            Some((run, closest)) if run.end as usize + 1 == j => {
                run.end = j as u32;
                if rank < best {
                    (best, *closest) = (rank, j);
                }
            }
            _ => {
                row.push((Run { start: j as u32, end: j as u32 }, j));
                best = rank;
            }
        }
    }
    row
}

/// What an update says about ids, checked against the live set before and after it.
fn check_update(before: &[ComponentId], online: &OnlineLoops, update: &Update) -> Result<(), TestCaseError> {
    let after: Vec<ComponentId> = online.components().map(|(id, _)| id).collect();
    for merge in &update.merged {
        prop_assert!(merge.survivor < merge.retired);
        prop_assert!(online.component(merge.retired).is_none(), "retired {} still live", merge.retired);
        prop_assert!(online.resolve(merge.retired) <= merge.survivor);
    }
    let retired: Vec<ComponentId> = update.merged.iter().map(|m| m.retired).collect();
    let mut expected: Vec<ComponentId> =
        before.iter().chain(&update.created).copied().filter(|id| !retired.contains(id)).collect();
    expected.sort_unstable();
    prop_assert_eq!(&after, &expected, "live ids after the update");
    for &id in &update.extended {
        prop_assert!(before.contains(&id) && online.component(id).is_some(), "extended {}", id);
    }
    for run in &update.runs {
        prop_assert!(run.run.start <= run.run.end && run.run.end as usize <= run.row);
    }
    Ok(())
}

/// Pushes `traj` into a fresh engine in chunks of the sizes in `chunks` (cycled); with `every`,
/// checks each update's rows against the brute force, its ids, and the live components against
/// the batch of the prefix.
fn push_all(
    traj: &Trajectory,
    metric: MetricSpec,
    gamma: f64,
    chunks: &[usize],
    every: bool,
) -> Result<OnlineLoops, TestCaseError> {
    let dim = traj.dim();
    let mut online = OnlineLoops::new(metric, dim, gamma).unwrap();
    let mut pushed = 0;
    for &size in chunks.iter().cycle() {
        if pushed == traj.len() {
            break;
        }
        let end = (pushed + size.max(1)).min(traj.len());
        let before: Vec<ComponentId> = online.components().map(|(id, _)| id).collect();
        let update = if end == pushed + 1 {
            online.push(traj.timestamps_s()[pushed], traj.point(pushed)).unwrap()
        } else {
            online.push_many(&traj.timestamps_s()[pushed..end], &traj.coords()[pushed * dim..end * dim]).unwrap()
        };
        prop_assert_eq!((update.first_pose, update.pose), (pushed, end - 1));
        if every {
            check_update(&before, &online, &update)?;
            for n in pushed..end {
                let rows: Vec<(Run, usize)> =
                    update.runs.iter().filter(|r| r.row == n).map(|r| (r.run, r.closest)).collect();
                prop_assert_eq!(rows, brute_row(traj, &metric, gamma, n), "row {}", n);
            }
            if end >= 2 {
                let part = prefix(traj, end);
                let loops = metric.find_loops(&part, gamma).unwrap();
                check_live(&online, &loops, tolerance(&part))?;
                let tau = online.loop_duration_s(end - 1).unwrap();
                prop_assert!(
                    close(update.loop_duration_s, tau, tolerance(&part)),
                    "{} against {}",
                    update.loop_duration_s,
                    tau
                );
            }
        }
        pushed = end;
    }
    Ok(online)
}

/// The snapshot equals the batch, and the live components match it.
fn check_final(online: &OnlineLoops, traj: &Trajectory, metric: MetricSpec, gamma: f64) -> Result<(), TestCaseError> {
    let batch = metric.find_loops(traj, gamma).unwrap();
    let snapshot = online.to_loops().unwrap();
    prop_assert!(snapshot == batch, "to_loops differs from find_loops");
    check_live(online, &batch, tolerance(traj))
}

proptest! {
    #![proptest_config(config(160, 0x0419_0001))]

    /// Pose by pose, with every update checked.
    #[test]
    fn pose_by_pose_equals_the_batch_after_every_push(case in any_case(90)) {
        let online = push_all(&case.traj, MetricSpec::Euclidean, case.gamma, &[1], true)?;
        check_final(&online, &case.traj, MetricSpec::Euclidean, case.gamma)?;
    }

    /// Batches of random sizes give the same state as single pushes, bit for bit.
    #[test]
    fn batches_equal_single_pushes(case in any_case(200), chunks in prop::collection::vec(1..40usize, 1..8)) {
        let single = push_all(&case.traj, MetricSpec::Euclidean, case.gamma, &[1], false)?;
        let batched = push_all(&case.traj, MetricSpec::Euclidean, case.gamma, &chunks, true)?;
        let a: Vec<OnlineComponent> = single.components().map(|(_, c)| c.clone()).collect();
        let b: Vec<OnlineComponent> = batched.components().map(|(_, c)| c.clone()).collect();
        prop_assert_eq!(a, b);
        check_final(&batched, &case.traj, MetricSpec::Euclidean, case.gamma)?;
    }

    /// A rebuild from a corrected past, then more pushes, ends where pushing the corrected
    /// trajectory from the start ends.
    #[test]
    fn rebuild_then_push(case in any_case(160), cut in 0.0..1.0f64, shift in -3.0..3.0f64) {
        let traj = &case.traj;
        let (n, dim) = (traj.len(), traj.dim());
        let cut = (2.0 + cut * (n - 2) as f64) as usize;
        // The back end moves the second half of the past by `shift` γ.
        let corrected_coords: Vec<f64> = traj.coords().iter().enumerate()
            .map(|(k, &c)| if k / dim >= cut / 2 { c + shift * case.gamma } else { c })
            .collect();
        let corrected = Trajectory::new(traj.timestamps_s().to_vec(), corrected_coords, dim).unwrap();
        let mut online = push_all(&prefix(traj, cut), MetricSpec::Euclidean, case.gamma, &[7], false)?;
        online.rebuild(&prefix(&corrected, cut)).unwrap();
        let fresh = push_all(&prefix(&corrected, cut), MetricSpec::Euclidean, case.gamma, &[cut], false)?;
        let a: Vec<OnlineComponent> = online.components().map(|(_, c)| c.clone()).collect();
        let b: Vec<OnlineComponent> = fresh.components().map(|(_, c)| c.clone()).collect();
        prop_assert_eq!(a, b, "a rebuild is pushing the corrected poses at once");
        prop_assert_eq!(online.rebuild_count(), 1);
        for k in cut..n {
            online.push(corrected.timestamps_s()[k], corrected.point(k)).unwrap();
        }
        check_final(&online, &corrected, MetricSpec::Euclidean, case.gamma)?;
    }
}

// =============================================================================================
// Other metrics
// =============================================================================================

/// A seeded walk of `n` poses on SE(3): positions by steps up to `step` m, rotations by small
/// random turns, sometimes back to an earlier pose.
fn se3_walk(n: usize, seed: u64, step: f64) -> Trajectory {
    let mut rng = Lcg(seed);
    let mut positions = vec![[0.0; 3]];
    let mut quats = vec![[0.0, 0.0, 0.0, 1.0]];
    for k in 1..n {
        if rng.next() < 0.05 {
            let back = (rng.next() * k as f64) as usize;
            positions.push(positions[back]);
            quats.push(quats[back]);
            continue;
        }
        let p: [f64; 3] = positions[k - 1];
        positions.push([0, 1, 2].map(|a| p[a] + step * (2.0 * rng.next() - 1.0)));
        let q: [f64; 4] = quats[k - 1];
        let turn = [0, 1, 2, 3].map(|a| q[a] + 0.3 * (2.0 * rng.next() - 1.0));
        let norm = turn.iter().map(|c| c * c).sum::<f64>().sqrt();
        quats.push(turn.map(|c| c / norm));
    }
    let times = (0..n).map(|k| k as f64 * 0.1).collect();
    Trajectory::se3(times, &positions, &quats).unwrap()
}

/// splitmix-style generator in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The engine under `metric` on `traj`, pushed pose by pose with every update checked (the
/// online engine gets the points as plain coordinates).
fn check_metric(traj: &Trajectory, metric: MetricSpec, gamma: f64) {
    let plain = prefix(traj, traj.len());
    let online = push_all(&plain, metric, gamma, &[1, 3, 1, 17], true).unwrap();
    check_final(&online, &plain, metric, gamma).unwrap();
    // The batch on the manifold's own trajectory gives the same loops.
    assert!(online.to_loops().unwrap() == metric.find_loops(traj, gamma).unwrap());
}

#[test]
fn se3_with_and_without_rotation() {
    for seed in 0..4 {
        let traj = se3_walk(220, seed, 0.6);
        for weight in [0.0, 2.0] {
            let metric =
                MetricSpec::Se3(Se3 { rotation_weight_m_per_rad: weight, rotation: RotationDistance::Geodesic });
            check_metric(&traj, metric, 1.5);
        }
    }
}

#[test]
fn torus_and_se2_whose_angle_wrap_is_not_symmetric() {
    for seed in 0..4 {
        let mut rng = Lcg(seed);
        let n = 240;
        let mut angles = vec![3.0, -3.0];
        let mut poses = vec![[0.0, 0.0, 3.1]];
        for k in 1..n {
            // Around ±π, where wrap_angle(a − b) and wrap_angle(b − a) round differently.
            let (a, b) = (angles[2 * (k - 1)], angles[2 * (k - 1) + 1]);
            angles.push(loops_core::wrap_angle(a + 0.4 * (2.0 * rng.next() - 1.0)));
            angles.push(loops_core::wrap_angle(b + 0.4 * (2.0 * rng.next() - 1.0)));
            let p = poses[k - 1];
            poses.push([
                p[0] + rng.next() - 0.5,
                p[1] + rng.next() - 0.5,
                loops_core::wrap_angle(p[2] + rng.next() - 0.5),
            ]);
        }
        let times: Vec<f64> = (0..n).map(|k| k as f64).collect();
        let torus = Trajectory::torus(times.clone(), &angles, 2).unwrap();
        check_metric(&torus, MetricSpec::Torus, 0.5);
        let se2 = Trajectory::se2(times, &poses).unwrap();
        check_metric(&se2, MetricSpec::Se2(Se2 { rotation_weight_m_per_rad: 1.0 }), 1.0);
    }
}

/// Pairs whose torus distance rounds differently in the two orders, exactly at γ: the online
/// engine measures (j, n) as the batch does, earlier pose first, so it keeps exactly the batch's
/// pairs.
#[test]
fn pairs_at_gamma_whose_distance_depends_on_the_order() {
    use loops_core::{Metric, Torus};
    let mut rng = Lcg(7);
    let mut found = [false; 2];
    while found != [true; 2] {
        let (a, b) = (6.2 * rng.next() - 3.1, 6.2 * rng.next() - 3.1);
        let far = loops_core::wrap_angle(a + std::f64::consts::PI);
        let traj = Trajectory::torus(vec![0.0, 1.0, 2.0], &[a, far, b], 1).unwrap();
        let (x, y) = (traj.point(0), traj.point(2));
        let (forward, backward) = (Torus.distance(x, y), Torus.distance(y, x));
        if !(0.1..1.0).contains(&forward) || forward == backward {
            continue;
        }
        // γ at the smaller of the two: the batch keeps (0, 2) only when it is δ(x_0, x_2).
        let gamma = forward.min(backward);
        found[usize::from(forward < backward)] = true;
        let online = push_all(&traj, MetricSpec::Torus, gamma, &[1], true).unwrap();
        let loops = online.to_loops().unwrap();
        assert_eq!(loops.component_of(0, 2).is_some(), forward <= gamma, "{a} {b}");
        assert!(loops == MetricSpec::Torus.find_loops(&traj, gamma).unwrap());
    }
}

#[test]
fn sphere() {
    for seed in 0..3 {
        let mut rng = Lcg(seed);
        let n = 240;
        let mut v = [1.0, 0.0, 0.0];
        let mut vectors = Vec::new();
        for _ in 0..n {
            vectors.push(v);
            v = [0, 1, 2].map(|a| v[a] + 0.3 * (2.0 * rng.next() - 1.0));
            let norm = v.iter().map(|c| c * c).sum::<f64>().sqrt();
            v = v.map(|c| c / norm);
        }
        let traj = Trajectory::sphere((0..n).map(|k| k as f64 * 0.5).collect(), &vectors).unwrap();
        check_metric(&traj, MetricSpec::Sphere(Sphere { radius: 2.0 }), 0.4);
    }
}

// =============================================================================================
// Adversarial trajectories
// =============================================================================================

fn line(xs: &[f64]) -> Trajectory {
    Trajectory::new((0..xs.len()).map(|i| i as f64 * 0.1).collect(), xs.to_vec(), 1).unwrap()
}

#[test]
fn stationary_robot() {
    let traj = line(&vec![5.0; 3000]);
    let online = push_all(&traj, MetricSpec::Euclidean, 1.0, &[1], false).unwrap();
    check_final(&online, &traj, MetricSpec::Euclidean, 1.0).unwrap();
    let (_, whole) = online.components().next().unwrap();
    assert_eq!(whole.pair_count, 3000 * 3000);
    assert_eq!(online.components().count(), 1);
}

#[test]
fn back_and_forth_on_a_line_and_repeated_circuits() {
    let shuttle: Vec<f64> = (0..1500).map(|k| ((k % 200) as f64 - 100.0).abs()).collect();
    let traj = line(&shuttle);
    for gamma in [0.5, 1.0, 3.0, 30.0] {
        let online = push_all(&traj, MetricSpec::Euclidean, gamma, &[1, 5], false).unwrap();
        check_final(&online, &traj, MetricSpec::Euclidean, gamma).unwrap();
    }
    // Ten laps of a square of side 10 on the integer lattice: pairs exactly γ apart everywhere.
    let lap: Vec<[f64; 2]> = (0..40)
        .map(|k| match k / 10 {
            0 => [k as f64, 0.0],
            1 => [10.0, (k - 10) as f64],
            2 => [(30 - k) as f64, 10.0],
            _ => [0.0, (40 - k) as f64],
        })
        .collect();
    let points: Vec<[f64; 2]> = lap.iter().cycle().take(400).copied().collect();
    let traj = Trajectory::from_points((0..400).map(|k| k as f64).collect(), &points).unwrap();
    for gamma in [1.0, 2.0, 10.0] {
        let online = push_all(&traj, MetricSpec::Euclidean, gamma, &[1], gamma == 1.0).unwrap();
        check_final(&online, &traj, MetricSpec::Euclidean, gamma).unwrap();
    }
}

/// A push reuses the stretches of an earlier walk of the ball hierarchy while the pose stays
/// near that walk's centre (the leaves pushed since appended, stretches found far carried by
/// path length), and walks again when it leaves, when the rounding margin grows or when the
/// carried stretches pile up. A drive that takes every one of these ways, on the integer
/// lattice so that many pairs lie at exactly γ: laps of a square and a parallel one exactly γ
/// off, a stop, jumps far beyond γ and to exactly γ, slow circles whose far side is just within
/// γ, laps of a small square within γ of each other (the run ending on the diagonal holds the
/// last pose's point again and again), a stay a million metres away (the margin grows tenfold)
/// and a way back over the laps. Every row, closest columns included, against the brute
/// force's, and the snapshot against the batch.
#[test]
fn carried_stretches_take_every_way_and_stay_exact() {
    let gamma = 10.0;
    let mut points: Vec<[f64; 2]> = Vec::new();
    let square = |side: f64, x0: f64, y0: f64| -> Vec<[f64; 2]> {
        let s = side as usize;
        (0..4 * s)
            .map(|k| {
                let t = (k % s) as f64;
                match k / s {
                    0 => [x0 + t, y0],
                    1 => [x0 + side, y0 + t],
                    2 => [x0 + side - t, y0 + side],
                    _ => [x0, y0 + side - t],
                }
            })
            .collect()
    };
    points.extend(square(40.0, 0.0, 0.0));
    points.extend(square(40.0, 0.0, 0.0));
    // A lap exactly γ inside the first (its corners γ√2 off), entered by one jump of γ.
    points.extend(square(20.0, 10.0, 10.0));
    // A stop of 300 poses, then a jump of 1000 γ and back, then one of exactly γ.
    points.extend(std::iter::repeat_n([10.0, 10.0], 300));
    points.extend(std::iter::repeat_n([10_010.0, 10.0], 20));
    points.push([10.0, 10.0]);
    points.push([16.0, 18.0]);
    // Slow circles of radius 4.7 around (20, 20): their far side is within γ but not within the
    // carried walk's inner reach.
    points.extend((0..700).map(|k| {
        let angle = std::f64::consts::TAU * k as f64 / 70.0;
        [20.0 + 4.7 * angle.cos(), 20.0 + 4.7 * angle.sin()]
    }));
    // Laps of a square of side 4, all within γ of each other, with a stop in each: the run
    // that ends on the diagonal holds earlier poses at the very point of the last one, and its
    // closest column is the earliest of them.
    for _ in 0..6 {
        points.extend(square(4.0, 50.0, 50.0));
        points.extend(std::iter::repeat_n([54.0, 54.0], 5));
    }
    // A stay far away, where the rounding margin is larger, then back over the laps.
    points.extend((0..100).map(|k| [1e6 + k as f64, 1e6]));
    points.extend(square(40.0, 0.0, 10.0));
    points.extend(square(40.0, 0.0, 0.0));
    let times: Vec<f64> = (0..points.len()).map(|k| k as f64 * 0.1).collect();
    let traj = Trajectory::from_points(times, &points).unwrap();
    let dim = traj.dim();
    for chunk in [1, 5] {
        let mut online = OnlineLoops::new(MetricSpec::Euclidean, dim, gamma).unwrap();
        for first in (0..traj.len()).step_by(chunk) {
            let end = (first + chunk).min(traj.len());
            let update =
                online.push_many(&traj.timestamps_s()[first..end], &traj.coords()[first * dim..end * dim]).unwrap();
            for n in first..end {
                let row: Vec<(Run, usize)> =
                    update.runs.iter().filter(|r| r.row == n).map(|r| (r.run, r.closest)).collect();
                assert_eq!(row, brute_row(&traj, &MetricSpec::Euclidean, gamma, n), "row {n}, pushes of {chunk}");
            }
        }
        check_final(&online, &traj, MetricSpec::Euclidean, gamma).unwrap();
    }
}

#[test]
fn bad_poses_are_refused_naming_the_pose_and_change_nothing() {
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, 2, 1.0).unwrap();
    online.push(0.0, &[0.0, 0.0]).unwrap();
    online.push(1.0, &[0.5, 0.0]).unwrap();
    let before = online.clone().to_loops().unwrap();
    let error = online.push(1.0, &[1.0, 0.0]).unwrap_err();
    assert_eq!(error, Error::TimestampsNotIncreasing { index: 2, previous_s: 1.0, value_s: 1.0 });
    assert!(error.to_string().contains("index 2"), "{error}");
    let error = online.push_many(&[2.0, 3.0, 3.0], &[0.0; 6]).unwrap_err();
    assert_eq!(error, Error::TimestampsNotIncreasing { index: 4, previous_s: 3.0, value_s: 3.0 });
    let error = online.push_many(&[2.0, 3.0], &[0.0, 0.0, f64::NAN, 1.0]).unwrap_err();
    assert_eq!(error.to_string(), "coordinate 0 of pose 3 is not finite (NaN)");
    assert!(matches!(online.push(2.0, &[0.0]), Err(Error::RaggedCoordinates { .. })));
    assert!(matches!(online.push_many(&[2.0], &[0.0; 4]), Err(Error::LengthMismatch { .. })));
    assert!(matches!(online.push(f64::NAN, &[0.0, 0.0]), Err(Error::NonFiniteTimestamp { index: 2, .. })));
    assert_eq!(online.len(), 2);
    assert!(online.to_loops().unwrap() == before);
    // The metric's checks, named by the pose too.
    let se3 = MetricSpec::Se3(Se3 { rotation_weight_m_per_rad: 1.0, rotation: RotationDistance::Geodesic });
    let mut poses = OnlineLoops::new(se3, 7, 1.0).unwrap();
    poses.push(0.0, &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]).unwrap();
    let error = poses.push(1.0, &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0]).unwrap_err();
    assert!(matches!(error, Error::NonUnitQuaternion { index: 1, .. }), "{error}");
    assert!(OnlineLoops::new(se3, 3, 1.0).is_err());
    assert!(matches!(OnlineLoops::new(MetricSpec::Euclidean, 2, 0.0), Err(Error::InvalidGamma(_))));
    assert_eq!(poses.len(), 1);
    assert!(matches!(poses.to_loops(), Err(Error::TooFewPoses { count: 1 })));
    assert!(poses.trajectory().is_none());
    assert!(matches!(poses.loop_duration_s(1), Err(Error::IndexOutOfRange { index: 1, len: 1 })));
    // A rebuild with points of another dimension is refused.
    assert!(poses.rebuild(&line(&[0.0, 1.0])).is_err());
    poses.clear();
    assert!(poses.is_empty() && poses.rebuild_count() == 1);
}

#[test]
fn updates_name_creations_extensions_and_merges() {
    // A walk on a small lattice, with jumps: it comes back often, from several sides.
    let mut rng = Lcg(19);
    let mut position = [0.0, 0.0];
    let mut points = Vec::new();
    for k in 0..1500 {
        if k % 97 == 0 {
            position = [(rng.next() * 12.0).floor(), (rng.next() * 12.0).floor()];
        } else {
            let axis = usize::from(rng.next() < 0.5);
            position[axis] = (position[axis] + if rng.next() < 0.5 { 1.0 } else { -1.0 }).clamp(0.0, 12.0);
        }
        points.push(position);
    }
    let traj = Trajectory::from_points((0..points.len()).map(|k| k as f64 * 0.2).collect(), &points).unwrap();
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, 2, 1.0).unwrap();
    let (mut created, mut extended, mut merged) = (0, 0, 0);
    for n in 0..traj.len() {
        let before: Vec<ComponentId> = online.components().map(|(id, _)| id).collect();
        let next_id = online.components().map(|(id, _)| id + 1).chain(before.iter().map(|&id| id + 1)).max();
        let update = online.push(traj.timestamps_s()[n], traj.point(n)).unwrap();
        check_update(&before, &online, &update).unwrap();
        // New ids come in order, after every id given before.
        for (k, &id) in update.created.iter().enumerate() {
            assert!(next_id.is_none_or(|next| id >= next) && (k == 0 || id == update.created[k - 1] + 1));
        }
        assert!(update.merged.iter().all(|m| m.pose == n));
        // Every run of the row names the component it is in now.
        for run in &update.runs {
            assert_eq!(online.resolve(run.component), run.component);
        }
        (created, extended, merged) =
            (created + update.created.len(), extended + update.extended.len(), merged + update.merged.len());
    }
    assert!(created > 10 && extended > 100 && merged > 10, "{created} created, {extended} extended, {merged} merged");
    check_final(&online, &traj, MetricSpec::Euclidean, 1.0).unwrap();
}

// =============================================================================================
// Real data
// =============================================================================================

/// `../shared/data` beside the checkout, or `None` (with a message) when it is absent.
fn real_data(file: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data").join(file);
    if path.exists() {
        Some(path)
    } else {
        eprintln!("skipped: {} is absent (real data lives in ../shared/data)", path.display());
        None
    }
}

/// Numbers per line of a text file.
fn rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|line| line.split_whitespace().filter_map(|w| w.parse().ok()).collect::<Vec<f64>>())
        .filter(|row| !row.is_empty())
        .collect()
}

/// Pushes every pose of a real trajectory (in batches of 1 and 10 alternately, as a front end
/// that sometimes lags), then compares with the batch.
fn check_real(traj: &Trajectory, gamma: f64) {
    let online = push_all(traj, MetricSpec::Euclidean, gamma, &[1, 10], false).unwrap();
    check_final(&online, traj, MetricSpec::Euclidean, gamma).unwrap();
    eprintln!("{} poses, {} components: online equals the batch", traj.len(), online.components().count());
}

#[test]
fn kitti_00() {
    let Some(path) = real_data("kitti_odometry/00.txt") else { return };
    let rows = rows(&path);
    // Time, then the 3 × 4 [R | t] of camera 0 row-major: the ground plane is x–z.
    let times = rows.iter().map(|r| r[0]).collect();
    let points: Vec<[f64; 2]> = rows.iter().map(|r| [r[4], r[12]]).collect();
    check_real(&Trajectory::from_points(times, &points).unwrap(), 6.0);
}

#[test]
fn tuc_corridor() {
    let Some(path) = real_data("tuc/SLAM/Corridor_GT.txt") else { return };
    let text = std::fs::read_to_string(path).unwrap();
    let (mut times, mut points) = (Vec::new(), Vec::new());
    for line in text.lines().filter(|l| l.starts_with("point2")) {
        let v: Vec<f64> = line.split_whitespace().skip(1).filter_map(|w| w.parse().ok()).collect();
        times.push(v[0]);
        points.push([v[1], v[2]]);
    }
    check_real(&Trajectory::from_points(times, &points).unwrap(), 0.3);
}

#[test]
fn mulran_kaist_01() {
    let Some(path) = real_data("mulran_kaist/kaist01_localization_poses01_seq02asmap.txt") else { return };
    let rows = rows(&path);
    // No timestamps: 10 Hz.
    let times = (0..rows.len()).map(|k| k as f64 * 0.1).collect();
    let points: Vec<[f64; 3]> = rows.iter().map(|r| [r[3], r[7], r[11]]).collect();
    check_real(&Trajectory::from_points(times, &points).unwrap(), 10.0);
}

#[test]
fn an_interrupted_push_many_keeps_the_poses_before_it() {
    let traj = loops_core::UrbanDrive { duration_s: 120.0, ..loops_core::UrbanDrive::default() }
        .generate()
        .unwrap()
        .trajectory;
    let dim = traj.dim();
    let mut online = OnlineLoops::new(MetricSpec::Euclidean, dim, 20.0).unwrap();
    online.push_many(&traj.timestamps_s()[..50], &traj.coords()[..50 * dim]).unwrap();
    let before = online.to_loops().unwrap();
    // Interrupted before the first pose of the batch: none of it is added.
    let stop = loops_core::Interrupt::new();
    stop.interrupt();
    let rest = (&traj.timestamps_s()[50..], &traj.coords()[50 * dim..]);
    assert_eq!(stop.run(|| online.push_many(rest.0, rest.1)), Err(Error::Interrupted));
    assert_eq!(online.len(), 50);
    assert_eq!(online.to_loops().unwrap(), before);
    // And it goes on as if nothing had been asked.
    online.push_many(rest.0, rest.1).unwrap();
    assert_eq!(online.to_loops().unwrap(), loops_core::find_loops(&traj, &loops_core::Euclidean, 20.0).unwrap());
}
