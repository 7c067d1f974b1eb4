//! Samples and τ from tiles equal the fleet's in memory: keyed draws over the merged statistics,
//! each tile offering its pairs after a rescan or from the runs its scan kept, give `sample_fleet`'s samples pair for pair for
//! 1, 2 and 7 tiles per session pair and any thread count, for every sampler of components,
//! budgets and rates, between sessions only or not, trivial components skipped or not; a fleet
//! of one session has the session's groups, quotas and row picks; a fleet's keys follow its
//! sessions' names, not their place; τ from the tiles' shares is `FleetLoops::loop_duration`'s.

mod support;

use loops_core::{
    Euclidean, SampleSize, Sampler, SamplerKind, Separation, Trajectory, find_loops_separated,
    fleet::{Fleet, FleetLoops, FleetOptions, find_fleet_loops, sample_fleet},
    sample::{DrawCandidates, DrawRequest, KeyLayout, KeyedDraw, pair_key},
    sample_loops,
    tile::{
        SessionBlocks, TileDuration, TileKeep, TileMerge, TileRuns, TileSummary, draw_session_tile, draw_tile_runs,
        plan_session_tiles, scan_session_tile, session_loop_duration, tile_requests,
    },
    with_threads,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use support::fleets::tour;

const SIGMAS: [SamplerKind; 7] = [
    SamplerKind::One,
    SamplerKind::Rho,
    SamplerKind::RhoDispersed,
    SamplerKind::Alpha,
    SamplerKind::ClosestFirst,
    SamplerKind::ClosestThenSpread,
    SamplerKind::NearestThenUniform,
];

/// Random walks in a 30 m square that cross each other often, with stops (repeated poses).
fn walks(seed: u64) -> Vec<Trajectory> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..rng.random_range(3..5))
        .map(|k| {
            let n = rng.random_range(60..160);
            let mut p = [rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0)];
            let mut t = 100.0 * k as f64;
            let (mut times, mut points) = (Vec::new(), Vec::new());
            for _ in 0..n {
                if rng.random::<f64>() > 0.15 {
                    p = [p[0] + rng.random_range(-1.0..1.0), p[1] + rng.random_range(-1.0..1.0)];
                }
                t += rng.random_range(0.05..0.3);
                times.push(t);
                points.push(p);
            }
            Trajectory::from_points(times, &points).unwrap()
        })
        .collect()
}

fn adversarial() -> Vec<Trajectory> {
    let a = tour(90, 0.0, [0.0, 0.0]);
    let points: Vec<[f64; 2]> = (0..a.len()).rev().map(|k| [a.point(k)[0], a.point(k)[1]]).collect();
    let reversed = Trajectory::from_points((0..a.len()).map(|k| 1e5 + k as f64).collect(), &points).unwrap();
    let parked = Trajectory::from_points((0..60).map(|k| k as f64 * 0.1).collect(), &vec![[10.0, 0.0]; 60]).unwrap();
    vec![a.clone(), a, reversed, parked, tour(70, 7.0, [5e3, -5e3])]
}

/// A tile's share of τ on every row and column of the tile (0 outside its stretches).
fn dense_values(d: &TileDuration) -> [Vec<f64>; 2] {
    let dense = |stretches: &[(usize, Vec<f64>)], len: usize| {
        let mut out = vec![0.0; len];
        for (offset, values) in stretches {
            out[*offset..offset + values.len()].copy_from_slice(values);
        }
        out
    };
    [dense(&d.rows, d.tile.rows.len()), dense(&d.columns, d.tile.columns.len())]
}

/// A tile's share of τ as format version 2 saved it: tag `ILtd`, the version, then the tile and
/// a value for every row and column, in MessagePack.
fn dense_bytes(d: &TileDuration) -> Vec<u8> {
    let [rows, columns] = dense_values(d);
    let mut bytes = b"ILtd".to_vec();
    bytes.extend_from_slice(&2u16.to_le_bytes());
    bytes.extend(rmp_serde::to_vec(&(&d.tile, rows, columns)).unwrap());
    bytes
}

/// `value`'s bytes as format version 3 wrote them (tag `tag`): long arrays of numbers as
/// MessagePack arrays, not packed.
fn unpacked_bytes<T: serde::Serialize>(tag: &[u8; 4], value: &T) -> Vec<u8> {
    let mut bytes = tag.to_vec();
    bytes.extend_from_slice(&3u16.to_le_bytes());
    value.serialize(&mut rmp_serde::Serializer::new(&mut bytes).with_human_readable()).unwrap();
    bytes
}

/// The fleet's tiles, scanned (with their shares of τ) and merged in one step through bytes.
struct Tiled {
    merged: loops_core::tile::MergedLoops,
    durations: Vec<TileDuration>,
    starts: Vec<usize>,
    /// Each tile's runs as its scan kept them.
    runs: std::collections::HashMap<loops_core::tile::Tile, TileRuns>,
}

fn tiled(sessions: &[Trajectory], gamma: f64, separation: Separation, per_pair: usize) -> Tiled {
    let longest = sessions.iter().map(Trajectory::len).max().unwrap();
    let block = longest.div_ceil(per_pair).max(1);
    let blocks: Vec<SessionBlocks> =
        sessions.iter().map(|s| SessionBlocks::new(s, &Euclidean, block).unwrap()).collect();
    let tiles = plan_session_tiles(&blocks, &Euclidean, gamma).unwrap();
    let mut starts = vec![0];
    for s in sessions {
        starts.push(starts.last().unwrap() + s.len());
    }
    let (mut parts, mut durations, mut runs) = (Vec::new(), Vec::new(), std::collections::HashMap::new());
    for tile in &tiles {
        let [a, b] = tile.sessions;
        let pair = [&sessions[a], &sessions[b]];
        let scan =
            |keep| scan_session_tile(pair, [starts[a], starts[b]], &Euclidean, gamma, separation, tile, keep).unwrap();
        let timed = scan(TileKeep::SUMMARY.with_duration());
        let (summary, duration) = (timed.summary, timed.duration.unwrap());
        let kept = scan(TileKeep::SUMMARY.with_duration().with_runs());
        assert_eq!((&kept.summary, &kept.duration), (&summary, &Some(duration.clone())), "{tile:?}: keeping its runs");
        let kept = kept.runs.unwrap();
        assert_eq!(kept.tile(), tile);
        // Bytes of version 3 (arrays of numbers) read back as those of this version (packed).
        assert_eq!(TileRuns::from_bytes(&unpacked_bytes(b"ILtr", &kept)).unwrap(), kept, "{tile:?}");
        assert_eq!(TileRuns::from_bytes(&kept.to_bytes()).unwrap(), kept, "{tile:?}");
        assert_ne!(unpacked_bytes(b"ILtr", &kept)[6..], kept.to_bytes()[6..], "{tile:?}: packed as arrays");
        assert_eq!(TileSummary::from_bytes(&unpacked_bytes(b"ILts", &summary)).unwrap(), summary, "{tile:?}");
        assert_eq!(TileDuration::from_bytes(&unpacked_bytes(b"ILtt", &duration)).unwrap(), duration, "{tile:?}");
        runs.insert(tile.clone(), kept);
        parts.push(TileMerge::new(TileSummary::from_bytes(&summary.to_bytes()).unwrap()).unwrap());
        let read = TileDuration::from_bytes(&duration.to_bytes()).unwrap();
        let dense = dense_values(&read);
        assert_eq!(dense_values(&TileDuration::from_bytes(&dense_bytes(&read)).unwrap()), dense, "{tile:?}");
        durations.push(read);
    }
    // Two levels: pairs of tiles, then all of those.
    let mut level = Vec::new();
    let mut rest = parts.into_iter();
    while let Some(first) = rest.next() {
        let merged = TileMerge::merge([first].into_iter().chain(rest.next()).collect()).unwrap();
        level.push(TileMerge::from_bytes(&merged.to_bytes()).unwrap());
    }
    let merged = TileMerge::merge(level).unwrap().finish().unwrap();
    assert_eq!(loops_core::tile::MergedLoops::from_bytes(&unpacked_bytes(b"ILml", &merged)).unwrap(), merged);
    assert_eq!(loops_core::tile::MergedLoops::from_bytes(&merged.to_bytes()).unwrap(), merged);
    assert_ne!(unpacked_bytes(b"ILml", &merged)[6..], merged.to_bytes()[6..], "components packed as arrays");
    starts.pop();
    Tiled { merged, durations, starts, runs }
}

/// The samples of a keyed draw over tiles, as (pair in fleet indices, component, δ, times).
type Drawn = Vec<([usize; 2], usize, f64, [f64; 2])>;

fn draw_from_tiles(
    sessions: &[Trajectory],
    t: &Tiled,
    gamma: f64,
    separation: Separation,
    sampler: &Sampler,
    between_only: bool,
    kept: bool,
) -> (Drawn, usize, u64) {
    let stats = t.merged.draw_stats();
    let blocks: Vec<[usize; 2]> = t.merged.components().iter().map(|m| m.sessions).collect();
    let keep = |c: usize| !between_only || blocks[c][0] != blocks[c][1];
    let names: Vec<String> = (0..sessions.len()).map(|k| format!("s{k}")).collect();
    let keys = KeyLayout::sessions(&t.starts, &names);
    let mut draw = KeyedDraw::with_keys(sampler, &stats, &keep, keys).unwrap();
    let mut passes = 0;
    while let Some(request) = draw.request().cloned() {
        passes += 1;
        assert!(passes < 10, "the draw does not end");
        for (k, part) in tile_requests(&t.merged, &request).into_iter().enumerate() {
            let Some(part) = part else { continue };
            let part = DrawRequest::from_bytes(&part.to_bytes()).unwrap();
            let tile = &t.merged.tiles()[k];
            let [a, b] = tile.sessions;
            let (pair, starts, labels) =
                ([&sessions[a], &sessions[b]], [t.starts[a], t.starts[b]], t.merged.tile_labels(k));
            let offers = if kept {
                draw_tile_runs(pair, starts, &Euclidean, &t.runs[tile], labels, &part)
            } else {
                draw_session_tile(pair, starts, &Euclidean, gamma, separation, tile, labels, &part)
            }
            .unwrap();
            draw.absorb(DrawCandidates::from_bytes(&offers.to_bytes()).unwrap());
        }
        draw.complete();
    }
    let picks = draw.picks().unwrap().iter().map(|p| (p.pair, p.component, p.distance, p.times_s)).collect();
    (picks, draw.groups(), draw.available())
}

fn in_memory(
    fleet: &Fleet,
    loops: &FleetLoops,
    sampler: &Sampler,
    between_only: bool,
    threads: usize,
) -> (Drawn, usize, u64) {
    let samples =
        with_threads(Some(threads), || sample_fleet(fleet, &Euclidean, loops, sampler, between_only)).unwrap().unwrap();
    let located = fleet.localize(&samples).unwrap();
    let drawn = samples
        .rows()
        .iter()
        .zip(&located)
        .map(|(s, l)| (s.pair.unwrap(), s.component.unwrap(), s.distance.unwrap(), l.times_s))
        .collect();
    (drawn, samples.groups(), samples.available())
}

fn samplers() -> Vec<Sampler> {
    let mut out = Vec::new();
    for (k, kind) in SIGMAS.into_iter().enumerate() {
        for size in [SampleSize::Budget(3), SampleSize::Budget(40), SampleSize::Budget(700)] {
            out.push(Sampler::new(kind, size, 11 + k as u64));
        }
        let rate = match kind {
            SamplerKind::Alpha => 0.05,
            SamplerKind::One => 2.0,
            _ => 0.3,
        };
        out.push(Sampler::new(kind, SampleSize::Rate(rate), 5));
        out.push(Sampler { skip_trivial: true, ..Sampler::new(kind, SampleSize::Budget(60), 2) });
    }
    out
}

fn check_fleet(sessions: &[Trajectory], gamma: f64, separation: Separation) {
    let named = sessions.iter().enumerate().map(|(k, t)| (format!("s{k}"), t.clone())).collect();
    let fleet = Fleet::new(named).unwrap();
    let options = FleetOptions { separation, ..FleetOptions::default() };
    let loops = find_fleet_loops(&fleet, &Euclidean, gamma, &options).unwrap();
    let (own, other) = loops.loop_duration();
    for per_pair in [1, 2, 7] {
        let t = tiled(sessions, gamma, separation, per_pair);
        // τ from the tiles' shares.
        for (a, s) in sessions.iter().enumerate() {
            let (o, x) = session_loop_duration(a, t.starts[a], s.len(), &t.durations).unwrap();
            let range = t.starts[a]..t.starts[a] + s.len();
            for (got, want) in [(&o, &own[range.clone()]), (&x, &other[range])] {
                for (k, (g, w)) in got.iter().zip(want.iter()).enumerate() {
                    assert!(
                        (g - w).abs() <= 1e-9 * (1.0 + w.abs()),
                        "{per_pair} tiles, session {a} pose {k}: τ {g} != {w}"
                    );
                }
            }
        }
        for (s, sampler) in samplers().into_iter().enumerate() {
            for between_only in [false, true] {
                let expected = in_memory(&fleet, &loops, &sampler, between_only, 1);
                // Half the draws from the runs the scans kept, half from rescans.
                let kept = (s + usize::from(between_only)) % 2 == 0;
                let got = draw_from_tiles(sessions, &t, gamma, separation, &sampler, between_only, kept);
                assert_eq!(
                    got, expected,
                    "{per_pair} tiles per pair, {:?} {:?} skip_trivial {} between_only {between_only}, {separation}, kept runs {kept}",
                    sampler.kind, sampler.size, sampler.skip_trivial
                );
                if per_pair == 2 {
                    assert_eq!(in_memory(&fleet, &loops, &sampler, between_only, 2), expected, "threads change it");
                }
            }
        }
    }
}

#[test]
fn random_fleets_draw_from_tiles_as_in_memory() {
    for seed in 0..3 {
        check_fleet(&walks(seed), 1.5, Separation::NONE);
    }
    check_fleet(&walks(7), 1.5, Separation::path(3.0));
}

/// Long sessions, whose tiles are scanned on the stretches where their blocks meet.
#[test]
fn long_sessions_draw_from_tiles_as_in_memory() {
    let sessions = support::fleets::district_walks(3, 700, 6.0, 3);
    for separation in [Separation::NONE, Separation::path(3.0)] {
        check_fleet(&sessions, 1.0, separation);
    }
}

#[test]
fn adversarial_fleets_draw_from_tiles_as_in_memory() {
    for separation in [Separation::NONE, Separation::path(4.5)] {
        check_fleet(&adversarial(), 1.5, separation);
    }
}

/// A fleet of one session is that session (on another clock): the same groups, pairs available
/// and quotas for every sampler of components (σ_α: the same count under a budget), and the same pairs for those that pick rows'
/// closest pairs only; uniform picks differ, since a fleet keys its pairs by session name.
#[test]
fn a_fleet_of_one_samples_as_the_session_alone() {
    let drive = walks(3).remove(0);
    let fleet = Fleet::new(vec![("only".into(), drive.clone())]).unwrap();
    let loops = find_fleet_loops(&fleet, &Euclidean, 1.5, &FleetOptions::default()).unwrap();
    let alone = find_loops_separated(&drive, &Euclidean, 1.5, Separation::NONE).unwrap();
    let mut uniform_differs = 0;
    for sampler in samplers() {
        let a = sample_fleet(&fleet, &Euclidean, &loops, &sampler, false).unwrap();
        let b = sample_loops(&drive, &Euclidean, &alone, &sampler).unwrap();
        let key = |s: &loops_core::Samples| -> Vec<_> {
            s.rows().iter().map(|r| (r.pair, r.component, r.distance.map(f64::to_bits))).collect()
        };
        let per_component = |s: &loops_core::Samples| {
            let mut counts = std::collections::BTreeMap::new();
            s.rows().iter().for_each(|r| *counts.entry(r.component).or_insert(0) += 1);
            counts
        };
        let what = format!("{:?} {:?}", sampler.kind, sampler.size);
        assert!(!b.is_empty());
        assert_eq!((a.groups(), a.available()), (b.groups(), b.available()), "{what}");
        if sampler.kind == SamplerKind::Alpha {
            // A budget's count; a rate's is random.
            if let SampleSize::Budget(_) = sampler.size {
                assert_eq!(a.len(), b.len(), "{what}");
            }
        } else {
            assert_eq!(per_component(&a), per_component(&b), "{what}");
        }
        // Budgets below the components' rows: no uniform pick.
        let rows_only = matches!(
            sampler.kind,
            SamplerKind::RhoDispersed | SamplerKind::ClosestFirst | SamplerKind::ClosestThenSpread
        ) && matches!(sampler.size, SampleSize::Budget(b) if b <= 40);
        if rows_only {
            assert_eq!(key(&a), key(&b), "{what}");
        } else if key(&a) != key(&b) {
            uniform_differs += 1;
        }
    }
    assert!(uniform_differs > 0, "the session's name keys no uniform pick");
}

/// A fleet keys a pair by its sessions' names and its own poses: moving the sessions (others
/// added or removed before them) leaves the key, another name gives another; one trajectory's
/// keys are `pair_key`'s.
#[test]
fn fleet_keys_follow_the_sessions_not_their_place() {
    let single = KeyLayout::default();
    for (i, j) in [(0, 1), (5, 70), (63, 64), (1000, 1300)] {
        assert_eq!(single.pair_key(4, i, j), pair_key(4, i, j));
    }
    let here = KeyLayout::sessions(&[0, 100, 250], &["a", "b", "c"]);
    let moved = KeyLayout::sessions(&[0, 40, 160, 310], &["0", "a", "b", "c"]);
    let renamed = KeyLayout::sessions(&[0, 100, 250], &["a", "x", "c"]);
    let (mut same, mut other) = (0, 0);
    for (i, j) in [(3, 120), (110, 130), (120, 260), (99, 100), (5, 7), (260, 299)] {
        let shift = |f: usize| if f >= 100 { f + 60 } else { f + 40 };
        assert_eq!(here.pair_key(9, i, j), moved.pair_key(9, shift(i), shift(j)), "({i}, {j})");
        same += 1;
        let in_b = (100..250).contains(&i) || (100..250).contains(&j);
        if in_b {
            assert_ne!(here.pair_key(9, i, j), renamed.pair_key(9, i, j), "({i}, {j})");
            other += 1;
        } else {
            assert_eq!(here.pair_key(9, i, j), renamed.pair_key(9, i, j), "({i}, {j})");
        }
    }
    assert_eq!((same, other), (6, 4));
    // Two sessions' pairs at the same own indices have other keys.
    assert_ne!(here.pair_key(9, 3, 20), here.pair_key(9, 103, 120));
}

/// Keys are uniform: the share of keys below a threshold is the threshold's fraction, and
/// σ_1's picks within one component spread over its pairs as a uniform draw does.
#[test]
fn keys_are_uniform_and_independent_of_the_block() {
    let n = 200_000;
    let below = (0..n).filter(|&k| pair_key(9, k / 300, k % 300 + 1) < u64::MAX / 4).count();
    let share = below as f64 / n as f64;
    assert!((share - 0.25).abs() < 0.005, "{share}");
    // Seeds and rows give other keys; the same cell the same key.
    assert_ne!(pair_key(1, 5, 70), pair_key(2, 5, 70));
    assert_ne!(pair_key(1, 5, 70), pair_key(1, 6, 70));
    assert_eq!(pair_key(1, 5, 70), pair_key(1, 5, 70));
}

/// Runs kept by one tile's scan answer only that tile's draws, with its labels and its sessions'
/// starts: anything else is an error, not other pairs.
#[test]
fn kept_runs_refuse_another_tile() {
    let sessions = walks(3);
    let t = tiled(&sessions, 1.5, Separation::NONE, 2);
    let stats = t.merged.draw_stats();
    let mut draw =
        KeyedDraw::new(&Sampler::new(SamplerKind::Rho, SampleSize::Budget(50), 1), &stats, &|_| true).unwrap();
    let request = draw.request().cloned().unwrap();
    let parts = tile_requests(&t.merged, &request);
    let (k, part) = parts.iter().enumerate().find_map(|(k, p)| p.as_ref().map(|p| (k, p))).unwrap();
    let tile = &t.merged.tiles()[k];
    let [a, b] = tile.sessions;
    let (pair, starts, labels) = ([&sessions[a], &sessions[b]], [t.starts[a], t.starts[b]], t.merged.tile_labels(k));
    let runs = &t.runs[tile];
    assert!(runs.run_count() > 0);
    assert!(runs.heap_bytes() >= 16 * runs.run_count());
    let good = draw_tile_runs(pair, starts, &Euclidean, runs, labels, part).unwrap();
    draw.absorb(good);
    let fewer = &labels[..labels.len() - 1];
    let moved = [starts[0] + 1, starts[1] + 1];
    for (labels, starts) in [(fewer, starts), (labels, moved)] {
        let err = draw_tile_runs(pair, starts, &Euclidean, runs, labels, part).unwrap_err();
        assert!(matches!(err, loops_core::Error::InconsistentTiles { .. }), "{err}");
    }
}
