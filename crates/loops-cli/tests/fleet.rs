//! `loops fleet` and `loops synth --vehicles` end to end: the files written against
//! `loops_core::fleet::find_fleet_loops` on the same logs, exit codes, one-line errors, and what
//! `--force` may replace.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

use loops_core::{
    Euclidean, Metric, Separation,
    fleet::{Fleet, FleetOptions, find_fleet_loops},
};

mod support;
use support::{assert_one_line_error, laps_tum, loops, names, stderr, temp_dir, write_in};

/// A CSV file as a header and rows of fields by column name (no quoted fields in these files).
fn read_csv(path: &Path) -> (Vec<String>, Vec<BTreeMap<String, String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().expect("a header").split(',').map(str::to_owned).collect();
    let rows = lines
        .map(|line| header.iter().cloned().zip(line.split(',').map(str::to_owned)).collect::<BTreeMap<_, _>>())
        .collect();
    (header, rows)
}

fn field<T: std::str::FromStr>(row: &BTreeMap<String, String>, name: &str) -> T
where
    T::Err: std::fmt::Debug,
{
    row[name].parse().unwrap_or_else(|e| panic!("{name} = {:?}: {e:?}", row[name]))
}

/// A synthetic fleet as TUM files (`loops synth --vehicles`), in fleet order.
fn synth_fleet(dir: &Path, vehicles: &str, days: &str, duration_s: &str) -> Vec<PathBuf> {
    let folder = dir.join("fleet");
    let args = ["synth", folder.to_str().unwrap(), "--vehicles", vehicles, "--days", days, "--duration-s", duration_s];
    let output = loops(&[&args[..], &["--format", "tum", "--seed", "5"]].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    // In the order written: day by day, vehicle by vehicle (the fleet's order).
    stdout.lines().map(|line| PathBuf::from(line.strip_prefix("wrote ").unwrap().split(" (").next().unwrap())).collect()
}

/// The fleet of `files` as the core finds it: sessions named by stem, positions x, y, z.
fn core_fleet(files: &[PathBuf], gamma: f64) -> (Fleet, loops_core::fleet::FleetLoops) {
    let sessions = files
        .iter()
        .map(|file| {
            let name = file.file_stem().unwrap().to_string_lossy().into_owned();
            (name, loops_io::read_tum(file).unwrap().to_trajectory().unwrap())
        })
        .collect();
    let fleet = Fleet::new(sessions).unwrap();
    let options = FleetOptions { separation: Separation::for_gamma(gamma), ..FleetOptions::default() };
    let loops = find_fleet_loops(&fleet, &Euclidean, gamma, &options).unwrap();
    (fleet, loops)
}

#[test]
fn fleet_files_agree_with_the_core() {
    let dir = temp_dir("agree");
    let files = synth_fleet(&dir, "3", "2", "300");
    assert_eq!(files.len(), 6);
    let out = dir.join("out");
    let mut args: Vec<&str> = vec!["fleet"];
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    args.extend(["--gamma", "40", "--budget", "300", "--out", out.to_str().unwrap()]);
    let output = loops(&args);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    let err = stderr(&output);
    assert!(
        err.contains(" poses, gamma 40 (euclidean), sampler nearest-then-uniform (budget 300), results to "),
        "{err}"
    );
    assert!(err.contains("separation: path >= 160 (the default"), "{err}");
    assert!(err.contains("loops: pruning kd-tree (auto"), "{err}");

    let sessions: Vec<String> = files.iter().map(|f| f.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    let mut expected: Vec<String> = sessions.clone();
    expected.extend(
        [
            "components.csv",
            "index.html",
            "loops-fleet.json",
            "samples.csv",
            "samples.g2o",
            "session_pairs.csv",
            "summary.json",
        ]
        .map(str::to_owned),
    );
    expected.sort();
    assert_eq!(names(&out), expected);
    for session in &sessions {
        let folder = out.join(session);
        assert_eq!(
            names(&folder),
            ["components.csv", "loop_duration.csv", "report.html", "samples.csv", "summary.json"],
            "{session}: the files of `loops run`"
        );
    }

    // components.csv: every component of the core's result, with both sessions.
    let (fleet, core) = core_fleet(&files, 40.0);
    let (header, rows) = read_csv(&out.join("components.csv"));
    let mut columns: Vec<&str> = loops_io::FLEET_COMPONENT_COLUMNS.to_vec();
    columns.push("samples");
    assert_eq!(header, columns);
    let components = core.components();
    assert_eq!(rows.len(), components.len());
    let between = components.iter().filter(|c| c.sessions[0] != c.sessions[1]).count();
    assert!(between > 0 && between < components.len(), "a fleet with loops within and between sessions");
    for (row, c) in rows.iter().zip(&components) {
        assert_eq!(field::<usize>(row, "id"), c.id);
        assert_eq!([field::<usize>(row, "session_a"), field::<usize>(row, "session_b")], c.sessions);
        assert_eq!(row["name_a"], fleet.names()[c.sessions[0]]);
        assert_eq!(field::<u64>(row, "pair_count"), c.pair_count);
        assert_eq!(field::<f64>(row, "area_s2"), c.area_s2);
        let poses: [[usize; 2]; 2] =
            [[field(row, "i_min"), field(row, "i_max")], [field(row, "j_min"), field(row, "j_max")]];
        assert_eq!(poses, c.poses);
        assert_eq!([field::<usize>(row, "closest_i"), field(row, "closest_j")], c.closest_pair);
        assert_eq!(field::<f64>(row, "t_prime_min_s"), fleet.session(c.sessions[1]).timestamps_s()[c.poses[1][0]]);
    }

    // session_pairs.csv: the core's sparse overlap matrix.
    let (header, pairs) = read_csv(&out.join("session_pairs.csv"));
    assert_eq!(header, loops_io::SESSION_PAIR_COLUMNS);
    let core_pairs = core.session_pairs();
    assert_eq!(pairs.len(), core_pairs.len());
    for (row, p) in pairs.iter().zip(&core_pairs) {
        assert_eq!([field::<usize>(row, "session_a"), field(row, "session_b")], p.sessions);
        assert_eq!((field::<usize>(row, "components"), field::<u64>(row, "pair_count")), (p.components, p.pair_count));
        assert_eq!(field::<f64>(row, "density"), p.density);
    }

    // samples.csv: the budget, each pair within γ on the poses it names, in the component's block.
    let (header, samples) = read_csv(&out.join("samples.csv"));
    assert_eq!(header, loops_io::FLEET_SAMPLE_COLUMNS);
    assert_eq!(samples.len(), 300);
    let mut per_component: BTreeMap<usize, u64> = BTreeMap::new();
    for row in &samples {
        let (a, b, i, j) = (
            field::<usize>(row, "session_a"),
            field::<usize>(row, "session_b"),
            field::<usize>(row, "i"),
            field(row, "j"),
        );
        let distance = Euclidean.distance(fleet.session(a).point(i), fleet.session(b).point(j));
        assert!(distance <= 40.0 && distance == field::<f64>(row, "distance"), "{row:?}");
        let component: usize = field(row, "component");
        assert_eq!(components[component].sessions, [a, b], "{row:?}");
        assert_eq!(field::<f64>(row, "t_s"), fleet.session(a).timestamps_s()[i]);
        *per_component.entry(component).or_default() += 1;
    }
    for row in &rows {
        let id: usize = field(row, "id");
        assert_eq!(field::<u64>(row, "samples"), per_component.get(&id).copied().unwrap_or(0), "component {id}");
    }

    // samples.g2o: one edge per sample, keyed by GTSAM Symbols (robot letter per session).
    let g2o = std::fs::read_to_string(out.join("samples.g2o")).unwrap();
    let edges: Vec<&str> = g2o.lines().collect();
    assert_eq!(edges.len(), samples.len());
    for (edge, row) in edges.iter().zip(&samples) {
        let words: Vec<&str> = edge.split_whitespace().collect();
        assert_eq!(words[0], "EDGE_SE3:QUAT");
        let key = |word: &str, session: usize, pose: usize| {
            let key: u64 = word.parse().unwrap();
            assert_eq!(((key >> 56) as u8, key & ((1 << 56) - 1)), (b'a' + session as u8, pose as u64), "{edge}");
        };
        key(words[1], field(row, "session_a"), field(row, "i"));
        key(words[2], field(row, "session_b"), field(row, "j"));
    }

    // summary.json and the table: the same counts.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["between_components"], between);
    assert_eq!(summary["components"], components.len());
    assert_eq!(summary["pruning"], "kd-tree");
    assert_eq!(summary["samples"], 300);
    assert_eq!(summary["sessions"].as_array().unwrap().len(), 6);
    assert_eq!(summary["pages"].as_array().unwrap().iter().filter(|p| p["ok"] == true).count(), 6);
    let overlapping = core_pairs.iter().filter(|p| p.sessions[0] != p.sessions[1]).count();
    assert!(
        stdout.starts_with(&format!(
            "6 session(s), {} poses: {} components within sessions, {between} between sessions in {overlapping} session pair(s); 300 samples",
            fleet.poses(),
            components.len() - between
        )),
        "{stdout}"
    );

    // Each session's folder is `loops run` on that log alone: its components are the fleet's
    // block of the session with itself.
    for (k, session) in sessions.iter().enumerate() {
        let (_, own) = read_csv(&out.join(session).join("components.csv"));
        let block: Vec<_> = components.iter().filter(|c| c.sessions == [k, k]).collect();
        assert_eq!(own.len(), block.len(), "{session}");
        for (row, c) in own.iter().zip(&block) {
            assert_eq!((field::<u64>(row, "pair_count"), field::<usize>(row, "i_min")), (c.pair_count, c.poses[0][0]));
        }
    }
    let page = std::fs::read_to_string(out.join("index.html")).unwrap();
    for figure in ["overlap-matrix", "fleet-map"] {
        assert!(page.contains(&format!("data-figure=\"{figure}\"")), "{figure}");
    }
    assert!(page.contains(&format!("href=\"{}/report.html\"", sessions[0])));

    // Between sessions only: every sample joins two sessions, and the JSON goes to stdout.
    let between_only = dir.join("between");
    let mut args: Vec<&str> = vec!["fleet"];
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    args.extend(["--gamma", "40", "--budget", "100", "--between-only", "--out", between_only.to_str().unwrap()]);
    let output = loops(&[&args[..], &["--json", "-", "--pruning", "hierarchy"]].concat());
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let printed: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!((printed["between_only"].as_bool(), printed["pruning"].as_str()), (Some(true), Some("hierarchy")));
    assert_eq!(printed["between_covered"], printed["between_components"], "P1 between sessions");
    let (_, samples) = read_csv(&between_only.join("samples.csv"));
    assert_eq!(samples.len(), 100);
    assert!(samples.iter().all(|row| row["session_a"] != row["session_b"]));
    // The pruning does not change the result.
    assert_eq!(
        std::fs::read(between_only.join("session_pairs.csv")).unwrap(),
        std::fs::read(out.join("session_pairs.csv")).unwrap()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

fn fleet(logs: &[&Path], out: &Path, extra: &[&str]) -> Output {
    let mut args: Vec<&str> = vec!["fleet"];
    args.extend(logs.iter().map(|l| l.to_str().unwrap()));
    args.extend(["--gamma", "2", "--budget", "20", "--out", out.to_str().unwrap()]);
    loops(&[&args[..], extra].concat())
}

#[test]
fn force_replaces_only_what_loops_fleet_wrote() {
    let dir = temp_dir("force");
    let (a, b) = (dir.join("a.tum"), dir.join("b.tum"));
    laps_tum(&a, 0, 0.0);
    laps_tum(&b, 1000, 0.5);
    let logs = [a.as_path(), b.as_path()];
    // A user's file with the name of one of the fleet's is never replaced, even with --force.
    for name in ["index.html", "components.csv", "samples.g2o"] {
        let out = dir.join(format!("o-{name}"));
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join(name), "mine\n").unwrap();
        let output = fleet(&logs, &out, &["--force"]);
        assert_one_line_error(&output, "which `loops fleet` did not write");
        assert!(stderr(&output).contains(name), "{}", stderr(&output));
        assert_eq!(std::fs::read_to_string(out.join(name)).unwrap(), "mine\n");
        assert_eq!(names(&out), [name], "nothing else written");
    }
    // Its own results: refused without --force, replaced with it.
    let out = dir.join("ours");
    assert!(fleet(&logs, &out, &[]).status.success());
    let before = names(&out);
    assert_one_line_error(&fleet(&logs, &out, &[]), "pass --force");
    let again = fleet(&logs, &out, &["--force", "--seed", "3"]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(names(&out), before);
    // A user's folder with a session's name stays; that session's page fails (exit 1) and the
    // fleet's files are written.
    let mine = dir.join("mine");
    std::fs::create_dir_all(mine.join("a")).unwrap();
    std::fs::write(mine.join("a/summary.json"), "{}").unwrap();
    let clash = fleet(&logs, &mine, &["--force"]);
    assert_eq!(clash.status.code(), Some(1), "{}", stderr(&clash));
    assert!(stderr(&clash).contains("not an output of `loops fleet`"), "{}", stderr(&clash));
    assert_eq!(std::fs::read_to_string(mine.join("a/summary.json")).unwrap(), "{}");
    assert!(mine.join("b/report.html").is_file() && mine.join("index.html").is_file());
    assert!(!names(&mine).iter().any(|n| n.starts_with('.')), "no staging folder left: {:?}", names(&mine));
    // The results of `loops run` are not the fleet's to replace, nor the fleet's `loops run`'s.
    let run = dir.join("run");
    let output = loops(&["run", a.to_str().unwrap(), "--gamma", "2", "--out", run.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_one_line_error(&fleet(&logs, &run, &["--force"]), "index.html, which `loops fleet` did not write");
    let output = loops(&["run", a.to_str().unwrap(), "--gamma", "2", "--out", out.to_str().unwrap(), "--force"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("which `loops run` did not write"), "{}", stderr(&output));
    // A log inside --out is refused before anything is written.
    let inside = out.join("b.tum");
    laps_tum(&inside, 2000, 0.0);
    assert_one_line_error(&fleet(&[a.as_path(), inside.as_path()], &out, &["--force"]), "lies inside --out");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_fleets_are_one_line_errors() {
    let dir = temp_dir("errors");
    std::fs::create_dir_all(dir.join("x")).unwrap();
    std::fs::create_dir_all(dir.join("y")).unwrap();
    let (a, b) = (dir.join("x/drive.tum"), dir.join("y/drive.tum"));
    laps_tum(&a, 0, 0.0);
    laps_tum(&b, 1000, 0.5);
    let out = dir.join("out");
    // Two sessions of one name: both named, and how to rename them.
    let output = fleet(&[a.as_path(), b.as_path()], &out, &[]);
    assert_one_line_error(&output, "two sessions are named \"drive\"");
    assert!(stderr(&output).contains("--session NAME=FILE"), "{}", stderr(&output));
    assert!(!out.exists(), "refused before anything is written");
    // Renamed with --session, they make a fleet; a session of two files is one trajectory.
    let c = dir.join("c.tum");
    laps_tum(&c, 5000, 0.0);
    let sessions = [
        "--session".to_owned(),
        format!("first={}", a.display()),
        "--session".to_owned(),
        format!("second={},{}", b.display(), c.display()),
    ];
    let sessions: Vec<&str> = sessions.iter().map(String::as_str).collect();
    let output = fleet(&[], &out, &sessions);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["sessions"][1]["name"], "second");
    assert_eq!(summary["sessions"][1]["poses"], 640);
    assert_eq!(summary["sessions"][1]["source"], format!("{} + {}", b.display(), c.display()));
    // Sessions of different dimensions: a 2-D CSV beside 3-D TUM files, unless one plane.
    let flat = dir.join("flat.csv");
    let mut text = String::from("t,x,y\n");
    for k in 0..50 {
        text += &format!("{},{},0\n", 9000 + k, f64::from(k) * 0.25);
    }
    std::fs::write(&flat, text).unwrap();
    let output = fleet(&[a.as_path(), flat.as_path()], &dir.join("mixed"), &[]);
    assert_one_line_error(&output, "session \"flat\" has 2 coordinates, the first has 3");
    assert!(stderr(&output).contains("--axes"), "{}", stderr(&output));
    assert!(!dir.join("mixed").exists(), "nothing written");
    let output = fleet(&[a.as_path(), flat.as_path()], &dir.join("plane"), &["--axes", "0,1"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    // Flags that do not fit, and a session name that cannot name a folder.
    let fresh = dir.join("fresh");
    assert_one_line_error(
        &fleet(&[a.as_path()], &fresh, &["--between-only", "--sampler", "lio-sam"]),
        "--between-only",
    );
    assert_one_line_error(&fleet(&[a.as_path()], &fresh, &["--pruning", "octree"]), "unknown pruning");
    assert_one_line_error(&fleet(&[a.as_path()], &fresh, &["--session", "nofiles"]), "expected NAME=FILE");
    assert_one_line_error(
        &fleet(&[a.as_path()], &fresh, &["--session", &format!(".hidden={}", c.display())]),
        "cannot name",
    );
    let missing = dir.join("missing.tum");
    assert_one_line_error(&fleet(&[a.as_path(), missing.as_path()], &fresh, &[]), "missing.tum");
    let output = loops(&["fleet", a.to_str().unwrap(), "--gamma", "-1", "--out", fresh.to_str().unwrap()]);
    assert_one_line_error(&output, "gamma must be a positive");
    assert!(!fresh.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn more_sessions_than_robot_letters_have_no_g2o() {
    let dir = temp_dir("letters");
    let logs: Vec<PathBuf> = (0..27)
        .map(|k| write_in(&dir, &format!("s{k:02}.tum"), format!("{k}.0 0 0 0 0 0 0 1\n{k}.5 1 0 0 0 0 0 1\n")))
        .collect();
    let refs: Vec<&Path> = logs.iter().map(PathBuf::as_path).collect();
    let out = dir.join("out");
    let output = fleet(&refs, &out, &["--no-separation", "--quiet"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(stderr(&output).contains("samples.g2o not written"), "{}", stderr(&output));
    assert!(stderr(&output).contains("at most 26 sessions, and the fleet has 27"), "{}", stderr(&output));
    assert!(!out.join("samples.g2o").exists());
    // Every session at the same place: all 27 × 26 / 2 session pairs meet.
    let (_, pairs) = read_csv(&out.join("session_pairs.csv"));
    assert_eq!(pairs.iter().filter(|r| r["session_a"] != r["session_b"]).count(), 27 * 26 / 2);
    // With 26 sessions the g2o is written, and an earlier one of ours is removed at 27.
    let output = fleet(&refs[..26], &out, &["--no-separation", "--quiet", "--force"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(out.join("samples.g2o").is_file());
    let output = fleet(&refs, &out, &["--no-separation", "--quiet", "--force"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(!out.join("samples.g2o").exists(), "a stale samples.g2o would not match samples.csv");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn synth_writes_a_fleet_one_file_per_session() {
    let dir = temp_dir("synth");
    let files = synth_fleet(&dir, "2", "2", "120");
    let names: Vec<String> = files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(names, ["car0-day0.tum", "car1-day0.tum", "car0-day1.tum", "car1-day1.tum"]);
    // The files are the core's fleet: positions, headings and each session's own clock.
    let spec = loops_core::UrbanFleet {
        vehicles: 2,
        days: 2,
        drive: loops_core::UrbanDrive { duration_s: 120.0, seed: 5, ..loops_core::UrbanDrive::default() },
        ..loops_core::UrbanFleet::default()
    };
    for ((name, drive), file) in spec.drives().unwrap().iter().zip(&files) {
        let table = loops_io::read_tum(file).unwrap();
        assert_eq!(file.file_stem().unwrap().to_string_lossy(), *name);
        assert_eq!(table.timestamps_s.len(), drive.trajectory.len());
        for (k, t) in table.timestamps_s.iter().enumerate() {
            assert!((t - drive.trajectory.timestamps_s()[k]).abs() < 1e-6, "{name} pose {k}");
            assert_eq!(&table.positions[k][..], drive.trajectory.point(k));
            let q = table.orientations_xyzw.as_ref().unwrap()[k];
            let error = loops_core::wrap_angle(2.0 * q[2].atan2(q[3]) - drive.yaw_rad[k]);
            assert!(error.abs() < 1e-9, "{name} heading {k}");
        }
    }
    let day1 = loops_io::read_tum(&files[2]).unwrap();
    assert!(day1.timestamps_s[0] >= 86_400.0, "the second day starts a day later");
    // Not replaced without --force; --days needs --vehicles; no vehicles is the core's error.
    let folder = dir.join("fleet");
    let again = loops(&["synth", folder.to_str().unwrap(), "--vehicles", "2", "--days", "2", "--format", "tum"]);
    assert_one_line_error(&again, "car0-day0.tum exists; pass --force");
    let output = loops(&["synth", dir.join("x").to_str().unwrap(), "--days", "2"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert!(stderr(&output).contains("--vehicles"), "{}", stderr(&output));
    assert_one_line_error(&loops(&["synth", dir.join("y").to_str().unwrap(), "--vehicles", "0"]), "vehicles");
    assert!(!dir.join("y").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
