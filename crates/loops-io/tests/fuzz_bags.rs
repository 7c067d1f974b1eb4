//! Fuzz targets (proptest) for the bag readers: ROS 1 bags, ROS 1 and compressed CDR messages,
//! rosbag2 sqlite3 files, and rosbag2 folders (`metadata.yaml`, file compression). Valid input
//! reads back exactly; random bytes and structured mutations of valid input give an error
//! naming the file, never a panic.
//!
//! Each target runs 256 cases from a fixed seed, so a failure replays. For a long run, set
//! `LOOPS_FUZZ_SECONDS`: each target then runs rounds of 256 cases (the seed advancing each
//! round) until that many seconds have passed, and prints its case count; run one target at a
//! time, in release:
//! `LOOPS_FUZZ_SECONDS=600 cargo test --release -p loops-io --test fuzz_bags ros1_bags -- --nocapture`.
//! The figures of the last long runs are in `tests/FUZZ.md`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use loops_io::{
    McapOptions, MessageEncoding, PoseType, TimeSource, decode_poses, list_topics, read_ros1, read_rosbag2,
};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};

mod support;
use support::logs::{self, PoseStamped as Pose};
use support::{ROS_TYPES, mutate, mutation, mutations};

/// Runs `test` on values of `strategy`: 256 cases from `seed`, or rounds of them for
/// `LOOPS_FUZZ_SECONDS` seconds.
fn fuzz<S: Strategy>(name: &str, seed: u64, strategy: S, test: impl Fn(S::Value) -> Result<(), TestCaseError>) {
    let budget = std::env::var("LOOPS_FUZZ_SECONDS").ok().and_then(|s| s.parse::<f64>().ok());
    let start = Instant::now();
    let mut cases = 0u64;
    let mut round = 0u64;
    loop {
        let config = Config { cases: 256, failure_persistence: None, ..Config::default() };
        let mut bytes = [0u8; 32];
        bytes[..8].copy_from_slice(&seed.to_le_bytes());
        bytes[8..16].copy_from_slice(&round.to_le_bytes());
        let mut runner = TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &bytes));
        if let Err(error) = runner.run(&strategy, &test) {
            panic!("{name}, round {round} (seed {seed:#x}): {error}");
        }
        cases += 256;
        round += 1;
        match budget {
            Some(seconds) if start.elapsed() < Duration::from_secs_f64(seconds) => {}
            _ => break,
        }
    }
    if budget.is_some() {
        let seconds = start.elapsed().as_secs_f64();
        println!("fuzz {name}: {cases} cases in {seconds:.0} s ({:.0} cases/s)", cases as f64 / seconds);
    }
}

/// A scratch file in the target folder (one per target: targets run in parallel threads).
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz-bags");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir.join(name)
}

fn pose() -> impl Strategy<Value = Pose> {
    (
        (0u32..i32::MAX as u32, 0u32..1_000_000_000),
        "[a-z_/]{0,10}",
        proptest::array::uniform3(any::<f64>()),
        proptest::array::uniform4(any::<f64>()),
    )
        .prop_map(|(stamp, frame, position, orientation)| Pose { seq: 3, stamp, frame, position, orientation })
}

fn stamp_ns(pose: &Pose) -> i64 {
    i64::from(pose.stamp.0) * 1_000_000_000 + i64::from(pose.stamp.1)
}

fn bits<const N: usize>(values: [f64; N]) -> [u64; N] {
    values.map(f64::to_bits)
}

/// Every error names the file first.
fn check_error(result: loops_io::Result<impl Sized>, path: &Path) -> Result<(), TestCaseError> {
    if let Err(error) = result {
        let message = error.to_string();
        prop_assert!(message.starts_with(&path.display().to_string()), "{}", message);
    }
    Ok(())
}

// ---- ROS 1 messages, and CDR messages compressed by rosbag2 ----------------------------------

#[test]
fn messages() {
    let strategy = (pose(), mutations(), proptest::collection::vec(any::<u8>(), 0..300), any::<bool>());
    fuzz("ROS 1 and compressed CDR messages", 0x0051, strategy, |(pose, mutations, random, lz4)| {
        let ros1 = pose.ros1();
        let got = decode_poses(PoseType::PoseStamped, MessageEncoding::Ros1, &ros1)
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(got.len(), 1);
        prop_assert_eq!(got[0].stamp_ns, stamp_ns(&pose));
        prop_assert_eq!(bits(got[0].position), bits(pose.position));
        prop_assert_eq!(bits(got[0].orientation_xyzw), bits(pose.orientation));
        prop_assert_eq!(&got[0].frame_id, &pose.frame);
        for cut in 0..ros1.len() {
            prop_assert!(decode_poses(PoseType::PoseStamped, MessageEncoding::Ros1, &ros1[..cut]).is_err());
        }
        let cdr = pose.cdr();
        let compressed = if lz4 {
            let mut encoder = lz4_flex::frame::FrameEncoder::new(Vec::new());
            encoder.write_all(&cdr).expect("lz4");
            encoder.finish().expect("lz4")
        } else {
            zstd::bulk::compress(&cdr, 3).expect("zstd")
        };
        let got = decode_poses(PoseType::PoseStamped, MessageEncoding::Cdr, &compressed)
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(bits(got[0].position), bits(pose.position));
        for pose_type in ROS_TYPES {
            let _ = decode_poses(pose_type, MessageEncoding::Ros1, &random);
            let _ = decode_poses(pose_type, MessageEncoding::Ros1, &mutate(&ros1, &mutations));
            let _ = decode_poses(pose_type, MessageEncoding::Cdr, &mutate(&compressed, &mutations));
            let mut framed = if lz4 { vec![0x04, 0x22, 0x4d, 0x18] } else { vec![0x28, 0xb5, 0x2f, 0xfd] };
            framed.extend(&random);
            let _ = decode_poses(pose_type, MessageEncoding::Cdr, &framed);
        }
        Ok(())
    });
}

// ---- ROS 1 bags -----------------------------------------------------------------------------

/// A ROS 1 bag of `poses` ([`logs::ros1_bag_of`], independent of the crate's reader).
fn ros1_bag(poses: &[Pose], compression: &str, per_chunk: usize) -> Vec<u8> {
    let poses: Vec<((u32, u32), Vec<u8>)> = poses.iter().map(|pose| (pose.stamp, pose.ros1())).collect();
    logs::ros1_bag_of(&poses, compression, per_chunk, &[])
}

#[test]
fn ros1_bags() {
    let strategy = (
        proptest::collection::vec(pose(), 1..10),
        prop_oneof![Just("none"), Just("bz2"), Just("lz4")],
        1usize..5,
        mutations(),
        proptest::collection::vec(any::<u8>(), 0..600),
    );
    let path = scratch("ros1.bag");
    fuzz("ROS 1 bags", 0xB1, strategy, |(poses, compression, per_chunk, mutations, random)| {
        let bytes = ros1_bag(&poses, compression, per_chunk);
        std::fs::write(&path, &bytes).expect("scratch");
        let table = read_ros1(&path, &McapOptions::default().time(TimeSource::Log))
            .map_err(|e| TestCaseError::fail(e.to_string()))?;
        let mut want = poses.clone();
        want.sort_by_key(stamp_ns);
        prop_assert_eq!(table.timestamps_ns.clone().unwrap(), want.iter().map(stamp_ns).collect::<Vec<_>>());
        let topics = list_topics(&path).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(topics.iter().map(|t| t.message_count).collect::<Vec<_>>(), vec![poses.len() as u64; 2]);
        std::fs::write(&path, mutate(&bytes, &mutations)).expect("scratch");
        check_error(read_ros1(&path, &McapOptions::default()), &path)?;
        check_error(list_topics(&path), &path)?;
        let mut noise = bytes[..13 + 4096].to_vec();
        noise.extend(&random);
        std::fs::write(&path, &noise).expect("scratch");
        check_error(read_ros1(&path, &McapOptions::default()), &path)?;
        std::fs::write(&path, &random).expect("scratch");
        prop_assert!(read_ros1(&path, &McapOptions::default()).is_err());
        Ok(())
    });
}

// ---- rosbag2 sqlite3 files ------------------------------------------------------------------

/// A rosbag2 sqlite3 file of `poses` at the times 0, 1, 2, ... ns ([`logs::sqlite_bag_of`]).
fn sqlite_bag(path: &Path, poses: &[Pose], compress: bool) {
    let poses: Vec<(i64, Vec<u8>)> = poses.iter().enumerate().map(|(i, pose)| (i as i64, pose.cdr())).collect();
    logs::sqlite_bag_of(path, &poses, compress);
}

#[test]
fn sqlite3_files() {
    // SQLite files are built once (a database per case would be slow) and mutated per case.
    let dir = scratch("sqlite3");
    std::fs::create_dir_all(&dir).expect("scratch");
    let mut runner = TestRunner::new_with_rng(Config::default(), TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]));
    let mut bases = Vec::new();
    for (index, count) in [1usize, 5, 40, 300].into_iter().enumerate() {
        let poses = proptest::collection::vec(pose(), count).new_tree(&mut runner).expect("poses").current();
        let path = dir.join(format!("base{index}.db3"));
        sqlite_bag(&path, &poses, index % 2 == 1);
        let table = read_rosbag2(&path, &McapOptions::default().time(TimeSource::Log)).expect("valid sqlite3 bag");
        assert_eq!(table.len(), count);
        for (i, pose) in poses.iter().enumerate() {
            assert_eq!(bits(table.positions[i]), bits(pose.position));
        }
        bases.push(std::fs::read(&path).expect("base"));
    }
    let path = dir.join("mutated.db3");
    let strategy = (0..bases.len(), proptest::collection::vec(mutation(), 1..8), any::<bool>());
    fuzz("rosbag2 sqlite3 files", 0x5013, strategy, |(base, mutations, header_only)| {
        let bytes = if header_only {
            // Mutations of the first page (the header and the schema) reach more code.
            let mut bytes = bases[base].clone();
            let head = mutate(&bytes[..4096.min(bytes.len())], &mutations);
            let end = 4096.min(bytes.len());
            bytes.splice(..end, head);
            bytes
        } else {
            mutate(&bases[base], &mutations)
        };
        std::fs::write(&path, &bytes).expect("scratch");
        check_error(read_rosbag2(&path, &McapOptions::default()), &path)?;
        check_error(read_rosbag2(&path, &McapOptions::default().topic("/chatter")), &path)?;
        check_error(list_topics(&path), &path)?;
        Ok(())
    });
}

// ---- rosbag2 folders: metadata.yaml and file compression ------------------------------------

const METADATA: &str = "rosbag2_bagfile_information:
  version: 9
  storage_identifier: sqlite3
  relative_file_paths:
  - bag_0.db3.zstd
  duration:
    nanoseconds: 100
  starting_time:
    nanoseconds_since_epoch: 0
  message_count: 10
  topics_with_message_count: []
  compression_format: zstd
  compression_mode: FILE
  files:
  - path: bag_0.db3.zstd
";

fn yaml_ish() -> impl Strategy<Value = String> {
    let token = prop_oneof![
        Just("rosbag2_bagfile_information:".to_owned()),
        Just("relative_file_paths:".to_owned()),
        Just("storage_identifier: mcap".to_owned()),
        Just("compression_mode: MESSAGE".to_owned()),
        Just("compression_format: lz4".to_owned()),
        Just("- bag_0.db3.zstd".to_owned()),
        Just("- ../../etc".to_owned()),
        Just("files: [{path: x}]".to_owned()),
        Just("  ".to_owned()),
        "[ -~]{0,12}",
    ];
    proptest::collection::vec(token, 0..12).prop_map(|tokens| tokens.join("\n"))
}

#[test]
fn rosbag2_folders() {
    let dir = scratch("folder");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch");
    let mut runner = TestRunner::new_with_rng(Config::default(), TestRng::from_seed(RngAlgorithm::ChaCha, &[9; 32]));
    let poses = proptest::collection::vec(pose(), 30).new_tree(&mut runner).expect("poses").current();
    // Beside the bag's folder: a storage file in it that metadata.yaml does not list is an error.
    let plain = dir.with_file_name("folder-plain.db3");
    sqlite_bag(&plain, &poses, false);
    let compressed = zstd::bulk::compress(&std::fs::read(&plain).expect("db3"), 3).expect("zstd");
    let storage = dir.join("bag_0.db3.zstd");
    let metadata = dir.join("metadata.yaml");
    std::fs::write(&storage, &compressed).expect("scratch");
    std::fs::write(&metadata, METADATA).expect("scratch");
    let table = read_rosbag2(&dir, &McapOptions::default()).expect("valid bag");
    assert_eq!(table.len(), poses.len());
    let strategy = (mutations(), yaml_ish(), mutations(), any::<bool>());
    fuzz(
        "rosbag2 folders (metadata.yaml, file compression)",
        0xF01D,
        strategy,
        |(yaml_mutations, text, zstd_mutations, which)| {
            let yaml = if which { mutate(METADATA.as_bytes(), &yaml_mutations) } else { text.into_bytes() };
            std::fs::write(&metadata, &yaml).expect("scratch");
            std::fs::write(&storage, &compressed).expect("scratch");
            for result in
                [read_rosbag2(&dir, &McapOptions::default()), read_rosbag2(&metadata, &McapOptions::default())]
            {
                if let Err(error) = result {
                    let message = error.to_string();
                    prop_assert!(message.starts_with(&dir.display().to_string()), "{}", message);
                }
            }
            std::fs::write(&metadata, METADATA).expect("scratch");
            std::fs::write(&storage, mutate(&compressed, &zstd_mutations)).expect("scratch");
            check_error(read_rosbag2(&storage, &McapOptions::default()), &storage)?;
            let _ = list_topics(&dir);
            Ok(())
        },
    );
}
