//! Pose-graph edges: their measurements and information matrices as written (TORO's `EDGE2`
//! order reordered), and edge-only files chained from their odometry edges, checked against
//! vertices whose relative poses were written as edges with hand-written algebra.

use std::fmt::Write as _;

use loops_io::{IoError, ReadOptions, RelativePose, Timing, read_pose_graph, read_pose_graph_with};

mod support;
use support::TempDir;

/// A seeded xorshift generator of numbers in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn between(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

fn chained() -> ReadOptions {
    ReadOptions::default().chain_edges(true)
}

#[test]
fn edges_carry_their_measurement_and_information() {
    let dir = TempDir::new();
    let text = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n\
                EDGE_SE2 0 1 1 0.5 0.25 11 12 13 22 23 33\nEDGE_SE2 1 0 -1 0 -0.25\n";
    let graph = read_pose_graph(dir.file("g.g2o", text), &Timing::FromFile).unwrap();
    assert_eq!(graph.edges[0].measurement, RelativePose::Se2 { translation: [1.0, 0.5], rotation_rad: 0.25 });
    assert_eq!(graph.edges[0].information, [11.0, 12.0, 13.0, 22.0, 23.0, 33.0]);
    assert!(graph.edges[1].information.is_empty(), "no information written: none read");
    assert_eq!(graph.edge_rows(&graph.edges[1]), Some([1, 0]));
    assert!(graph.chain.is_none());

    // TORO writes xx xy yy θθ xθ yθ.
    let toro = "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nEDGE2 0 1 1 0 0 11 12 22 33 13 23\n";
    let graph = read_pose_graph(dir.file("t.graph", toro), &Timing::FromFile).unwrap();
    assert_eq!(graph.edges[0].information, [11.0, 12.0, 13.0, 22.0, 23.0, 33.0]);

    let upper: String = (1..=21).map(|k| format!(" {k}")).collect();
    let text = format!(
        "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n\
         EDGE_SE3:QUAT 0 1 1 2 3 0 0 0.6 0.8{upper}\n"
    );
    let graph = read_pose_graph(dir.file("q.g2o", &text), &Timing::FromFile).unwrap();
    assert_eq!(
        graph.edges[0].measurement,
        RelativePose::Se3 { translation: [1.0, 2.0, 3.0], rotation_xyzw: [0.0, 0.0, 0.6, 0.8] }
    );
    assert_eq!(graph.edges[0].information, (1..=21).map(f64::from).collect::<Vec<_>>());

    // TORO 3-D: roll, pitch, yaw; a yaw of 1.2 alone is a rotation of 1.2 about z.
    let text = format!("VERTEX3 0 0 0 0 0 0 0\nVERTEX3 1 1 0 0 0 0 0\nEDGE3 0 1 1 0 0 0 0 1.2{upper}\n");
    let graph = read_pose_graph(dir.file("e.graph", &text), &Timing::FromFile).unwrap();
    let RelativePose::Se3 { rotation_xyzw: q, .. } = graph.edges[0].measurement else { panic!("a 3-D edge") };
    let expected = [0.0, 0.0, 0.6f64.sin(), 0.6f64.cos()];
    assert!(q.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-15), "{q:?}");
}

#[test]
fn a_partial_or_bad_information_matrix_names_its_line() {
    let dir = TempDir::new();
    let cases = [
        (
            "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0\n",
            "line 3: expected 6 or 12 columns (EDGE_SE2 i j dx dy dtheta, then the information matrix's 6 entries or \
             none), found 9: the line ends after column 9 (\"0\")",
        ),
        (
            "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 x 1\n",
            r#"line 3: column 11 ("x") is not a number"#,
        ),
    ];
    for (text, expected) in cases {
        let path = dir.file("bad.g2o", text);
        let message = read_pose_graph(&path, &Timing::FromFile).unwrap_err().to_string();
        assert!(message.ends_with(expected), "{message}");
    }
}

#[test]
fn an_edge_only_file_is_refused_naming_the_option_and_chained_on_request() {
    let dir = TempDir::new();
    let path = dir.file("edges.g2o", "# odometry\nEDGE_SE2 0 1 1 0 0\nEDGE_SE2 1 2 1 0 0\nEDGE_SE2 2 0 -2 0 0\n");
    for error in
        [read_pose_graph(&path, &Timing::FromFile).unwrap_err(), loops_io::read_trajectory(&path, None).unwrap_err()]
    {
        assert!(matches!(error, IoError::PoseGraph { .. }), "{error:?}");
        let message = error.to_string();
        assert!(message.contains("3 edge(s) (the first on line 2) but no vertex"), "{message}");
        assert!(message.contains("chain_edges=True (--chain-edges)"), "{message}");
    }
    let (table, notes) = loops_io::read_trajectory_chaining(&path, &chained()).unwrap();
    let chain = notes.chain;
    assert_eq!(table.positions, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]);
    assert_eq!(table.timestamps_s, [0.0, 1.0, 2.0]);
    assert_eq!(table.source_lines, [2, 2, 3], "the line of the edge that placed each pose");
    let chain = chain.expect("chained");
    assert_eq!((chain.first_id, chain.last_id, chain.poses()), (0, 2, 3));
    assert!(chain.to_string().contains("3 poses (vertices 0 to 2) chained from the odometry edges"), "{chain}");
    assert!(chain.to_string().contains("dead reckoning"));
    // A file with vertices is read as before, chain_edges or not.
    let with_vertices = dir.file("v.g2o", "VERTEX_SE2 0 5 5 0\nVERTEX_SE2 1 6 5 0\nEDGE_SE2 0 1 1 0 0\n");
    let (table, notes) = loops_io::read_trajectory_chaining(&with_vertices, &chained()).unwrap();
    assert!(notes.chain.is_none() && notes.warnings().is_empty());
    assert_eq!(table.positions[0], [5.0, 5.0, 0.0]);
    // A rate times the chained poses by their ids.
    let graph = read_pose_graph_with(&path, &chained().timing(Timing::RateHz(4.0))).unwrap();
    assert_eq!(graph.vertices.timestamps_s, [0.0, 0.25, 0.5]);
}

#[test]
fn a_gap_in_the_odometry_names_the_missing_vertex() {
    let dir = TempDir::new();
    let cases = [
        ("EDGE_SE2 3 4 1 0 0\nEDGE_SE2 4 5 1 0 0\nEDGE_SE2 6 7 1 0 0\nEDGE_SE2 7 3 0 0 0\n", 5, "3 to 7"),
        ("EDGE_SE2 0 2 1 0 0\nEDGE_SE2 1 2 1 0 0\n", 0, "0 to 2"),
    ];
    for (text, k, range) in cases {
        let path = dir.file("gap.g2o", text);
        let message = read_pose_graph_with(&path, &chained()).unwrap_err().to_string();
        let expected = format!("no edge joins vertex {k} and vertex {} (the edges name vertices {range};", k + 1);
        assert!(message.contains(&expected), "{message}");
    }
    let path = dir.file("zero.g2o", "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 0\n");
    let message = read_pose_graph_with(&path, &chained()).unwrap_err().to_string();
    assert!(message.contains("line 1: the edge's quaternion [0.0, 0.0, 0.0, 0.0] is zero"), "{message}");
}

/// SE(2): vertices at random poses (the first at the origin), their relative poses written as
/// `EDGE_SE2` lines by hand-written trigonometry (one step backwards, k + 1 → k, and loop
/// closures among them), chained back.
#[test]
fn chained_se2_edges_give_back_the_vertices() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let n = 200;
    let mut poses = vec![[0.0, 0.0, 0.0]];
    for _ in 1..n {
        let [x, y, th]: [f64; 3] = *poses.last().unwrap();
        let (step, turn) = (rng.between(0.1, 2.0), rng.between(-0.8, 0.8));
        poses.push([x + step * th.cos(), y + step * th.sin(), th + turn]);
    }
    let relative = |a: [f64; 3], b: [f64; 3]| -> [f64; 3] {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let (s, c) = a[2].sin_cos();
        [c * dx + s * dy, -s * dx + c * dy, b[2] - a[2]]
    };
    let mut text = String::new();
    for k in 0..n - 1 {
        let (a, b) = if k == 57 { (k + 1, k) } else { (k, k + 1) };
        let [dx, dy, dth] = relative(poses[a], poses[b]);
        writeln!(text, "EDGE_SE2 {a} {b} {dx:?} {dy:?} {dth:?} 1 0 0 1 0 1").unwrap();
        if k % 20 == 19 {
            let [dx, dy, dth] = relative(poses[k + 1], poses[k / 2]);
            writeln!(text, "EDGE_SE2 {} {} {dx:?} {dy:?} {dth:?}", k + 1, k / 2).unwrap();
        }
    }
    let dir = TempDir::new();
    let graph = read_pose_graph_with(dir.file("se2.g2o", &text), &chained()).unwrap();
    assert_eq!(graph.vertices.len(), n);
    assert_eq!(graph.vertices.dim, 2);
    assert_eq!(graph.loop_closures().count(), (n - 1) / 20);
    let orientations = graph.vertices.orientations_xyzw.as_ref().unwrap();
    for (k, pose) in poses.iter().enumerate() {
        let got = graph.vertices.positions[k];
        assert!((got[0] - pose[0]).abs() < 1e-9 && (got[1] - pose[1]).abs() < 1e-9, "pose {k}: {got:?} {pose:?}");
        let [_, _, z, w] = orientations[k];
        let heading = 2.0 * z.atan2(w);
        assert!(loops_core::angle_difference(heading, pose[2]).abs() < 1e-9, "pose {k}: {heading} {}", pose[2]);
    }
}

/// Hamilton product of quaternions `[x, y, z, w]`.
fn multiply(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

fn conjugate(q: [f64; 4]) -> [f64; 4] {
    [-q[0], -q[1], -q[2], q[3]]
}

/// `v` rotated by the unit quaternion `q`: `q v q*`.
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let r = multiply(multiply(q, [v[0], v[1], v[2], 0.0]), conjugate(q));
    [r[0], r[1], r[2]]
}

/// SE(3): random poses, relative poses by hand-written quaternion algebra as `EDGE_SE3:QUAT`
/// lines, chained back.
#[test]
fn chained_se3_edges_give_back_the_vertices() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let n = 150;
    let unit = |rng: &mut Rng| {
        let q = [rng.between(-1.0, 1.0), rng.between(-1.0, 1.0), rng.between(-1.0, 1.0), rng.between(-1.0, 1.0)];
        let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        q.map(|v| v / norm)
    };
    let mut poses: Vec<([f64; 3], [f64; 4])> = vec![([0.0; 3], [0.0, 0.0, 0.0, 1.0])];
    for _ in 1..n {
        let (t, q) = *poses.last().unwrap();
        let step = rotate(q, [rng.between(0.1, 2.0), rng.between(-0.3, 0.3), rng.between(-0.3, 0.3)]);
        poses.push(([t[0] + step[0], t[1] + step[1], t[2] + step[2]], unit(&mut rng)));
    }
    let relative = |a: ([f64; 3], [f64; 4]), b: ([f64; 3], [f64; 4])| {
        let d = rotate(conjugate(a.1), [b.0[0] - a.0[0], b.0[1] - a.0[1], b.0[2] - a.0[2]]);
        (d, multiply(conjugate(a.1), b.1))
    };
    let mut text = String::new();
    for k in 0..n - 1 {
        let (a, b) = if k == 33 { (k + 1, k) } else { (k, k + 1) };
        let (d, q) = relative(poses[a], poses[b]);
        writeln!(
            text,
            "EDGE_SE3:QUAT {a} {b} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
            d[0], d[1], d[2], q[0], q[1], q[2], q[3]
        )
        .unwrap();
    }
    let dir = TempDir::new();
    let graph = read_pose_graph_with(dir.file("se3.g2o", &text), &chained()).unwrap();
    assert_eq!((graph.vertices.len(), graph.vertices.dim), (n, 3));
    let orientations = graph.vertices.orientations_xyzw.as_ref().unwrap();
    for (k, (t, q)) in poses.iter().enumerate() {
        let got = graph.vertices.positions[k];
        assert!(got.iter().zip(t).all(|(a, b)| (a - b).abs() < 1e-9), "pose {k}: {got:?} {t:?}");
        let dot: f64 = orientations[k].iter().zip(q).map(|(a, b)| a * b).sum();
        assert!((dot.abs() - 1.0).abs() < 1e-9, "pose {k}: {:?} {q:?}", orientations[k]);
    }
}

/// The six real pose graphs: every edge has a positive semi-definite 3 × 3 information matrix
/// in g2o's order (TORO's reordered; read as written, the TORO matrices are not), and their
/// vertices, odometry guesses, are the chain of their odometry edges (printed to 6 decimals).
#[test]
fn real_graphs_information_and_their_odometry_chain() {
    let Some(dir) = support::real_data_dir() else { return };
    let dir = dir.join("pose_graphs");
    let names = [
        "input_INTEL_g2o.g2o",
        "input_M3500_g2o.g2o",
        "input_MITb_g2o.g2o",
        "CSAIL_P_toro.graph",
        "FR079_P_toro.graph",
        "FRH_P_toro.graph",
    ];
    let positive = |m: &[f64]| {
        let [xx, xy, xt, yy, yt, tt] = [m[0], m[1], m[2], m[3], m[4], m[5]];
        let minor2 = xx * yy - xy * xy;
        let det = xx * (yy * tt - yt * yt) - xy * (xy * tt - yt * xt) + xt * (xy * yt - yy * xt);
        let scale = xx.abs().max(yy.abs()).max(tt.abs());
        xx >= 0.0 && minor2 >= -1e-9 * scale * scale && det >= -1e-9 * scale * scale * scale
    };
    let temp = TempDir::new();
    for name in names {
        let path = dir.join(name);
        let graph = read_pose_graph(&path, &Timing::FromFile).unwrap();
        assert!(graph.edges.iter().all(|e| e.information.len() == 6), "{name}");
        let bad = graph.edges.iter().filter(|e| !positive(&e.information)).count();
        assert_eq!(bad, 0, "{name}: {bad} information matrices not positive semi-definite");
        // The edges alone, chained.
        let text = std::fs::read_to_string(&path).unwrap();
        let edges: String =
            text.lines().filter(|line| line.starts_with("EDGE")).map(|line| format!("{line}\n")).collect();
        let chained = read_pose_graph_with(temp.file(name, &edges), &chained()).unwrap();
        assert_eq!(chained.vertex_ids, graph.vertex_ids, "{name}");
        let worst = graph
            .vertices
            .positions
            .iter()
            .zip(&chained.vertices.positions)
            .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
            .fold(0.0, f64::max);
        eprintln!("{name}: chained odometry within {worst:.2e} m of the vertices");
        assert!(worst < 2e-3, "{name}: {worst}");
    }
}

/// GTSAM's own graphs: `LANDMARK2` (Victoria Park, City Trees) and `BR` (`example.graph`) lines
/// are skipped with their poses read, and every skipped tag (TORO's `EQUIV` too) is counted, for
/// the caller to say so; evo's `.kitti` extension is KITTI.
#[test]
fn gtsam_graphs_read_their_poses_and_say_what_was_skipped() {
    let dir = TempDir::new();
    let text = "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nEDGE2 0 1 1 0 0 1 0 1 1 0 0\n\
                LANDMARK2 1 7 2.5 0.3 1 0 1\nBR 1 7 0.2 2.5 0.01 0.1\nEQUIV 0 1\nEQUIV 1 0\n";
    let path = dir.file("example.graph", text);
    let (table, notes) = loops_io::read_trajectory_chaining(&path, &loops_io::ReadOptions::default()).unwrap();
    assert_eq!(table.len(), 2);
    let warnings = notes.warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].ends_with(
            "example.graph: skipped 1 LANDMARK2 line (first on line 4), 1 BR line (first on line 5), 2 EQUIV lines \
             (first on line 6): only pose vertices and the edges between them are read"
        ),
        "{}",
        warnings[0]
    );
    let graph = read_pose_graph_with(&path, &loops_io::ReadOptions::default()).unwrap();
    assert_eq!(graph.skipped.map(|s| s.tags.len()), Some(3));
    // evo writes KITTI poses as `.kitti`: 12 numbers a line, no times.
    let kitti = dir.file("traj.kitti", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n");
    assert_eq!(loops_io::Format::detect(&kitti), Some(loops_io::Format::Kitti));
    let options = loops_io::ReadOptions::default().timing(Timing::RateHz(10.0));
    let table = loops_io::read_trajectory_with(&kitti, &options).unwrap();
    assert_eq!(table.positions[1], [1.0, 0.0, 0.0]);
}
