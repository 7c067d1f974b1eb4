//! `loops components --edges`: where the loop-closure edges of a pose graph fall, checked edge
//! by edge against a brute force (δ of the two vertices, the separation on the path length,
//! and a dense 4-connected labelling of the distance matrix); edge-only graphs chained with
//! `--chain-edges`.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Output;

mod support;
use support::{loops, one_line_error, stderr, stdout, temp_dir, write_in};

/// Exit code 2 and one line on stderr, mentioning each of `needles`.
fn assert_one_line_error(output: &Output, needles: &[&str]) {
    let err = one_line_error(output);
    for needle in needles {
        assert!(err.contains(needle), "{err:?} should mention {needle:?}");
    }
}

/// A small 2-D graph that comes back to itself: 90 vertices along a figure of eight traced
/// twice with a drift, odometry edges, and loop-closure edges between many pairs (near and far,
/// in both directions), as g2o text; and the vertices.
fn small_graph() -> (String, Vec<[f64; 2]>) {
    let n = 90;
    let points: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 45.0;
            [6.0 * a.sin() + 0.01 * k as f64, 3.0 * (2.0 * a).sin() + 0.004 * k as f64]
        })
        .collect();
    let mut text = String::new();
    for (k, [x, y]) in points.iter().enumerate() {
        writeln!(text, "VERTEX_SE2 {k} {x:?} {y:?} 0").unwrap();
    }
    for k in 0..n - 1 {
        writeln!(text, "EDGE_SE2 {k} {} 0 0 0 1 0 0 1 0 1", k + 1).unwrap();
    }
    for i in 0..n {
        for j in i + 2..n {
            if (i * 7 + j * 3) % 17 == 0 {
                let (a, b) = if (i + j) % 2 == 0 { (i, j) } else { (j, i) };
                writeln!(text, "EDGE_SE2 {a} {b} 0 0 0 1 0 0 1 0 1").unwrap();
            }
        }
    }
    (text, points)
}

/// δ of vertices `i` and `j`: the Euclidean distance of their positions.
fn delta(points: &[[f64; 2]], i: usize, j: usize) -> f64 {
    let (dx, dy) = (points[i][0] - points[j][0], points[i][1] - points[j][1]);
    (dx * dx + dy * dy).sqrt()
}

/// The cells `(i, j)`, `i ≤ j`, of S_γ that keep `separation` (path length, time; the time of
/// pose k is k seconds), labelled by 4-connected flood fill of the dense matrix: 0 outside.
fn dense_labels(points: &[[f64; 2]], gamma: f64, separation: Option<(f64, f64)>) -> Vec<Vec<usize>> {
    let n = points.len();
    let distance = |i: usize, j: usize| delta(points, i, j);
    let mut s = vec![0.0];
    for k in 1..n {
        s.push(s[k - 1] + distance(k - 1, k));
    }
    let inside = |i: usize, j: usize| {
        i <= j
            && distance(i, j) <= gamma
            && separation.is_none_or(|(path, time)| j > i && s[j] - s[i] >= path && (j - i) as f64 >= time)
    };
    let mut labels = vec![vec![0; n]; n];
    let mut next = 0;
    for i0 in 0..n {
        for j0 in 0..n {
            if !inside(i0, j0) || labels[i0][j0] != 0 {
                continue;
            }
            next += 1;
            labels[i0][j0] = next;
            let mut stack = vec![(i0, j0)];
            while let Some((i, j)) = stack.pop() {
                let neighbours = [(i.wrapping_sub(1), j), (i + 1, j), (i, j.wrapping_sub(1)), (i, j + 1)];
                for (a, b) in neighbours {
                    if a < n && b < n && inside(a, b) && labels[a][b] == 0 {
                        labels[a][b] = next;
                        stack.push((a, b));
                    }
                }
            }
        }
    }
    labels
}

/// The rows of an edge verdicts CSV, by column name.
fn csv_rows(text: &str) -> Vec<HashMap<String, String>> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    assert_eq!(header, ["line", "from_id", "to_id", "i", "j", "t_s", "t_prime_s", "distance", "verdict", "component"]);
    lines.map(|line| header.iter().map(|h| h.to_string()).zip(line.split(',').map(str::to_owned)).collect()).collect()
}

#[test]
fn every_edge_verdict_is_the_brute_forces() {
    let dir = temp_dir("brute");
    let (text, points) = small_graph();
    let graph = dir.join("small.g2o");
    std::fs::write(&graph, text).unwrap();
    let gamma = 1.5;
    // Flags, and the separation (path length, time) they ask for.
    type Case<'a> = (&'a [&'a str], Option<(f64, f64)>);
    let cases: [Case<'_>; 3] = [
        (&[], Some((4.0 * gamma, 0.0))),
        (&["--no-separation"], None),
        (&["--separation-path", "2", "--separation-time", "9"], Some((2.0, 9.0))),
    ];
    let mut seen = std::collections::BTreeSet::new();
    for (k, (flags, separation)) in cases.into_iter().enumerate() {
        let csv = dir.join(format!("edges-{k}.csv"));
        let args = [&["components", graph.to_str().unwrap(), "--gamma", "1.5"], flags, &["--edges-csv"]].concat();
        let output = loops(&[&args[..], &[csv.to_str().unwrap()]].concat());
        assert!(output.status.success(), "{}", stderr(&output));
        let rows = csv_rows(&std::fs::read_to_string(&csv).unwrap());
        let labels = dense_labels(&points, gamma, separation);
        let paper = dense_labels(&points, gamma, None);
        let mut by_component: HashMap<String, usize> = HashMap::new();
        let mut counts: HashMap<String, usize> = HashMap::new();
        for row in &rows {
            let (i, j): (usize, usize) = (row["i"].parse().unwrap(), row["j"].parse().unwrap());
            assert_eq!((row["from_id"].parse::<usize>().unwrap(), row["to_id"].parse::<usize>().unwrap()), (i, j));
            assert!(i.abs_diff(j) > 1, "only loop closures");
            let (a, b) = (i.min(j), i.max(j));
            let delta = delta(&points, i, j);
            assert!((row["distance"].parse::<f64>().unwrap() - delta).abs() <= 1e-12 * delta.max(1.0), "{row:?}");
            let label = labels[a][b];
            let verdict = row["verdict"].as_str();
            *counts.entry(verdict.to_owned()).or_default() += 1;
            seen.insert(verdict.to_owned());
            match verdict {
                "outside" => assert!(delta > gamma, "{row:?}"),
                "not-separated" => assert!(delta <= gamma && label == 0 && separation.is_some(), "{row:?}"),
                "component" | "trivial" => {
                    assert!(label > 0, "{row:?}");
                    // The same engine component for the same dense label, and back.
                    let previous = by_component.insert(row["component"].clone(), label);
                    assert!(previous.is_none_or(|p| p == label), "{row:?}");
                    // Trivial: the component holds the diagonal (only without a separation).
                    let trivial = (0..points.len()).any(|d| labels[d][d] == label);
                    assert_eq!(verdict == "trivial", trivial, "{row:?}");
                }
                other => panic!("unknown verdict {other}"),
            }
            assert_eq!(delta <= gamma, paper[a][b] > 0);
        }
        let mut labels_seen: Vec<usize> = by_component.values().copied().collect();
        labels_seen.sort_unstable();
        labels_seen.dedup();
        assert_eq!(labels_seen.len(), by_component.len(), "one engine component per dense label");
        // The counts printed are the CSV's.
        let printed = stdout(&output);
        for name in ["component", "trivial", "not-separated", "outside"] {
            let line = printed.lines().find(|l| l.trim_start().starts_with(&format!("{name} "))).expect(name);
            let count: usize = line.split_whitespace().nth(1).unwrap().parse().unwrap();
            assert_eq!(count, counts.get(name).copied().unwrap_or(0), "{name}: {printed}");
        }
        assert!(printed.contains(&format!("{} of ", rows.len())), "{printed}");
    }
    assert_eq!(seen.len(), 4, "every verdict is exercised: {seen:?}");
}

#[test]
fn edges_as_json_on_stdout_and_the_flags_errors() {
    let dir = temp_dir("json");
    let (text, _) = small_graph();
    let graph = dir.join("small.g2o");
    std::fs::write(&graph, text).unwrap();
    let g = graph.to_str().unwrap();
    let output = loops(&["components", g, "--gamma", "1.5", "--edges-json", "-"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let json: serde_json::Value = serde_json::from_str(&stdout(&output)).expect("only JSON on stdout");
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(json["loop_closures"].as_u64(), Some(rows.len() as u64));
    let counts = &json["counts"];
    let total: u64 =
        ["component", "trivial", "not-separated", "outside"].iter().map(|k| counts[k].as_u64().unwrap()).sum();
    assert_eq!(total, rows.len() as u64);
    assert_eq!(json["separation"]["path"].as_f64(), Some(6.0));

    let tum = dir.join("a.tum");
    std::fs::write(&tum, "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 0 0 0 0 0 0 1\n").unwrap();
    let t = tum.to_str().unwrap();
    assert_one_line_error(
        &loops(&["components", t, "--gamma", "1", "--edges"]),
        &["--edges needs a pose graph", "tum"],
    );
    assert_one_line_error(&loops(&["components", g, g, "--gamma", "1", "--edges"]), &["one pose graph", "2 files"]);
    assert_one_line_error(
        &loops(&["components", g, "--gamma", "1", "--json", "-", "--edges-csv", "-"]),
        &["each take all of stdout"],
    );
    // An existing file is kept unless --force, and nothing is written when one is refused.
    let (csv, json) = (dir.join("e.csv"), dir.join("e.json"));
    std::fs::write(&json, "mine").unwrap();
    let output = loops(&[
        "components",
        g,
        "--gamma",
        "1.5",
        "--edges-csv",
        csv.to_str().unwrap(),
        "--edges-json",
        json.to_str().unwrap(),
    ]);
    assert_one_line_error(&output, &["e.json", "exists"]);
    assert!(!csv.exists(), "a command that fails writes nothing");
    assert_eq!(std::fs::read_to_string(&json).unwrap(), "mine");
}

/// Vertices' relative poses as the edges of a file without vertices.
fn edge_only(dir: &Path, gap_at: Option<usize>) -> PathBuf {
    let (_, points) = small_graph();
    let mut text = String::new();
    for k in 0..points.len() - 1 {
        if Some(k) == gap_at {
            continue;
        }
        let (dx, dy) = (points[k + 1][0] - points[k][0], points[k + 1][1] - points[k][1]);
        writeln!(text, "EDGE2 {k} {} {dx:?} {dy:?} 0 1 0 1 1 0 0", k + 1).unwrap();
    }
    writeln!(text, "EDGE2 80 2 0 0 0 1 0 1 1 0 0").unwrap();
    write_in(dir, &format!("edges-{gap_at:?}.graph"), text)
}

#[test]
fn an_edge_only_graph_is_chained_on_request_with_a_warning() {
    let dir = temp_dir("chain");
    let path = edge_only(&dir, None);
    let p = path.to_str().unwrap();
    assert_one_line_error(&loops(&["components", p, "--gamma", "1.5"]), &["but no vertex", "--chain-edges"]);
    let output = loops(&["components", p, "--gamma", "1.5", "--chain-edges", "--edges", "--no-separation"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let err = stderr(&output);
    assert!(
        err.contains("90 poses (vertices 0 to 89) chained from the odometry edges") && err.contains("dead reckoning"),
        "{err}"
    );
    assert!(stdout(&output).contains("90 poses over 89.0 s"), "{}", stdout(&output));
    assert!(stdout(&output).contains("loop-closure edges: 1 of 90 edges"), "{}", stdout(&output));
    let info = loops(&["info", p, "--chain-edges"]);
    assert!(
        stdout(&info).contains("no vertices: the poses are its 89 odometry edges chained from vertex 0"),
        "{}",
        stdout(&info)
    );
    // The chain is the vertices (the small graph's poses, here without headings).
    let (text, _) = small_graph();
    let with_vertices = dir.join("v.g2o");
    std::fs::write(&with_vertices, text).unwrap();
    let report = |file: &str, chain: &[&str]| {
        let output = loops(&[&["components", file, "--gamma", "1.5", "--json", "-"], chain].concat());
        assert!(output.status.success(), "{}", stderr(&output));
        let mut json: serde_json::Value = serde_json::from_str(&stdout(&output)).unwrap();
        json.as_object_mut().unwrap().remove("source");
        json
    };
    let chained = report(p, &["--chain-edges"]);
    let given = report(with_vertices.to_str().unwrap(), &[]);
    assert_eq!(chained["components"].as_array().unwrap().len(), given["components"].as_array().unwrap().len());
    assert_eq!(chained["pair_count"], given["pair_count"]);
    let gap = edge_only(&dir, Some(41));
    assert_one_line_error(
        &loops(&["components", gap.to_str().unwrap(), "--gamma", "1.5", "--chain-edges"]),
        &["no edge joins vertex 41 and vertex 42"],
    );
}
