//! Fleets against references: every intra-session block is the session's own result, and every
//! inter-session block is the 4-connected labelling of its dense cross mask (every pair
//! measured), on random fleets and adversarial ones (identical sessions, a time-reversed
//! session, parked sessions, a session far from all others), with both prunings.

mod support;

use std::collections::{HashMap, VecDeque};

use loops_core::{
    Euclidean, Metric, SampleSize, Sampler, SamplerKind, Separation, Trajectory, find_loops, find_loops_separated,
    fleet::{Fleet, FleetOptions, Pruning, find_fleet_loops, sample_fleet},
    tile::{merge_tiles, plan_tiles, scan_tile},
};
use proptest::prelude::*;
use support::fleets::{adversarial_fleet, random_fleet, tour};

/// The components of the dense cross mask of sessions `a` × `b` (rows × columns): labels per
/// cell (u32::MAX outside), by breadth-first search over 4-neighbours.
fn dense_cross_labels(a: &Trajectory, b: &Trajectory, gamma: f64) -> (Vec<u32>, u32) {
    let (n, m) = (a.len(), b.len());
    let inside: Vec<bool> = (0..n * m).map(|k| Euclidean.distance(a.point(k / m), b.point(k % m)) <= gamma).collect();
    let mut labels = vec![u32::MAX; n * m];
    let mut count = 0;
    for start in 0..n * m {
        if !inside[start] || labels[start] != u32::MAX {
            continue;
        }
        labels[start] = count;
        let mut queue = VecDeque::from([start]);
        while let Some(k) = queue.pop_front() {
            let (i, j) = (k / m, k % m);
            let neighbours = [(i.wrapping_sub(1), j), (i + 1, j), (i, j.wrapping_sub(1)), (i, j + 1)];
            for (r, c) in neighbours {
                if r < n && c < m && inside[r * m + c] && labels[r * m + c] == u32::MAX {
                    labels[r * m + c] = count;
                    queue.push_back(r * m + c);
                }
            }
        }
        count += 1;
    }
    (labels, count)
}

/// Holes of one label of a dense mask: 8-connected background regions that do not reach the
/// border of the padded bounding box.
fn holes(labels: &[u32], m: usize, l: u32) -> u64 {
    let cells: Vec<usize> = (0..labels.len()).filter(|&k| labels[k] == l).collect();
    let (r0, r1) = (cells.iter().map(|k| k / m).min().unwrap(), cells.iter().map(|k| k / m).max().unwrap());
    let (c0, c1) = (cells.iter().map(|k| k % m).min().unwrap(), cells.iter().map(|k| k % m).max().unwrap());
    let (h, w) = (r1 - r0 + 3, c1 - c0 + 3);
    let fg =
        |r: usize, c: usize| r >= 1 && c >= 1 && r < h - 1 && c < w - 1 && labels[(r0 + r - 1) * m + c0 + c - 1] == l;
    let mut seen = vec![false; h * w];
    let mut regions = 0;
    for start in 0..h * w {
        if seen[start] || fg(start / w, start % w) {
            continue;
        }
        regions += 1;
        seen[start] = true;
        let mut queue = VecDeque::from([start]);
        while let Some(k) = queue.pop_front() {
            let (r, c) = ((k / w) as i64, (k % w) as i64);
            for dr in -1..=1 {
                for dc in -1..=1 {
                    let (rr, cc) = (r + dr, c + dc);
                    if rr >= 0 && cc >= 0 && rr < h as i64 && cc < w as i64 {
                        let kk = rr as usize * w + cc as usize;
                        if !seen[kk] && !fg(rr as usize, cc as usize) {
                            seen[kk] = true;
                            queue.push_back(kk);
                        }
                    }
                }
            }
        }
    }
    regions - 1
}

/// Checks every block of the fleet's result against the references.
fn check_fleet(sessions: &[Trajectory], gamma: f64, separation: Separation) -> Result<(), String> {
    let named: Vec<(String, Trajectory)> =
        sessions.iter().enumerate().map(|(k, t)| (format!("s{k}"), t.clone())).collect();
    let fleet = Fleet::new(named).map_err(|e| e.to_string())?;
    let starts = fleet.starts().to_vec();
    let mut results = Vec::new();
    for pruning in [Pruning::Hierarchy, Pruning::KdTree] {
        let options = FleetOptions { separation, pruning, chunk_radius: None };
        let loops = find_fleet_loops(&fleet, &Euclidean, gamma, &options).map_err(|e| e.to_string())?;
        let comps = loops.components();
        let joint = loops.loops();
        // Intra-session blocks: the session's own result, component by component.
        for (a, traj) in sessions.iter().enumerate() {
            let alone = find_loops_separated(traj, &Euclidean, gamma, separation).map_err(|e| e.to_string())?;
            let own: Vec<_> = comps.iter().filter(|c| c.sessions == [a, a]).collect();
            if own.len() != alone.components().len() {
                return Err(format!(
                    "{pruning:?}: session {a} has {} components, alone {}",
                    own.len(),
                    alone.components().len()
                ));
            }
            for (c, single) in own.iter().zip(alone.components()) {
                let fleet_view = (
                    c.trivial,
                    c.pair_count,
                    c.holes,
                    c.poses,
                    c.closest_pair,
                    c.closest_distance,
                    c.area_s2.to_bits(),
                );
                let own_view = (
                    single.trivial,
                    single.pair_count,
                    single.holes,
                    [single.i_range, single.j_range],
                    single.closest_pair,
                    single.closest_distance,
                    single.area_s2.to_bits(),
                );
                if fleet_view != own_view {
                    return Err(format!("{pruning:?}: session {a}: {fleet_view:?} != {own_view:?}"));
                }
            }
        }
        // Inter-session blocks: the dense cross mask's components.
        for a in 0..sessions.len() {
            for b in a + 1..sessions.len() {
                let (sa, sb) = (&sessions[a], &sessions[b]);
                let (labels, count) = dense_cross_labels(sa, sb, gamma);
                let m = sb.len();
                let mut ours_of: HashMap<u32, usize> = HashMap::new();
                let mut dense_of: HashMap<usize, u32> = HashMap::new();
                for i in 0..sa.len() {
                    for j in 0..m {
                        let ours = joint.component_of(starts[a] + i, starts[b] + j);
                        let dense = labels[i * m + j];
                        match (ours, dense) {
                            (None, u32::MAX) => {}
                            (Some(c), l) if l != u32::MAX => {
                                if *ours_of.entry(l).or_insert(c) != c || *dense_of.entry(c).or_insert(l) != l {
                                    return Err(format!(
                                        "{pruning:?}: block ({a}, {b}) cell ({i}, {j}) splits or joins"
                                    ));
                                }
                            }
                            _ => {
                                return Err(format!(
                                    "{pruning:?}: block ({a}, {b}) cell ({i}, {j}): ours {ours:?}, dense {dense}"
                                ));
                            }
                        }
                    }
                }
                if ours_of.len() != count as usize {
                    return Err(format!("{pruning:?}: block ({a}, {b}): {} components, dense {count}", ours_of.len()));
                }
                for (&l, &c) in &ours_of {
                    let comp = &comps[c];
                    let cells = labels.iter().filter(|&&x| x == l).count() as u64;
                    let area: f64 = (0..labels.len())
                        .filter(|&k| labels[k] == l)
                        .map(|k| sa.cell_widths_s()[k / m] * sb.cell_widths_s()[k % m])
                        .sum();
                    let closest = (0..labels.len())
                        .filter(|&k| labels[k] == l)
                        .map(|k| Euclidean.distance(sa.point(k / m), sb.point(k % m)))
                        .fold(f64::INFINITY, f64::min);
                    if comp.sessions != [a, b] || comp.trivial || comp.pair_count != cells {
                        return Err(format!("{pruning:?}: block ({a}, {b}) component {c}: {comp:?}, {cells} cells"));
                    }
                    if comp.holes != holes(&labels, m, l) {
                        return Err(format!(
                            "{pruning:?}: component {c} holes {} != {}",
                            comp.holes,
                            holes(&labels, m, l)
                        ));
                    }
                    if (comp.area_s2 - area).abs() > 1e-9 * area.max(1.0) || comp.closest_distance != closest {
                        return Err(format!(
                            "{pruning:?}: component {c}: area {} vs {area}, closest {} vs {closest}",
                            comp.area_s2, comp.closest_distance
                        ));
                    }
                }
            }
        }
        results.push(loops);
    }
    // Both prunings give the same answer.
    let (h, k) = (&results[0], &results[1]);
    if h.loops().sublevel_set() != k.loops().sublevel_set() || h.components() != k.components() {
        return Err("the prunings disagree".into());
    }
    Ok(())
}

/// Tiles of every size, scanned apart and merged, give the fleet's components.
fn check_tiles(sessions: &[Trajectory], gamma: f64, separation: Separation) -> Result<(), String> {
    let named: Vec<(String, Trajectory)> =
        sessions.iter().enumerate().map(|(k, t)| (format!("s{k}"), t.clone())).collect();
    let fleet = Fleet::new(named).map_err(|e| e.to_string())?;
    let options = FleetOptions { separation, ..FleetOptions::default() };
    let whole = find_fleet_loops(&fleet, &Euclidean, gamma, &options).map_err(|e| e.to_string())?;
    let expected = whole.loops().components();
    let longest = sessions.iter().map(Trajectory::len).max().unwrap_or(1);
    for per_session in [1, 2, 7, longest] {
        let block = longest.div_ceil(per_session).max(1);
        let tiles = plan_tiles(&fleet, &Euclidean, gamma, block).map_err(|e| e.to_string())?;
        let mut summaries = Vec::new();
        // Any order: the reversed order of the plan.
        for tile in tiles.iter().rev() {
            summaries.push(scan_tile(&fleet, &Euclidean, gamma, separation, tile).map_err(|e| e.to_string())?);
        }
        let merged = merge_tiles(&summaries).map_err(|e| e.to_string())?;
        if merged.len() != expected.len() {
            return Err(format!("block {block}: {} components, the fleet {}", merged.len(), expected.len()));
        }
        for (m, e) in merged.iter().zip(expected) {
            let exact = |c: &loops_core::LoopComponent| {
                (
                    c.id,
                    c.trivial,
                    c.pair_count,
                    c.run_count,
                    c.holes,
                    c.i_range,
                    c.j_range,
                    c.closest_pair,
                    c.closest_distance,
                )
            };
            if exact(m) != exact(e) || (m.area_s2 - e.area_s2).abs() > 1e-10 * (e.area_s2 + 1.0) {
                return Err(format!("block {block} ({} tiles): {m:?} != {e:?}", tiles.len()));
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(support::config(96, 0xF1EE7))]

    #[test]
    fn tiles_merge_to_the_fleet_result(fleet in random_fleet(50, 1..4, 2.0)) {
        check_tiles(&fleet.sessions(), fleet.gamma(), fleet.separation()).map_err(TestCaseError::fail)?;
    }

    #[test]
    fn random_fleets_match_the_references(fleet in random_fleet(60, 2..5, 3.0)) {
        check_fleet(&fleet.sessions(), fleet.gamma(), fleet.separation()).map_err(TestCaseError::fail)?;
    }
}

#[test]
fn adversarial_fleets_match_the_references() {
    let sessions = adversarial_fleet(120, 80, 50, 90);
    for gamma in [0.5, 1.5, 4.0] {
        for separation in [Separation::NONE, Separation::path(3.0 * gamma)] {
            check_fleet(&sessions, gamma, separation).unwrap_or_else(|e| panic!("γ = {gamma}, {separation}: {e}"));
            check_tiles(&sessions, gamma, separation)
                .unwrap_or_else(|e| panic!("tiles, γ = {gamma}, {separation}: {e}"));
        }
    }
}

/// One trajectory given whole, or cut into two consecutive sessions: every component of the cut
/// lies within one component of the whole, and the cut's components partition each of the
/// whole's components (their cells add up). The whole may join what the cut keeps apart (a
/// component crossing the cut row is split into the intra block above it and the inter block
/// to its right), never the other way.
#[test]
fn a_trajectory_cut_in_two_refines_the_whole() {
    for (n, gamma) in [(300, 1.0), (257, 3.0), (200, 0.3)] {
        let whole = tour(n, 0.0, [0.0, 0.0]);
        let whole_loops = find_loops(&whole, &Euclidean, gamma).unwrap();
        for cut in [2, n / 3, n / 2, n - 2] {
            let part = |range: std::ops::Range<usize>| {
                let t = whole.timestamps_s()[range.clone()].to_vec();
                Trajectory::new(t, whole.coords()[range.start * 2..range.end * 2].to_vec(), 2).unwrap()
            };
            let fleet = Fleet::new(vec![("first".into(), part(0..cut)), ("second".into(), part(cut..n))]).unwrap();
            let cut_loops = find_fleet_loops(&fleet, &Euclidean, gamma, &FleetOptions::default()).unwrap();
            // Same cells (the upper halves coincide in fleet indices).
            assert_eq!(cut_loops.loops().sublevel_set().upper_pairs(), whole_loops.sublevel_set().upper_pairs());
            let mut whole_of: HashMap<usize, usize> = HashMap::new();
            let mut upper_cells = vec![0_u64; whole_loops.components().len()];
            for run in cut_loops.loops().runs() {
                let w = whole_loops.component_of(run.row, run.start).expect("a cut cell is a whole cell");
                for j in run.start..=run.end {
                    assert_eq!(whole_loops.component_of(run.row, j), Some(w));
                }
                assert_eq!(*whole_of.entry(run.component).or_insert(w), w, "a cut component in two whole ones");
                upper_cells[w] += run.len() as u64;
            }
            for (w, comp) in whole_loops.components().iter().enumerate() {
                let upper: u64 = whole_loops.runs().filter(|r| r.component == w).map(|r| r.len() as u64).sum();
                assert_eq!(upper_cells[w], upper, "n {n}, cut {cut}: whole component {w} ({comp:?})");
            }
            assert!(cut_loops.components().len() >= whole_loops.components().len());
        }
    }
}

#[test]
fn fleet_samples_name_their_sessions_and_stay_between_on_request() {
    let sessions: Vec<(String, Trajectory)> =
        (0..4).map(|k| (format!("car{k}"), tour(150 + 10 * k, 100.0 * k as f64, [0.3 * k as f64, 0.0]))).collect();
    let fleet = Fleet::new(sessions).unwrap();
    let loops = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default()).unwrap();
    let between = loops.between_sessions();
    assert!(!between.is_empty());
    for kind in [SamplerKind::One, SamplerKind::Rho, SamplerKind::RhoDispersed, SamplerKind::Alpha] {
        let sampler = Sampler::new(kind, SampleSize::Budget(400), 5);
        let samples = sample_fleet(&fleet, &Euclidean, &loops, &sampler, true).unwrap();
        assert_eq!(samples.len(), 400, "{kind:?}");
        let located = fleet.localize(&samples).unwrap();
        for s in &located {
            assert_ne!(s.sessions[0], s.sessions[1], "{kind:?}: a sample within a session");
            let (a, b) = (fleet.session(s.sessions[0]), fleet.session(s.sessions[1]));
            assert_eq!(a.timestamps_s()[s.poses[0]], s.times_s[0]);
            assert_eq!(b.timestamps_s()[s.poses[1]], s.times_s[1]);
            assert!(Euclidean.distance(a.point(s.poses[0]), b.point(s.poses[1])) <= 1.0);
        }
        if kind != SamplerKind::Alpha {
            // P1 over the components between sessions.
            let covered: std::collections::BTreeSet<_> = located.iter().filter_map(|s| s.component).collect();
            assert_eq!(covered.len(), between.len(), "{kind:?}");
        }
        // The same seed, the same samples.
        assert_eq!(sample_fleet(&fleet, &Euclidean, &loops, &sampler, true).unwrap(), samples);
    }
    let baseline = Sampler::new(SamplerKind::LioSam, SampleSize::Budget(10), 5);
    assert!(sample_fleet(&fleet, &Euclidean, &loops, &baseline, true).is_err());
    assert!(sample_fleet(&fleet, &Euclidean, &loops, &baseline, false).is_ok());
}

#[test]
fn overlap_matrix_and_split_duration_add_up() {
    let sessions: Vec<(String, Trajectory)> =
        (0..3).map(|k| (format!("day{k}"), tour(100, 0.0, [0.5 * k as f64, 0.0]))).collect();
    let fleet = Fleet::new(sessions).unwrap();
    let loops = find_fleet_loops(&fleet, &Euclidean, 1.0, &FleetOptions::default()).unwrap();
    let (own, other) = loops.loop_duration();
    let pairs = loops.session_pairs();
    // ∫τ over the fleet = Σ α of intra blocks + 2 Σ α of inter blocks (each appears for both
    // sessions' poses).
    let widths = fleet.joint().cell_widths_s();
    let integral = |tau: &[f64]| tau.iter().zip(widths).map(|(t, w)| t * w).sum::<f64>();
    let intra: f64 = pairs.iter().filter(|p| p.sessions[0] == p.sessions[1]).map(|p| p.area_s2).sum();
    let inter: f64 = pairs.iter().filter(|p| p.sessions[0] != p.sessions[1]).map(|p| p.area_s2).sum();
    assert!((integral(&own) - intra).abs() < 1e-9 * intra, "{} vs {intra}", integral(&own));
    assert!((integral(&other) - 2.0 * inter).abs() < 1e-9 * inter, "{} vs {}", integral(&other), 2.0 * inter);
    // Each session's own τ is its τ alone.
    for a in 0..3 {
        let alone = find_loops(fleet.session(a), &Euclidean, 1.0).unwrap();
        let tau = alone.loop_duration(Default::default(), Default::default(), Default::default()).unwrap();
        let start = fleet.starts()[a];
        assert_eq!(&own[start..start + tau.len()], &tau[..], "session {a}: bit for bit");
    }
    for p in &pairs {
        assert!(p.density > 0.0 && p.density <= 1.0, "{p:?}");
    }
}
