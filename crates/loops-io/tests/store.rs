//! A fleet store's folder: what is written reads back as the same store (sessions, tiles bit
//! for bit, settings, poses), its tables hold the store's answer, and a refused update leaves
//! every file as it was.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use loops_core::{
    SampleSize, Sampler, SamplerKind, Trajectory, UrbanDrive, UrbanFleet,
    store::{FleetStore, StoreSession, StoreSettings},
};
use loops_io::store::{StoreConfig, read_samples, read_store, update_opened_store, update_store, update_store_scanned};

fn sessions() -> Vec<(String, Trajectory)> {
    let spec = UrbanFleet {
        vehicles: 2,
        days: 2,
        drive: UrbanDrive { duration_s: 40.0, rate_hz: 4.0, city_size_m: 300.0, seed: 9, ..UrbanDrive::default() },
        start_spread_s: 600.0,
    };
    let fleet = spec.generate().unwrap();
    (0..fleet.len()).map(|k| (fleet.names()[k].clone(), fleet.session(k).clone())).collect()
}

fn config() -> StoreConfig {
    StoreConfig {
        settings: StoreSettings { block: 50, ..StoreSettings::new(8.0) },
        sampler: Some((Sampler::new(SamplerKind::Rho, SampleSize::Budget(20), 3), false)),
    }
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("loops-io-store-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                out.insert(path.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

#[test]
fn a_store_reads_back_as_written() {
    let dir = temp("round-trip");
    let all = sessions();
    let (day0, day1): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|(n, _)| n.ends_with("day0"));
    update_store(&dir, Some(&config()), day0.clone(), &[]).unwrap();
    let report = update_store(&dir, None, day1.clone(), &[]).unwrap();
    assert_eq!(report.stored.state, "state-000002");
    let names = |d: &Path| {
        let mut n: Vec<String> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        n.sort();
        n
    };
    assert_eq!(names(&dir), ["loops-store.json", "poses", "state-000002", "store.json"], "the old state is removed");
    // One pose file a session, beside the states.
    assert_eq!(pose_files(&dir), pose_files_of(&report.stored.store));
    let read = read_store(&dir).unwrap();
    assert_eq!(read.config, config());
    assert_eq!(read.store, report.stored.store);
    // The same store as one made in memory.
    let by_name: BTreeMap<String, Trajectory> = all.iter().cloned().collect();
    let mut source = |s: &StoreSession| Ok(by_name[&s.name].clone());
    let mut memory = FleetStore::new(config().settings).unwrap();
    memory.update(all.clone(), &[], &mut source).unwrap();
    assert!(memory.tiles() == read.store.tiles());
    assert_eq!(memory.sessions(), read.store.sessions());
    // Poses read back exactly (the fingerprint is checked on reading).
    for s in read.store.sessions() {
        assert_eq!(read.poses(s).unwrap(), by_name[&s.name], "{}", s.name);
    }
    // The components table holds the store's components.
    let loops = memory.loops().unwrap();
    let rows = parquet_rows(&read.table("components.parquet"));
    assert_eq!(rows, loops.components().len());
    assert_eq!(parquet_rows(&read.table("loop_duration.parquet")), all.iter().map(|(_, t)| t.len()).sum::<usize>());
    let drawn = &report.samples.as_ref().unwrap().rows;
    assert!(!drawn.is_empty());
    assert_eq!(parquet_rows(&read.table("samples.parquet")), drawn.len());
    // Read back as drawn, and as drawn in memory.
    assert_eq!(&read_samples(&read).unwrap(), drawn);
    let (sampler, between_only) = config().sampler.unwrap();
    assert_eq!(&memory.samples(&loops, &sampler, between_only, &mut source).unwrap().rows, drawn);
    assert_eq!(report.added_components, read.store.added_components(&loops).len());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every entry under `dir` (and `dir` itself) with its modification time, and each file's bytes.
fn times_and_bytes(dir: &Path) -> BTreeMap<PathBuf, (std::time::SystemTime, Option<Vec<u8>>)> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(path) = stack.pop() {
        let time = std::fs::metadata(&path).unwrap().modified().unwrap();
        let bytes = if path.is_dir() {
            stack.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
            None
        } else {
            Some(std::fs::read(&path).unwrap())
        };
        out.insert(path, (time, bytes));
    }
    out
}

/// An update that changes nothing (nothing given, the stored sessions given again, or scans of
/// no tile) writes nothing: no new state, every file and time of the folder as it was, and the
/// store's last update still the one that changed it; the report says nothing changed.
#[test]
fn an_update_that_changes_nothing_writes_nothing() {
    let dir = temp("unchanged");
    let all = sessions();
    let (day0, day1): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|(n, _)| n.ends_with("day0"));
    update_store(&dir, Some(&config()), day0.clone(), &[]).unwrap();
    let written = update_store(&dir, None, day1.clone(), &[]).unwrap();
    let before = times_and_bytes(&dir);
    std::thread::sleep(std::time::Duration::from_millis(20));
    type Again = (Option<StoreConfig>, Vec<(String, Trajectory)>);
    let again: [Again; 4] =
        [(None, vec![]), (Some(config()), vec![]), (None, day1.clone()), (Some(config()), all.clone())];
    for (config, put) in again {
        let report = update_store(&dir, config.as_ref(), put.clone(), &[]).unwrap();
        assert!(report.update.changes_nothing() && report.update.tiles_scanned == 0, "{:?}", report.update);
        assert_eq!(report.update.unchanged.len(), put.len());
        assert_eq!(report.stored.state, "state-000002", "a new state for an update that changes nothing");
        assert_eq!(report.stored.store.last_update(), written.stored.store.last_update());
        assert_eq!(report.components, written.components);
        assert_eq!(report.added_components, written.added_components);
        assert!(times_and_bytes(&dir) == before, "an update that changes nothing touched the folder");
    }
    let report = update_store_scanned(&dir, None, day1, &[], Vec::new()).unwrap();
    assert!(report.update.changes_nothing());
    assert!(times_and_bytes(&dir) == before, "an update that changes nothing touched the folder");
    // Its refusals are those of any update, and write nothing either.
    assert!(update_store(&dir, None, vec![], &["nobody".to_owned()]).is_err());
    assert!(times_and_bytes(&dir) == before);
    let _ = std::fs::remove_dir_all(&dir);
}

fn parquet_rows(path: &Path) -> usize {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    let reader = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    reader.metadata().file_metadata().num_rows() as usize
}

#[test]
fn a_refused_update_changes_no_file() {
    let dir = temp("refused");
    let all = sessions();
    update_store(&dir, Some(&config()), all[..2].to_vec(), &[]).unwrap();
    let before = snapshot(&dir);
    let name = all[0].0.clone();
    let err = update_store(&dir, None, vec![all[0].clone()], std::slice::from_ref(&name)).unwrap_err().to_string();
    assert!(err.contains("is both given and removed"), "{err}");
    let other = StoreConfig { settings: StoreSettings { gamma: 9.0, ..config().settings }, ..config() };
    let err = update_store(&dir, Some(&other), vec![all[2].clone()], &[]).unwrap_err().to_string();
    assert!(err.contains("gamma is 8 in the store, not 9"), "{err}");
    assert_eq!(snapshot(&dir), before);
    // A file of the user's in the folder is left alone; a folder of theirs is not made a store.
    let theirs = temp("theirs");
    std::fs::create_dir_all(&theirs).unwrap();
    std::fs::write(theirs.join("notes.txt"), "mine").unwrap();
    assert!(update_store(&theirs, Some(&config()), all[..1].to_vec(), &[]).is_err());
    assert_eq!(std::fs::read_to_string(theirs.join("notes.txt")).unwrap(), "mine");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&theirs);
}

/// Samples, bit for bit.
fn sample_bits(rows: &[loops_core::fleet::FleetSample]) -> Vec<([usize; 4], [u64; 3], Option<usize>)> {
    rows.iter()
        .map(|s| {
            let distance = s.distance.map_or(u64::MAX, f64::to_bits);
            (
                [s.sessions[0], s.sessions[1], s.poses[0], s.poses[1]],
                [s.times_s[0].to_bits(), s.times_s[1].to_bits(), distance],
                s.component,
            )
        })
        .collect()
}

/// A store's answer, bit for bit: components, the overlap matrix, τ, and the samples of
/// `config()`'s sampler with the number of tiles the draw rescanned.
fn answer(store: &FleetStore, source: &mut loops_core::store::SessionSource<'_>) -> (String, Vec<u64>, usize) {
    let loops = store.loops().unwrap();
    let (own, other) = store.loop_duration().unwrap();
    let (sampler, between_only) = config().sampler.unwrap();
    let samples = store.samples(&loops, &sampler, between_only, source).unwrap();
    let mut bits: Vec<u64> = own.iter().chain(&other).map(|v| v.to_bits()).collect();
    for c in loops.components() {
        bits.extend([c.area_s2.to_bits(), c.closest_distance.to_bits()]);
    }
    for p in loops.session_pairs() {
        bits.extend([p.area_s2.to_bits(), p.density.to_bits()]);
    }
    let text = format!("{:?}\n{:?}\n{:?}", loops.components(), loops.session_pairs(), sample_bits(&samples.rows));
    (text, bits, samples.tiles_rescanned)
}

#[test]
fn a_reopened_store_draws_and_updates_as_kept_in_memory_without_a_scan() {
    let dir = temp("reopened");
    let all = sessions();
    let by_name: BTreeMap<String, Trajectory> = all.iter().cloned().collect();
    let mut source = |s: &StoreSession| Ok(by_name[&s.name].clone());
    let (day0, day1): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|(n, _)| n.ends_with("day0"));
    // Kept in memory: the store the first update made, updated in process.
    let mut memory = update_store(&dir, Some(&config()), day0.clone(), &[]).unwrap().stored.store;
    // From scratch: one update of the same sessions into an empty store.
    let scratch = |sessions: &[(String, Trajectory)]| {
        let mut store = FleetStore::new(config().settings).unwrap();
        store.update(sessions.to_vec(), &[], &mut |s: &StoreSession| Ok(by_name[&s.name].clone())).unwrap();
        store
    };
    let reopened = read_store(&dir).unwrap();
    let (got, got_bits, rescanned) = answer(&reopened.store, &mut source);
    assert_eq!(rescanned, 0, "the reopened store rescans no tile to draw");
    let (kept, kept_bits, _) = answer(&memory, &mut source);
    let (fresh, fresh_bits, _) = answer(&scratch(&day0), &mut source);
    assert!(got == kept && got_bits == kept_bits, "reopened against kept in memory");
    assert!(got == fresh && got_bits == fresh_bits, "reopened against from scratch");
    // The next update, from the folder (read back, then updated), against memory and scratch.
    let report = update_store(&dir, None, day1.clone(), &[]).unwrap();
    assert_eq!(report.stored.store.last_update().tiles_kept, memory.tiles().len());
    assert_eq!(report.samples.as_ref().unwrap().tiles_rescanned, 0, "the update's draw rescans no stored tile");
    memory.update(day1.clone(), &[], &mut source).unwrap();
    let (got, got_bits, _) = answer(&read_store(&dir).unwrap().store, &mut source);
    let (kept, kept_bits, _) = answer(&memory, &mut source);
    let (fresh, fresh_bits, _) = answer(&scratch(&all), &mut source);
    assert!(got == kept && got_bits == kept_bits, "updated from the folder against kept in memory");
    assert!(got == fresh && got_bits == fresh_bits, "updated from the folder against from scratch");
    assert_eq!(
        sample_bits(&read_samples(&read_store(&dir).unwrap()).unwrap()),
        sample_bits(&report.samples.unwrap().rows)
    );
    // The folder keeps what the update's draw found: read back, the same draw answers tiles
    // from it (and gives the same samples, compared above); a damaged copy is refused by name.
    let reread = read_store(&dir).unwrap();
    let (sampler, between_only) = config().sampler.unwrap();
    let drawn = reread.store.samples(&reread.store.loops().unwrap(), &sampler, between_only, &mut source).unwrap();
    assert!(drawn.tiles_read < drawn.tiles_asked, "{} of {} tiles read", drawn.tiles_read, drawn.tiles_asked);
    let draws = dir.join(&reread.state).join("draws.parquet");
    std::fs::write(&draws, b"not parquet").unwrap();
    let err = read_store(&dir).unwrap_err().to_string();
    assert!(err.contains("draws.parquet"), "{err}");
    std::fs::remove_file(&draws).unwrap();
    let without = read_store(&dir).unwrap();
    let drawn = without.store.samples(&without.store.loops().unwrap(), &sampler, between_only, &mut source).unwrap();
    assert_eq!(drawn.tiles_read, drawn.tiles_asked, "a state without draws reads every tile asked");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The files of a store's folder but its marker (which names its folder).
fn state_files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    snapshot(dir).into_iter().filter(|(p, _)| p != Path::new("loops-store.json")).collect()
}

#[test]
fn an_update_starts_from_the_opened_store_while_the_folder_holds_it() {
    let (a, b) = (temp("opened-a"), temp("opened-b"));
    let all = sessions();
    let (day0, day1): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|(n, _)| n.ends_with("day0"));
    for dir in [&a, &b] {
        update_store(dir, Some(&config()), day0.clone(), &[]).unwrap();
    }
    // Current: the state's tables are not read again (a damaged one does not stop the update),
    // and what is written is what an update that reads them writes.
    let opened = read_store(&a).unwrap();
    std::fs::write(a.join(&opened.state).join("loop_duration.parquet"), b"damaged").unwrap();
    let from_opened = update_opened_store(opened, None, day1.clone(), &[], None).unwrap();
    let from_folder = update_store(&b, None, day1.clone(), &[]).unwrap();
    assert_eq!(from_opened.stored.store, from_folder.stored.store);
    assert_eq!(state_files(&a), state_files(&b));

    // Stale: the folder moved on (another update removed a session), so it is read.
    let stale = read_store(&a).unwrap();
    let first = vec![day0[0].clone()];
    for dir in [&a, &b] {
        update_store(dir, None, Vec::new(), &[first[0].0.clone()]).unwrap();
    }
    let from_stale = update_opened_store(stale, None, first.clone(), &[], None).unwrap();
    assert!(!from_stale.update.changes_nothing(), "the removed session is added again");
    assert_eq!(from_stale.stored.store, update_store(&b, None, first.clone(), &[]).unwrap().stored.store);
    assert_eq!(state_files(&a), state_files(&b));

    // A store made again in the same folder, up to the same state's name: read too.
    let old = read_store(&a).unwrap();
    for dir in [&a, &b] {
        std::fs::remove_dir_all(dir).unwrap();
        update_store(dir, Some(&config()), day1.clone(), &[]).unwrap();
        update_store(dir, None, first.clone(), &[]).unwrap();
        update_store(dir, None, Vec::new(), &[first[0].0.clone()]).unwrap();
        update_store(dir, None, first.clone(), &[]).unwrap();
    }
    assert_eq!(read_store(&a).unwrap().state, old.state);
    let from_old = update_opened_store(old, None, day0.clone(), &[], None).unwrap();
    assert_eq!(from_old.stored.store, update_store(&b, None, day0.clone(), &[]).unwrap().stored.store);
    assert_eq!(state_files(&a), state_files(&b));
    for dir in [&a, &b] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Copies the folder `from` to `to`.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() { copy_dir(&path, &target) } else { std::fs::copy(&path, &target).map(|_| ()).unwrap() }
    }
}

/// A copy of the store that the writer of layout 2 (tile bytes of format 3) made of
/// `sessions()` with `config()`: day 0, then day 1 (`tests/fixtures/store-v2`).
fn layout_2_store(name: &str) -> PathBuf {
    let dir = temp(name);
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/store-v2"), &dir);
    dir
}

#[test]
fn stores_of_earlier_layouts_still_read_and_update() {
    let all = sessions();
    let by_name: BTreeMap<String, Trajectory> = all.iter().cloned().collect();
    let mut source = |s: &StoreSession| Ok(by_name[&s.name].clone());
    let mut memory = FleetStore::new(config().settings).unwrap();
    memory.update(all.clone(), &[], &mut source).unwrap();
    let (want, want_bits, _) = answer(&memory, &mut source);

    // Layout 2 (one table of tiles in fleet indices, beside their runs): read as written, it
    // draws without a rescan; its next update writes layout 3 and equals the same update of a
    // store made now.
    let dir = layout_2_store("version-2");
    assert!(dir.join("state-000002/tiles.parquet").is_file());
    let old = read_store(&dir).unwrap();
    assert!(memory.tiles() == old.store.tiles());
    let (got, got_bits, rescanned) = answer(&old.store, &mut source);
    assert!(got == want && got_bits == want_bits);
    assert_eq!(rescanned, 0, "a store of layout 2 keeps its runs");
    let gone = [all[0].0.clone()];
    let updated = update_store(&dir, None, Vec::new(), &gone).unwrap();
    assert!(dir.join(&updated.stored.state).join("tiles").is_dir());
    assert!(!dir.join(&updated.stored.state).join("tiles.parquet").exists());
    let now = temp("version-3");
    update_store(&now, Some(&config()), all.clone(), &[]).unwrap();
    let want_updated = update_store(&now, None, Vec::new(), &gone).unwrap();
    assert_eq!(updated.stored.store, want_updated.stored.store);
    assert_eq!(read_store(&dir).unwrap().store, read_store(&now).unwrap().store);

    // Layout 3 (tiles by part, merges in one table in fleet indices): read as written, its
    // next update writes the merges by part and equals the same update of a store made now.
    let dir = temp("version-3-fixture");
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/store-v3"), &dir);
    assert!(dir.join("state-000001/merges.parquet").is_file());
    let old = read_store(&dir).unwrap();
    assert!(memory.tiles() == old.store.tiles());
    assert!(memory.kept_merges().eq(old.store.kept_merges()));
    let (got, got_bits, _) = answer(&old.store, &mut source);
    assert!(got == want && got_bits == want_bits);
    let updated = update_store(&dir, None, Vec::new(), &gone).unwrap();
    let state = dir.join(&updated.stored.state);
    assert!(state.join("merges").is_dir() && !state.join("merges.parquet").exists());
    assert_eq!(updated.stored.store, want_updated.stored.store);
    assert_eq!(read_store(&dir).unwrap().store, read_store(&now).unwrap().store);
    let _ = std::fs::remove_dir_all(&dir);

    // Layout 4 (each state with a link to every session's pose file): read as written, its
    // next update moves the pose files beside the states and equals the same update of a
    // store made now.
    let dir = temp("version-4-fixture");
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/store-v4"), &dir);
    assert!(dir.join("state-000001/poses").is_dir() && !dir.join("poses").exists());
    let old = read_store(&dir).unwrap();
    assert!(memory.tiles() == old.store.tiles());
    for s in old.store.sessions() {
        assert_eq!(old.poses(s).unwrap(), by_name[&s.name], "{}", s.name);
    }
    let (got, got_bits, _) = answer(&old.store, &mut source);
    assert!(got == want && got_bits == want_bits);
    let updated = update_store(&dir, None, Vec::new(), &gone).unwrap();
    assert!(!dir.join(&updated.stored.state).join("poses").exists());
    assert_eq!(pose_files(&dir), pose_files_of(&updated.stored.store));
    assert_eq!(updated.stored.store, want_updated.stored.store);
    assert_eq!(read_store(&dir).unwrap().store, read_store(&now).unwrap().store);
    let _ = std::fs::remove_dir_all(&dir);

    // Layout 1 had no merges or runs: layout 2 without them, marked so.
    let dir = layout_2_store("version-1");
    let state = dir.join("state-000002");
    for name in ["merges.parquet", "tile_runs.parquet"] {
        std::fs::remove_file(state.join(name)).unwrap();
    }
    for file in [dir.join("store.json"), state.join("settings.json")] {
        let text = std::fs::read_to_string(&file).unwrap().replace("\"version\": 2", "\"version\": 1");
        std::fs::write(&file, text).unwrap();
    }
    let old = read_store(&dir).unwrap();
    assert!(old.store.kept_runs().unwrap().iter().all(Option::is_none));
    let (got, got_bits, rescanned) = answer(&old.store, &mut source);
    assert!(rescanned > 0, "a store without runs rescans to draw");
    assert!(got == want && got_bits == want_bits);
    for dir in [dir, now, temp("version-2")] {
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The names of the files in the store's folder of pose files, sorted.
fn pose_files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir.join("poses")).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    names.sort();
    names
}

/// The names of the pose files of `store`'s sessions, sorted.
fn pose_files_of(store: &FleetStore) -> Vec<String> {
    let mut names: Vec<String> = store.sessions().iter().map(|s| format!("{:016x}.parquet", s.fingerprint)).collect();
    names.sort();
    names
}

/// The inode of the file at `path` (0 off Unix).
fn inode(path: &Path) -> u64 {
    #[cfg(unix)]
    return std::os::unix::fs::MetadataExt::ino(&std::fs::metadata(path).unwrap());
    #[cfg(not(unix))]
    0
}

/// The inode of each file in the store's folder of pose files, by name.
fn pose_inodes(dir: &Path) -> BTreeMap<String, u64> {
    let folder = dir.join("poses");
    pose_files(dir).into_iter().map(|name| (name.clone(), inode(&folder.join(name)))).collect()
}

#[test]
fn an_update_touches_only_the_pose_files_of_the_sessions_it_changes() {
    let dir = temp("pose-files");
    let all = sessions();
    let (day0, day1): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|(n, _)| n.ends_with("day0"));
    update_store(&dir, Some(&config()), day0.clone(), &[]).unwrap();
    let before = pose_inodes(&dir);
    // Adding sessions writes their files and leaves the others' as they were.
    let report = update_store(&dir, None, day1.clone(), &[]).unwrap();
    assert_eq!(pose_files(&dir), pose_files_of(&report.stored.store));
    let after = pose_inodes(&dir);
    assert!(
        before.iter().all(|(name, inode)| after.get(name) == Some(inode)),
        "a stored session's file was written again"
    );
    // A session replaced: its old file goes, its new one comes; a session removed: its file goes.
    let (name, t) = day1[0].clone();
    let mut coords = t.coords().to_vec();
    coords[0] += 0.5;
    let moved = Trajectory::new(t.timestamps_s().to_vec(), coords, t.dim()).unwrap();
    let report = update_store(&dir, None, vec![(name.clone(), moved.clone())], &[day0[0].0.clone()]).unwrap();
    assert_eq!(pose_files(&dir), pose_files_of(&report.stored.store));
    let read = read_store(&dir).unwrap();
    let replaced = read.store.sessions().iter().find(|s| s.name == name).unwrap();
    assert_eq!(read.poses(replaced).unwrap(), moved);
    // A file a killed update left (no session of the state has it) goes with the next update
    // that writes; an update that changes nothing leaves the folder as it is.
    let stray = dir.join("poses").join("00000000deadbeef.parquet");
    std::fs::copy(dir.join("poses").join(&pose_files(&dir)[0]), &stray).unwrap();
    let note = dir.join("poses").join("notes.txt");
    std::fs::write(&note, "not a pose file").unwrap();
    update_store(&dir, None, vec![(name.clone(), moved)], &[]).unwrap();
    assert!(stray.exists(), "an update that changes nothing wrote");
    let report = update_store(&dir, None, vec![day0[0].clone()], &[]).unwrap();
    assert!(!stray.exists());
    assert!(note.exists(), "a file not named as a pose file was removed");
    std::fs::remove_file(&note).unwrap();
    assert_eq!(pose_files(&dir), pose_files_of(&report.stored.store));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The parts of the current state's `tiles` folder: name, rows, and (on Unix) the file's inode.
fn parts(dir: &Path) -> BTreeMap<String, (usize, u64)> {
    parts_of(dir, "tiles")
}

/// The parts of the current state's folder `folder` (`tiles`, `merges`), as [`parts`].
fn parts_of(dir: &Path, folder: &str) -> BTreeMap<String, (usize, u64)> {
    let state = read_store(dir).unwrap().state;
    std::fs::read_dir(dir.join(state).join(folder))
        .unwrap()
        .map(|e| {
            let path = e.unwrap().path();
            (path.file_name().unwrap().to_string_lossy().into_owned(), (parquet_rows(&path), inode(&path)))
        })
        .collect()
}

#[test]
fn an_update_writes_only_the_parts_that_change() {
    let dir = temp("parts");
    let all = sessions();
    let (day0, day1): (Vec<_>, Vec<_>) = all.iter().cloned().partition(|(n, _)| n.ends_with("day0"));
    update_store(&dir, Some(&config()), day0.clone(), &[]).unwrap();
    let first = parts(&dir);
    assert_eq!(first.keys().collect::<Vec<_>>(), ["000001.parquet"]);
    // An add: the stored part is linked as it is, a new one holds the scanned tiles only.
    let first_merges = parts_of(&dir, "merges");
    let report = update_store(&dir, None, day1.clone(), &[]).unwrap();
    let second = parts(&dir);
    assert_eq!(second.keys().collect::<Vec<_>>(), ["000001.parquet", "000002.parquet"]);
    if cfg!(unix) {
        assert_eq!(second["000001.parquet"], first["000001.parquet"], "linked, not written again");
        let merges = parts_of(&dir, "merges");
        assert_eq!(merges["000001.parquet"], first_merges["000001.parquet"], "linked, not written again");
    }
    assert_eq!(second["000002.parquet"].0, report.update.tiles_scanned);
    assert_eq!(second.values().map(|p| p.0).sum::<usize>(), report.stored.store.tiles().len());
    // The merges alike: the stored pairs' part linked, the new pairs' merges in a new one.
    let merges = parts_of(&dir, "merges");
    let pairs: Vec<[usize; 2]> = report.stored.store.kept_merges().map(|(pair, _)| pair).collect();
    let new_sessions: Vec<usize> = (0..report.stored.store.sessions().len())
        .filter(|&s| report.stored.store.sessions()[s].name.ends_with("day1"))
        .collect();
    let new_pairs = pairs.iter().filter(|p| p.iter().any(|s| new_sessions.contains(s))).count();
    assert!(0 < new_pairs && new_pairs < pairs.len(), "{new_pairs} of {}", pairs.len());
    assert_eq!(merges.keys().collect::<Vec<_>>(), ["000001.parquet", "000002.parquet"]);
    assert_eq!(merges["000002.parquet"].0, new_pairs);
    assert_eq!(merges["000001.parquet"].0, pairs.len() - new_pairs);
    // Read back lazily, the add read none of the old tiles' summaries (its draw reads runs).
    let read = report.stored.store.tiles().iter().filter(|t| t.is_read()).count();
    assert_eq!(read, report.update.tiles_scanned, "tiles read by an add");
    // A replacement: the parts that held the session's tiles are written again without them;
    // the store equals one made from scratch, read back too.
    let (name, t) = &day0[0];
    let shifted: Vec<f64> =
        t.coords().iter().enumerate().map(|(k, x)| x + if k % t.dim() == 0 { 3.0 } else { 0.0 }).collect();
    let moved = Trajectory::new(t.timestamps_s().to_vec(), shifted, t.dim()).unwrap();
    assert_eq!(moved.manifold(), t.manifold());
    let report = update_store(&dir, None, vec![(name.clone(), moved.clone())], &[]).unwrap();
    let third = parts(&dir);
    assert_eq!(third.values().map(|p| p.0).sum::<usize>(), report.stored.store.tiles().len());
    assert!(!third.contains_key("000001.parquet"), "{third:?}");
    let merges = parts_of(&dir, "merges");
    assert_eq!(merges.values().map(|p| p.0).sum::<usize>(), report.stored.store.kept_merges().count());
    assert!(!merges.contains_key("000001.parquet"), "{merges:?}");
    let mut final_sessions: BTreeMap<String, Trajectory> = all.iter().cloned().collect();
    final_sessions.insert(name.clone(), moved);
    let mut scratch = FleetStore::new(config().settings).unwrap();
    scratch
        .update(final_sessions.clone().into_iter().collect(), &[], &mut |s: &StoreSession| {
            Ok(final_sessions[&s.name].clone())
        })
        .unwrap();
    let read = read_store(&dir).unwrap();
    assert!(scratch.tiles() == read.store.tiles());
    assert!(read.store.tiles() == report.stored.store.tiles());
    // A damaged part is named, in one line: a merge part, then a tile part.
    let part = dir.join(&read.state).join("merges").join(merges.keys().next().unwrap());
    let bytes = std::fs::read(&part).unwrap();
    std::fs::write(&part, &bytes[..bytes.len() / 2]).unwrap();
    let error = read_store(&dir).unwrap_err().to_string();
    assert!(error.contains(&part.display().to_string()) && !error.contains('\n'), "{error}");
    std::fs::write(&part, bytes).unwrap();
    let part = dir.join(&read.state).join("tiles").join(third.keys().next().unwrap());
    std::fs::write(&part, b"not parquet").unwrap();
    let error = read_store(&dir).unwrap_err().to_string();
    assert!(error.contains(&part.display().to_string()) && !error.contains('\n'), "{error}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_store_updated_every_day_keeps_a_bounded_number_of_parts() {
    // Forty short drives across one crossing, added one a day: every two share a tile.
    let dir = temp("many-parts");
    let drives: Vec<(String, Trajectory)> = (0..40)
        .map(|d| {
            let angle = d as f64 * 0.07;
            let points: Vec<[f64; 2]> =
                (0..30).map(|k| (k as f64 - 15.0) * 2.0).map(|r| [r * angle.cos(), r * angle.sin()]).collect();
            (format!("day{d:02}"), Trajectory::from_points((0..30).map(|k| k as f64).collect(), &points).unwrap())
        })
        .collect();
    let settings = StoreConfig { settings: StoreSettings { block: 50, ..StoreSettings::new(4.0) }, sampler: None };
    let (mut most, mut most_merges) = (0, 0);
    for (d, drive) in drives.iter().enumerate() {
        let report = update_store(&dir, (d == 0).then_some(&settings), vec![drive.clone()], &[]).unwrap();
        let now = parts(&dir);
        most = most.max(now.len());
        assert_eq!(now.values().map(|p| p.0).sum::<usize>(), report.stored.store.tiles().len(), "day {d}");
        let merges = parts_of(&dir, "merges");
        most_merges = most_merges.max(merges.len());
        assert_eq!(merges.values().map(|p| p.0).sum::<usize>(), report.stored.store.kept_merges().count());
    }
    assert_eq!(most, 32, "parts are folded together beyond 32");
    assert_eq!(most_merges, 32, "merge parts too");
    let by_name: BTreeMap<String, Trajectory> = drives.iter().cloned().collect();
    let mut scratch = FleetStore::new(settings.settings).unwrap();
    scratch.update(drives.clone(), &[], &mut |s: &StoreSession| Ok(by_name[&s.name].clone())).unwrap();
    let read = read_store(&dir).unwrap();
    assert_eq!(read.store.tiles().len(), 40 * 41 / 2);
    assert!(scratch.tiles() == read.store.tiles());
    let _ = std::fs::remove_dir_all(&dir);
}
