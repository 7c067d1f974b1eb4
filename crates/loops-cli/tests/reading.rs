//! How the commands read what a newcomer has: several files as one trajectory, KITTI poses with
//! `--times`, repeated stamps and detections outside the span dropped on request (one line on
//! stderr each), quaternions printed with few decimals, and `loops info` telling all it
//! promises (format, timestamp order, a graph's edges and loop closures, /tf frame pairs).

use std::path::Path;
use std::process::Command;

mod support;
use support::{assert_one_line_error, loops, stderr, stdout, temp_dir};

/// A square lap of 40 m driven `laps` times at 1 m/s from time `t0`, one pose a second, as TUM
/// lines (`x` and `y` in metres, identity orientation).
fn laps(t0: f64, laps: usize) -> Vec<String> {
    (0..160 * laps)
        .map(|k| {
            let s = (k % 160) as f64;
            let (x, y) = match (k % 160) / 40 {
                0 => (s, 0.0),
                1 => (40.0, s - 40.0),
                2 => (120.0 - s, 40.0),
                _ => (0.0, 160.0 - s),
            };
            format!("{:?} {x:?} {y:?} 0 0 0 0 1", t0 + k as f64)
        })
        .collect()
}

fn write_tum(path: &Path, lines: &[String]) {
    std::fs::write(path, format!("# timestamp tx ty tz qx qy qz qw\n{}\n", lines.join("\n"))).expect("write");
}

/// `loops components ... --json -` as JSON, without its `source`.
fn report(args: &[&str]) -> serde_json::Value {
    let output = loops(&[&["components"], args, &["--json", "-"]].concat());
    assert!(output.status.success(), "{args:?}: {}", stderr(&output));
    let mut report: serde_json::Value = serde_json::from_str(&stdout(&output)).expect("JSON");
    report.as_object_mut().expect("object").remove("source");
    report
}

#[test]
fn several_files_are_one_trajectory_in_time_order() {
    let dir = temp_dir("join");
    let lines = laps(100.0, 3);
    let [whole, a, b, c] = ["whole.tum", "a.tum", "b.tum", "c.tum"].map(|name| dir.join(name));
    write_tum(&whole, &lines);
    write_tum(&a, &lines[..100]);
    write_tum(&b, &lines[100..300]);
    write_tum(&c, &lines[300..]);
    let expected = report(&[whole.to_str().unwrap(), "--gamma", "2"]);
    assert!(expected["components"].as_array().unwrap().iter().any(|c| c["trivial"] == false), "{expected}");
    for order in [[&a, &b, &c], [&c, &a, &b], [&b, &c, &a]] {
        let files: Vec<&str> = order.iter().map(|p| p.to_str().unwrap()).collect();
        assert_eq!(report(&[&files[..], &["--gamma", "2"]].concat()), expected, "{files:?}");
    }
    // The table names the files it read.
    let output = loops(&["components", c.to_str().unwrap(), a.to_str().unwrap(), b.to_str().unwrap(), "--gamma", "2"]);
    assert!(stdout(&output).starts_with(&format!("{} + {} + {}\n", c.display(), a.display(), b.display())));
    // sample too, and its g2o edges come from the joined poses.
    let edges = dir.join("edges.g2o");
    let output = loops(&[
        "sample",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        c.to_str().unwrap(),
        "--gamma",
        "2",
        "--budget",
        "20",
        "--skip-trivial",
        "--g2o",
        edges.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(stdout(&output).contains("480 poses"), "{}", stdout(&output));
    assert_eq!(std::fs::read_to_string(&edges).unwrap().lines().filter(|l| l.starts_with("EDGE_SE3:QUAT")).count(), 20);
}

#[test]
fn overlapping_files_are_an_error_naming_both_and_the_stamps() {
    let dir = temp_dir("overlap");
    let lines = laps(0.0, 2);
    let [a, b] = ["a.tum", "b.tum"].map(|name| dir.join(name));
    write_tum(&a, &lines[..200]);
    write_tum(&b, &lines[150..]);
    let output = loops(&["components", a.to_str().unwrap(), b.to_str().unwrap(), "--gamma", "2"]);
    assert_one_line_error(
        &output,
        &[&format!(
            "{}: overlaps {} in time: its first pose (line 2, 150 s) is not after the last pose of {} (line 201, \
             199 s)",
            b.display(),
            a.display(),
            a.display()
        )],
    );
    // An error inside one file names that file and line, not the first file's.
    let bad = dir.join("bad.tum");
    let mut bad_lines = laps(1000.0, 1);
    bad_lines[5] = bad_lines[4].clone();
    write_tum(&bad, &bad_lines);
    let output = loops(&["components", a.to_str().unwrap(), bad.to_str().unwrap(), "--gamma", "2"]);
    assert_one_line_error(&output, &[&format!("{} line 7: timestamps must strictly increase", bad.display())]);
}

#[test]
fn repeated_stamps_are_dropped_on_request_saying_how_many() {
    let dir = temp_dir("dups");
    let mut lines = laps(0.0, 2);
    lines[10] = lines[9].replace(" 9.0 0.0 ", " 9.0 0.5 ");
    lines[11] = lines[10].replace(" 9.0 0.5 ", " 9.0 0.7 ");
    let file = dir.join("dups.tum");
    write_tum(&file, &lines);
    let f = file.to_str().unwrap();
    let strict = loops(&["components", f, "--gamma", "4"]);
    assert_one_line_error(&strict, &["line 12: timestamps must strictly increase", "--drop-duplicate-stamps"]);
    let lenient = loops(&["components", f, "--gamma", "4", "--drop-duplicate-stamps"]);
    assert!(lenient.status.success(), "{}", stderr(&lenient));
    assert_eq!(
        stderr(&lenient),
        format!(
            "loops: {f}: --drop-duplicate-stamps dropped 2 pose(s) whose timestamp repeats the one before (lines 12 and 13)\n"
        )
    );
    assert!(stdout(&lenient).contains("318 poses"), "{}", stdout(&lenient));
    // The poses kept are the first of each stamp: the same as the file without the repeats.
    let without = dir.join("without.tum");
    write_tum(&without, &[&lines[..10], &lines[12..]].concat());
    assert_eq!(
        report(&[f, "--gamma", "4", "--drop-duplicate-stamps"]),
        report(&[without.to_str().unwrap(), "--gamma", "4"])
    );
    // Nothing to drop: nothing said.
    let quiet = loops(&["components", without.to_str().unwrap(), "--gamma", "4", "--drop-duplicate-stamps"]);
    assert_eq!(stderr(&quiet), "");
}

#[test]
fn detections_outside_the_span_are_dropped_on_request_saying_how_many() {
    let dir = temp_dir("detections");
    let file = dir.join("drive.tum");
    write_tum(&file, &laps(0.0, 2)); // 0 to 319 s
    let detections = dir.join("input.txt");
    std::fs::write(
        &detections,
        "odom2 0 0 0 0\nloop 170 10 0.9\nloop 319.4 159 0.5\nloop 200 40 0.8\nloop 250 -1 0.3\n",
    )
    .unwrap();
    let (f, d) = (file.to_str().unwrap(), detections.to_str().unwrap());
    let args = ["sample", f, "--gamma", "2", "--budget", "5", "--detections", d, "--epsilon-s", "5"];
    assert_one_line_error(
        &loops(&args),
        &[&format!("{d} line 3: detection 1 at 319.4 s lies outside"), "--drop-detections-outside-span"],
    );
    let lenient = loops(&[&args[..], &["--drop-detections-outside-span"]].concat());
    assert!(lenient.status.success(), "{}", stderr(&lenient));
    let first_line = stderr(&lenient).lines().next().unwrap_or_default().to_owned();
    assert_eq!(
        first_line,
        format!(
            "loops: {d}: --drop-detections-outside-span dropped 2 of 4 detection(s) outside the trajectory's time span \
             [0, 319] s (lines 3 and 5)"
        )
    );
    assert!(stdout(&lenient).contains("samples from 2 groups"), "{}", stdout(&lenient));
    // The flag goes with --detections.
    let output = loops(&["sample", f, "--gamma", "2", "--drop-detections-outside-span"]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
}

#[test]
fn kitti_poses_take_their_times_from_a_times_file() {
    let dir = temp_dir("times");
    // A 13-number KITTI file, and the same as poses/00.txt + times.txt.
    let mut with_times = String::new();
    let mut poses = String::new();
    let mut times = String::new();
    for line in laps(5.0, 2) {
        let v: Vec<f64> = line.split_whitespace().map(|f| f.parse().unwrap()).collect();
        // Camera frame: x right, y down, z forward; the ground is x-z.
        let pose = format!("1 0 0 {:?} 0 1 0 0 0 0 1 {:?}", v[1], v[2]);
        with_times += &format!("{:?} {pose}\n", v[0]);
        poses += &format!("{pose}\n");
        times += &format!("{:e}\n", v[0]);
    }
    let [full, pose_file, times_file] = ["13.txt", "00.txt", "times.txt"].map(|name| dir.join(name));
    std::fs::write(&full, with_times).unwrap();
    std::fs::write(&pose_file, poses).unwrap();
    std::fs::write(&times_file, times).unwrap();
    let (p, t) = (pose_file.to_str().unwrap(), times_file.to_str().unwrap());
    let expected = report(&[full.to_str().unwrap(), "--axes", "0,2", "--gamma", "2"]);
    assert_eq!(report(&[p, "--times", t, "--axes", "0,2", "--gamma", "2"]), expected);
    assert_one_line_error(&loops(&["components", p, "--gamma", "2"]), &["line 1: 12 numbers", "--times", "--rate-hz"]);
    let both = loops(&["components", p, "--times", t, "--rate-hz", "10", "--gamma", "2"]);
    assert_eq!(both.status.code(), Some(2), "{}", stderr(&both));
    assert!(stderr(&both).contains("cannot be used with"), "{}", stderr(&both));
    // info reads them the same way.
    let info = loops(&["info", p, "--times", t]);
    assert!(info.status.success(), "{}", stderr(&info));
    assert!(
        stdout(&info).contains("320 poses, 3 coordinates each, with orientations, over 319.000 s"),
        "{}",
        stdout(&info)
    );
}

#[test]
fn kitti_00_with_a_times_file_equals_the_file_with_times() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/kitti_odometry/00.txt");
    if !data.is_file() {
        support::skipped(
            "KITTI 00 with --times",
            &format!("no {} (it lives beside the checkout in CI)", data.display()),
        );
        return;
    }
    let dir = temp_dir("kitti00");
    let (mut poses, mut times) = (String::new(), String::new());
    for line in std::fs::read_to_string(&data).unwrap().lines() {
        let (time, pose) = line.split_once(' ').unwrap();
        poses += &format!("{pose}\n");
        times += &format!("{time}\n");
    }
    let [pose_file, times_file] = ["00.txt", "times.txt"].map(|name| dir.join(name));
    std::fs::write(&pose_file, poses).unwrap();
    std::fs::write(&times_file, times).unwrap();
    let expected = report(&[data.to_str().unwrap(), "--axes", "0,2", "--gamma", "6", "--no-separation"]);
    let got = report(&[
        pose_file.to_str().unwrap(),
        "--times",
        times_file.to_str().unwrap(),
        "--axes",
        "0,2",
        "--gamma",
        "6",
        "--no-separation",
    ]);
    assert_eq!(got, expected);
    assert_eq!(got["poses"], 4541);
    assert_eq!(got["components"].as_array().unwrap().len(), 7); // the KITTI tutorial's 6 revisits and 1 trivial component of S_gamma
}

#[test]
fn quaternions_of_few_decimals_take_a_tolerance() {
    let dir = temp_dir("quaternions");
    let mut lines = laps(0.0, 2);
    lines[7] = lines[7].replace(" 0 0 0 1", " 0 0 0 1.02");
    let file = dir.join("q.tum");
    write_tum(&file, &lines);
    let f = file.to_str().unwrap();
    let metric = "se3(rotation_weight_m_per_rad=1)";
    assert_one_line_error(
        &loops(&["components", f, "--gamma", "2", "--metric", metric]),
        &["line 9: quaternion of pose 7 has norm 1.02", "quaternion_tolerance", "--quaternion-tolerance"],
    );
    let loose = loops(&["components", f, "--gamma", "2", "--metric", metric, "--quaternion-tolerance", "0.05"]);
    assert!(loose.status.success(), "{}", stderr(&loose));
    let strict = loops(&["components", f, "--gamma", "2", "--metric", metric, "--quaternion-tolerance", "1e-9"]);
    assert_one_line_error(&strict, &["line 9:", "--quaternion-tolerance"]);
    assert_one_line_error(
        &loops(&["components", f, "--gamma", "2", "--quaternion-tolerance", "-1"]),
        &["quaternion_tolerance"],
    );
}

#[test]
fn info_tells_the_format_the_order_and_a_graphs_edges() {
    let dir = temp_dir("info");
    let mut lines = laps(0.0, 1);
    lines[21] = lines[20].clone();
    let tum = dir.join("drive.txt");
    write_tum(&tum, &lines);
    // A 2-D pose graph: odometry edges between consecutive ids and 3 loop closures.
    let mut graph = String::new();
    for id in 0..10 {
        graph += &format!("VERTEX_SE2 {id} {id}.0 0 0\n");
    }
    for id in 0..9 {
        graph += &format!("EDGE_SE2 {id} {} 1 0 0 1 0 0 1 0 1\n", id + 1);
    }
    for (i, j) in [(0, 5), (2, 9), (3, 7)] {
        graph += &format!("EDGE_SE2 {i} {j} 0 0 0 1 0 0 1 0 1\n");
    }
    let g2o = dir.join("graph.g2o");
    std::fs::write(&g2o, &graph).unwrap();
    let output = loops(&["info", tum.to_str().unwrap(), g2o.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(
        stdout(&output),
        format!(
            "{}\n  format: tum (from the extension)\n  160 poses, 3 coordinates each, with orientations, \
             over 159.000 s\n  1 timestamp(s) repeat the one before, the first at line 23 (20 s); --drop-duplicate-stamps \
             drops them\n{}\n  format: g2o (from the extension)\n  10 poses, 2 coordinates each, with \
             orientations, vertex ids 0 to 9 (no times: --rate-hz or --times gives seconds)\n  timestamps \
             strictly increasing\n  12 edges, 3 of them loop closures (between \
             vertices more than one id apart)\n",
            tum.display(),
            g2o.display()
        )
    );
    let given = loops(&["info", tum.to_str().unwrap(), "--format", "tum"]);
    assert!(stdout(&given).contains("  format: tum (given)\n"), "{}", stdout(&given));
    let unsorted = dir.join("unsorted.tum");
    write_tum(&unsorted, &[lines[3].clone(), lines[1].clone()]);
    let output = loops(&["info", unsorted.to_str().unwrap()]);
    assert!(
        stdout(&output).contains("timestamps out of order: 1 s at line 3 is before 3 s at line 2"),
        "{}",
        stdout(&output)
    );
}

#[test]
fn info_lists_the_frame_pairs_of_transform_topics() {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../loops-io/tests/make_mcap_fixtures.py");
    let dir = temp_dir("info-mcap");
    let made = match Command::new(support::python()).arg(&script).arg(&dir).output() {
        Ok(output) => output,
        Err(error) => {
            support::skip("the frame pairs of loops info", &format!("cannot run Python ({error})"));
            return;
        }
    };
    if made.status.code() == Some(3) {
        support::skip("the frame pairs of loops info", &stderr(&made));
        return;
    }
    assert!(made.status.success(), "{}", stderr(&made));
    let path = dir.join("ros2_zstd.mcap");
    let output = loops(&["info", path.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(text.contains("  format: mcap (from the extension)\n"), "{text}");
    assert!(
        text.contains(
            "frame pairs of /tf (parent -> child, transforms; --frames PARENT,CHILD):\n  base_link -> laser (5)\n  \
             map -> odom (24)\n  odom -> base_link (24)\n"
        ),
        "{text}"
    );
    assert!(
        text.contains(
            "frame pairs of /transform (parent -> child, transforms; --frames PARENT,CHILD):\n  map -> base_link (24)\n"
        ),
        "{text}"
    );
    // A topic that is not a transform has no pairs listed.
    assert!(!text.contains("frame pairs of /pose"), "{text}");
}
