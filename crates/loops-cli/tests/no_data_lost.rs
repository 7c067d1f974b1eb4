//! Data lost or overwritten: each test reproduces what an attack sweep did, and fails on the
//! code before its fix (the table in `crates/loops-io/tests/FUZZ.md`). "Item N" is the sweep's
//! numbering: the first sweep's items 1–5, 14 and 20; then the second sweep's items 1–3.

use std::path::{Path, PathBuf};
use std::process::Output;

mod support;
use support::{assert_one_line_error, laps_tum, loops, names, stderr, temp_dir, write_in};

/// Two laps of a 40 m square at 1 m/s, as TUM, in `dir`.
fn laps(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    laps_tum(&path, 0, 0.0);
    path
}

fn run(log: &Path, out: &Path, extra: &[&str]) -> Output {
    let args = ["run", log.to_str().unwrap(), "--gamma", "2", "--budget", "20", "--out", out.to_str().unwrap()];
    loops(&[&args[..], extra].concat())
}

/// Item 1: `--force` never replaces a user's `index.html` or `summary.json` in --out.
#[test]
fn force_keeps_the_users_top_level_files() {
    let dir = temp_dir("top");
    let log = laps(&dir, "a.tum");
    for name in ["index.html", "summary.json"] {
        let out = dir.join(format!("o-{name}"));
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join(name), "mine\n").unwrap();
        let output = run(&log, &out, &["--force"]);
        assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
        let err = stderr(&output);
        assert!(err.contains(name) && err.contains("did not write"), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert_eq!(std::fs::read_to_string(out.join(name)).unwrap(), "mine\n");
        assert_eq!(names(&out), [name], "nothing else written");
    }
    // Results of an earlier run are replaced with --force, as before.
    let out = dir.join("ours");
    assert!(run(&log, &out, &[]).status.success());
    let again = run(&log, &out, &["--force"]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(names(&out), ["a", "index.html", "loops-run.json", "summary.json"]);
    // A user's folder with a log's name is not replaced (and no staging folder stays behind).
    let mine = dir.join("mine");
    std::fs::create_dir_all(mine.join("a")).unwrap();
    std::fs::write(mine.join("a/summary.json"), "{}").unwrap();
    let clash = run(&log, &mine, &["--force"]);
    assert_eq!(clash.status.code(), Some(1), "{}", stderr(&clash));
    assert!(stderr(&clash).contains("not an output of `loops run`"), "{}", stderr(&clash));
    assert_eq!(std::fs::read_to_string(mine.join("a/summary.json")).unwrap(), "{}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 2: a log reached through a link to --out's folder is inside --out.
#[cfg(unix)]
#[test]
fn logs_inside_out_are_found_through_links() {
    let dir = temp_dir("link");
    let logs = dir.join("logs");
    std::fs::create_dir(&logs).unwrap();
    let log = laps(&logs, "a.tum");
    let link = dir.join("linkdir");
    std::os::unix::fs::symlink(&logs, &link).unwrap();
    let before = std::fs::read(&log).unwrap();
    let output = run(&log, &link, &["--force"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("lies inside --out"), "{}", stderr(&output));
    assert_eq!(names(&logs), ["a.tum"]);
    assert_eq!(std::fs::read(&log).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 3: a run holds --out; another stops at once, naming the folder and the holder's pid.
#[cfg(unix)]
#[test]
fn a_second_run_into_a_held_folder_stops() {
    let dir = temp_dir("lock");
    let log = laps(&dir, "a.tum");
    let out = dir.join("out");
    // An earlier run leaves its marker; this test then holds the folder as a run does.
    assert!(run(&log, &out, &[]).status.success());
    let marker: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("loops-run.json")).unwrap()).unwrap();
    let holder = std::fs::File::open(&out).unwrap();
    holder.try_lock().unwrap();
    let before = std::fs::read(out.join("summary.json")).unwrap();
    let start = std::time::Instant::now();
    let second = run(&log, &out, &["--force"]);
    assert!(start.elapsed().as_secs() < 30);
    assert_eq!(second.status.code(), Some(2), "{}", stderr(&second));
    let err = stderr(&second);
    assert!(err.contains(out.to_str().unwrap()) && err.contains("in use"), "{err}");
    assert!(err.contains(&format!("pid {}", marker["pid"])), "{err}");
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), before);
    holder.unlock().unwrap();
    assert!(run(&log, &out, &["--force"]).status.success());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 4: a failed log leaves no staging folder; what a killed run left in its scratch folder
/// (which its marker lists) is removed by the next run into the folder, which says so. Entries
/// of the user's that merely look like leftovers are never removed.
#[test]
fn staging_folders_do_not_stay_behind() {
    let dir = temp_dir("staging");
    let log = laps(&dir, "a.tum");
    let out = dir.join("out");
    std::fs::create_dir_all(out.join("a")).unwrap();
    std::fs::write(out.join("a/notes.txt"), "mine").unwrap();
    for _ in 0..2 {
        let clash = run(&log, &out, &["--force"]);
        assert_eq!(clash.status.code(), Some(1), "{}", stderr(&clash));
        assert!(!names(&out).iter().any(|n| n.starts_with('.')), "{:?}", names(&out));
    }
    // What a SIGKILL leaves: the scratch folder, which the marker lists, with a log's folder
    // and a file in progress; and beside it a user's entries shaped like leftovers.
    let killed = dir.join("killed");
    assert!(run(&log, &killed, &[]).status.success());
    let marker = std::fs::read_to_string(killed.join("loops-run.json")).unwrap();
    assert!(marker.contains(r#""scratch": ".loops-run.partial""#), "{marker}");
    std::fs::create_dir_all(killed.join(".loops-run.partial/0")).unwrap();
    std::fs::write(killed.join(".loops-run.partial/0/report.html"), "half").unwrap();
    std::fs::write(killed.join(".loops-run.partial/1"), "half").unwrap();
    std::fs::create_dir(killed.join(".a.partial-999999")).unwrap();
    std::fs::write(killed.join(".index.html.Qw34Er.tmp"), "a user's file").unwrap();
    std::fs::write(killed.join(".my-notes"), "a user's hidden file").unwrap();
    let next = run(&log, &killed, &["--force"]);
    assert!(next.status.success(), "{}", stderr(&next));
    assert!(stderr(&next).contains("removed what an interrupted run left"), "{}", stderr(&next));
    assert_eq!(
        names(&killed),
        [
            ".a.partial-999999",
            ".index.html.Qw34Er.tmp",
            ".my-notes",
            "a",
            "index.html",
            "loops-run.json",
            "summary.json"
        ]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 5: a command that fails writes nothing.
#[test]
fn a_failing_sample_writes_no_file() {
    let dir = temp_dir("sample");
    let log = laps(&dir, "in.tum");
    let csv = dir.join("x.csv");
    let json = dir.join("x.json");
    let args = ["sample", log.to_str().unwrap(), "--gamma", "2", "--budget", "10", "--csv", csv.to_str().unwrap()];
    let taken = write_in(&dir, "taken.g2o", "a user's file");
    let output = loops(&[&args[..], &["--json", json.to_str().unwrap(), "--g2o", taken.to_str().unwrap()]].concat());
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("taken.g2o exists"), "{}", stderr(&output));
    std::fs::remove_file(&taken).unwrap();
    assert_eq!(names(&dir), ["in.tum"], "no x.csv, no x.json, no temporary file");
    let output = loops(&[&args[..], &["--g2o", dir.join("x.g2o").to_str().unwrap()]].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(names(&dir), ["in.tum", "x.csv", "x.g2o"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 14: a thread count past the core's cap is refused at once.
#[test]
fn huge_thread_counts_are_refused() {
    let dir = temp_dir("threads");
    let log = laps(&dir, "a.tum");
    let start = std::time::Instant::now();
    for command in ["components", "sample"] {
        let output = loops(&[command, log.to_str().unwrap(), "--gamma", "2", "--threads", "1000000"]);
        assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
        assert!(stderr(&output).contains("threads = 1000000 is invalid: between 1 and 1024"), "{}", stderr(&output));
    }
    let out = dir.join("out");
    let output = run(&log, &out, &["--threads", "1000000"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(!out.exists(), "refused before anything is written");
    assert!(start.elapsed().as_secs() < 30);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Item 20: `--gamma -inf` reaches the core's check; a repeated metric key is named as such.
#[test]
fn negative_and_infinite_values_reach_the_core() {
    let dir = temp_dir("gamma");
    let log = laps(&dir, "a.tum");
    for gamma in ["-inf", "-1", "inf", "NaN"] {
        let output = loops(&["components", log.to_str().unwrap(), "--gamma", gamma]);
        assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
        assert!(stderr(&output).contains("gamma must be a positive finite distance"), "{gamma}: {}", stderr(&output));
    }
    let output = loops(&["demo", "--gamma", "-inf", "--duration-s", "60"]);
    assert!(stderr(&output).contains("gamma must be a positive finite distance"), "{}", stderr(&output));
    let output = loops(&["sample", log.to_str().unwrap(), "--gamma", "2", "--epsilon-s", "-inf"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(!stderr(&output).contains("unexpected argument"), "{}", stderr(&output));
    let metric = "so3(rotation=chordal,rotation=geodesic)";
    let output = loops(&["components", log.to_str().unwrap(), "--gamma", "0.1", "--metric", metric]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("repeated parameter 'rotation'"), "{}", stderr(&output));
    std::fs::remove_dir_all(&dir).unwrap();
}

// The second sweep.

/// A folder of `name` with a user's entries shaped like what a killed run leaves, and a file:
/// the names it holds.
fn users_leftover_shaped_entries(out: &Path) -> Vec<String> {
    std::fs::create_dir_all(out.join(".thesis.partial-2024")).unwrap();
    std::fs::write(out.join(".thesis.partial-2024/ch1.tex"), "work").unwrap();
    std::fs::create_dir_all(out.join(".drive.old-12")).unwrap();
    std::fs::write(out.join(".notes.backup.tmp"), "draft").unwrap();
    std::fs::write(out.join(".summary.json.Ab12xZ.tmp"), "mine too").unwrap();
    std::fs::write(out.join("mydata.txt"), "mine").unwrap();
    names(out)
}

/// Second sweep, item 1: `loops run` and `loops fleet` never remove an entry of --out because it
/// looks like a leftover, with or without --force: only what their marker lists.
#[test]
fn leftover_shaped_entries_of_the_user_are_never_removed() {
    let dir = temp_dir("shaped");
    let (a, b) = (laps(&dir, "a.tum"), dir.join("b.tum"));
    laps_tum(&b, 1000, 0.5);
    for (command, force) in [("run", false), ("run", true), ("fleet", false), ("fleet", true)] {
        let out = dir.join(format!("u-{command}-{force}"));
        let before = users_leftover_shaped_entries(&out);
        let mut args = vec![command, a.to_str().unwrap()];
        if command == "fleet" {
            args.push(b.to_str().unwrap());
        }
        args.extend(["--gamma", "2", "--budget", "20", "--out", out.to_str().unwrap()]);
        if force {
            args.push("--force");
        }
        let output = loops(&args);
        if force {
            assert!(output.status.success(), "{command}: {}", stderr(&output));
            let after = names(&out);
            assert!(before.iter().all(|name| after.contains(name)), "{command}: {before:?} -> {after:?}");
        } else {
            assert_one_line_error(&output, "exists and is not empty");
            assert_eq!(names(&out), before, "{command}");
        }
        assert!(!stderr(&output).contains("removed"), "{command}: {}", stderr(&output));
        assert_eq!(std::fs::read_to_string(out.join(".thesis.partial-2024/ch1.tex")).unwrap(), "work");
        assert_eq!(std::fs::read_to_string(out.join(".notes.backup.tmp")).unwrap(), "draft");
        assert_eq!(std::fs::read_to_string(out.join(".summary.json.Ab12xZ.tmp")).unwrap(), "mine too");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Second sweep, item 2: no output is written onto an input, --force or not, also through a
/// link: `loops run --json`, `loops fleet --json`, `loops components --json`, `loops sample
/// --g2o/--csv/--json`.
#[test]
fn force_never_writes_onto_an_input() {
    let dir = temp_dir("onto");
    let (a, b) = (laps(&dir, "a.tum"), dir.join("b.tum"));
    laps_tum(&b, 1000, 0.5);
    let before = std::fs::read(&a).unwrap();
    let link = dir.join("link.json");
    #[cfg(unix)]
    std::os::unix::fs::symlink(&a, &link).unwrap();
    #[cfg(not(unix))]
    let link = a.clone();
    let (a_str, b_str, out) = (a.to_str().unwrap(), b.to_str().unwrap(), dir.join("o"));
    let out_str = out.to_str().unwrap();
    for target in [a.to_str().unwrap(), link.to_str().unwrap()] {
        let attempts: [Vec<&str>; 7] = [
            vec!["run", a_str, "--gamma", "2", "--out", out_str, "--json", target, "--force"],
            vec!["fleet", a_str, b_str, "--gamma", "2", "--out", out_str, "--json", target, "--force"],
            vec!["components", a_str, "--gamma", "2", "--json", target, "--force"],
            vec!["sample", a_str, "--gamma", "2", "--budget", "5", "--g2o", target, "--force"],
            vec!["sample", a_str, "--gamma", "2", "--budget", "5", "--csv", target, "--force"],
            vec!["sample", a_str, "--gamma", "2", "--budget", "5", "--json", target, "--force"],
            vec!["components", a_str, "--gamma", "2", "--edges-csv", target, "--force"],
        ];
        for args in attempts {
            let output = loops(&args);
            assert_one_line_error(&output, &["would overwrite the input", "a.tum"]);
            assert_eq!(std::fs::read(&a).unwrap(), before, "{args:?}");
            assert!(!out.exists(), "{args:?}: refused before anything is written");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Second sweep, item 3: a log named like one of `loops run`'s own files gets a folder of another
/// name, and a log with a name of 250 characters runs (its work in progress has a short name).
#[test]
fn logs_named_like_the_tools_files_and_long_names_run() {
    let dir = temp_dir("names");
    let marker_named = laps(&dir, "loops-run.json.tum");
    let long = laps(&dir, &format!("{}.tum", "l".repeat(250)));
    let out = dir.join("out");
    let output = loops(&[
        "run",
        marker_named.to_str().unwrap(),
        long.to_str().unwrap(),
        "--gamma",
        "2",
        "--budget",
        "20",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(names(&out), ["index.html", &"l".repeat(250), "loops-run.json", "loops-run.json-2", "summary.json"]);
    assert!(out.join("loops-run.json-2/summary.json").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}
