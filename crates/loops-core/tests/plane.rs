//! The (t, t′) plane against brute force: grids, the label image against the dense labelling
//! of the support module (flood fill of the full matrix, mirrored), membership of pairs against
//! a linear scan of the runs, outlines against counted pixel sides, isocontours against the
//! edges whose ends straddle the level, nearest poses against an argmin.

mod support;

use std::collections::BTreeMap;

use loops_core::{
    Euclidean, Metric, MetricSpec, RotationDistance, Se3, So3, Timeline, Trajectory, UrbanDrive, find_loops,
    plane::{Border, PlaneGrid, chain_polylines, component_outlines, distance_image, isocontour, outline_segments},
};
use proptest::prelude::*;
use support::{DenseLoops, OUTSIDE, any_case, config};

/// An optional window as fractions of the span (reaching a little outside it).
fn window() -> impl Strategy<Value = Option<([f64; 2], [f64; 2])>> {
    let side = (-0.1..1.1f64, 0.02..1.0f64).prop_map(|(a, w)| [a, a + w]);
    proptest::option::of((side.clone(), side))
}

/// The pose of the window `[a, b]` (seconds from the first pose) nearest `centre`, ties to the
/// earlier: an argmin over every pose.
fn nearest_in(times: &[f64], a: f64, b: f64, centre: f64) -> Option<usize> {
    let t0 = times[0];
    let mut best: Option<(f64, usize)> = None;
    for (k, &t) in times.iter().enumerate() {
        let r = t - t0;
        if r >= a && r <= b && best.is_none_or(|(d, _)| (r - centre).abs() < d) {
            best = Some(((r - centre).abs(), k));
        }
    }
    best.map(|(_, k)| k)
}

/// The poses of one axis, from the definition.
fn brute_axis(times: &[f64], [a, b]: [f64; 2], max_pixels: usize) -> Vec<usize> {
    let t0 = times[0];
    let inside: Vec<usize> = (0..times.len()).filter(|&k| times[k] - t0 >= a && times[k] - t0 <= b).collect();
    if inside.len() <= max_pixels {
        return inside;
    }
    let step = (b - a) / max_pixels as f64;
    (0..max_pixels).filter_map(|k| nearest_in(times, a, b, a + (k as f64 + 0.5) * step)).collect()
}

proptest! {
    #![proptest_config(config(160, 0x5EED_0F1A))]

    /// Every pixel of the label image is the dense reference's component of its pair, read in
    /// the upper half (the mirror), numbered as the engine numbers components; the distance
    /// image is the reference's δ, and a pixel is labelled exactly where δ ≤ γ.
    #[test]
    fn label_image_is_the_dense_labelling_mirrored(
        case in any_case(90),
        max_pixels in 1usize..120,
        window in window(),
    ) {
        let (traj, gamma) = (&case.traj, case.gamma);
        let loops = find_loops(traj, &Euclidean, gamma).unwrap();
        let dense = DenseLoops::new(traj, gamma);
        let span = traj.span_s();
        let window_s = window.map(|(t, u)| ([t[0] * span, t[1] * span], [u[0] * span, u[1] * span]));
        let Ok(grid) = PlaneGrid::new(&loops, window_s, max_pixels) else {
            // Only a window without poses is refused.
            let (t, u) = window_s.unwrap();
            prop_assert!(brute_axis(traj.timestamps_s(), t, 1).is_empty() || brute_axis(traj.timestamps_s(), u, 1).is_empty());
            return Ok(());
        };
        let (t, u) = window_s.unwrap_or(([0.0, span], [0.0, span]));
        prop_assert_eq!(grid.columns(), &brute_axis(traj.timestamps_s(), t, max_pixels)[..]);
        prop_assert_eq!(grid.rows(), &brute_axis(traj.timestamps_s(), u, max_pixels)[..]);

        let labels = loops.label_image(&grid).unwrap();
        let image = distance_image(traj, &Euclidean, &grid).unwrap();
        let n = traj.len();
        let engine_id: BTreeMap<u32, u32> =
            dense.upper_order.iter().enumerate().map(|(id, &d)| (d, id as u32)).collect();
        let w = grid.width();
        for (r, &j) in grid.rows().iter().enumerate() {
            for (c, &i) in grid.columns().iter().enumerate() {
                let (a, b) = (i.min(j), i.max(j));
                let d = dense.label[a * n + b];
                let expected = (d != OUTSIDE).then(|| engine_id[&d]);
                prop_assert_eq!(labels[r * w + c], expected, "pixel ({}, {}) = pair ({}, {})", c, r, i, j);
                prop_assert_eq!(image[r * w + c], dense.set.delta(i, j));
                prop_assert_eq!(labels[r * w + c].is_some(), image[r * w + c] <= gamma);
            }
        }
    }

    /// Membership of many pairs at once, either order, equals a linear scan of the runs.
    #[test]
    fn components_of_pairs_equal_a_scan_of_the_runs(
        case in any_case(120),
        picks in proptest::collection::vec((0.0..1.0f64, 0.0..1.0f64), 0..60),
    ) {
        let loops = find_loops(&case.traj, &Euclidean, case.gamma).unwrap();
        let n = loops.len();
        let pairs: Vec<[usize; 2]> =
            picks.iter().map(|&(a, b)| [(a * n as f64) as usize, (b * n as f64) as usize]).collect();
        let runs: Vec<_> = loops.runs().collect();
        let scan = |i: usize, j: usize| {
            let (row, column) = (i.min(j), i.max(j));
            runs.iter().find(|r| r.row == row && r.start <= column && column <= r.end).map(|r| r.component)
        };
        let got = loops.components_of_pairs(&pairs).unwrap();
        let expected: Vec<Option<usize>> = pairs.iter().map(|&[i, j]| scan(i, j)).collect();
        prop_assert_eq!(&got, &expected);
        let counts = loops.pair_counts_per_component(&pairs).unwrap();
        for (c, &count) in counts.iter().enumerate() {
            prop_assert_eq!(count, expected.iter().filter(|&&e| e == Some(c)).count() as u64);
        }
        prop_assert!(loops.components_of_pairs(&[[0, n]]).is_err());
    }

    /// Outlines: a closed border gives closed polylines whose unit edges are the sides of the
    /// component's pixels that face another label or the outside; an open border gives the
    /// edges between neighbouring pixels of different labels, and nothing along the border.
    #[test]
    fn outlines_are_the_pixel_sides_between_labels(
        (width, height, cells) in (1usize..9, 1usize..9).prop_flat_map(|(w, h)| {
            (Just(w), Just(h), proptest::collection::vec(proptest::option::of(0u32..3), w * h))
        }),
    ) {
        let label = |a: i64, b: i64| {
            (a >= 0 && b >= 0 && (a as usize) < width && (b as usize) < height).then(|| cells[b as usize * width + a as usize])
        };
        // Closed: per component, the pixel sides facing something else (outside included).
        let outlines = component_outlines(&cells, width, height, Border::Closed).unwrap();
        let mut sides: BTreeMap<u32, usize> = BTreeMap::new();
        for b in 0..height as i64 {
            for a in 0..width as i64 {
                let Some(Some(c)) = label(a, b) else { continue };
                for (da, db) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                    if label(a + da, b + db).flatten() != Some(c) {
                        *sides.entry(c).or_default() += 1;
                    }
                }
            }
        }
        let drawn: BTreeMap<u32, usize> =
            outlines.iter().map(|(&c, lines)| (c, lines.iter().map(|l| l.len() - 1).sum())).collect();
        prop_assert_eq!(&drawn, &sides);
        for line in outlines.values().flatten() {
            prop_assert_eq!(line.first(), line.last(), "a closed outline");
            for w in line.windows(2) {
                let step = (w[0][0].abs_diff(w[1][0]), w[0][1].abs_diff(w[1][1]));
                prop_assert!(step == (1, 0) || step == (0, 1), "unit steps along the lattice");
            }
        }
        // Open: the pairs of neighbouring pixels with different labels.
        let edges = outline_segments(&cells, width, height, Border::Open).unwrap();
        let mut between = 0;
        for b in 0..height as i64 {
            for a in 0..width as i64 {
                between += usize::from(label(a + 1, b).is_some_and(|l| l != label(a, b).flatten()));
                between += usize::from(label(a, b + 1).is_some_and(|l| l != label(a, b).flatten()));
            }
        }
        prop_assert_eq!(edges.len(), between);
        for e in &edges {
            prop_assert!(e.sides[0] != e.sides[1]);
        }
    }

    /// Chaining uses every edge exactly once, in either direction.
    #[test]
    fn chains_use_every_edge_once(edges in proptest::collection::vec((0u8..12, 0u8..12), 0..40)) {
        let edges: Vec<[u8; 2]> = edges.into_iter().filter(|(a, b)| a != b).map(|(a, b)| [a, b]).collect();
        let lines = chain_polylines(&edges);
        let mut used: Vec<[u8; 2]> =
            lines.iter().flat_map(|l| l.windows(2).map(|w| [w[0].min(w[1]), w[0].max(w[1])])).collect();
        let mut given: Vec<[u8; 2]> = edges.iter().map(|e| [e[0].min(e[1]), e[0].max(e[1])]).collect();
        used.sort_unstable();
        given.sort_unstable();
        prop_assert_eq!(used, given);
    }

    /// Every crossing of the isocontour lies on an edge between two pixel centres whose values
    /// straddle the level, at the interpolated place, and every such edge is crossed.
    #[test]
    fn isocontours_cross_exactly_the_straddling_edges(
        (width, height, values) in (1usize..8, 1usize..8).prop_flat_map(|(w, h)| {
            (Just(w), Just(h), proptest::collection::vec(0i32..5, w * h))
        }),
        level in 0.0..4.0f64,
    ) {
        let values: Vec<f64> = values.into_iter().map(f64::from).collect();
        let v = |a: usize, b: usize| values[b * width + a];
        let mut expected = Vec::new();
        for b in 0..height {
            for a in 0..width {
                let mut cross = |a2: usize, b2: usize| {
                    let (v0, v1) = (v(a, b), v(a2, b2));
                    if (v0 <= level) != (v1 <= level) {
                        let f = (v0 - level) / (v0 - v1);
                        expected.push([a as f64 + 0.5 + f * (a2 - a) as f64, b as f64 + 0.5 + f * (b2 - b) as f64]);
                    }
                };
                // Only edges of cells (2 × 2 blocks of centres) carry the contour.
                if a + 1 < width && height > 1 {
                    cross(a + 1, b);
                }
                if b + 1 < height && width > 1 {
                    cross(a, b + 1);
                }
            }
        }
        let key = |p: [f64; 2]| [(p[0] * 1e9).round() as i64, (p[1] * 1e9).round() as i64];
        let mut got: Vec<[i64; 2]> = isocontour(&values, width, height, level).unwrap().into_iter().flatten().map(key).collect();
        got.sort_unstable();
        got.dedup();
        let mut expected: Vec<[i64; 2]> = expected.into_iter().map(key).collect();
        expected.sort_unstable();
        prop_assert_eq!(got, expected);
    }

    /// The nearest pose of each time is an argmin of |t_k − t| (ties to the earlier pose).
    #[test]
    fn nearest_poses_are_the_argmin(case in any_case(60), fractions in proptest::collection::vec(0.0..=1.0f64, 1..30)) {
        let times = case.traj.timestamps_s();
        let (t0, span) = (times[0], case.traj.span_s());
        let query: Vec<f64> = fractions.iter().map(|f| (t0 + f * span).clamp(t0, times[times.len() - 1])).collect();
        let got = case.traj.nearest_poses(&query).unwrap();
        for (&t, &k) in query.iter().zip(&got) {
            prop_assert_eq!(Some(k), nearest_in(times, f64::NEG_INFINITY, f64::INFINITY, t - t0));
        }
    }
}

#[test]
fn isocontour_of_a_bump_is_one_closed_line() {
    let (width, height) = (15, 11);
    let values: Vec<f64> =
        (0..width * height).map(|k| ((k % width) as f64 - 7.0).hypot((k / width) as f64 - 5.0)).collect();
    let lines = isocontour(&values, width, height, 3.5).unwrap();
    assert_eq!(lines.len(), 1);
    assert_eq!(lines[0].first(), lines[0].last());
    assert!(lines[0].len() > 8);
    for p in &lines[0] {
        assert!(((p[0] - 7.5).hypot(p[1] - 5.5) - 3.5).abs() < 0.3, "{p:?}");
    }
}

#[test]
fn distance_images_by_name_equal_the_metric_for_se3_and_so3() {
    let drive = UrbanDrive { duration_s: 120.0, ..UrbanDrive::default() }.generate().unwrap();
    let se3 = drive.se3_trajectory().unwrap();
    let grid = PlaneGrid::new(&se3, None, 37).unwrap();
    let metric = Se3 { rotation_weight_m_per_rad: 5.0, rotation: RotationDistance::Geodesic };
    let spec: MetricSpec = "se3(rotation_weight_m_per_rad=5)".parse().unwrap();
    assert_eq!(spec.distance_image(&se3, &grid).unwrap(), distance_image(&se3, &metric, &grid).unwrap());
    let quaternions: Vec<[f64; 4]> = (0..se3.len()).map(|i| se3.point(i)[3..7].try_into().unwrap()).collect();
    let so3 = Trajectory::so3(se3.timestamps_s().to_vec(), &quaternions).unwrap();
    let image = MetricSpec::So3(So3::default()).distance_image(&so3, &grid).unwrap();
    for (r, &j) in grid.rows().iter().enumerate() {
        for (c, &i) in grid.columns().iter().enumerate() {
            assert_eq!(image[r * grid.width() + c], So3::default().distance(so3.point(i), so3.point(j)));
        }
    }
    // The image needs the metric's points: positions are no SE(3) poses.
    assert!(spec.distance_image(&drive.trajectory, &grid).is_err());
    assert_eq!(grid.poses(), so3.pose_times_s().len());
}
