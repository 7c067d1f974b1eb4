//! `SublevelSet::compute` (arc-length skipping) against a dense matrix of every pair, on inputs
//! built to be nasty for the skipping bounds: steps beyond γ, points exactly γ apart, repeated
//! points, stationary stretches with 1e-9 jitter, back and forth, far-off coordinates.

mod support;

use loops_core::{Euclidean, Metric, Run, Separation, SublevelSet, Trajectory, find_loops, with_threads};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;
use support::{Case, DenseSet, any_case, config, float_case, lattice_case};

/// The engine's set equals the dense matrix cell by cell, and equals `brute_force`.
fn check_set(case: &Case) -> Result<(), TestCaseError> {
    let Case { traj, gamma, .. } = case;
    let n = traj.len();
    let set = SublevelSet::compute(traj, &Euclidean, *gamma)?;
    let dense = DenseSet::new(traj, *gamma);
    prop_assert_eq!(set.rows(), n);
    prop_assert_eq!(set.gamma(), *gamma);
    let mut run_index = 0;
    for i in 0..n {
        let expected = dense.upper_runs(i);
        prop_assert_eq!(set.row(i), expected.as_slice(), "row {}", i);
        prop_assert_eq!(set.row(i)[0].start as usize, i, "row {} starts off the diagonal", i);
        for j in 0..n {
            prop_assert_eq!(set.contains(i, j), dense.at(i, j), "contains({}, {})", i, j);
        }
        // Closest column of each run: the argmin of δ over the run, ties to the earliest.
        for run in set.row(i) {
            let cells = run.start as usize..=run.end as usize;
            let best = cells.clone().map(|j| dense.delta(i, j)).fold(f64::INFINITY, f64::min);
            let first = cells.clone().find(|&j| dense.delta(i, j) == best);
            let closest = set.closest_columns()[run_index] as usize;
            prop_assert_eq!(Some(closest), first, "closest column of row {} run {:?}", i, run);
            run_index += 1;
        }
    }
    prop_assert_eq!(run_index, set.runs().len());
    prop_assert_eq!(set.upper_pairs(), (0..n).map(|i| (i..n).filter(|&j| dense.at(i, j)).count() as u64).sum::<u64>());
    let brute = SublevelSet::brute_force(traj, &Euclidean, *gamma)?;
    prop_assert_eq!(&set, &brute);
    Ok(())
}

/// One thread and two threads give the same set and the same loops.
fn check_threads(case: &Case) -> Result<(), TestCaseError> {
    let Case { traj, gamma, .. } = case;
    let one = with_threads(Some(1), || SublevelSet::compute(traj, &Euclidean, *gamma))??;
    let two = with_threads(Some(2), || SublevelSet::compute(traj, &Euclidean, *gamma))??;
    prop_assert_eq!(&one, &two);
    let one = with_threads(Some(1), || find_loops(traj, &Euclidean, *gamma))??;
    let two = with_threads(Some(2), || find_loops(traj, &Euclidean, *gamma))??;
    prop_assert_eq!(one, two);
    Ok(())
}

proptest! {
    #![proptest_config(config(256, 0x5EED_0001))]

    #[test]
    fn float_walks_equal_the_dense_matrix(case in float_case(400)) {
        check_set(&case)?;
    }

    #[test]
    fn lattice_walks_equal_the_dense_matrix(case in lattice_case(400)) {
        check_set(&case)?;
    }

    #[test]
    fn one_and_two_threads_agree(case in any_case(400)) {
        check_threads(&case)?;
    }
}

proptest! {
    #![proptest_config(config(12, 0x5EED_0003))]

    /// Paths long enough for many far-field stretches and many rayon tasks.
    #[test]
    fn long_walks_equal_the_brute_force(case in any_case(2500)) {
        let Case { traj, gamma, .. } = &case;
        let set = with_threads(Some(2), || SublevelSet::compute(traj, &Euclidean, *gamma))??;
        let brute = SublevelSet::brute_force(traj, &Euclidean, *gamma)?;
        for i in 0..traj.len() {
            prop_assert_eq!(set.row(i), brute.row(i), "row {}", i);
        }
        prop_assert_eq!(&set, &brute);
    }
}

fn line(xs: &[f64]) -> Trajectory {
    Trajectory::new((0..xs.len()).map(|i| i as f64).collect(), xs.to_vec(), 1).unwrap()
}

/// Rows longer than one rayon task (64 rows) with thousands of exact revisits and ties at γ.
#[test]
fn long_lattice_back_and_forth_across_tasks() {
    let xs: Vec<f64> = (0..700).map(|k| f64::from((k % 7) - 3)).collect();
    let traj = line(&xs);
    for gamma in [1.0, 2.0, 3.0] {
        let dense = DenseSet::new(&traj, gamma);
        let set = with_threads(Some(2), || SublevelSet::compute(&traj, &Euclidean, gamma)).unwrap().unwrap();
        for i in 0..traj.len() {
            assert_eq!(set.row(i), dense.upper_runs(i).as_slice(), "γ {gamma}, row {i}");
        }
    }
}

/// Values the arithmetic cannot hold are refused, naming pose and value: coordinates of 1e155
/// (their squared differences overflow to ∞, which once dropped pairs) and timestamps near
/// f64's limit (an infinite span and NaN areas). At the largest magnitude accepted the scan
/// still equals the brute force, and spans and areas are finite.
#[test]
fn magnitudes_beyond_the_arithmetic_are_refused() {
    use loops_core::{Error, MAX_MAGNITUDE, Scale, Selection, Side};
    let refused = Trajectory::new(vec![0.0, 1.0, 2.0], vec![0.0, 1e155, 0.0], 1).unwrap_err();
    assert!(
        matches!(refused, Error::CoordinateTooLarge { index: 1, axis: 0, value, .. } if value == 1e155),
        "{refused}"
    );
    assert!(refused.to_string().contains("pose 1"), "{refused}");
    let refused = Trajectory::new(vec![-1.7e308, 0.0, 1.7e308], vec![0.0, 1.0, 2.0], 1).unwrap_err();
    assert!(matches!(refused, Error::TimestampTooLarge { index: 0, .. }), "{refused}");

    let traj = line(&[0.0, MAX_MAGNITUDE, -MAX_MAGNITUDE, 0.0, MAX_MAGNITUDE]);
    for gamma in [1.0, 1.5 * MAX_MAGNITUDE, 2.0 * MAX_MAGNITUDE] {
        let set = SublevelSet::compute(&traj, &Euclidean, gamma).unwrap();
        assert_eq!(set, SublevelSet::brute_force(&traj, &Euclidean, gamma).unwrap(), "γ {gamma}");
    }
    let times = vec![-MAX_MAGNITUDE, 0.0, MAX_MAGNITUDE];
    let wide = Trajectory::new(times, vec![0.0, 0.5, 0.0], 1).unwrap();
    let loops = find_loops(&wide, &Euclidean, 1.0).unwrap();
    let (a, b) = (-MAX_MAGNITUDE, MAX_MAGNITUDE);
    let alpha = loops.loop_area(a, b, Selection::All, Side::Both, Scale::Seconds).unwrap();
    assert!(alpha.is_finite() && alpha > 0.0, "{alpha}");
    assert!(loops.loop_duration(Selection::All, Side::Both, Scale::Seconds).unwrap().iter().all(|t| t.is_finite()));
}

/// Two cells of one run whose squared distances differ by one ulp but whose δ (after the square
/// root) are equal: the closest column is the argmin of the metric's rank (δ² here), so the one
/// exactly at 5 wins, in the brute force and the scan alike.
#[test]
fn closest_column_follows_the_metric_rank() {
    // δ²(0, 2) = 25 + 1 ulp, δ²(0, 3) = 25; both δ round to 5.
    let y = 6e-8;
    let points = [[0.0, 0.0], [10.0, 0.0], [5.0, y], [3.0, 4.0]];
    let traj = Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0], &points).unwrap();
    let (near, exact) = (traj.point(2), traj.point(3));
    assert_eq!(Euclidean.distance(traj.point(0), near), 5.0);
    assert_eq!(Euclidean.distance(traj.point(0), exact), 5.0);
    assert!(Euclidean.distance_rank(traj.point(0), near) > 25.0);
    let brute = SublevelSet::brute_force(&traj, &Euclidean, 5.5).unwrap();
    let set = SublevelSet::compute(&traj, &Euclidean, 5.5).unwrap();
    assert_eq!(set.row(0), &[Run { start: 0, end: 0 }, Run { start: 2, end: 3 }]);
    assert_eq!(brute.closest_columns()[1], 3);
    assert_eq!(set.closest_columns()[1], 3, "the smaller δ², though δ is equal");
    let loops = loops_core::find_loops(&traj, &Euclidean, 5.5).unwrap();
    let component = &loops.components()[loops.component_of(0, 3).unwrap()];
    assert_eq!(
        component.closest_distance,
        0.0_f64.max(Euclidean.distance(traj.point(component.closest_pair[0]), traj.point(component.closest_pair[1])))
    );
}

/// A robot that parks: stretches of hundreds of poses at one place (exactly, with 1e-9 jitter,
/// or scattered within a fraction of γ), joined by drives. Long runs take the hierarchy's whole
/// stretches and its closest-column search; both must give the brute force's set, closest
/// columns included.
fn parked_case() -> impl Strategy<Value = (Trajectory, f64)> {
    let stop = (0usize..4, 150usize..700, 0usize..3, any::<u64>());
    (proptest::collection::vec(stop, 1..5), 0.5f64..4.0).prop_map(|(stops, gamma)| {
        let (mut xs, mut state) = (Vec::new(), 0x9E37_79B9_u64);
        for (place, len, noise, seed) in stops {
            state ^= seed;
            let centre = [place as f64 * 3.0, (place % 2) as f64 * 1.5];
            let spread = [0.0, 1e-9, 0.3 * gamma][noise];
            // Drive there straight, in steps of γ/37: stretches of the hierarchy then end at every
            // distance from a stop, some just beyond γ.
            let from = xs.last().copied().unwrap_or(centre);
            let steps = (((centre[0] - from[0]).hypot(centre[1] - from[1])) / (gamma / 37.0)).ceil() as usize;
            for k in 1..=steps {
                let f = k as f64 / steps as f64;
                xs.push([from[0] + f * (centre[0] - from[0]), from[1] + f * (centre[1] - from[1])]);
            }
            for _ in 0..len {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let (u, v) = ((state >> 11) as f64 / (1u64 << 53) as f64, (state >> 3 & 0xffff) as f64 / 65536.0);
                xs.push([centre[0] + spread * (u - 0.5), centre[1] + spread * (v - 0.5)]);
            }
        }
        let times = (0..xs.len()).map(|i| i as f64 * 0.1).collect();
        (Trajectory::from_points(times, &xs).unwrap(), gamma)
    })
}

proptest! {
    #![proptest_config(config(24, 0x5EED_0004))]

    #[test]
    fn parked_robots_equal_the_brute_force((traj, gamma) in parked_case()) {
        let set = with_threads(Some(2), || SublevelSet::compute(&traj, &Euclidean, gamma))??;
        let brute = SublevelSet::brute_force(&traj, &Euclidean, gamma)?;
        for i in 0..traj.len() {
            prop_assert_eq!(set.row(i), brute.row(i), "row {}", i);
        }
        prop_assert_eq!(set.closest_columns(), brute.closest_columns());
        prop_assert_eq!(&set, &brute);
    }
}

/// A million identical poses: one component in n runs (row i: columns i..n), found without
/// measuring every pair.
#[test]
fn a_parked_robot_is_one_component() {
    let n = 1_000_000;
    let traj = Trajectory::from_points((0..n).map(|i| i as f64 * 0.1).collect(), &vec![[1.0, 2.0]; n]).unwrap();
    let set = SublevelSet::compute(&traj, &Euclidean, 1.0).unwrap();
    assert_eq!(set.runs().len(), n);
    assert!((0..n).all(|i| set.row(i) == [Run { start: i as u32, end: (n - 1) as u32 }]));
    assert!(set.closest_columns().iter().enumerate().all(|(i, &c)| c as usize == i));
    let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
    assert_eq!(loops.components().len(), 1);
    assert_eq!(loops.components()[0].closest_distance, 0.0);
}

/// The Euclidean metric, counting the distances the scan measures (`distance`) and those the
/// closest columns rank (`distance_rank`, `closest_in`: one per cell) apart.
#[derive(Default)]
struct Counting {
    distances: std::sync::atomic::AtomicU64,
    ranks: std::sync::atomic::AtomicU64,
}

impl Counting {
    fn take(&self) -> (u64, u64) {
        use std::sync::atomic::Ordering::Relaxed;
        (self.distances.swap(0, Relaxed), self.ranks.swap(0, Relaxed))
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
        self.distances.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Euclidean.distance(a, b)
    }
    fn rounding_scale(&self, traj: &Trajectory) -> f64 {
        Euclidean.rounding_scale(traj)
    }
    fn distance_rank(&self, a: &[f64], b: &[f64]) -> f64 {
        self.ranks.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Euclidean.distance_rank(a, b)
    }
    fn closest_in(&self, x: &[f64], points: &[f64]) -> usize {
        self.ranks.fetch_add((points.len() / x.len()) as u64, std::sync::atomic::Ordering::Relaxed);
        Euclidean.closest_in(x, points)
    }
}

/// The separated set equals the dense matrix restricted to pairs far enough apart and the
/// brute force, and its scan measures no distance that the unseparated scan does not (each
/// row starts at its first separated column, and from a later column the bounds jump at
/// least as far), but for the one distance that the closest-column search may measure in each
/// run off the diagonal (a run clipped off the diagonal is searched where it was not).
fn check_separated_set(case: &Case, separation: Separation) -> Result<(), TestCaseError> {
    let Case { traj, gamma, .. } = case;
    let counting = Counting::default();
    let set = with_threads(Some(1), || SublevelSet::compute(traj, &counting, *gamma))??;
    let (scan, _) = counting.take();
    let separated = with_threads(Some(1), || SublevelSet::compute_separated(traj, &counting, *gamma, separation))??;
    let (separated_scan, _) = counting.take();
    let searches = separated.runs().len() as u64;
    prop_assert!(
        separated_scan <= scan + searches,
        "{} distances separated, {} without, {} runs ({})",
        separated_scan,
        scan,
        searches,
        separation
    );
    let dense = DenseSet::separated(traj, *gamma, separation);
    for i in 0..traj.len() {
        let expected = dense.upper_runs(i);
        prop_assert_eq!(separated.row(i), expected.as_slice(), "row {} ({})", i, separation);
        // Clipped where produced: a subset of the row of S_γ.
        for run in separated.row(i) {
            prop_assert!(set.contains(i, run.start as usize) && set.contains(i, run.end as usize));
        }
    }
    prop_assert_eq!(&separated, &SublevelSet::brute_force_separated(traj, &Euclidean, *gamma, separation)?);
    Ok(())
}

fn separation() -> impl Strategy<Value = Separation> {
    prop_oneof![
        (0.0..40.0f64).prop_map(Separation::path),
        (0.0..40.0f64).prop_map(Separation::time_s),
        (0.0..20.0f64, 0.0..20.0f64).prop_map(|(path, time_s)| Separation { path, time_s }),
    ]
}

proptest! {
    #![proptest_config(config(256, 0x5EED_0015))]

    #[test]
    fn separated_sets_equal_the_dense_matrix(case in any_case(400), separation in separation()) {
        check_separated_set(&case, separation)?;
    }
}

/// The urban drive (real-sized: 6,000 poses, γ = 40 m): the default separation measures fewer
/// distances than S_γ's scan, ranks only the cells of runs it clips off the diagonal, and finds
/// the same components as the brute force.
#[test]
fn separation_on_the_urban_drive_measures_fewer_distances() {
    let traj = loops_core::UrbanDrive { duration_s: 600.0, ..Default::default() }.generate().unwrap().trajectory;
    let gamma = loops_core::UrbanDrive::DEFAULT_GAMMA_M;
    let counting = Counting::default();
    let all = SublevelSet::compute(&traj, &counting, gamma).unwrap();
    let (scan, ranks) = counting.take();
    let separation = Separation::for_gamma(gamma);
    let revisits = SublevelSet::compute_separated(&traj, &counting, gamma, separation).unwrap();
    let (separated_scan, separated_ranks) = counting.take();
    assert!(separated_scan < scan, "{separated_scan} vs {scan}");
    let clipped_cells: u64 = revisits.runs().iter().map(|r| r.len() as u64).sum();
    assert!(separated_ranks <= ranks + clipped_cells, "{separated_ranks} ranks vs {ranks} + {clipped_cells}");
    assert!(revisits.upper_pairs() < all.upper_pairs());
    assert_eq!(revisits, SublevelSet::brute_force_separated(&traj, &Euclidean, gamma, separation).unwrap());
}

/// A drive long enough for several row batches, labelling stretches cut by their runs and a
/// dense part: the same loops (runs, closest columns, labels, components) and the same τ on 1,
/// 2 and 3 threads.
#[test]
fn a_drive_is_the_same_on_one_two_and_three_threads() {
    use loops_core::{Scale, Selection, Side, UrbanDrive};
    let dense = UrbanDrive { duration_s: 600.0, city_size_m: 200.0, ..UrbanDrive::default() }.generate().unwrap();
    let drive = UrbanDrive { duration_s: 1800.0, ..UrbanDrive::default() }.generate().unwrap();
    let (dense, drive) = (dense.trajectory, drive.trajectory);
    let t0 = dense.timestamps_s()[dense.len() - 1] + 0.1;
    let mut times = dense.timestamps_s().to_vec();
    times.extend(drive.timestamps_s().iter().map(|t| t0 + t));
    let coords = [dense.coords(), drive.coords()].concat();
    let traj = Trajectory::new(times, coords, dense.dim()).unwrap();
    let run = |threads| {
        with_threads(Some(threads), || {
            let loops = find_loops(&traj, &Euclidean, 40.0).unwrap();
            let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds).unwrap();
            (loops, tau)
        })
        .unwrap()
    };
    let one = run(1);
    assert!(one.0.sublevel_set().runs().len() > 50_000, "runs enough for many stretches");
    for threads in [2, 3] {
        let other = run(threads);
        assert!(one.0 == other.0, "{threads} threads: the loops differ");
        assert!(one.1 == other.1, "{threads} threads: tau differs");
    }
}
