//! A fleet store kept up by random sequences of adds, replacements and removals gives the
//! from-scratch answer: `find_fleet_loops` and `sample_fleet` over its sessions in name order
//! (components and the overlap matrix, areas to rounding; τ; samples pair for pair), and the
//! same stored tiles, bit for bit, as a store made in one update of the final sessions.

use std::collections::{BTreeMap, HashMap};

use loops_core::{
    Euclidean, Result, SampleSize, Sampler, SamplerKind, Separation, Trajectory, UrbanDrive, UrbanFleet,
    fleet::{Fleet, FleetOptions, find_fleet_loops, sample_fleet},
    store::{FleetStore, ScannedTile, StoreSession, StoreSettings},
    tile::{MergedLoops, TileRuns},
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const GAMMA_M: f64 = 8.0;

/// Two versions of each session of a small city fleet (a corrected trajectory is another
/// drive under the same name).
fn versions() -> BTreeMap<String, [Trajectory; 2]> {
    let spec = |seed: u64| UrbanFleet {
        vehicles: 3,
        days: 2,
        drive: UrbanDrive { duration_s: 50.0, rate_hz: 4.0, city_size_m: 300.0, seed, ..UrbanDrive::default() },
        start_spread_s: 600.0,
    };
    let (a, b) = (spec(3).generate().unwrap(), spec(4).generate().unwrap());
    (0..a.len()).map(|k| (a.names()[k].clone(), [a.session(k).clone(), b.session(k).clone()])).collect()
}

fn close(got: f64, want: f64) -> bool {
    (got - want).abs() <= 1e-9 * (1.0 + want.abs())
}

fn samplers() -> Vec<(Sampler, bool)> {
    vec![
        (Sampler::new(SamplerKind::Rho, SampleSize::Budget(30), 5), false),
        (Sampler::new(SamplerKind::ClosestFirst, SampleSize::Budget(20), 6), true),
        (Sampler::new(SamplerKind::Alpha, SampleSize::Rate(0.01), 7), false),
    ]
}

/// The store's answer against the from-scratch one over `sessions` (name → trajectory); the
/// number of tiles its draws answered from what earlier draws found in them.
fn check_against_scratch(store: &FleetStore, sessions: &BTreeMap<String, Trajectory>, context: &str) -> usize {
    let names: Vec<&str> = store.sessions().iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, sessions.keys().map(String::as_str).collect::<Vec<_>>(), "{context}: sessions");
    let loops = store.loops().unwrap();
    if sessions.is_empty() {
        assert!(loops.components().is_empty() && loops.session_pairs().is_empty(), "{context}");
        return 0;
    }
    let settings = store.settings();
    let fleet = Fleet::new(sessions.iter().map(|(n, t)| (n.clone(), t.clone())).collect()).unwrap();
    let options = FleetOptions { separation: settings.separation, ..FleetOptions::default() };
    let scratch = find_fleet_loops(&fleet, &Euclidean, settings.gamma, &options).unwrap();
    let want = scratch.components();
    assert_eq!(loops.components().len(), want.len(), "{context}: component count");
    for (g, w) in loops.components().iter().zip(&want) {
        assert!(close(g.area_s2, w.area_s2), "{context}: area of {w:?}: {}", g.area_s2);
        let g = loops_core::fleet::FleetComponent { area_s2: w.area_s2, ..g.clone() };
        assert_eq!(&g, w, "{context}: component");
    }
    let want = scratch.session_pairs();
    assert_eq!(loops.session_pairs().len(), want.len(), "{context}: overlap matrix entries");
    for (g, w) in loops.session_pairs().iter().zip(&want) {
        assert_eq!((g.sessions, g.components, g.pair_count), (w.sessions, w.components, w.pair_count), "{context}");
        assert!(close(g.area_s2, w.area_s2) && close(g.density, w.density), "{context}: {g:?} vs {w:?}");
    }
    let (own, other) = store.loop_duration().unwrap();
    let (want_own, want_other) = scratch.loop_duration();
    for (got, want) in [(&own, &want_own), (&other, &want_other)] {
        assert_eq!(got.len(), want.len(), "{context}: τ length");
        assert!(got.iter().zip(want.iter()).all(|(g, w)| close(*g, *w)), "{context}: τ");
    }
    let mut source = source_of(sessions);
    let mut cached = 0;
    for (sampler, between_only) in samplers() {
        let got = store.samples(&loops, &sampler, between_only, &mut source).unwrap();
        cached += got.tiles_asked - got.tiles_read;
        let samples = sample_fleet(&fleet, &Euclidean, &scratch, &sampler, between_only).unwrap();
        let want = fleet.localize(&samples).unwrap();
        assert_eq!(got.rows, want, "{context}: samples of {:?} {:?}", sampler.kind, sampler.size);
        assert_eq!((got.groups, got.available), (samples.groups(), samples.available()), "{context}");
        assert_eq!(got.warnings, samples.warnings(), "{context}");
    }
    cached
}

/// A source that gives each stored session's poses from `sessions`.
fn source_of(sessions: &BTreeMap<String, Trajectory>) -> impl FnMut(&StoreSession) -> Result<Trajectory> + '_ {
    |s: &StoreSession| Ok(sessions[&s.name].clone())
}

fn settings(separation: Separation) -> StoreSettings {
    StoreSettings { gamma: GAMMA_M, separation, block: 64, ..StoreSettings::new(GAMMA_M) }
}

/// Random updates from an empty store; after each, the from-scratch answer, and at the end the
/// tiles of a store made at once.
fn random_updates(seed: u64, separation: Separation) {
    let pool = versions();
    let names: Vec<String> = pool.keys().cloned().collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut store = FleetStore::new(settings(separation)).unwrap();
    // What the store should hold: name → version.
    let mut held: BTreeMap<String, usize> = BTreeMap::new();
    let (mut scans, mut cached) = (0, 0);
    for step in 0..9 {
        let absent: Vec<&String> = names.iter().filter(|n| !held.contains_key(*n)).collect();
        let present: Vec<String> = held.keys().cloned().collect();
        let mut put = Vec::new();
        let mut remove = Vec::new();
        let kind = rng.random_range(0..6);
        match kind {
            // Add one or two sessions (a day's drives at once).
            0..=2 if !absent.is_empty() => {
                for _ in 0..rng.random_range(1..=2.min(absent.len())) {
                    let name = absent[rng.random_range(0..absent.len())].clone();
                    if put.iter().all(|(n, _)| *n != name) {
                        let version = rng.random_range(0..2);
                        put.push((name.clone(), pool[&name][version].clone()));
                        held.insert(name, version);
                    }
                }
            }
            // Replace a session by its other version (or by itself: nothing to scan).
            3 | 4 if !present.is_empty() => {
                let name = present[rng.random_range(0..present.len())].clone();
                let version = if rng.random::<f64>() < 0.8 { 1 - held[&name] } else { held[&name] };
                put.push((name.clone(), pool[&name][version].clone()));
                held.insert(name, version);
            }
            // Remove a session, and maybe add another in the same update.
            _ if !present.is_empty() => {
                let name = present[rng.random_range(0..present.len())].clone();
                held.remove(&name);
                remove.push(name);
                if let Some(&new) = absent.first() {
                    put.push((new.clone(), pool[new][0].clone()));
                    held.insert(new.clone(), 0);
                }
            }
            _ => {
                let name = absent[0].clone();
                put.push((name.clone(), pool[&name][0].clone()));
                held.insert(name, 0);
            }
        }
        let current: BTreeMap<String, Trajectory> =
            held.iter().map(|(n, &v)| (n.clone(), pool[n][v].clone())).collect();
        let mut source = source_of(&current);
        let update = store.update(put, &remove, &mut source).unwrap().clone();
        scans += update.tiles_scanned;
        // Only the tiles of changed sessions are scanned.
        let changed: Vec<usize> = update.changed().iter().map(|n| store.session_index(n).unwrap()).collect();
        let touching = store.tiles().iter().filter(|t| t.tile().sessions.iter().any(|s| changed.contains(s))).count();
        assert_eq!(update.tiles_scanned, touching, "seed {seed} step {step}: {update:?}");
        cached += check_against_scratch(&store, &current, &format!("seed {seed} step {step} ({kind}, {update:?})"));
    }
    // The draws after an update answered tiles it left alone from what the draws before found.
    assert!(cached > 0, "seed {seed}: no tile answered from an earlier draw");
    // The same tiles as a store made in one update, bit for bit.
    let current: BTreeMap<String, Trajectory> = held.iter().map(|(n, &v)| (n.clone(), pool[n][v].clone())).collect();
    let mut at_once = FleetStore::new(settings(separation)).unwrap();
    let all: Vec<(String, Trajectory)> = current.iter().map(|(n, t)| (n.clone(), t.clone())).collect();
    at_once.update(all, &[], &mut source_of(&current)).unwrap();
    assert_eq!(store.sessions(), at_once.sessions(), "seed {seed}");
    assert!(store.tiles() == at_once.tiles(), "seed {seed}: the stored tiles depend on the order of the updates");
    assert!(scans > 0, "seed {seed}");
    // Parts read back are accepted; a missing tile is not.
    let parts = |tiles: Vec<loops_core::store::StoredTile>| {
        FleetStore::from_parts(*store.settings(), store.sessions().to_vec(), tiles, store.last_update().clone())
    };
    let read_back = parts(store.stored_tiles().unwrap()).unwrap();
    assert_eq!(read_back, store);
    // What the store kept of its answer through the updates (the merges of its session pairs,
    // moved; τ, added to; the runs of its tiles) is what a store read back makes again from
    // the tiles alone (merging all, adding up τ, rescanning for the draws).
    let (kept, again) = (store.loops().unwrap(), read_back.loops().unwrap());
    assert_eq!(kept.components(), again.components(), "seed {seed}: kept merges");
    assert_eq!(kept.session_pairs(), again.session_pairs(), "seed {seed}: kept merges");
    assert_eq!(kept.component_times_s(), again.component_times_s(), "seed {seed}: kept merges");
    check_against_scratch(&read_back, &current, &format!("seed {seed}: read back"));
    // What the store kept, through its bytes, taken back: the same answer, drawn without a scan.
    let merges: Vec<([usize; 2], MergedLoops)> =
        store.kept_merges().map(|(p, m)| (p, MergedLoops::from_bytes(&m.to_bytes()).unwrap())).collect();
    let runs: Vec<Option<TileRuns>> = store
        .kept_runs()
        .unwrap()
        .into_iter()
        .map(|r| Some(TileRuns::from_bytes(&r.expect("every tile scanned").to_bytes()).unwrap()))
        .collect();
    let saved = |merges: Vec<([usize; 2], MergedLoops)>, runs: Vec<Option<TileRuns>>| {
        let (settings, sessions, tiles) = (*store.settings(), store.sessions().to_vec(), store.stored_tiles().unwrap());
        FleetStore::from_saved(settings, sessions, tiles, store.last_update().clone(), merges, runs)
    };
    let taken = saved(merges.clone(), runs.clone()).unwrap();
    check_against_scratch(&taken, &current, &format!("seed {seed}: taken back"));
    let loops = taken.loops().unwrap();
    for (sampler, between_only) in samplers() {
        let drawn = taken.samples(&loops, &sampler, between_only, &mut source_of(&current)).unwrap();
        assert_eq!(drawn.tiles_rescanned, 0, "seed {seed}: {:?}", sampler.kind);
        // A store read back again, which has drawn nothing yet.
        let fresh = parts(store.stored_tiles().unwrap()).unwrap();
        let again = fresh.samples(&loops, &sampler, between_only, &mut source_of(&current)).unwrap();
        assert!(again.tiles_rescanned > 0 || again.rows.is_empty(), "seed {seed}: a store without runs rescans");
        assert_eq!((again.rows, again.tiles_read), (drawn.rows, drawn.tiles_asked), "seed {seed}");
    }
    if merges.len() > 1 {
        let err = saved(merges[1..].to_vec(), runs.clone()).unwrap_err().to_string();
        assert!(err.contains("merges for the"), "{err}");
        let mut swapped = merges.clone();
        let first = swapped[0].1.clone();
        swapped[0].1 = swapped[1].1.clone();
        swapped[1].1 = first;
        let err = saved(swapped, runs.clone()).unwrap_err().to_string();
        assert!(err.contains("is not of their"), "{err}");
    }
    if runs.len() > 1 {
        let mut swapped = runs.clone();
        swapped.swap(0, 1);
        let err = saved(merges.clone(), swapped).unwrap_err().to_string();
        assert!(err.contains("the runs of tile 0 are not of tile"), "{err}");
    }
    if store.tiles().len() > 1 {
        let mut fewer = store.stored_tiles().unwrap();
        fewer.remove(fewer.len() / 2);
        let err = parts(fewer).unwrap_err().to_string();
        assert!(err.contains("but the plan of the sessions has"), "{err}");
    }
}

#[test]
fn random_updates_give_the_answer_from_scratch() {
    for seed in 0..4 {
        random_updates(seed, Separation::NONE);
    }
}

#[test]
fn random_updates_with_a_separation_give_the_answer_from_scratch() {
    random_updates(11, Separation::path(20.0));
}

/// Bad updates leave the store as it was, with a message naming the session.
#[test]
fn refused_updates_change_nothing() {
    let pool = versions();
    let mut store = FleetStore::new(settings(Separation::NONE)).unwrap();
    let first: Vec<(String, Trajectory)> = pool.iter().take(2).map(|(n, v)| (n.clone(), v[0].clone())).collect();
    let current: BTreeMap<String, Trajectory> = first.iter().cloned().collect();
    store.update(first, &[], &mut source_of(&current)).unwrap();
    let before = store.clone();
    let name = current.keys().next().unwrap().clone();
    let flat = Trajectory::new(vec![0.0, 1.0, 2.0], vec![0.0, 1.0, 2.0], 1).unwrap();
    type Case<'a> = (Vec<(String, Trajectory)>, Vec<String>, &'a str);
    let cases: Vec<Case> = vec![
        (vec![], vec!["nobody".into()], "\"nobody\" is not in the store"),
        (vec![(name.clone(), pool[&name][1].clone())], vec![name.clone()], "is both given and removed"),
        (vec![("flat".into(), flat)], vec![], "session \"flat\" has 1 coordinates"),
    ];
    for (put, remove, message) in cases {
        let err = store.update(put, &remove, &mut source_of(&current)).unwrap_err().to_string();
        assert!(err.contains(message), "{err}");
        assert_eq!(store, before);
    }
    // A source that gives other poses for a stored session.
    let third = pool.iter().nth(2).map(|(n, v)| (n.clone(), v[0].clone())).unwrap();
    let mut wrong = |_: &StoreSession| Ok(pool[&third.0][1].clone());
    let err = store.update(vec![third.clone()], &[], &mut wrong).unwrap_err().to_string();
    assert!(err.contains("are not those stored"), "{err}");
    assert_eq!(store, before);
    assert!(store.add(vec![(name.clone(), pool[&name][0].clone())], &mut source_of(&current)).is_err());
    assert!(store.replace(vec![(third.0, third.1)], &mut source_of(&current)).is_err());
    assert_eq!(store, before);
}

/// An update that changes nothing (nothing given, nothing removed, or stored sessions given
/// again with the same content) leaves the store exactly as it was, what the last update that
/// changed it did included, and says so; so does the plan applied step by step.
#[test]
fn an_update_that_changes_nothing_leaves_the_store_as_it_was() {
    let pool = versions();
    let mut store = FleetStore::new(settings(Separation::NONE)).unwrap();
    let first: Vec<(String, Trajectory)> = pool.iter().take(3).map(|(n, v)| (n.clone(), v[0].clone())).collect();
    let current: BTreeMap<String, Trajectory> = first.iter().cloned().collect();
    store.update(first.clone(), &[], &mut source_of(&current)).unwrap();
    let before = store.clone();
    let names: Vec<String> = first.iter().map(|(n, _)| n.clone()).collect();
    for put in [vec![], first.clone(), first[1..].to_vec()] {
        let given: Vec<String> = put.iter().map(|(n, _)| n.clone()).collect();
        let update = store.update(put, &[], &mut source_of(&current)).unwrap().clone();
        assert!(update.added.is_empty() && update.replaced.is_empty() && update.removed.is_empty(), "{update:?}");
        assert_eq!((update.unchanged, update.tiles_scanned), (given, 0));
        assert_eq!(store, before, "an update that changes nothing changed the store");
        assert_eq!(store.last_update().added, names);
    }
    let sessions = first.iter().map(|(n, t)| StoreSession::new(n.clone(), t, store.settings()).unwrap()).collect();
    let plan = store.plan_update(sessions, &[]).unwrap();
    assert!(plan.changes_nothing() && plan.tiles().is_empty());
    assert!(store.apply_update(&plan, Vec::new()).unwrap().changes_nothing());
    assert_eq!(store, before);
}

/// Adding the last day scans only its tiles: far fewer than all.
#[test]
fn a_new_day_scans_its_own_tiles_only() {
    let pool = versions();
    let mut store = FleetStore::new(settings(Separation::NONE)).unwrap();
    let (day0, day1): (Vec<_>, Vec<_>) =
        pool.iter().map(|(n, v)| (n.clone(), v[0].clone())).partition(|(n, _)| n.ends_with("day0"));
    let all: HashMap<String, Trajectory> = pool.iter().map(|(n, v)| (n.clone(), v[0].clone())).collect();
    let mut source = |s: &StoreSession| Ok(all[&s.name].clone());
    store.update(day0, &[], &mut source).unwrap();
    let update = store.update(day1, &[], &mut source).unwrap().clone();
    assert_eq!(update.tiles_kept + update.tiles_scanned, store.tiles().len());
    assert!(update.tiles_kept > 0 && update.tiles_scanned > 0, "{update:?}");
}

/// `near` rules out the blocks far from the place by their stored balls, reads no session
/// with no block near, and finds the passes `passes_near` finds in every whole session, at
/// random points and polygons of the city and beyond it, and at random radii.
#[test]
fn near_skips_far_blocks_and_finds_every_pass() {
    let pool = versions();
    let sessions: BTreeMap<String, Trajectory> = pool.iter().map(|(n, v)| (n.clone(), v[0].clone())).collect();
    let mut store = FleetStore::new(StoreSettings { block: 16, ..settings(Separation::NONE) }).unwrap();
    let all: Vec<(String, Trajectory)> = sessions.iter().map(|(n, t)| (n.clone(), t.clone())).collect();
    store.update(all, &[], &mut source_of(&sessions)).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (mut passes, mut skipped) = (0, 0);
    for trial in 0..40 {
        let mut xy = || [rng.random_range(-50.0..350.0), rng.random_range(-50.0..350.0)];
        let place = if trial % 2 == 0 {
            loops_core::Place::point(xy()).unwrap()
        } else {
            loops_core::Place::polygon((0..3 + trial % 4).map(|_| xy()).collect()).unwrap()
        };
        let radius = rng.random_range(0.0..30.0);
        let mut read = 0;
        let mut counting = |s: &StoreSession| {
            read += 1;
            Ok(sessions[&s.name].clone())
        };
        let got = store.near(&place, Some(radius), &mut counting).unwrap();
        let want: Vec<(usize, loops_core::Pass)> = sessions
            .values()
            .enumerate()
            .flat_map(|(k, t)| loops_core::passes_near(t, &place, radius).unwrap().into_iter().map(move |p| (k, p)))
            .collect();
        assert_eq!(got.iter().map(|p| (p.session, p.pass)).collect::<Vec<_>>(), want, "trial {trial}");
        passes += want.len();
        skipped += sessions.len() - read;
    }
    // The places are such that both happen: passes found, sessions not read.
    assert!(passes > 20 && skipped > 20, "{passes} passes, {skipped} sessions not read");
}

/// An update by its steps — plan, each tile scanned on its own in any order and shipped as
/// bytes, apply — gives the store that `update` gives, bit for bit (its tiles, kept merges and
/// runs); apply refuses a plan of another state and scans that are not exactly the plan's,
/// leaving the store as it was.
#[test]
fn an_update_by_its_steps_is_the_update() {
    let pool = versions();
    let all: HashMap<String, Trajectory> = pool.iter().map(|(n, v)| (n.clone(), v[0].clone())).collect();
    let mut source = |s: &StoreSession| Ok(all[&s.name].clone());
    let (day0, day1): (Vec<_>, Vec<_>) =
        pool.iter().map(|(n, v)| (n.clone(), v[0].clone())).partition(|(n, _)| n.ends_with("day0"));
    let settings = settings(Separation::NONE);
    let mut store = FleetStore::new(settings).unwrap();
    store.update(day0, &[], &mut source).unwrap();
    // Day 1, with a day-0 session corrected.
    let (fixed, _) = pool.iter().find(|(n, _)| n.ends_with("day0")).unwrap();
    let mut put = day1.clone();
    put.push((fixed.clone(), pool[fixed][1].clone()));
    let mut whole = store.clone();
    whole.update(put.clone(), &[], &mut source).unwrap();

    let given: Vec<StoreSession> =
        put.iter().map(|(n, t)| StoreSession::new(n.clone(), t, &settings).unwrap()).collect();
    let plan = store.plan_update(given.clone(), &[]).unwrap();
    assert_eq!(plan.tiles().len(), whole.last_update().tiles_scanned);
    let poses = |s: usize| poses_of(&plan, s, &put, &all);
    let mut scanned: Vec<ScannedTile> = (0..plan.tiles().len())
        .rev()
        .map(|k| {
            let [a, b] = plan.tiles()[k].sessions;
            let scan = plan.scan_tile(k, [&poses(a), &poses(b)]).unwrap();
            ScannedTile::from_bytes(&scan.to_bytes()).unwrap()
        })
        .collect();
    // A group of tiles scanned together (each side's balls made once for the group) gives each
    // tile's own scan, bit for bit.
    let held: BTreeMap<usize, Trajectory> =
        plan.tiles().iter().flat_map(|t| t.sessions).map(|s| (s, poses(s))).collect();
    let group: Vec<usize> = (0..plan.tiles().len()).rev().step_by(2).collect();
    let sides: Vec<std::ops::Range<usize>> =
        group.iter().flat_map(|&k| [plan.tiles()[k].rows.clone(), plan.tiles()[k].columns.clone()]).collect();
    let distinct: std::collections::BTreeSet<(usize, usize)> = sides.iter().map(|r| (r.start, r.end)).collect();
    assert!(distinct.len() < sides.len(), "no side shared by two tiles of the group");
    let together = plan
        .scan_tiles(&group, |k| {
            let [a, b] = plan.tiles()[k].sessions;
            Ok([&held[&a], &held[&b]])
        })
        .unwrap();
    for (&k, scan) in group.iter().zip(&together) {
        assert_eq!(scan.to_bytes(), scanned[plan.tiles().len() - 1 - k].to_bytes(), "tile {k}");
    }
    let before = store.clone();
    let wrong =
        |store: &mut FleetStore, scanned: Vec<ScannedTile>| store.apply_update(&plan, scanned).unwrap_err().to_string();
    let missing = wrong(&mut store, scanned[1..].to_vec());
    assert!(missing.contains("was not scanned"), "{missing}");
    let twice = wrong(&mut store, [scanned.clone(), vec![scanned[0].clone()]].concat());
    assert!(twice.contains("scanned twice"), "{twice}");
    let other_plan = store.plan_update(given[..1].to_vec(), &[]).unwrap();
    let [a, b] = other_plan.tiles()[0].sessions;
    let (pa, pb) = (poses_of(&other_plan, a, &put, &all), poses_of(&other_plan, b, &put, &all));
    let foreign = other_plan.scan_tile(0, [&pa, &pb]).unwrap();
    let foreign = wrong(&mut store, [scanned[1..].to_vec(), vec![foreign]].concat());
    assert!(foreign.contains("was scanned for plan"), "{foreign}");
    assert!(ScannedTile::from_bytes(&scanned[0].to_bytes()[..40]).is_err());
    assert_eq!(store, before);
    // A plan made before another update is refused.
    let mut moved = store.clone();
    moved.remove(std::slice::from_ref(fixed)).unwrap();
    let stale = moved.apply_update(&plan, scanned.clone()).unwrap_err().to_string();
    assert!(stale.contains("is not of this store's state"), "{stale}");

    // A plan read back holds together; a forged one whose tile or start leaves its sessions
    // is refused as it is read, before a scan could read past them.
    let saved = serde_json::to_value(&plan).unwrap();
    let read: loops_core::store::UpdatePlan = serde_json::from_value(saved.clone()).unwrap();
    assert_eq!(read, plan);
    let forged = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut value = saved.clone();
        edit(&mut value);
        serde_json::from_value::<loops_core::store::UpdatePlan>(value).unwrap_err().to_string()
    };
    let far = forged(&|v| v["tiles"][0]["sessions"][1] = serde_json::json!(99));
    assert!(far.contains("tile 0") && far.contains("does not lie on the poses"), "{far}");
    let long = forged(&|v| v["tiles"][0]["rows"]["end"] = serde_json::json!(1_000_000_000u64));
    assert!(long.contains("tile 0"), "{long}");
    let start = forged(&|v| v["starts"][1] = serde_json::json!(7));
    assert!(start.contains("session 1 starts at pose 7"), "{start}");

    scanned.reverse();
    store.apply_update(&plan, scanned).unwrap();
    assert_eq!(store, whole);
    assert!(store.kept_merges().eq(whole.kept_merges()));
    assert!(store.kept_runs().unwrap() == whole.kept_runs().unwrap());
}

/// The poses of session `s` of `plan`: given, or stored.
fn poses_of(
    plan: &loops_core::store::UpdatePlan,
    s: usize,
    put: &[(String, Trajectory)],
    all: &HashMap<String, Trajectory>,
) -> Trajectory {
    let name = &plan.sessions()[s].name;
    put.iter().find(|(n, _)| n == name).map_or_else(|| all[name].clone(), |(_, t)| t.clone())
}

/// Saved draws as `keep_draws` takes them.
fn view(draws: &[(u64, Vec<u8>)]) -> Vec<(u64, &[u8])> {
    draws.iter().map(|(seed, b)| (*seed, b.as_slice())).collect()
}

/// What a draw finds in the tiles answers later draws of its seed only where it holds what they
/// ask: draws of one seed with budgets going up and down, between the updates of a store, each
/// equal to the draw over the fleet from scratch, some tiles answered from earlier draws.
#[test]
fn draws_of_one_seed_reuse_what_they_found_only_where_it_answers() {
    let pool = versions();
    let mut store = FleetStore::new(settings(Separation::NONE)).unwrap();
    let mut held: BTreeMap<String, Trajectory> = BTreeMap::new();
    let (mut cached, mut draws) = (0, 0);
    for (step, (name, v)) in pool.iter().enumerate() {
        held.insert(name.clone(), v[0].clone());
        store.update(vec![(name.clone(), v[0].clone())], &[], &mut source_of(&held)).unwrap();
        let fleet = Fleet::new(held.iter().map(|(n, t)| (n.clone(), t.clone())).collect()).unwrap();
        let scratch = find_fleet_loops(&fleet, &Euclidean, GAMMA_M, &FleetOptions::default()).unwrap();
        let loops = store.loops().unwrap();
        // σ_1 at one pair a component, then six: thresholds the first draw's slack covers, but
        // more pairs than it kept.
        let sizes = [
            (SamplerKind::Rho, SampleSize::Budget(40)),
            (SamplerKind::Rho, SampleSize::Budget(400)),
            (SamplerKind::One, SampleSize::Rate(1.0)),
            (SamplerKind::One, SampleSize::Rate(6.0)),
            (SamplerKind::NearestThenUniform, SampleSize::Budget(200)),
        ];
        for (kind, size) in sizes {
            let sampler = Sampler::new(kind, size, 3);
            let got = store.samples(&loops, &sampler, false, &mut source_of(&held)).unwrap();
            let want = fleet.localize(&sample_fleet(&fleet, &Euclidean, &scratch, &sampler, false).unwrap()).unwrap();
            assert_eq!(got.rows, want, "step {step}: {kind:?} {size:?}");
            cached += got.tiles_asked - got.tiles_read;
            draws += 1;
        }
    }
    assert!(cached > 0 && draws > 8, "{cached} tiles answered from earlier draws in {draws} draws");
    // What the draws found, as bytes, taken back by a store read back: its draw reads fewer
    // tiles and gives the same samples; damaged bytes are refused and leave it as it was.
    let sampler = Sampler::new(SamplerKind::Rho, SampleSize::Budget(400), 3);
    store.samples(&store.loops().unwrap(), &sampler, false, &mut source_of(&held)).unwrap();
    let saved = store.kept_draws();
    assert!(saved.len() == 1 && saved[0].1.len() > 100, "{saved:?}");
    let (settings, sessions, tiles) = (*store.settings(), store.sessions().to_vec(), store.stored_tiles().unwrap());
    let fresh =
        || FleetStore::from_parts(settings, sessions.clone(), tiles.clone(), store.last_update().clone()).unwrap();
    let (with, without) = (fresh(), fresh());
    let mut damaged = saved.clone();
    let at = damaged[0].1.len() - 20;
    damaged[0].1[at] ^= 1;
    let err = without.keep_draws(&view(&damaged)).unwrap_err().to_string();
    assert!(err.contains("checksum"), "{err}");
    with.keep_draws(&view(&saved)).unwrap();
    let loops = with.loops().unwrap();
    let a = with.samples(&loops, &sampler, false, &mut source_of(&held)).unwrap();
    let b = without.samples(&loops, &sampler, false, &mut source_of(&held)).unwrap();
    assert_eq!(a.rows, b.rows);
    assert!(a.tiles_read < b.tiles_read, "{} against {} tiles read", a.tiles_read, b.tiles_read);
}

/// A new day leaves the draw where it was: with a budget below the number of components, each
/// component's quota is rounded by its own permanent number and its rows spread by it, so
/// the draw after adding a day (371 components, then an eighth more sessions) reads again few
/// of the tiles it asks — σ_ρ 64 of 429 (171 of 444 when quotas were rounded along the
/// components), the default sampler's closest pairs of rows 36 of 299 (all 292 when only pools
/// were kept); and every draw is the draw over the fleet from scratch.
#[test]
fn a_new_day_leaves_most_of_the_draw_where_it_was() {
    let fleet = UrbanFleet {
        vehicles: 4,
        days: 8,
        drive: UrbanDrive { duration_s: 60.0, rate_hz: 4.0, city_size_m: 300.0, seed: 8, ..UrbanDrive::default() },
        start_spread_s: 600.0,
    }
    .generate()
    .unwrap();
    let all: BTreeMap<String, Trajectory> =
        (0..fleet.len()).map(|k| (fleet.names()[k].clone(), fleet.session(k).clone())).collect();
    let (last, before): (Vec<_>, Vec<_>) = all.clone().into_iter().partition(|(n, _)| n.ends_with("day7"));
    let mut store = FleetStore::new(settings(Separation::NONE)).unwrap();
    store.update(before, &[], &mut source_of(&all)).unwrap();
    let components = store.loops().unwrap().components().len();
    for kind in [SamplerKind::Rho, SamplerKind::NearestThenUniform] {
        let sampler = Sampler::new(kind, SampleSize::Budget(components / 4), 5);
        store.samples(&store.loops().unwrap(), &sampler, false, &mut source_of(&all)).unwrap();
    }
    store.update(last, &[], &mut source_of(&all)).unwrap();
    let scratch_fleet = Fleet::new(all.iter().map(|(n, t)| (n.clone(), t.clone())).collect()).unwrap();
    let scratch = find_fleet_loops(&scratch_fleet, &Euclidean, GAMMA_M, &FleetOptions::default()).unwrap();
    for kind in [SamplerKind::Rho, SamplerKind::NearestThenUniform] {
        let sampler = Sampler::new(kind, SampleSize::Budget(components / 4), 5);
        let got = store.samples(&store.loops().unwrap(), &sampler, false, &mut source_of(&all)).unwrap();
        let want = scratch_fleet
            .localize(&sample_fleet(&scratch_fleet, &Euclidean, &scratch, &sampler, false).unwrap())
            .unwrap();
        assert_eq!(got.rows, want, "{kind:?}");
        assert!(
            3 * got.tiles_read < got.tiles_asked,
            "{kind:?}: {} of the {} tiles asked read again ({components} components before the day)",
            got.tiles_read,
            got.tiles_asked
        );
    }
}

/// A tile kept as saved in its sessions' own indices, counting how often it is read.
#[derive(Debug)]
struct Counted {
    stored: loops_core::store::StoredTile,
    runs: Option<TileRuns>,
    reads: std::sync::Arc<[std::sync::atomic::AtomicUsize; 2]>,
}

impl loops_core::store::SavedTile for Counted {
    fn stored(&self) -> Result<loops_core::store::StoredTile> {
        self.reads[0].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(self.stored.clone())
    }

    fn runs(&self) -> Result<Option<TileRuns>> {
        self.reads[1].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(self.runs.clone())
    }
}

/// `store` as read back lazily from what it saves (each tile in its sessions' own indices,
/// counting its reads in `reads`: summaries, runs), with its merges and τ.
fn read_lazily(store: &FleetStore, reads: &std::sync::Arc<[std::sync::atomic::AtomicUsize; 2]>) -> Result<FleetStore> {
    let starts = store.starts();
    let runs = store.kept_runs()?;
    let tiles = store
        .stored_tiles()?
        .into_iter()
        .zip(runs)
        .map(|(t, r)| {
            let [a, b] = t.tile().sessions;
            let saved =
                Counted { stored: t.local([starts[a], starts[b]]), runs: r.map(TileRuns::local), reads: reads.clone() };
            (t.tile().clone(), std::sync::Arc::new(saved) as std::sync::Arc<dyn loops_core::store::SavedTile>)
        })
        .collect();
    let merges = store.kept_merges().map(|(pair, m)| (pair, m.clone())).collect();
    let (own, other) = store.loop_duration()?;
    let duration = store
        .sessions()
        .iter()
        .zip(&starts)
        .map(|(s, &first)| (own[first..first + s.poses()].to_vec(), other[first..first + s.poses()].to_vec()))
        .collect();
    let (settings, sessions, last) = (*store.settings(), store.sessions().to_vec(), store.last_update().clone());
    FleetStore::from_saved_lazily(settings, sessions, tiles, last, merges, duration)
}

/// A store read back lazily reads no old tile to add a session, the runs of the tiles its
/// draws ask alone, and to replace a session the kept tiles of the sessions that lose a tile,
/// each once; its answers and tiles are those from scratch all along. What it is given is
/// checked: τ of the wrong length, or a tile saved as another, is refused.
#[test]
fn a_store_read_lazily_reads_only_the_tiles_its_updates_and_draws_need() {
    use std::sync::atomic::Ordering::Relaxed;
    let pool = versions();
    let names: Vec<String> = pool.keys().cloned().collect();
    // The session added sorts first: every old tile moves in the fleet.
    let (day, first) = names.split_first().unwrap();
    let mut current: BTreeMap<String, Trajectory> = first.iter().map(|n| (n.clone(), pool[n][0].clone())).collect();
    let mut store = FleetStore::new(settings(Separation::NONE)).unwrap();
    let put = current.iter().map(|(n, t)| (n.clone(), t.clone())).collect();
    store.update(put, &[], &mut source_of(&current)).unwrap();
    let reads = std::sync::Arc::new([std::sync::atomic::AtomicUsize::new(0), std::sync::atomic::AtomicUsize::new(0)]);
    let mut lazy = read_lazily(&store, &reads).unwrap();
    assert!(lazy.tiles().iter().all(|t| !t.is_read()));
    assert_eq!((reads[0].load(Relaxed), reads[1].load(Relaxed)), (0, 0), "reading back");

    // A day's session added: no old tile read.
    current.insert(day.clone(), pool[day][0].clone());
    let update = lazy.update(vec![(day.clone(), pool[day][0].clone())], &[], &mut source_of(&current)).unwrap();
    assert!(update.tiles_scanned > 0 && update.tiles_kept > 0, "{update:?}");
    assert_eq!((reads[0].load(Relaxed), reads[1].load(Relaxed)), (0, 0), "adding a session");
    check_against_scratch(&lazy, &current, "read lazily, a session added");
    let runs_read = reads[1].load(Relaxed);
    assert!(
        runs_read > 0 && runs_read <= update.tiles_kept,
        "{runs_read} runs read of {} old tiles",
        update.tiles_kept
    );
    assert_eq!(reads[0].load(Relaxed), 0, "drawing reads runs alone");

    // A session replaced: the kept tiles of the sessions that lose one are read, once (those
    // the last update scanned are at hand).
    let name = first[0].clone();
    let s = lazy.session_index(&name).unwrap();
    let lose: Vec<usize> = lazy
        .tiles()
        .iter()
        .filter(|t| t.tile().sessions.contains(&s))
        .flat_map(|t| t.tile().sessions)
        .filter(|&x| x != s)
        .collect();
    let want = lazy
        .tiles()
        .iter()
        .filter(|t| !t.tile().sessions.contains(&s) && t.tile().sessions.iter().any(|x| lose.contains(x)))
        .filter(|t| !t.is_read())
        .count();
    assert!(want > 0);
    current.insert(name.clone(), pool[&name][1].clone());
    lazy.update(vec![(name.clone(), pool[&name][1].clone())], &[], &mut source_of(&current)).unwrap();
    assert_eq!(reads[0].load(Relaxed), want, "replacing a session reads the kept tiles of those that lose one");
    check_against_scratch(&lazy, &current, "read lazily, a session replaced");
    // The first session removed: every tile moves, those read and those not.
    current.remove(day);
    lazy.remove(std::slice::from_ref(day)).unwrap();
    check_against_scratch(&lazy, &current, "read lazily, a session removed");
    let mut at_once = FleetStore::new(settings(Separation::NONE)).unwrap();
    let all = current.iter().map(|(n, t)| (n.clone(), t.clone())).collect();
    at_once.update(all, &[], &mut source_of(&current)).unwrap();
    assert!(
        lazy.tiles() == at_once.tiles(),
        "the tiles of a store read lazily and updated, against those made at once"
    );

    // What is given is checked: τ of another length; a tile saved as another.
    let (settings, sessions, last_update) = (*store.settings(), store.sessions().to_vec(), store.last_update().clone());
    let merges = || store.kept_merges().map(|(pair, m)| (pair, m.clone())).collect::<Vec<_>>();
    let tiles = || {
        let starts = store.starts();
        store
            .stored_tiles()
            .unwrap()
            .into_iter()
            .map(|t| {
                let [a, b] = t.tile().sessions;
                let saved = Counted { stored: t.local([starts[a], starts[b]]), runs: None, reads: reads.clone() };
                (t.tile().clone(), std::sync::Arc::new(saved) as std::sync::Arc<dyn loops_core::store::SavedTile>)
            })
            .collect::<Vec<_>>()
    };
    let short = vec![(vec![0.0; 1], vec![0.0; 1]); sessions.len()];
    let err = FleetStore::from_saved_lazily(settings, sessions.clone(), tiles(), last_update.clone(), merges(), short)
        .unwrap_err()
        .to_string();
    assert!(err.contains("τ of 1 and 1 poses for session 0"), "{err}");
    // A value no τ can be, in two sessions: the first is named.
    let (own, other_s) = store.loop_duration().unwrap();
    let mut at = 0;
    let mut bad: Vec<(Vec<f64>, Vec<f64>)> = sessions
        .iter()
        .map(|s| {
            at += s.poses();
            (own[at - s.poses()..at].to_vec(), other_s[at - s.poses()..at].to_vec())
        })
        .collect();
    let last = bad.len() - 1;
    bad[1].1[2] = f64::NAN;
    bad[last].0[0] = -1.0;
    let err = FleetStore::from_saved_lazily(settings, sessions.clone(), tiles(), last_update.clone(), merges(), bad)
        .unwrap_err()
        .to_string();
    assert!(err.contains("τ of pose 2 of session 1") && err.contains("NaN"), "{err}");
    // A merge whose first component draws from a row past its session: named, with the rows.
    let mut altered = merges();
    let mut bytes = altered[0].1.to_bytes();
    // Tag and version, the array of the merge's fields, the header of its packed components;
    // then the first component's record: its loop component (105 bytes), sessions (16), times
    // (32), then the draw's statistics, whose rows follow a flag.
    let header = match bytes[7] {
        0xc4 => 2,
        0xc5 => 3,
        _ => 5,
    };
    let at = 6 + 1 + header + 105 + 16 + 32 + 1;
    bytes[at..at + 8].copy_from_slice(&(1u64 << 40).to_le_bytes());
    altered[0].1 = loops_core::tile::MergedLoops::from_bytes(&bytes).unwrap();
    let (own, other_s) = store.loop_duration().unwrap();
    let kept: Vec<(Vec<f64>, Vec<f64>)> = sessions
        .iter()
        .zip(store.starts())
        .map(|(s, f)| (own[f..f + s.poses()].to_vec(), other_s[f..f + s.poses()].to_vec()))
        .collect();
    let err = FleetStore::from_saved_lazily(settings, sessions.clone(), tiles(), last_update.clone(), altered, kept)
        .unwrap_err()
        .to_string();
    assert!(err.contains("component 0 of the merge of sessions") && err.contains("1099511627776"), "{err}");
    let mut swapped = tiles();
    let k = swapped.iter().position(|(t, _)| t.sessions[0] != t.sessions[1]).unwrap();
    let other = swapped.iter().position(|(t, _)| t.sessions[0] == t.sessions[1]).unwrap();
    let moved = swapped[other].1.clone();
    swapped[k].1 = moved;
    let (own, other_s) = store.loop_duration().unwrap();
    let starts = store.starts();
    let duration = sessions
        .iter()
        .zip(&starts)
        .map(|(s, &f)| (own[f..f + s.poses()].to_vec(), other_s[f..f + s.poses()].to_vec()))
        .collect();
    let swapped = FleetStore::from_saved_lazily(settings, sessions, swapped, last_update, merges(), duration).unwrap();
    let err = swapped.stored_tiles().unwrap_err().to_string();
    assert!(err.contains("it was saved as tile") && !err.contains('\n'), "{err}");
}
