//! Bags written by an independent writer, the `rosbags` Python package, through
//! `make_bag_fixtures.py`: rosbag2 sqlite3 and MCAP (uncompressed, zstd per message, zstd per
//! file, split in 3 files) and ROS 1 (uncompressed, bz2, lz4 chunks), of `PoseStamped` and
//! `Odometry`, read back exactly through the folder, `metadata.yaml` and the file path; TF
//! topics and frame pairs; the topic lists; broken bags. KITTI 00 (from `shared/data`) is the
//! acceptance trajectory: the same poses and the same loop components as its text file.
//!
//! Skipped, with a message, when python3 or `rosbags` is missing, and (KITTI) when
//! `shared/data` is absent.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use loops_core::{Euclidean, find_loops};
use loops_io::{
    Format, IoError, McapOptions, PoseTable, PoseType, TimeSource, Timing, list_topics, read_kitti, read_ros1,
    read_rosbag2, read_trajectory, read_trajectory_with,
};
use serde_json::Value;

mod support;

use support::{BagPose as Pose, bag_fixtures as make_fixtures, small_bag_poses as small_poses};

fn small() -> Option<&'static (PathBuf, Value, Vec<Pose>)> {
    static FIXTURES: OnceLock<Option<(PathBuf, Value, Vec<Pose>)>> = OnceLock::new();
    FIXTURES
        .get_or_init(|| {
            let poses = small_poses();
            make_fixtures("small", &poses).map(|(dir, manifest)| (dir, manifest, poses))
        })
        .as_ref()
}

macro_rules! small_or_skip {
    () => {
        match small() {
            Some((dir, manifest, poses)) => (dir.as_path(), manifest, poses.as_slice()),
            None => return,
        }
    };
}

fn fixtures(manifest: &Value) -> impl Iterator<Item = &Value> {
    manifest["fixtures"].as_array().expect("fixtures").iter()
}

fn text<'a>(fixture: &'a Value, key: &str) -> &'a str {
    fixture[key].as_str().unwrap_or_else(|| panic!("{key} in {fixture}"))
}

/// The ways a user names a fixture, each with the poses it holds and its number of /chatter
/// messages (one per 10 poses of each file): the folder, its `metadata.yaml` and each storage
/// file (a split's file holds its part) for rosbag2; the file for ROS 1.
fn named_paths(dir: &Path, fixture: &Value, poses: &[Pose]) -> Vec<(PathBuf, Vec<Pose>, usize)> {
    let files: Vec<PathBuf> =
        fixture["files"].as_array().expect("files").iter().map(|f| dir.join(f.as_str().expect("file"))).collect();
    let chatter = poses.len().div_ceil(10);
    if text(fixture, "kind") == "ros1" {
        return vec![(files[0].clone(), poses.to_vec(), chatter)];
    }
    let third = poses.len().div_ceil(files.len());
    let parts: Vec<Vec<Pose>> =
        (0..files.len()).map(|index| poses.iter().skip(index * third).take(third).copied().collect()).collect();
    let chatter: usize = parts.iter().map(|part| part.len().div_ceil(10)).sum();
    let folder = dir.join(text(fixture, "folder"));
    let mut paths =
        vec![(folder.clone(), poses.to_vec(), chatter), (folder.join("metadata.yaml"), poses.to_vec(), chatter)];
    for (file, part) in files.iter().zip(parts) {
        let chatter = part.len().div_ceil(10);
        paths.push((file.clone(), part, chatter));
    }
    paths
}

/// Asserts that `table` holds exactly `poses` (stamps shifted by `shift_ns`).
fn assert_poses(table: &PoseTable, poses: &[Pose], shift_ns: i64, what: &str) {
    let stamps: Vec<i64> = poses.iter().map(|pose| pose.0 + shift_ns).collect();
    assert_eq!(table.timestamps_ns.as_deref(), Some(&stamps[..]), "{what}");
    let seconds: Vec<f64> = stamps.iter().map(|&ns| loops_io::seconds_of_ns(ns)).collect();
    assert_eq!(table.timestamps_s, seconds, "{what}");
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for (i, (got, want)) in table.positions.iter().zip(poses).enumerate() {
        assert_eq!(bits(got), bits(&want.1), "{what}: position {i}");
    }
    let orientations = table.orientations_xyzw.as_ref().expect("orientations");
    for (i, (got, want)) in orientations.iter().zip(poses).enumerate() {
        assert_eq!(bits(got), bits(&want.2), "{what}: orientation {i}");
    }
    assert_eq!(table.len(), poses.len(), "{what}");
}

/// Frame pairs by topic: `(topic, [(parent, child, transforms)])`.
type TopicPairs<'a> = Vec<(&'a str, Vec<(&'a str, &'a str, u64)>)>;

fn check_fixture(dir: &Path, fixture: &Value, poses: &[Pose], delay_ns: i64) {
    let topic = text(fixture, "topic");
    let ros1 = text(fixture, "kind") == "ros1";
    for (path, part, chatter) in named_paths(dir, fixture, poses) {
        let what = format!("{} ({})", path.display(), text(fixture, "name"));
        if part.is_empty() {
            continue;
        }
        // The format from the path, and the one pose topic picked (over /tf and /chatter).
        let expected_format = if ros1 {
            Format::Ros1
        } else if path.extension().is_some_and(|e| e == "mcap") {
            Format::Mcap
        } else {
            Format::Rosbag2
        };
        assert_eq!(Format::detect(&path), Some(expected_format), "{what}");
        let table = read_trajectory(&path, None).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_poses(&table, &part, 0, &what);
        let sources = table.messages.as_ref().expect("message sources");
        assert_eq!(sources.topic, topic, "{what}");
        assert_eq!(sources.messages.len(), part.len());
        assert!(sources.files.iter().all(|file| file.is_file()), "{what}: {:?}", sources.files);
        // The log time, and the same poses from /tf, odom -> base_link (and tf/tfMessage).
        let options = |topic: &str| {
            let mut options = loops_io::ReadOptions::default();
            options.mcap = McapOptions::default().topic(topic);
            options
        };
        let mut log = options(topic);
        log.mcap = log.mcap.time(TimeSource::Log);
        assert_poses(&read_trajectory_with(&path, &log).unwrap(), &part, delay_ns, &format!("{what} log time"));
        let tf_topics: &[&str] = if ros1 { &["/tf", "/tf_old"] } else { &["/tf"] };
        for tf in tf_topics {
            let mut read = options(tf);
            let error = read_trajectory_with(&path, &read).unwrap_err();
            assert!(matches!(error, IoError::FramePair { .. }), "{what}: {error}");
            read.mcap = read.mcap.frames("odom", "base_link");
            let table = read_trajectory_with(&path, &read).unwrap_or_else(|e| panic!("{what} {tf}: {e}"));
            assert_poses(&table, &part, 0, &format!("{what} {tf}"));
        }
        // The frame pairs of each transform topic: map -> odom (identity) and odom -> base_link
        // (the pose) in every message.
        let pairs = loops_io::list_frame_pairs(&path).unwrap_or_else(|e| panic!("{what}: {e}"));
        let counted: TopicPairs<'_> = pairs
            .iter()
            .map(|(topic, pairs)| {
                (topic.as_str(), pairs.iter().map(|p| (p.parent.as_str(), p.child.as_str(), p.count)).collect())
            })
            .collect();
        let n = part.len() as u64;
        let expected: TopicPairs<'_> =
            tf_topics.iter().map(|&tf| (tf, vec![("map", "odom", n), ("odom", "base_link", n)])).collect();
        assert_eq!(counted, expected, "{what}");
        // The topic list.
        let topics = list_topics(&path).unwrap_or_else(|e| panic!("{what}: {e}"));
        let names: Vec<&str> = topics.iter().map(|t| t.topic.as_str()).collect();
        let mut want = vec!["/chatter", topic, "/tf"];
        if ros1 {
            want.push("/tf_old");
        }
        want.sort_unstable();
        assert_eq!(names, want, "{what}");
        for info in &topics {
            let count = if info.topic == "/chatter" { chatter } else { part.len() };
            assert_eq!(info.message_count, count as u64, "{what}: {info}");
            let pose_type = match info.topic.as_str() {
                "/pose" => Some(PoseType::PoseStamped),
                "/odom" => Some(PoseType::Odometry),
                "/tf" | "/tf_old" => Some(PoseType::TfMessage),
                _ => None,
            };
            assert_eq!(info.pose_type, pose_type, "{what}: {info}");
            assert_eq!(info.message_encoding, if ros1 { "ros1" } else { "cdr" }, "{what}");
            let first = part[0].0 + delay_ns;
            let last = part[part.len() - 1].0 + delay_ns;
            if info.topic != "/chatter" {
                assert_eq!(info.log_time_span_ns, Some((first as u64, last as u64)), "{what}: {info}");
            }
        }
    }
}

#[test]
fn every_fixture_reads_back_exactly_every_way() {
    let (dir, manifest, poses) = small_or_skip!();
    let delay = manifest["log_delay_ns"].as_i64().expect("delay");
    let mut count = 0;
    for fixture in fixtures(manifest) {
        check_fixture(dir, fixture, poses, delay);
        count += 1;
    }
    assert_eq!(count, 22, "16 rosbag2 bags and 6 ROS 1 bags");
}

#[test]
fn the_readers_of_each_kind_agree_with_the_dispatch() {
    let (dir, manifest, poses) = small_or_skip!();
    for fixture in fixtures(manifest) {
        let options = McapOptions::default();
        let table = match text(fixture, "kind") {
            "ros1" => read_ros1(dir.join(text(fixture, "name")), &options),
            _ => read_rosbag2(dir.join(text(fixture, "folder")), &options),
        }
        .unwrap();
        assert_poses(&table, poses, 0, text(fixture, "name"));
    }
}

#[test]
fn sqlite_sources_are_rows_and_ros1_sources_are_chunk_bytes() {
    let (dir, _, _) = small_or_skip!();
    let table = read_trajectory(dir.join("r2-sqlite3-none-PoseStamped"), None).unwrap();
    let sources = table.messages.unwrap();
    let location = sources.location(0).unwrap();
    assert!(location.to_string().ends_with("topic /pose, message at row 1"), "{location}");
    let table = read_trajectory(dir.join("ros1-bz2-Odometry.bag"), None).unwrap();
    let location = table.messages.unwrap().location(3).unwrap();
    assert!(location.offset_in_chunk.is_some());
    assert!(location.to_string().contains("topic /odom, message at byte "), "{location}");
}

// ---- broken bags ----------------------------------------------------------------------------

/// A scratch copy of a fixture, in a folder of its own.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("bag-scratch").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
    }
}

#[test]
fn truncated_ros1_bags_name_the_file_and_offset() {
    let (dir, _, _) = small_or_skip!();
    let scratch = scratch("ros1-cut");
    for compression in ["none", "bz2", "lz4"] {
        let bytes = std::fs::read(dir.join(format!("ros1-{compression}-PoseStamped.bag"))).unwrap();
        let path = scratch.join("cut.bag");
        let step = (bytes.len() / 97).max(1);
        for cut in (0..bytes.len()).step_by(step).chain([bytes.len() - 1]) {
            std::fs::write(&path, &bytes[..cut]).unwrap();
            for result in [read_ros1(&path, &McapOptions::default()).map(|_| ()), list_topics(&path).map(|_| ())] {
                let error = result.expect_err(&format!("{compression} cut at {cut}"));
                let message = error.to_string();
                assert!(message.starts_with(&format!("{} offset ", path.display())), "{cut}: {message}");
                assert!(matches!(error, IoError::Ros1 { .. }), "{cut}: {error:?}");
                assert!(error.offset().is_some_and(|offset| offset <= cut as u64), "{cut}: {message}");
            }
        }
    }
    let error = read_ros1(scratch.join("missing.bag"), &McapOptions::default()).unwrap_err();
    assert!(matches!(error, IoError::Open { .. }), "{error}");
    let path = scratch.join("old.bag");
    std::fs::write(&path, b"#ROSBAG V1.2\nxxxxxxxxxxxxxxx").unwrap();
    let error = read_ros1(&path, &McapOptions::default()).unwrap_err();
    assert!(error.to_string().contains("format \"1.2\", which this crate does not read"), "{error}");
}

#[test]
fn a_corrupt_ros1_chunk_names_its_offset() {
    let (dir, _, _) = small_or_skip!();
    let scratch = scratch("ros1-flip");
    for compression in ["bz2", "lz4"] {
        let mut bytes = std::fs::read(dir.join(format!("ros1-{compression}-Odometry.bag"))).unwrap();
        // The first chunk's data starts after the 4096-byte bag header record and the chunk's
        // header: corrupt bytes inside it.
        let at = 4096 + 13 + 200;
        for byte in &mut bytes[at..at + 8] {
            *byte ^= 0x5a;
        }
        let path = scratch.join("flip.bag");
        std::fs::write(&path, &bytes).unwrap();
        let error = read_ros1(&path, &McapOptions::default()).unwrap_err();
        let message = error.to_string();
        assert!(message.starts_with(&format!("{} offset ", path.display())), "{message}");
    }
}

#[test]
fn broken_rosbag2_bags_say_what_and_where() {
    let (dir, _, _) = small_or_skip!();
    let scratch = scratch("rosbag2-broken");

    // A truncated .db3: SQLite's complaint, with the file.
    let folder = scratch.join("cut");
    copy_folder(&dir.join("r2-sqlite3-none-PoseStamped"), &folder);
    let db3 = folder.join("r2-sqlite3-none-PoseStamped.db3");
    let bytes = std::fs::read(&db3).unwrap();
    for cut in [0, 10, 100, 4096, bytes.len() / 2, bytes.len() - 100] {
        std::fs::write(&db3, &bytes[..cut]).unwrap();
        let error = read_trajectory(&folder, None).unwrap_err();
        let message = error.to_string();
        assert!(message.starts_with(&db3.display().to_string()), "{cut}: {message}");
        assert!(matches!(error, IoError::Sqlite { .. }), "{cut}: {error:?}");
    }

    // A message whose data is garbage: the row is named.
    let folder = scratch.join("garbage");
    copy_folder(&dir.join("r2-sqlite3-message-PoseStamped"), &folder);
    let db3 = folder.join("r2-sqlite3-message-PoseStamped.db3");
    {
        let db = rusqlite::Connection::open(&db3).unwrap();
        db.execute("UPDATE messages SET data = x'28b52ffd0000ffff' WHERE id = 4", []).unwrap();
    }
    let error = read_trajectory(&folder, None).unwrap_err();
    let message = error.to_string();
    assert!(
        message.starts_with(&format!(
            "{} topic /pose, message at row 4: the zstd compressed message does not decompress",
            db3.display()
        )),
        "{message}"
    );

    // A metadata.yaml listing a missing file, or not YAML, or not a bag's.
    let folder = scratch.join("missing");
    copy_folder(&dir.join("r2-mcap-split3-PoseStamped"), &folder);
    std::fs::remove_file(folder.join("r2-mcap-split3-PoseStamped_1.mcap")).unwrap();
    let error = read_trajectory(&folder, None).unwrap_err();
    assert!(matches!(error, IoError::Bag { .. }), "{error:?}");
    assert!(
        error.to_string().contains("\"r2-mcap-split3-PoseStamped_1.mcap\" that the bag lists is missing"),
        "{error}"
    );
    std::fs::write(folder.join("metadata.yaml"), "rosbag2_bagfile_information:\n  relative_file_paths: [a\n").unwrap();
    let error = read_trajectory(folder.join("metadata.yaml"), None).unwrap_err();
    assert!(matches!(error, IoError::Parse { .. }), "{error:?}");
    std::fs::write(folder.join("metadata.yaml"), "just: text\n").unwrap();
    let error = read_trajectory(&folder, None).unwrap_err();
    assert!(error.to_string().contains("not a rosbag2 metadata.yaml"), "{error}");

    // A file-compressed bag whose file is cut short.
    let folder = scratch.join("zstd-cut");
    copy_folder(&dir.join("r2-mcap-file-PoseStamped"), &folder);
    let zstd = folder.join("r2-mcap-file-PoseStamped.mcap.zstd");
    let bytes = std::fs::read(&zstd).unwrap();
    for cut in [0, 3, 20, bytes.len() / 2, bytes.len() - 1] {
        std::fs::write(&zstd, &bytes[..cut]).unwrap();
        let error = read_trajectory(&folder, None).unwrap_err();
        assert!(error.to_string().starts_with(&zstd.display().to_string()), "{cut}: {error}");
    }

    // A folder that is no bag.
    let empty = scratch.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let error = read_trajectory(&empty, None).unwrap_err();
    assert!(error.to_string().contains("no metadata.yaml and no .db3 or .mcap file"), "{error}");
}

#[test]
fn a_folder_without_metadata_reads_its_splits_in_order() {
    let (dir, _, poses) = small_or_skip!();
    let folder = scratch("no-metadata");
    copy_folder(&dir.join("r2-sqlite3-split3-Odometry"), &folder);
    std::fs::remove_file(folder.join("metadata.yaml")).unwrap();
    let table = read_trajectory(&folder, None).unwrap();
    assert_poses(&table, poses, 0, "no metadata");
    let files = &table.messages.unwrap().files;
    let names: Vec<_> = files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(
        names,
        ["r2-sqlite3-split3-Odometry_0.db3", "r2-sqlite3-split3-Odometry_1.db3", "r2-sqlite3-split3-Odometry_2.db3"]
    );
}

// ---- KITTI 00: the acceptance trajectory ----------------------------------------------------

/// The KITTI fixtures: folder, manifest, the poses written, the text file's table.
type Kitti = (PathBuf, Value, Vec<Pose>, PoseTable);

fn kitti() -> Option<&'static Kitti> {
    static FIXTURES: OnceLock<Option<Kitti>> = OnceLock::new();
    FIXTURES
        .get_or_init(|| {
            let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/kitti_odometry/00.txt");
            if !path.is_file() {
                support::skipped(
                    "the KITTI bags",
                    &format!("no {} (it lives beside the checkout in CI)", path.display()),
                );
                return None;
            }
            let table = read_kitti(&path, &Timing::FromFile).expect("KITTI 00");
            let orientations = table.orientations_xyzw.as_ref().expect("KITTI orientations");
            let poses: Vec<Pose> = (0..table.len())
                .map(|i| ((table.timestamps_s[i] * 1e9).round() as i64, table.positions[i], orientations[i]))
                .collect();
            make_fixtures("kitti00", &poses).map(|(dir, manifest)| (dir, manifest, poses, table))
        })
        .as_ref()
}

/// The components of a trajectory, by what does not depend on the time cells' last bits.
type Component = (bool, u64, u64, [usize; 2], [usize; 2]);

fn components(table: &PoseTable) -> Vec<Component> {
    let trajectory = table.to_trajectory().expect("trajectory");
    let loops = find_loops(&trajectory, &Euclidean, 10.0).expect("loops");
    loops.components().iter().map(|c| (c.trivial, c.pair_count, c.holes, c.i_range, c.j_range)).collect()
}

#[test]
fn kitti_00_reads_bit_exactly_from_every_bag_every_way() {
    let Some((dir, manifest, poses, kitti)) = kitti() else { return };
    assert_eq!(poses.len(), 4541);
    let delay = manifest["log_delay_ns"].as_i64().expect("delay");
    let expected = components(kitti);
    let revisits = expected.iter().filter(|c| !c.0).count();
    assert!(revisits > 0, "KITTI 00 revisits its streets");
    let mut checked = Vec::new();
    for fixture in fixtures(manifest) {
        check_fixture(dir, fixture, poses, delay);
        for (path, part, _) in named_paths(dir, fixture, poses) {
            if part.len() != poses.len() {
                continue;
            }
            let table = read_trajectory(&path, None).unwrap();
            // The text file's positions and orientations, bit for bit, and its loop components.
            assert_eq!(table.positions, kitti.positions, "{}", path.display());
            assert_eq!(table.orientations_xyzw, kitti.orientations_xyzw, "{}", path.display());
            assert_eq!(components(&table), expected, "{}", path.display());
            checked.push(path);
        }
    }
    // Folder and metadata.yaml of 16 rosbag2 bags, the file of the 12 single-file ones, 6 ROS 1.
    assert_eq!(checked.len(), 16 * 2 + 12 + 6);
}
