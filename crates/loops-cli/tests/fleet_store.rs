//! `loops fleet --store`: a store grown day by day agrees with the core on the same sessions;
//! a log that cannot be read leaves the store as it was, with one line on stderr; an update
//! killed at a seeded moment leaves the old state or the new one, never a mix.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use loops_core::{
    Euclidean, Separation,
    fleet::{Fleet, FleetOptions, find_fleet_loops},
};
use loops_io::store::read_store;
use rand::{RngExt, SeedableRng};

mod support;
use support::{assert_one_line_error, loops, stderr, temp_dir, write_in};

const GAMMA: &str = "30";

/// A synthetic fleet as TUM files (`loops synth --vehicles`), day by day.
fn synth_fleet(dir: &Path, vehicles: &str, days: &str, duration_s: &str) -> Vec<PathBuf> {
    let folder = dir.join("fleet");
    let args = ["synth", folder.to_str().unwrap(), "--vehicles", vehicles, "--days", days, "--duration-s", duration_s];
    let output = loops(&[&args[..], &["--format", "tum", "--seed", "5"]].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    stdout.lines().map(|line| PathBuf::from(line.strip_prefix("wrote ").unwrap().split(" (").next().unwrap())).collect()
}

fn store_run(store: &Path, files: &[PathBuf], extra: &[&str]) -> std::process::Output {
    let mut args: Vec<&str> = vec!["fleet", "--store", store.to_str().unwrap()];
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    args.extend(["--gamma", GAMMA, "--budget", "40", "--block", "200"]);
    args.extend(extra);
    loops(&args)
}

/// (name, component count) of the core's fleet of `files`, sessions in name order.
fn core_components(files: &[PathBuf]) -> (Vec<String>, usize) {
    let sessions: BTreeMap<String, loops_core::Trajectory> = files
        .iter()
        .map(|file| {
            let name = file.file_stem().unwrap().to_string_lossy().into_owned();
            (name, loops_io::read_tum(file).unwrap().to_trajectory().unwrap())
        })
        .collect();
    let gamma: f64 = GAMMA.parse().unwrap();
    let fleet = Fleet::new(sessions.clone().into_iter().collect()).unwrap();
    let options = FleetOptions { separation: Separation::for_gamma(gamma), ..FleetOptions::default() };
    let loops = find_fleet_loops(&fleet, &Euclidean, gamma, &options).unwrap();
    (sessions.into_keys().collect(), loops.components().len())
}

/// The stored sessions' names and the stored components (from the tables the store wrote).
fn stored(store: &Path) -> (Vec<String>, usize) {
    let s = read_store(store).unwrap();
    let names = s.store.sessions().iter().map(|x| x.name.clone()).collect();
    (names, s.store.loops().unwrap().components().len())
}

/// Every file under `dir` and its bytes, but the ownership marker (which records the pid of the
/// last run that took the folder).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if !path.ends_with("loops-store.json") {
                out.insert(path.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&path).unwrap());
            }
        }
    }
    out
}

/// The modification time of `dir` and of everything under it, the marker included.
fn times(dir: &Path) -> BTreeMap<PathBuf, std::time::SystemTime> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(path) = stack.pop() {
        out.insert(path.clone(), std::fs::metadata(&path).unwrap().modified().unwrap());
        if path.is_dir() {
            stack.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
        }
    }
    out
}

#[test]
fn a_store_grown_by_the_day_agrees_with_the_core() {
    let dir = temp_dir("days");
    let files = synth_fleet(&dir, "2", "3", "120");
    let store = dir.join("store");
    for day in 0..3 {
        let output = store_run(&store, &files[2 * day..2 * day + 2], &[]);
        assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
        assert!(String::from_utf8_lossy(&output.stdout).contains("added car0-day"), "{}", stderr(&output));
        assert_eq!(stored(&store), core_components(&files[..2 * day + 2]), "day {day}");
    }
    // Again (yesterday's run once more): nothing changed, one line, nothing written (no file,
    // no time).
    let (before, then) = (snapshot(&store), times(&store));
    std::thread::sleep(std::time::Duration::from_millis(20));
    for (again, said) in [
        (&files[..2], "2 stored as given (car0-day0, car1-day0)"),
        (&files[4..], "2 stored as given (car0-day2, car1-day2)"),
    ] {
        let output = store_run(&store, again, &[]);
        assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert_eq!(stdout.lines().count(), 1, "{stdout}");
        assert!(stdout.contains(&format!("nothing changed, nothing written: {said}; 6 sessions")), "{stdout}");
        assert_eq!(snapshot(&store), before);
        assert!(times(&store) == then, "an update that changes nothing touched the store");
    }
    // A session removed.
    let output = store_run(&store, &[], &["--remove", "car0-day1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let rest: Vec<PathBuf> = files.iter().filter(|f| !f.ends_with("car0-day1.tum")).cloned().collect();
    assert_eq!(stored(&store), core_components(&rest));
    // Other settings than the store's: one line, nothing changed.
    let before = snapshot(&store);
    let output = loops(&["fleet", "--store", store.to_str().unwrap(), files[2].to_str().unwrap(), "--gamma", "20"]);
    assert_one_line_error(&output, &["gamma is 30 in the store, not 20"]);
    assert_eq!(snapshot(&store), before);
    // A folder of the user's is not made a store.
    let theirs = dir.join("theirs");
    std::fs::create_dir_all(&theirs).unwrap();
    write_in(&theirs, "notes.txt", "mine");
    let output = store_run(&theirs, &files[..1], &[]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert_eq!(std::fs::read_to_string(theirs.join("notes.txt")).unwrap(), "mine");
}

#[test]
fn a_corrupt_log_leaves_the_store_unchanged() {
    let dir = temp_dir("corrupt");
    let files = synth_fleet(&dir, "2", "1", "60");
    let store = dir.join("store");
    let output = store_run(&store, &files[..1], &[]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let before = snapshot(&store);
    let bad = write_in(&dir, "bad.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\nnot a pose\n");
    let output = store_run(&store, &[files[1].clone(), bad], &[]);
    assert_one_line_error(&output, &["bad.tum", "line 3"]);
    assert_eq!(snapshot(&store), before, "the store changed");
}

#[test]
fn a_killed_update_leaves_the_old_or_the_new_state() {
    let dir = temp_dir("killed");
    let files = synth_fleet(&dir, "2", "2", "120");
    let base = dir.join("base");
    assert_eq!(store_run(&base, &files[..2], &[]).status.code(), Some(0));
    let old = core_components(&files[..2]);
    let new = core_components(&files);
    // How long an update takes here, to kill within it.
    let timed = dir.join("timed");
    copy_dir(&base, &timed);
    let clock = Instant::now();
    assert_eq!(store_run(&timed, &files[2..], &[]).status.code(), Some(0));
    let took = clock.elapsed();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
    let (mut olds, mut news) = (0, 0);
    for k in 0..8 {
        let store = dir.join(format!("store-{k}"));
        copy_dir(&base, &store);
        let mut args: Vec<String> = vec!["fleet".into(), "--store".into(), store.display().to_string()];
        args.extend(files[2..].iter().map(|f| f.display().to_string()));
        args.extend(["--gamma", GAMMA, "--budget", "40", "--block", "200"].map(String::from));
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_loops"))
            .args(&args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(took.mul_f64(rng.random_range(0.05..1.0)));
        let _ = child.kill();
        let _ = child.wait();
        let now = stored(&store);
        assert!(now == old || now == new, "kill {k}: the store holds {now:?}");
        if now == old {
            olds += 1
        } else {
            news += 1
        }
        // The next update finishes the work and cleans what the killed one left.
        let output = store_run(&store, &files[2..], &[]);
        assert_eq!(output.status.code(), Some(0), "kill {k}: {}", stderr(&output));
        assert_eq!(stored(&store), new);
        assert!(!store.join(".loops-store.partial").exists());
        let states = support::names(&store).into_iter().filter(|n| n.starts_with("state-")).count();
        assert_eq!(states, 1, "kill {k}");
        // One pose file a session: none that the killed update wrote is left over.
        assert_eq!(support::names(&store.join("poses")).len(), new.0.len(), "kill {k}");
    }
    eprintln!("killed updates: {olds} left the old state, {news} the new one (an update takes {took:?})");
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}
