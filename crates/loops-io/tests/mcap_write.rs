//! `write_mcap`: a synthetic drive written as MCAP reads back bit for bit with our reader, with
//! the `mcap` crate's summary reader, and with the official Python reader (`mcap` and
//! `mcap-ros2-support`, skipped with a message when python3 or the packages are missing);
//! files are not overwritten unless asked, and a failed write leaves nothing behind.

use std::path::{Path, PathBuf};
use std::process::Command;

use loops_core::UrbanDrive;
use loops_io::{
    McapCompression, McapOptions, McapPoseMessage, McapWriteOptions, PoseTable, PoseType, ReadOptions, WriteError,
    list_topics, read_mcap, read_trajectory_with, seconds_of_ns, write_mcap,
};
use serde_json::Value;

mod support;

/// A fresh, empty folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("mcap-write-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Stamps of the drive start here: 2023-11-14, nanoseconds since the epoch.
const START_NS: i64 = 1_700_000_000_123_456_789;

/// A seeded urban drive as a 3-D table with yaw quaternions and nanosecond stamps from
/// [`START_NS`] (the drive's seconds, to the nanosecond).
fn drive_table(duration_s: f64) -> PoseTable {
    let drive = UrbanDrive { duration_s, seed: 7, ..Default::default() }.generate().unwrap();
    let se3 = drive.se3_trajectory().unwrap();
    let (poses, _) = se3.coords().as_chunks::<7>();
    let stamps_ns: Vec<i64> = se3.timestamps_s().iter().map(|&t| START_NS + (t * 1e9).round() as i64).collect();
    let mut table = empty_table();
    table.timestamps_s = stamps_ns.iter().map(|&ns| seconds_of_ns(ns)).collect();
    table.timestamps_ns = Some(stamps_ns);
    table.positions = poses.iter().map(|p| [p[0], p[1], p[2]]).collect();
    table.orientations_xyzw = Some(poses.iter().map(|p| [p[3], p[4], p[5], p[6]]).collect());
    table
}

/// A 3-D table with no poses.
fn empty_table() -> PoseTable {
    PoseTable {
        path: PathBuf::from("drive.tum"),
        timestamps_s: Vec::new(),
        timestamps_ns: None,
        positions: Vec::new(),
        orientations_xyzw: None,
        dim: 3,
        source_lines: Vec::new(),
        messages: None,
    }
}

#[test]
fn a_drive_reads_back_bit_for_bit() {
    let dir = scratch("round-trip");
    let table = drive_table(120.0);
    assert_eq!(table.len(), 1200);
    for compression in [McapCompression::Zstd, McapCompression::Lz4, McapCompression::None] {
        let path = dir.join(format!("drive-{compression:?}.mcap"));
        write_mcap(&path, &table, &McapWriteOptions::default().compression(compression), false).unwrap();
        let back = read_trajectory_with(&path, &ReadOptions::default()).unwrap();
        assert_eq!(back.timestamps_ns, table.timestamps_ns, "{compression:?}");
        assert_eq!(back.timestamps_s, table.timestamps_s);
        assert_eq!(back.positions, table.positions);
        assert_eq!(back.orientations_xyzw, table.orientations_xyzw);
        let sources = back.messages.as_ref().unwrap();
        assert_eq!((sources.topic.as_str(), sources.schema_name.as_str()), ("/pose", "geometry_msgs/msg/PoseStamped"));
        assert!(sources.messages.iter().all(|m| m.offset_in_chunk.is_some()), "every message is in a chunk");
        // The log and publish times are the stamps.
        for time in [loops_io::TimeSource::Log, loops_io::TimeSource::Publish] {
            let by_time = read_mcap(&path, &McapOptions::default().time(time)).unwrap();
            assert_eq!(by_time.timestamps_ns, table.timestamps_ns, "{time:?}");
        }

        let topics = list_topics(&path).unwrap();
        assert_eq!(topics.len(), 1);
        let topic = &topics[0];
        assert_eq!(topic.to_string(), "/pose (geometry_msgs/msg/PoseStamped, cdr, 1200 messages)");
        assert_eq!((topic.schema_encoding.as_str(), topic.pose_type), ("ros2msg", Some(PoseType::PoseStamped)));
        let stamps = table.timestamps_ns.as_ref().unwrap();
        assert_eq!(topic.log_time_span_ns, Some((stamps[0] as u64, stamps[1199] as u64)));

        // The summary section, as indexed readers and `mcap info` see it.
        let bytes = std::fs::read(&path).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary section");
        let stats = summary.stats.as_ref().expect("statistics");
        assert_eq!((stats.message_count, stats.channel_count, stats.schema_count), (1200, 1, 1));
        assert_eq!(stats.channel_message_counts.values().copied().collect::<Vec<_>>(), [1200]);
        assert_eq!((stats.message_start_time, stats.message_end_time), (stamps[0] as u64, stamps[1199] as u64));
        assert!(!summary.chunk_indexes.is_empty());
        let expected = match compression {
            McapCompression::Zstd => "zstd",
            McapCompression::Lz4 => "lz4",
            _ => "",
        };
        assert!(
            summary
                .chunk_indexes
                .iter()
                .all(|chunk| chunk.compression == expected && !chunk.message_index_offsets.is_empty())
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_long_drive_fills_several_chunks() {
    let dir = scratch("chunks");
    let table = drive_table(3600.0);
    let path = dir.join("hour.mcap");
    write_mcap(&path, &table, &McapWriteOptions::default(), false).unwrap();
    let summary = mcap::Summary::read(&std::fs::read(&path).unwrap()).unwrap().unwrap();
    assert!(summary.chunk_indexes.len() > 1, "{} chunks", summary.chunk_indexes.len());
    let back = read_mcap(&path, &McapOptions::default()).unwrap();
    assert_eq!((back.timestamps_ns, back.positions), (table.timestamps_ns.clone(), table.positions.clone()));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn odometry_and_tables_without_orientations_or_nanoseconds() {
    let dir = scratch("odometry");
    let drive = drive_table(10.0);
    // Seconds only, 2-D, no orientations: stamps to the nearest nanosecond, identity rotations.
    let mut table = empty_table();
    table.dim = 2;
    table.timestamps_s = vec![0.1, 1.5, 1_700_000_000.25, 1_700_000_000.3];
    table.positions = drive.positions[..4].iter().map(|p| [p[0], p[1], 0.0]).collect();
    let options = McapWriteOptions::default()
        .topic("/odom")
        .frame_id("odom")
        .message(McapPoseMessage::Odometry { child_frame_id: "base_link".into() });
    let path = dir.join("odom.mcap");
    write_mcap(&path, &table, &options, false).unwrap();
    let back = read_mcap(&path, &McapOptions::default()).unwrap();
    assert_eq!(back.messages.as_ref().unwrap().schema_name, "nav_msgs/msg/Odometry");
    assert_eq!(
        back.timestamps_ns,
        // As printed: the f64 of 1_700_000_000.3 is 1_700_000_000.2999999523...
        Some(vec![100_000_000, 1_500_000_000, 1_700_000_000_250_000_000, 1_700_000_000_300_000_000])
    );
    assert_eq!(back.timestamps_s, table.timestamps_s);
    assert_eq!(back.positions, table.positions);
    assert_eq!(back.orientations_xyzw, Some(vec![[0.0, 0.0, 0.0, 1.0]; 4]));
    let topics = list_topics(&path).unwrap();
    assert_eq!(topics[0].to_string(), "/odom (nav_msgs/msg/Odometry, cdr, 4 messages)");
    // Epoch seconds as f64 (about 0.24 µs apart) come back as the same f64.
    let mut seconds_only = drive_table(120.0);
    seconds_only.timestamps_ns = None;
    for (i, t) in seconds_only.timestamps_s.iter_mut().enumerate() {
        *t = 1_700_000_000.0 + i as f64 * 0.1 + (i % 7) as f64 * 1e-3;
    }
    let path = dir.join("seconds.mcap");
    write_mcap(&path, &seconds_only, &McapWriteOptions::default(), false).unwrap();
    let back = read_mcap(&path, &McapOptions::default()).unwrap();
    assert_eq!(back.timestamps_s, seconds_only.timestamps_s);
    assert_eq!(back.positions, seconds_only.positions);
    // An empty table makes a file with the topic and no message.
    let path = dir.join("empty.mcap");
    write_mcap(&path, &empty_table(), &McapWriteOptions::default(), false).unwrap();
    let topics = list_topics(&path).unwrap();
    assert_eq!((topics[0].message_count, topics[0].log_time_span_ns), (0, None));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn files_are_not_overwritten_and_failures_leave_nothing() {
    let dir = scratch("overwrite");
    let table = drive_table(5.0);
    let path = dir.join("drive.mcap");
    std::fs::write(&path, "keep me").unwrap();
    let options = McapWriteOptions::default();
    let error = write_mcap(&path, &table, &options, false).unwrap_err();
    assert!(matches!(error, WriteError::Exists { .. }), "{error:?}");
    assert_eq!(error.to_string(), format!("{}: the file exists; refusing to overwrite it", path.display()));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "keep me");
    write_mcap(&path, &table, &options, true).unwrap();
    assert_eq!(read_mcap(&path, &McapOptions::default()).unwrap().positions, table.positions);

    // Stamps MCAP and ROS 2 cannot hold: nothing is written.
    let target = dir.join("bad.mcap");
    let mut early = table.clone();
    early.timestamps_ns.as_mut().unwrap()[3] = -1_500_000_000;
    let mut late = table.clone();
    late.timestamps_ns.as_mut().unwrap()[2] = (i64::from(i32::MAX) + 1) * 1_000_000_000;
    let mut not_a_number = table.clone();
    not_a_number.timestamps_ns = None;
    not_a_number.timestamps_s[1] = f64::NAN;
    let mut seconds_only_early = table.clone();
    seconds_only_early.timestamps_ns = None;
    seconds_only_early.timestamps_s[0] = -0.25;
    let mut short = table.clone();
    short.orientations_xyzw.as_mut().unwrap().pop();
    let cases = [
        (early, &options, "pose 3: its stamp, -1.500000000 s, is before 1970-01-01 00:00:00 UTC (0 s)"),
        (late, &options, "pose 2: its stamp, 2147483648.000000000 s, is after 2038-01-19 03:14:07 UTC"),
        (not_a_number, &options, "pose 1: its stamp, NaN s, is not a finite number of seconds"),
        (seconds_only_early, &options, "pose 0: its stamp, -0.25 s, is before 1970"),
        (short, &options, "the table has 50 positions but 49 orientations_xyzw"),
    ];
    for (bad, options, message) in cases {
        let error = write_mcap(&target, &bad, options, false).unwrap_err();
        let WriteError::Write { path, error: cause } = &error else { panic!("{error:?}") };
        assert_eq!((path, cause.kind()), (&target, std::io::ErrorKind::InvalidInput));
        let text = error.to_string();
        assert!(text.starts_with(&format!("{}: cannot write the file: {message}", target.display())), "{text}");
    }
    let nul = McapWriteOptions::default().frame_id("map\0");
    let error = write_mcap(&target, &table, &nul, false).unwrap_err();
    assert!(error.to_string().contains(r#"frame_id "map\0" is not a ROS 2 string"#), "{error}");

    // A missing folder.
    let error = write_mcap(dir.join("missing/drive.mcap"), &table, &options, false).unwrap_err();
    assert!(matches!(error, WriteError::Write { .. }), "{error:?}");

    // Only the one file written: no temporary file is left behind.
    let names: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|entry| entry.unwrap().file_name().to_string_lossy().into()).collect();
    assert_eq!(names, ["drive.mcap"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Decodes an MCAP file with `mcap` and `mcap-ros2-support` and prints what it holds as JSON:
/// the header's profile, the summary's counts and chunk compressions, and every message with its
/// numbers as IEEE-754 bit patterns. Exit code 3 when a package is missing.
const PYTHON_READER: &str = r#"
import json, struct, sys
try:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
except ImportError as error:
    print(f"missing Python package ({error}): pip install mcap mcap-ros2-support", file=sys.stderr)
    sys.exit(3)

def bits(value):
    return struct.unpack("<Q", struct.pack("<d", value))[0]

with open(sys.argv[1], "rb") as stream:
    reader = make_reader(stream, decoder_factories=[DecoderFactory()])
    summary = reader.get_summary()
    out = {
        "profile": reader.get_header().profile,
        "message_count": summary.statistics.message_count,
        "channel_message_counts": {
            summary.channels[id].topic: count
            for id, count in summary.statistics.channel_message_counts.items()
        },
        "compressions": sorted({chunk.compression for chunk in summary.chunk_indexes}),
        "messages": [],
    }
    for schema, channel, message, decoded in reader.iter_decoded_messages():
        odometry = schema.name == "nav_msgs/msg/Odometry"
        pose = decoded.pose.pose if odometry else decoded.pose
        p, q, stamp = pose.position, pose.orientation, decoded.header.stamp
        out["messages"].append({
            "schema": schema.name,
            "encoding": schema.encoding + "/" + channel.message_encoding,
            "topic": channel.topic,
            "stamp_ns": stamp.sec * 10**9 + stamp.nanosec,
            "log_time": message.log_time,
            "publish_time": message.publish_time,
            "frame_id": decoded.header.frame_id,
            "child_frame_id": decoded.child_frame_id if odometry else "",
            "p": [bits(v) for v in (p.x, p.y, p.z)],
            "q": [bits(v) for v in (q.x, q.y, q.z, q.w)],
        })
print(json.dumps(out))
"#;

/// What the Python reader says of `path`, or `None` (after a message) when it cannot run here.
fn read_with_python(path: &Path) -> Option<Value> {
    let output = match Command::new(support::python()).arg("-c").arg(PYTHON_READER).arg(path).output() {
        Ok(output) => output,
        Err(error) => {
            support::skip("the Python reader check", &format!("cannot run Python ({error})"));
            return None;
        }
    };
    match output.status.code() {
        Some(0) => Some(serde_json::from_slice(&output.stdout).expect("the reader's JSON")),
        Some(3) => {
            support::skip("the Python reader check", &String::from_utf8_lossy(&output.stderr));
            None
        }
        _ => panic!("the Python reader failed on {}: {}", path.display(), String::from_utf8_lossy(&output.stderr)),
    }
}

#[test]
fn the_official_python_reader_decodes_the_same_poses() {
    let dir = scratch("python");
    let table = drive_table(120.0);
    let pose_stamped = McapWriteOptions::default().topic("/vehicle/pose");
    let odometry = McapWriteOptions::default()
        .frame_id("odom")
        .message(McapPoseMessage::Odometry { child_frame_id: "base_link".into() })
        .compression(McapCompression::Lz4);
    for (name, options) in [("pose.mcap", pose_stamped), ("odom.mcap", odometry)] {
        let path = dir.join(name);
        write_mcap(&path, &table, &options, false).unwrap();
        let Some(read) = read_with_python(&path) else { return };
        let schema = options.message.pose_type().schema_name();
        assert_eq!(read["profile"], "ros2");
        assert_eq!(read["message_count"], 1200);
        assert_eq!(read["channel_message_counts"][&options.topic], 1200);
        let compression = if name == "pose.mcap" { "zstd" } else { "lz4" };
        assert_eq!(read["compressions"], serde_json::json!([compression]));
        let messages = read["messages"].as_array().unwrap();
        assert_eq!(messages.len(), table.len());
        let stamps = table.timestamps_ns.as_ref().unwrap();
        let orientations = table.orientations_xyzw.as_ref().unwrap();
        let child = match &options.message {
            McapPoseMessage::Odometry { child_frame_id } => child_frame_id.as_str(),
            _ => "",
        };
        let float = |v: &Value| f64::from_bits(v.as_u64().expect("bits"));
        for (index, message) in messages.iter().enumerate() {
            let what = format!("{name} message {index}");
            assert_eq!(message["schema"], schema, "{what}");
            assert_eq!(message["encoding"], "ros2msg/cdr", "{what}");
            assert_eq!(message["topic"].as_str(), Some(options.topic.as_str()), "{what}");
            assert_eq!(message["frame_id"].as_str(), Some(options.frame_id.as_str()), "{what}");
            assert_eq!(message["child_frame_id"], child, "{what}");
            for time in ["stamp_ns", "log_time", "publish_time"] {
                assert_eq!(message[time].as_i64(), Some(stamps[index]), "{what} {time}");
            }
            let position: [f64; 3] = std::array::from_fn(|i| float(&message["p"][i]));
            let orientation: [f64; 4] = std::array::from_fn(|i| float(&message["q"][i]));
            assert_eq!((position, orientation), (table.positions[index], orientations[index]), "{what}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
