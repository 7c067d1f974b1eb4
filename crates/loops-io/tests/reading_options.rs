//! What a newcomer hits on real files, and the options that read them: repeated timestamps
//! dropped on request, detections outside the trajectory's span dropped on request, files
//! joined as one trajectory, quaternions normalised with a tolerance, the format told as
//! `loops info` prints it, and KITTI's `times.txt`. Each option is checked against a
//! straightforward reimplementation on random tables, and on the real files where it matters
//! (skipped, saying so, without `../shared/data`).

use loops_io::{
    Format, IoError, McapOptions, McapWriteOptions, PoseTable, ReadOptions, Timing, format_of, read_detections,
    read_kitti, read_mcap, read_trajectory, read_trajectory_with, read_tuc, read_tum, write_mcap,
};
use proptest::prelude::*;

mod support;
use support::{KITTI_READ_AS_TUM, TempDir, real_data_dir};

/// TUM text of poses `(t, x)`, one a line after a comment, with a blank line every 7 poses (so
/// that lines and pose indices differ).
fn tum_text(poses: &[(f64, f64)]) -> String {
    let mut text = String::from("# t x y z qx qy qz qw\n");
    for (i, (t, x)) in poses.iter().enumerate() {
        if i % 7 == 6 {
            text.push('\n');
        }
        text += &format!("{t:?} {x:?} {:?} 0 0 0 0 1\n", 2.0 * t);
    }
    text
}

mod duplicate_stamps {
    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Against `Vec::dedup_by`: the first row of each run of equal stamps stays, the others
        /// go, with their lines; what stays is the table the file without those lines reads as.
        #[test]
        fn keep_the_first_pose_of_each_stamp(repeats in proptest::collection::vec(0usize..4, 2..40)) {
            let mut poses = Vec::new();
            for (k, &repeat) in repeats.iter().enumerate() {
                for r in 0..=repeat {
                    poses.push((k as f64 * 0.5, (10 * k + r) as f64));
                }
            }
            let dir = TempDir::new();
            let path = dir.file("dups.tum", &tum_text(&poses));
            let original = read_tum(&path).unwrap();
            let mut table = original.clone();
            let dropped = table.drop_duplicate_stamps();

            let mut rows: Vec<(f64, [f64; 3], usize)> = original
                .timestamps_s
                .iter()
                .zip(&original.positions)
                .zip(&original.source_lines)
                .map(|((&t, &p), &line)| (t, p, line))
                .collect();
            let all_lines: Vec<usize> = rows.iter().map(|row| row.2).collect();
            rows.dedup_by(|later, first| later.0 == first.0);
            let kept_lines: Vec<usize> = rows.iter().map(|row| row.2).collect();
            let dropped_lines: Vec<usize> = all_lines.into_iter().filter(|line| !kept_lines.contains(line)).collect();

            prop_assert_eq!(&table.timestamps_s, &rows.iter().map(|row| row.0).collect::<Vec<_>>());
            prop_assert_eq!(&table.positions, &rows.iter().map(|row| row.1).collect::<Vec<_>>());
            prop_assert_eq!(&table.source_lines, &kept_lines);
            prop_assert_eq!(table.orientations_xyzw.as_ref().map(Vec::len), Some(kept_lines.len()));
            prop_assert_eq!(dropped.count, dropped_lines.len());
            prop_assert_eq!(&dropped.lines, &dropped_lines);
            prop_assert_eq!(&dropped.path, &path);
            // The same as reading the file without the dropped lines (lines renumbered aside).
            let text = tum_text(&poses);
            let kept_text: String = text
                .lines()
                .enumerate()
                .filter(|(i, _)| !dropped_lines.contains(&(i + 1)))
                .map(|(_, line)| format!("{line}\n"))
                .collect();
            let without = read_tum(dir.file("without.tum", &kept_text)).unwrap();
            prop_assert_eq!(&without.positions, &table.positions);
            prop_assert_eq!(&without.timestamps_s, &table.timestamps_s);
            // Strict reading refuses the original exactly when something was dropped.
            prop_assert_eq!(original.to_trajectory().is_err(), dropped.count > 0);
            prop_assert_eq!(table.to_trajectory().unwrap().len(), rows.len());
            // Nothing more to drop.
            prop_assert!(table.drop_duplicate_stamps().is_empty());
        }
    }

    #[test]
    fn out_of_order_stays_an_error_and_names_the_option_for_repeats() {
        let dir = TempDir::new();
        let path = dir.file("order.tum", &tum_text(&[(0.0, 0.0), (2.0, 1.0), (1.0, 2.0)]));
        let mut table = read_tum(&path).unwrap();
        assert!(table.drop_duplicate_stamps().is_empty());
        let error = table.to_trajectory().unwrap_err();
        assert!(!error.to_string().contains("drop_duplicate_stamps"), "{error}");
        let path = dir.file("repeat.tum", &tum_text(&[(0.0, 0.0), (1.0, 1.0), (1.0, 2.0)]));
        let error = read_tum(&path).unwrap().to_trajectory().unwrap_err();
        assert!(
            error.to_string().ends_with(
                "line 4: timestamps must strictly increase: 1 s is not after 1 s (line 3); \
                 drop_duplicate_stamps=True (--drop-duplicate-stamps) keeps the first pose of each stamp"
            ),
            "{error}"
        );
    }

    #[test]
    fn poses_from_mcap_keep_their_messages() {
        let dir = TempDir::new();
        let stamps = [0.0, 0.1, 0.1, 0.2, 0.3, 0.3, 0.3, 0.4];
        let table = PoseTable {
            path: dir.0.join("in.tum"),
            timestamps_s: stamps.to_vec(),
            timestamps_ns: None,
            positions: (0..stamps.len()).map(|i| [i as f64, 0.0, 0.0]).collect(),
            orientations_xyzw: Some(vec![[0.0, 0.0, 0.0, 1.0]; stamps.len()]),
            dim: 3,
            source_lines: Vec::new(),
            messages: None,
        };
        let path = dir.0.join("dups.mcap");
        write_mcap(&path, &table, &McapWriteOptions::default(), false).unwrap();
        let read = read_mcap(&path, &McapOptions::default()).unwrap();
        let mut dropped_table = read.clone();
        let dropped = dropped_table.drop_duplicate_stamps();
        assert_eq!((dropped.count, dropped.lines.len()), (3, 0)); // messages, not lines
        assert_eq!(dropped_table.positions, [0, 1, 3, 4, 7].map(|x| [f64::from(x), 0.0, 0.0]));
        let ns = dropped_table.timestamps_ns.as_ref().unwrap();
        assert_eq!(ns, &[0, 100_000_000, 200_000_000, 300_000_000, 400_000_000]);
        // Each pose kept its own message: the one it had before, in the same order.
        let before = read.messages.as_ref().unwrap();
        let after = dropped_table.messages.as_ref().unwrap();
        let kept: Vec<_> = [0, 1, 3, 4, 7].iter().map(|&i| before.messages[i]).collect();
        assert_eq!(after.messages, kept);
        assert_eq!(dropped_table.to_trajectory().unwrap().len(), 5);
    }

    #[test]
    fn fr2_desk_has_one_and_reads_once_it_is_dropped() {
        let Some(data) = real_data_dir() else { return };
        let path = data.join("tum_rgbd/fr2_desk_groundtruth.txt");
        let mut table = read_trajectory(&path, None).unwrap();
        assert_eq!(table.len(), 20957);
        assert_eq!(table.to_trajectory().unwrap_err().line(), Some(10863));
        let dropped = table.drop_duplicate_stamps();
        assert_eq!((dropped.count, dropped.lines.as_slice()), (1, &[10863][..]));
        let spec = "se3(rotation_weight_m_per_rad=0.5)".parse().unwrap();
        assert_eq!(table.to_trajectory_for(&spec, None).unwrap().len(), 20956);
    }
}

mod detections_outside_span {
    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Against a filter written out: a detection stays when both its times lie in
        /// [first pose, last pose], as the core places them; what stays is placed without error.
        #[test]
        fn drop_exactly_those_the_core_refuses(
            pairs in proptest::collection::vec((-2.0f64..12.0, -2.0f64..12.0, 0.0f64..1.0), 1..30),
            ends in (0.0f64..3.0, 7.0f64..10.0),
        ) {
            let dir = TempDir::new();
            let mut text = String::from("odom2 0 0 0 0\n");
            for (t, u, score) in &pairs {
                text += &format!("loop {t:?} {u:?} {score:?}\n");
            }
            let path = dir.file("input.txt", &text);
            let (first, last) = ends;
            let times: Vec<f64> = (0..=20).map(|k| first + (last - first) * k as f64 / 20.0).collect();
            let traj = loops_core::Trajectory::new(times.clone(), vec![0.0; times.len()], 1).unwrap();
            let original = read_detections(&path).unwrap();
            let mut table = original.clone();
            let dropped = table.drop_outside_span(&traj);

            let inside = |t: f64| first <= t && t <= times[times.len() - 1];
            let keep: Vec<bool> = pairs.iter().map(|(t, u, _)| inside(*t) && inside(*u)).collect();
            let lines = |keep_it: bool| -> Vec<usize> {
                (0..pairs.len()).filter(|&i| keep[i] == keep_it).map(|i| i + 2).collect()
            };
            prop_assert_eq!(&table.source_lines, &lines(true));
            prop_assert_eq!(&dropped.lines, &lines(false));
            prop_assert_eq!(dropped.count, lines(false).len());
            let kept = |column: usize| -> Vec<f64> {
                pairs.iter().zip(&keep).filter(|(_, k)| **k).map(|(p, _)| [p.0, p.1, p.2][column]).collect()
            };
            prop_assert_eq!(&table.t_s, &kept(0));
            prop_assert_eq!(&table.t_prime_s, &kept(1));
            prop_assert_eq!(table.scores.as_ref(), Some(&kept(2)));
            prop_assert_eq!(original.to_detections(&traj).is_err(), dropped.count > 0);
            if !table.t_s.is_empty() {
                prop_assert_eq!(table.to_detections(&traj).unwrap().len(), table.t_s.len());
            }
        }
    }

    #[test]
    fn the_error_names_the_option() {
        let dir = TempDir::new();
        let path = dir.file("input.txt", "loop 0.5 0.2 1\nloop 4.5 1 1\n");
        let traj = loops_core::Trajectory::new(vec![0.0, 1.0, 2.0], vec![0.0; 3], 1).unwrap();
        let error = read_detections(&path).unwrap().to_detections(&traj).unwrap_err();
        assert_eq!(
            error.to_string(),
            format!(
                "{} line 2: detection 1 at 4.5 s lies outside the trajectory's time span [0, 2] s; \
                 drop_outside_span=True (--drop-detections-outside-span) drops such detections",
                path.display()
            )
        );
    }

    #[test]
    fn corridor_has_39_past_the_end_of_its_ground_truth() {
        let Some(data) = real_data_dir() else { return };
        let traj = read_tuc(data.join("tuc/SLAM/Corridor_GT.txt")).unwrap().to_trajectory().unwrap();
        let mut table = read_detections(data.join("tuc/SLAM/Corridor_Input.txt")).unwrap();
        assert_eq!(table.t_s.len(), 10_019);
        let end = traj.timestamps_s()[traj.len() - 1];
        let dropped = table.drop_outside_span(&traj);
        assert_eq!((dropped.count, dropped.lines.len(), table.t_s.len()), (39, 39, 9_980));
        assert_eq!(dropped.lines[0], 32673);
        assert!(table.t_s.iter().chain(&table.t_prime_s).all(|&t| t <= end));
        assert_eq!(table.to_detections(&traj).unwrap().len(), 9_980);
    }
}

mod joined_files {
    use super::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// A trajectory cut into files, given in any order, joins back to itself.
        #[test]
        fn pieces_join_back_in_time_order(
            cuts in proptest::collection::btree_set(1usize..59, 0..5),
            order in any::<prop::sample::Index>(),
        ) {
            let poses: Vec<(f64, f64)> = (0..60).map(|i| (100.0 + i as f64 * 0.25, (i as f64).sin())).collect();
            let dir = TempDir::new();
            let whole = read_tum(dir.file("whole.tum", &tum_text(&poses))).unwrap();
            let mut bounds = vec![0];
            bounds.extend(cuts.iter().copied());
            bounds.push(poses.len());
            let mut tables: Vec<PoseTable> = bounds
                .windows(2)
                .enumerate()
                .map(|(k, w)| read_tum(dir.file(&format!("part{k}.tum"), &tum_text(&poses[w[0]..w[1]]))).unwrap())
                .collect();
            let first_path = tables[0].path.clone();
            let shift = order.index(tables.len());
            tables.rotate_left(shift);
            let joined = PoseTable::join(tables).unwrap();
            prop_assert_eq!(&joined.timestamps_s, &whole.timestamps_s);
            prop_assert_eq!(&joined.positions, &whole.positions);
            prop_assert_eq!(&joined.orientations_xyzw, &whole.orientations_xyzw);
            prop_assert_eq!(&joined.path, &first_path);
            if bounds.len() > 2 {
                prop_assert!(joined.source_lines.is_empty()); // they would name the wrong file
            } else {
                prop_assert_eq!(&joined.source_lines, &whole.source_lines);
            }
            prop_assert_eq!(joined.to_trajectory().unwrap().len(), poses.len());
        }
    }

    #[test]
    fn overlapping_files_name_both_and_the_stamps() {
        let dir = TempDir::new();
        let a = dir.file("a.tum", &tum_text(&[(0.0, 0.0), (5.0, 1.0), (10.0, 2.0)]));
        let b = dir.file("b.tum", &tum_text(&[(10.0, 3.0), (20.0, 4.0)]));
        for tables in
            [vec![read_tum(&a).unwrap(), read_tum(&b).unwrap()], vec![read_tum(&b).unwrap(), read_tum(&a).unwrap()]]
        {
            let error = PoseTable::join(tables).unwrap_err();
            assert!(matches!(error, IoError::Join { .. }), "{error:?}");
            assert_eq!(error.path(), b);
            assert_eq!(
                error.to_string(),
                format!(
                    "{b}: overlaps {a} in time: its first pose (line 2, 10 s) is not after the last pose of {a} \
                     (line 4, 10 s); files read as one trajectory must follow one another",
                    a = a.display(),
                    b = b.display()
                )
            );
        }
        // The same file twice overlaps itself.
        let error = PoseTable::join(vec![read_tum(&a).unwrap(), read_tum(&a).unwrap()]).unwrap_err();
        assert!(error.to_string().contains("overlaps"), "{error}");
    }

    #[test]
    fn dimensions_must_agree_and_something_must_be_given() {
        let dir = TempDir::new();
        let tum = read_tum(dir.file("a.tum", &tum_text(&[(0.0, 0.0), (1.0, 1.0)]))).unwrap();
        let csv = loops_io::read_csv(dir.file("b.csv", "t,x,y\n5,0,0\n6,1,0\n")).unwrap();
        let error = PoseTable::join(vec![tum.clone(), csv]).unwrap_err();
        assert!(error.to_string().contains("2 coordinates a pose, and"), "{error}");
        assert!(error.to_string().contains("a.tum has 3"), "{error}");
        assert!(matches!(PoseTable::join(Vec::new()).unwrap_err(), IoError::Join { .. }));
        assert_eq!(PoseTable::join(vec![tum.clone()]).unwrap(), tum);
    }

    #[test]
    fn orientations_and_integer_stamps_are_kept_when_every_file_has_them() {
        let dir = TempDir::new();
        let tum = read_tum(dir.file("a.tum", &tum_text(&[(0.0, 0.0), (1.0, 1.0)]))).unwrap();
        let csv = loops_io::read_csv(dir.file("b.csv", "t,x,y,z\n5,0,0,0\n6,1,0,0\n")).unwrap();
        let joined = PoseTable::join(vec![csv, tum]).unwrap();
        assert_eq!(joined.timestamps_s, [0.0, 1.0, 5.0, 6.0]);
        assert_eq!(joined.orientations_xyzw, None);
        assert_eq!(joined.timestamps_ns, None);
    }
}

mod quaternion_tolerance {
    use super::*;

    #[test]
    fn a_tolerance_of_your_choice_names_the_line_beyond_it() {
        let dir = TempDir::new();
        // Norms 1, 1.0002 (4 decimals), 1.02.
        let path = dir
            .file("q.tum", "# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n1 1 0 0 0.7072 0 0 0.7072\n2 2 0 0 0 0 0 1.02\n");
        let spec: loops_core::MetricSpec = "se3(rotation_weight_m_per_rad=1)".parse().unwrap();
        let table = read_tum(&path).unwrap();
        let error = table.to_trajectory_for(&spec, None).unwrap_err();
        assert_eq!(error.line(), Some(4));
        assert!(error.to_string().contains("quaternion_tolerance"), "{error}");
        let mut strict = table.clone();
        let error = strict.normalize_orientations(1e-6).unwrap_err();
        assert_eq!(error.line(), Some(3));
        assert!(error.to_string().contains("not 1: zero, or farther from unit length than quaternion_tolerance"));
        let mut loose = table.clone();
        loose.normalize_orientations(0.05).unwrap();
        for q in loose.orientations_xyzw.as_ref().unwrap() {
            assert!((q.iter().map(|v| v * v).sum::<f64>().sqrt() - 1.0).abs() < 1e-15, "{q:?}");
        }
        let traj = loose.to_trajectory_for(&spec, None).unwrap();
        assert_eq!(traj.point(2)[3..], [0.0, 0.0, 0.0, 1.0]);
        for bad in [-1.0, f64::NAN] {
            let error = table.clone().normalize_orientations(bad).unwrap_err();
            assert!(error.to_string().contains("quaternion_tolerance"), "{error}");
        }
    }
}

mod formats_told {
    use super::*;

    #[test]
    fn from_the_extension_and_first_line() {
        let dir = TempDir::new();
        let cases = [
            ("kitti.txt", "0 1 0 0 0 0 1 0 0 0 0 1 0\n", Format::Kitti),
            ("kitti12.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n", Format::Kitti),
            ("tum.txt", "# c\n0 0 0 0 0 0 0 1\n", Format::Tum),
            ("tuc.txt", "point2 0 1 2 0 0 0 0\n", Format::Tuc),
            ("graph.txt", "VERTEX2 0 0 0 0\n", Format::G2o),
            ("gt.csv", "0 0 0 0 0 0 0 1\n", Format::Tum),
            ("plain.csv", "t,x,y\n0,0,0\n", Format::Csv),
            ("graph.g2o", "whatever", Format::G2o),
            ("log.mcap", "not read", Format::Mcap),
        ];
        for (name, text, format) in cases {
            let path = dir.file(name, text);
            assert_eq!(format_of(&path).unwrap(), format, "{name}");
        }
        let error = format_of(dir.file("x.log", "")).unwrap_err();
        assert!(matches!(error, IoError::UnknownFormat { .. }), "{error:?}");
        assert!(matches!(format_of(dir.0.join("missing.txt")).unwrap_err(), IoError::Open { .. }));
    }

    #[test]
    fn real_files_are_told_as_read() {
        let Some(data) = real_data_dir() else { return };
        for (file, format) in [
            ("kitti_odometry/00.txt", Format::Kitti),
            ("mulran_kaist/kaist01_localization_poses01_seq02asmap.txt", Format::Kitti),
            ("tum_rgbd/fr2_desk_groundtruth.txt", Format::Tum),
            ("tuc/SLAM/Corridor_GT.txt", Format::Tuc),
            ("euroc/evo_V102_groundtruth.csv", Format::Euroc),
            ("urbannav_hk/gt_slam_UrbanNav-HK-TST-20210517.csv", Format::Tum),
            ("pose_graphs/FR079_P_toro.graph", Format::G2o),
        ] {
            assert_eq!(format_of(data.join(file)).unwrap(), format, "{file}");
        }
    }

    #[test]
    fn a_kitti_file_read_as_tum_says_so() {
        let dir = TempDir::new();
        let path = dir.file("00.txt", "0 1 0 0 0 0 1 0 0 0 0 1 0\n");
        let error = read_tum(&path).unwrap_err();
        assert!(error.to_string().ends_with(KITTI_READ_AS_TUM), "{error}");
    }
}

mod kitti_times {
    use super::*;

    /// `text` with the first number of each data line moved to a times file: KITTI's
    /// `poses/XX.txt` and `sequences/XX/times.txt` from a 13-number file.
    fn split_times(text: &str) -> (String, String) {
        let (mut poses, mut times) = (String::new(), String::new());
        for line in text.lines().filter(|line| !line.trim().is_empty()) {
            let (time, pose) = line.trim().split_once(' ').expect("a time and a pose");
            poses += &format!("{pose}\n");
            times += &format!("{time}\n");
        }
        (poses, times)
    }

    fn assert_same(a: &PoseTable, b: &PoseTable) {
        assert_eq!(a.timestamps_s, b.timestamps_s);
        assert_eq!(a.positions, b.positions);
        assert_eq!(a.orientations_xyzw, b.orientations_xyzw);
        assert_eq!(a.len(), b.len());
    }

    #[test]
    fn a_times_file_gives_twelve_number_lines_their_times() {
        let dir = TempDir::new();
        let text: String = (0..30)
            .map(|i| {
                let (s, c) = (f64::from(i) * 0.2).sin_cos();
                format!("{:e} {c:?} 0 {s:?} {i} 0 1 0 0 {:?} 0 {c:?} {}\n", 0.1037 * f64::from(i), -s, 2 * i)
            })
            .collect();
        let with_times = dir.file("13.txt", &text);
        let (poses, times) = split_times(&text);
        let poses = dir.file("00.txt", &poses);
        let times = dir.file("times.txt", &times);
        let expected = read_kitti(&with_times, &Timing::FromFile).unwrap();
        let options = ReadOptions::default().timing(Timing::TimesFile(times.clone()));
        let read = read_trajectory_with(&poses, &options).unwrap();
        assert_same(&read, &expected);
        assert!(read.timestamps_s.iter().zip(0..).all(|(&t, i)| t == 0.1037 * f64::from(i)));
        // Without the times: the error names both ways to give them.
        let error = read_trajectory(&poses, None).unwrap_err();
        assert!(error.to_string().contains("(times, --times)"), "{error}");
    }

    #[test]
    fn kitti_00_from_poses_and_times_equals_the_file_with_times() {
        let Some(data) = real_data_dir() else { return };
        let path = data.join("kitti_odometry/00.txt");
        let (poses, times) = split_times(&std::fs::read_to_string(&path).unwrap());
        let dir = TempDir::new();
        let (poses, times) = (dir.file("00.txt", &poses), dir.file("times.txt", &times));
        let expected = read_trajectory(&path, None).unwrap();
        let read = read_trajectory_with(&poses, &ReadOptions::default().timing(Timing::TimesFile(times))).unwrap();
        assert_eq!(read.len(), 4541);
        assert_same(&read, &expected);
    }

    #[test]
    fn times_of_the_wrong_count_are_an_error() {
        let dir = TempDir::new();
        let poses = dir.file("00.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n");
        let times = dir.file("times.txt", "0.0\n0.1\n0.2\n");
        let error =
            read_trajectory_with(&poses, &ReadOptions::default().timing(Timing::TimesFile(times.clone()))).unwrap_err();
        assert_eq!(error.path(), times.as_path());
        assert!(error.to_string().ends_with(": 3 timestamps but 2 poses"), "{error}");
    }
}
