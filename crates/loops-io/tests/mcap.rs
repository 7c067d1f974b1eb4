//! MCAP files written by the official Python writers (`mcap`, `mcap-ros2-support`,
//! `mcap-protobuf-support`, `foxglove-schemas-protobuf`) through `make_mcap_fixtures.py`: every
//! pose type, unchunked and chunked (none, zstd, lz4), read back exactly; topic choice; several
//! files; broken files. Skipped, with a message, when python3 or the packages are missing.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use loops_io::{IoError, McapOptions, PoseType, TimeSource, list_topics, read_mcap, read_mcap_files, seconds_of_ns};
use serde_json::Value;

mod support;
use support::logs;

/// The fixture folder and its manifest, made once per script version (cached in the target
/// folder), or `None` when Python cannot make them here.
fn fixtures() -> Option<&'static (PathBuf, Value)> {
    static FIXTURES: OnceLock<Option<(PathBuf, Value)>> = OnceLock::new();
    FIXTURES.get_or_init(make_fixtures).as_ref()
}

fn make_fixtures() -> Option<(PathBuf, Value)> {
    support::mcap_fixtures()
}

/// The fixture folder and manifest, or return from the test (after the message printed once).
macro_rules! fixtures_or_skip {
    () => {
        match fixtures() {
            Some((dir, manifest)) => (dir.as_path(), manifest),
            None => return,
        }
    };
}

/// A pose as the manifest gives it.
#[derive(Debug, Clone, PartialEq)]
struct Expected {
    stamp_ns: i64,
    log_time: i64,
    publish_time: i64,
    position: [f64; 3],
    orientation: [f64; 4],
}

fn expected(poses: &Value) -> Vec<Expected> {
    let float = |v: &Value| f64::from_bits(v.as_u64().expect("bits"));
    poses
        .as_array()
        .expect("poses")
        .iter()
        .map(|pose| Expected {
            stamp_ns: pose["stamp_ns"].as_i64().expect("stamp"),
            log_time: pose["log_time"].as_i64().expect("log time"),
            publish_time: pose["publish_time"].as_i64().expect("publish time"),
            position: std::array::from_fn(|i| float(&pose["p"][i])),
            orientation: std::array::from_fn(|i| float(&pose["q"][i])),
        })
        .collect()
}

/// Reads `topic` (and `frames`) from `path` with each time source and checks every pose bit for
/// bit against `poses`.
fn check_topic(path: &Path, topic: &str, frames: Option<(&str, &str)>, poses: &[Expected], chunked: bool) {
    let what = format!("{} {topic} {frames:?}", path.display());
    for time in [TimeSource::Header, TimeSource::Log, TimeSource::Publish] {
        let mut options = McapOptions::default().topic(topic).time(time);
        if let Some((parent, child)) = frames {
            options = options.frames(parent, child);
        }
        let table = read_mcap(path, &options).unwrap_or_else(|e| panic!("{what}: {e}"));
        let mut want = poses.to_vec();
        let time_of = |pose: &Expected| match time {
            TimeSource::Header => pose.stamp_ns,
            TimeSource::Log => pose.log_time,
            _ => pose.publish_time,
        };
        want.sort_by_key(time_of);
        let stamps: Vec<i64> = want.iter().map(time_of).collect();
        assert_eq!(table.timestamps_ns.as_deref(), Some(&stamps[..]), "{what} {time:?}");
        let seconds: Vec<f64> = stamps.iter().map(|&ns| seconds_of_ns(ns)).collect();
        assert_eq!(table.timestamps_s, seconds, "{what}");
        assert_eq!(table.positions, want.iter().map(|pose| pose.position).collect::<Vec<_>>(), "{what}");
        assert_eq!(
            table.orientations_xyzw.as_deref(),
            Some(&want.iter().map(|pose| pose.orientation).collect::<Vec<_>>()[..]),
            "{what}"
        );
        assert_eq!(table.dim, 3);
        assert!(table.source_lines.is_empty());
        let sources = table.messages.as_ref().expect("message sources");
        assert_eq!(sources.topic, topic);
        assert_eq!(sources.frames, frames.map(|(p, c)| (p.to_owned(), c.to_owned())));
        assert_eq!(sources.messages.len(), poses.len());
        assert!(sources.messages.iter().all(|m| m.offset_in_chunk.is_some() == chunked), "{what}");
    }
}

#[test]
fn every_pose_type_in_every_layout_reads_back_exactly() {
    let (dir, manifest) = fixtures_or_skip!();
    let mut checked = std::collections::BTreeSet::new();
    for file in manifest["files"].as_array().expect("files") {
        let path = dir.join(file["name"].as_str().expect("name"));
        let chunked = file["chunked"].as_bool().expect("chunked");
        for (topic, entry) in file["topics"].as_object().expect("topics") {
            let schema = entry["schema"].as_str().expect("schema");
            let encoding = entry["encoding"].as_str().expect("encoding");
            let Some((pose_type, _)) = PoseType::of_channel(schema, encoding) else { continue };
            if pose_type.is_transform() {
                for (pair, poses) in entry["pairs"].as_object().expect("pairs") {
                    let (parent, child) = pair.split_once("->").expect("pair");
                    check_topic(&path, topic, Some((parent, child)), &expected(poses), chunked);
                }
            } else {
                check_topic(&path, topic, None, &expected(&entry["poses"]), chunked);
            }
            checked.insert((pose_type, encoding.to_owned(), file["compression"].as_str().expect("mode").to_owned()));
        }
    }
    // 5 ROS 2 types × 4 layouts + 5 Foxglove types × 2 encodings × 4 layouts.
    assert_eq!(checked.len(), 5 * 4 + 5 * 2 * 4, "{checked:?}");
}

#[test]
fn topics_are_listed_with_counts_types_and_spans() {
    let (dir, manifest) = fixtures_or_skip!();
    let file = &manifest["files"][0];
    assert_eq!(file["name"], "ros2_unchunked.mcap");
    for name in ["ros2_unchunked.mcap", "ros2_zstd.mcap", "ros2_lz4.mcap"] {
        let topics = list_topics(dir.join(name)).unwrap();
        let names: Vec<&str> = topics.iter().map(|t| t.topic.as_str()).collect();
        assert_eq!(names, ["/custom", "/odom", "/pose", "/pose_cov", "/status", "/tf", "/transform"]);
        for info in &topics {
            let entry = &file["topics"][&info.topic];
            assert_eq!(info.schema_name, entry["schema"].as_str().unwrap());
            assert_eq!((info.schema_encoding.as_str(), info.message_encoding.as_str()), ("ros2msg", "cdr"));
            assert_eq!(info.message_count, entry["count"].as_u64().unwrap());
            let pose_type = PoseType::of_channel(&info.schema_name, "cdr").map(|t| t.0);
            assert_eq!(info.pose_type, pose_type);
        }
        let odom = topics.iter().find(|t| t.topic == "/odom").unwrap();
        assert_eq!(odom.to_string(), "/odom (nav_msgs/msg/Odometry, cdr, 24 messages)");
    }
    // Log time span of the pose topic, from the unchunked file's manifest.
    let poses = expected(&file["topics"]["/pose"]["poses"]);
    let topics = list_topics(dir.join("ros2_unchunked.mcap")).unwrap();
    let pose = topics.iter().find(|t| t.topic == "/pose").unwrap();
    let first = poses.iter().map(|p| p.log_time as u64).min().unwrap();
    let last = poses.iter().map(|p| p.log_time as u64).max().unwrap();
    assert_eq!(pose.log_time_span_ns, Some((first, last)));
    let protobuf = list_topics(dir.join("protobuf_lz4.mcap")).unwrap();
    assert!(protobuf.iter().all(|t| t.schema_encoding == "protobuf" && t.pose_type.is_some()), "{protobuf:?}");
}

#[test]
fn the_one_pose_topic_is_picked() {
    let (dir, manifest) = fixtures_or_skip!();
    let path = dir.join("auto_pick.mcap");
    // /robot/pose beside /tf and /status: poses come before transforms.
    let table = read_mcap(&path, &McapOptions::default()).unwrap();
    let sources = table.messages.as_ref().unwrap();
    assert_eq!(
        (sources.topic.as_str(), sources.schema_name.as_str()),
        ("/robot/pose", "geometry_msgs/msg/PoseStamped")
    );
    let poses = expected(&manifest["special"]["auto_pick.mcap"]["/robot/pose"]["poses"]);
    assert_eq!(table.positions, poses.iter().map(|p| p.position).collect::<Vec<_>>());
    // By extension, through the reader of every format.
    assert_eq!(loops_io::read_trajectory(&path, None).unwrap(), table);
    let options = loops_io::ReadOptions::default().mcap(McapOptions::default().topic("/tf"));
    assert_eq!(loops_io::read_trajectory_with(&path, &options).unwrap().messages.unwrap().topic, "/tf");
    // /tf holds one pair only: it is taken without naming it.
    let table = read_mcap(&path, &McapOptions::default().topic("/tf")).unwrap();
    assert_eq!(table.messages.unwrap().frames, Some(("map".to_owned(), "base_link".to_owned())));
    // The table becomes a trajectory, SE(3) included.
    let table = read_mcap(&path, &McapOptions::default()).unwrap();
    let traj = table.to_trajectory_for(&"se3(rotation_weight_m_per_rad=10)".parse().unwrap(), None).unwrap();
    assert_eq!(traj.len(), 24);
}

#[test]
fn several_pose_topics_are_an_error_listing_them() {
    let (dir, _) = fixtures_or_skip!();
    let path = dir.join("two_pose_topics.mcap");
    let error = read_mcap(&path, &McapOptions::default()).unwrap_err();
    assert!(matches!(&error, IoError::AmbiguousTopic { candidates, .. } if candidates.len() == 2), "{error:?}");
    assert_eq!(
        error.to_string(),
        format!(
            "{}: 2 topics hold poses, name one: /a (geometry_msgs/msg/PoseStamped, cdr, 3 messages), \
             /b (nav_msgs/msg/Odometry, cdr, 3 messages)",
            path.display()
        )
    );
    // Each one by name.
    for topic in ["/a", "/b"] {
        let table = read_mcap(&path, &McapOptions::default().topic(topic)).unwrap();
        assert_eq!(table.timestamps_s, [1.0, 2.0, 3.0]);
    }
}

#[test]
fn transform_topics_need_a_pair_when_they_have_several() {
    let (dir, _) = fixtures_or_skip!();
    let path = dir.join("ros2_zstd.mcap");
    let error = read_mcap(&path, &McapOptions::default().topic("/tf")).unwrap_err();
    assert_eq!(error.topic(), Some("/tf"));
    assert!(
        error.to_string().ends_with(
            "topic /tf: 3 frame pairs (parent -> child), name one: base_link -> laser (5), map -> odom (24), \
             odom -> base_link (24)"
        ),
        "{error}"
    );
    // A pair no transform holds is composed along map -> odom -> base_link -> laser, at the
    // five stamps of base_link -> laser (the link nearest the child); frames not linked fail.
    let table = read_mcap(&path, &McapOptions::default().topic("/tf").frames("map", "laser")).unwrap();
    assert_eq!(table.len(), 5);
    let error = read_mcap(&path, &McapOptions::default().topic("/tf").frames("world", "camera")).unwrap_err();
    assert!(error.to_string().contains(r#"no transform from "world" to "camera"; the frame pairs"#), "{error}");
    let error = read_mcap(&path, &McapOptions::default().topic("/tf").frames("map", "camera")).unwrap_err();
    assert!(matches!(error, IoError::FrameTree { .. }), "{error:?}");
    assert!(error.to_string().contains(r#"frame "camera" is on no transform"#), "{error}");
    // Foxglove FrameTransforms likewise.
    let path = dir.join("protobuf_zstd.mcap");
    let error = read_mcap(&path, &McapOptions::default().topic("/fox/tfs")).unwrap_err();
    assert!(matches!(&error, IoError::FramePair { pairs, wanted: None, .. } if pairs.len() == 2), "{error:?}");
}

/// Frame pairs by topic: `(topic, [(parent, child, transforms)])`.
type TopicPairs = Vec<(String, Vec<(String, String, u64)>)>;

#[test]
fn frame_pairs_are_listed_as_the_writers_wrote_them() {
    let (dir, manifest) = fixtures_or_skip!();
    let mut with_pairs = 0;
    for file in manifest["files"].as_array().expect("files") {
        let name = file["name"].as_str().expect("name");
        let path = dir.join(name);
        // From the manifest: each transform topic's pairs, with the transforms written.
        let mut expected: TopicPairs = Vec::new();
        for (topic, entry) in file["topics"].as_object().expect("topics") {
            let schema = entry["schema"].as_str().expect("schema");
            let encoding = entry["encoding"].as_str().expect("encoding");
            let Some((pose_type, _)) = PoseType::of_channel(schema, encoding) else { continue };
            if !pose_type.is_transform() {
                continue;
            }
            let mut pairs: Vec<(String, String, u64)> = entry["pairs"]
                .as_object()
                .expect("pairs")
                .iter()
                .map(|(pair, poses)| {
                    let (parent, child) = pair.split_once("->").expect("pair");
                    (parent.to_owned(), child.to_owned(), poses.as_array().expect("poses").len() as u64)
                })
                .collect();
            pairs.sort();
            expected.push((topic.clone(), pairs));
        }
        expected.sort();
        let listed: TopicPairs = loops_io::list_frame_pairs(&path)
            .unwrap()
            .into_iter()
            .map(|(topic, pairs)| (topic, pairs.into_iter().map(|p| (p.parent, p.child, p.count)).collect()))
            .collect();
        assert_eq!(listed, expected, "{name}");
        with_pairs += usize::from(listed.iter().any(|(_, pairs)| pairs.len() > 1));
    }
    assert!(with_pairs > 0, "some file has a transform topic with several pairs");
    // The pairs a read without --frames names are the ones listed.
    let path = dir.join("ros2_zstd.mcap");
    let listed = loops_io::list_frame_pairs(&path).unwrap();
    let tf = &listed.iter().find(|(topic, _)| topic == "/tf").expect("/tf").1;
    match read_mcap(&path, &McapOptions::default().topic("/tf")).unwrap_err() {
        IoError::FramePair { pairs, .. } => assert_eq!(&pairs, tf),
        other => panic!("{other}"),
    }
}

#[test]
fn files_of_one_recording_make_one_trajectory_ordered_by_time() {
    let (dir, manifest) = fixtures_or_skip!();
    let poses = expected(&manifest["special"]["split"]["/pose"]["poses"]);
    let files = [dir.join("split_odd.mcap"), dir.join("split_even.mcap")];
    let table = read_mcap_files(&files, &McapOptions::default()).unwrap();
    let stamps: Vec<i64> = poses.iter().map(|p| p.stamp_ns).collect();
    assert_eq!(table.timestamps_ns.as_deref(), Some(&stamps[..]));
    assert_eq!(table.positions, poses.iter().map(|p| p.position).collect::<Vec<_>>());
    let sources = table.messages.as_ref().unwrap();
    assert_eq!(sources.files, files);
    // Pose k was written to the even file when k is even: file 1 of the two given.
    let from: Vec<usize> = sources.messages.iter().map(|m| m.file).collect();
    assert_eq!(from, (0..poses.len()).map(|k| 1 - k % 2).collect::<Vec<_>>());
    let traj = table.to_trajectory().unwrap();
    assert_eq!(traj.len(), 48);
    // Log times (stamp + 5 ns) order the same way.
    let table = read_mcap_files(&files, &McapOptions::default().time(TimeSource::Log)).unwrap();
    assert_eq!(table.timestamps_ns.unwrap(), stamps.iter().map(|s| s + 5).collect::<Vec<_>>());
}

#[test]
fn duplicate_stamps_are_reported_at_their_messages() {
    let (dir, _) = fixtures_or_skip!();
    // PosesInFrame: two poses per message, at the message's stamp.
    let path = dir.join("protobuf_unchunked.mcap");
    let table = read_mcap(&path, &McapOptions::default().topic("/fox/poses")).unwrap();
    let error = table.to_trajectory().unwrap_err();
    let sources = table.messages.as_ref().unwrap();
    let offset = sources.messages[1].offset;
    assert_eq!(sources.messages[0], sources.messages[1]);
    assert_eq!(error.offset(), Some(offset));
    assert_eq!(error.topic(), Some("/fox/poses"));
    let message = error.to_string();
    assert!(
        message.starts_with(&format!("{} topic /fox/poses, message at offset {offset}: ", path.display())),
        "{message}"
    );
    assert!(
        message.ends_with(&format!(
            "(message at offset {offset}); drop_duplicate_stamps=True (--drop-duplicate-stamps) keeps the first \
             pose of each stamp"
        )),
        "{message}"
    );
    // In a chunk, the message is placed in it.
    let path = dir.join("protobuf_lz4.mcap");
    let table = read_mcap(&path, &McapOptions::default().topic("/fox/poses")).unwrap();
    let message = table.to_trajectory().unwrap_err().to_string();
    assert!(message.contains("topic /fox/poses, message at byte "), "{message}");
    assert!(message.contains(" of the chunk at offset "), "{message}");
}

/// Writes `bytes` as a new file beside the fixtures and reads it with the default options and
/// as a topic list: both fail, and `read`'s error is returned.
fn read_broken(dir: &Path, name: &str, bytes: &[u8]) -> IoError {
    let path = dir.join(format!("broken-{}-{name}", std::process::id()));
    std::fs::write(&path, bytes).unwrap();
    let error = read_mcap(&path, &McapOptions::default().topic("/pose")).unwrap_err();
    let listed = list_topics(&path);
    std::fs::remove_file(&path).unwrap();
    assert!(error.to_string().starts_with(&path.display().to_string()), "{error}");
    assert_eq!(error.path(), path);
    assert!(listed.is_err(), "{name}: the topic list reads the whole file too");
    error
}

#[test]
fn truncated_files_are_errors_at_an_offset() {
    let (dir, _) = fixtures_or_skip!();
    for name in ["ros2_unchunked.mcap", "ros2_zstd.mcap", "ros2_lz4.mcap", "ros2_chunked.mcap"] {
        let bytes = std::fs::read(dir.join(name)).unwrap();
        for cut in (0..bytes.len()).step_by(bytes.len() / 97 + 1).chain([bytes.len() - 1, bytes.len() / 2]) {
            let error = read_broken(dir, name, &bytes[..cut]);
            assert!(matches!(error, IoError::Mcap { .. }), "{name} cut at {cut}: {error:?}");
            let message = error.to_string();
            assert!(message.contains("truncated") || message.contains("not an MCAP file"), "{name} {cut}: {message}");
        }
        let error = read_broken(dir, name, &bytes[..bytes.len() / 2]);
        let offset = error.offset().unwrap();
        assert!(offset < bytes.len() as u64 / 2, "{error}");
        assert!(
            logs::mcap_records(&bytes).iter().any(|&(pos, _, _)| pos as u64 == offset),
            "{error}: not a record's offset"
        );
    }
}

#[test]
fn bad_magic_at_either_end() {
    let (dir, _) = fixtures_or_skip!();
    let mut bytes = std::fs::read(dir.join("ros2_zstd.mcap")).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0xff;
    let error = read_broken(dir, "end.mcap", &bytes);
    assert_eq!(error.offset(), Some(last as u64 - 7));
    assert!(error.to_string().ends_with("bad magic: the footer is not followed by the MCAP magic bytes"), "{error}");
    bytes[last] ^= 0xff;
    bytes[1] = b'X';
    let error = read_broken(dir, "start.mcap", &bytes);
    assert!(error.to_string().contains(" offset 0: not an MCAP file"), "{error}");
    let error = read_broken(dir, "text.mcap", b"# timestamp tx ty tz qx qy qz qw\n");
    assert!(error.to_string().contains(" offset 0: not an MCAP file"), "{error}");
}

#[test]
fn a_chunk_with_a_wrong_crc_is_named_by_its_offset() {
    let (dir, _) = fixtures_or_skip!();
    for name in ["ros2_zstd.mcap", "ros2_lz4.mcap", "ros2_chunked.mcap", "json_zstd.mcap"] {
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let chunks: Vec<usize> = logs::mcap_records(&bytes).iter().filter(|r| r.1 == 0x06).map(|r| r.0).collect();
        assert!(chunks.len() > 3, "{name}: many small chunks");
        let chunk = chunks[2];
        // Chunk body: start, end (u64 each), uncompressed size (u64), then the CRC (u32).
        let mut broken = bytes.clone();
        broken[chunk + 9 + 24] ^= 0x01;
        let error = read_broken(dir, name, &broken);
        assert_eq!(error.offset(), Some(chunk as u64), "{error}");
        assert!(
            error.to_string().contains(&format!(" offset {chunk}: the chunk is corrupt: the CRC of its records is ")),
            "{error}"
        );
        // A flipped byte in the records themselves: caught by the CRC or the decompressor.
        let (_, _, len) = logs::mcap_records(&bytes).into_iter().find(|r| r.0 == chunk).unwrap();
        let mut broken = bytes.clone();
        broken[chunk + 9 + len - 5] ^= 0x10;
        let error = read_broken(dir, name, &broken);
        assert_eq!(error.offset(), Some(chunk as u64), "{error}");
    }
}

#[test]
fn topic_errors_name_the_file_and_topic() {
    let (dir, _) = fixtures_or_skip!();
    let path = dir.join("ros2_lz4.mcap");
    let error = read_mcap(&path, &McapOptions::default().topic("/custom")).unwrap_err();
    assert!(matches!(error, IoError::UnsupportedTopic { .. }), "{error:?}");
    assert!(
        error.to_string().starts_with(&format!(
            "{}: topic /custom has type \"my_msgs/msg/Custom\" in encoding \"cdr\", which this crate does not read",
            path.display()
        )),
        "{error}"
    );
    let error = read_mcap(&path, &McapOptions::default().topic("/nope")).unwrap_err();
    assert!(
        error
            .to_string()
            .contains(r#"no topic "/nope"; the topics are: /custom (my_msgs/msg/Custom, cdr, 24 messages), /odom"#),
        "{error}"
    );
    let path = dir.join("no_pose_topic.mcap");
    let error = read_mcap(&path, &McapOptions::default()).unwrap_err();
    assert!(matches!(&error, IoError::NoPoseTopic { topics, .. } if topics.len() == 2), "{error:?}");
    assert!(error.to_string().contains("no topic holds poses of a type this crate reads"), "{error}");
}

#[test]
fn an_empty_topic_names_its_channel() {
    let (dir, _) = fixtures_or_skip!();
    let path = dir.join("empty_topic.mcap");
    let bytes = std::fs::read(&path).unwrap();
    for options in [McapOptions::default(), McapOptions::default().topic("/pose")] {
        let error = read_mcap(&path, &options).unwrap_err();
        let IoError::EmptyTopic { channel_offset, topic, .. } = &error else { panic!("{error:?}") };
        assert_eq!((topic.topic.as_str(), topic.message_count), ("/pose", 0));
        // The Python writer chunks by default: the channel record is in the first chunk.
        assert!(matches!(bytes[*channel_offset as usize], 0x04 | 0x06), "a channel or chunk record");
        assert_eq!(
            error.to_string(),
            format!(
                "{} topic /pose: no poses (0 messages; its channel is in the record at offset {channel_offset})",
                path.display()
            )
        );
    }
}

#[test]
fn a_cdr_message_shorter_than_its_type() {
    let (dir, _) = fixtures_or_skip!();
    for (name, chunked) in [("short_cdr.mcap", false), ("short_cdr_chunked.mcap", true)] {
        let path = dir.join(name);
        let bytes = std::fs::read(&path).unwrap();
        for options in [McapOptions::default(), McapOptions::default().topic("/pose")] {
            let error = read_mcap(&path, &options).unwrap_err();
            let IoError::Message { location, message } = &error else { panic!("{error:?}") };
            assert_eq!(location.topic, "/pose");
            assert_eq!(location.offset_in_chunk.is_some(), chunked);
            let opcode = bytes[location.offset as usize];
            assert_eq!(opcode, if chunked { 0x06 } else { 0x05 }, "a message or a chunk record");
            assert!(
                message.starts_with("the CDR message ends at byte ")
                    && message.contains("but geometry_msgs/msg/PoseStamped needs 56 bytes for pose at byte")
                    && message.ends_with("the message is shorter than its type"),
                "{message}"
            );
            let place = match location.offset_in_chunk {
                Some(inner) => format!("message at byte {inner} of the chunk at offset {}", location.offset),
                None => format!("message at offset {}", location.offset),
            };
            assert!(
                error.to_string().starts_with(&format!("{} topic /pose, {place}: the CDR", path.display())),
                "{error}"
            );
        }
        // The message at that offset is the 4th (of 6): the first 3 read.
        if !chunked {
            let error = read_mcap(&path, &McapOptions::default()).unwrap_err();
            let message_offsets: Vec<u64> =
                logs::mcap_records(&bytes).iter().filter(|r| r.1 == 0x05).map(|r| r.0 as u64).collect();
            assert_eq!(error.offset(), Some(message_offsets[3]));
        }
    }
}

#[test]
fn no_file_at_all() {
    let error = read_mcap_files::<&Path>(&[], &McapOptions::default()).unwrap_err();
    assert_eq!(error.to_string(), ": number of MCAP files = 0 is invalid: at least one file");
}

#[test]
fn a_missing_file() {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("no-such.mcap");
    let error = read_mcap(&path, &McapOptions::default()).unwrap_err();
    assert!(matches!(error, IoError::Open { .. }), "{error:?}");
    assert!(matches!(list_topics(&path).unwrap_err(), IoError::Open { .. }));
}
