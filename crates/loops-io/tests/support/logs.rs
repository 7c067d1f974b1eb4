//! Valid logs and text files of every kind this crate reads, built in memory, for the attack
//! tests: `n` poses, pose `i` at `i` seconds (plus a second's fraction), at `(i, 2i, i/2)`; and a
//! hand-made MCAP record writer for records no writer makes (a string "of 4 GiB", a chunk of a
//! zstd bomb). Independent of the crate's readers.

use std::collections::BTreeMap;
use std::io::{Cursor, Read, Write};
use std::path::Path;

/// The pose topic of every log here; `/other` (MCAP, JSON) and `/chatter` (bags, strings) are
/// the topics not read.
pub const TOPIC: &str = "/pose";

/// The position of pose `i`.
pub fn position(i: usize) -> [f64; 3] {
    [i as f64, 2.0 * i as f64, 0.5 * i as f64]
}

/// The stamp of pose `i`: seconds and nanoseconds.
pub fn stamp(i: usize) -> (u32, u32) {
    (1_700_000_000 + i as u32, 250_000_000)
}

/// A `geometry_msgs/PoseStamped`, for the encoders below.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseStamped {
    /// The ROS 1 header's sequence number (CDR has none).
    pub seq: u32,
    /// Seconds and nanoseconds.
    pub stamp: (u32, u32),
    pub frame: String,
    pub position: [f64; 3],
    pub orientation: [f64; 4],
}

impl PoseStamped {
    /// Pose `i` of the logs here: frame `map`, identity orientation.
    pub fn of(i: usize) -> Self {
        let (position, orientation) = (position(i), [0.0, 0.0, 0.0, 1.0]);
        Self { seq: i as u32, stamp: stamp(i), frame: "map".into(), position, orientation }
    }

    /// The message in little-endian CDR (after its 4-byte encapsulation header).
    pub fn cdr(&self) -> Vec<u8> {
        let mut out = vec![0, 1, 0, 0];
        out.extend(self.stamp.0.to_le_bytes());
        out.extend(self.stamp.1.to_le_bytes());
        out.extend((self.frame.len() as u32 + 1).to_le_bytes());
        out.extend(self.frame.as_bytes());
        out.push(0);
        while !(out.len() - 4).is_multiple_of(8) {
            out.push(0);
        }
        for v in self.position.iter().chain(&self.orientation) {
            out.extend(v.to_le_bytes());
        }
        out
    }

    /// The message in ROS 1's serialisation.
    pub fn ros1(&self) -> Vec<u8> {
        let mut out = self.seq.to_le_bytes().to_vec();
        out.extend(self.stamp.0.to_le_bytes());
        out.extend(self.stamp.1.to_le_bytes());
        out.extend((self.frame.len() as u32).to_le_bytes());
        out.extend(self.frame.as_bytes());
        for v in self.position.iter().chain(&self.orientation) {
            out.extend(v.to_le_bytes());
        }
        out
    }
}

/// A little-endian CDR `geometry_msgs/PoseStamped` of pose `i` (frame `map`) with the stamp's
/// nanoseconds `nanosec`.
pub fn cdr_pose_stamped_with(i: usize, nanosec: u32) -> Vec<u8> {
    PoseStamped { stamp: (stamp(i).0, nanosec), ..PoseStamped::of(i) }.cdr()
}

/// A little-endian CDR `geometry_msgs/PoseStamped` of pose `i`.
pub fn cdr_pose_stamped(i: usize) -> Vec<u8> {
    PoseStamped::of(i).cdr()
}

/// A ROS 1 `geometry_msgs/PoseStamped` of pose `i`.
pub fn ros1_pose_stamped(i: usize) -> Vec<u8> {
    PoseStamped::of(i).ros1()
}

/// How an MCAP file of the `mcap` crate's writer is laid out.
#[derive(Debug, Clone, Copy)]
pub struct McapLayout {
    /// `None`: messages at the top level; `Some(bytes)`: in chunks of about that size.
    pub chunk_size: Option<u64>,
    pub compression: Option<mcap::Compression>,
    /// The summary section (statistics, chunk indexes, repeated schemas and channels).
    pub summary: bool,
    /// CRCs of chunks, of the data section and of the summary.
    pub crcs: bool,
}

impl McapLayout {
    pub const UNCHUNKED: Self = Self { chunk_size: None, compression: None, summary: true, crcs: true };
    pub const CHUNKED: Self = Self { chunk_size: Some(400), compression: None, summary: true, crcs: true };
    pub const ZSTD: Self =
        Self { chunk_size: Some(600), compression: Some(mcap::Compression::Zstd), summary: true, crcs: true };
    pub const LZ4: Self =
        Self { chunk_size: Some(500), compression: Some(mcap::Compression::Lz4), summary: true, crcs: true };
    pub const ALL: [(&'static str, Self); 4] =
        [("unchunked", Self::UNCHUNKED), ("chunked", Self::CHUNKED), ("zstd", Self::ZSTD), ("lz4", Self::LZ4)];
}

/// An MCAP file of `n` poses (`PoseStamped` in CDR on [`TOPIC`]) and as many JSON messages on
/// `/other`, interleaved, written by the `mcap` crate's writer.
pub fn mcap(n: usize, layout: McapLayout) -> Vec<u8> {
    let mut buffer = Cursor::new(Vec::new());
    {
        let options = mcap::WriteOptions::new()
            .compression(layout.compression)
            .chunk_size(layout.chunk_size)
            .use_chunks(layout.chunk_size.is_some())
            .emit_summary_records(layout.summary)
            .emit_summary_offsets(layout.summary)
            .emit_statistics(layout.summary)
            .emit_chunk_indexes(layout.summary)
            .emit_message_indexes(layout.summary)
            .calculate_chunk_crcs(layout.crcs)
            .calculate_data_section_crc(layout.crcs)
            .calculate_summary_section_crc(layout.crcs);
        let mut writer = options.create(&mut buffer).expect("writer");
        let schema = writer.add_schema("geometry_msgs/msg/PoseStamped", "ros2msg", b"").expect("schema");
        let channel = writer.add_channel(schema, TOPIC, "cdr", &BTreeMap::new()).expect("channel");
        let other = writer.add_channel(0, "/other", "json", &BTreeMap::new()).expect("channel");
        for i in 0..n {
            let time = u64::from(stamp(i).0) * 1_000_000_000;
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: i as u32,
                log_time: time,
                publish_time: time,
            };
            writer.write_to_known_channel(&header, &cdr_pose_stamped(i)).expect("message");
            let header = mcap::records::MessageHeader { channel_id: other, ..header };
            writer.write_to_known_channel(&header, b"{\"n\": 1}").expect("message");
        }
        writer.finish().expect("finish");
    }
    buffer.into_inner()
}

/// The top-level records of an MCAP file: offset, opcode and body length, from the first
/// record to the footer (summary included).
pub fn mcap_records(bytes: &[u8]) -> Vec<(usize, u8, usize)> {
    let mut out = Vec::new();
    let mut pos = 8;
    while pos + 9 <= bytes.len() {
        let len = u64::from_le_bytes(bytes[pos + 1..pos + 9].try_into().unwrap()) as usize;
        out.push((pos, bytes[pos], len));
        if bytes[pos] == 0x02 {
            break;
        }
        pos += 9 + len;
    }
    out
}

/// Hand-made MCAP records, for what no writer makes.
pub mod raw {
    /// A record: opcode, body length, body.
    pub fn record(opcode: u8, body: &[u8]) -> Vec<u8> {
        let mut out = vec![opcode];
        out.extend((body.len() as u64).to_le_bytes());
        out.extend(body);
        out
    }

    /// A `u32`-length-prefixed string.
    pub fn string(bytes: &[u8]) -> Vec<u8> {
        let mut out = (bytes.len() as u32).to_le_bytes().to_vec();
        out.extend(bytes);
        out
    }

    pub fn header() -> Vec<u8> {
        record(0x01, &[string(b"ros2"), string(b"raw")].concat())
    }

    pub fn schema(id: u16, name: &[u8]) -> Vec<u8> {
        record(0x03, &[id.to_le_bytes().to_vec(), string(name), string(b"ros2msg"), string(b"")].concat())
    }

    pub fn channel(id: u16, schema: u16, topic: &[u8], encoding: &[u8]) -> Vec<u8> {
        let body =
            [id.to_le_bytes().to_vec(), schema.to_le_bytes().to_vec(), string(topic), string(encoding), string(b"")]
                .concat();
        record(0x04, &body)
    }

    /// A message record's body up to its data.
    pub fn message_head(channel: u16, sequence: u32, time: u64) -> Vec<u8> {
        [
            channel.to_le_bytes().to_vec(),
            sequence.to_le_bytes().to_vec(),
            time.to_le_bytes().to_vec(),
            time.to_le_bytes().to_vec(),
        ]
        .concat()
    }

    pub fn message(channel: u16, sequence: u32, time: u64, data: &[u8]) -> Vec<u8> {
        record(0x05, &[message_head(channel, sequence, time), data.to_vec()].concat())
    }

    /// A chunk record holding `records` compressed as `compression` into `compressed`, declaring
    /// `uncompressed_size` bytes and CRC 0.
    pub fn chunk(compression: &[u8], compressed: &[u8], uncompressed_size: u64) -> Vec<u8> {
        let body = [
            0u64.to_le_bytes().to_vec(),
            u64::MAX.to_le_bytes().to_vec(),
            uncompressed_size.to_le_bytes().to_vec(),
            0u32.to_le_bytes().to_vec(),
            string(compression),
            (compressed.len() as u64).to_le_bytes().to_vec(),
            compressed.to_vec(),
        ]
        .concat();
        record(0x06, &body)
    }

    /// The end of a file without a summary: data end (CRC 0), footer, magic.
    pub fn end() -> Vec<u8> {
        [record(0x0f, &0u32.to_le_bytes()), record(0x02, &[0u8; 20]), mcap::MAGIC.to_vec()].concat()
    }

    /// A whole file: magic, header, `records`, end.
    pub fn file(records: &[Vec<u8>]) -> Vec<u8> {
        [mcap::MAGIC.to_vec(), header(), records.concat(), end()].concat()
    }
}

/// A zstd frame holding `prefix` then `zeros` zero bytes, the zeros in RLE blocks of 128 KiB (4
/// bytes each): the shape of a zstd bomb, 32 kB per GiB. With `declare`, the frame header
/// declares its content size.
pub fn zstd_rle(prefix: &[u8], zeros: u64, declare: bool) -> Vec<u8> {
    const BLOCK: u64 = 128 << 10;
    let mut out = vec![0x28, 0xb5, 0x2f, 0xfd];
    if declare {
        // Frame header descriptor: 8-byte content size, single segment (no window descriptor).
        out.push(0b1110_0000);
        out.extend((prefix.len() as u64 + zeros).to_le_bytes());
    } else {
        // No content size; window descriptor: 2^(10+7) = 128 KiB.
        out.extend([0x00, 7 << 3]);
    }
    let block_header = |last: bool, kind: u32, size: u32| {
        let value = u32::from(last) | (kind << 1) | (size << 3);
        value.to_le_bytes()[..3].to_vec()
    };
    let mut blocks = Vec::new();
    for piece in prefix.chunks(BLOCK as usize) {
        blocks.push([block_header(false, 0, piece.len() as u32), piece.to_vec()].concat());
    }
    let mut left = zeros;
    while left > 0 {
        let size = left.min(BLOCK);
        blocks.push([block_header(false, 1, size as u32), vec![0]].concat());
        left -= size;
    }
    if blocks.is_empty() {
        blocks.push(block_header(false, 0, 0));
    }
    let last = blocks.len() - 1;
    blocks[last][0] |= 1;
    out.extend(blocks.concat());
    out
}

/// A record field of a ROS 1 bag header: `u32` length, `name=value`.
pub fn ros1_field(name: &str, value: &[u8]) -> Vec<u8> {
    let mut out = ((name.len() + 1 + value.len()) as u32).to_le_bytes().to_vec();
    out.extend(name.as_bytes());
    out.push(b'=');
    out.extend(value);
    out
}

/// A ROS 1 record: header length, header fields, data length, data.
pub fn ros1_record(out: &mut Vec<u8>, header: &[Vec<u8>], data: &[u8]) {
    let header: Vec<u8> = header.concat();
    out.extend((header.len() as u32).to_le_bytes());
    out.extend(&header);
    out.extend((data.len() as u32).to_le_bytes());
    out.extend(data);
}

/// A ROS 1 message record (op 2) on connection `conn` at `time` (seconds, nanoseconds).
pub fn ros1_message_record(out: &mut Vec<u8>, conn: u32, (sec, nsec): (u32, u32), data: &[u8]) {
    let time = [sec.to_le_bytes(), nsec.to_le_bytes()].concat();
    ros1_record(
        out,
        &[ros1_field("op", &[2]), ros1_field("conn", &conn.to_le_bytes()), ros1_field("time", &time)],
        data,
    );
}

fn ros1_connection(conn: u32, topic: &str, kind: &str) -> Vec<u8> {
    let mut out = Vec::new();
    let data = [ros1_field("topic", topic.as_bytes()), ros1_field("type", kind.as_bytes()), ros1_field("md5sum", b"*")]
        .concat();
    ros1_record(
        &mut out,
        &[ros1_field("op", &[7]), ros1_field("conn", &conn.to_le_bytes()), ros1_field("topic", topic.as_bytes())],
        &data,
    );
    out
}

/// Compresses a ROS 1 chunk's records as `compression` says (`none`, `bz2`, `lz4`).
pub fn ros1_compress(compression: &str, plain: &[u8]) -> Vec<u8> {
    match compression {
        "bz2" => {
            let mut out = Vec::new();
            bzip2::read::BzEncoder::new(plain, bzip2::Compression::fast()).read_to_end(&mut out).expect("bz2");
            out
        }
        "lz4" => {
            let mut encoder = lz4_flex::frame::FrameEncoder::new(Vec::new());
            encoder.write_all(plain).expect("lz4");
            encoder.finish().expect("lz4")
        }
        _ => plain.to_vec(),
    }
}

/// A ROS 1 bag of `n` `PoseStamped` on [`TOPIC`] (connection 0) and as many strings on
/// `/chatter` (connection 1), in chunks of `per_chunk` poses compressed as `compression`, each
/// followed by its index data records; connection and chunk info records at the end. `extra`,
/// one message record on `/chatter` (a large one, for a bomb) or nothing, goes first in the
/// first chunk, indexed.
pub fn ros1_bag_with(n: usize, compression: &str, per_chunk: usize, extra: &[u8]) -> Vec<u8> {
    let poses: Vec<((u32, u32), Vec<u8>)> = (0..n).map(|i| (stamp(i), ros1_pose_stamped(i))).collect();
    ros1_bag_of(&poses, compression, per_chunk, extra)
}

/// A ROS 1 bag as [`ros1_bag_with`] of the `PoseStamped` messages `poses`: each its stamp and
/// its ROS 1 bytes (a string on `/chatter` at the same time after each).
pub fn ros1_bag_of(poses: &[((u32, u32), Vec<u8>)], compression: &str, per_chunk: usize, extra: &[u8]) -> Vec<u8> {
    let mut body = Vec::new();
    let mut infos = Vec::new();
    for (index, chunk) in poses.chunks(per_chunk.max(1)).enumerate() {
        let mut plain = Vec::new();
        // Per connection: the stamp and offset of each message.
        let mut offsets = [Vec::new(), Vec::new()];
        if index == 0 {
            plain.extend(ros1_connection(0, TOPIC, "geometry_msgs/PoseStamped"));
            plain.extend(ros1_connection(1, "/chatter", "std_msgs/String"));
            if !extra.is_empty() {
                offsets[1].push(((0, 0), plain.len() as u32));
                plain.extend(extra);
            }
        }
        for (stamp, message) in chunk {
            offsets[0].push((*stamp, plain.len() as u32));
            ros1_message_record(&mut plain, 0, *stamp, message);
            offsets[1].push((*stamp, plain.len() as u32));
            ros1_message_record(&mut plain, 1, *stamp, b"\x02\0\0\0hi");
        }
        let data = ros1_compress(compression, &plain);
        let chunk_pos = (13 + 4096 + body.len()) as u64;
        ros1_record(
            &mut body,
            &[
                ros1_field("op", &[5]),
                ros1_field("compression", compression.as_bytes()),
                ros1_field("size", &(plain.len() as u32).to_le_bytes()),
            ],
            &data,
        );
        for (conn, offsets) in offsets.iter().enumerate() {
            let conn = conn as u32;
            let entries: Vec<u8> = offsets
                .iter()
                .flat_map(|((sec, nsec), offset)| {
                    [sec.to_le_bytes(), nsec.to_le_bytes(), offset.to_le_bytes()].concat()
                })
                .collect();
            ros1_record(
                &mut body,
                &[
                    ros1_field("op", &[4]),
                    ros1_field("ver", &1u32.to_le_bytes()),
                    ros1_field("conn", &conn.to_le_bytes()),
                    ros1_field("count", &(offsets.len() as u32).to_le_bytes()),
                ],
                &entries,
            );
        }
        infos.push((chunk_pos, chunk.len() as u32));
    }
    let index_pos = (13 + 4096 + body.len()) as u64;
    body.extend(ros1_connection(0, TOPIC, "geometry_msgs/PoseStamped"));
    body.extend(ros1_connection(1, "/chatter", "std_msgs/String"));
    for (chunk_pos, count) in &infos {
        let data = [0u32.to_le_bytes(), count.to_le_bytes(), 1u32.to_le_bytes(), count.to_le_bytes()].concat();
        ros1_record(
            &mut body,
            &[
                ros1_field("op", &[6]),
                ros1_field("ver", &1u32.to_le_bytes()),
                ros1_field("chunk_pos", &chunk_pos.to_le_bytes()),
                ros1_field("count", &2u32.to_le_bytes()),
            ],
            &data,
        );
    }
    let mut out = b"#ROSBAG V2.0\n".to_vec();
    let header = [
        ros1_field("op", &[3]),
        ros1_field("index_pos", &index_pos.to_le_bytes()),
        ros1_field("conn_count", &2u32.to_le_bytes()),
        ros1_field("chunk_count", &(infos.len() as u32).to_le_bytes()),
    ];
    let header_len: usize = header.iter().map(Vec::len).sum();
    ros1_record(&mut out, &header, &vec![b' '; 4096 - 8 - header_len]);
    assert_eq!(out.len(), 13 + 4096);
    out.extend(body);
    out
}

/// A ROS 1 bag of `n` poses, as [`ros1_bag_with`] without extra records.
pub fn ros1_bag(n: usize, compression: &str, per_chunk: usize) -> Vec<u8> {
    ros1_bag_with(n, compression, per_chunk, &[])
}

/// A rosbag2 sqlite3 file at `path` (the tables rosbag2 writes): `n` poses on [`TOPIC`],
/// compressed per message (zstd) or not, and strings on `/chatter`.
pub fn sqlite_bag(path: &Path, n: usize, compress: bool) {
    let poses: Vec<(i64, Vec<u8>)> =
        (0..n).map(|i| (i64::from(stamp(i).0) * 1_000_000_000, cdr_pose_stamped(i))).collect();
    sqlite_bag_of(path, &poses, compress);
}

/// A rosbag2 sqlite3 file as [`sqlite_bag`] of the `PoseStamped` messages `poses`: each its
/// timestamp (ns) and its CDR bytes (a string on `/chatter` at the same time after each).
pub fn sqlite_bag_of(path: &Path, poses: &[(i64, Vec<u8>)], compress: bool) {
    let _ = std::fs::remove_file(path);
    let db = rusqlite::Connection::open(path).expect("sqlite");
    db.execute_batch(
        "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
         CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
             serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,
             data BLOB NOT NULL);
         CREATE INDEX timestamp_idx ON messages (timestamp ASC);
         INSERT INTO topics VALUES (1, '/pose', 'geometry_msgs/msg/PoseStamped', 'cdr', ''),
             (2, '/chatter', 'std_msgs/msg/String', 'cdr', '');",
    )
    .expect("tables");
    for (time, data) in poses {
        let data = if compress { zstd::bulk::compress(data, 1).expect("zstd") } else { data.clone() };
        db.execute(
            "INSERT INTO messages (topic_id, timestamp, data) VALUES (1, ?1, ?2)",
            rusqlite::params![time, data],
        )
        .expect("insert");
        db.execute(
            "INSERT INTO messages (topic_id, timestamp, data) VALUES (2, ?1, x'0001000003000000686900')",
            [time],
        )
        .expect("insert");
    }
}

/// The text formats, with a file of `n` poses in each: (name, extension, contents).
pub fn text_files(n: usize) -> Vec<(&'static str, &'static str, String)> {
    let mut tum = String::from("# timestamp tx ty tz qx qy qz qw\n");
    let mut kitti = String::new();
    let mut euroc = String::from("#timestamp [ns],p_x,p_y,p_z,q_w,q_x,q_y,q_z\n");
    let mut tuc = String::new();
    let mut g2o = String::new();
    let mut g2o_3d = String::new();
    let mut toro = String::new();
    let mut csv = String::from("t,x,y,z\n");
    let mut detections = String::from("odom2 0 0 0 0\n");
    for i in 0..n {
        let [x, y, z] = position(i);
        let t = i as f64 + 0.25;
        let yaw = 0.1 * i as f64;
        let (s, c) = (yaw / 2.0).sin_cos();
        tum += &format!("{t} {x} {y} {z} 0 0 {s} {c}\n");
        let (sy, cy) = yaw.sin_cos();
        kitti += &format!("{t} {cy} {} 0 {x} {sy} {cy} 0 {y} 0 0 1 {z}\n", -sy);
        euroc += &format!("{},{x},{y},{z},{c},0,0,{s}\n", 1_403_636_579_758_555_392u64 + 5_000_000 * i as u64);
        tuc += &format!("point2 {t} {x} {y} 0 0 0 0\nangle {t} {yaw} 0\n");
        g2o += &format!("VERTEX_SE2 {i} {x} {y} {yaw}\n");
        g2o_3d += &format!("VERTEX_SE3:QUAT {i} {x} {y} {z} 0 0 {s} {c}\n");
        toro += &format!("VERTEX2 {i} {x} {y} {yaw}\n");
        csv += &format!("{t},{x},{y},{z}\n");
        if i >= 2 {
            detections += &format!("loop {t} {} 0.5\n", t - 2.0);
        }
    }
    for i in 1..n {
        g2o += &format!("EDGE_SE2 {} {i} 1 2 0.1 1 0 0 1 0 1\n", i - 1);
        g2o_3d += &format!("EDGE_SE3:QUAT {} {i} 1 2 0.5 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n", i - 1);
        toro += &format!("EDGE2 {} {i} 1 2 0.1 1 0 1 1 0 0\n", i - 1);
    }
    vec![
        ("tum", "tum", tum),
        ("kitti", "txt", kitti),
        ("euroc", "csv", euroc),
        ("tuc", "txt", tuc),
        ("g2o", "g2o", g2o),
        ("g2o-3d", "g2o", g2o_3d),
        ("toro", "graph", toro),
        ("csv", "csv", csv),
        ("detections", "txt", detections),
    ]
}
