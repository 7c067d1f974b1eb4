//! The paths of `cluster_detections`: the counting sort by cell (grids of at most about 4n
//! cells), the radix sort of cell keys (larger grids; a comparison sort up to 4,096 points) and
//! the comparison sort of `(cx, cy, detection)` (over 2³² cells) give the same clusters, ids
//! included; and the early exits of the cell-pair test (boxes, nearest points) agree with brute
//! force where they are sharpest: all points in one cell, duplicates, blobs exactly ε apart.
//!
//! A far point added past the largest detection stretches the grid and moves the other
//! detections to another path without changing their clusters or, since ids follow the smallest
//! point, their ids.

use loops_core::{DetectionClusters, Detections, cluster_detections};
use proptest::prelude::*;

mod support;
use support::{brute_force_clusters, canonical, config};

/// Grid cells per side when the extent is `extent_s` (the cell side is ε/√2, a little less).
fn cells_per_side(extent_s: f64, epsilon: f64) -> f64 {
    extent_s / (epsilon / std::f64::consts::SQRT_2)
}

/// The clusters of `points`, and of `points` with one far point added at offset `far_s` past
/// the largest coordinate on both axes; checks that the far point is a cluster of its own, the
/// last one, and that every other label and cluster is the same.
fn same_with_far_point(points: &[(f64, f64)], epsilon: f64, far_s: f64) -> Result<DetectionClusters, TestCaseError> {
    let (t, t_prime): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
    let base = cluster_detections(&Detections::new(t.clone(), t_prime.clone())?, epsilon)?;
    let top = t.iter().chain(&t_prime).fold(f64::NEG_INFINITY, |a, &b| a.max(b));
    let (mut t_far, mut t_prime_far) = (t, t_prime);
    t_far.push(top + far_s);
    t_prime_far.push(top + far_s);
    let far = cluster_detections(&Detections::new(t_far, t_prime_far)?, epsilon)?;
    let n = points.len();
    prop_assert_eq!(far.len(), base.len() + 1);
    prop_assert_eq!(far.labels()[n] as usize, base.len(), "the far point is the last cluster");
    prop_assert_eq!(&far.labels()[..n], base.labels(), "labels differ once the grid is stretched");
    for (a, b) in base.clusters().iter().zip(far.clusters()) {
        prop_assert_eq!(
            (a.id, a.size, a.t_s, a.t_prime_s, a.cells, a.anchor),
            (b.id, b.size, b.t_s, b.t_prime_s, b.cells, b.anchor)
        );
    }
    Ok(base)
}

/// Clumps of points around a few centres (spread up to 1.5ε), lattice points ε·k/2 apart (exact
/// ties at ε) and duplicates, in a square of `extent` ε; `n` points.
fn mixed_points(n: std::ops::Range<usize>, extent: f64) -> impl Strategy<Value = (Vec<(f64, f64)>, f64)> {
    (n, prop::sample::select(vec![1.0, 30.0, 0.1, 7.3]), 1usize..40, any::<u64>()).prop_map(
        move |(n, eps, centres, seed)| {
            let mut state = seed | 1;
            let mut uniform = move || {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64
            };
            let centres: Vec<(f64, f64)> =
                (0..centres).map(|_| (extent * eps * uniform(), extent * eps * uniform())).collect();
            let mut points = Vec::with_capacity(n);
            while points.len() < n {
                let (cx, cy) = centres[(uniform() * centres.len() as f64) as usize % centres.len()];
                match (uniform() * 4.0) as u32 {
                    0 => points.push((cx + eps * (uniform() - 0.5) * 3.0, cy + eps * (uniform() - 0.5) * 3.0)),
                    1 => {
                        let step = eps * (1 + (uniform() * 3.0) as u32) as f64 / 2.0;
                        let (a, b) = ((uniform() * 8.0).floor(), (uniform() * 8.0).floor());
                        points.push(((cx / eps).floor() * eps + a * step, (cy / eps).floor() * eps + b * step));
                    }
                    2 if !points.is_empty() => {
                        points.push(points[(uniform() * points.len() as f64) as usize % points.len()])
                    }
                    _ => points.push((cx + eps * uniform() * 0.6, cy + eps * uniform() * 0.6)),
                }
            }
            (points, eps)
        },
    )
}

proptest! {
    #![proptest_config(config(24, 0x5EED_C1A5))]

    /// Small sets: the counting sort, the comparison sort of keys and of `(cx, cy, detection)`
    /// agree with one another and with brute force.
    #[test]
    fn small_sets_same_on_every_path((points, eps) in mixed_points(1..400, 30.0)) {
        let n = points.len() as f64;
        let (t, t_prime): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
        let det = Detections::new(t, t_prime)?; // puts each pair in order, t ≤ t′
        let base = cluster_detections(&det, eps)?;
        prop_assert_eq!(canonical(base.labels()), brute_force_clusters(det.t_s(), det.t_prime_s(), eps));
        // 3√n + 64 cells per side: over 4n + 1024 cells, so keys are sorted by comparison.
        same_with_far_point(&points, eps, eps * (3.0 * n.sqrt() + 64.0))?;
        // 2¹⁷ cells per side: over 2³² cells, so (cx, cy, detection) is sorted by comparison.
        same_with_far_point(&points, eps, eps * 131_072.0)?;
    }
}

proptest! {
    #![proptest_config(config(12, 0x5EED_C1A6))]

    /// Sets above 4,096 points: the counting sort and the radix sort of keys, with one, two and
    /// three digits, agree; so does the comparison sort of `(cx, cy, detection)`.
    #[test]
    fn large_sets_same_on_every_path((points, eps) in mixed_points(4_097..7_000, 60.0)) {
        let n = points.len() as f64;
        // Cells per side: keys of about 16 bits and 25 bits (two digits), 31 bits (three
        // digits), and a grid of over 2³² cells.
        for cells in [3.0 * n.sqrt() + 64.0, 5_000.0, 40_000.0, 262_144.0] {
            same_with_far_point(&points, eps, cells * eps / cells_per_side(eps, eps))?;
        }
    }
}

proptest! {
    #![proptest_config(config(64, 0x5EED_C1A7))]

    /// All points in one cell, many duplicates: one cluster, one cell.
    #[test]
    fn one_cell_and_duplicates(
        offsets in prop::collection::vec((0usize..8, 0usize..8), 1..300),
        eps in prop::sample::select(vec![1.0, 30.0, 0.1, 7.3]),
        corner in (0.0f64..1e4, 2e4f64..3e4),
    ) {
        // A lattice of 8 × 8 points spanning a third of ε: within a cell of side ≈ ε/√2 when the
        // lattice does not straddle a cell border, in up to four cells when it does.
        let side = eps / 3.0 / 7.0;
        let points: Vec<(f64, f64)> =
            offsets.iter().map(|&(a, b)| (corner.0 + a as f64 * side, corner.1 + b as f64 * side)).collect();
        let (t, t_prime): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
        let clusters = cluster_detections(&Detections::new(t, t_prime)?, eps)?;
        prop_assert_eq!(clusters.len(), 1);
        prop_assert!(clusters.labels().iter().all(|&l| l == 0));
        prop_assert_eq!(clusters.clusters()[0].size, points.len());
        prop_assert!((1..=4).contains(&clusters.clusters()[0].cells));
        same_with_far_point(&points, eps, eps * 131_072.0)?;
    }

    /// Two blobs facing each other across a cell border, their closest pair at exactly ε, just
    /// under or just over it: the nearest-point test and the search must agree with brute force.
    #[test]
    fn blobs_a_hair_from_epsilon(
        n in 2usize..150,
        eps in prop::sample::select(vec![1.0, 30.0, 0.37]),
        factor in prop::sample::select(vec![1.0, 1.0 - 1e-12, 1.0 + 1e-12, 1.5, 2.0]),
        direction in 0usize..4,
        seed in any::<u64>(),
    ) {
        let mut state = seed | 1;
        let mut uniform = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        // Unit direction from blob A's closest point to blob B's; each blob lies behind its point.
        let (ux, uy) = [(1.0, 0.0), (0.0, 1.0), (0.6, 0.8), (0.8, -0.6)][direction];
        let base = (1000.0, 3000.0);
        let gap = eps * factor;
        let (a0, b0) = (base, (base.0 + ux * gap, base.1 + uy * gap));
        let mut points = vec![a0, b0];
        for k in 0..n {
            // Behind the closest point along −u (for A) or +u (for B), spread across it.
            let (along, across) = (uniform() * 0.6 * eps, (uniform() - 0.5) * 0.6 * eps);
            let (origin, sign) = if k % 2 == 0 { (a0, -1.0) } else { (b0, 1.0) };
            // Keep every blob point at least as far from the other blob as the closest point.
            let along = along + across.abs();
            points.push((origin.0 + sign * ux * along - uy * across, origin.1 + sign * uy * along + ux * across));
        }
        let (t, t_prime): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
        let det = Detections::new(t, t_prime)?;
        let clusters = cluster_detections(&det, eps)?;
        prop_assert_eq!(canonical(clusters.labels()), brute_force_clusters(det.t_s(), det.t_prime_s(), eps));
    }
}

/// Points in time order are read where they lie; in random order, on a sparse grid, they are
/// first copied in cell order. Both give the same clusters, ids included.
#[test]
fn same_clusters_in_time_order_and_shuffled() {
    let eps = 30.0;
    // 60,000 points in 29 × 31 clumps ε/2 wide, 5ε apart (a grid of 5 · 10⁴ cells: counting
    // sort) or 100ε apart (10⁷ cells: radix sort, and in random order the detection indices in
    // a cell span more than 32,768, so the points are copied).
    for (seed, spacing) in [(1u64, 5.0), (2, 100.0)] {
        let mut state = seed;
        let mut uniform = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut points: Vec<(f64, f64)> = (0..60_000)
            .map(|k| {
                let centre = ((k % 29) as f64 * spacing * eps, 1e6 + ((k * 7) % 31) as f64 * spacing * eps);
                (centre.0 + 0.5 * eps * uniform(), centre.1 + 0.5 * eps * uniform())
            })
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        let mut order: Vec<usize> = (0..points.len()).collect();
        for k in (1..order.len()).rev() {
            order.swap(k, (uniform() * (k + 1) as f64) as usize);
        }
        let shuffled: Vec<(f64, f64)> = order.iter().map(|&k| points[k]).collect();
        let cluster = |points: &[(f64, f64)]| {
            let (t, t_prime): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
            cluster_detections(&Detections::new(t, t_prime).unwrap(), eps).unwrap()
        };
        let (in_time_order, scattered) = (cluster(&points), cluster(&shuffled));
        assert_eq!(in_time_order.len(), 29 * 31, "spacing {spacing}");
        for (position, &k) in order.iter().enumerate() {
            assert_eq!(scattered.labels()[position], in_time_order.labels()[k], "spacing {spacing}");
        }
        for (a, b) in in_time_order.clusters().iter().zip(scattered.clusters()) {
            assert_eq!((a.id, a.size, a.t_s, a.t_prime_s, a.cells), (b.id, b.size, b.t_s, b.t_prime_s, b.cells));
            assert_eq!(order[b.anchor], a.anchor);
        }
    }
}
