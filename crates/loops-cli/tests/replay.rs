//! `loops replay`: one JSON line per keyframe whose candidates are the Rust API's, keyframes
//! every few seconds giving the same candidates, latency figures on stderr, and one-line errors
//! for bad flags and bad poses.

use std::path::Path;
use std::process::{Command, Output};

mod support;
use support::TempDir;

use loops_core::{
    Separation, UrbanDrive,
    online::{Cap, FirstOffer, OnlineLoops, OnlineSampler, OnlineSamplerOptions},
};
use serde_json::Value;

/// A folder with a 10 min synthetic drive as a TUM file (numbers written so they read back
/// exactly), and its times and positions.
fn drive(name: &str) -> (TempDir, Vec<f64>, Vec<[f64; 3]>) {
    let dir = TempDir::at(std::env::temp_dir().join(format!("loops-replay-{name}-{}", std::process::id())));
    let traj = UrbanDrive { duration_s: 600.0, seed: 4, ..UrbanDrive::default() }.generate().expect("drive").trajectory;
    let mut text = String::from("# timestamp tx ty tz qx qy qz qw\n");
    let (mut times, mut points) = (Vec::new(), Vec::new());
    for k in 0..traj.len() {
        let p = traj.point(k);
        let point = [p[0], p[1], if p.len() > 2 { p[2] } else { 0.0 }];
        let t = traj.timestamps_s()[k];
        text += &format!("{t:?} {:?} {:?} {:?} 0 0 0 1\n", point[0], point[1], point[2]);
        times.push(t);
        points.push(point);
    }
    std::fs::write(dir.join("drive.tum"), text).expect("write");
    (dir, times, points)
}

fn loops(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_loops")).args(args).current_dir(dir).output().expect("the loops binary runs")
}

/// The candidates of the Rust API on the same poses: (keyframe, j, component, distance, first).
fn rust_candidates(
    times: &[f64],
    points: &[[f64; 3]],
    options: OnlineSamplerOptions,
) -> Vec<(u64, u64, u64, f64, bool)> {
    let mut online = OnlineLoops::new(loops_core::MetricSpec::Euclidean, 3, 40.0).unwrap();
    let mut sampler = OnlineSampler::new(options).unwrap();
    let mut out = Vec::new();
    for (t, p) in times.iter().zip(points) {
        let update = online.push(*t, p).unwrap();
        for c in sampler.offer(&online, &update).unwrap() {
            out.push((c.keyframe as u64, c.pair[0] as u64, u64::from(c.component), c.distance, c.first));
        }
    }
    out
}

/// The JSON lines of stdout, parsed.
fn lines(output: &Output) -> Vec<Value> {
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    String::from_utf8(output.stdout.clone())
        .unwrap()
        .lines()
        .map(|line| serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {line}")))
        .collect()
}

fn candidates(lines: &[Value]) -> Vec<(u64, u64, u64, f64, bool)> {
    lines
        .iter()
        .flat_map(|line| line["candidates"].as_array().unwrap().iter())
        .map(|c| {
            (
                c["keyframe"].as_u64().unwrap(),
                c["j"].as_u64().unwrap(),
                c["component"].as_u64().unwrap(),
                c["distance"].as_f64().unwrap(),
                c["first"].as_bool().unwrap(),
            )
        })
        .collect()
}

/// Equal, distances to the last bit that a JSON float may lose in parsing.
fn assert_same(got: &[(u64, u64, u64, f64, bool)], expected: &[(u64, u64, u64, f64, bool)]) {
    assert_eq!(got.len(), expected.len());
    for (g, e) in got.iter().zip(expected) {
        assert_eq!((g.0, g.1, g.2, g.4), (e.0, e.1, e.2, e.4));
        assert!((g.3 - e.3).abs() <= 1e-15 * e.3.abs().max(1.0), "{g:?} {e:?}");
    }
}

#[test]
fn each_keyframes_line_parses_and_its_candidates_are_the_rust_apis() {
    let (dir, times, points) = drive("api");
    let args = ["replay", "drive.tum", "--gamma", "40", "--rate", "0.05", "--cap-per-minute", "2", "--seed", "3"];
    let output = loops(&dir, &args);
    let parsed = lines(&output);
    assert_eq!(parsed.len(), times.len(), "one line per pose");
    // Latencies are whole nanoseconds, printed as such: at most 3 decimals of µs.
    let text = String::from_utf8_lossy(&output.stdout);
    for latency in text.split("\"latency_us\":").skip(1) {
        let number: String = latency.chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
        let decimals = number.split('.').nth(1).map_or(0, str::len);
        assert!(decimals <= 3, "latency_us {number}");
    }
    for (k, line) in parsed.iter().enumerate() {
        assert_eq!(line["pose"].as_u64(), Some(k as u64));
        assert_eq!(line["t_s"].as_f64(), Some(times[k]));
        assert_eq!(line["poses"].as_u64(), Some(1));
        assert!(line["latency_us"].as_f64().unwrap() >= 0.0);
        assert!(line["loop_duration_s"].as_f64().unwrap() >= 0.0);
        assert!(line["created"].is_array() && line["merged"].is_array());
    }
    let options = OnlineSamplerOptions {
        rate: 0.05,
        cap: Cap::PerMinute(2.0),
        separation: Separation::for_gamma(40.0),
        seed: 3,
        ..OnlineSamplerOptions::default()
    };
    let expected = rust_candidates(&times, &points, options);
    assert!(expected.len() > 10);
    assert_same(&candidates(&parsed), &expected);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("p50") && stderr.contains("p99") && stderr.contains("poses/s"), "{stderr}");
    assert!(stderr.contains(&format!("replayed {} poses", times.len())), "{stderr}");

    // Keyframes every 5 s: fewer lines, the same candidates.
    let every = lines(&loops(&dir, &[&args[..], &["--every-s", "5"]].concat()));
    assert!(every.len() < parsed.len() / 10);
    let pushed: u64 = every.iter().map(|line| line["poses"].as_u64().unwrap()).sum();
    assert_eq!(pushed, times.len() as u64);
    assert_eq!(every.last().unwrap()["pose"].as_u64(), Some(times.len() as u64 - 1));
    assert_same(&candidates(&every), &expected);

    // The paper's S_gamma, no first-appearance candidates.
    let plain = lines(&loops(
        &dir,
        &["replay", "drive.tum", "--gamma", "40", "--rate", "0.01", "--no-first", "--no-separation"],
    ));
    let options = OnlineSamplerOptions { rate: 0.01, first_on_appearance: false, ..OnlineSamplerOptions::default() };
    assert_same(&candidates(&plain), &rust_candidates(&times, &points, options));

    // The improvements carry the pair they improve, and --first-offer edge has none.
    let mut core = OnlineLoops::new(loops_core::MetricSpec::Euclidean, 3, 40.0).unwrap();
    let mut sampler = OnlineSampler::new(OnlineSamplerOptions {
        rate: 0.05,
        cap: Cap::PerMinute(2.0),
        separation: Separation::for_gamma(40.0),
        seed: 3,
        ..OnlineSamplerOptions::default()
    })
    .unwrap();
    let mut improvements = Vec::new();
    for (t, p) in times.iter().zip(&points) {
        let update = core.push(*t, p).unwrap();
        let offered = sampler.offer(&core, &update).unwrap();
        improvements
            .extend(offered.iter().filter_map(|c| c.improves.map(|i| (c.keyframe as u64, c.pair[1] as u64, i))));
    }
    let printed: Vec<(u64, u64, [usize; 2])> = parsed
        .iter()
        .flat_map(|line| line["candidates"].as_array().unwrap().clone())
        .filter(|c| c.get("improves").is_some())
        .map(|c| {
            let i = c["improves"].as_array().unwrap();
            let i = [i[0].as_u64().unwrap() as usize, i[1].as_u64().unwrap() as usize];
            (c["keyframe"].as_u64().unwrap(), c["k"].as_u64().unwrap(), i)
        })
        .collect();
    assert!(!improvements.is_empty());
    assert_eq!(printed, improvements);
    let edge = lines(&loops(&dir, &[&args[..], &["--first-offer", "edge"]].concat()));
    let at_edge = OnlineSamplerOptions {
        rate: 0.05,
        cap: Cap::PerMinute(2.0),
        separation: Separation::for_gamma(40.0),
        seed: 3,
        first_offer: FirstOffer::AtEdge,
        ..OnlineSamplerOptions::default()
    };
    assert_same(&candidates(&edge), &rust_candidates(&times, &points, at_edge));
    assert!(edge.iter().all(|line| line["candidates"].as_array().unwrap().iter().all(|c| c.get("improves").is_none())));
    let unknown = loops(&dir, &[&args[..], &["--first-offer", "middle"]].concat());
    assert!(!unknown.status.success());
    assert!(String::from_utf8_lossy(&unknown.stderr).contains("edge-then-closest"));

    // --quiet: the figures only.
    let quiet = loops(&dir, &[&args[..], &["--quiet"]].concat());
    assert!(quiet.status.success() && quiet.stdout.is_empty());
    assert!(String::from_utf8_lossy(&quiet.stderr).contains("latency per keyframe"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_flags_and_bad_poses_are_one_line_errors() {
    let (dir, _, _) = drive("errors");
    let cases: [(&[&str], &str); 6] = [
        (&["--gamma", "40", "--every-s", "-1"], "--every-s"),
        (&["--gamma", "40", "--rate", "-1"], "rate"),
        (&["--gamma", "40", "--cap-per-minute", "0"], "cap"),
        (&["--gamma", "nan"], "NaN"),
        (&["--gamma", "40", "--metric", "manhattan"], "manhattan"),
        (&["--gamma", "40", "--separation-path", "-3"], "-3"),
    ];
    for (flags, named) in cases {
        let output = loops(&dir, &[&["replay", "drive.tum"][..], flags].concat());
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{flags:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{flags:?}: {stderr}");
        assert!(stderr.starts_with("loops: error: ") && stderr.contains(named), "{flags:?}: {stderr}");
        assert!(output.stdout.is_empty());
    }
    std::fs::write(dir.join("back.tum"), "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n0.5 2 0 0 0 0 0 1\n").unwrap();
    let output = loops(&dir, &["replay", "back.tum", "--gamma", "1"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("back.tum") && stderr.contains("line 3"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ctrl_c_stops_after_the_keyframe_in_progress_and_prints_the_figures() {
    use std::io::{BufRead, BufReader};
    let dir = TempDir::at(std::env::temp_dir().join(format!("loops-replay-interrupt-{}", std::process::id())));
    let synth = loops(&dir, &["synth", "long.tum", "--duration-s", "7200", "--seed", "2"]);
    assert!(synth.status.success(), "{}", String::from_utf8_lossy(&synth.stderr));
    let mut child = Command::new(env!("CARGO_BIN_EXE_loops"))
        .args(["replay", "long.tum", "--gamma", "40"])
        .current_dir(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("loops runs");
    // Once the first keyframe's line is out, the replay is under way: interrupt it.
    let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
    let mut first = String::new();
    stdout.read_line(&mut first).expect("a line");
    assert!(first.starts_with("{\"pose\":0,"), "{first}");
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().expect("kill runs");
    assert!(status.success());
    let rest: Vec<String> = stdout.lines().map(|line| line.expect("a line")).collect();
    let output = child.wait_with_output().expect("it ends");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted after") && stderr.contains("p99"), "{stderr}");
    // Every line printed is whole, and the figures count exactly the poses printed.
    let poses = 1 + rest.len();
    for line in &rest {
        serde_json::from_str::<Value>(line).expect("a whole JSON line");
    }
    assert!(stderr.contains(&format!("interrupted after {poses} poses")), "{poses}: {stderr}");
    assert!(poses < 72_000, "the replay ran to the end before the interrupt");
    let _ = std::fs::remove_dir_all(&dir);
}
