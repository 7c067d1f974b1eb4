//! The seeded attack sweep of the readers: every reader takes corrupted input —
//! bytes flipped and overwritten at seeded offsets, records with huge lengths and flipped
//! opcodes, bombs, malformed text — and must give, for each case, either a correct read or a
//! one-line error naming the file. Each target counts its cases and fails on any of:
//!
//! - **panic**: the reader panicked (caught per case);
//! - **abort**: the read allocated more than [`ABORT_BYTES`] at once, counted by a global
//!   allocator (`support/peak.rs`). The inputs are under 1 MB (the bombs aside, which declare
//!   up to 256 MiB): a reader that allocates 64 MiB for them is one that a declared length
//!   steers, and under an address limit (`ulimit -v`, a container) that is where the process
//!   dies with SIGABRT;
//! - **silent loss**: the read succeeded with fewer poses than the input holds. For the logs
//!   (MCAP, bags), poses are counted by the messages they came from, and "holds" is the
//!   unmutated file's count: each base file carries what lets a reader see a lost message (MCAP:
//!   a summary with statistics, chunk indexes and summary offsets, and message indexes; ROS 1:
//!   index data records; rosbag2 sqlite3: the database's own structure), so a corrupted file
//!   that reads fewer messages of the topic lost them without a word. (Inside a message, a
//!   corruption that still decodes — a protobuf field number or a JSON key changed, which both
//!   encodings skip by design, taking a pose of a `PosesInFrame` with it — is a change of
//!   content, as a changed coordinate is: no container records what a message holds.) Bases
//!   without such a structure (an MCAP file without summary or indexes) are swept for the other
//!   failures only. For text,
//!   "holds" is counted in the mutated file by the format's own rules: every data line (not
//!   blank, not a `#` comment, not the one header row the format allows) of a pose record
//!   (TUM, KITTI, EuRoC, CSV rows; `point2`/`point3` of TUC; vertex and edge tags of g2o and
//!   TORO; detection rows and `loop` lines) must give a pose, vertex, edge or detection, or the
//!   read must fail. A line the mutation turned into a comment or into another record type the
//!   format skips is not a loss: the format says it holds no pose;
//! - **bad message**: an error whose message is not one line, holds an escape sequence or
//!   library internals ("registry", "backtrace"), or does not start with the file's path.
//!
//! The kinds added by the second sweep ("readers, round two") check what the four failures above
//! cannot see by mutating bytes at random: two text records run together on one line
//! (`text_merged_lines`: the merged file must read both or fail), a message's opcode corrupted in
//! MCAP files without a summary (`mcap_message_opcodes`: every opcode, counted against the
//! unmutated file), and rosbag2 folders whose `metadata.yaml` leaves out a split, lists a missing
//! one or counts more messages than the files hold (`rosbag2_split_lists`); the `rosbag2` target
//! also fails when a decompressed copy (`loops-bag-*`) stays in the temporary folder.
//!
//! Each target runs a fixed number of cases from a fixed seed (a few minutes for all in a debug
//! build). With `LOOPS_FUZZ_SECONDS` set, each runs rounds of cases (the seed advancing each
//! round) for that long and prints its figures; run one target at a time, in release:
//! `LOOPS_FUZZ_SECONDS=1800 nice -n 19 cargo test --release -p loops-io --test attack_sweep mcap --
//! --exact --nocapture`; `LOOPS_FUZZ_FORMAT=tum` (kitti, euroc, tuc, g2o, csv, detections) limits
//! the `text` target to one reader. The figures of the long runs are in `tests/FUZZ.md`.
//!
//! The `engine_stops` target sweeps the engine itself, on a robot that parks at nearly one
//! place twice or three times: its failures are panics, aborts, wrong answers (against the
//! brute force) and hangs (distances measured per row and run beyond a bound).

// The readers' errors (`IoError`) are returned as they are, through the measuring closures.
#![allow(clippy::result_large_err)]

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use loops_io::{
    IoError, LIBRSF_TAGS, McapOptions, Timing, list_topics, read_csv, read_detections, read_euroc, read_kitti,
    read_mcap, read_pose_graph, read_ros1, read_rosbag2, read_tuc, read_tum,
};

#[path = "support/peak.rs"]
mod peak;
mod support;

use support::logs::{self, McapLayout, TOPIC};

#[global_allocator]
static ALLOCATOR: peak::Counting = peak::Counting;

/// The most one read may allocate at once before the sweep counts it as an abort: 64 MiB.
const ABORT_BYTES: usize = 64 << 20;

/// The failures shown per target when it fails.
const SHOWN_FAILURES: usize = 8;

// ---- the driver -----------------------------------------------------------------------------

/// A seeded generator (SplitMix64): the cases are the same on every machine.
struct Rng(u64);

impl Rng {
    fn new(seed: u64, round: u64) -> Self {
        Rng(seed ^ round.wrapping_mul(0x9e37_79b9_7f4a_7c15))
    }
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// A number in `0..n` (`n > 0`).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn chance(&mut self, one_in: usize) -> bool {
        self.below(one_in) == 0
    }
    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// What a read gives: the poses (or rows) read, or the error.
type Read = Box<dyn Fn(&Path) -> Result<usize, IoError>>;

/// An input to corrupt: its bytes, where a case writes them, how to read them, and the count
/// a successful read must reach (`None`: not checked).
struct Base {
    name: String,
    bytes: Vec<u8>,
    /// The file a case writes (in a scratch folder of the target).
    path: PathBuf,
    /// The paths whose errors may name the file (a rosbag2 folder's errors name its files).
    read: Read,
    /// The count of the unmutated input, for formats that can see a loss.
    expected: Option<usize>,
    /// The top-level records (offset, body offset, body length), for record attacks.
    records: Vec<(usize, usize, usize)>,
}

/// The tally of one target.
#[derive(Default)]
struct Tally {
    cases: u64,
    errors: u64,
    reads: u64,
    panics: u64,
    aborts: u64,
    losses: u64,
    bad_messages: u64,
    max_peak: usize,
    failures: Vec<String>,
}

impl Tally {
    /// A failure: shown (the first few), and its input kept beside the scratch files
    /// (`failed-N-NAME`) to replay.
    fn fail(&mut self, what: String, base: &Base, bytes: &[u8]) {
        if self.failures.len() < SHOWN_FAILURES {
            let name = base.path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            let kept = base.path.with_file_name(format!("failed-{}-{name}", self.failures.len()));
            let _ = std::fs::write(&kept, bytes);
            self.failures.push(format!("{what} (input kept as {})", kept.display()));
        }
    }

    /// One case: `bytes` written to `base.path` and read; `holds` is what the read must reach
    /// (for text, counted in the mutated bytes), `label` what the case did.
    fn case(&mut self, base: &Base, bytes: &[u8], holds: Option<usize>, label: &str) {
        std::fs::write(&base.path, bytes).expect("scratch file");
        self.cases += 1;
        self.judge(base, bytes, holds, label);
    }

    /// Reads `base.path` and counts the outcome (see [`case`](Self::case)).
    fn judge(&mut self, base: &Base, bytes: &[u8], holds: Option<usize>, label: &str) {
        let outcome = catch_unwind(AssertUnwindSafe(|| peak::peak_of(|| (base.read)(&base.path))));
        let (result, peak) = match outcome {
            Ok(read) => read,
            Err(panic) => {
                self.panics += 1;
                let message = panic
                    .downcast_ref::<String>()
                    .map(String::as_str)
                    .or_else(|| panic.downcast_ref::<&str>().copied())
                    .unwrap_or("?");
                self.fail(format!("panic: {} {label}: {message}", base.name), base, bytes);
                return;
            }
        };
        self.max_peak = self.max_peak.max(peak);
        if peak > ABORT_BYTES {
            self.aborts += 1;
            self.fail(format!("abort: {} {label}: {peak} bytes allocated", base.name), base, bytes);
        }
        match result {
            Ok(count) => {
                self.reads += 1;
                if let Some(holds) = holds
                    && count < holds
                {
                    self.losses += 1;
                    self.fail(format!("silent loss: {} {label}: {count} read of {holds}", base.name), base, bytes);
                }
            }
            Err(error) => {
                self.errors += 1;
                let message = error.to_string();
                let lower = message.to_lowercase();
                let path = error.path().display().to_string();
                let named = base.path.display().to_string();
                let parent = base.path.parent().map(|p| p.display().to_string()).unwrap_or_default();
                if message.contains(['\n', '\r', '\x1b'])
                    || lower.contains("registry")
                    || lower.contains("backtrace")
                    || !(message.starts_with(&named) || (message.starts_with(&parent) && path.starts_with(&parent)))
                {
                    self.bad_messages += 1;
                    self.fail(format!("bad message: {} {label}: {message:?}", base.name), base, bytes);
                }
            }
        }
    }

    /// One case whose input is already in place (a folder the case built): read `base.path`.
    fn case_in_place(&mut self, base: &Base, holds: Option<usize>, label: &str) {
        self.cases += 1;
        self.judge(base, &[], holds, label);
    }

    fn report_and_check(&self, target: &str, seconds: f64) {
        println!(
            "sweep {target}: {} cases in {seconds:.0} s ({:.0}/s): {} errors, {} reads; {} panics, {} aborts, {} silent \
             losses, {} bad messages; peak {:.1} MiB",
            self.cases,
            self.cases as f64 / seconds.max(1e-9),
            self.errors,
            self.reads,
            self.panics,
            self.aborts,
            self.losses,
            self.bad_messages,
            self.max_peak as f64 / f64::from(1 << 20)
        );
        assert!(
            self.panics + self.aborts + self.losses + self.bad_messages == 0,
            "sweep {target} failed:\n{}",
            self.failures.join("\n")
        );
    }
}

/// Runs `round` (cases from a seed and round number) once, or for `LOOPS_FUZZ_SECONDS`.
fn sweep(target: &str, seed: u64, mut round: impl FnMut(&mut Rng, &mut Tally)) {
    let budget = std::env::var("LOOPS_FUZZ_SECONDS").ok().and_then(|s| s.parse::<f64>().ok());
    let start = Instant::now();
    let mut tally = Tally::default();
    let mut number = 0u64;
    loop {
        let mut rng = Rng::new(seed, number);
        round(&mut rng, &mut tally);
        number += 1;
        match budget {
            Some(seconds) if start.elapsed() < Duration::from_secs_f64(seconds) => {}
            _ => break,
        }
    }
    tally.report_and_check(target, start.elapsed().as_secs_f64());
}

/// A scratch folder of the target.
fn scratch(target: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("attack-sweep").join(target);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

// ---- mutations ------------------------------------------------------------------------------

/// Values that make lengths and counts wrong in interesting ways.
const INTERESTING_U32: [u32; 8] = [0, 1, 0x7f, 0xff, 0x7fff_ffff, 0x8000_0000, 0xffff_fffe, 0xffff_ffff];
const INTERESTING_U64: [u64; 6] = [0, 1, 1 << 32, 1 << 40, i64::MAX as u64, u64::MAX];

/// One byte-level mutation of `data`: flip, set, overwrite with an interesting value, insert,
/// remove, duplicate a range, truncate.
fn mutate_bytes(rng: &mut Rng, data: &mut Vec<u8>) -> String {
    if data.is_empty() {
        data.push(rng.next() as u8);
        return "grown".into();
    }
    let at = rng.below(data.len());
    match rng.below(9) {
        0 | 1 => {
            let xor = (rng.below(255) + 1) as u8;
            data[at] ^= xor;
            format!("flip {at}^{xor:#04x}")
        }
        2 => {
            data[at] = rng.next() as u8;
            format!("set {at}")
        }
        3 => {
            let value = *rng.pick(&INTERESTING_U32);
            overwrite(data, at, &value.to_le_bytes());
            format!("u32 {at}={value:#x}")
        }
        4 => {
            let value = *rng.pick(&INTERESTING_U64);
            overwrite(data, at, &value.to_le_bytes());
            format!("u64 {at}={value:#x}")
        }
        5 => {
            let n = rng.below(16) + 1;
            let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
            data.splice(at..at, bytes);
            format!("insert {n} at {at}")
        }
        6 => {
            let end = (at + rng.below(64) + 1).min(data.len());
            data.drain(at..end);
            format!("remove {at}..{end}")
        }
        7 => {
            let end = (at + rng.below(256) + 1).min(data.len());
            let copy = data[at..end].to_vec();
            let to = rng.below(data.len());
            data.splice(to..to, copy);
            format!("duplicate {at}..{end} to {to}")
        }
        _ => {
            data.truncate(at);
            format!("truncate {at}")
        }
    }
}

fn overwrite(data: &mut [u8], at: usize, bytes: &[u8]) {
    for (k, byte) in bytes.iter().enumerate() {
        if let Some(slot) = data.get_mut(at + k) {
            *slot = *byte;
        }
    }
}

/// One attack on a record of `records` (offset, body offset, body length): its opcode set, its
/// length (u64 at offset+1) made interesting, or a u32 in the first 64 bytes of its body (where
/// the lengths of strings and maps lie) made interesting.
fn mutate_record(rng: &mut Rng, data: &mut [u8], records: &[(usize, usize, usize)]) -> String {
    let &(offset, body, len) = rng.pick(records);
    match rng.below(3) {
        0 => {
            let opcode = if rng.chance(2) { rng.below(0x10) as u8 } else { rng.next() as u8 };
            overwrite(data, offset, &[opcode]);
            format!("opcode of {offset} = {opcode:#04x}")
        }
        1 => {
            let value = *rng.pick(&INTERESTING_U64);
            overwrite(data, offset + 1, &value.to_le_bytes());
            format!("length of {offset} = {value:#x}")
        }
        _ => {
            let at = body + rng.below(len.clamp(1, 64));
            let value = *rng.pick(&INTERESTING_U32);
            overwrite(data, at, &value.to_le_bytes());
            format!("u32 in record {offset} at {at} = {value:#x}")
        }
    }
}

/// One to three mutations of a binary base.
fn mutate_binary(rng: &mut Rng, base: &Base) -> (Vec<u8>, String) {
    let mut data = base.bytes.clone();
    let mut label = Vec::new();
    for _ in 0..rng.below(3) + 1 {
        if !base.records.is_empty() && rng.chance(3) {
            label.push(mutate_record(rng, &mut data, &base.records));
        } else {
            label.push(mutate_bytes(rng, &mut data));
        }
    }
    (data, label.join(", "))
}

// ---- MCAP -----------------------------------------------------------------------------------

/// The messages a table of poses came from (a `PosesInFrame` or a TF message holds several).
fn messages(table: &loops_io::PoseTable) -> usize {
    let mut sources: Vec<_> = table.messages.as_ref().map(|m| m.messages.clone()).unwrap_or_default();
    sources.sort_by_key(|m| (m.file, m.offset, m.offset_in_chunk));
    sources.dedup();
    sources.len()
}

/// MCAP top-level records as (offset, body offset, body length).
fn mcap_records(bytes: &[u8]) -> Vec<(usize, usize, usize)> {
    logs::mcap_records(bytes).into_iter().map(|(offset, _, len)| (offset, offset + 9, len)).collect()
}

fn read_mcap_topic(topic: String) -> Read {
    Box::new(move |path| {
        let count = messages(&read_mcap(path, &McapOptions::default().topic(topic.clone()))?);
        // The topic list walks the whole file too; its errors must be as good.
        list_topics(path)?;
        Ok(count)
    })
}

/// The MCAP bases: the `mcap` crate's writer in every layout (with and without CRCs), two
/// without summary (not checked for losses), and the Python writers' fixtures when Python is
/// here (every pose type, chunked or not, zstd, lz4).
fn mcap_bases(dir: &Path) -> Vec<Base> {
    let mut bases = Vec::new();
    for (name, layout) in McapLayout::ALL {
        for crcs in [true, false] {
            for summary in [true, false] {
                if !summary && !crcs {
                    continue;
                }
                let bytes = logs::mcap(16, McapLayout { crcs, summary, ..layout });
                bases.push(Base {
                    name: format!(
                        "rust-{name}{}{}",
                        if crcs { "" } else { "-nocrc" },
                        if summary { "" } else { "-nosummary" }
                    ),
                    records: mcap_records(&bytes),
                    bytes,
                    path: dir.join(format!("rust-{name}-{crcs}-{summary}.mcap")),
                    read: read_mcap_topic(TOPIC.to_owned()),
                    expected: summary.then_some(16),
                });
            }
        }
    }
    if let Some((fixtures, manifest)) = support::mcap_fixtures() {
        for file in manifest["files"].as_array().expect("files") {
            let name = file["name"].as_str().expect("name");
            let source = fixtures.join(name);
            let topics = file["topics"].as_object().expect("topics");
            for topic in topics.keys() {
                let options = McapOptions::default().topic(topic.clone());
                let Ok(table) = read_mcap(&source, &options) else { continue };
                let bytes = std::fs::read(&source).expect("fixture");
                bases.push(Base {
                    name: format!("python-{name}{topic}"),
                    records: mcap_records(&bytes),
                    bytes,
                    path: dir.join(format!("python-{}", name)),
                    read: read_mcap_topic(topic.clone()),
                    expected: Some(messages(&table)),
                });
            }
        }
    } else {
        println!("sweep mcap: no Python fixtures here; the mcap crate's files only");
    }
    bases
}

/// A small MCAP file whose chunk holds a message of `size` zero bytes, as a zstd bomb.
fn mcap_bomb(size: u64, channel: u16) -> Vec<u8> {
    use logs::raw;
    let head = raw::message_head(channel, 1, 7);
    let record_len = head.len() as u64 + size;
    let prefix = [vec![0x05], record_len.to_le_bytes().to_vec(), head].concat();
    raw::file(&[
        raw::schema(1, b"geometry_msgs/msg/PoseStamped"),
        raw::channel(1, 1, TOPIC.as_bytes(), b"cdr"),
        raw::channel(2, 0, b"/other", b"json"),
        raw::message(1, 0, 5, &logs::cdr_pose_stamped(0)),
        raw::chunk(b"zstd", &logs::zstd_rle(&prefix, size, false), 9 + record_len),
    ])
}

#[test]
fn mcap() {
    let dir = scratch("mcap");
    let bases = mcap_bases(&dir);
    let bomb = Base {
        name: "bomb".into(),
        bytes: Vec::new(),
        path: dir.join("bomb.mcap"),
        read: read_mcap_topic(TOPIC.to_owned()),
        expected: Some(1),
        records: Vec::new(),
    };
    let mut first = true;
    sweep("mcap", 0x003C_A915, |rng, tally| {
        if std::mem::take(&mut first) {
            // Crafted, once: bombs on the topic not read (read in bounded memory) and on the one
            // read (refused by the message's length); every opcode at every record of a base.
            tally.case(&bomb, &mcap_bomb(256 << 20, 2), Some(1), "zstd bomb of 256 MiB on /other");
            let pose_bomb = Base { expected: None, ..bomb_like(&bomb) };
            tally.case(&pose_bomb, &mcap_bomb(100 << 20, 1), None, "zstd bomb of 100 MiB on /pose");
            let base = &bases[4];
            for &(offset, _, _) in &base.records {
                for opcode in (0u8..=0x10).chain([0x80, 0x8c, 0xff]) {
                    let mut bytes = base.bytes.clone();
                    bytes[offset] = opcode;
                    tally.case(base, &bytes, base.expected, &format!("opcode of {offset} = {opcode:#04x}"));
                }
                for value in INTERESTING_U64 {
                    let mut bytes = base.bytes.clone();
                    overwrite(&mut bytes, offset + 1, &value.to_le_bytes());
                    tally.case(base, &bytes, base.expected, &format!("length of {offset} = {value:#x}"));
                }
            }
        }
        for _ in 0..1500 {
            let base = rng.pick(&bases);
            let (bytes, label) = mutate_binary(rng, base);
            tally.case(base, &bytes, base.expected, &label);
        }
    });
}

/// A base reading as `base` does, for crafted inputs.
fn bomb_like(base: &Base) -> Base {
    Base {
        name: base.name.clone(),
        bytes: Vec::new(),
        path: base.path.clone(),
        read: read_mcap_topic(TOPIC.to_owned()),
        expected: base.expected,
        records: Vec::new(),
    }
}

/// Every opcode at the message records of MCAP files without a summary, where no count would see
/// a lost message: each case must read every pose of the unmutated file or fail.
#[test]
fn mcap_message_opcodes() {
    let dir = scratch("mcap-opcodes");
    let mut bases = Vec::new();
    for (name, layout) in McapLayout::ALL {
        for crcs in [true, false] {
            let bytes = logs::mcap(16, McapLayout { crcs, summary: false, ..layout });
            let path = dir.join(format!("{name}-{crcs}.mcap"));
            std::fs::write(&path, &bytes).expect("scratch file");
            let count = messages(&read_mcap(&path, &McapOptions::default().topic(TOPIC)).expect("the base reads"));
            bases.push(Base {
                name: format!("rust-{name}{}-nosummary", if crcs { "" } else { "-nocrc" }),
                records: mcap_records(&bytes),
                bytes,
                path,
                read: read_mcap_topic(TOPIC.to_owned()),
                expected: Some(count),
            });
        }
    }
    // The top-level message records of an unchunked base (offset, body offset, body length).
    let is_message = |base: &Base, record: &(usize, usize, usize)| base.bytes[record.0] == 0x05;
    let mut first = true;
    sweep("mcap_message_opcodes", 0x000C_0DE5, |rng, tally| {
        if std::mem::take(&mut first) {
            // Crafted, once: every opcode at the first, a middle and the last message of each
            // unchunked base.
            for base in bases.iter().filter(|base| base.name.contains("unchunked")) {
                let records: Vec<_> = base.records.iter().filter(|record| is_message(base, record)).collect();
                for record in [records[0], records[records.len() / 2], records[records.len() - 1]] {
                    for opcode in (0..=u8::MAX).filter(|&opcode| opcode != 0x05) {
                        let mut bytes = base.bytes.clone();
                        bytes[record.0] = opcode;
                        tally.case(base, &bytes, base.expected, &format!("opcode of {} = {opcode:#04x}", record.0));
                    }
                }
            }
        }
        for _ in 0..400 {
            let base = rng.pick(&bases);
            let messages: Vec<_> = base.records.iter().filter(|record| is_message(base, record)).collect();
            let &(offset, _, _) =
                if messages.is_empty() || rng.chance(4) { rng.pick(&base.records) } else { *rng.pick(&messages) };
            let opcode = rng.next() as u8;
            let mut bytes = base.bytes.clone();
            bytes[offset] = opcode;
            // A record whose opcode became a message's: its bytes are read as one, not lost.
            tally.case(base, &bytes, base.expected, &format!("opcode of {offset} = {opcode:#04x}"));
        }
    });
}

// ---- ROS 1 bags -----------------------------------------------------------------------------

/// ROS 1 top-level records as (offset, body offset, body length): the header length's offset,
/// the header's.
fn ros1_records(bytes: &[u8]) -> Vec<(usize, usize, usize)> {
    let mut out = Vec::new();
    let mut pos = 13;
    let u32_at = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes(b.try_into().unwrap()) as usize);
    while let Some(header_len) = u32_at(pos) {
        out.push((pos, pos + 4, header_len));
        let Some(data_len) = u32_at(pos + 4 + header_len) else { break };
        pos += 8 + header_len + data_len;
    }
    out
}

fn read_ros1_poses() -> Read {
    Box::new(|path| {
        let count = messages(&read_ros1(path, &McapOptions::default().topic(TOPIC))?);
        list_topics(path)?;
        Ok(count)
    })
}

#[test]
fn ros1() {
    let dir = scratch("ros1");
    let mut bases = Vec::new();
    for compression in ["none", "bz2", "lz4"] {
        let bytes = logs::ros1_bag(16, compression, 5);
        bases.push(Base {
            name: format!("rust-{compression}"),
            records: ros1_records(&bytes),
            bytes,
            path: dir.join(format!("rust-{compression}.bag")),
            read: read_ros1_poses(),
            expected: Some(16),
        });
    }
    if let Some((fixtures, manifest)) = support::bag_fixtures("small", &support::small_bag_poses()) {
        for fixture in manifest["fixtures"].as_array().expect("fixtures") {
            if fixture["kind"] != "ros1" {
                continue;
            }
            let file = fixtures.join(fixture["files"][0].as_str().expect("file"));
            let topic = fixture["topic"].as_str().expect("topic").to_owned();
            let Ok(table) = read_ros1(&file, &McapOptions::default().topic(topic.clone())) else { continue };
            let bytes = std::fs::read(&file).expect("fixture");
            let name = fixture["name"].as_str().expect("name");
            bases.push(Base {
                name: format!("python-{name}"),
                records: ros1_records(&bytes),
                bytes,
                path: dir.join(format!("python-{name}.bag")),
                read: Box::new(move |path| {
                    let count = messages(&read_ros1(path, &McapOptions::default().topic(topic.clone()))?);
                    list_topics(path)?;
                    Ok(count)
                }),
                expected: Some(messages(&table)),
            });
        }
    } else {
        println!("sweep ros1: no Python fixtures here; the in-test bags only");
    }
    let mut first = true;
    sweep("ros1", 0xB115, |rng, tally| {
        if std::mem::take(&mut first) {
            // A chunk of 64 MiB in 260 kB of lz4, on the topic not read: bounded memory.
            let mut extra = Vec::new();
            logs::ros1_message_record(&mut extra, 1, (0, 0), &vec![0u8; 64 << 20]);
            let bomb = logs::ros1_bag_with(3, "lz4", 3, &extra);
            drop(extra);
            tally.case(&bases[0], &bomb, Some(3), "lz4 chunk of 64 MiB");
        }
        for _ in 0..1000 {
            let base = rng.pick(&bases);
            let (bytes, label) = mutate_binary(rng, base);
            tally.case(base, &bytes, base.expected, &label);
        }
    });
}

// ---- rosbag2 --------------------------------------------------------------------------------

#[test]
fn rosbag2() {
    let dir = scratch("rosbag2");
    let read_rosbag2_poses = || -> Read {
        Box::new(|path| {
            let count = messages(&read_rosbag2(path, &McapOptions::default().topic(TOPIC))?);
            list_topics(path)?;
            Ok(count)
        })
    };
    let mut bases = Vec::new();
    for compress in [false, true] {
        let path = dir.join(format!("base-{compress}.db3"));
        logs::sqlite_bag(&path, 16, compress);
        let bytes = std::fs::read(&path).expect("db3");
        let _ = std::fs::remove_file(&path);
        bases.push(Base {
            name: format!("sqlite3{}", if compress { "-message-zstd" } else { "" }),
            records: Vec::new(),
            path: dir.join(format!("sqlite3-{compress}.db3")),
            read: read_rosbag2_poses(),
            expected: Some(16),
            bytes: bytes.clone(),
        });
        if !compress {
            bases.push(Base {
                name: "sqlite3-file-zstd".into(),
                records: Vec::new(),
                bytes: zstd::bulk::compress(&bytes, 3).expect("zstd"),
                path: dir.join("file.db3.zstd"),
                read: read_rosbag2_poses(),
                expected: Some(16),
            });
        }
    }
    let mcap = logs::mcap(16, McapLayout::ZSTD);
    bases.push(Base {
        name: "mcap-storage".into(),
        records: mcap_records(&mcap),
        bytes: mcap.clone(),
        path: dir.join("bag_0.mcap"),
        read: read_rosbag2_poses(),
        expected: Some(16),
    });
    bases.push(Base {
        name: "mcap-file-zstd".into(),
        records: Vec::new(),
        bytes: zstd::bulk::compress(&mcap, 3).expect("zstd"),
        path: dir.join("bag_0.mcap.zstd"),
        read: read_rosbag2_poses(),
        expected: Some(16),
    });
    if let Some((fixtures, manifest)) = support::bag_fixtures("small", &support::small_bag_poses()) {
        for fixture in manifest["fixtures"].as_array().expect("fixtures") {
            if fixture["kind"] != "rosbag2" {
                continue;
            }
            let name = fixture["name"].as_str().expect("name");
            let topic = fixture["topic"].as_str().expect("topic").to_owned();
            for file in fixture["files"].as_array().expect("files") {
                let file = fixtures.join(file.as_str().expect("file"));
                let Ok(table) = read_rosbag2(&file, &McapOptions::default().topic(topic.clone())) else { continue };
                let file_name = file.file_name().expect("name").to_string_lossy().into_owned();
                let topic = topic.clone();
                bases.push(Base {
                    name: format!("python-{file_name}"),
                    records: if file_name.ends_with(".mcap") {
                        mcap_records(&std::fs::read(&file).expect("mcap"))
                    } else {
                        Vec::new()
                    },
                    bytes: std::fs::read(&file).expect("fixture"),
                    path: dir.join(format!("python-{name}-{file_name}")),
                    read: Box::new(move |path| {
                        let count = messages(&read_rosbag2(path, &McapOptions::default().topic(topic.clone()))?);
                        list_topics(path)?;
                        Ok(count)
                    }),
                    expected: Some(messages(&table)),
                });
            }
        }
    } else {
        println!("sweep rosbag2: no Python fixtures here; the in-test bags only");
    }
    let temporary = || -> Vec<PathBuf> {
        let mut names: Vec<PathBuf> = std::fs::read_dir(std::env::temp_dir())
            .map(|entries| entries.filter_map(|entry| Some(entry.ok()?.path())).collect())
            .unwrap_or_default();
        names.retain(|path| path.file_name().is_some_and(|name| name.to_string_lossy().starts_with("loops-bag-")));
        names.sort();
        names
    };
    let temporary_before = temporary();
    let mut first = true;
    sweep("rosbag2", 0x0050_1315, |rng, tally| {
        if std::mem::take(&mut first) {
            // A file-compressed storage file that is a zstd bomb: refused at 1000 times its size.
            let file = bases.iter().find(|base| base.name == "sqlite3-file-zstd").expect("the file-compressed base");
            let bomb = Base { expected: None, ..bomb_from(file) };
            tally.case(&bomb, &logs::zstd_rle(&[], 256 << 20, false), None, "file zstd bomb of 256 MiB");
        }
        for _ in 0..800 {
            let base = rng.pick(&bases);
            let (mut bytes, mut label) = mutate_binary(rng, base);
            // The header page of a database reaches more of SQLite's checks.
            if base.path.extension().is_some_and(|e| e == "db3") && rng.chance(3) {
                bytes = base.bytes.clone();
                let mut head = bytes[..4096.min(bytes.len())].to_vec();
                label = format!("first page: {}", mutate_bytes(rng, &mut head));
                let end = 4096.min(bytes.len());
                bytes.splice(..end, head);
            }
            tally.case(base, &bytes, base.expected, &label);
        }
    });
    // Decompressed copies have no name (but for the moment SQLite opens one): none stays.
    let left: Vec<PathBuf> = temporary().into_iter().filter(|path| !temporary_before.contains(path)).collect();
    assert!(left.is_empty(), "sweep rosbag2 left decompressed copies in the temporary folder: {left:?}");
}

/// A base reading its path as `base` does, for crafted inputs.
fn bomb_from(base: &Base) -> Base {
    Base {
        name: format!("{}-crafted", base.name),
        bytes: Vec::new(),
        path: base.path.clone(),
        read: Box::new(|path| Ok(messages(&read_rosbag2(path, &McapOptions::default().topic(TOPIC))?))),
        expected: base.expected,
        records: Vec::new(),
    }
}

// ---- text -----------------------------------------------------------------------------------

/// The poses a text file holds by its format's rules (see the module's "silent loss").
fn text_holds(format: &str, text: &str) -> usize {
    // A byte-order mark that starts the file is not text (the readers drop it).
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines: Vec<&str> =
        text.split('\n').map(|line| line.trim()).filter(|line| !line.is_empty() && !line.starts_with('#')).collect();
    let is_number = |field: &str| field.parse::<f64>().is_ok();
    // The fields as the readers split them: a delimited field trimmed and unquoted (one pair of
    // quotes), a white-space separated one as it is.
    let unquote = |field: &str| -> String {
        let field = field.trim();
        field.strip_prefix('"').and_then(|inner| inner.strip_suffix('"')).unwrap_or(field).to_owned()
    };
    let fields = |line: &str| -> Vec<String> {
        let delimiter = [',', ';', '\t'].into_iter().find(|c| line.contains(*c));
        match (format, delimiter) {
            ("tum", _) if line.contains(',') => line.split(',').map(unquote).collect(),
            ("tum" | "kitti" | "tuc" | "g2o", _) => line.split_ascii_whitespace().map(str::to_owned).collect(),
            ("euroc", _) => line.split(',').map(unquote).collect(),
            (_, Some(c)) => line.split(c).map(unquote).collect(),
            (_, None) => line.split_ascii_whitespace().map(str::to_owned).collect(),
        }
    };
    // A header holds no number, not even among the words of a field (as the readers rule).
    let header = |line: &str| !fields(line).iter().any(|f| f.split_ascii_whitespace().any(is_number));
    let first_word = |line: &str| line.split_ascii_whitespace().next().unwrap_or("").to_owned();
    match format {
        "kitti" => lines.len(),
        "tum" | "euroc" | "csv" => lines.len() - usize::from(lines.first().is_some_and(|line| header(line))),
        "tuc" => lines.iter().filter(|line| matches!(first_word(line).as_str(), "point2" | "point3")).count(),
        "g2o" => lines
            .iter()
            .filter(|line| {
                matches!(
                    first_word(line).as_str(),
                    "VERTEX_SE2"
                        | "VERTEX2"
                        | "VERTEX_SE3:QUAT"
                        | "VERTEX3"
                        | "EDGE_SE2"
                        | "EDGE2"
                        | "EDGE_SE3:QUAT"
                        | "EDGE3"
                )
            })
            .count(),
        "detections" => {
            let mut holds = 0;
            // A row is a detection, but a header row before the first detection, or another
            // libRSF record type (`odom2 ...`).
            for line in &lines {
                let fields = fields(line);
                let word = fields.first().cloned().unwrap_or_default();
                let all_words = !fields.iter().any(|f| f.split_ascii_whitespace().any(is_number));
                if word == "loop" {
                    holds += 1;
                    continue;
                } else if word.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
                    && fields.len() > 1
                    && !all_words
                    && LIBRSF_TAGS.contains(&word.as_str())
                {
                    continue;
                }
                if holds == 0 && all_words {
                    continue;
                }
                holds += 1;
            }
            holds
        }
        other => unreachable!("{other}"),
    }
}

/// One line-level mutation of `text`: a line deleted, duplicated, swapped, cut, joined to the
/// next, its first word misspelled, a NUL, a CR, a BOM or a non-UTF-8 byte put in it, or (rarely)
/// a line of 1.5 MiB.
fn mutate_lines(rng: &mut Rng, text: &mut Vec<u8>) -> String {
    let mut lines: Vec<Vec<u8>> = text.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
    let at = rng.below(lines.len());
    let label = match rng.below(11) {
        0 => {
            lines.remove(at);
            format!("delete line {}", at + 1)
        }
        1 => {
            let copy = lines[at].clone();
            lines.insert(at, copy);
            format!("duplicate line {}", at + 1)
        }
        2 => {
            let other = rng.below(lines.len());
            lines.swap(at, other);
            format!("swap lines {} and {}", at + 1, other + 1)
        }
        3 => {
            let cut = rng.below(lines[at].len() + 1);
            lines[at].truncate(cut);
            format!("cut line {} at {cut}", at + 1)
        }
        4 if at + 1 < lines.len() => {
            let next = lines.remove(at + 1);
            lines[at].push(b' ');
            lines[at].extend(next);
            format!("join line {} to the next", at + 1)
        }
        5 => {
            let end = lines[at].iter().position(|&b| b == b' ' || b == b',').unwrap_or(lines[at].len());
            if end > 0 {
                let i = rng.below(end);
                lines[at][i] = b"AEIOUXaeioux_0"[rng.below(14)];
            }
            format!("misspell line {}", at + 1)
        }
        6 => {
            let i = rng.below(lines[at].len() + 1);
            lines[at].insert(i, 0);
            format!("NUL in line {}", at + 1)
        }
        7 => {
            let i = rng.below(lines[at].len() + 1);
            lines[at].insert(i, b'\r');
            format!("CR in line {}", at + 1)
        }
        8 => {
            let i = rng.below(lines[at].len() + 1);
            let bytes: &[u8] = if rng.chance(2) { b"\xef\xbb\xbf" } else { b"\xff" };
            lines[at].splice(i..i, bytes.iter().copied());
            format!("BOM or 0xff in line {}", at + 1)
        }
        9 if rng.chance(50) => {
            lines.insert(at, vec![b'1'; 3 << 19]);
            format!("line of 1.5 MiB at {}", at + 1)
        }
        _ => {
            let i = rng.below(lines[at].len() + 1);
            lines[at].insert(i, if rng.chance(2) { b'#' } else { b' ' });
            format!("# or space in line {}", at + 1)
        }
    };
    *text = lines.join(&b'\n');
    label
}

/// The text bases: each format's file of `logs::text_files`, with its format (for
/// [`text_holds`]) and reader.
fn text_bases(dir: &Path) -> Vec<(&'static str, Base)> {
    let mut bases = Vec::new();
    for (name, extension, contents) in logs::text_files(10) {
        let path = dir.join(format!("{name}.{extension}"));
        let (format, read): (&str, Read) = match name {
            "tum" => ("tum", Box::new(|p| Ok(read_tum(p)?.len()))),
            "kitti" => ("kitti", Box::new(|p| Ok(read_kitti(p, &Timing::FromFile)?.len()))),
            "euroc" => ("euroc", Box::new(|p| Ok(read_euroc(p)?.len()))),
            "tuc" => ("tuc", Box::new(|p| Ok(read_tuc(p)?.len()))),
            "g2o" | "g2o-3d" | "toro" => (
                "g2o",
                Box::new(|p| {
                    let graph = read_pose_graph(p, &Timing::FromFile)?;
                    Ok(graph.vertices.len() + graph.edges.len())
                }),
            ),
            "csv" => ("csv", Box::new(|p| Ok(read_csv(p)?.len()))),
            "detections" => ("detections", Box::new(|p| Ok(read_detections(p)?.t_s.len()))),
            other => unreachable!("{other}"),
        };
        let expected = text_holds(format, &contents);
        bases.push((
            format,
            Base {
                name: name.to_owned(),
                bytes: contents.into_bytes(),
                path,
                read,
                expected: Some(expected),
                records: Vec::new(),
            },
        ));
    }
    bases
}

#[test]
fn text() {
    let dir = scratch("text");
    let times_path = dir.join("times.txt");
    let mut bases = text_bases(&dir);
    // A times file (one time a line) for KITTI poses without times.
    let kitti_12 = dir.join("kitti12.txt");
    std::fs::write(&kitti_12, "1 0 0 5 0 1 0 6 0 0 1 7\n1 0 0 6 0 1 0 6 0 0 1 7\n1 0 0 7 0 1 0 6 0 0 1 7\n").unwrap();
    let times = times_path.clone();
    bases.push((
        "kitti",
        Base {
            name: "times".into(),
            bytes: b"0.5\n1.0\n1.5\n".to_vec(),
            path: times_path,
            read: Box::new(move |_| Ok(read_kitti(&kitti_12, &Timing::TimesFile(times.clone()))?.len())),
            expected: None,
            records: Vec::new(),
        },
    ));
    // `LOOPS_FUZZ_FORMAT=tum` (or kitti, euroc, tuc, g2o, csv, detections) sweeps one reader.
    if let Ok(only) = std::env::var("LOOPS_FUZZ_FORMAT") {
        bases.retain(|(format, _)| *format == only);
        assert!(!bases.is_empty(), "LOOPS_FUZZ_FORMAT={only}: no such text format");
    }
    sweep("text", 0x007E_4715, |rng, tally| {
        for _ in 0..3000 {
            let (format, base) = rng.pick(&bases);
            let mut bytes = base.bytes.clone();
            let mut label = Vec::new();
            for _ in 0..rng.below(3) + 1 {
                label.push(if rng.chance(2) { mutate_lines(rng, &mut bytes) } else { mutate_bytes(rng, &mut bytes) });
            }
            let holds = base.expected.map(|_| text_holds(format, &String::from_utf8_lossy(&bytes)));
            tally.case(base, &bytes, holds, &label.join(", "));
        }
    });
}

/// Two records run together on one line: a data line joined to the next by a space, a tab, a
/// comma or a semicolon (or nothing, after a line of one field). The file holds what it held
/// before the join, by the format's rules: the read must give all of it, or fail naming the line.
#[test]
fn text_merged_lines() {
    let dir = scratch("text-merged");
    let bases = text_bases(&dir);
    let is_data = |line: &[u8]| {
        let line = String::from_utf8_lossy(line);
        let line = line.trim();
        !line.is_empty() && !line.starts_with('#')
    };
    sweep("text_merged_lines", 0x003E_A6ED, |rng, tally| {
        for _ in 0..1500 {
            let (format, base) = rng.pick(&bases);
            let mut bytes = base.bytes.clone();
            let mut label = Vec::new();
            // Sometimes another line-level mutation first: the join then meets its result.
            if rng.chance(4) {
                label.push(mutate_lines(rng, &mut bytes));
            }
            let holds = text_holds(format, &String::from_utf8_lossy(&bytes));
            let mut lines: Vec<Vec<u8>> = bytes.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
            let joinable: Vec<usize> =
                (0..lines.len().saturating_sub(1)).filter(|&i| is_data(&lines[i]) && is_data(&lines[i + 1])).collect();
            if joinable.is_empty() {
                continue;
            }
            let at = *rng.pick(&joinable);
            let joiner: &[u8] = rng.pick(&["\u{20}", "\t", ",", ";", "  "]).as_bytes();
            let next = lines.remove(at + 1);
            lines[at].extend_from_slice(joiner);
            lines[at].extend(next);
            label.push(format!("join line {} to the next with {:?}", at + 1, String::from_utf8_lossy(joiner)));
            tally.case(base, &lines.join(&b'\n'), Some(holds), &label.join(", "));
        }
    });
}

// ---- rosbag2 split lists --------------------------------------------------------------------

/// A rosbag2 folder of three sqlite3 splits (`n` poses each, on /pose, and as many /chatter
/// messages) and its `metadata.yaml` with every count, as rosbag2 writes it.
fn split_folder(dir: &Path, n: usize) -> (Vec<(String, Vec<u8>)>, serde_yaml_ng::Value) {
    let mut files = Vec::new();
    for split in 0..3 {
        let path = dir.join(format!("split_{split}.db3"));
        let poses: Vec<(i64, Vec<u8>)> = (split * n..(split + 1) * n)
            .map(|i| (i64::from(logs::stamp(i).0) * 1_000_000_000, logs::cdr_pose_stamped(i)))
            .collect();
        logs::sqlite_bag_of(&path, &poses, false);
        files.push((format!("split_{split}.db3"), std::fs::read(&path).expect("db3")));
        let _ = std::fs::remove_file(&path);
    }
    let yaml = format!(
        "rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  relative_file_paths: [split_0.db3, split_1.db3, split_2.db3]
  message_count: {total}
  topics_with_message_count:
  - topic_metadata: {{name: /pose, type: geometry_msgs/msg/PoseStamped, serialization_format: cdr}}
    message_count: {poses}
  - topic_metadata: {{name: /chatter, type: std_msgs/msg/String, serialization_format: cdr}}
    message_count: {poses}
  files:
  - {{path: split_0.db3, message_count: {per_file}}}
  - {{path: split_1.db3, message_count: {per_file}}}
  - {{path: split_2.db3, message_count: {per_file}}}
",
        total = 6 * n,
        poses = 3 * n,
        per_file = 2 * n,
    );
    (files, serde_yaml_ng::from_str(&yaml).expect("metadata"))
}

/// The `rosbag2_bagfile_information` map of a `metadata.yaml`.
fn info(metadata: &mut serde_yaml_ng::Value) -> &mut serde_yaml_ng::Mapping {
    metadata["rosbag2_bagfile_information"].as_mapping_mut().expect("a map")
}

/// rosbag2 folders of three splits whose `metadata.yaml` and files disagree: a split left out of
/// the list (there or moved away), a listed one missing, a count raised (a file's, a topic's,
/// the bag's) or lowered, a storage file the list does not name. Each read must give every pose
/// the folder's metadata promises, or fail naming the metadata file or a storage file.
#[test]
fn rosbag2_split_lists() {
    const POSES_PER_SPLIT: usize = 5;
    let dir = scratch("rosbag2-splits");
    let (files, metadata) = split_folder(&dir, POSES_PER_SPLIT);
    let folder = dir.join("bag");
    let base = Base {
        name: "sqlite3-split3".into(),
        bytes: Vec::new(),
        path: folder.join("metadata.yaml"),
        read: Box::new(|path| {
            let count = messages(&read_rosbag2(path, &McapOptions::default().topic(TOPIC))?);
            list_topics(path)?;
            Ok(count)
        }),
        expected: Some(3 * POSES_PER_SPLIT),
        records: Vec::new(),
    };
    sweep("rosbag2_split_lists", 0x0005_B117, |rng, tally| {
        for _ in 0..60 {
            let _ = std::fs::remove_dir_all(&folder);
            std::fs::create_dir_all(&folder).expect("scratch folder");
            for (name, bytes) in &files {
                std::fs::write(folder.join(name), bytes).expect("split");
            }
            let mut metadata = metadata.clone();
            let split = rng.below(3);
            let name = files[split].0.clone();
            let mut holds = 3 * POSES_PER_SPLIT;
            let label = match rng.below(6) {
                0 => {
                    let list = info(&mut metadata)["relative_file_paths"].as_sequence_mut().expect("a list");
                    list.retain(|listed| listed.as_str() != Some(&name));
                    if rng.chance(2) {
                        info(&mut metadata)["files"].as_sequence_mut().expect("files").remove(split);
                    }
                    format!("{name} left out of the list")
                }
                1 => {
                    info(&mut metadata)["relative_file_paths"]
                        .as_sequence_mut()
                        .expect("a list")
                        .retain(|listed| listed.as_str() != Some(&name));
                    std::fs::remove_file(folder.join(&name)).expect("remove");
                    format!("{name} left out of the list and moved away, the counts kept")
                }
                2 => {
                    std::fs::remove_file(folder.join(&name)).expect("remove");
                    format!("{name} listed and missing")
                }
                3 => {
                    let raise = (rng.below(7) + 1) as u64;
                    let (what, count) = match rng.below(3) {
                        0 => ("message_count", &mut info(&mut metadata)["message_count"]),
                        1 => {
                            ("/pose's count", &mut info(&mut metadata)["topics_with_message_count"][0]["message_count"])
                        }
                        _ => ("a file's count", &mut info(&mut metadata)["files"][split]["message_count"]),
                    };
                    *count = (count.as_u64().expect("a count") + raise).into();
                    // A message promised that no file holds: the read must fail.
                    holds += 1;
                    format!("{what} raised by {raise}")
                }
                4 => {
                    let count = &mut info(&mut metadata)["topics_with_message_count"][0]["message_count"];
                    *count = (count.as_u64().expect("a count") - 1).into();
                    "/pose's count lowered by 1 (a stale metadata: reads whole)".to_owned()
                }
                _ => {
                    // A storage file in the folder that no list names: its poses are the bag's.
                    std::fs::write(folder.join("split_3.db3"), &files[split].1).expect("extra");
                    holds += POSES_PER_SPLIT;
                    "an unlisted storage file in the folder".to_owned()
                }
            };
            std::fs::write(&base.path, serde_yaml_ng::to_string(&metadata).expect("yaml")).expect("metadata");
            tally.case_in_place(&base, Some(holds), &label);
        }
    });
}

// ---- the engine: stops at one place ---------------------------------------------------------

/// The Euclidean metric, counting the distances measured and the ranks taken.
#[derive(Default)]
struct CountingMetric(std::sync::atomic::AtomicU64);

impl loops_core::Metric for CountingMetric {
    fn name(&self) -> String {
        "euclidean".to_owned()
    }
    fn check_dim(&self, dim: usize) -> loops_core::Result<()> {
        loops_core::Euclidean.check_dim(dim)
    }
    fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        loops_core::Euclidean.distance(a, b)
    }
    fn is_coordinate_euclidean(&self) -> bool {
        true
    }
    fn distance_rank(&self, a: &[f64], b: &[f64]) -> f64 {
        self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        loops_core::Euclidean.distance_rank(a, b)
    }
    fn closest_in(&self, x: &[f64], points: &[f64]) -> usize {
        self.0.fetch_add((points.len() / x.len()) as u64, std::sync::atomic::Ordering::Relaxed);
        loops_core::Euclidean.closest_in(x, points)
    }
}

/// Distances and ranks per row and run past which a case counts as a hang: the stops cost
/// O(log n) each, a few here; the engine once spent the length of the other stop.
const STOP_EVALUATIONS_PER_RUN: f64 = 16.0;

/// The engine on a robot that parks two or three times at nearly one place: each case draws
/// the stops' offsets from the ones the arithmetic finds hardest (10⁻¹⁴ m, γ/2, γ − 10⁻⁹, γ,
/// one ulp beyond γ, …), their lengths, jitter (none, or 10⁻⁹ m), a separation and the origin
/// (near 0, or far, where the offsets round), and must give the brute force's set, closest
/// columns included (a **wrong answer** otherwise), within a bounded number of distances per
/// row and run when the stops are exact (a **hang** otherwise: the n² of the old engine on
/// stops; jittered stops, no two poses alike, cost what their length does), allocating less than
/// [`ABORT_BYTES`] at once, without a panic.
#[test]
fn engine_stops() {
    use loops_core::{Euclidean, Separation, SublevelSet, Trajectory};
    let start = Instant::now();
    let budget = std::env::var("LOOPS_FUZZ_SECONDS").ok().and_then(|s| s.parse::<f64>().ok());
    let (mut cases, mut panics, mut aborts, mut hangs, mut wrong) = (0u64, 0u64, 0u64, 0u64, 0u64);
    let mut most_per_run = 0.0_f64;
    let mut failures: Vec<String> = Vec::new();
    let mut round = 0;
    loop {
        let mut rng = Rng::new(0x0057_0F5E, round);
        for _ in 0..24 {
            let gamma = *rng.pick(&[1.5, 40.0, 0.3]);
            let offsets = [0.0, 1e-14, 0.5 * gamma, gamma - 1e-9, gamma, f64::next_up(gamma), gamma + 1e-9];
            let origin = *rng.pick(&[[0.0, 0.0], [1000.0, -3000.0], [-7.25, 1e5]]);
            let stops = 2 + rng.below(2);
            let places: Vec<f64> = (0..stops).map(|k| if k == 0 { 0.0 } else { *rng.pick(&offsets) }).collect();
            let jitter = *rng.pick(&[0.0, 0.0, 1e-9]);
            let separation = *rng.pick(&[
                Separation::NONE,
                Separation { path: gamma, time_s: 0.0 },
                Separation { path: 0.0, time_s: 5.0 },
            ]);
            let mut points: Vec<[f64; 2]> = Vec::new();
            for (k, &offset) in places.iter().enumerate() {
                let place = [origin[0] + offset, origin[1]];
                if k > 0 {
                    // Out 3γ and back in steps of γ/7.
                    points.extend(
                        (1..42).map(|s: i32| [place[0], place[1] + f64::from(21 - (21 - s).abs()) * gamma / 7.0]),
                    );
                }
                for _ in 0..100 + rng.below(400) {
                    let noise = |rng: &mut Rng| jitter * (rng.below(1000) as f64 / 1000.0 - 0.5);
                    points.push([place[0] + noise(&mut rng), place[1] + noise(&mut rng)]);
                }
            }
            let label = format!("stops at {places:?} from {origin:?}, γ {gamma}, jitter {jitter}, {separation}");
            let traj = Trajectory::from_points((0..points.len()).map(|i| i as f64 * 0.1).collect(), &points)
                .expect("valid poses");
            cases += 1;
            let counting = CountingMetric::default();
            // On one thread of its own pool, whose allocations the thread's counter sees.
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                loops_core::with_threads(Some(1), || {
                    peak::peak_of(|| SublevelSet::compute_separated(&traj, &counting, gamma, separation))
                })
                .expect("a pool of one thread")
            }));
            let Ok((set, peak)) = outcome else {
                panics += 1;
                failures.push(format!("panic: {label}"));
                continue;
            };
            let set = set.expect("valid input");
            if peak > ABORT_BYTES {
                aborts += 1;
                failures.push(format!("abort: {label}: {peak} bytes allocated"));
            }
            let per_run = counting.0.into_inner() as f64 / (set.rows() + set.runs().len()) as f64;
            // Jittered stops are no stops to the engine (no two poses alike): their closest
            // columns cost what the stretch's length does, and only their answer is checked.
            if jitter == 0.0 {
                most_per_run = most_per_run.max(per_run);
            }
            if jitter == 0.0 && per_run > STOP_EVALUATIONS_PER_RUN {
                hangs += 1;
                failures.push(format!("hang: {label}: {per_run:.1} distances per row and run"));
            }
            let brute = SublevelSet::brute_force_separated(&traj, &Euclidean, gamma, separation).expect("valid input");
            if set != brute {
                wrong += 1;
                failures.push(format!("wrong answer: {label}"));
            }
        }
        round += 1;
        match budget {
            Some(seconds) if start.elapsed() < Duration::from_secs_f64(seconds) => {}
            _ => break,
        }
    }
    println!(
        "sweep engine_stops: {cases} cases in {:.0} s; {panics} panics, {aborts} aborts, {hangs} hangs, {wrong} wrong \
         answers; at most {most_per_run:.1} distances per row and run on exact stops",
        start.elapsed().as_secs_f64()
    );
    failures.truncate(SHOWN_FAILURES);
    assert!(panics + aborts + hangs + wrong == 0, "sweep engine_stops failed:\n{}", failures.join("\n"));
}
