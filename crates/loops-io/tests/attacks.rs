//! The attacks that found the reader failures of the first attack sweep ("nothing lost, nothing aborted"),
//! one test (or a few) per item: data dropped without a word (items 6, 7, 8, 10), aborts from
//! allocations a corrupt length or a bomb declares (11, 12, 16) and messages that were not one
//! line (19). Each builds its input here, and checks that the reader refuses it with one line
//! naming the file, the place and the defect, or reads it within bounded memory (counted by a
//! global allocator, `support/peak.rs`).

// The readers' errors (`IoError`) are returned as they are, through the measuring closures.
#![allow(clippy::result_large_err)]

use std::path::{Path, PathBuf};

use loops_io::{
    IoError, McapOptions, MessageEncoding, PoseType, Timing, decode_poses, list_topics, read_detections, read_euroc,
    read_kitti, read_mcap, read_pose_graph, read_ros1, read_rosbag2, read_trajectory, read_tuc, read_tum,
};

#[path = "support/peak.rs"]
mod peak;
mod support;

use peak::peak_of;
use support::logs::{self, McapLayout, TOPIC, mcap, mcap_records, raw};

#[global_allocator]
static ALLOCATOR: peak::Counting = peak::Counting;

/// A scratch file in the target folder holding `bytes` (one name per test: tests run in
/// parallel).
fn write(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("attacks");
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("scratch file");
    path
}

/// A message as the issue wants it: one line, no terminal escapes, no library internals, and
/// starting with the file.
fn assert_one_line(message: &str, path: &Path) {
    let lower = message.to_lowercase();
    assert!(!message.contains('\n') && !message.contains('\r'), "several lines: {message:?}");
    assert!(!message.contains('\x1b'), "an escape sequence: {message:?}");
    assert!(!lower.contains("registry") && !lower.contains("backtrace"), "library internals: {message:?}");
    assert!(message.starts_with(&path.display().to_string()), "does not start with the file: {message:?}");
}

fn pose_options() -> McapOptions {
    McapOptions::default().topic(TOPIC)
}

/// Reads `bytes` as an MCAP file: the error (which the topic list gives too), one line.
fn mcap_error(name: &str, bytes: &[u8]) -> IoError {
    let path = write(name, bytes);
    let error = read_mcap(&path, &pose_options()).expect_err("a broken file");
    assert_one_line(&error.to_string(), &path);
    let listed = list_topics(&path).expect_err("the topic list walks the whole file too");
    assert_one_line(&listed.to_string(), &path);
    error
}

/// The offset of the first top-level record of `opcode`, and of all of them.
fn offsets(bytes: &[u8], opcode: u8) -> Vec<usize> {
    mcap_records(bytes).iter().filter(|record| record.1 == opcode).map(|record| record.0).collect()
}

/// The offset in `bytes` of the message record holding pose `i`'s CDR data (uncompressed).
fn message_of_pose(bytes: &[u8], i: usize) -> usize {
    let data = logs::cdr_pose_stamped(i);
    let at = bytes.windows(data.len()).position(|window| window == data).expect("the pose's message");
    at - 22 - 9
}

// ---- item 6: a chunk's opcode, messages lost against the file's own counts ------------------

#[test]
fn item6_a_chunk_with_a_flipped_opcode_is_an_error_at_its_offset() {
    for summary in [true, false] {
        let bytes = mcap(200, McapLayout { summary, ..McapLayout::ZSTD });
        let chunks = offsets(&bytes, 0x06);
        assert!(chunks.len() > 4, "many chunks");
        let mut broken = bytes.clone();
        broken[chunks[2]] = 0x8c;
        let error = mcap_error(&format!("flipped-chunk-{summary}.mcap"), &broken);
        assert!(matches!(error, IoError::Mcap { .. }), "{error:?}");
        assert_eq!(error.offset(), Some(chunks[2] as u64), "{error}");
        let message = error.to_string();
        assert!(message.contains("unknown opcode 0x8c holds a chunk") && message.contains("lost"), "{message}");
    }
}

#[test]
fn item6_a_chunk_the_summary_indexes_must_be_there() {
    // The opcode flipped and the chunk header garbled: the record no longer looks like a chunk,
    // but the summary's chunk index still points at it.
    let bytes = mcap(200, McapLayout { crcs: false, ..McapLayout::ZSTD });
    let chunk = offsets(&bytes, 0x06)[3];
    let mut broken = bytes.clone();
    broken[chunk] = 0x8c;
    broken[chunk + 9 + 28..chunk + 9 + 32].copy_from_slice(&[0xff; 4]);
    let error = mcap_error("garbled-chunk.mcap", &broken);
    // The message index records after the chunk now follow no chunk: the first is refused where
    // it stands, before the summary's chunk index is reached.
    let index = *offsets(&bytes, 0x07).iter().find(|&&at| at > chunk).expect("the chunk's message index");
    assert_eq!(error.offset(), Some(index as u64), "{error}");
    assert!(error.to_string().contains("a message index record that follows no chunk"), "{error}");
    // Without them (one record of an extension in their place, which reads as nothing lost), the
    // summary's chunk index names the chunk.
    let mut no_index = broken.clone();
    let chunks = offsets(&bytes, 0x06);
    let next = chunks.iter().find(|&&at| at > chunk).copied().unwrap_or(offsets(&bytes, 0x0f)[0]);
    no_index[index] = 0x8d;
    no_index[index + 1..index + 9].copy_from_slice(&((next - index - 9) as u64).to_le_bytes());
    no_index[index + 9..next].fill(0xff);
    let error = mcap_error("garbled-chunk-no-index.mcap", &no_index);
    assert_eq!(error.offset(), Some(chunk as u64), "{error}");
    let message = error.to_string();
    assert!(message.contains("chunk index") && message.contains("unknown opcode 0x8c"), "{message}");
}

#[test]
fn item6_a_message_lost_at_the_top_level_is_counted_by_the_statistics() {
    let bytes = mcap(50, McapLayout { crcs: false, ..McapLayout::UNCHUNKED });
    let message = message_of_pose(&bytes, 17);
    let mut broken = bytes.clone();
    broken[message] = 0x85;
    // The record reads as a message on a channel of the file: refused where it stands.
    let error = mcap_error("lost-message.mcap", &broken);
    assert_eq!(error.offset(), Some(message as u64), "{error}");
    let text = error.to_string();
    assert!(text.contains(&format!("unknown opcode 0x85 reads as a message on channel 1 ({TOPIC})")), "{text}");
    // A record that does not read as one (its channel id corrupt too) is skipped, as the format
    // asks, and the statistics count the loss.
    broken[message + 9..message + 11].copy_from_slice(&[0x77, 0x77]);
    let error = mcap_error("lost-message-unknown-channel.mcap", &broken);
    let statistics = offsets(&bytes, 0x0b)[0];
    assert_eq!(error.offset(), Some(statistics as u64), "{error}");
    let text = error.to_string();
    assert!(
        text.contains("counts 50 messages on channel")
            && text.contains(&format!("({TOPIC}), but the data section holds 49: 1 messages lost")),
        "{text}"
    );
    assert!(text.contains(&format!("the first at offset {message} (opcode 0x85)")), "{text}");
}

#[test]
fn item6_a_statistics_record_lost_with_a_message_is_noticed_by_the_summary_offsets() {
    // Found by the long sweep: without CRCs, a message whose opcode is corrupt and a statistics
    // record whose opcode is corrupt too left nothing to count the loss against.
    let bytes = mcap(30, McapLayout { crcs: false, ..McapLayout::UNCHUNKED });
    let statistics = offsets(&bytes, 0x0b)[0];
    let mut broken = bytes.clone();
    let message = message_of_pose(&bytes, 9);
    broken[message] = 0x34;
    // Its channel id corrupt too, so that the record does not read as a message (which is
    // refused where it stands).
    broken[message + 9..message + 11].copy_from_slice(&[0x77, 0x77]);
    broken[statistics] = 0xa3;
    let error = mcap_error("lost-statistics.mcap", &broken);
    let text = error.to_string();
    assert!(
        text.contains(&format!(
            "group at offset {statistics} holds statistics records, but the record there has opcode 0xa3 (unknown)"
        )),
        "{text}"
    );
    // A message turned into a header record is a second header: an error where it stands.
    let message = message_of_pose(&bytes, 4);
    let mut broken = bytes.clone();
    broken[message] = 0x01;
    broken[statistics] = 0xa3;
    let error = mcap_error("second-header.mcap", &broken);
    assert_eq!(error.offset(), Some(message as u64), "{error}");
    assert!(error.to_string().contains("a header record after the first record"), "{error}");
}

#[test]
fn item6_messages_lost_inside_a_chunk_are_counted_by_its_message_index() {
    // An uncompressed chunk without CRCs: a message moved to another channel, or whose opcode
    // is flipped, is found by the chunk's message indexes and its record kinds.
    let bytes = mcap(60, McapLayout { crcs: false, ..McapLayout::CHUNKED });
    let message = message_of_pose(&bytes, 20);
    let chunk = offsets(&bytes, 0x06).into_iter().rev().find(|&c| c < message).expect("its chunk");
    let other = bytes[message + 9] + 1;
    let mut moved = bytes.clone();
    moved[message + 9] = other;
    let error = mcap_error("moved-message.mcap", &moved);
    assert_eq!(error.offset(), Some(chunk as u64), "{error}");
    assert!(error.to_string().contains("its message index (the record at offset"), "{error}");
    let mut flipped = bytes.clone();
    flipped[message] = 0x85;
    let error = mcap_error("flipped-message.mcap", &flipped);
    assert_eq!(error.offset(), Some(chunk as u64), "{error}");
    assert!(error.to_string().contains("a record of opcode 0x85 (unknown) in a chunk"), "{error}");
}

#[test]
fn item6_a_ros1_message_moved_to_another_connection_is_counted_by_the_index() {
    let bag = logs::ros1_bag(12, "none", 4);
    let data = logs::ros1_pose_stamped(6);
    let at = bag.windows(data.len()).position(|window| window == data).expect("pose 6");
    let conn = bag[..at].windows(5).rposition(|window| window == b"conn=").expect("its conn field") + 5;
    let mut moved = bag.clone();
    moved[conn] = 1;
    let path = write("moved.bag", &moved);
    let error = read_ros1(&path, &pose_options()).unwrap_err();
    assert_one_line(&error.to_string(), &path);
    let chunk = bag[..at].windows(13).rposition(|window| window == b"compression=n").expect("its chunk") - 16;
    assert_eq!(error.offset(), Some(chunk as u64), "{error}");
    assert!(error.to_string().contains("the chunk holds 3 messages on connection 0, but its index data"), "{error}");
    assert!(error.to_string().ends_with("lists 4: 1 messages lost (a record in the chunk is corrupt)"), "{error}");
}

// ---- item 7: unknown g2o / TORO tags ----------------------------------------------------------

#[test]
fn item7_an_unknown_graph_tag_is_an_error_naming_line_and_tag() {
    for (name, text, line, shown) in [
        ("vertx2.graph", "VERTEX2 0 0 0 0\nVERTEX2 1 1 0 0\nVERTX2 2 2 0 0\nVERTEX2 3 3 0 0\n", 3, "\"VERTX2\""),
        ("nul.g2o", "VERTEX_SE2 0 0 0 0\nVERTEX_SE2\0 1 1 0 0\nVERTEX_SE2 2 2 0 0\n", 2, "\"VERTEX_SE2\\0\""),
    ] {
        let path = write(name, text.as_bytes());
        let error = read_pose_graph(&path, &Timing::FromFile).unwrap_err();
        assert_eq!(error.line(), Some(line), "{error}");
        assert!(error.to_string().contains(&format!("unknown tag {shown}")), "{error}");
        assert_one_line(&error.to_string(), &path);
        assert!(read_trajectory(&path, None).is_err());
    }
    // The types g2o defines that are not poses are still skipped.
    let path = write(
        "known.g2o",
        b"VERTEX_SE2 0 0 0 0\nFIX 0\nVERTEX_XY 7 1 1\nVERTEX_SE2 1 1 0 0\nEDGE_SE2_XY 0 7 1 1 1 0 1\n",
    );
    assert_eq!(read_pose_graph(&path, &Timing::FromFile).unwrap().vertices.len(), 2);
}

#[test]
fn item7_unknown_librsf_record_types_are_errors_too() {
    let path = write("poitn2.txt", b"point2 0 0 0 0 0 0 0\npoitn2 1 1 0 0 0 0 0\npoint2 2 2 0 0 0 0 0\n");
    let error = read_tuc(&path).unwrap_err();
    assert_eq!(error.line(), Some(2), "{error}");
    assert!(error.to_string().contains("unknown record type \"poitn2\""), "{error}");
    let path = write("lop.txt", b"odom2 0 0 0 0\nloop 5 1 1\nlop 6 2 1\n");
    let error = read_detections(&path).unwrap_err();
    assert_eq!(error.line(), Some(3), "{error}");
    // Found by the sweep: a first `loop` line whose numbers are corrupt was taken for a header.
    let path = write("loop-header.txt", b"odom2 0 0 0 0\nloop 2.2\x0b 0.25x\nloop 3 1 1\n");
    let error = read_detections(&path).unwrap_err();
    assert_eq!(error.line(), Some(2), "{error}");
}

// ---- item 8: KITTI rotation blocks that are no rotations ------------------------------------

#[test]
fn item8_a_kitti_block_that_is_no_rotation_is_an_error_naming_the_defect() {
    let good = "0 1 0 0 1 0 1 0 2 0 0 1 3\n";
    for (block, defect) in [
        ("0 0 0 5 0 0 0 6 0 0 0 7", "is zero"),
        ("-1 0 0 5 0 1 0 6 0 0 1 7", "is a reflection (determinant -1.000000)"),
        ("1 0 0 5 0 1 0 6 0 0 2 7", "is not orthonormal: RᵀR differs from the identity by up to 3.000e0"),
        ("1 0.1 0 5 0 1 0 6 0 0 1 7", "is not orthonormal"),
    ] {
        let path = write("bad-block.txt", format!("{good}1 {block}\n").as_bytes());
        let error = read_kitti(&path, &Timing::FromFile).unwrap_err();
        assert_eq!(error.line(), Some(2), "{error}");
        assert!(error.to_string().contains(defect), "{defect}: {error}");
        assert_one_line(&error.to_string(), &path);
    }
    // Printed to 6 digits, a rotation is ~1e-6 from orthonormal: it reads.
    let path = write("printed.txt", b"0 0.999999 0.001414 0 1 -0.001414 0.999999 0 2 0 0 1 3\n");
    assert_eq!(read_kitti(&path, &Timing::FromFile).unwrap().len(), 1);
}

// ---- item 10: CRCs, bytes after the end, nanoseconds ----------------------------------------

#[test]
fn item10_the_data_and_summary_crcs_are_checked() {
    let bytes = mcap(30, McapLayout::UNCHUNKED);
    let message = message_of_pose(&bytes, 7);
    let mut broken = bytes.clone();
    broken[message + 9 + 22 + 30] ^= 0x04; // a bit of pose 7's x
    let error = mcap_error("data-crc.mcap", &broken);
    assert_eq!(error.offset(), Some(offsets(&bytes, 0x0f)[0] as u64), "{error}");
    assert!(error.to_string().contains("the data section is corrupt: its CRC is"), "{error}");

    let statistics = offsets(&bytes, 0x0b)[0];
    let mut broken = bytes.clone();
    broken[statistics + 9] ^= 0x01; // the message count
    let error = mcap_error("summary-crc.mcap", &broken);
    assert_eq!(error.offset(), Some(offsets(&bytes, 0x02)[0] as u64), "{error}");
    assert!(error.to_string().contains("the summary section is corrupt: its CRC is"), "{error}");
}

#[test]
fn item10_bytes_after_the_closing_magic_are_an_error() {
    let mut bytes = mcap(10, McapLayout::ZSTD);
    let end = bytes.len();
    bytes.extend(b"trailing");
    let error = mcap_error("trailing.mcap", &bytes);
    assert_eq!(error.offset(), Some(end as u64), "{error}");
    assert!(error.to_string().contains("8 bytes follow the closing MCAP magic bytes"), "{error}");
}

#[test]
fn item10_a_stamp_of_a_billion_nanoseconds_or_more_is_an_error() {
    let data = logs::cdr_pose_stamped_with(3, 1_000_000_000);
    let error = decode_poses(PoseType::PoseStamped, MessageEncoding::Cdr, &data).unwrap_err();
    assert!(error.to_string().contains("header.stamp.nanosec is 1000000000 ns"), "{error}");
    let mut ros1 = logs::ros1_pose_stamped(3);
    ros1[8..12].copy_from_slice(&2_000_000_000u32.to_le_bytes());
    let error = decode_poses(PoseType::PoseStamped, MessageEncoding::Ros1, &ros1).unwrap_err();
    assert!(error.to_string().contains("header.stamp.nsecs is 2000000000 ns"), "{error}");
    let json = br#"{"timestamp": {"sec": 1, "nsec": 1000000000}, "frame_id": "m", "pose": {}}"#;
    assert!(decode_poses(PoseType::FoxglovePoseInFrame, MessageEncoding::Json, json).is_err());
    // In a file: the message is named.
    let file = raw::file(&[
        raw::schema(1, b"geometry_msgs/msg/PoseStamped"),
        raw::channel(1, 1, TOPIC.as_bytes(), b"cdr"),
        raw::message(1, 0, 5, &logs::cdr_pose_stamped(0)),
        raw::message(1, 1, 6, &data),
    ]);
    let path = write("nanosec.mcap", &file);
    let error = read_mcap(&path, &pose_options()).unwrap_err();
    assert_one_line(&error.to_string(), &path);
    assert!(matches!(error, IoError::Message { .. }), "{error:?}");
    assert!(error.to_string().contains("header.stamp.nanosec is 1000000000 ns"), "{error}");
}

// ---- item 11: lengths checked before allocating ---------------------------------------------

/// Most a reader may allocate for a small corrupt file: its 1 MiB read buffer and change.
const SMALL_FILE_PEAK: usize = 4 << 20;

#[test]
fn item11_a_string_declaring_4_gib_allocates_nothing() {
    let mut schema = raw::schema(1, b"geometry_msgs/msg/PoseStamped");
    schema[9 + 2..9 + 6].copy_from_slice(&u32::MAX.to_le_bytes());
    let file = raw::file(&[schema]);
    assert!(file.len() < 150, "a tiny file: {} bytes", file.len());
    let path = write("huge-name.mcap", &file);
    let (result, peak) = peak_of(|| read_mcap(&path, &McapOptions::default()));
    let error = result.unwrap_err();
    assert!(peak < SMALL_FILE_PEAK, "{peak} bytes allocated");
    assert_eq!(error.offset(), Some(8 + raw::header().len() as u64), "{error}");
    assert!(
        error.to_string().contains("its name is declared 4294967295 bytes long, but the schema record has"),
        "{error}"
    );
    assert_one_line(&error.to_string(), &path);

    let mut channel = raw::channel(1, 0, TOPIC.as_bytes(), b"json");
    let metadata = channel.len() - 4;
    channel[metadata..].copy_from_slice(&u32::MAX.to_le_bytes());
    let path = write("huge-metadata.mcap", &raw::file(&[channel]));
    let (result, peak) = peak_of(|| read_mcap(&path, &McapOptions::default()));
    assert!(peak < SMALL_FILE_PEAK, "{peak} bytes allocated");
    let error = result.unwrap_err();
    assert!(error.to_string().contains("its metadata is declared 4294967295 bytes long"), "{error}");
}

#[test]
fn item11_message_decoders_check_lengths_first() {
    let mut cdr = logs::cdr_pose_stamped(0);
    cdr[12..16].copy_from_slice(&u32::MAX.to_le_bytes()); // frame_id's length
    let (result, peak) = peak_of(|| decode_poses(PoseType::PoseStamped, MessageEncoding::Cdr, &cdr));
    assert!(result.is_err() && peak < 1 << 16, "{peak}");
    let mut ros1 = logs::ros1_pose_stamped(0);
    ros1[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    let (result, peak) = peak_of(|| decode_poses(PoseType::PoseStamped, MessageEncoding::Ros1, &ros1));
    assert!(result.is_err() && peak < 1 << 16, "{peak}");
    // Protobuf: field 2 (frame_id) declaring 2^62 bytes.
    let protobuf = [0x12, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x40];
    let (result, peak) = peak_of(|| decode_poses(PoseType::FoxglovePoseInFrame, MessageEncoding::Protobuf, &protobuf));
    assert!(result.is_err() && peak < 1 << 16, "{peak}");
}

#[test]
fn item11_a_ros1_header_declaring_4_gib_allocates_nothing() {
    let mut bag = logs::ros1_bag(3, "none", 3);
    // The first record after the bag header: the chunk. Its header length, then its first field.
    let chunk = 13 + 4096;
    bag[chunk + 4..chunk + 8].copy_from_slice(&u32::MAX.to_le_bytes());
    let path = write("huge-field.bag", &bag);
    let (result, peak) = peak_of(|| read_ros1(&path, &McapOptions::default()));
    assert!(peak < SMALL_FILE_PEAK, "{peak}");
    let error = result.unwrap_err();
    assert_eq!(error.offset(), Some(chunk as u64), "{error}");
    assert_one_line(&error.to_string(), &path);
}

// ---- item 12: bombs -------------------------------------------------------------------------

/// A file of one pose on /pose, and a chunk holding one message on /other of `size` zero bytes,
/// compressed as a zstd bomb (32 kB per GiB).
fn mcap_bomb(size: u64, channel: u16) -> Vec<u8> {
    let head = raw::message_head(channel, 1, 7);
    let record_len = head.len() as u64 + size;
    let prefix = [vec![0x05], record_len.to_le_bytes().to_vec(), head].concat();
    let compressed = logs::zstd_rle(&prefix, size, false);
    raw::file(&[
        raw::schema(1, b"geometry_msgs/msg/PoseStamped"),
        raw::channel(1, 1, TOPIC.as_bytes(), b"cdr"),
        raw::channel(2, 0, b"/other", b"json"),
        raw::message(1, 0, 5, &logs::cdr_pose_stamped(0)),
        raw::chunk(b"zstd", &compressed, 9 + record_len),
    ])
}

#[test]
fn item12_an_mcap_zstd_bomb_is_read_in_bounded_memory() {
    let size = 256 << 20;
    let bomb = mcap_bomb(size, 2);
    assert!(bomb.len() < 16 << 10, "{} bytes", bomb.len());
    let path = write("bomb.mcap", &bomb);
    let (table, peak) = peak_of(|| read_mcap(&path, &pose_options()));
    assert_eq!(table.unwrap().len(), 1);
    assert!(peak < 8 << 20, "{peak} bytes allocated for a {size}-byte message not read");
    let (topics, peak) = peak_of(|| list_topics(&path));
    assert_eq!(topics.unwrap().iter().map(|t| t.message_count).collect::<Vec<_>>(), [1, 1]);
    assert!(peak < 8 << 20, "{peak}");

    // On the topic read, the message is refused by its length, before it is decompressed.
    let path = write("bomb-pose.mcap", &mcap_bomb(100 << 20, 1));
    let (result, peak) = peak_of(|| read_mcap(&path, &pose_options()));
    assert!(peak < 8 << 20, "{peak}");
    let error = result.unwrap_err();
    assert!(error.to_string().contains("over the limit of 64 MiB for a pose message"), "{error}");

    // A chunk declaring more than 4 GiB is refused before anything is decompressed.
    let declared = 5u64 << 30;
    let chunk = raw::chunk(b"zstd", &logs::zstd_rle(&[], 1 << 20, false), declared);
    let error = mcap_error("bomb-declared.mcap", &raw::file(&[chunk]));
    assert!(error.to_string().contains(&format!("the chunk declares {declared} bytes decompressed")), "{error}");
}

#[test]
fn item12_a_ros1_chunk_bomb_is_read_in_bounded_memory() {
    let size = 64usize << 20;
    let mut extra = Vec::new();
    logs::ros1_message_record(&mut extra, 1, (0, 0), &vec![0u8; size]);
    let bag = logs::ros1_bag_with(5, "lz4", 5, &extra);
    drop(extra);
    assert!(bag.len() < size / 100, "{} bytes", bag.len());
    let path = write("bomb.bag", &bag);
    drop(bag);
    let (table, peak) = peak_of(|| read_ros1(&path, &pose_options()));
    assert_eq!(table.unwrap().len(), 5);
    // The lz4 frame decoder holds two blocks of 4 MiB.
    assert!(peak < 16 << 20, "{peak} bytes allocated for a chunk of {size}");
}

#[test]
fn item12_a_file_compressed_bag_may_not_decompress_past_a_thousand_times_its_size() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("attacks");
    std::fs::create_dir_all(&dir).unwrap();
    for declare in [false, true] {
        let bomb = logs::zstd_rle(&[], 256 << 20, declare);
        let path = dir.join(format!("bomb-{declare}.db3.zstd"));
        std::fs::write(&path, &bomb).unwrap();
        let error = read_rosbag2(&path, &McapOptions::default()).unwrap_err();
        let message = error.to_string();
        assert_one_line(&message, &path);
        assert!(message.contains("over the limit of 67108864 bytes for this file (1000 times its"), "{message}");
        if declare {
            assert!(message.contains(&format!("it declares {} bytes decompressed", 256 << 20)), "{message}");
        }
    }
}

/// Found by the long sweep: a file-compressed database whose messages b-tree a corruption left
/// with rows out of order; SQLite's walk gave 15 of the 16 messages, without an error.
#[test]
fn item6_a_database_with_rows_out_of_order_is_an_error_not_a_loss() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("attacks");
    std::fs::create_dir_all(&dir).unwrap();
    let db = dir.join("out-of-order.db3");
    logs::sqlite_bag(&db, 16, false);
    let mut bytes = zstd::bulk::compress(&std::fs::read(&db).unwrap(), 3).unwrap();
    bytes[473..477].copy_from_slice(&0u32.to_le_bytes());
    let path = dir.join("out-of-order.db3.zstd");
    std::fs::write(&path, &bytes).unwrap();
    let message = read_rosbag2(&path, &McapOptions::default().topic(TOPIC)).unwrap_err().to_string();
    assert_one_line(&message, &path);
    assert!(message.contains("rows out of order"), "{message}");
}

// ---- item 16: lines without end -------------------------------------------------------------

#[test]
fn item16_a_line_longer_than_1_mib_is_an_error_naming_it_in_every_text_reader() {
    let mut text = b"0 1 0 0 5 0 1 0 6 0 0 1 7\n".to_vec();
    text.extend(std::iter::repeat_n(b'7', 3 << 20));
    let path = write("long-line.txt", &text);
    let times = write("long-times.txt", &text);
    type Reader<'a> = Box<dyn Fn() -> Result<usize, IoError> + 'a>;
    let readers: Vec<(&str, Reader)> = vec![
        ("tum", Box::new(|| read_tum(&path).map(|t| t.len()))),
        ("kitti", Box::new(|| read_kitti(&path, &Timing::FromFile).map(|t| t.len()))),
        ("euroc", Box::new(|| read_euroc(&path).map(|t| t.len()))),
        ("tuc", Box::new(|| read_tuc(&path).map(|t| t.len()))),
        ("g2o", Box::new(|| read_pose_graph(&path, &Timing::FromFile).map(|g| g.vertices.len()))),
        ("csv", Box::new(|| loops_io::read_csv(&path).map(|t| t.len()))),
        ("detections", Box::new(|| read_detections(&path).map(|t| t.t_s.len()))),
        ("sniffed", Box::new(|| read_trajectory(&path, None).map(|t| t.len()))),
        (
            "times",
            Box::new(|| {
                read_kitti(write("one.txt", b"1 0 0 5 0 1 0 6 0 0 1 7\n"), &Timing::TimesFile(times.clone()))
                    .map(|t| t.len())
            }),
        ),
    ];
    for (name, read) in readers {
        let (result, peak) = peak_of(read);
        let error = result.expect_err(name);
        // The KITTI line before fails some readers first; the others reach line 2.
        if error.line() == Some(2) {
            assert!(error.to_string().contains("the line is longer than 1 MiB"), "{name}: {error}");
        }
        assert!(peak < 4 << 20, "{name}: {peak} bytes for a file of {} bytes", text.len());
    }
    let error = read_kitti(&path, &Timing::FromFile).unwrap_err();
    assert_eq!(error.line(), Some(2), "{error}");
}

#[test]
fn item16_dev_zero_is_an_error_after_1_mib() {
    let zero = Path::new("/dev/zero");
    if !zero.exists() {
        eprintln!("skipping: no /dev/zero here");
        return;
    }
    let (result, peak) = peak_of(|| read_tum(zero));
    let error = result.unwrap_err();
    assert_eq!(error.line(), Some(1), "{error}");
    assert!(error.to_string().contains("the line is longer than 1 MiB"), "{error}");
    assert!(peak < 4 << 20, "{peak}");
}

// ---- item 19: one line, from any corruption -------------------------------------------------

#[test]
fn item19_a_non_utf8_topic_and_a_huge_metadata_length_are_one_line() {
    let file = raw::file(&[raw::channel(1, 0, b"/p\xffose", b"json")]);
    let error = mcap_error("non-utf8.mcap", &file);
    assert!(error.to_string().contains("its topic is not UTF-8 (invalid byte at byte 2 of it)"), "{error}");
    let mut channel = raw::channel(1, 0, TOPIC.as_bytes(), b"json");
    let metadata = channel.len() - 4;
    channel[metadata..].copy_from_slice(&u32::MAX.to_le_bytes());
    mcap_error("metadata.mcap", &raw::file(&[channel]));
}

#[test]
fn item19_every_byte_flipped_gives_a_one_line_message() {
    let mut checked = 0;
    let mut cases = 0;
    for (name, layout) in McapLayout::ALL {
        for crcs in [false, name == "zstd"] {
            let bytes = mcap(4, McapLayout { crcs, ..layout });
            let path = write(&format!("flip-{name}-{crcs}.mcap"), &bytes);
            for at in 0..bytes.len() {
                for xor in [0x01u8, 0xff] {
                    cases += 1;
                    let mut broken = bytes.clone();
                    broken[at] ^= xor;
                    std::fs::write(&path, &broken).unwrap();
                    for result in
                        [read_mcap(&path, &McapOptions::default()).map(|_| ()), list_topics(&path).map(|_| ())]
                    {
                        if let Err(error) = result {
                            assert_one_line(&error.to_string(), &path);
                            checked += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(checked > cases / 2, "{checked} messages checked in {cases} files");
}
