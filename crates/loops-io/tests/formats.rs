//! KITTI, EuRoC, libRSF (TUC) and pose-graph readers, the writers, and the real files of these
//! formats in `shared/data`.

use std::path::Path;

use loops_io::{
    EdgeKind, Format, G2oOptions, IoError, PoseTable, ReadOptions, Timing, WriteError, read_euroc, read_kitti,
    read_pose_graph, read_trajectory, read_trajectory_with, read_tuc, read_tum, write_g2o_edges, write_tum,
};

mod support;
use support::{TempDir, real_data_dir};

/// The message after the file's path.
fn after_path(error: &IoError, path: &Path) -> String {
    let message = error.to_string();
    let prefix = path.display().to_string();
    assert!(message.starts_with(&prefix), "{message}");
    message[prefix.len()..].to_owned()
}

fn close(a: &[f64], b: &[f64], tolerance: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(a, b)| (a - b).abs() <= tolerance)
}

/// Quaternions equal up to sign.
fn same_rotation(a: [f64; 4], b: [f64; 4], tolerance: f64) -> bool {
    close(&a, &b, tolerance) || close(&a, &b.map(|v| -v), tolerance)
}

mod kitti {
    use super::*;

    const QUARTER_TURN: &str = "0 -1 0 8 1 0 0 9 0 0 1 10"; // 90° about z, at (8, 9, 10)

    #[test]
    fn thirteen_numbers_carry_the_time() {
        let dir = TempDir::new();
        let path = dir.file("poses.txt", &format!("# comment\n0 1 0 0 5 0 1 0 6 0 0 1 7\n\n0.25 {QUARTER_TURN}\n"));
        let table = read_kitti(&path, &Timing::FromFile).unwrap();
        assert_eq!(table.timestamps_s, [0.0, 0.25]);
        assert_eq!(table.positions, [[5.0, 6.0, 7.0], [8.0, 9.0, 10.0]]);
        assert_eq!(table.source_lines, [2, 4]);
        let q = table.orientations_xyzw.as_ref().unwrap();
        assert_eq!(q[0], [0.0, 0.0, 0.0, 1.0]);
        let half = std::f64::consts::FRAC_1_SQRT_2;
        assert!(same_rotation(q[1], [0.0, 0.0, half, half], 1e-15), "{:?}", q[1]);
        // A rate replaces the time column.
        let table = read_kitti(&path, &Timing::RateHz(4.0)).unwrap();
        assert_eq!(table.timestamps_s, [0.0, 0.25]);
        // By content, from a .txt file.
        assert_eq!(read_trajectory(&path, None).unwrap(), read_kitti(&path, &Timing::FromFile).unwrap());
    }

    #[test]
    fn twelve_numbers_need_a_rate_or_a_times_file() {
        let dir = TempDir::new();
        let path = dir.file("00.txt", &format!("1 0 0 0 0 1 0 0 0 0 1 0\n{QUARTER_TURN}\n{QUARTER_TURN}\n"));
        let error = read_kitti(&path, &Timing::FromFile).unwrap_err();
        assert_eq!(
            after_path(&error, &path),
            " line 1: 12 numbers (a 3×4 pose) and no time: give the poses' times, a rate (rate_hz, --rate-hz) \
             or KITTI's times.txt (times, --times)"
        );
        let table = read_kitti(&path, &Timing::RateHz(10.0)).unwrap();
        assert_eq!(table.timestamps_s, [0.0, 0.1, 0.2]);
        let times = dir.file("times.txt", "1.5e0\n1.6\n# end\n1.75\n");
        let table = read_kitti(&path, &Timing::TimesFile(times.clone())).unwrap();
        assert_eq!(table.timestamps_s, [1.5, 1.6, 1.75]);
        let options = ReadOptions::default().format(Format::Kitti).timing(Timing::TimesFile(times));
        assert_eq!(read_trajectory_with(&path, &options).unwrap().timestamps_s, [1.5, 1.6, 1.75]);

        let short = dir.file("short_times.txt", "0\n1\n");
        let error = read_kitti(&path, &Timing::TimesFile(short.clone())).unwrap_err();
        assert_eq!(after_path(&error, &short), ": 2 timestamps but 3 poses");
        let bad = dir.file("bad_times.txt", "0\n1 2\n3\n");
        let error = read_kitti(&path, &Timing::TimesFile(bad.clone())).unwrap_err();
        assert_eq!(
            after_path(&error, &bad),
            " line 2: expected 1 column (one time in seconds a line), found 2: column 2 (\"2\") is past the end of the \
             record, at column 1 (two records run together on one line?)"
        );
        for rate in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let error = read_kitti(&path, &Timing::RateHz(rate)).unwrap_err();
            assert!(
                matches!(
                    error,
                    IoError::Trajectory { error: loops_core::Error::InvalidParameter { name: "rate_hz", .. }, .. }
                ),
                "{error:?}"
            );
        }
    }

    #[test]
    fn too_few_columns_and_ragged_lines() {
        let dir = TempDir::new();
        let path = dir.file("few.txt", "1 0 0 0 0 1 0 0 0 0 1\n");
        let error = read_kitti(&path, &Timing::RateHz(1.0)).unwrap_err();
        assert_eq!(
            after_path(&error, &path),
            " line 1: expected 12 or 13 columns (a row-major 3×4 pose [R|t], after a time when 13), found 11: the line \
             ends after column 11 (\"1\")"
        );
        let path = dir.file("ragged.txt", &format!("0 {QUARTER_TURN}\n{QUARTER_TURN}\n"));
        let error = read_kitti(&path, &Timing::FromFile).unwrap_err();
        assert_eq!(
            after_path(&error, &path),
            " line 2: expected 13 columns as on line 1, found 12: the line ends after column 12 (\"10\")"
        );
        let path = dir.file("word.txt", "0 1 0 0 x 0 1 0 0 0 0 1 0\n");
        let error = read_kitti(&path, &Timing::FromFile).unwrap_err();
        assert_eq!(after_path(&error, &path), r#" line 1: column 5 ("x") is not a number"#);
        let path = dir.file("empty.txt", "# nothing\n");
        assert!(matches!(read_kitti(&path, &Timing::RateHz(1.0)).unwrap_err(), IoError::Empty { .. }));
    }
}

mod euroc {
    use super::*;

    const HEADER: &str =
        "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n";

    #[test]
    fn nanoseconds_are_exact_and_quaternions_reordered() {
        let dir = TempDir::new();
        let text = format!(
            "{HEADER}1403715524907143168,0.515356,1.996773,0.971104,0.161996,0.789985,-0.205376,0.554528,-0.002276\n\
             1403715524912143104, 0.5, 2, 1, 1, 0, 0, 0, 0.1\n"
        );
        let path = dir.file("data.csv", &text);
        let table = read_euroc(&path).unwrap();
        assert_eq!(table.timestamps_ns, Some(vec![1_403_715_524_907_143_168, 1_403_715_524_912_143_104]));
        assert_eq!(table.timestamps_s[0], 1_403_715_524.0 + 0.907_143_168);
        assert_eq!(table.positions[0], [0.515356, 1.996773, 0.971104]);
        assert_eq!(table.orientations_xyzw.as_ref().unwrap()[0], [0.789985, -0.205376, 0.554528, 0.161996]);
        assert_eq!(table.source_lines, [2, 3]);
        // By content, from a .csv file.
        assert_eq!(read_trajectory(&path, None).unwrap(), table);
    }

    #[test]
    fn bad_lines() {
        let dir = TempDir::new();
        let path = dir.file("few.csv", &format!("{HEADER}1403715524907143168,0.5,2,1,1,0,0\n"));
        let error = read_euroc(&path).unwrap_err();
        assert_eq!(
            after_path(&error, &path),
            r#" line 2: expected at least 8 columns (timestamp [ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z), found 7: the line ends after column 7 ("0")"#
        );
        let path = dir.file("seconds.csv", "1403715524.9,0.5,2,1,1,0,0,0\n");
        let error = read_euroc(&path).unwrap_err();
        assert_eq!(
            after_path(&error, &path),
            r#" line 1: column 1 ("1403715524.9") is not an integer timestamp in nanoseconds"#
        );
        let path = dir.file("nan.csv", "1,0.5,nan,1,1,0,0,0\n");
        assert_eq!(after_path(&read_euroc(&path).unwrap_err(), &path), r#" line 1: column 3 ("nan") is not finite"#);
    }
}

mod tuc {
    use super::*;

    #[test]
    fn point2_with_and_without_angles() {
        let dir = TempDir::new();
        let text = "point2 0 1 2 0 0 0 0\nangle 0 0.5 0\nodom2 0 1 1 1 0 0 0\npoint2 0.2 3 4 0 0 0 0\nangle 0.2 -1 0\n";
        let path = dir.file("GT.txt", text);
        let table = read_tuc(&path).unwrap();
        assert_eq!((table.dim, table.source_lines.clone()), (2, vec![1, 4]));
        assert_eq!(table.positions, [[1.0, 2.0, 0.0], [3.0, 4.0, 0.0]]);
        let q = table.orientations_xyzw.as_ref().unwrap();
        assert!(close(&q[1], &[0.0, 0.0, (-0.5f64).sin(), (-0.5f64).cos()], 1e-15));
        assert_eq!(read_trajectory(&path, None).unwrap(), table, "told apart from TUM by its first word");
        let path = dir.file("no_angles.txt", "point2 0 1 2\npoint2 1 3 4\nangle 0 0.5\n");
        assert_eq!(read_tuc(&path).unwrap().orientations_xyzw, None, "a point without its angle: no orientations");
    }

    #[test]
    fn point3_is_local_east_north_up() {
        let dir = TempDir::new();
        // Three fixes near Chemnitz: the second 100 m up the normal of the WGS84 ellipsoid
        // (the gradient of x²/a² + y²/a² + z²/b²), the third 50 m from the first.
        let origin = [3_934_098.670_252_7, 902_425.342_798_05, 4_922_416.429_090_7];
        let (a2, b2) = (6_378_137.0f64.powi(2), 6_356_752.314_245_179f64.powi(2));
        let gradient = [origin[0] / a2, origin[1] / a2, origin[2] / b2];
        let length = gradient.iter().map(|v| v * v).sum::<f64>().sqrt();
        let up = gradient.map(|v| v / length);
        let text = format!(
            "point3 0 {} {} {} 0 0 0 0 0 0 0 0 0\npoint3 1 {} {} {}\npoint3 2 {} {} {} 0 0 0 0 0 0 0 0 0\n",
            origin[0],
            origin[1],
            origin[2],
            origin[0] + 100.0 * up[0],
            origin[1] + 100.0 * up[1],
            origin[2] + 100.0 * up[2],
            origin[0] + 30.0,
            origin[1] - 40.0,
            origin[2],
        );
        let path = dir.file("Chemnitz_GT.txt", &text);
        let table = read_tuc(&path).unwrap();
        assert_eq!((table.dim, table.positions[0]), (3, [0.0; 3]));
        let [x, y, z] = table.positions[1];
        assert!(x.abs() < 1e-4 && y.abs() < 1e-4 && (z - 100.0).abs() < 1e-6, "{:?}", table.positions[1]);
        let norm = |p: [f64; 3]| p.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((norm(table.positions[2]) - 50.0).abs() < 1e-9, "distances are kept");
    }

    #[test]
    fn bad_lines() {
        let dir = TempDir::new();
        let path = dir.file("few.txt", "point3 0 1 2\n");
        assert_eq!(
            after_path(&read_tuc(&path).unwrap_err(), &path),
            " line 1: expected 5 or 14 columns (point3 t X Y Z, then the covariance's 9 entries or none), found 4: the \
             line ends after column 4 (\"2\")"
        );
        let path = dir.file("mixed.txt", "point2 0 1 2\npoint3 1 1 2 3\n");
        assert_eq!(
            after_path(&read_tuc(&path).unwrap_err(), &path),
            " line 2: a point3 line in a file of point2 lines (line 1)"
        );
        // Found by the fuzzer: a first fix at the centre of the Earth made NaNs.
        let path = dir.file("centre.txt", "point3 0\t0\t-0\t-0\npoint3 1 1 2 3\n");
        let table = read_tuc(&path).unwrap();
        assert!(table.positions.iter().flatten().all(|v| v.is_finite()), "{:?}", table.positions);
        let path = dir.file("overflow.txt", "point3 0 1e308 0 0\npoint3 1 -1e308 0 0\n");
        assert_eq!(
            after_path(&read_tuc(&path).unwrap_err(), &path),
            " line 2: the ECEF position is too far from the first one to subtract it (overflow)"
        );
        let path = dir.file("input.txt", "odom2 0 0 0 0 1 1 1\nloop 1 2 0.5\n");
        assert!(matches!(read_tuc(&path).unwrap_err(), IoError::Empty { .. }));
    }
}

mod graph {
    use super::*;

    #[test]
    fn g2o_2d_vertices_edges_and_loop_closures() {
        let dir = TempDir::new();
        let text = "VERTEX_SE2 2 1 1 1.5\nVERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0.5\nFIX 0\n\
                    EDGE_SE2 0 1 1 0 0.5 1 0 0 1 0 1\nEDGE_SE2 1 2 0 1 1 1 0 0 1 0 1\n\
                    VERTEX_XY 7 3 4\nEDGE_SE2_XY 2 7 1 1 1 0 1\nEDGE_SE2 2 0 -1 1 -1.5\n";
        let path = dir.file("tiny.g2o", text);
        let graph = read_pose_graph(&path, &Timing::FromFile).unwrap();
        assert_eq!(graph.vertex_ids, [0, 1, 2]);
        assert_eq!(graph.vertices.timestamps_s, [0.0, 1.0, 2.0], "the id in seconds");
        assert_eq!(graph.vertices.source_lines, [2, 3, 1]);
        assert_eq!(graph.vertices.positions[2], [1.0, 1.0, 0.0]);
        assert_eq!(graph.vertices.dim, 2);
        let q = graph.vertices.orientations_xyzw.as_ref().unwrap()[1];
        assert!(close(&q, &[0.0, 0.0, 0.25f64.sin(), 0.25f64.cos()], 1e-15));
        let edges: Vec<(u64, u64, usize)> = graph.edges.iter().map(|e| (e.from, e.to, e.line)).collect();
        assert_eq!(edges, [(0, 1, 5), (1, 2, 6), (2, 0, 9)]);
        assert_eq!(graph.loop_closures().count(), 1);
        assert_eq!(graph.vertex_index(2), Some(2));
        assert_eq!(graph.vertex_index(7), None, "landmarks are not pose vertices");
        let traj = read_trajectory(&path, None).unwrap();
        assert_eq!(traj, graph.vertices);
        let graph = read_pose_graph(&path, &Timing::RateHz(10.0)).unwrap();
        assert_eq!(graph.vertices.timestamps_s, [0.0, 0.1, 0.2]);
    }

    #[test]
    fn toro_and_3d() {
        let dir = TempDir::new();
        let path = dir.file("toro.graph", "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nEDGE2 0 1 1 0 0 1 0 1 0 0 1\n");
        let graph = read_pose_graph(&path, &Timing::FromFile).unwrap();
        assert_eq!((graph.vertex_ids.len(), graph.edges.len()), (2, 1));
        let text = "VERTEX_SE3:QUAT 0 1 2 3 0 0 0 1\nVERTEX_SE3:QUAT 1 4 5 6 0 0 0.6 0.8\n\
                    EDGE_SE3:QUAT 0 1 3 3 3 0 0 0.6 0.8 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n";
        let path = dir.file("3d.g2o", text);
        let graph = read_pose_graph(&path, &Timing::FromFile).unwrap();
        assert_eq!(graph.vertices.dim, 3);
        assert_eq!(graph.vertices.orientations_xyzw.as_ref().unwrap()[1], [0.0, 0.0, 0.6, 0.8]);
        let path = dir.file("toro3.graph", "VERTEX3 0 1 2 3 0 0 1.5\n");
        let graph = read_pose_graph(&path, &Timing::FromFile).unwrap();
        let q = graph.vertices.orientations_xyzw.as_ref().unwrap()[0];
        assert!(close(&q, &[0.0, 0.0, 0.75f64.sin(), 0.75f64.cos()], 1e-15));
    }

    #[test]
    fn bad_graphs() {
        let dir = TempDir::new();
        let cases = [
            (
                "VERTEX_SE2 0 0 0\n",
                r#" line 1: expected 5 columns (VERTEX_SE2 id x y theta), found 4: the line ends after column 4 ("0")"#,
            ),
            (
                "VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 1\n",
                " line 2: expected 6 or 12 columns (EDGE_SE2 i j dx dy dtheta, then the information matrix's 6 \
                 entries or none), found 3: the line ends after column 3 (\"1\")",
            ),
            ("VERTEX_SE2 -1 0 0 0\n", r#" line 1: column 2 ("-1") is not a vertex id (a non-negative integer)"#),
            ("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 0 1 0 0\n", " line 2: vertex 0 is given twice (first on line 1)"),
            (
                "VERTEX_SE2 0 0 0 0\nEDGE_SE2 0 5 1 0 0\n",
                " line 2: the edge joins vertex 5, which the file does not have",
            ),
            (
                "VERTEX_SE2 0 0 0 0\nVERTEX_SE3:QUAT 1 0 0 0 0 0 0 1\n",
                " line 2: a 3-D pose in a file of 2-D poses (line 1): one graph has one dimension",
            ),
            ("VERTEX_SE2 0 0 nan 0\n", r#" line 1: column 4 ("nan") is not finite"#),
        ];
        for (text, expected) in cases {
            let path = dir.file("bad.g2o", text);
            let error = read_pose_graph(&path, &Timing::FromFile).unwrap_err();
            assert_eq!(after_path(&error, &path), expected, "{text:?}");
        }
        let path = dir.file("edges_only.g2o", "# no vertices\nFIX 0\n");
        assert!(matches!(read_pose_graph(&path, &Timing::FromFile).unwrap_err(), IoError::Empty { .. }));
    }
}

mod writers {
    use super::*;

    fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        names
    }

    #[test]
    fn tum_round_trip_and_no_overwrite() {
        let dir = TempDir::new();
        let source =
            dir.file("in.tum", "0.1 1e-3 -2.5 3 0 0 0 1\n0.30000000000000004 1 2 3 0.1 0.2 0.3 0.9273618495495703\n");
        let table = read_tum(&source).unwrap();
        let out = dir.0.join("out.tum");
        write_tum(&out, &table, false).unwrap();
        let back = read_tum(&out).unwrap();
        assert_eq!(
            (back.timestamps_s.clone(), back.positions.clone()),
            (table.timestamps_s.clone(), table.positions.clone())
        );
        assert_eq!(back.orientations_xyzw, table.orientations_xyzw);
        assert_eq!(back.source_lines, [2, 3], "after the header");

        let before = std::fs::read(&out).unwrap();
        let mut other = table.clone();
        other.positions[0][0] = 99.0;
        let error = write_tum(&out, &other, false).unwrap_err();
        assert!(matches!(&error, WriteError::Exists { path } if path == &out), "{error:?}");
        assert_eq!(std::fs::read(&out).unwrap(), before, "left as it was");
        write_tum(&out, &other, true).unwrap();
        assert_eq!(read_tum(&out).unwrap().positions[0][0], 99.0);
        assert_eq!(listing(&dir.0), ["in.tum", "out.tum"], "no temporary file left");

        let error = write_tum(dir.0.join("missing/out.tum"), &table, false).unwrap_err();
        assert!(matches!(error, WriteError::Write { .. }), "{error:?}");
        assert_eq!(listing(&dir.0), ["in.tum", "out.tum"]);
    }

    #[test]
    fn tum_keeps_nanoseconds_and_fills_in_what_is_missing() {
        let dir = TempDir::new();
        let euroc = dir.file("e.csv", "1403715524907143168,1,2,3,1,0,0,0\n1403715524912143104,1,2,3,1,0,0,0\n");
        let table = read_euroc(&euroc).unwrap();
        let out = dir.0.join("e.tum");
        write_tum(&out, &table, false).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        assert!(text.contains("\n1403715524.907143168 1 2 3 0 0 0 1\n"), "{text}");
        let csv = dir.file("p.csv", "t,x,y\n0,1,2\n1,3,4\n");
        let table = loops_io::read_csv(&csv).unwrap();
        write_tum(dir.0.join("p.tum"), &table, false).unwrap();
        let text = std::fs::read_to_string(dir.0.join("p.tum")).unwrap();
        assert_eq!(text, "# timestamp tx ty tz qx qy qz qw\n0 1 2 0 0 0 0 1\n1 3 4 0 0 0 0 1\n");
    }

    /// The numbers after the tag and ids of each line starting with `tag`.
    fn lines_of(text: &str, tag: &str) -> Vec<(usize, usize, Vec<f64>)> {
        text.lines()
            .filter(|line| line.starts_with(&format!("{tag} ")))
            .map(|line| {
                let fields: Vec<&str> = line.split(' ').collect();
                (
                    fields[1].parse().unwrap(),
                    fields[2].parse().unwrap(),
                    fields[3..].iter().map(|f| f.parse().unwrap()).collect(),
                )
            })
            .collect()
    }

    /// Rotation matrix of a unit quaternion, to check the writer with independent algebra.
    fn matrix(q: [f64; 4]) -> [[f64; 3]; 3] {
        let [x, y, z, w] = q;
        [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ]
    }

    #[test]
    fn g2o_se3_edges_are_relative_poses() {
        let dir = TempDir::new();
        let text =
            "0 1 2 3 0.1 0.2 0.3 0.9273618495495703\n1 -4 0.5 2 -0.3 0.1 0 0.9486832980505138\n2 0 0 0 0 0 0 1\n";
        let table = read_tum(dir.file("in.tum", text)).unwrap();
        let out = dir.0.join("c.g2o");
        write_g2o_edges(&out, &table, &[(0, 1), (2, 0)], &G2oOptions::default()).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        let edges = lines_of(&text, "EDGE_SE3:QUAT");
        assert_eq!(edges.len(), 2);
        for (i, j, values) in edges {
            assert_eq!(values.len(), 7 + 21);
            let (pi, pj) = (table.positions[i], table.positions[j]);
            let qi = table.orientations_xyzw.as_ref().unwrap()[i];
            let ri = matrix(qi);
            // t = R_iᵀ (p_j − p_i)
            let d = [pj[0] - pi[0], pj[1] - pi[1], pj[2] - pi[2]];
            let t: Vec<f64> = (0..3).map(|c| (0..3).map(|r| ri[r][c] * d[r]).sum()).collect();
            assert!(close(&values[..3], &t, 1e-12), "{values:?} {t:?}");
            // R_i R_rel = R_j
            let r_rel = matrix([values[3], values[4], values[5], values[6]]);
            let rj = matrix(table.orientations_xyzw.as_ref().unwrap()[j]);
            for r in 0..3 {
                for c in 0..3 {
                    let product: f64 = (0..3).map(|k| ri[r][k] * r_rel[k][c]).sum();
                    assert!((product - rj[r][c]).abs() < 1e-12);
                }
            }
        }
        assert!(lines_of(&text, "VERTEX_SE3:QUAT").is_empty(), "vertices only on request");
        let error = write_g2o_edges(&out, &table, &[(0, 1)], &G2oOptions::default()).unwrap_err();
        assert!(matches!(error, IoError::Write(WriteError::Exists { .. })), "{error:?}");
        let error = write_g2o_edges(&out, &table, &[(0, 3)], &G2oOptions::default().overwrite(true)).unwrap_err();
        assert!(error.to_string().ends_with("pose index 3 is out of range: the trajectory has 3 poses"), "{error}");
    }

    #[test]
    fn g2o_se2_edges_and_vertices_load_back() {
        let dir = TempDir::new();
        let text = "VERTEX_SE2 0 0 0 3\nVERTEX_SE2 1 1 0 -3\nVERTEX_SE2 2 5 5 0.5\n";
        let graph = read_pose_graph(dir.file("in.g2o", text), &Timing::FromFile).unwrap();
        let out = dir.0.join("c.g2o");
        let options = G2oOptions::default().with_vertices(true);
        write_g2o_edges(&out, &graph.vertices, &[(0, 1), (2, 0)], &options).unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        let edges = lines_of(&text, "EDGE_SE2");
        let (dx, dy, dtheta) = (edges[0].2[0], edges[0].2[1], edges[0].2[2]);
        // From θ = 3 to θ = −3: the short way round, 2π − 6.
        assert!((dtheta - (std::f64::consts::TAU - 6.0)).abs() < 1e-12, "{dtheta}");
        assert!(close(&[dx, dy], &[3.0f64.cos(), -(3.0f64.sin())], 1e-12), "{dx} {dy}");
        assert_eq!(edges[0].2.len(), 3 + 6);
        let back = read_pose_graph(&out, &Timing::FromFile).unwrap();
        assert_eq!(back.vertex_ids, [0, 1, 2]);
        assert!(close(&back.vertices.positions.concat(), &graph.vertices.positions.concat(), 0.0));
        assert_eq!(back.loop_closures().count(), 1);
        // A 3-D table written as SE(2): x, y and the heading.
        let table = read_tum(dir.file("t.tum", "0 0 0 9 0 0 0 1\n1 2 0 7 0 0 1 0\n")).unwrap();
        let out = dir.0.join("se2.g2o");
        write_g2o_edges(&out, &table, &[(0, 1)], &G2oOptions::default().kind(EdgeKind::Se2)).unwrap();
        let edges = lines_of(&std::fs::read_to_string(&out).unwrap(), "EDGE_SE2");
        assert!(close(&edges[0].2[..3], &[2.0, 0.0, std::f64::consts::PI], 1e-12), "{:?}", edges[0].2);
    }
}

/// The real files in `shared/data`; skipped when the folder is absent.
mod real_data {
    use super::*;

    fn data_lines(path: &Path, starting: &str) -> usize {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .filter(|l| !l.trim().is_empty() && l.starts_with(starting))
            .count()
    }

    fn assert_unit(table: &PoseTable, tolerance: f64) {
        for q in table.orientations_xyzw.as_ref().unwrap() {
            let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!((norm - 1.0).abs() <= tolerance, "{q:?}");
        }
    }

    #[test]
    fn kitti_odometry_sequences() {
        let Some(dir) = real_data_dir() else { return };
        for sequence in 0..=10 {
            let path = dir.join(format!("kitti_odometry/{sequence:02}.txt"));
            let table = read_trajectory(&path, None).unwrap();
            assert_eq!(table.len(), data_lines(&path, ""), "{sequence}");
            assert_eq!(table.timestamps_s[0], 0.0);
            assert_unit(&table, 1e-12);
            let traj = table.to_trajectory_plane([0, 2]).unwrap_or_else(|e| panic!("{e}"));
            assert!(traj.span_s() > 20.0);
        }
        // 00: the first pose is the identity, the second about 0.86 m ahead (z).
        let table = read_kitti(dir.join("kitti_odometry/00.txt"), &Timing::FromFile).unwrap();
        assert_eq!(table.positions[1], [-0.04690294, -0.02839928, 0.8586941]);
        assert!(same_rotation(table.orientations_xyzw.as_ref().unwrap()[0], [0.0, 0.0, 0.0, 1.0], 1e-9));
    }

    #[test]
    fn mulran_has_no_timestamps_and_takes_ten_hertz() {
        let Some(dir) = real_data_dir() else { return };
        for (name, poses) in [
            ("kaist01_localization_poses01_seq02asmap.txt", 8226),
            ("kaist02_localization_poses02_seq02asmap.txt", 8941),
        ] {
            let path = dir.join("mulran_kaist").join(name);
            let error = read_trajectory(&path, None).unwrap_err();
            assert!(
                error.to_string().ends_with(
                    "line 1: 12 numbers (a 3×4 pose) and no time: give the poses' times, a rate (rate_hz, --rate-hz) \
                     or KITTI's times.txt (times, --times)"
                ),
                "{error}"
            );
            let options = ReadOptions::default().timing(Timing::RateHz(10.0));
            let table = read_trajectory_with(&path, &options).unwrap();
            assert_eq!(table.len(), poses);
            assert!(table.timestamps_s.iter().enumerate().all(|(i, &t)| t == i as f64 / 10.0));
            assert_unit(&table, 1e-12);
            // Stationary at the start: identical poses, but a trajectory all the same.
            assert_eq!(table.positions[0], table.positions[1]);
            let traj = table.to_trajectory().unwrap();
            assert!((traj.span_s() - (poses - 1) as f64 / 10.0).abs() < 1e-9);
        }
    }

    #[test]
    fn euroc_v102() {
        let Some(dir) = real_data_dir() else { return };
        let path = dir.join("euroc/evo_V102_groundtruth.csv");
        let table = read_trajectory(&path, None).unwrap();
        assert_eq!(table, read_euroc(&path).unwrap());
        assert_eq!(table.len(), 16702);
        assert_eq!(table.timestamps_ns.as_ref().unwrap()[0], 1_403_715_524_907_143_168);
        assert_eq!(table.positions[0], [0.515356, 1.996773, 0.971104]);
        assert_eq!(table.orientations_xyzw.as_ref().unwrap()[0], [0.789985, -0.205376, 0.554528, 0.161996]);
        assert_unit(&table, loops_core::FILE_QUATERNION_TOLERANCE); // some are 2e-4 off
        let traj = table.to_trajectory_for(&"se3(rotation_weight_m_per_rad=1)".parse().unwrap(), None).unwrap();
        assert!((traj.span_s() - 83.5).abs() < 1.0, "{}", traj.span_s());
    }

    #[test]
    fn tuc_slam_point2_with_headings() {
        let Some(dir) = real_data_dir() else { return };
        for (name, poses) in [("Corridor_GT.txt", 11346), ("Lecture_Hall_GT.txt", 6919)] {
            let path = dir.join("tuc/SLAM").join(name);
            let table = read_trajectory(&path, None).unwrap();
            assert_eq!(table, read_tuc(&path).unwrap());
            assert_eq!((table.len(), table.dim), (poses, 2), "{name}");
            assert!(table.orientations_xyzw.is_some(), "{name}: every point2 has its angle");
            let traj = table.to_trajectory_for(&"se2(rotation_weight_m_per_rad=1)".parse().unwrap(), None).unwrap();
            assert_eq!(traj.len(), poses);
        }
        // The inputs hold odometry and loop detections, no positions.
        let error = read_tuc(dir.join("tuc/SLAM/Corridor_Input.txt")).unwrap_err();
        assert!(matches!(error, IoError::Empty { .. }), "{error:?}");
    }

    /// ECEF points of a `point3` file, read independently of the crate.
    fn ecef(path: &Path) -> Vec<[f64; 3]> {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .filter(|line| line.starts_with("point3"))
            .map(|line| {
                let f: Vec<f64> = line.split_whitespace().skip(2).take(3).map(|v| v.parse().unwrap()).collect();
                [f[0], f[1], f[2]]
            })
            .collect()
    }

    #[test]
    fn tuc_point3_ecef_becomes_local_east_north_up() {
        let Some(dir) = real_data_dir() else { return };
        let mut paths = vec![dir.join("tuc/Chemnitz_City/Chemnitz_GT.txt")];
        for entry in std::fs::read_dir(dir.join("tuc/smartLoc")).unwrap() {
            let path = entry.unwrap().path();
            if path.to_string_lossy().ends_with("_GT.txt") {
                paths.push(path);
            }
        }
        assert_eq!(paths.len(), 5);
        for path in paths {
            let table = read_trajectory(&path, None).unwrap();
            let raw = ecef(&path);
            assert_eq!((table.len(), table.dim), (raw.len(), 3), "{}", path.display());
            assert_eq!(table.positions[0], [0.0; 3]);
            for (local, point) in table.positions.iter().zip(&raw).step_by(97) {
                let d: f64 = (0..3).map(|k| (point[k] - raw[0][k]).powi(2)).sum::<f64>().sqrt();
                let l: f64 = local.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!((d - l).abs() < 1e-6, "{}: distances kept", path.display());
            }
            // City drives: flat, so z (up) stays small next to the horizontal extent.
            let extent = |axis: usize| {
                let values = table.positions.iter().map(|p| p[axis]);
                values.clone().fold(f64::MIN, f64::max) - values.fold(f64::MAX, f64::min)
            };
            assert!(
                extent(2) < 0.2 * extent(0).max(extent(1)),
                "{}: {} {} {}",
                path.display(),
                extent(0),
                extent(1),
                extent(2)
            );
            assert!(table.to_trajectory().is_ok());
        }
        let chemnitz = read_tuc(dir.join("tuc/Chemnitz_City/Chemnitz_GT.txt")).unwrap();
        assert_eq!(chemnitz.len(), 8571);
    }

    /// Edges with |i − j| > 1, counted from the text independently of the crate.
    fn loop_edges_in(path: &Path) -> usize {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .filter(|line| line.starts_with("EDGE"))
            .filter(|line| {
                let ids: Vec<i64> = line.split_whitespace().skip(1).take(2).map(|v| v.parse().unwrap()).collect();
                (ids[0] - ids[1]).abs() > 1
            })
            .count()
    }

    #[test]
    fn pose_graphs_and_their_loop_closures() {
        let Some(dir) = real_data_dir() else { return };
        for (name, vertices, edges, loops) in [
            ("input_INTEL_g2o.g2o", 1228, 1483, Some(256)),
            ("input_M3500_g2o.g2o", 3500, 5453, Some(1954)),
            ("input_MITb_g2o.g2o", 808, 827, None),
            ("CSAIL_P_toro.graph", 1045, 1172, None),
            ("FR079_P_toro.graph", 989, 1217, None),
            ("FRH_P_toro.graph", 1316, 2820, None),
        ] {
            let path = dir.join("pose_graphs").join(name);
            let graph = read_pose_graph(&path, &Timing::FromFile).unwrap();
            assert_eq!((graph.vertex_ids.len(), graph.edges.len()), (vertices, edges), "{name}");
            assert_eq!(graph.vertex_ids, (0..vertices as u64).collect::<Vec<_>>(), "{name}");
            let closures = graph.loop_closures().count();
            assert_eq!(closures, loop_edges_in(&path), "{name}");
            if let Some(loops) = loops {
                assert_eq!(closures, loops, "{name}");
            }
            assert_eq!(read_trajectory(&path, None).unwrap(), graph.vertices, "{name}");
            let traj = graph.vertices.to_trajectory_for(&"se2(rotation_weight_m_per_rad=1)".parse().unwrap(), None);
            assert_eq!(traj.unwrap().len(), vertices, "{name}");
        }
    }

    #[test]
    fn candidate_edges_from_kitti_ground_truth() {
        let Some(dir) = real_data_dir() else { return };
        let table = read_kitti(dir.join("kitti_odometry/00.txt"), &Timing::FromFile).unwrap();
        let out = TempDir::new();
        let path = out.0.join("candidates.g2o");
        let pairs = [(0, 4450), (100, 2500), (1500, 3400)];
        write_g2o_edges(&path, &table, &pairs, &G2oOptions::default()).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        for (line, (i, j)) in text.lines().zip(pairs) {
            let values: Vec<f64> = line.split(' ').skip(3).take(3).map(|v| v.parse().unwrap()).collect();
            let (a, b) = (table.positions[i], table.positions[j]);
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            let t = values.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!((d - t).abs() < 1e-9, "{line}: a rotation keeps the distance {d}");
        }
    }
}
