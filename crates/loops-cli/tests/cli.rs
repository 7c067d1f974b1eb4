//! The `loops` binary end to end: output, exit codes, one-line errors, atomic JSON.

use std::path::{Path, PathBuf};

mod support;
use support::{assert_one_line_error, loops, square_lap, stderr, temp_dir, write_in};

/// A TUM file of an out-and-back drive along x (0 → 20 m → 0) at 1 m/s.
fn out_and_back(dir: &Path) -> PathBuf {
    let mut text = String::from("# timestamp tx ty tz qx qy qz qw\n");
    for i in 0..=40 {
        let x = if i <= 20 { i } else { 40 - i };
        text += &format!("{i}.0 {x}.0 0.0 0.0 0 0 0 1\n");
    }
    write_in(dir, "drive.tum", text)
}

#[test]
fn components_table_and_json() {
    let dir = temp_dir("json");
    let file = out_and_back(&dir);
    let json = dir.join("out.json");
    let paper = ["components", file.to_str().unwrap(), "--gamma", "1.5", "--no-separation"];
    let output = loops(&[&paper[..], &["--json", json.to_str().unwrap()]].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("41 poses"), "{stdout}");
    assert!(stdout.contains("separation: none (--no-separation"), "{stdout}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // Going out and back along one line folds the path onto itself: every pair within γ of the
    // turn is connected to the diagonal through the turning point, so by the paper's topology it
    // is all one trivial component, shaped like an X in the (t, t') plane.
    let components = report["components"].as_array().unwrap();
    assert_eq!(components.len(), 1, "{report}");
    assert_eq!(components[0]["trivial"], true);
    assert_eq!(report["poses"], 41);
    assert_eq!(report["separation"], serde_json::json!({"path": 0.0, "time_s": 0.0}));
    // By default only revisits count (at least 4γ = 6 apart along the path): the way back is one
    // revisit of the way out, and the header says which separation was used.
    let table = loops(&["components", file.to_str().unwrap(), "--gamma", "1.5"]);
    let table = String::from_utf8_lossy(&table.stdout);
    assert!(table.contains("separation: path >= 6 (the default, 4 x gamma"), "{table}");
    let revisits = loops(&["components", file.to_str().unwrap(), "--gamma", "1.5", "--json", "-"]);
    assert!(revisits.status.success(), "{}", stderr(&revisits));
    let report: serde_json::Value = serde_json::from_slice(&revisits.stdout).unwrap();
    assert_eq!(report["separation"], serde_json::json!({"path": 6.0, "time_s": 0.0}));
    let components = report["components"].as_array().unwrap();
    assert_eq!(components.len(), 1, "{report}");
    assert_eq!(components[0]["trivial"], false);
    // Asked for by time instead, or beyond the path's length: the latter is a warning.
    let far = loops(&["components", file.to_str().unwrap(), "--gamma", "1.5", "--separation-path", "1000"]);
    assert!(far.status.success(), "{}", stderr(&far));
    assert!(stderr(&far).contains("warning: no revisit at gamma 1.5"), "{}", stderr(&far));
    assert_one_line_error(
        &loops(&["components", file.to_str().unwrap(), "--gamma", "1.5", "--separation-time", "-1"]),
        "time separation",
    );

    // The JSON is not replaced without --force, and is with it.
    let again = loops(&["components", file.to_str().unwrap(), "--gamma", "1.5", "--json", json.to_str().unwrap()]);
    assert_one_line_error(&again, "--force");
    let forced =
        loops(&["components", file.to_str().unwrap(), "--gamma", "2.5", "--json", json.to_str().unwrap(), "--force"]);
    assert!(forced.status.success(), "{}", stderr(&forced));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["gamma"], 2.5);
    let leftovers: Vec<_> = std::fs::read_dir(&dir).unwrap().filter_map(Result::ok).map(|e| e.file_name()).collect();
    assert_eq!(leftovers.len(), 2, "no temporary files left behind: {leftovers:?}");
}

/// `--json -` is how every command prints JSON on stdout: the same JSON its `--json FILE`
/// writes, and nothing else on stdout.
#[test]
fn json_dash_prints_the_json_on_stdout() {
    let dir = temp_dir("json-stdout");
    let file = out_and_back(&dir);
    let f = file.to_str().unwrap();
    for command in [&["components", f, "--gamma", "1.5"][..], &["sample", f, "--gamma", "1.5", "--budget", "5"]] {
        let path = dir.join(format!("{}.json", command[0]));
        let written = loops(&[command, &["--json", path.to_str().unwrap()]].concat());
        assert!(written.status.success(), "{}", stderr(&written));
        let printed = loops(&[command, &["--json", "-"]].concat());
        assert!(printed.status.success(), "{}", stderr(&printed));
        assert_eq!(String::from_utf8_lossy(&printed.stdout), std::fs::read_to_string(&path).unwrap(), "{command:?}");
    }
    assert!(!dir.join("-").exists());
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let dir = temp_dir("bad");
    let file = out_and_back(&dir);
    let file = file.to_str().unwrap();
    let flags: [(&[&str], &str); 7] = [
        (&["--gamma", "0"], "gamma must be a positive"),
        (&["--gamma", "-3"], "gamma must be a positive"),
        (&["--gamma", "NaN"], "gamma must be a positive"),
        (&["--gamma", "1", "--metric", "manhattan"], "unknown metric"),
        (&["--gamma", "1", "--format", "rosbag"], "unknown file format"),
        (&["--gamma", "1", "--threads", "0"], "threads"),
        (&["--gamma", "1", "--axes", "0,7"], "axis"),
    ];
    for (flags, needle) in flags {
        assert_one_line_error(&loops(&[&["components", file][..], flags].concat()), needle);
    }

    let missing = dir.join("missing.tum");
    assert_one_line_error(&loops(&["components", missing.to_str().unwrap(), "--gamma", "1"]), "missing.tum");

    // Files of bad content, and what the error names.
    let files = [
        ("malformed.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 0 abc 0 0 0 1\n", "line 3"),
        ("nan.tum", "0 0 0 0 0 0 0 1\n1 nan 0 0 0 0 0 1\n", "line 2"),
        ("unsorted.tum", "0 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n1 2 0 0 0 0 0 1\n", "line 3"),
        ("single.csv", "t,x,y\n0,1,2\n", "at least 2 poses"),
        ("empty.csv", "", "no poses"),
    ];
    for (name, text, needle) in files {
        let path = write_in(&dir, name, text);
        assert_one_line_error(&loops(&["components", path.to_str().unwrap(), "--gamma", "1"]), needle);
    }
}

#[test]
fn demo_summarises_a_short_drive() {
    let output = loops(&["demo", "--duration-s", "600", "--seed", "3", "--limit", "3"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("6000 poses"), "{stdout}");
    assert!(stdout.contains("(seed 3"), "{stdout}");
    let rows = stdout
        .lines()
        .skip_while(|l| !l.trim_start().starts_with("id"))
        .skip(1)
        .filter(|l| !l.contains("more"))
        .count();
    assert!(rows <= 3, "--limit 3 shows at most 3 rows:\n{stdout}");
    assert_one_line_error(&loops(&["demo", "--duration-s", "-1"]), "duration_s");
}

#[test]
fn help_has_examples() {
    for command in ["components", "demo"] {
        let output = loops(&[command, "--help"]);
        assert!(output.status.success());
        assert!(String::from_utf8_lossy(&output.stdout).contains("Examples:"), "{command}");
    }
}

#[test]
fn se3_metric_uses_the_file_orientations() {
    let dir = temp_dir("se3");
    // Out along x facing +x, back facing −x (yaw π: quaternion [0, 0, 1, 0]).
    let mut text = String::new();
    for i in 0..=40 {
        let (x, q) = if i <= 20 { (i, "0 0 0 1") } else { (40 - i, "0 0 1 0") };
        text += &format!("{i}.0 {x}.0 0.0 0.0 {q}\n");
    }
    let path = write_in(&dir, "turn.tum", text);
    let pairs = |metric: &str| {
        let json = dir.join(format!("{}.json", metric.len()));
        let output = loops(&[
            "components",
            path.to_str().unwrap(),
            "--gamma",
            "1.5",
            "--metric",
            metric,
            "--no-separation",
            "--json",
            json.to_str().unwrap(),
        ]);
        assert!(output.status.success(), "{metric}: {}", stderr(&output));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        report["pair_count"].as_u64().unwrap()
    };
    let euclidean = pairs("euclidean");
    let se3 = pairs("se3(rotation_weight_m_per_rad=10)");
    // Under SE(3) a half turn costs 10π m > γ: only pairs on the same leg (and the turn) stay.
    assert!(se3 < euclidean, "se3 {se3} vs euclidean {euclidean}");
    let same_leg: u64 = 2 * (21 * 3 - 2) - 21; // each leg: |i − j| ≤ 1 within it, full plane
    assert!(se3 >= same_leg, "{se3}");
    // A file without orientations cannot feed an SE(3) metric.
    let csv = dir.join("plain.csv");
    std::fs::write(&csv, "t,x,y\n0,0,0\n1,1,0\n").unwrap();
    assert_one_line_error(
        &loops(&["components", csv.to_str().unwrap(), "--gamma", "1", "--metric", "se3(rotation_weight_m_per_rad=1)"]),
        "orientations",
    );
}

/// Three laps of a 40 m square at 1 m/s: revisits one and two laps apart.
fn laps(dir: &Path) -> PathBuf {
    let mut text = String::from("t,x,y\n");
    for k in 0..480 {
        let (x, y) = square_lap(k);
        text += &format!("{k},{x},{y}\n");
    }
    write_in(dir, "laps.csv", text)
}

#[test]
fn sample_writes_exactly_the_budget_and_reports_quality() {
    let dir = temp_dir("sample");
    let file = laps(&dir);
    let out = dir.join("pairs.csv");
    let args = ["sample", file.to_str().unwrap(), "--gamma", "2", "--sampler", "rho", "--budget", "50"];
    let output = loops(&[&args[..], &["--csv", out.to_str().unwrap()]].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("P1 coverage"), "{stdout}");
    let csv = std::fs::read_to_string(&out).unwrap();
    assert_eq!(csv.lines().count(), 51, "header and 50 pairs");
    assert!(csv.lines().next().unwrap().contains("sampler"));
    // Candidate edges for a back end, with relative poses from the file (2-D here: EDGE_SE2).
    let g2o = dir.join("edges.g2o");
    let with_edges = loops(&[&args[..], &["--g2o", g2o.to_str().unwrap()]].concat());
    assert!(with_edges.status.success(), "{}", stderr(&with_edges));
    let edges = std::fs::read_to_string(&g2o).unwrap();
    assert_eq!(edges.lines().filter(|l| l.starts_with("EDGE_SE2 ")).count(), 50, "{edges}");
    // Kept without --force; the same seed writes the same file.
    assert_one_line_error(&loops(&[&args[..], &["--csv", out.to_str().unwrap()]].concat()), "exists");
    let again = loops(&[&args[..], &["--csv", out.to_str().unwrap(), "--force"]].concat());
    assert!(again.status.success());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), csv);
}

/// The lags j − i of the pairs in a samples CSV.
fn lags(csv: &str) -> Vec<i64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (i, j) = (column("i"), column("j"));
    lines
        .map(|line| {
            let fields: Vec<&str> = line.split(',').collect();
            fields[j].parse::<i64>().unwrap() - fields[i].parse::<i64>().unwrap()
        })
        .collect()
}

#[test]
fn sample_skip_trivial_keeps_only_revisits() {
    let dir = temp_dir("sample-skip");
    let file = laps(&dir);
    let f = file.to_str().unwrap();
    let run = |extra: &[&str], out: &Path| {
        let args = ["sample", f, "--gamma", "2", "--sampler", "rho", "--budget", "60", "--csv", out.to_str().unwrap()];
        let output = loops(&[&args[..], extra].concat());
        assert!(output.status.success(), "{}", stderr(&output));
        lags(&std::fs::read_to_string(out).unwrap())
    };
    // The laps are 160 poses long: a revisit is about a lap apart; by the paper's topology the
    // trivial component holds the pairs a few poses apart.
    let plain = run(&["--no-separation"], &dir.join("plain.csv"));
    assert!(plain.iter().any(|&lag| lag < 20), "{plain:?}");
    // By default (at least 4γ apart along the path) the budget goes to revisits only.
    let default = run(&[], &dir.join("default.csv"));
    assert_eq!(default.len(), 60);
    assert!(default.iter().all(|&lag| lag > 100), "{default:?}");
    let skipping = run(&["--no-separation", "--skip-trivial"], &dir.join("skip.csv"));
    assert_eq!(skipping.len(), 60);
    assert!(skipping.iter().all(|&lag| lag > 100), "{skipping:?}");
    assert_one_line_error(
        &loops(&["sample", f, "--gamma", "2", "--sampler", "lio-sam", "--budget", "5", "--skip-trivial"]),
        "--skip-trivial does not apply to the lio-sam baseline",
    );
}

#[test]
fn sample_from_detections_and_bad_input() {
    let dir = temp_dir("sample-det");
    let file = laps(&dir);
    let detections = dir.join("det.txt");
    std::fs::write(&detections, "odom2 0 0 0\nloop 5 165 1\nloop 6 166 0.5\nloop 50 370 0.9\n").unwrap();
    let output = loops(&[
        "sample",
        file.to_str().unwrap(),
        "--gamma",
        "2",
        "--sampler",
        "one",
        "--budget",
        "2",
        "--detections",
        detections.to_str().unwrap(),
        "--epsilon-s",
        "5",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(String::from_utf8_lossy(&output.stdout).contains("2 samples from 2 groups"));
    let f = file.to_str().unwrap();
    assert_one_line_error(
        &loops(&["sample", f, "--gamma", "2", "--sampler", "sigma", "--budget", "5"]),
        "unknown sampler",
    );
    assert_one_line_error(&loops(&["sample", f, "--gamma", "2", "--sampler", "rho", "--budget", "0"]), "budget");
    let outside = dir.join("outside.txt");
    std::fs::write(&outside, "t,t_prime\n5,165\n5,9999\n").unwrap();
    assert_one_line_error(
        &loops(&[
            "sample",
            f,
            "--gamma",
            "2",
            "--sampler",
            "one",
            "--budget",
            "2",
            "--detections",
            outside.to_str().unwrap(),
        ]),
        "line 3",
    );
}

#[test]
fn info_describes_a_text_file() {
    let dir = temp_dir("info");
    let file = out_and_back(&dir);
    let output = loops(&["info", file.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("41 poses, 3 coordinates each, with orientations, over 40.000 s"), "{stdout}");
    assert_one_line_error(&loops(&["info", file.to_str().unwrap(), "--time", "wall"]), "time source");
    assert_one_line_error(&loops(&["info", dir.join("nope.mcap").to_str().unwrap()]), "nope.mcap");
}

/// A TUM file in KITTI's camera frame (y down, the ground in x-z): out along z facing +z, then
/// back facing −z (a half turn about y), 1 m per pose.
fn out_and_back_on_the_ground(dir: &Path) -> (PathBuf, Vec<(f64, f64)>) {
    let mut text = String::new();
    let mut poses = Vec::new();
    for i in 0..=40 {
        // Facing −z is the rotation by π about y: quaternion [0, 1, 0, 0].
        let (z, q, heading) = if i <= 20 { (i, "0 0 0 1", 0.0) } else { (40 - i, "0 1 0 0", std::f64::consts::PI) };
        text += &format!("{i}.0 0.5 1.5 {z}.0 {q}\n");
        poses.push((f64::from(z), heading));
    }
    (write_in(dir, "ground.tum", text), poses)
}

#[test]
fn se2_on_the_chosen_plane_takes_its_coordinates_and_heading() {
    let dir = temp_dir("se2-plane");
    let (path, poses) = out_and_back_on_the_ground(&dir);
    let (weight, gamma) = (10.0, 1.5);
    let metric = format!("se2(rotation_weight_m_per_rad={weight})");
    let pairs = |axes: &[&str]| {
        let mut args = vec!["components", path.to_str().unwrap(), "--gamma", "1.5", "--metric", &metric];
        args.extend_from_slice(&["--no-separation", "--json", "-"]);
        args.extend_from_slice(axes);
        let output = loops(&args);
        assert!(output.status.success(), "{axes:?}: {}", stderr(&output));
        let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
        report["pair_count"].as_u64().unwrap()
    };
    // Brute force on x-z: |Δz| + W |Δθ| ≤ γ over the full plane (x is constant), the paper's S_γ.
    let expected = poses
        .iter()
        .flat_map(|a| poses.iter().map(move |b| (a, b)))
        .filter(|(a, b)| (a.0 - b.0).abs() + weight * (a.1 - b.1).abs() <= gamma)
        .count() as u64;
    assert_eq!(pairs(&["--axes", "0,2"]), expected);
    assert_eq!(pairs(&["--axes", "2,0"]), expected);
    // On x-y every pose is at (0.5, 1.5): all pairs of a leg (the heading about z of a half
    // turn about y is π as well), so the plane changes the answer.
    assert_eq!(pairs(&[]), 21 * 21 + 20 * 20);
    assert_one_line_error(
        &loops(&["components", path.to_str().unwrap(), "--gamma", "1", "--metric", &metric, "--axes", "0,3"]),
        "plane axis",
    );
}

#[test]
fn run_draws_the_maps_in_the_plane_of_axes() {
    let dir = temp_dir("run-plane");
    let (path, _) = out_and_back_on_the_ground(&dir);
    let report = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec!["run", path.to_str().unwrap(), "--gamma", "1.5", "--budget", "10", "--quiet"];
        args.extend_from_slice(&["--out", out.to_str().unwrap()]);
        args.extend_from_slice(extra);
        let output = loops(&args);
        assert!(output.status.success(), "{extra:?}: {}", stderr(&output));
        std::fs::read_to_string(out.join("ground").join("report.html")).unwrap()
    };
    let labels = |html: &str| -> Vec<String> {
        html.split("class=\"label\">").skip(1).filter_map(|s| s.split('<').next()).map(str::to_owned).collect()
    };
    let metres = |html: &str| labels(html).into_iter().filter(|l| l.ends_with("(m)")).collect::<Vec<_>>();
    // Both maps, labelled with the plane's axes (across, then up), and the plane in the summary.
    let xz = report("xz", &["--axes", "0,2"]);
    assert_eq!(metres(&xz), ["x (m)", "z (m)", "x (m)", "z (m)"]);
    assert!(xz.contains("<dt>map plane</dt><dd>x–z</dd>"), "the summary names the plane");
    assert!(xz.contains("The trajectory in x–z"));
    let zy = report("zy", &["--axes", "2,1"]);
    assert_eq!(metres(&zy), ["z (m)", "y (m)", "z (m)", "y (m)"]);
    // By default x-y; under se3 (whole poses) --axes chooses the maps only.
    assert_eq!(metres(&report("default", &[])), ["x (m)", "y (m)", "x (m)", "y (m)"]);
    let se3 = report("se3", &["--axes", "0,2", "--metric", "se3(rotation_weight_m_per_rad=10)"]);
    assert_eq!(metres(&se3), ["x (m)", "z (m)", "x (m)", "z (m)"]);
    // Axes the file does not have are refused before anything is written, whatever the metric.
    for metric in ["euclidean", "so3"] {
        let out = dir.join(format!("bad-{metric}"));
        let output = loops(&[
            "run",
            path.to_str().unwrap(),
            "--gamma",
            "1",
            "--metric",
            metric,
            "--axes",
            "0,3",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(output.status.code(), Some(1), "{metric}: {}", stderr(&output));
        assert!(stderr(&output).contains("plane axis"), "{metric}: {}", stderr(&output));
        assert!(!out.join("ground").exists());
    }
}
