//! Fuzz targets (proptest): the CDR, protobuf and JSON message decoders, the MCAP reader and the
//! text readers take random bytes and structured mutations of valid input without panicking,
//! and read valid input back exactly.
//!
//! The seeds are fixed, so a failure replays. For a longer run, raise the case count:
//! `PROPTEST_CASES=100000 cargo test --release -p loops-io --test fuzz`.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::PathBuf;

use loops_io::{McapOptions, MessageEncoding, PoseType, Timing, decode_poses, list_topics, read_mcap};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

mod support;
use support::{ROS_TYPES, mutate, mutations};

fn config(seed: u64) -> ProptestConfig {
    ProptestConfig {
        cases: ProptestConfig::default().cases.max(256),
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// A pose as the encoders below write it.
#[derive(Debug, Clone, PartialEq)]
struct Pose {
    stamp: (i32, u32),
    parent: String,
    child: String,
    position: [f64; 3],
    orientation: [f64; 4],
}

fn pose() -> impl Strategy<Value = Pose> {
    (
        (any::<i32>(), 0u32..1_000_000_000),
        "[a-z_/]{0,12}",
        "[a-z_/]{0,12}",
        proptest::array::uniform3(any::<f64>()),
        proptest::array::uniform4(any::<f64>()),
    )
        .prop_map(|(stamp, parent, child, position, orientation)| Pose {
            stamp,
            parent,
            child,
            position,
            orientation,
        })
}

fn stamp_ns(stamp: (i32, u32)) -> i64 {
    i64::from(stamp.0) * 1_000_000_000 + i64::from(stamp.1)
}

/// Floats compared by bits (NaN included).
fn bits<const N: usize>(values: [f64; N]) -> [u64; N] {
    values.map(f64::to_bits)
}

// ---- CDR ------------------------------------------------------------------------------------

/// A CDR writer independent of the crate's reader: alignment relative to the body.
struct Cdr {
    data: Vec<u8>,
    little_endian: bool,
    max_align: usize,
}

impl Cdr {
    fn new(little_endian: bool, xcdr2: bool) -> Self {
        let kind = match (xcdr2, little_endian) {
            (false, false) => 0x00,
            (false, true) => 0x01,
            (true, false) => 0x06,
            (true, true) => 0x07,
        };
        Self { data: vec![0, kind, 0, 0], little_endian, max_align: if xcdr2 { 4 } else { 8 } }
    }
    fn align(&mut self, n: usize) {
        let n = n.min(self.max_align);
        while !(self.data.len() - 4).is_multiple_of(n) {
            self.data.push(0);
        }
    }
    fn u32(&mut self, v: u32) {
        self.align(4);
        let bytes = if self.little_endian { v.to_le_bytes() } else { v.to_be_bytes() };
        self.data.extend(bytes);
    }
    fn f64(&mut self, v: f64) {
        self.align(8);
        let bytes = if self.little_endian { v.to_le_bytes() } else { v.to_be_bytes() };
        self.data.extend(bytes);
    }
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.data.extend(s.as_bytes());
        self.data.push(0);
    }
    fn header(&mut self, pose: &Pose) {
        self.u32(pose.stamp.0 as u32);
        self.u32(pose.stamp.1);
        self.string(&pose.parent);
    }
    fn pose(&mut self, pose: &Pose) {
        for v in pose.position.iter().chain(&pose.orientation) {
            self.f64(*v);
        }
    }
    fn doubles(&mut self, count: usize) {
        for i in 0..count {
            self.f64(i as f64);
        }
    }
    fn transform_stamped(&mut self, pose: &Pose) {
        self.header(pose);
        self.string(&pose.child);
        self.pose(pose);
    }
}

/// A valid CDR message of `pose_type` holding `poses` (one, except for TF), and what reads back.
fn cdr_message(pose_type: PoseType, poses: &[Pose], little_endian: bool, xcdr2: bool) -> (Vec<u8>, Vec<Pose>) {
    let mut w = Cdr::new(little_endian, xcdr2);
    let first = &poses[0];
    let mut expected = vec![first.clone()];
    match pose_type {
        PoseType::PoseStamped => {
            w.header(first);
            w.pose(first);
            expected[0].child.clear();
        }
        PoseType::PoseWithCovarianceStamped => {
            w.header(first);
            w.pose(first);
            w.doubles(36);
            expected[0].child.clear();
        }
        PoseType::TransformStamped => w.transform_stamped(first),
        PoseType::Odometry => {
            w.header(first);
            w.string(&first.child);
            w.pose(first);
            w.doubles(36 + 6 + 36);
        }
        _ => {
            w.u32(poses.len() as u32);
            for pose in poses {
                w.transform_stamped(pose);
            }
            expected = poses.to_vec();
        }
    }
    (w.data, expected)
}

fn check_decoded(pose_type: PoseType, encoding: MessageEncoding, data: &[u8], expected: &[Pose]) {
    let decoded = decode_poses(pose_type, encoding, data).unwrap_or_else(|e| panic!("{pose_type} {encoding}: {e}"));
    assert_eq!(decoded.len(), expected.len());
    for (got, want) in decoded.iter().zip(expected) {
        assert_eq!(got.stamp_ns, stamp_ns(want.stamp));
        assert_eq!((&got.frame_id, &got.child_frame_id), (&want.parent, &want.child));
        assert_eq!(bits(got.position), bits(want.position));
        assert_eq!(bits(got.orientation_xyzw), bits(want.orientation));
    }
}

proptest! {
    #![proptest_config(config(0xCD5))]

    #[test]
    fn cdr_random_bytes_never_panic(data in proptest::collection::vec(any::<u8>(), 0..400), header in 0u8..0x12) {
        for pose_type in ROS_TYPES {
            let _ = decode_poses(pose_type, MessageEncoding::Cdr, &data);
            let mut with_header = vec![0, header, 0, 0];
            with_header.extend(&data);
            let _ = decode_poses(pose_type, MessageEncoding::Cdr, &with_header);
        }
    }

    #[test]
    fn cdr_valid_messages_read_back_exactly_and_every_prefix_fails(
        poses in proptest::collection::vec(pose(), 1..4),
        little_endian in any::<bool>(),
        xcdr2 in any::<bool>(),
    ) {
        for pose_type in ROS_TYPES {
            let (data, expected) = cdr_message(pose_type, &poses, little_endian, xcdr2);
            check_decoded(pose_type, MessageEncoding::Cdr, &data, &expected);
            for cut in 0..data.len() {
                prop_assert!(decode_poses(pose_type, MessageEncoding::Cdr, &data[..cut]).is_err(), "{pose_type} cut at {cut}");
            }
        }
    }

    #[test]
    fn cdr_mutated_messages_never_panic(
        poses in proptest::collection::vec(pose(), 1..4),
        little_endian in any::<bool>(),
        mutations in mutations(),
    ) {
        for pose_type in ROS_TYPES {
            let (data, _) = cdr_message(pose_type, &poses, little_endian, false);
            let _ = decode_poses(pose_type, MessageEncoding::Cdr, &mutate(&data, &mutations));
        }
    }
}

// ---- protobuf and JSON ----------------------------------------------------------------------

/// A protobuf writer independent of prost.
#[derive(Default)]
struct Proto(Vec<u8>);

impl Proto {
    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.0.push((v as u8) | 0x80);
            v >>= 7;
        }
        self.0.push(v as u8);
    }
    fn tag(&mut self, field: u32, wire: u8) {
        self.varint(u64::from(field) << 3 | u64::from(wire));
    }
    fn double(&mut self, field: u32, v: f64) {
        self.tag(field, 1);
        self.0.extend(v.to_le_bytes());
    }
    fn bytes(&mut self, field: u32, bytes: &[u8]) {
        self.tag(field, 2);
        self.varint(bytes.len() as u64);
        self.0.extend(bytes);
    }
    fn message(&mut self, field: u32, build: impl FnOnce(&mut Proto)) {
        let mut inner = Proto::default();
        build(&mut inner);
        self.bytes(field, &inner.0);
    }
    fn timestamp(&mut self, field: u32, stamp: (i32, u32)) {
        self.message(field, |m| {
            m.tag(1, 0);
            m.varint(i64::from(stamp.0) as u64);
            m.tag(2, 0);
            m.varint(i64::from(stamp.1 as i32) as u64);
        });
    }
    fn vector(&mut self, field: u32, v: &[f64]) {
        self.message(field, |m| {
            for (i, x) in v.iter().enumerate() {
                m.double(i as u32 + 1, *x);
            }
        });
    }
    fn pose(&mut self, field: u32, pose: &Pose) {
        self.message(field, |m| {
            m.vector(1, &pose.position);
            m.vector(2, &pose.orientation);
        });
    }
    fn frame_transform(&mut self, pose: &Pose) {
        self.timestamp(1, pose.stamp);
        self.bytes(2, pose.parent.as_bytes());
        self.bytes(3, pose.child.as_bytes());
        self.vector(4, &pose.position);
        self.vector(5, &pose.orientation);
    }
}

const FOXGLOVE_TYPES: [PoseType; 5] = [
    PoseType::FoxglovePoseInFrame,
    PoseType::FoxglovePosesInFrame,
    PoseType::FoxgloveFrameTransform,
    PoseType::FoxgloveFrameTransforms,
    PoseType::FoxgloveOdometry,
];

/// A valid protobuf message and the same as Foxglove JSON, with what reads back.
fn foxglove_message(pose_type: PoseType, poses: &[Pose]) -> (Vec<u8>, Vec<u8>, Vec<Pose>) {
    let first = &poses[0];
    let mut m = Proto::default();
    let json_time = |s: (i32, u32)| serde_json::json!({"sec": s.0, "nsec": s.1});
    let json_vector = |v: &[f64]| {
        let names = ["x", "y", "z", "w"];
        serde_json::Value::Object(
            v.iter().enumerate().map(|(i, x)| (names[i].to_owned(), serde_json::json!(x))).collect(),
        )
    };
    let json_pose = |p: &Pose| serde_json::json!({"position": json_vector(&p.position), "orientation": json_vector(&p.orientation)});
    let json_transform = |p: &Pose| {
        serde_json::json!({"timestamp": json_time(p.stamp), "parent_frame_id": p.parent, "child_frame_id": p.child,
            "translation": json_vector(&p.position), "rotation": json_vector(&p.orientation)})
    };
    let (json, expected) = match pose_type {
        PoseType::FoxglovePoseInFrame => {
            m.timestamp(1, first.stamp);
            m.bytes(2, first.parent.as_bytes());
            m.pose(3, first);
            let json = serde_json::json!({"timestamp": json_time(first.stamp), "frame_id": first.parent, "pose": json_pose(first)});
            (json, vec![Pose { child: String::new(), ..first.clone() }])
        }
        PoseType::FoxglovePosesInFrame => {
            m.timestamp(1, first.stamp);
            m.bytes(2, first.parent.as_bytes());
            for pose in poses {
                m.pose(3, pose);
            }
            let json = serde_json::json!({"timestamp": json_time(first.stamp), "frame_id": first.parent,
                "poses": poses.iter().map(json_pose).collect::<Vec<_>>()});
            let expected = poses
                .iter()
                .map(|p| Pose { stamp: first.stamp, parent: first.parent.clone(), child: String::new(), ..p.clone() })
                .collect();
            (json, expected)
        }
        PoseType::FoxgloveFrameTransform => {
            m.frame_transform(first);
            (json_transform(first), vec![first.clone()])
        }
        PoseType::FoxgloveFrameTransforms => {
            for pose in poses {
                m.message(1, |t| t.frame_transform(pose));
            }
            (serde_json::json!({"transforms": poses.iter().map(json_transform).collect::<Vec<_>>()}), poses.to_vec())
        }
        _ => {
            m.timestamp(1, first.stamp);
            m.bytes(2, first.parent.as_bytes());
            m.bytes(3, first.child.as_bytes());
            m.pose(4, first);
            m.vector(5, &[1.0, 2.0, 3.0]);
            let json = serde_json::json!({"timestamp": json_time(first.stamp), "frame_id": first.parent,
                "body_frame_id": first.child, "pose": json_pose(first), "linear_velocity": {"x": 1.0}});
            (json, vec![first.clone()])
        }
    };
    (m.0, serde_json::to_vec(&json).expect("JSON"), expected)
}

/// Finite values only: JSON has no NaN or infinity.
fn finite_pose() -> impl Strategy<Value = Pose> {
    pose().prop_filter("finite", |p| p.position.iter().chain(&p.orientation).all(|v| v.is_finite()))
}

proptest! {
    #![proptest_config(config(0xF0C5))]

    #[test]
    fn protobuf_and_json_random_input_never_panics(
        data in proptest::collection::vec(any::<u8>(), 0..400),
        text in "(?s).{0,200}",
    ) {
        for pose_type in FOXGLOVE_TYPES {
            let _ = decode_poses(pose_type, MessageEncoding::Protobuf, &data);
            let _ = decode_poses(pose_type, MessageEncoding::Json, &data);
            let _ = decode_poses(pose_type, MessageEncoding::Json, text.as_bytes());
        }
    }

    #[test]
    fn protobuf_and_json_messages_read_back_exactly(poses in proptest::collection::vec(finite_pose(), 1..4)) {
        for pose_type in FOXGLOVE_TYPES {
            let (protobuf, json, expected) = foxglove_message(pose_type, &poses);
            check_decoded(pose_type, MessageEncoding::Protobuf, &protobuf, &expected);
            check_decoded(pose_type, MessageEncoding::Json, &json, &expected);
        }
    }

    #[test]
    fn mutated_protobuf_and_json_never_panic(
        poses in proptest::collection::vec(finite_pose(), 1..4),
        mutations in mutations(),
    ) {
        for pose_type in FOXGLOVE_TYPES {
            let (protobuf, json, _) = foxglove_message(pose_type, &poses);
            let _ = decode_poses(pose_type, MessageEncoding::Protobuf, &mutate(&protobuf, &mutations));
            let _ = decode_poses(pose_type, MessageEncoding::Json, &mutate(&json, &mutations));
        }
    }
}

// ---- MCAP files -----------------------------------------------------------------------------

/// An MCAP file of PoseStamped messages, written with the `mcap` crate's writer.
fn mcap_file(poses: &[Pose], compression: Option<mcap::Compression>, chunk_size: Option<u64>) -> Vec<u8> {
    let mut buffer = Cursor::new(Vec::new());
    {
        let options =
            mcap::WriteOptions::new().compression(compression).chunk_size(chunk_size).use_chunks(chunk_size.is_some());
        let mut writer = options.create(&mut buffer).expect("writer");
        let schema = writer.add_schema("geometry_msgs/msg/PoseStamped", "ros2msg", b"").expect("schema");
        let channel = writer.add_channel(schema, "/pose", "cdr", &BTreeMap::new()).expect("channel");
        let other = writer.add_channel(0, "/other", "json", &BTreeMap::new()).expect("channel");
        for (i, pose) in poses.iter().enumerate() {
            let (data, _) = cdr_message(PoseType::PoseStamped, std::slice::from_ref(pose), true, false);
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: i as u32,
                log_time: i as u64,
                publish_time: i as u64,
            };
            writer.write_to_known_channel(&header, &data).expect("message");
            let header = mcap::records::MessageHeader { channel_id: other, ..header };
            writer.write_to_known_channel(&header, b"{}").expect("message");
        }
        writer.finish().expect("finish");
    }
    buffer.into_inner()
}

/// A scratch file in the target folder (one name per test: tests run in parallel threads).
fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir.join(name)
}

fn compression() -> impl Strategy<Value = (Option<mcap::Compression>, Option<u64>)> {
    prop_oneof![
        Just((None, None)),
        Just((None, Some(300))),
        Just((Some(mcap::Compression::Zstd), Some(500))),
        Just((Some(mcap::Compression::Lz4), Some(400))),
    ]
}

proptest! {
    #![proptest_config(config(0x3CA9))]

    #[test]
    fn mcap_files_read_back_and_mutations_never_panic(
        poses in proptest::collection::vec(pose(), 1..12),
        (compression, chunk_size) in compression(),
        mutations in mutations(),
    ) {
        let bytes = mcap_file(&poses, compression, chunk_size);
        let path = scratch("mutated.mcap");
        std::fs::write(&path, &bytes).unwrap();
        let table = read_mcap(&path, &McapOptions::default().time(loops_io::TimeSource::Log)).unwrap();
        prop_assert_eq!(table.len(), poses.len());
        for (i, pose) in poses.iter().enumerate() {
            prop_assert_eq!(bits(table.positions[i]), bits(pose.position));
            prop_assert_eq!(table.timestamps_ns.as_ref().unwrap()[i], i as i64);
        }
        let mutated = mutate(&bytes, &mutations);
        std::fs::write(&path, &mutated).unwrap();
        for result in [read_mcap(&path, &McapOptions::default()), read_mcap(&path, &McapOptions::default().topic("/other"))] {
            if let Err(error) = result {
                prop_assert!(error.to_string().starts_with(&path.display().to_string()), "{}", error);
            }
        }
        let _ = list_topics(&path);
    }

    #[test]
    fn random_bytes_after_the_magic_never_panic(data in proptest::collection::vec(any::<u8>(), 0..600)) {
        let mut bytes = mcap::MAGIC.to_vec();
        bytes.extend(&data);
        let path = scratch("random.mcap");
        std::fs::write(&path, &bytes).unwrap();
        prop_assert!(read_mcap(&path, &McapOptions::default()).is_err());
        let _ = list_topics(&path);
    }
}

// ---- text formats ---------------------------------------------------------------------------

fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        8 => any::<f64>().prop_filter("finite", |v| v.is_finite()).prop_map(|v| v.to_string()),
        4 => (0u32..5000).prop_map(|v| v.to_string()),
        1 => Just("nan".to_owned()),
        1 => Just("-".to_owned()),
        1 => Just(String::new()),
        1 => "[0-9eE.+-]{1,5}",
    ]
}

/// Lines shaped like the text formats: a tag or none, then a near-right count of numbers.
fn near_miss_text() -> impl Strategy<Value = String> {
    let tag = prop_oneof![
        Just(""),
        Just("VERTEX_SE2 "),
        Just("VERTEX2 "),
        Just("VERTEX_SE3:QUAT "),
        Just("VERTEX3 "),
        Just("EDGE_SE2 "),
        Just("EDGE2 "),
        Just("EDGE_SE3:QUAT "),
        Just("EDGE3 "),
        Just("point2 "),
        Just("point3 "),
        Just("angle "),
        Just("# "),
    ];
    let separator = prop_oneof![Just(" "), Just(","), Just("\t")];
    let line = (tag, separator, proptest::collection::vec(number(), 0..16))
        .prop_map(|(tag, separator, numbers)| format!("{tag}{}", numbers.join(separator)));
    proptest::collection::vec(line, 0..10).prop_map(|lines| lines.join("\n"))
}

fn read_text_every_way(test: &str, contents: &[u8]) {
    let path = scratch(&format!("{test}.txt"));
    std::fs::write(&path, contents).unwrap();
    let times = scratch(&format!("{test}-times.txt"));
    std::fs::write(&times, contents).unwrap();
    let timings = [Timing::FromFile, Timing::RateHz(10.0), Timing::TimesFile(times)];
    let mut results =
        vec![loops_io::read_euroc(&path), loops_io::read_tuc(&path), loops_io::read_trajectory(&path, None)];
    for timing in &timings {
        results.push(loops_io::read_kitti(&path, timing));
        results.push(loops_io::read_pose_graph(&path, timing).map(|graph| graph.vertices));
    }
    for result in results {
        match result {
            Ok(table) => {
                assert!(!table.is_empty());
                assert_eq!(table.positions.len(), table.len());
                assert!(table.positions.iter().flatten().all(|v| v.is_finite()));
                let _ = table.to_trajectory();
            }
            Err(error) => assert!(!error.to_string().is_empty()),
        }
    }
}

proptest! {
    #![proptest_config(config(0x7E47))]

    #[test]
    fn text_readers_never_panic_on_random_bytes(contents in proptest::collection::vec(any::<u8>(), 0..400)) {
        read_text_every_way("bytes", &contents);
    }

    #[test]
    fn text_readers_never_panic_on_near_misses(text in near_miss_text()) {
        read_text_every_way("near", text.as_bytes());
    }
}
