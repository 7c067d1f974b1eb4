//! Detections and the ε graph: `cluster_detections` against a brute-force union-find over every
//! pair (O(n²), written from the definition), on random and adversarial sets; independence of the
//! input order and of the thread count; uniform draws from S_γ; bad input.

use loops_core::{
    Detections, Error, Euclidean, Loops, SampleSize, Trajectory, UrbanDrive, cluster_detections, find_loops,
    with_threads,
};
use proptest::prelude::*;

mod support;
use support::{brute_force_clusters, canonical, config};

/// Clusters (t, t′) points (already ordered t ≤ t′ or not) and checks everything checkable.
fn check(t: Vec<f64>, t_prime: Vec<f64>, epsilon: f64) -> Result<(), TestCaseError> {
    let det = Detections::new(t, t_prime)?;
    let clusters = cluster_detections(&det, epsilon)?;
    let expected = brute_force_clusters(det.t_s(), det.t_prime_s(), epsilon);
    prop_assert_eq!(canonical(clusters.labels()), expected, "partition differs from brute force");
    // Cluster statistics agree with the labels.
    for c in clusters.clusters() {
        let members: Vec<usize> = (0..det.len()).filter(|&k| clusters.labels()[k] as usize == c.id).collect();
        prop_assert_eq!(c.size, members.len());
        let extent = |v: &[f64]| {
            members.iter().fold([f64::INFINITY, f64::NEG_INFINITY], |e, &k| [e[0].min(v[k]), e[1].max(v[k])])
        };
        prop_assert_eq!(c.t_s, extent(det.t_s()));
        prop_assert_eq!(c.t_prime_s, extent(det.t_prime_s()));
        prop_assert!(c.cells >= 1 && c.area_proxy_s2 > 0.0);
        prop_assert_eq!(clusters.labels()[c.anchor] as usize, c.id);
    }
    // Ids follow the smallest point of each cluster.
    let anchors: Vec<(f64, f64)> =
        clusters.clusters().iter().map(|c| (det.t_s()[c.anchor], det.t_prime_s()[c.anchor])).collect();
    prop_assert!(anchors.windows(2).all(|w| w[0] < w[1]), "ids not in order of smallest point");
    Ok(())
}

/// A fixed pseudo-random permutation of 0..n.
fn permutation(n: usize, seed: u64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    let mut state = seed;
    for k in (1..n).rev() {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        order.swap(k, (state >> 33) as usize % (k + 1));
    }
    order
}

fn point_sets() -> impl Strategy<Value = (Vec<(f64, f64)>, f64)> {
    let scattered = (1usize..300, 1.0f64..2000.0, 0.5f64..80.0)
        .prop_flat_map(|(n, extent, eps)| (prop::collection::vec((0.0..extent, 0.0..extent), n), Just(eps)));
    // Points on a lattice of step ε·k/2 (k = 1, 2, 3): exact ties at ε, diagonals, duplicates.
    let lattice =
        (1usize..200, 1u32..4, prop::sample::select(vec![1.0, 30.0, 0.1, 7.3])).prop_flat_map(|(n, k, eps)| {
            let step = eps * f64::from(k) / 2.0;
            (prop::collection::vec((0i32..12, 0i32..12), n), Just(step), Just(eps)).prop_map(|(cells, step, eps)| {
                (cells.into_iter().map(|(a, b)| (f64::from(a) * step, f64::from(b) * step)).collect(), eps)
            })
        });
    // Clumps: many near-duplicates around a few centres, spread from 0 to 1.5ε.
    let clumps = (1usize..6, 1usize..120, 5.0f64..50.0).prop_flat_map(|(centres, n, eps)| {
        (
            prop::collection::vec((0.0..20.0 * eps, 0.0..20.0 * eps), centres),
            prop::collection::vec((0usize..6, -0.75f64..0.75, -0.75f64..0.75), n),
            Just(eps),
        )
            .prop_map(|(centres, offsets, eps)| {
                let points = offsets
                    .into_iter()
                    .map(|(c, dx, dy)| {
                        let (x, y) = centres[c % centres.len()];
                        (x + dx * eps, y + dy * eps)
                    })
                    .collect();
                (points, eps)
            })
    });
    prop_oneof![scattered, lattice, clumps]
}

proptest! {
    #![proptest_config(config(256, 0x5EED_0401))]

    #[test]
    fn partition_equals_brute_force_clusters((points, eps) in point_sets()) {
        let (t, t_prime): (Vec<f64>, Vec<f64>) = points.into_iter().unzip();
        check(t, t_prime, eps)?;
    }

    #[test]
    fn invariant_under_permutation((points, eps) in point_sets(), seed in any::<u64>()) {
        let (t, t_prime): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
        let clusters = cluster_detections(&Detections::new(t.clone(), t_prime.clone())?, eps)?;
        let order = permutation(t.len(), seed);
        let shuffled = Detections::new(order.iter().map(|&k| t[k]).collect(), order.iter().map(|&k| t_prime[k]).collect())?;
        let other = cluster_detections(&shuffled, eps)?;
        // The same ids, not only the same partition.
        for (position, &k) in order.iter().enumerate() {
            prop_assert_eq!(other.labels()[position], clusters.labels()[k]);
        }
        prop_assert_eq!(other.len(), clusters.len());
        for (a, b) in clusters.clusters().iter().zip(other.clusters()) {
            prop_assert_eq!((a.size, a.t_s, a.t_prime_s, a.cells), (b.size, b.t_s, b.t_prime_s, b.cells));
        }
    }
}

#[test]
fn grid_exactly_epsilon_apart() {
    for eps in [1.0, 30.0, 0.1, 1e-3, 7.3] {
        let n = 25;
        let mut t = Vec::new();
        let mut t_prime = Vec::new();
        for a in 0..n {
            for b in 0..n {
                t.push(a as f64 * eps);
                t_prime.push(1e4 + b as f64 * eps);
            }
        }
        let det = Detections::new(t.clone(), t_prime.clone()).unwrap();
        let clusters = cluster_detections(&det, eps).unwrap();
        assert_eq!(canonical(clusters.labels()), brute_force_clusters(det.t_s(), det.t_prime_s(), eps), "eps {eps}");
        // Whether the grid is one cluster depends only on the f64 test (a · ε − b · ε vs ε).
        check(t, t_prime, eps).unwrap();
    }
}

#[test]
fn points_a_hair_from_epsilon() {
    for (factor, joined) in [(1.0 + 1e-12, false), (1.0 - 1e-12, true), (1.0, true)] {
        for eps in [30.0, 1.0, 0.37] {
            let step = eps * factor;
            // A line along t, along t′, and a diagonal line (ε/√2 per axis).
            let d = step / std::f64::consts::SQRT_2;
            let lines: [(Vec<f64>, Vec<f64>); 3] = [
                ((0..50).map(|k| 100.0 + k as f64 * step).collect(), vec![5000.0; 50]),
                (vec![100.0; 50], (0..50).map(|k| 5000.0 + k as f64 * step).collect()),
                ((0..50).map(|k| 100.0 + k as f64 * d).collect(), (0..50).map(|k| 5000.0 + k as f64 * d).collect()),
            ];
            for (t, t_prime) in lines {
                let det = Detections::new(t.clone(), t_prime.clone()).unwrap();
                let clusters = cluster_detections(&det, eps).unwrap();
                assert_eq!(canonical(clusters.labels()), brute_force_clusters(&t, &t_prime, eps));
                if factor != 1.0 {
                    assert_eq!(clusters.len() == 1, joined, "factor {factor} eps {eps}: {} clusters", clusters.len());
                }
            }
        }
    }
}

#[test]
fn duplicates_and_one_huge_cluster() {
    // 3000 copies of one point, and 3000 points filling a 40ε × 40ε square densely: one cluster
    // each, and a lone point 1.01ε from the square's corner.
    let eps = 30.0;
    let mut t = vec![10.0; 3000];
    let mut t_prime = vec![20.0; 3000];
    let mut state = 7u64;
    for _ in 0..3000 {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (state >> 11) as f64 / (1u64 << 53) as f64;
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let v = (state >> 11) as f64 / (1u64 << 53) as f64;
        t.push(1000.0 + 40.0 * eps * u);
        t_prime.push(3000.0 + 40.0 * eps * v);
    }
    t.push(1000.0 - 1.01 * eps);
    t_prime.push(3000.0);
    let det = Detections::new(t.clone(), t_prime.clone()).unwrap();
    let clusters = cluster_detections(&det, eps).unwrap();
    assert_eq!(canonical(clusters.labels()), brute_force_clusters(&t, &t_prime, eps));
    assert_eq!(clusters.clusters()[0].size, 3000);
    assert_eq!(clusters.clusters()[0].cells, 1);
}

#[test]
fn epoch_timestamps() {
    // Unix times (1.7e9 s): the grid works on offsets from the smallest time.
    let base = 1.7e9;
    let t: Vec<f64> = (0..400).map(|k| base + (k % 20) as f64 * 29.0 + (k / 20) as f64 * 0.25).collect();
    let t_prime: Vec<f64> = (0..400).map(|k| base + 5000.0 + (k / 20) as f64 * 31.0).collect();
    check(t, t_prime, 30.0).unwrap();
}

#[test]
fn same_clusters_on_any_thread_count() {
    let drive = UrbanDrive { duration_s: 900.0, seed: 3, ..UrbanDrive::default() }.generate().unwrap();
    let loops = find_loops(&drive.trajectory, &Euclidean, 40.0).unwrap();
    let det = Detections::draw(&loops, SampleSize::Rate(0.02), 1).unwrap();
    let one = with_threads(Some(1), || cluster_detections(&det, 30.0)).unwrap().unwrap();
    let two = with_threads(Some(2), || cluster_detections(&det, 30.0)).unwrap().unwrap();
    assert_eq!(one, two);
    let again = with_threads(Some(2), || Detections::draw(&loops, SampleSize::Rate(0.02), 1)).unwrap().unwrap();
    assert_eq!(det, again);
}

// ---------------------------------------------------------------------------------------------
// Draws from S_γ
// ---------------------------------------------------------------------------------------------

fn drive_loops() -> (Trajectory, Loops) {
    let drive = UrbanDrive { duration_s: 600.0, seed: 11, ..UrbanDrive::default() }.generate().unwrap();
    let loops = find_loops(&drive.trajectory, &Euclidean, 40.0).unwrap();
    (drive.trajectory, loops)
}

/// Off-diagonal pairs (i < j) of S_γ per block of an 8 × 8 grid over (i, j), from the runs.
fn pairs_per_block(loops: &Loops, blocks: usize) -> Vec<u64> {
    let n = loops.len();
    let block_of = |k: usize| k * blocks / n;
    let mut counts = vec![0u64; blocks * blocks];
    for i in 0..n {
        for run in loops.sublevel_set().row(i) {
            for j in (run.start as usize).max(i + 1)..=run.end as usize {
                counts[block_of(i) * blocks + block_of(j)] += 1;
            }
        }
    }
    counts
}

#[test]
fn draws_are_inside_and_uniform() {
    let (_, loops) = drive_loops();
    let blocks = 8;
    let expected_share = pairs_per_block(&loops, blocks);
    let total: u64 = expected_share.iter().sum();
    for size in [SampleSize::Budget(20_000), SampleSize::Rate(0.01)] {
        let det = Detections::draw(&loops, size, 42).unwrap();
        let pairs = det.pairs().unwrap();
        let mut seen = std::collections::BTreeSet::new();
        let mut observed = vec![0u64; blocks * blocks];
        for (k, &[i, j]) in pairs.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            assert!(i < j, "diagonal or unordered pair {i}, {j}");
            assert!(loops.sublevel_set().contains(i, j), "pair ({i}, {j}) is not in S_gamma");
            assert_eq!((det.t_s()[k], det.t_prime_s()[k]), (loops.timestamps_s()[i], loops.timestamps_s()[j]));
            assert!(seen.insert((i, j)), "pair drawn twice");
            observed[i * blocks / loops.len() * blocks + j * blocks / loops.len()] += 1;
        }
        if let SampleSize::Budget(b) = size {
            assert_eq!(det.len(), b);
        } else {
            let mean = 0.01 * total as f64;
            assert!((det.len() as f64 - mean).abs() < 5.0 * mean.sqrt(), "{} drawn, {mean} expected", det.len());
        }
        // Chi-square over the non-empty blocks; 0.1% critical value for the degrees of freedom.
        let drawn = det.len() as f64;
        let mut chi2 = 0.0;
        let mut cells = 0;
        for (o, &e) in observed.iter().zip(&expected_share) {
            if e > 0 {
                let expected = drawn * e as f64 / total as f64;
                chi2 += (*o as f64 - expected).powi(2) / expected;
                cells += 1;
            } else {
                assert_eq!(*o, 0);
            }
        }
        let df = f64::from(cells - 1);
        // Wilson–Hilferty: the 99.9% quantile of chi-square with df degrees of freedom.
        let z = 3.09;
        let critical = df * (1.0 - 2.0 / (9.0 * df) + z * (2.0 / (9.0 * df)).sqrt()).powi(3);
        assert!(chi2 < critical, "chi-square {chi2:.1} over {cells} blocks (critical {critical:.1})");
    }
}

#[test]
fn draw_rejects_bad_sizes() {
    let (_, loops) = drive_loops();
    for rate in [0.0, -0.1, 1.5, f64::NAN] {
        assert!(matches!(
            Detections::draw(&loops, SampleSize::Rate(rate), 0),
            Err(Error::InvalidParameter { name: "rate", .. })
        ));
    }
    assert!(matches!(
        Detections::draw(&loops, SampleSize::Budget(0), 0),
        Err(Error::InvalidParameter { name: "budget", .. })
    ));
    let too_many = loops.pair_count() as usize;
    assert!(Detections::draw(&loops, SampleSize::Budget(too_many), 0).is_err());
    // A rate so small that nothing is drawn: an empty detection set is an error.
    assert_eq!(Detections::draw(&loops, SampleSize::Rate(1e-15), 0).unwrap_err(), Error::NoDetections);
}

#[test]
fn bad_detections_are_named() {
    let (traj, _) = drive_loops();
    assert_eq!(Detections::new(vec![], vec![]).unwrap_err(), Error::NoDetections);
    assert_eq!(Detections::from_indices(&traj, &[], &[]).unwrap_err(), Error::NoDetections);
    let err = Detections::new(vec![1.0, 2.0], vec![3.0]).unwrap_err();
    assert_eq!(err.to_string(), "t_prime_s has 1 values, but 2 are needed (one per detection)");
    let end = traj.timestamps_s()[traj.len() - 1];
    let err = Detections::new(vec![0.0, 10.0], vec![5.0, end + 1.0]).unwrap().locate(&traj).unwrap_err();
    assert!(matches!(err, Error::DetectionOutsideSpan { index: 1, .. }), "{err}");
    assert!(err.to_string().contains("outside the trajectory's time span"), "{err}");
    let err = Detections::new(vec![-0.5], vec![5.0]).unwrap().locate(&traj).unwrap_err();
    assert!(matches!(err, Error::DetectionOutsideSpan { index: 0, .. }));
    let err = Detections::from_indices(&traj, &[0, 1], &[2, traj.len()]).unwrap_err();
    assert_eq!(err, Error::PoseIndexOutOfRange { index: 1, pose: traj.len(), poses: traj.len() });
    let det = Detections::new(vec![0.0], vec![1.0]).unwrap();
    for eps in [0.0, -30.0, f64::INFINITY, f64::NAN] {
        let err = cluster_detections(&det, eps).unwrap_err();
        assert!(matches!(err, Error::InvalidParameter { name: "epsilon_s", .. }), "{err}");
    }
}
