//! Readers on good, bad and random files, and on the real trajectories in `shared/data`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use loops_io::{Format, IoError, PoseTable, read_csv, read_trajectory, read_tum};

mod support;
use support::{KITTI_READ_AS_TUM, real_data_dir};

/// A file in the temp folder, removed when dropped. Names are unique per process and file.
struct TempFile(PathBuf);

impl TempFile {
    fn new(name: &str, contents: impl AsRef<[u8]>) -> Self {
        static COUNT: AtomicUsize = AtomicUsize::new(0);
        let count = COUNT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("loops-io-test-{}-{count}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp folder");
        let path = dir.join(name);
        std::fs::write(&path, contents).expect("temp file");
        Self(path)
    }

    fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if let Some(dir) = self.0.parent() {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// The error's message, checked to start with the file name (every message does).
fn message(error: &IoError, file: &TempFile) -> String {
    let message = error.to_string();
    assert!(message.starts_with(&file.path().display().to_string()), "{message}");
    assert_eq!(error.path(), file.path());
    message
}

/// The message after the path: `line 3: ...` or `: ...`.
fn after_path(error: &IoError, file: &TempFile) -> String {
    message(error, file)[file.path().display().to_string().len()..].to_owned()
}

mod tum {
    use super::*;

    #[test]
    fn comments_blanks_tabs_commas_and_crlf() {
        let text = "# ground truth trajectory\r\n\
                    # timestamp tx ty tz qx qy qz qw\r\n\
                    \r\n\
                    1305031098.6659 1.3563 0.6305 1.6380 0.6132 0.5962 -0.3311 -0.3986\r\n\
                    1305031098.6758\t1.3543\t0.6306\t1.6360\t0.6129\t0.5966\t-0.3316\t-0.3980\r\n\
                    \t  # a comment between poses\r\n\
                    1305031098.6858, 1.3520, 0.6318, 1.6353, 0.6129, 0.5966, -0.3316, -0.3980\r\n\
                    1305031098.6958   1e0 -0 +2.5 0 0 0 1";
        let file = TempFile::new("fr1.txt", text);
        let table = read_tum(file.path()).unwrap();
        assert_eq!(table.path, file.path());
        assert_eq!(table.dim, 3);
        assert_eq!(table.source_lines, [4, 5, 7, 8]);
        assert_eq!(table.timestamps_s, [1305031098.6659, 1305031098.6758, 1305031098.6858, 1305031098.6958]);
        assert_eq!(table.positions[0], [1.3563, 0.6305, 1.6380]);
        assert_eq!(table.positions[3], [1.0, 0.0, 2.5]);
        let orientations = table.orientations_xyzw.as_ref().unwrap();
        assert_eq!(orientations.len(), 4);
        assert_eq!(orientations[1], [0.6129, 0.5966, -0.3316, -0.3980]);
        let traj = table.to_trajectory().unwrap();
        assert_eq!((traj.len(), traj.dim()), (4, 3));
    }

    #[test]
    fn a_header_without_hash_is_skipped() {
        let file = TempFile::new("h.tum", "timestamp tx ty tz qx qy qz qw\n0 1 2 3 0 0 0 1\n1 1 2 3 0 0 0 1\n");
        let table = read_tum(file.path()).unwrap();
        assert_eq!(table.source_lines, [2, 3]);
    }

    #[test]
    fn quaternions_are_kept_as_read() {
        let file = TempFile::new("q.tum", "0 0 0 0 1 1 1 1\n1 0 0 0 0 0 0 2\n");
        let table = read_tum(file.path()).unwrap();
        assert_eq!(table.orientations_xyzw, Some(vec![[1.0; 4], [0.0, 0.0, 0.0, 2.0]]));
    }

    #[test]
    fn too_few_columns() {
        let file = TempFile::new("few.tum", "# c\n0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0\n");
        let error = read_tum(file.path()).unwrap_err();
        assert!(matches!(error, IoError::Parse { line: 3, .. }), "{error:?}");
        assert_eq!(
            after_path(&error, &file),
            r#" line 3: expected 8 columns (timestamp tx ty tz qx qy qz qw), found 7: the line ends after column 7 ("0")"#
        );
    }

    #[test]
    fn too_many_columns() {
        let file = TempFile::new("many.tum", "0 0 0 0 0 0 0 1 7\n");
        let error = read_tum(file.path()).unwrap_err();
        assert_eq!(
            after_path(&error, &file),
            " line 1: expected 8 columns (timestamp tx ty tz qx qy qz qw), found 9: column 9 (\"7\") is past the end \
             of the record, at column 8 (two records run together on one line?)"
        );
    }

    #[test]
    fn a_non_number() {
        let file = TempFile::new("abc.tum", "0 0 0 0 0 0 0 1\n\n1 0 abc 0 0 0 0 1\n");
        let error = read_tum(file.path()).unwrap_err();
        assert_eq!(after_path(&error, &file), r#" line 3: column 3 ("abc") is not a number"#);
        assert_eq!(error.line(), Some(3));
    }

    #[test]
    fn nan_and_inf() {
        let file = TempFile::new("nan.tum", "0 0 0 0 0 0 0 1\n1 0 0 NaN 0 0 0 1\n");
        let error = read_tum(file.path()).unwrap_err();
        assert_eq!(after_path(&error, &file), r#" line 2: column 4 ("NaN") is not finite"#);
        let file = TempFile::new("inf.tum", "inf 0 0 0 0 0 0 1\n");
        let error = read_tum(file.path()).unwrap_err();
        assert_eq!(after_path(&error, &file), r#" line 1: column 1 ("inf") is not finite"#);
    }

    #[test]
    fn duplicate_timestamp_is_mapped_to_its_line() {
        let text = "# t x y z qx qy qz qw\n5.0 0 0 0 0 0 0 1\n5.2 1 0 0 0 0 0 1\n# pause\n5.2 2 0 0 0 0 0 1\n";
        let file = TempFile::new("dup.tum", text);
        let table = read_tum(file.path()).unwrap();
        let error = table.to_trajectory().unwrap_err();
        assert_eq!(
            after_path(&error, &file),
            " line 5: timestamps must strictly increase: 5.2 s is not after 5.2 s (line 3)\
             ; drop_duplicate_stamps=True (--drop-duplicate-stamps) keeps the first pose of each stamp"
        );
        match error {
            IoError::Trajectory { line, previous_line, error, .. } => {
                assert_eq!((line, previous_line), (Some(5), Some(3)));
                assert!(matches!(error, loops_core::Error::TimestampsNotIncreasing { index: 2, .. }));
            }
            other => panic!("expected a trajectory error, got {other:?}"),
        }
    }

    #[test]
    fn decreasing_timestamp_is_mapped_to_its_line() {
        let file = TempFile::new("drive.tum", "5.0 0 0 0 0 0 0 1\n5.2 0 0 0 0 0 0 1\n5.1 0 0 0 0 0 0 1\n");
        let error = read_tum(file.path()).unwrap().to_trajectory_plane([0, 2]).unwrap_err();
        assert_eq!(
            after_path(&error, &file),
            " line 3: timestamps must strictly increase: 5.1 s is not after 5.2 s (line 2)"
        );
    }

    #[test]
    fn one_pose_is_too_few_for_a_trajectory() {
        let file = TempFile::new("one.tum", "0 0 0 0 0 0 0 1\n");
        let error = read_tum(file.path()).unwrap().to_trajectory().unwrap_err();
        assert_eq!(after_path(&error, &file), ": a trajectory needs at least 2 poses, got 1");
        assert_eq!(error.line(), None);
    }

    #[test]
    fn empty_and_comment_only_files() {
        for text in ["", "\n\n", "# only a comment\r\n   \r\n"] {
            let file = TempFile::new("empty.tum", text);
            let error = read_tum(file.path()).unwrap_err();
            assert!(matches!(error, IoError::Empty { .. }), "{error:?}");
            assert_eq!(after_path(&error, &file), ": no poses: the file has no data lines");
        }
    }

    #[test]
    fn missing_file() {
        let path = std::env::temp_dir().join("loops-io-test-no-such-dir").join("missing.tum");
        let error = read_tum(&path).unwrap_err();
        match &error {
            IoError::Open { error: io, .. } => assert_eq!(io.kind(), std::io::ErrorKind::NotFound),
            other => panic!("expected Open, got {other:?}"),
        }
        assert!(error.to_string().starts_with(&format!("{}: cannot read the file: ", path.display())), "{error}");
        assert!(std::error::Error::source(&error).is_none(), "the message holds the cause");
    }

    #[test]
    fn bytes_that_are_not_utf8() {
        let file = TempFile::new("latin1.tum", b"# Me\xdfdaten\n0 0 0 0 0 0 0 1\n1 0 0 \xb0 0 0 0 1\n");
        let error = read_tum(file.path()).unwrap_err();
        assert_eq!(after_path(&error, &file), " line 3: column 4 (\"\u{fffd}\") is not a number");
    }
}

mod csv {
    use super::*;

    #[test]
    fn no_header_three_columns_is_2d() {
        let file = TempFile::new("a.csv", "0,1,2\n0.5,3,4\n");
        let table = read_csv(file.path()).unwrap();
        assert_eq!(table.dim, 2);
        assert_eq!(table.positions, [[1.0, 2.0, 0.0], [3.0, 4.0, 0.0]]);
        assert_eq!(table.orientations_xyzw, None);
        let traj = table.to_trajectory().unwrap();
        assert_eq!(traj.coords(), &[1.0, 2.0, 3.0, 4.0]);
    }

    #[test]
    fn no_header_four_columns_is_3d() {
        let file = TempFile::new("b.csv", "0,1,2,3\n1,4,5,6\n");
        let table = read_csv(file.path()).unwrap();
        assert_eq!(table.dim, 3);
        assert_eq!(table.to_trajectory().unwrap().point(1), &[4.0, 5.0, 6.0]);
    }

    #[test]
    fn header_maps_columns_by_name() {
        let file =
            TempFile::new("c.csv", "\u{feff}\"Timestamp\",\"z\",\"Y\",\"x\",\"label\"\n0,3,2,1,start\n1,6,5,4,end\n");
        let table = read_csv(file.path()).unwrap();
        assert_eq!(table.dim, 3);
        assert_eq!(table.positions, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        assert_eq!(table.source_lines, [2, 3]);
    }

    #[test]
    fn header_without_known_names_keeps_the_order() {
        let file = TempFile::new("d.csv", "stamp,east,north\n0,1,2\n1,3,4\n");
        let table = read_csv(file.path()).unwrap();
        assert_eq!((table.dim, table.positions[1]), (2, [3.0, 4.0, 0.0]));
    }

    #[test]
    fn semicolons_tabs_spaces_comments_and_crlf() {
        let cases = [
            "# exported\r\ntime;x;y\r\n0;1;2\r\n\r\n1;3;4\r\n",
            "t\tx\ty\n# comment\n0\t1\t2\n1\t3\t4",
            "0 1 2\n  1   3 4  \n",
            "t, x, y\n0, 1, 2\n1, 3, 4\n",
        ];
        for text in cases {
            let file = TempFile::new("e.csv", text);
            let table = read_csv(file.path()).unwrap_or_else(|e| panic!("{text:?}: {e}"));
            assert_eq!(table.timestamps_s, [0.0, 1.0], "{text:?}");
            assert_eq!(table.positions, [[1.0, 2.0, 0.0], [3.0, 4.0, 0.0]], "{text:?}");
        }
    }

    #[test]
    fn header_only_is_empty() {
        let file = TempFile::new("h.csv", "t,x,y\n# nothing yet\n");
        let error = read_csv(file.path()).unwrap_err();
        assert!(matches!(error, IoError::Empty { .. }), "{error:?}");
    }

    #[test]
    fn empty_file() {
        let file = TempFile::new("empty.csv", "");
        assert!(matches!(read_csv(file.path()).unwrap_err(), IoError::Empty { .. }));
    }

    #[test]
    fn too_few_columns() {
        let file = TempFile::new("few.csv", "t,x,y,z\n0,1,2,3\n1,1,2\n");
        let error = read_csv(file.path()).unwrap_err();
        assert_eq!(
            after_path(&error, &file),
            r#" line 3: expected 4 columns as on line 1, found 3: the line ends after column 3 ("2")"#
        );
        let file = TempFile::new("two.csv", "0,1\n1,2\n");
        let error = read_csv(file.path()).unwrap_err();
        assert!(after_path(&error, &file).starts_with(" line 1: expected 3 columns (t, x, y) or 4"), "{error}");
    }

    #[test]
    fn a_non_number_and_an_empty_field() {
        let file = TempFile::new("abc.csv", "t,x,y\n0,1,2\n1,abc,2\n");
        let error = read_csv(file.path()).unwrap_err();
        assert_eq!(after_path(&error, &file), r#" line 3: column 2 ("abc") is not a number"#);
        let file = TempFile::new("gap.csv", "0,1,2\n1,,2\n");
        let error = read_csv(file.path()).unwrap_err();
        assert_eq!(after_path(&error, &file), " line 2: column 2 is empty");
    }

    #[test]
    fn nan() {
        let file = TempFile::new("nan.csv", "0,1,2\n1,nan,2\n");
        let error = read_csv(file.path()).unwrap_err();
        assert_eq!(after_path(&error, &file), r#" line 2: column 2 ("nan") is not finite"#);
    }

    #[test]
    fn a_row_mixing_numbers_and_words_is_not_a_header() {
        let file = TempFile::new("mixed.csv", "0,x,2\n1,3,4\n");
        let error = read_csv(file.path()).unwrap_err();
        assert_eq!(after_path(&error, &file), r#" line 1: column 2 ("x") is not a number"#);
    }

    #[test]
    fn a_header_naming_some_columns_only() {
        let file = TempFile::new("latlon.csv", "time,lat,lon\n0,22.3,114.1\n");
        let error = read_csv(file.path()).unwrap_err();
        assert_eq!(
            after_path(&error, &file),
            " line 1: the header names no column x, y (t may be called time or timestamp)"
        );
    }

    #[test]
    fn duplicate_timestamp_is_mapped_to_its_line() {
        let file = TempFile::new("dup.csv", "t,x,y\n0,0,0\n1,1,0\n1,2,0\n");
        let error = read_csv(file.path()).unwrap().to_trajectory().unwrap_err();
        assert_eq!(
            after_path(&error, &file),
            " line 4: timestamps must strictly increase: 1 s is not after 1 s (line 3)\
             ; drop_duplicate_stamps=True (--drop-duplicate-stamps) keeps the first pose of each stamp"
        );
    }

    #[test]
    fn tum_read_as_csv_says_so() {
        let file = TempFile::new("gt.csv", "0 0 0 0 0 0 -0 1\n1 1 0 0 0 0 0 1\n");
        let error = read_csv(file.path()).unwrap_err();
        assert!(
            after_path(&error, &file).ends_with("look like TUM (timestamp tx ty tz qx qy qz qw): read it as TUM"),
            "{error}"
        );
    }
}

mod format {
    use super::*;

    #[test]
    fn names() {
        assert_eq!("tum".parse::<Format>(), Ok(Format::Tum));
        assert_eq!("CSV".parse::<Format>(), Ok(Format::Csv));
        assert_eq!(Format::Tum.to_string(), "tum");
    }

    #[test]
    fn unknown_name_lists_the_valid_names() {
        let error = "bag".parse::<Format>().unwrap_err();
        assert_eq!(
            error.to_string(),
            r#"unknown file format "bag": expected one of tum, csv, kitti, euroc, g2o, tuc, mcap, rosbag2, ros1"#
        );
        assert!(matches!(error, loops_core::Error::UnknownName { .. }));
    }

    #[test]
    fn extensions() {
        assert_eq!(Format::from_path("a/b.tum"), Some(Format::Tum));
        assert_eq!(Format::from_path("b.TXT"), Some(Format::Tum));
        assert_eq!(Format::from_path("b.Csv"), Some(Format::Csv));
        assert_eq!(Format::from_path("b.csv.gz"), None);
        assert_eq!(Format::from_path("csv"), None);
    }

    #[test]
    fn read_trajectory_by_extension_and_by_name() {
        let tum = "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n";
        let csv = "t,x,y\n0,0,0\n1,1,0\n";
        for (name, text, dim) in [("a.tum", tum, 3), ("a.txt", tum, 3), ("a.csv", csv, 2)] {
            let file = TempFile::new(name, text);
            let table = read_trajectory(file.path(), None).unwrap();
            assert_eq!(table.dim, dim, "{name}");
        }
        let file = TempFile::new("poses.log", csv);
        assert_eq!(read_trajectory(file.path(), Some(Format::Csv)).unwrap().dim, 2);
        let file = TempFile::new("poses.csv", tum);
        let error = read_trajectory(file.path(), Some(Format::Tum)).map(|table| table.dim);
        assert_eq!(error.unwrap(), 3, "an explicit format wins");
    }

    #[test]
    fn a_csv_holding_tum_is_read_as_tum() {
        let file = TempFile::new("gt_slam.csv", "1621218775 0 0 0 0 0 -0 1\n1621218776 1 2 3 0 0 0 1\n");
        let table = read_trajectory(file.path(), None).unwrap();
        assert_eq!(table.dim, 3);
        assert_eq!(table.positions[1], [1.0, 2.0, 3.0]);
        assert!(table.orientations_xyzw.is_some());
    }

    #[test]
    fn unknown_extension() {
        let file = TempFile::new("drive.log", "");
        let error = read_trajectory(file.path(), None).unwrap_err();
        assert!(matches!(&error, IoError::UnknownFormat { extension: Some(e), .. } if e == "log"), "{error:?}");
        assert_eq!(
            after_path(&error, &file),
            r#": cannot tell the file format from the extension ".log": expected .tum or .txt for tum, .csv for csv, .kitti for kitti, .g2o or .graph for g2o, .mcap for mcap, .db3 or .yaml or .zstd or .lz4 for rosbag2, .bag for ros1, or name the format (tum, csv, kitti, euroc, g2o, tuc, mcap, rosbag2, ros1)"#
        );
        let file = TempFile::new("poses", "");
        let error = read_trajectory(file.path(), None).unwrap_err();
        assert!(
            after_path(&error, &file).starts_with(": cannot tell the file format from a file without an extension"),
            "{error}"
        );
    }
}

/// Random input: the readers may refuse it but never panic, and what they accept is sound.
mod garbage {
    use proptest::prelude::*;
    use proptest::test_runner::RngSeed;

    use super::*;

    /// What holds for any table a reader returns.
    fn check_table(table: &PoseTable) {
        let count = table.timestamps_s.len();
        assert!(count > 0);
        assert_eq!(table.positions.len(), count);
        assert_eq!(table.source_lines.len(), count);
        assert!(table.source_lines.iter().all(|&line| line > 0));
        if let Some(orientations) = &table.orientations_xyzw {
            assert_eq!(orientations.len(), count);
            assert!(orientations.iter().flatten().all(|q| q.is_finite()));
        }
        assert!(table.timestamps_s.iter().all(|t| t.is_finite()));
        assert!(table.positions.iter().flatten().all(|c| c.is_finite()));
        assert!(matches!(table.dim, 2 | 3));
        // May fail (order, too few poses), must not panic.
        let _ = table.to_trajectory();
        let _ = table.to_trajectory_plane([0, 1]);
    }

    fn read_all_ways(name: &str, contents: &[u8]) {
        let file = TempFile::new(name, contents);
        let rate = loops_io::Timing::RateHz(10.0);
        for result in [
            read_tum(file.path()),
            read_csv(file.path()),
            read_trajectory(file.path(), None),
            loops_io::read_kitti(file.path(), &rate),
            loops_io::read_kitti(file.path(), &loops_io::Timing::FromFile),
            loops_io::read_euroc(file.path()),
            loops_io::read_tuc(file.path()),
            loops_io::read_pose_graph(file.path(), &rate).map(|graph| graph.vertices),
        ] {
            match result {
                Ok(table) => check_table(&table),
                Err(error) => {
                    let message = error.to_string();
                    assert!(message.starts_with(&file.path().display().to_string()), "{message}");
                }
            }
        }
    }

    /// Files shaped like pose files (one separator, 3, 4 or 8 columns, numbers) with the odd
    /// flaw: a junk field, a missing or extra column. Many of them parse.
    fn near_miss_files() -> impl Strategy<Value = String> {
        let token = prop_oneof![
            60 => any::<f64>().prop_filter("finite", |v| v.is_finite()).prop_map(|v| v.to_string()),
            30 => (-1000i32..1000).prop_map(|v| v.to_string()),
            1 => Just("nan".to_owned()),
            1 => Just("-inf".to_owned()),
            1 => Just("t".to_owned()),
            1 => Just("#".to_owned()),
            1 => Just("\"".to_owned()),
            1 => Just(String::new()),
            1 => "[0-9.eE+-]{1,6}",
        ];
        let separator = prop_oneof![Just(" "), Just("\t"), Just(","), Just(";"), Just(", ")];
        let width = prop_oneof![Just(3usize), Just(4), Just(8)];
        let ending = prop_oneof![Just("\n"), Just("\r\n")];
        (separator, width).prop_flat_map(move |(separator, width)| {
            let columns = prop_oneof![18 => Just(width), 1 => Just(width - 1), 1 => Just(width + 1)];
            let line = columns.prop_flat_map({
                let token = token.clone();
                move |count| proptest::collection::vec(token.clone(), count)
            });
            proptest::collection::vec((line, ending.clone()), 0..12)
                .prop_map(move |lines| lines.into_iter().map(|(fields, end)| fields.join(separator) + end).collect())
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig {
            cases: 256,
            rng_seed: RngSeed::Fixed(0x1005),
            // The seed is fixed, so a failure replays without a regressions file.
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        #[test]
        fn random_bytes_never_panic(contents in proptest::collection::vec(any::<u8>(), 0..400)) {
            read_all_ways("bytes.csv", &contents);
        }

        #[test]
        fn random_text_never_panics(contents in "(?s).{0,300}") {
            read_all_ways("text.tum", contents.as_bytes());
        }

        #[test]
        fn near_miss_files_never_panic(contents in near_miss_files()) {
            read_all_ways("near.csv", contents.as_bytes());
            read_all_ways("near.txt", contents.as_bytes());
        }

        #[test]
        fn written_poses_read_back_exactly(
            poses in proptest::collection::vec((any::<f64>(), [any::<f64>(); 3], [any::<f64>(); 4]), 1..20),
            comment_every in 1usize..5,
        ) {
            let poses: Vec<_> = poses
                .into_iter()
                .filter(|(t, p, q)| t.is_finite() && p.iter().chain(q).all(|v| v.is_finite()))
                .collect();
            prop_assume!(!poses.is_empty());
            let mut text = String::new();
            let mut lines = Vec::new();
            let mut line = 0;
            for (i, (t, p, q)) in poses.iter().enumerate() {
                if i % comment_every == 0 {
                    text += "# comment\n";
                    line += 1;
                }
                text += &format!("{t} {} {} {} {} {} {} {}\n", p[0], p[1], p[2], q[0], q[1], q[2], q[3]);
                line += 1;
                lines.push(line);
            }
            let file = TempFile::new("round.tum", text);
            let table = read_tum(file.path()).unwrap();
            prop_assert_eq!(table.timestamps_s, poses.iter().map(|pose| pose.0).collect::<Vec<_>>());
            prop_assert_eq!(table.positions, poses.iter().map(|pose| pose.1).collect::<Vec<_>>());
            prop_assert_eq!(table.orientations_xyzw, Some(poses.iter().map(|pose| pose.2).collect()));
            prop_assert_eq!(table.source_lines, lines);
        }
    }
}

/// The real trajectories in `shared/data` beside the checkout; skipped when it is absent.
mod real_data {
    use super::*;

    fn assert_unit_quaternions(table: &PoseTable, tolerance: f64) {
        for (orientation, line) in table.orientations_xyzw.as_ref().unwrap().iter().zip(&table.source_lines) {
            let norm = orientation.iter().map(|q| q * q).sum::<f64>().sqrt();
            assert!((norm - 1.0).abs() <= tolerance, "line {line}: |q| = {norm}");
        }
    }

    #[test]
    fn tum_rgbd_fr2_desk_has_a_duplicate_timestamp() {
        let Some(dir) = real_data_dir() else { return };
        let path = dir.join("tum_rgbd/fr2_desk_groundtruth.txt");
        let table = read_trajectory(&path, None).unwrap();
        assert_eq!(table.timestamps_s.len(), 20957, "poses, as its README says");
        assert_eq!(table.source_lines[0], 4, "after 3 comment lines");
        assert_eq!(table.timestamps_s[0], 1311868163.8697);
        assert_eq!(table.positions[0], [-0.1357, -1.4217, 1.4764]);
        assert_unit_quaternions(&table, 1e-3);
        // Lines 10862 and 10863 share the timestamp 1311868229.5760, with different poses.
        let error = table.to_trajectory().unwrap_err();
        assert_eq!(error.line(), Some(10863));
        assert!(
            error.to_string().ends_with(
                "fr2_desk_groundtruth.txt line 10863: timestamps must strictly increase: \
                 1311868229.576 s is not after 1311868229.576 s (line 10862); \
                 drop_duplicate_stamps=True (--drop-duplicate-stamps) keeps the first pose of each stamp"
            ),
            "{error}"
        );
    }

    #[test]
    fn tum_rgbd_fr1_xyz() {
        let Some(dir) = real_data_dir() else { return };
        let table = read_tum(dir.join("tum_rgbd/freiburg1_xyz-groundtruth.txt")).unwrap();
        assert_eq!(table.timestamps_s.len(), 3000);
        assert_unit_quaternions(&table, 1e-3);
        let traj = table.to_trajectory().unwrap();
        assert_eq!((traj.len(), traj.dim()), (3000, 3));
        assert!((traj.span_s() - 30.0896).abs() < 1e-3, "{}", traj.span_s());
    }

    #[test]
    fn urbannav_ground_truth_csv_files_are_tum() {
        let Some(dir) = real_data_dir() else { return };
        for (name, poses) in [
            ("gt_slam_UrbanNav-HK-CHTunnel-20210518.csv", 401),
            ("gt_slam_UrbanNav-HK-Mongkok-20210518.csv", 2312),
            ("gt_slam_UrbanNav-HK-TST-20210517.csv", 787), // no newline after the last line
            ("gt_slam_UrbanNav-HK-Whampoa-20210521.csv", 1539),
        ] {
            let path = dir.join("urbannav_hk").join(name);
            let table = read_trajectory(&path, None).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(table, read_tum(&path).unwrap(), "{name}");
            assert_eq!(table.timestamps_s.len(), poses, "{name}");
            assert_eq!(table.positions[0], [0.0; 3], "{name}: local frame at the first pose");
            assert!(table.timestamps_s.windows(2).all(|w| w[1] - w[0] == 1.0), "{name}: 1 Hz");
            assert_unit_quaternions(&table, 1e-9);
            let traj = table.to_trajectory().unwrap();
            assert_eq!(traj.span_s(), (poses - 1) as f64, "{name}");
            let error = read_csv(&path).unwrap_err();
            assert!(error.to_string().contains("read it as TUM"), "{error}");
        }
    }

    #[test]
    fn urbannav_novatel_exports_are_not_tum() {
        let Some(dir) = real_data_dir() else { return };
        let error = read_trajectory(dir.join("urbannav_hk/UrbanNav_TST_GT.txt"), None).unwrap_err();
        assert!(
            error
                .to_string()
                .contains("line 1: expected 8 columns (timestamp tx ty tz qx qy qz qw), found 20: column 9"),
            "{error}"
        );
        // Two header lines: the first has no number and is skipped, the second ("(sec) ...") fails.
        let error = read_trajectory(dir.join("urbannav_hk/UrbanNav_TST_GT_raw.txt"), None).unwrap_err();
        assert!(error.to_string().ends_with(r#"line 2: column 1 ("(sec)") is not a number"#), "{error}");
    }

    #[test]
    fn kitti_txt_is_read_as_kitti_not_tum() {
        let Some(dir) = real_data_dir() else { return };
        let path = dir.join("kitti_odometry/00.txt");
        let table = read_trajectory(&path, None).unwrap();
        assert_eq!(table.len(), 4541);
        assert!(table == loops_io::read_kitti(&path, &loops_io::Timing::FromFile).unwrap());
        let error = read_tum(&path).unwrap_err();
        assert!(error.to_string().ends_with(KITTI_READ_AS_TUM), "{error}");
    }

    #[test]
    fn euroc_csv_is_not_misread() {
        let Some(dir) = real_data_dir() else { return };
        // The "#timestamp [ns], ..." header is a comment; 17 unnamed columns are not t, x, y[, z].
        let error = read_csv(dir.join("euroc/evo_V102_groundtruth.csv")).unwrap_err();
        assert!(error.to_string().contains("line 2: expected 3 columns (t, x, y) or 4 (t, x, y, z)"), "{error}");
        assert!(error.to_string().ends_with("found 17"), "{error}");
    }
}
