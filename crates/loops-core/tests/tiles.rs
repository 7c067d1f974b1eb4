//! Tiles for a cluster: plans from each session's blocks alone cover every pair within γ, scans
//! from two sessions' trajectories alone equal the scans of the fleet, merges in any tree of
//! any grouping and order equal the fleet's result (components, their sessions, times and
//! poses, the overlap matrix), and the bytes a worker ships decode to the same summary or fail
//! with a clear error.

mod support;

use loops_core::{
    Error, Euclidean, Metric, Separation, Trajectory,
    fleet::{Fleet, FleetOptions, find_fleet_loops},
    tile::{
        OLDEST_TILE_FORMAT_VERSION, SessionBlocks, TILE_FORMAT_VERSION, Tile, TileKeep, TileMerge, TileSummary,
        plan_session_tiles, plan_tiles, scan_session_tile, scan_tile,
    },
};
use proptest::prelude::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use support::fleets::{adversarial_fleet, random_fleet, tour};

/// Every pair within γ of the fleet's plane (a ≤ b, j ≥ i within a session) lies in a tile:
/// checked pair by pair.
fn check_cover(sessions: &[Trajectory], starts: &[usize], tiles: &[Tile], gamma: f64) -> Result<(), String> {
    for (a, sa) in sessions.iter().enumerate() {
        for (b, sb) in sessions.iter().enumerate().skip(a) {
            for i in 0..sa.len() {
                let j0 = if a == b { i } else { 0 };
                for j in j0..sb.len() {
                    if Euclidean.distance(sa.point(i), sb.point(j)) > gamma {
                        continue;
                    }
                    let (fi, fj) = (starts[a] + i, starts[b] + j);
                    if !tiles.iter().any(|t| t.sessions == [a, b] && t.rows.contains(&fi) && t.columns.contains(&fj)) {
                        return Err(format!("pair ({fi}, {fj}) of sessions ({a}, {b}) is within γ but in no tile"));
                    }
                }
            }
        }
    }
    Ok(())
}

/// Merges `parts` in a random tree: random groups of 1 to 4 consecutive parts of a shuffled
/// list, each merge shipped through its bytes, until one is left.
fn random_tree(mut parts: Vec<TileMerge>, rng: &mut ChaCha8Rng) -> Result<TileMerge, String> {
    for k in (1..parts.len()).rev() {
        parts.swap(k, rng.random_range(0..=k));
    }
    while parts.len() > 1 {
        let mut next = Vec::new();
        let mut rest = parts.into_iter().peekable();
        while rest.peek().is_some() {
            let group: Vec<TileMerge> = rest.by_ref().take(rng.random_range(1..=4)).collect();
            let merged = TileMerge::merge(group).map_err(|e| e.to_string())?;
            next.push(TileMerge::from_bytes(&merged.to_bytes()).map_err(|e| e.to_string())?);
        }
        parts = next;
    }
    Ok(parts.pop().expect("at least one tile"))
}

/// Plans from blocks, scans from sessions, random merge trees and bytes: the fleet's result.
fn check_tree(sessions: &[Trajectory], gamma: f64, separation: Separation, seed: u64) -> Result<(), String> {
    let longest = sessions.iter().map(Trajectory::len).max().unwrap_or(1);
    check_tree_cut(sessions, gamma, separation, seed, &[1, 2, 7, longest])
}

/// [`check_tree`] for these numbers of blocks per session.
fn check_tree_cut(
    sessions: &[Trajectory],
    gamma: f64,
    separation: Separation,
    seed: u64,
    cuts: &[usize],
) -> Result<(), String> {
    let named: Vec<(String, Trajectory)> =
        sessions.iter().enumerate().map(|(k, t)| (format!("s{k}"), t.clone())).collect();
    let fleet = Fleet::new(named).map_err(|e| e.to_string())?;
    let options = FleetOptions { separation, ..FleetOptions::default() };
    let whole = find_fleet_loops(&fleet, &Euclidean, gamma, &options).map_err(|e| e.to_string())?;
    let expected = whole.components();
    let expected_pairs = whole.session_pairs();
    let starts = fleet.starts().to_vec();
    let spans: Vec<f64> = sessions.iter().map(Trajectory::span_s).collect();
    let longest = sessions.iter().map(Trajectory::len).max().unwrap_or(1);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for &per_session in cuts {
        let block = longest.div_ceil(per_session).max(1);
        let blocks: Vec<SessionBlocks> = sessions
            .iter()
            .map(|s| SessionBlocks::from_bytes(&SessionBlocks::new(s, &Euclidean, block)?.to_bytes()))
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?;
        let tiles = plan_session_tiles(&blocks, &Euclidean, gamma).map_err(|e| e.to_string())?;
        if tiles != plan_tiles(&fleet, &Euclidean, gamma, block).map_err(|e| e.to_string())? {
            return Err(format!("block {block}: the plan from blocks differs from the fleet's"));
        }
        check_cover(sessions, &starts, &tiles, gamma)?;
        let mut parts = Vec::new();
        for tile in &tiles {
            let [a, b] = tile.sessions;
            // The worker's view: its own copies of the two sessions, nothing else.
            let (own_a, own_b) = (sessions[a].clone(), sessions[b].clone());
            let scan = scan_session_tile(
                [&own_a, &own_b],
                [starts[a], starts[b]],
                &Euclidean,
                gamma,
                separation,
                tile,
                TileKeep::SUMMARY,
            )
            .map_err(|e| e.to_string())?;
            if scan.duration.is_some() || scan.runs.is_some() {
                return Err(format!("tile {tile:?}: the summary-only scan kept more"));
            }
            let summary = scan.summary;
            let of_fleet = scan_tile(&fleet, &Euclidean, gamma, separation, tile).map_err(|e| e.to_string())?;
            if summary != of_fleet {
                return Err(format!("tile {tile:?}: the scan from sessions differs from the fleet's"));
            }
            let shipped = TileSummary::from_bytes(&summary.to_bytes()).map_err(|e| e.to_string())?;
            if shipped != summary {
                return Err(format!("tile {tile:?}: the summary changed through its bytes"));
            }
            parts.push(TileMerge::new(shipped).map_err(|e| e.to_string())?);
        }
        let merged = random_tree(parts, &mut rng)?.finish().map_err(|e| e.to_string())?;
        let got = merged.fleet_components(&starts).map_err(|e| e.to_string())?;
        if got.len() != expected.len() {
            return Err(format!("block {block}: {} components, the fleet {}", got.len(), expected.len()));
        }
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-10 * (y.abs() + 1.0);
        for ((m, g), e) in merged.components().iter().zip(&got).zip(&expected) {
            let exact = |c: &loops_core::fleet::FleetComponent| {
                (c.id, c.sessions, c.trivial, c.pair_count, c.holes, c.poses, c.closest_pair, c.closest_distance)
            };
            if exact(g) != exact(e) || !close(g.area_s2, e.area_s2) {
                return Err(format!("block {block} ({} tiles): {g:?} != {e:?}", tiles.len()));
            }
            let joint = &whole.loops().components()[e.id];
            if m.component.run_count != joint.run_count || m.component.i_range != joint.i_range {
                return Err(format!("block {block}: {:?} != {joint:?}", m.component));
            }
            let [a, b] = e.sessions;
            let time = |s: usize, pose: usize| sessions[s].timestamps_s()[pose];
            let times =
                [[time(a, e.poses[0][0]), time(a, e.poses[0][1])], [time(b, e.poses[1][0]), time(b, e.poses[1][1])]];
            if m.times_s != times {
                return Err(format!("block {block}: component {} has times {:?}, not {times:?}", e.id, m.times_s));
            }
        }
        let pairs = merged.session_pairs(&spans).map_err(|e| e.to_string())?;
        if pairs.len() != expected_pairs.len() {
            return Err(format!("block {block}: {} session pairs, the fleet {}", pairs.len(), expected_pairs.len()));
        }
        for (p, e) in pairs.iter().zip(&expected_pairs) {
            let ok = p.sessions == e.sessions
                && p.components == e.components
                && p.pair_count == e.pair_count
                && close(p.area_s2, e.area_s2)
                && close(p.density, e.density);
            if !ok {
                return Err(format!("block {block}: session pair {p:?} != {e:?}"));
            }
        }
    }
    Ok(())
}

/// Blocks made `factor` times larger from finer ones: the same cut as blocks made at that size,
/// balls that hold every pose of their block (checked pose by pose), and plans from them that cover every pair within γ.
fn check_coarsened(sessions: &[Trajectory], gamma: f64, block: usize, factor: usize) -> Result<(), String> {
    let starts: Vec<usize> = sessions.iter().scan(0, |at, s| Some(std::mem::replace(at, *at + s.len()))).collect();
    let mut coarse = Vec::new();
    for (a, session) in sessions.iter().enumerate() {
        let fine = SessionBlocks::new(session, &Euclidean, block).map_err(|e| e.to_string())?;
        let got = fine.coarsened(factor, &Euclidean).map_err(|e| e.to_string())?;
        let exact = SessionBlocks::new(session, &Euclidean, block * factor).map_err(|e| e.to_string())?;
        if (got.poses, got.block, got.len(), got.span_s) != (exact.poses, exact.block, exact.len(), exact.span_s) {
            return Err(format!("session {a}: {got:?} is not cut as {exact:?}"));
        }
        for k in 0..got.len() {
            let centre = &got.centres[k * got.dim..(k + 1) * got.dim];
            let bound = got.radii[k] * (1.0 + 1e-12) + 1e-12;
            for i in k * got.block..((k + 1) * got.block).min(session.len()) {
                let d = Euclidean.distance(centre, session.point(i));
                if d > bound {
                    return Err(format!("session {a}, block {k}: pose {i} at {d} outside radius {}", got.radii[k]));
                }
            }
        }
        coarse.push(SessionBlocks::from_bytes(&got.to_bytes()).map_err(|e| e.to_string())?);
    }
    let tiles = plan_session_tiles(&coarse, &Euclidean, gamma).map_err(|e| e.to_string())?;
    check_cover(sessions, &starts, &tiles, gamma)
}

#[test]
fn coarsened_blocks_refuse_a_factor_of_zero() {
    let blocks = SessionBlocks::new(&tour(20, 0.0, [0.0, 0.0]), &Euclidean, 4).unwrap();
    assert!(matches!(blocks.coarsened(0, &Euclidean), Err(Error::InvalidParameter { name: "factor", .. })));
    assert!(matches!(blocks.coarsened(usize::MAX, &Euclidean), Err(Error::InvalidParameter { name: "factor", .. })));
    assert_eq!(blocks.coarsened(1, &Euclidean).unwrap(), blocks);
}

#[test]
fn adversarial_fleets_coarsen() {
    let sessions = adversarial_fleet(90, 60, 40, 70);
    for (block, factor) in [(1, 7), (4, 3), (7, 2), (16, 16)] {
        check_coarsened(&sessions, 1.5, block, factor).unwrap_or_else(|e| panic!("block {block} x {factor}: {e}"));
    }
}

proptest! {
    #![proptest_config(support::config(64, 0x7EE5))]

    #[test]
    fn coarsened_blocks_bound_their_poses(
        fleet in random_fleet(40, 1..4, 2.0), block in 1usize..9, factor in 1usize..6,
    ) {
        check_coarsened(&fleet.sessions(), fleet.gamma(), block, factor).map_err(TestCaseError::fail)?;
    }

    #[test]
    fn merge_trees_give_the_fleet_result(fleet in random_fleet(40, 1..4, 2.0), seed in any::<u64>()) {
        check_tree(&fleet.sessions(), fleet.gamma(), fleet.separation(), seed).map_err(TestCaseError::fail)?;
    }
}

#[test]
fn adversarial_fleets_merge_in_trees() {
    let sessions = adversarial_fleet(90, 60, 40, 70);
    for (k, gamma) in [0.5, 1.5, 4.0].into_iter().enumerate() {
        for separation in [Separation::NONE, Separation::path(3.0 * gamma)] {
            check_tree(&sessions, gamma, separation, k as u64)
                .unwrap_or_else(|e| panic!("γ = {gamma}, {separation}: {e}"));
        }
    }
}

/// Sessions of 1,500 poses in blocks of hundreds: a tile's scan keeps only the stretches of its
/// rows and columns that come within γ of the other side (chunks of 64 poses), within a session
/// (with and without a separation) and between sessions; the result is the fleet's.
#[test]
fn long_sessions_scan_only_where_their_blocks_meet() {
    let sessions = support::fleets::district_walks(3, 1500, 6.0, 18);
    for separation in [Separation::NONE, Separation::path(3.0)] {
        check_tree_cut(&sessions, 1.0, separation, 5, &[1, 3, 7]).unwrap_or_else(|e| panic!("{separation}: {e}"));
    }
}

/// A small summary with components and edge runs, for the byte tests.
fn some_summary() -> TileSummary {
    let fleet =
        Fleet::new(vec![("a".into(), tour(60, 0.0, [0.0, 0.0])), ("b".into(), tour(50, 3.0, [0.5, 0.0]))]).unwrap();
    let tiles = plan_tiles(&fleet, &Euclidean, 1.5, 20).unwrap();
    let tile = tiles.iter().find(|t| t.sessions == [0, 1]).unwrap();
    let summary = scan_tile(&fleet, &Euclidean, 1.5, Separation::NONE, tile).unwrap();
    assert!(!summary.components.is_empty() && !summary.edges.is_empty());
    summary
}

fn corrupt_message(result: Result<TileSummary, Error>) -> String {
    match result {
        Err(e @ Error::InvalidState { .. }) => e.to_string(),
        other => panic!("expected InvalidState, got {other:?}"),
    }
}

#[test]
fn bytes_round_trip_and_fail_clearly() {
    let summary = some_summary();
    let bytes = summary.to_bytes();
    assert_eq!(&bytes[..4], b"ILts");
    assert_eq!(u16::from_le_bytes([bytes[4], bytes[5]]), TILE_FORMAT_VERSION);
    assert_eq!(TileSummary::from_bytes(&bytes).unwrap(), summary);
    // Cut short anywhere.
    for len in 0..bytes.len() {
        let message = corrupt_message(TileSummary::from_bytes(&bytes[..len]));
        assert!(message.starts_with("invalid saved tile summary: "), "{message}");
    }
    // A byte too many.
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(corrupt_message(TileSummary::from_bytes(&longer)).contains("1 bytes left over"));
    // Another kind, another version, something else.
    let merge = TileMerge::new(summary.clone()).unwrap().to_bytes();
    assert!(corrupt_message(TileSummary::from_bytes(&merge)).contains("these are the bytes of a tile merge"));
    assert_eq!(TileMerge::from_bytes(&merge).unwrap(), TileMerge::new(summary.clone()).unwrap());
    let mut newer = bytes.clone();
    newer[4..6].copy_from_slice(&(TILE_FORMAT_VERSION + 1).to_le_bytes());
    let message = corrupt_message(TileSummary::from_bytes(&newer));
    assert!(message.contains(&format!(
        "format version {}; this build reads versions {OLDEST_TILE_FORMAT_VERSION} to {TILE_FORMAT_VERSION}",
        TILE_FORMAT_VERSION + 1
    )));
    // Bytes of the oldest version read still is read as it was written; those before it are not.
    let mut older = bytes.clone();
    older[4..6].copy_from_slice(&OLDEST_TILE_FORMAT_VERSION.to_le_bytes());
    assert_eq!(TileSummary::from_bytes(&older).unwrap(), summary);
    older[4..6].copy_from_slice(&(OLDEST_TILE_FORMAT_VERSION - 1).to_le_bytes());
    assert!(corrupt_message(TileSummary::from_bytes(&older)).contains("this build reads versions"));
    assert!(corrupt_message(TileSummary::from_bytes(b"PK\x03\x04rest")).contains("start with \"PK\\u{3}\\u{4}\""));
    // A label that names no component, and a run outside its tile.
    let mut bad = summary.clone();
    bad.edges[0].label = bad.components.len() as u32;
    assert!(corrupt_message(TileSummary::from_bytes(&bad.to_bytes())).contains("label"));
    assert!(matches!(TileMerge::new(bad), Err(Error::InconsistentTiles { .. })));
    let mut outside = summary.clone();
    outside.edges[0].row = outside.tile.rows.end;
    assert!(corrupt_message(TileSummary::from_bytes(&outside.to_bytes())).contains("outside tile"));
}

#[test]
fn flipped_bytes_never_panic() {
    let summary = some_summary();
    let bytes = summary.to_bytes();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..2000 {
        let mut flipped = bytes.clone();
        for _ in 0..rng.random_range(1..4) {
            let k = rng.random_range(6..flipped.len());
            flipped[k] ^= 1 << rng.random_range(0..8);
        }
        // Either refused, or a summary that merges and finishes (to anything) without a panic.
        if let Ok(s) = TileSummary::from_bytes(&flipped) {
            let merged = TileMerge::merge(vec![TileMerge::new(s).unwrap(), TileMerge::new(summary.clone()).unwrap()]);
            if let Ok(m) = merged
                && let Ok(loops) = m.finish()
            {
                let _ = loops.session_pairs(&[1.0, 1.0]);
                let _ = loops.fleet_components(&[0, 60]);
            }
        }
    }
}

#[test]
fn a_tile_merged_twice_is_refused() {
    let summary = some_summary();
    let once = TileMerge::new(summary.clone()).unwrap();
    let err = TileMerge::merge(vec![once.clone(), once]).unwrap_err();
    assert!(err.to_string().contains("each tile summarised once"), "{err}");
}

#[test]
fn session_tiles_check_their_sessions() {
    let (a, b) = (tour(30, 0.0, [0.0, 0.0]), tour(20, 0.0, [0.0, 0.0]));
    let tile = Tile { sessions: [0, 1], rows: 0..10, columns: 30..40 };
    let scan = |starts: [usize; 2], tile: &Tile| {
        scan_session_tile([&a, &b], starts, &Euclidean, 1.0, Separation::NONE, tile, TileKeep::SUMMARY)
    };
    assert!(scan([0, 30], &tile).is_ok());
    // Columns beyond session b, and session b's indices inside session a's.
    assert!(matches!(scan([0, 25], &tile), Err(Error::InvalidParameter { name: "tile", .. })));
    assert!(matches!(scan([0, 20], &Tile { columns: 20..30, ..tile.clone() }), Err(Error::InvalidParameter { .. })));
    let flat = Trajectory::new((0..20).map(f64::from).collect(), (0..20).map(f64::from).collect(), 1).unwrap();
    let err = scan_session_tile([&a, &flat], [0, 30], &Euclidean, 1.0, Separation::NONE, &tile, TileKeep::SUMMARY)
        .unwrap_err();
    assert!(err.to_string().contains("has 1 coordinates, session 0 has 2"), "{err}");
    // Within one session: one start, tiles on or above the diagonal.
    let own = Tile { sessions: [0, 0], rows: 10..20, columns: 0..10 };
    let keep = TileKeep::SUMMARY.with_duration().with_runs();
    assert!(scan_session_tile([&a, &a], [0, 0], &Euclidean, 1.0, Separation::NONE, &own, keep).is_err());
    let blocks = [SessionBlocks::new(&a, &Euclidean, 8).unwrap(), SessionBlocks::new(&b, &Euclidean, 9).unwrap()];
    assert!(plan_session_tiles(&blocks, &Euclidean, 1.0).unwrap_err().to_string().contains("same block size"));
    assert!(SessionBlocks::new(&a, &Euclidean, 0).is_err());
}

/// The Euclidean distance, hidden from the planner's KD-tree (it is not declared the distance of
/// the coordinates): the planner compares every two blocks.
struct Hidden;

impl Metric for Hidden {
    fn name(&self) -> String {
        "hidden euclidean".into()
    }

    fn check_dim(&self, dim: usize) -> loops_core::Result<()> {
        Euclidean.check_dim(dim)
    }

    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        Euclidean.distance(a, b)
    }
}

/// The planner's KD-tree over block centres finds the tiles that comparing every two blocks
/// finds, on fleets of many small sessions spread over a city and on stacked identical ones.
#[test]
fn kd_tree_plans_equal_all_pairs_plans() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for case in 0..6 {
        let sessions: Vec<Trajectory> = (0..40)
            .map(|k| {
                let offset = if case % 2 == 0 {
                    [rng.random_range(0.0..300.0), rng.random_range(0.0..300.0)]
                } else {
                    [0.0, 0.0]
                };
                tour(20 + rng.random_range(0..60), k as f64, offset)
            })
            .collect();
        for (gamma, block) in [(0.5, 7), (3.0, 16), (25.0, 40)] {
            let blocks: Vec<SessionBlocks> =
                sessions.iter().map(|s| SessionBlocks::new(s, &Euclidean, block).unwrap()).collect();
            let fast = plan_session_tiles(&blocks, &Euclidean, gamma).unwrap();
            let slow = plan_session_tiles(&blocks, &Hidden, gamma).unwrap();
            assert_eq!(fast, slow, "case {case}, γ = {gamma}, block {block}");
            assert!(!fast.is_empty());
        }
    }
}
