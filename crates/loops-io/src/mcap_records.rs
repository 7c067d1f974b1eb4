//! Walking the records of an MCAP file: schemas, channels and messages, at the top level and in
//! chunks, each with its byte offset; and the checks that nothing was lost on the way.
//!
//! The file is read from the start to the closing magic, by hand, every record parsed by the
//! small parsers below. Why not the `mcap` crate's readers:
//! - every error names the byte offset of the record at fault and what is wrong with it, in one
//!   line (`the chunk record is 4096 bytes long, but the file has 100 bytes left: it is
//!   truncated`); the crate's errors carry no offset, and its parse errors (binrw) print a
//!   colored multi-line backtrace with the crate's source paths;
//! - every length field is checked against the bytes its record has left before anything is
//!   read or allocated: the crate's record parser allocates what a string's length declares
//!   (a schema name "of 4 GiB" in a 101-byte file);
//! - memory stays bounded whatever the file declares: a chunk is decompressed as a stream and
//!   its records read one at a time from the decompressor, the messages of topics not decoded
//!   are skipped without being held, and a record that is kept is at most
//!   [`MAX_MESSAGE_BYTES`] (messages) or [`MAX_STRING_BYTES`] (names). The crate's
//!   `LinearReader` holds each record whole (up to its length limit).
//!
//! What is checked, beyond each record's structure:
//! - a chunk decompresses to exactly its declared `uncompressed_size`, at most
//!   [`MAX_CHUNK_BYTES`], and to its declared CRC (0: not computed);
//! - the data section's CRC (in the data end record) and the summary section's (in the footer),
//!   where the writer computed them;
//! - the closing magic, and no byte after it;
//! - each record where the format allows it: the data section holds schema, channel, message,
//!   chunk, message index (right after its chunk), attachment, metadata and data end records;
//!   the summary schema, channel, chunk index, attachment index, statistics, metadata index and
//!   summary offset records; a chunk only schema, channel and message records. A record of a
//!   kind the format defines anywhere else is an error: a message whose opcode was corrupted into
//!   a statistics record's, say, or records of the data section after a corrupt data end. The
//!   attachment and metadata records of the data section are read to their ends, so that a
//!   corrupt message does not pass as one. Two schema or channel records of one id must be
//!   identical, as the format says;
//! - a record of an unknown opcode is skipped, as the format asks (it reserves 0x01–0x7f for its
//!   own new records and 0x80–0xff for extensions), unless it is a lost message or chunk: a
//!   record whose bytes read as a message on a channel the file defined (its first two bytes
//!   the channel's id, and at least a message's 22 bytes of header), or as a chunk (its fixed
//!   fields, a compression this reader knows, and a records length that ends at the record's
//!   end), is an error naming the offset and the channel. So a corrupt opcode never loses a
//!   message without a word, in a file without a summary too, where no count would notice it.
//!   The cost: an extension record whose first two bytes happen to equal a channel id is
//!   refused too (no writer of this project's logs writes extension records). Opcode 0x00, which
//!   no record has, is an error;
//! - nothing lost against the file's own indexes: the message index records after a chunk
//!   count its messages per channel; the summary's chunk indexes list the chunks; its
//!   statistics record counts the chunks and the messages of each channel. A count that the
//!   walk does not meet is an error naming the offset and how many messages are missing.
//!
//! The same visitor takes the records of the bag walkers (rosbag2 sqlite3, ROS 1).

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::Path;

use mcap::records::op;

use crate::compression::MAX_MESSAGE_BYTES;
use crate::error::{IoError, Result};
use crate::printable::{one_line, printable};

/// A channel's identity across files: topics with the same name, schema and encodings are one.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) struct ChannelKey {
    pub(crate) topic: String,
    pub(crate) schema_name: String,
    pub(crate) schema_encoding: String,
    pub(crate) message_encoding: String,
}

/// Where a record lies: the offset of the top-level record (the chunk, for records in one),
/// and within a chunk the offset in its decompressed records.
#[derive(Debug, Clone, Copy)]
pub(crate) struct At {
    pub(crate) offset: u64,
    pub(crate) in_chunk: Option<u64>,
}

/// A message record's header.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MessageHeader {
    pub(crate) log_time: u64,
    pub(crate) publish_time: u64,
}

/// What the walker reports: channels as they appear, and messages. The walkers of the bags
/// (rosbag2 sqlite3, ROS 1) report to the same visitor.
pub(crate) trait Visitor {
    /// A channel appears (for the first time in this file); returns the visitor's index for it.
    fn channel(&mut self, key: ChannelKey, at: At) -> usize;
    /// A message on the channel the visitor numbered `channel`.
    fn message(&mut self, channel: usize, header: MessageHeader, data: &[u8], at: At) -> Result<()>;
    /// Whether the visitor decodes the messages of `channel` (a walker may skip reading the
    /// bytes of the others, and pass empty data).
    fn decodes(&self, _channel: usize) -> bool {
        true
    }
}

/// The name of a record type, for messages.
fn record_name(opcode: u8) -> &'static str {
    match opcode {
        op::HEADER => "header",
        op::FOOTER => "footer",
        op::SCHEMA => "schema",
        op::CHANNEL => "channel",
        op::MESSAGE => "message",
        op::CHUNK => "chunk",
        op::MESSAGE_INDEX => "message index",
        op::CHUNK_INDEX => "chunk index",
        op::ATTACHMENT => "attachment",
        op::ATTACHMENT_INDEX => "attachment index",
        op::STATISTICS => "statistics",
        op::METADATA => "metadata",
        op::METADATA_INDEX => "metadata index",
        op::SUMMARY_OFFSET => "summary offset",
        op::DATA_END => "data end",
        _ => "unknown",
    }
}

/// Largest chunk, decompressed: 4 GiB. Chunks are decompressed as a stream, so memory does not
/// grow with this size (only the time to decompress does); writers make chunks of about 1 MiB,
/// larger only to hold one large message. A chunk declaring more is refused before any of it
/// is decompressed, and no chunk decompresses past what it declares.
pub(crate) const MAX_CHUNK_BYTES: u64 = 4 << 30;

/// Largest string read (a schema name or encoding, a topic, a compression name): 1 MiB.
pub(crate) const MAX_STRING_BYTES: u64 = 1 << 20;

/// The buffer of a chunk's decompressed records: 64 KiB.
const DECOMPRESSED_BUFFER: usize = 64 << 10;

/// The bytes between records: opcode and length.
const RECORD_HEADER: u64 = 9;

/// The fixed fields of a chunk header before its compression string: start and end times,
/// uncompressed size, CRC, the compression string's length.
const CHUNK_FIXED: u64 = 8 + 8 + 8 + 4 + 4;

/// The bytes of a message record before its data: channel id, sequence, log and publish times.
const MESSAGE_HEAD: u64 = 2 + 4 + 8 + 8;

/// The first bytes of a record of unknown opcode that are read to tell a corrupt message or
/// chunk: a chunk's fixed fields, a compression name of up to 8 bytes, the records' length.
const UNKNOWN_HEAD: usize = CHUNK_FIXED as usize + 8 + 8;

/// The unknown records remembered, to name them when an index points at one.
const MAX_UNKNOWN_KEPT: usize = 4096;

/// The summary records remembered, for the summary offsets that point at them.
const MAX_SUMMARY_KEPT: usize = 1 << 20;

/// The file at `path` opened for a record walk (MCAP or ROS 1 bag): a buffered reader and the
/// file's length in bytes, which bounds every record length read from it.
pub(crate) fn open_records(path: &Path) -> Result<(BufReader<File>, u64)> {
    let open_error = |error| IoError::Open { path: path.to_path_buf(), error };
    let file = File::open(path).map_err(open_error)?;
    let len = file.metadata().map_err(open_error)?.len();
    Ok((BufReader::with_capacity(1 << 20, file), len))
}

/// Walks the records of the MCAP file at `path`, reporting channels and messages to `visitor`.
pub(crate) fn walk(path: &Path, visitor: &mut impl Visitor) -> Result<()> {
    let (reader, len) = open_records(path)?;
    walk_reader(reader, len, path, visitor)
}

/// Walks the records of the MCAP file `file` (read from its start), which errors call `path`.
pub(crate) fn walk_file(mut file: File, path: &Path, visitor: &mut impl Visitor) -> Result<()> {
    use std::io::Seek;
    let open_error = |error| IoError::Open { path: path.to_path_buf(), error };
    let len = file.metadata().map_err(open_error)?.len();
    file.rewind().map_err(open_error)?;
    walk_reader(BufReader::with_capacity(1 << 20, file), len, path, visitor)
}

fn walk_reader(reader: BufReader<File>, len: u64, path: &Path, visitor: &mut impl Visitor) -> Result<()> {
    let source = Source { reader, pos: 0, crc: crc32fast::Hasher::new(), summary_crc: None };
    let mut walker = Walker { path, source, len, state: State::default() };
    walker.run(visitor)
}

/// The file, read forward, with the CRCs of what was read: of everything from the start (the
/// data section's CRC), and from the end of the data end record (the summary section's).
#[derive(Debug)]
struct Source {
    reader: BufReader<File>,
    /// Bytes read so far: the offset of the next byte.
    pos: u64,
    crc: crc32fast::Hasher,
    summary_crc: Option<crc32fast::Hasher>,
}

impl Read for Source {
    fn read(&mut self, buffer: &mut [u8]) -> io::Result<usize> {
        let n = self.reader.read(buffer)?;
        self.crc.update(&buffer[..n]);
        if let Some(summary) = &mut self.summary_crc {
            summary.update(&buffer[..n]);
        }
        self.pos += n as u64;
        Ok(n)
    }
}

/// Reads `n` bytes of `reader` and drops them; fails if it ends before.
fn skip(reader: &mut impl Read, n: u64) -> io::Result<()> {
    let copied = io::copy(&mut reader.take(n), &mut io::sink())?;
    if copied < n {
        return Err(io::Error::new(io::ErrorKind::UnexpectedEof, format!("{copied} of {n} bytes")));
    }
    Ok(())
}

/// What a record parser says is wrong, as the end of a message.
type Fault = String;

/// How an I/O error reading the bytes of a record reads in a message.
#[derive(Debug, Clone, Copy)]
enum Context {
    /// The file itself: the record's length was checked against the file's, so only the
    /// operating system can fail.
    File,
    /// A chunk's decompressed records.
    Chunk { compression: &'static str },
}

impl Context {
    fn describe(self, error: &io::Error) -> Fault {
        match self {
            Context::File => format!("cannot read the file: {}", one_line(error)),
            Context::Chunk { compression: "" } => format!("the chunk's records cannot be read: {}", one_line(error)),
            Context::Chunk { compression } if error.kind() == io::ErrorKind::UnexpectedEof => {
                format!("the {compression} chunk's data ends before its records do: the chunk is corrupt")
            }
            Context::Chunk { compression } => {
                format!("the {compression} chunk does not decompress: {}", one_line(error))
            }
        }
    }
}

/// The fields of one record, read in order from a stream, never past the record's end: every
/// length a field declares is checked against the bytes the record has left before anything is
/// read or allocated.
struct Fields<'r, R> {
    reader: &'r mut R,
    /// Bytes of the record not read yet.
    left: u64,
    /// The record's kind, for messages (`schema`).
    record: &'static str,
    context: Context,
}

impl<'r, R: Read> Fields<'r, R> {
    fn new(reader: &'r mut R, len: u64, opcode: u8, context: Context) -> Self {
        Self { reader, left: len, record: record_name(opcode), context }
    }

    fn array<const N: usize>(&mut self, what: &str) -> std::result::Result<[u8; N], Fault> {
        if self.left < N as u64 {
            return Err(format!(
                "the {} record is too short: it ends in the middle of its {what} ({} bytes left, {N} needed)",
                self.record, self.left
            ));
        }
        let mut bytes = [0u8; N];
        self.reader.read_exact(&mut bytes).map_err(|e| self.context.describe(&e))?;
        self.left -= N as u64;
        Ok(bytes)
    }

    fn u16(&mut self, what: &str) -> std::result::Result<u16, Fault> {
        self.array(what).map(u16::from_le_bytes)
    }

    fn u32(&mut self, what: &str) -> std::result::Result<u32, Fault> {
        self.array(what).map(u32::from_le_bytes)
    }

    fn u64(&mut self, what: &str) -> std::result::Result<u64, Fault> {
        self.array(what).map(u64::from_le_bytes)
    }

    /// A length that `what` declares, checked against what the record has left.
    fn check_length(&self, len: u64, what: &str) -> std::result::Result<u64, Fault> {
        if len > self.left {
            return Err(format!(
                "its {what} is declared {len} bytes long, but the {} record has {} bytes left",
                self.record, self.left
            ));
        }
        Ok(len)
    }

    /// A `u32`-length-prefixed UTF-8 string of at most [`MAX_STRING_BYTES`].
    fn string(&mut self, what: &str) -> std::result::Result<String, Fault> {
        let len = self.u32(&format!("{what}'s length"))?;
        let len = self.check_length(u64::from(len), what)?;
        if len > MAX_STRING_BYTES {
            return Err(format!(
                "its {what} is declared {len} bytes long, over the limit of {} MiB for a name",
                MAX_STRING_BYTES >> 20
            ));
        }
        let mut bytes = vec![0u8; len as usize];
        self.reader.read_exact(&mut bytes).map_err(|e| self.context.describe(&e))?;
        self.left -= len;
        String::from_utf8(bytes).map_err(|error| {
            format!("its {what} is not UTF-8 (invalid byte at byte {} of it)", error.utf8_error().valid_up_to())
        })
    }

    /// `n` bytes, dropped.
    fn skip(&mut self, n: u64, what: &str) -> std::result::Result<(), Fault> {
        let n = self.check_length(n, what)?;
        skip(self.reader, n).map_err(|e| self.context.describe(&e))?;
        self.left -= n;
        Ok(())
    }

    /// A `u32`-byte-length-prefixed field (a map, an array), dropped.
    fn skip_prefixed(&mut self, what: &str) -> std::result::Result<(), Fault> {
        let len = self.u32(&format!("{what}'s length"))?;
        self.skip(u64::from(len), what)
    }

    /// The rest of the record, dropped (fields a later version of the format may add).
    fn skip_rest(&mut self) -> std::result::Result<(), Fault> {
        let left = self.left;
        self.skip(left, "rest")
    }

    /// The rest of the record into `buffer` (cleared first).
    fn rest_into(&mut self, buffer: &mut Vec<u8>) -> std::result::Result<(), Fault> {
        buffer.clear();
        buffer.resize(self.left as usize, 0);
        self.reader.read_exact(buffer).map_err(|e| self.context.describe(&e))?;
        self.left = 0;
        Ok(())
    }
}

/// A schema as a channel needs it.
#[derive(Debug, Clone, PartialEq, Eq)]
struct SchemaInfo {
    name: String,
    encoding: String,
}

/// What the walk has seen so far, in one file.
#[derive(Debug, Default)]
struct State {
    schemas: HashMap<u16, SchemaInfo>,
    /// MCAP channel id to the visitor's index, and the topic (for messages).
    channels: HashMap<u16, (usize, String)>,
    /// What each channel record defined: its schema id and message encoding, with the topic in
    /// `channels`; a second record of the id must say the same.
    channel_records: HashMap<u16, (u16, String)>,
    /// Messages read per MCAP channel id, in the whole file.
    counts: HashMap<u16, u64>,
    /// Reused buffer for message data.
    data: Vec<u8>,
    /// The last chunk walked and the messages read in it per channel, until its message index
    /// records have been checked.
    chunk: Option<ChunkCount<u16>>,
    /// The offsets and lengths (whole record) of the chunks walked, in file order.
    chunks: Vec<(u64, u64)>,
    /// Offsets and opcodes of the first unknown records of the data section.
    unknown: Vec<(u64, u8)>,
    /// The offset of the data end record, once walked.
    data_end_at: Option<u64>,
    /// The chunks the summary indexes: offset and length, with the offset of the index record.
    chunk_indexes: Vec<ChunkIndex>,
    /// The summary's statistics record, and its offset.
    statistics: Option<(u64, Statistics)>,
    /// Where the summary section starts: the end of the data end record.
    summary_begin: Option<u64>,
    /// The offsets and opcodes of the summary's records (the first [`MAX_SUMMARY_KEPT`]).
    summary_records: Vec<(u64, u8)>,
    /// The summary offset records: their offset, and the opcode and offset of the group each
    /// points at.
    summary_offsets: Vec<(u64, u8, u64)>,
}

/// The messages read in one chunk per key (an MCAP channel id, a ROS 1 connection), and what
/// the index records after the chunk declare (MCAP message indexes, ROS 1 index data).
#[derive(Debug)]
pub(crate) struct ChunkCount<K> {
    /// The chunk record's offset.
    pub(crate) offset: u64,
    pub(crate) read: HashMap<K, u64>,
    /// Per key: the count its index record declares, and the record's offset.
    pub(crate) indexed: HashMap<K, (u64, u64)>,
}

/// A key whose messages read in a chunk differ from the count its index record declares.
#[derive(Debug)]
pub(crate) struct CountMismatch<K> {
    pub(crate) key: K,
    pub(crate) read: u64,
    pub(crate) declared: u64,
    /// The index record's offset (the chunk's, for a key no index record lists).
    pub(crate) index_at: u64,
}

impl<K: Copy + Ord + std::hash::Hash> ChunkCount<K> {
    /// The chunk at `offset`, nothing read yet.
    pub(crate) fn new(offset: u64) -> Self {
        Self { offset, read: HashMap::new(), indexed: HashMap::new() }
    }

    /// The first key (in order) whose messages read differ from its index's count; none when
    /// the chunk has no index records (its writer did not index it, or stopped before).
    pub(crate) fn mismatch(&self) -> Option<CountMismatch<K>> {
        if self.indexed.is_empty() {
            return None;
        }
        let mut keys: Vec<K> = self.read.keys().chain(self.indexed.keys()).copied().collect();
        keys.sort_unstable();
        keys.dedup();
        keys.into_iter().find_map(|key| {
            let read = self.read.get(&key).copied().unwrap_or(0);
            let (declared, index_at) = self.indexed.get(&key).copied().unwrap_or((0, self.offset));
            (read != declared).then_some(CountMismatch { key, read, declared, index_at })
        })
    }
}

impl<K> CountMismatch<K> {
    /// `: N messages lost (a record in the chunk is corrupt)` when fewer were read than declared;
    /// nothing otherwise.
    pub(crate) fn lost(&self) -> String {
        if self.declared > self.read {
            format!(": {} messages lost (a record in the chunk is corrupt)", self.declared - self.read)
        } else {
            String::new()
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct ChunkIndex {
    at: u64,
    chunk_offset: u64,
    chunk_length: u64,
}

#[derive(Debug, Default)]
struct Statistics {
    message_count: u64,
    chunk_count: u32,
    channel_message_counts: HashMap<u16, u64>,
}

#[derive(Debug)]
struct Walker<'p> {
    path: &'p Path,
    source: Source,
    /// The file's length in bytes.
    len: u64,
    state: State,
}

/// Where the walk is in the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Section {
    Data,
    Summary,
}

impl Walker<'_> {
    fn error(&self, offset: u64, message: impl Into<String>) -> IoError {
        IoError::mcap(self.path, offset, message)
    }

    fn run(&mut self, visitor: &mut impl Visitor) -> Result<()> {
        let mut magic = [0u8; 8];
        let start = self.source.read_exact(&mut magic);
        if self.len < 8 || start.is_err() || magic != mcap::MAGIC {
            return Err(self.error(
                0,
                format!(
                    "not an MCAP file: it does not start with the MCAP magic bytes (89 4D 43 41 50 30 0D 0A); \
                     the file is {} bytes long",
                    self.len
                ),
            ));
        }
        let mut section = Section::Data;
        loop {
            let pos = self.source.pos;
            if self.len - pos < RECORD_HEADER {
                let what = if pos == self.len { "ends" } else { "ends in the middle of a record header" };
                return Err(self.error(pos, format!("the file {what} before its footer: it is truncated")));
            }
            // The data section's CRC covers every byte before the data end record.
            let crc_before = self.source.crc.clone();
            let mut head = [0u8; 9];
            self.source.read_exact(&mut head).map_err(|e| self.error(pos, Context::File.describe(&e)))?;
            let opcode = head[0];
            let body_len = u64::from_le_bytes(head[1..].try_into().expect("8 bytes"));
            let body_start = pos + RECORD_HEADER;
            let left = self.len - body_start;
            if body_len > left {
                return Err(self.error(
                    pos,
                    format!(
                        "the {} record is {body_len} bytes long, but the file has {left} bytes left: it is truncated",
                        record_name(opcode)
                    ),
                ));
            }
            if opcode != op::MESSAGE_INDEX {
                self.check_chunk_messages()?;
            }
            if opcode == op::FOOTER {
                return self.finish(pos, body_len, section);
            }
            if opcode == op::HEADER && pos != mcap::MAGIC.len() as u64 {
                return Err(self.error(
                    pos,
                    "a header record after the first record: the file is corrupt (a record whose opcode is \
                     corrupt?)",
                ));
            }
            if section == Section::Summary && self.state.summary_records.len() < MAX_SUMMARY_KEPT {
                self.state.summary_records.push((pos, opcode));
            }
            let at = At { offset: pos, in_chunk: None };
            let mut fields = Fields::new(&mut self.source, body_len, opcode, Context::File);
            let result = match (opcode, section) {
                (op::DATA_END, Section::Data) => {
                    let result = data_end(&mut fields, crc_before.finalize());
                    section = Section::Summary;
                    self.state.data_end_at = Some(pos);
                    result
                }
                (op::SCHEMA | op::CHANNEL | op::MESSAGE, Section::Data) => {
                    self.state.record(opcode, &mut fields, at, visitor)
                }
                (op::CHUNK, Section::Data) => {
                    let result = chunk(&mut self.state, &mut fields, pos, visitor);
                    self.state.chunks.push((pos, RECORD_HEADER + body_len));
                    result
                }
                (op::MESSAGE_INDEX, Section::Data) => {
                    self.state.message_index(&mut fields, pos).map_err(Failure::Fault)
                }
                (op::ATTACHMENT, Section::Data) => attachment(&mut fields).map_err(Failure::Fault),
                (op::METADATA, Section::Data) => metadata(&mut fields).map_err(Failure::Fault),
                (op::CHUNK_INDEX, Section::Summary) => self.state.chunk_index(&mut fields, pos).map_err(Failure::Fault),
                (op::STATISTICS, Section::Summary) => self.state.statistics(&mut fields, pos).map_err(Failure::Fault),
                (op::SUMMARY_OFFSET, Section::Summary) => {
                    self.state.summary_offset(&mut fields, pos).map_err(Failure::Fault)
                }
                (op::SCHEMA | op::CHANNEL | op::ATTACHMENT_INDEX | op::METADATA_INDEX, Section::Summary) => Ok(()),
                // The first record (a header anywhere else is an error above).
                (op::HEADER, Section::Data) => Ok(()),
                (op::HEADER..=op::DATA_END, Section::Data) => Err(Failure::Fault(format!(
                    "a {} record in the data section, where the format has none (it belongs to the summary): the \
                     record's opcode is corrupt (a message's?)",
                    record_name(opcode)
                ))),
                (op::HEADER..=op::DATA_END, Section::Summary) => Err(Failure::Fault(format!(
                    "a {} record after the data section ended (with the data end record at offset {}), where the \
                     format has none: the file is corrupt (a record's opcode, or the data end's?), and what the data \
                     section holds past it would be lost",
                    record_name(opcode),
                    self.state.data_end_at.unwrap_or(0)
                ))),
                (_, Section::Data) => self.state.unknown(&mut fields, pos, opcode).map_err(Failure::Fault),
                (_, Section::Summary) => Ok(()),
            };
            let result = result.and_then(|()| fields.skip_rest().map_err(Failure::Fault));
            match result {
                Ok(()) => {}
                Err(Failure::Fault(fault)) => {
                    return Err(self.error(pos, located(fault, None)));
                }
                Err(Failure::Error(error)) => return Err(*error),
            }
            if section == Section::Summary && self.source.summary_crc.is_none() {
                self.source.summary_crc = Some(crc32fast::Hasher::new());
                self.state.summary_begin = Some(body_start + body_len);
            }
            debug_assert_eq!(self.source.pos, body_start + body_len);
        }
    }

    /// The message index records after the last chunk, checked against its messages: called at
    /// the first record that is not a message index.
    fn check_chunk_messages(&mut self) -> Result<()> {
        let Some(chunk) = self.state.chunk.take() else { return Ok(()) };
        let Some(m) = chunk.mismatch() else { return Ok(()) };
        Err(self.error(
            chunk.offset,
            format!(
                "the chunk holds {} messages on channel {}{}, but its message index (the record at offset {}) lists \
                 {}{}",
                m.read,
                m.key,
                self.state.topic_of(m.key),
                m.index_at,
                m.declared,
                m.lost()
            ),
        ))
    }

    /// After the footer: its summary CRC, the closing magic, nothing after it, and the counts of
    /// the summary against what was read.
    fn finish(&mut self, footer_at: u64, body_len: u64, section: Section) -> Result<()> {
        let mut fields = Fields::new(&mut self.source, body_len, op::FOOTER, Context::File);
        let parsed = (|| {
            let summary_start = fields.u64("summary start")?;
            let summary_offset_start = fields.u64("summary offset start")?;
            // The summary CRC covers the summary up to and including the field before it.
            let calculated = fields.reader.summary_crc.take().map(crc32fast::Hasher::finalize);
            let summary_crc = fields.u32("summary CRC")?;
            fields.skip_rest()?;
            Ok::<_, Fault>((summary_start, summary_offset_start, calculated, summary_crc))
        })();
        let (summary_start, summary_offset_start, calculated, summary_crc) =
            parsed.map_err(|fault| self.error(footer_at, fault))?;
        if section == Section::Data {
            return Err(self.error(
                footer_at,
                "the footer comes before any data end record, which ends the data section: the file is corrupt",
            ));
        }
        if let Some(calculated) = calculated.filter(|_| summary_crc != 0)
            && calculated != summary_crc
        {
            return Err(self.error(
                footer_at,
                format!(
                    "the summary section is corrupt: its CRC is {calculated:#010x}, but the footer declares \
                     {summary_crc:#010x} (summary from offset {summary_start})"
                ),
            ));
        }
        let magic_at = footer_at + RECORD_HEADER + body_len;
        if self.len - magic_at < 8 {
            return Err(self.error(magic_at, "the file ends before the closing MCAP magic bytes: it is truncated"));
        }
        let mut magic = [0u8; 8];
        self.source.read_exact(&mut magic).map_err(|e| self.error(magic_at, Context::File.describe(&e)))?;
        if magic != mcap::MAGIC {
            return Err(self.error(magic_at, "bad magic: the footer is not followed by the MCAP magic bytes"));
        }
        let end = magic_at + 8;
        if self.len > end {
            return Err(self.error(
                end,
                format!(
                    "{} bytes follow the closing MCAP magic bytes, which end the file: the file is corrupt (or two \
                     files joined)",
                    self.len - end
                ),
            ));
        }
        self.check_summary_offsets(footer_at, summary_start, summary_offset_start)?;
        self.check_summary()
    }

    /// The footer's and the summary offset records' pointers against the summary's records: a
    /// record the summary says it holds (its statistics) must be there, with its opcode.
    fn check_summary_offsets(&self, footer_at: u64, summary_start: u64, summary_offset_start: u64) -> Result<()> {
        let state = &self.state;
        if state.summary_records.len() >= MAX_SUMMARY_KEPT {
            return Ok(());
        }
        let begin = state.summary_begin.unwrap_or(footer_at);
        if summary_start != 0 && summary_start != begin {
            return Err(self.error(
                footer_at,
                format!(
                    "the footer says the summary starts at offset {summary_start}, but the data end record ends at \
                     {begin}: the file is corrupt"
                ),
            ));
        }
        let opcode_at = |offset: u64| {
            state
                .summary_records
                .binary_search_by_key(&offset, |record| record.0)
                .ok()
                .map(|i| state.summary_records[i].1)
        };
        let wrong = |what: String, offset: u64, wanted: u8| {
            let there = match opcode_at(offset) {
                Some(opcode) => format!("the record there has opcode {opcode:#04x} ({})", record_name(opcode)),
                None => "no summary record starts there".to_owned(),
            };
            format!(
                "{what} at offset {offset} holds {} records, but {there}: the summary is corrupt",
                record_name(wanted)
            )
        };
        if summary_offset_start != 0
            && summary_offset_start != footer_at
            && opcode_at(summary_offset_start) != Some(op::SUMMARY_OFFSET)
        {
            return Err(self.error(
                footer_at,
                wrong(
                    "the footer says the summary offset section".to_owned(),
                    summary_offset_start,
                    op::SUMMARY_OFFSET,
                ),
            ));
        }
        for &(at, group, start) in &state.summary_offsets {
            if opcode_at(start) != Some(group) {
                return Err(self.error(at, wrong("this summary offset record says the group".to_owned(), start, group)));
            }
        }
        Ok(())
    }

    /// The summary's chunk indexes and statistics against what the walk read.
    fn check_summary(&self) -> Result<()> {
        let state = &self.state;
        for index in &state.chunk_indexes {
            let found = state.chunks.binary_search_by_key(&index.chunk_offset, |chunk| chunk.0);
            match found {
                Ok(i) if state.chunks[i].1 == index.chunk_length => {}
                Ok(i) => {
                    return Err(self.error(
                        index.chunk_offset,
                        format!(
                            "the chunk here is {} bytes long, but the summary's chunk index (the record at offset {}) \
                             says {}: the file is corrupt",
                            state.chunks[i].1, index.at, index.chunk_length
                        ),
                    ));
                }
                Err(_) => {
                    let what = match state.unknown.iter().find(|(offset, _)| *offset == index.chunk_offset) {
                        Some((_, opcode)) => format!(
                            "the record here has the unknown opcode {opcode:#04x}: the chunk's opcode is corrupt, and \
                             its messages would be lost"
                        ),
                        None => "no chunk record starts here: the file is corrupt".to_owned(),
                    };
                    return Err(self.error(
                        index.chunk_offset,
                        format!(
                            "the summary's chunk index (the record at offset {}) lists a chunk of {} bytes here, but \
                             {what}",
                            index.at, index.chunk_length
                        ),
                    ));
                }
            }
        }
        let Some((at, statistics)) = &state.statistics else { return Ok(()) };
        let suspects = match state.unknown.first() {
            Some((offset, opcode)) => format!(
                "; the data section holds {} record{} of unknown opcodes, the first at offset {offset} (opcode \
                 {opcode:#04x})",
                state.unknown.len(),
                if state.unknown.len() == 1 { "" } else { "s" }
            ),
            None => String::new(),
        };
        let lost = |declared: u64, read: u64| {
            if declared > read {
                format!(": {} messages lost (a record is corrupt){suspects}", declared - read)
            } else {
                String::new()
            }
        };
        let mut channels: Vec<u16> =
            statistics.channel_message_counts.keys().chain(state.counts.keys()).copied().collect();
        channels.sort_unstable();
        channels.dedup();
        if !statistics.channel_message_counts.is_empty() {
            for channel in channels {
                let declared = statistics.channel_message_counts.get(&channel).copied().unwrap_or(0);
                let read = state.counts.get(&channel).copied().unwrap_or(0);
                if declared != read {
                    return Err(self.error(
                        *at,
                        format!(
                            "the summary's statistics record counts {declared} messages on channel {channel}{}, but \
                             the data section holds {read}{}",
                            state.topic_of(channel),
                            lost(declared, read)
                        ),
                    ));
                }
            }
        }
        let read: u64 = state.counts.values().sum();
        if statistics.message_count != read {
            return Err(self.error(
                *at,
                format!(
                    "the summary's statistics record counts {} messages, but the data section holds {read}{}",
                    statistics.message_count,
                    lost(statistics.message_count, read)
                ),
            ));
        }
        if u64::from(statistics.chunk_count) != state.chunks.len() as u64 {
            return Err(self.error(
                *at,
                format!(
                    "the summary's statistics record counts {} chunks, but the data section holds {}",
                    statistics.chunk_count,
                    state.chunks.len()
                ),
            ));
        }
        Ok(())
    }
}

/// Why a record failed: what is wrong with it (the caller names the record's offset), or an
/// error already complete (a message the visitor could not decode).
#[derive(Debug)]
enum Failure {
    Fault(Fault),
    Error(Box<IoError>),
}

impl From<Fault> for Failure {
    fn from(fault: Fault) -> Self {
        Failure::Fault(fault)
    }
}

/// `fault`, located in a chunk at `inner` when it is in one.
fn located(fault: Fault, inner: Option<u64>) -> String {
    match inner {
        Some(inner) => format!("in the record at byte {inner} of this chunk: {fault}"),
        None => fault,
    }
}

/// A data end record: its CRC of the data section against `calculated` (0: not computed).
fn data_end(fields: &mut Fields<'_, Source>, calculated: u32) -> std::result::Result<(), Failure> {
    let declared = fields.u32("data section CRC")?;
    if declared != 0 && declared != calculated {
        return Err(Failure::Fault(format!(
            "the data section is corrupt: its CRC is {calculated:#010x}, but the data end record declares \
             {declared:#010x}"
        )));
    }
    Ok(())
}

/// An attachment record of the data section: its fields read to the end, so that a record of
/// another kind whose opcode became an attachment's fails here rather than being skipped.
fn attachment(fields: &mut Fields<'_, Source>) -> std::result::Result<(), Fault> {
    let _log_time = fields.u64("log time")?;
    let _create_time = fields.u64("create time")?;
    fields.skip_prefixed("name")?;
    fields.skip_prefixed("media type")?;
    let data_len = fields.u64("data length")?;
    fields.skip(data_len, "data")?;
    let _crc = fields.u32("CRC")?;
    Ok(())
}

/// A metadata record of the data section: its name and its map of strings, read to the map's
/// end (see [`attachment`]).
fn metadata(fields: &mut Fields<'_, Source>) -> std::result::Result<(), Fault> {
    fields.string("name")?;
    let len = fields.u32("metadata's length")?;
    let len = fields.check_length(u64::from(len), "metadata")?;
    let end = fields.left - len;
    while fields.left > end {
        for what in ["metadata key", "metadata value"] {
            let string_len = fields.u32(&format!("{what}'s length"))?;
            if u64::from(string_len) > fields.left.saturating_sub(end) {
                return Err(format!(
                    "a {what} is declared {string_len} bytes long, past the end of the metadata's {len} bytes"
                ));
            }
            fields.skip(u64::from(string_len), what)?;
        }
    }
    if fields.left != end {
        return Err(format!("the metadata's entries end past its declared {len} bytes"));
    }
    Ok(())
}

/// A chunk record at `offset`, its header fields not read yet: its records, decompressed as a
/// stream and read one at a time.
fn chunk(
    state: &mut State,
    fields: &mut Fields<'_, Source>,
    offset: u64,
    visitor: &mut impl Visitor,
) -> std::result::Result<(), Failure> {
    let _start = fields.u64("message start time")?;
    let _end = fields.u64("message end time")?;
    let uncompressed_size = fields.u64("uncompressed size")?;
    let crc = fields.u32("uncompressed CRC")?;
    let compression = fields.string("compression")?;
    let compressed_size = fields.u64("records' length")?;
    let compressed_size = fields.check_length(compressed_size, "records")?;
    let compression: &'static str = match compression.as_str() {
        "" => "",
        "zstd" => "zstd",
        "lz4" => "lz4",
        other => {
            return Err(Failure::Fault(format!(
                "the chunk is compressed with {other:?}, which this reader does not read (it reads zstd, lz4 and \
                 none)"
            )));
        }
    };
    if uncompressed_size > MAX_CHUNK_BYTES {
        return Err(Failure::Fault(format!(
            "the chunk declares {uncompressed_size} bytes decompressed, over the limit of {} GiB for one chunk",
            MAX_CHUNK_BYTES >> 30
        )));
    }
    if compression.is_empty() && compressed_size != uncompressed_size {
        return Err(Failure::Fault(format!(
            "the uncompressed chunk holds {compressed_size} bytes of records but declares {uncompressed_size}"
        )));
    }
    let context = Context::Chunk { compression };
    let mut compressed = (&mut *fields.reader).take(compressed_size);
    let decoder: Box<dyn Read + '_> = match compression {
        "zstd" => Box::new(
            zstd::stream::read::Decoder::new(&mut compressed).map_err(|e| Failure::Fault(context.describe(&e)))?,
        ),
        "lz4" => Box::new(lz4_flex::frame::FrameDecoder::new(&mut compressed)),
        _ => Box::new(&mut compressed),
    };
    // Buffered: the fields are read a few bytes at a time, and a decoder call per field would
    // cost more than the decompression.
    let mut records = BufReader::with_capacity(
        DECOMPRESSED_BUFFER.min(uncompressed_size as usize + 1),
        Decompressed { inner: decoder, crc: crc32fast::Hasher::new() },
    );
    state.chunk = Some(ChunkCount::new(offset));
    let mut inner = 0u64;
    while inner < uncompressed_size {
        let left = uncompressed_size - inner;
        if left < RECORD_HEADER {
            return Err(Failure::Fault(format!(
                "the chunk's records end in the middle of a record header at byte {inner} of this chunk ({left} \
                 bytes left of the {uncompressed_size} it declares)"
            )));
        }
        let mut head = [0u8; 9];
        records.read_exact(&mut head).map_err(|e| located(context.describe(&e), Some(inner)))?;
        let opcode = head[0];
        let len = u64::from_le_bytes(head[1..].try_into().expect("8 bytes"));
        if len > left - RECORD_HEADER {
            return Err(Failure::Fault(located(
                format!(
                    "the {} record is {len} bytes long, but the chunk has {} bytes left of the {uncompressed_size} it \
                     declares",
                    record_name(opcode),
                    left - RECORD_HEADER
                ),
                Some(inner),
            )));
        }
        if !matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE) {
            return Err(Failure::Fault(located(
                format!(
                    "a record of opcode {opcode:#04x} ({}) in a chunk, which holds only schema, channel and message \
                     records: the chunk is corrupt",
                    record_name(opcode)
                ),
                Some(inner),
            )));
        }
        let at = At { offset, in_chunk: Some(inner) };
        let mut record = Fields::new(&mut records, len, opcode, context);
        state
            .record(opcode, &mut record, at, visitor)
            .and_then(|()| record.skip_rest().map_err(Failure::Fault))
            .map_err(|failure| match failure {
                Failure::Fault(fault) => Failure::Fault(located(fault, Some(inner))),
                error => error,
            })?;
        inner += RECORD_HEADER + len;
    }
    // Nothing after the declared size.
    let mut extra = [0u8; 1];
    match records.read(&mut extra) {
        Ok(0) => {}
        Ok(_) => {
            return Err(Failure::Fault(format!(
                "the chunk decompresses to more than the {uncompressed_size} bytes it declares"
            )));
        }
        Err(e) => return Err(Failure::Fault(context.describe(&e))),
    }
    let calculated = records.get_ref().crc.clone().finalize();
    drop(records);
    if crc != 0 && calculated != crc {
        return Err(Failure::Fault(format!(
            "the chunk is corrupt: the CRC of its records is {calculated:#010x}, but the chunk declares {crc:#010x}"
        )));
    }
    // What the decompressor left of the compressed bytes (padding), then the rest of the record.
    let padding = compressed.limit();
    fields.left -= compressed_size - padding;
    fields.skip(padding, "padding")?;
    Ok(())
}

/// A chunk's decompressed records, with their CRC.
struct Decompressed<R> {
    inner: R,
    crc: crc32fast::Hasher,
}

impl<R: Read> Read for Decompressed<R> {
    fn read(&mut self, buffer: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buffer)?;
        self.crc.update(&buffer[..n]);
        Ok(n)
    }
}

impl State {
    /// The topic of MCAP channel `id`, for messages: ` (/odom)`, or nothing.
    fn topic_of(&self, id: u16) -> String {
        match self.channels.get(&id) {
            Some((_, topic)) => format!(" ({})", printable(topic)),
            None => " (a channel no record defines)".to_owned(),
        }
    }

    /// A schema, channel or message record, at the top level or in a chunk, its fields not read
    /// yet.
    fn record<R: Read>(
        &mut self,
        opcode: u8,
        fields: &mut Fields<'_, R>,
        at: At,
        visitor: &mut impl Visitor,
    ) -> std::result::Result<(), Failure> {
        match opcode {
            op::MESSAGE => {
                let channel_id = fields.u16("channel id")?;
                let _sequence = fields.u32("sequence")?;
                let log_time = fields.u64("log time")?;
                let publish_time = fields.u64("publish time")?;
                let header = MessageHeader { log_time, publish_time };
                let Some(&(channel, _)) = self.channels.get(&channel_id) else {
                    return Err(Failure::Fault(format!(
                        "a message on channel {channel_id}, which no earlier channel record defines"
                    )));
                };
                *self.counts.entry(channel_id).or_default() += 1;
                if let Some(chunk) = &mut self.chunk
                    && at.in_chunk.is_some()
                {
                    *chunk.read.entry(channel_id).or_default() += 1;
                }
                let mut data = std::mem::take(&mut self.data);
                data.clear();
                if visitor.decodes(channel) {
                    if fields.left > MAX_MESSAGE_BYTES {
                        return Err(Failure::Fault(format!(
                            "the message on channel {channel_id} is {} bytes long, over the limit of {} MiB for a \
                             pose message",
                            fields.left,
                            MAX_MESSAGE_BYTES >> 20
                        )));
                    }
                    fields.rest_into(&mut data)?;
                } else {
                    fields.skip_rest()?;
                }
                let result = visitor.message(channel, header, &data, at);
                self.data = data;
                result.map_err(|error| Failure::Error(Box::new(error)))
            }
            op::SCHEMA => {
                let id = fields.u16("id")?;
                let name = fields.string("name")?;
                let encoding = fields.string("encoding")?;
                fields.skip_prefixed("data")?;
                let schema = SchemaInfo { name, encoding };
                match self.schemas.get(&id) {
                    Some(first) if *first != schema => Err(Failure::Fault(format!(
                        "schema {id} is {:?} ({:?}) here, but an earlier schema record defines it as {:?} ({:?}): \
                         records of one id are identical, so this one is corrupt (a record whose opcode is corrupt?)",
                        printable(&schema.name),
                        printable(&schema.encoding),
                        printable(&first.name),
                        printable(&first.encoding)
                    ))),
                    Some(_) => Ok(()),
                    None => {
                        self.schemas.insert(id, schema);
                        Ok(())
                    }
                }
            }
            op::CHANNEL => {
                let id = fields.u16("id")?;
                let schema_id = fields.u16("schema id")?;
                let topic = fields.string("topic")?;
                let message_encoding = fields.string("message encoding")?;
                fields.skip_prefixed("metadata")?;
                if let Some((_, first_topic)) = self.channels.get(&id) {
                    let first = self.channel_records.get(&id);
                    if *first_topic != topic || first != Some(&(schema_id, message_encoding.clone())) {
                        return Err(Failure::Fault(format!(
                            "channel {id} is topic {:?} (schema {schema_id}, {:?}) here, but an earlier channel record \
                             defines it as {:?}{}: records of one id are identical, so this one is corrupt (a record \
                             whose opcode is corrupt?)",
                            printable(&topic),
                            printable(&message_encoding),
                            printable(first_topic),
                            first.map_or_else(String::new, |(schema, encoding)| format!(
                                " (schema {schema}, {:?})",
                                printable(encoding)
                            ))
                        )));
                    }
                    return Ok(());
                }
                self.channel_records.insert(id, (schema_id, message_encoding.clone()));
                let schema = match schema_id {
                    0 => SchemaInfo { name: String::new(), encoding: String::new() },
                    schema_id => match self.schemas.get(&schema_id) {
                        Some(schema) => schema.clone(),
                        None => {
                            return Err(Failure::Fault(format!(
                                "channel {id} ({topic:?}) refers to schema {schema_id}, which no earlier schema \
                                 record defines"
                            )));
                        }
                    },
                };
                let key = ChannelKey {
                    topic: topic.clone(),
                    schema_name: schema.name,
                    schema_encoding: schema.encoding,
                    message_encoding,
                };
                let index = visitor.channel(key, at);
                self.channels.insert(id, (index, topic));
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// A message index record after a chunk: how many messages of one channel the chunk holds.
    fn message_index(&mut self, fields: &mut Fields<'_, Source>, at: u64) -> std::result::Result<(), Fault> {
        let channel = fields.u16("channel id")?;
        let len = fields.u32("records' length")?;
        let len = fields.check_length(u64::from(len), "records")?;
        if len % 16 != 0 {
            return Err(format!("its records are {len} bytes long, not a multiple of their 16 bytes"));
        }
        fields.skip(len, "records")?;
        match &mut self.chunk {
            Some(chunk) => {
                if chunk.indexed.insert(channel, (len / 16, at)).is_some() {
                    return Err(format!("a second message index for channel {channel} after the same chunk"));
                }
                Ok(())
            }
            // Message indexes come right after their chunk: one after any other record is a
            // record whose opcode is corrupt (a message's, whose message would be lost).
            None => Err("a message index record that follows no chunk (message indexes come right after their \
                         chunk): the record's opcode is corrupt (a message's?)"
                .to_owned()),
        }
    }

    /// A chunk index record of the summary.
    fn chunk_index(&mut self, fields: &mut Fields<'_, Source>, at: u64) -> std::result::Result<(), Fault> {
        let _start = fields.u64("message start time")?;
        let _end = fields.u64("message end time")?;
        let chunk_offset = fields.u64("chunk start offset")?;
        let chunk_length = fields.u64("chunk length")?;
        self.chunk_indexes.push(ChunkIndex { at, chunk_offset, chunk_length });
        Ok(())
    }

    /// A summary offset record: where a group of summary records of one opcode starts.
    fn summary_offset(&mut self, fields: &mut Fields<'_, Source>, at: u64) -> std::result::Result<(), Fault> {
        let [group] = fields.array::<1>("group opcode")?;
        let start = fields.u64("group start")?;
        let length = fields.u64("group length")?;
        // Writers list empty groups too (length 0, no record at their start).
        if length > 0 && self.summary_offsets.len() < MAX_SUMMARY_KEPT {
            self.summary_offsets.push((at, group, start));
        }
        Ok(())
    }

    /// The statistics record of the summary.
    fn statistics(&mut self, fields: &mut Fields<'_, Source>, at: u64) -> std::result::Result<(), Fault> {
        let message_count = fields.u64("message count")?;
        let _schema_count = fields.u16("schema count")?;
        let _channel_count = fields.u32("channel count")?;
        let _attachment_count = fields.u32("attachment count")?;
        let _metadata_count = fields.u32("metadata count")?;
        let chunk_count = fields.u32("chunk count")?;
        let _start = fields.u64("message start time")?;
        let _end = fields.u64("message end time")?;
        let len = fields.u32("channel message counts' length")?;
        let len = fields.check_length(u64::from(len), "channel message counts")?;
        if len % 10 != 0 {
            return Err(format!("its channel message counts are {len} bytes long, not a multiple of their 10 bytes"));
        }
        let mut channel_message_counts = HashMap::new();
        for _ in 0..len / 10 {
            let channel = fields.u16("channel id")?;
            let count = fields.u64("message count")?;
            if channel_message_counts.insert(channel, count).is_some() {
                return Err(format!("its channel message counts name channel {channel} twice"));
            }
        }
        self.statistics = Some((at, Statistics { message_count, chunk_count, channel_message_counts }));
        Ok(())
    }

    /// A record of an unknown opcode in the data section: skipped (the format reserves opcodes
    /// for new records and extensions), unless its bytes are a message's or a chunk's (a record
    /// whose opcode is corrupt), or its opcode is 0, which no record has.
    fn unknown(&mut self, fields: &mut Fields<'_, Source>, at: u64, opcode: u8) -> std::result::Result<(), Fault> {
        if self.unknown.len() < MAX_UNKNOWN_KEPT {
            self.unknown.push((at, opcode));
        }
        if opcode == 0 {
            return Err("a record of opcode 0x00, which no MCAP record has (the format's and its extensions' are \
                        0x01 to 0xff): the record's opcode is corrupt"
                .to_owned());
        }
        let body_len = fields.left;
        let mut head = [0u8; UNKNOWN_HEAD];
        let head = &mut head[..(body_len as usize).min(UNKNOWN_HEAD)];
        fields.reader.read_exact(head).map_err(|e| fields.context.describe(&e))?;
        fields.left -= head.len() as u64;
        let u32_at = |at: usize| u32::from_le_bytes(head[at..at + 4].try_into().expect("4 bytes"));
        let u64_at = |at: usize| u64::from_le_bytes(head[at..at + 8].try_into().expect("8 bytes"));
        if body_len >= MESSAGE_HEAD {
            // A message: channel id, sequence, log and publish times, then the data.
            let channel = u16::from_le_bytes([head[0], head[1]]);
            if let Some((_, topic)) = self.channels.get(&channel) {
                return Err(format!(
                    "a record of unknown opcode {opcode:#04x} reads as a message on channel {channel} ({}): the \
                     message's opcode is corrupt, and it would be lost",
                    printable(topic)
                ));
            }
        }
        if body_len < CHUNK_FIXED + 8 {
            return Ok(());
        }
        let (start, end, uncompressed_size) = (u64_at(0), u64_at(8), u64_at(16));
        let compression_len = u32_at(28) as usize;
        if compression_len > 8 || (head.len() as u64) < CHUNK_FIXED + compression_len as u64 + 8 {
            return Ok(());
        }
        let compression = &head[CHUNK_FIXED as usize..CHUNK_FIXED as usize + compression_len];
        let compressed_size = u64_at(CHUNK_FIXED as usize + compression_len);
        let known = matches!(compression, b"" | b"zstd" | b"lz4");
        if known
            && start <= end
            && compressed_size == body_len - (CHUNK_FIXED + compression_len as u64 + 8)
            && (!compression.is_empty() || compressed_size == uncompressed_size)
        {
            return Err(format!(
                "a record of unknown opcode {opcode:#04x} holds a chunk ({} compression, {compressed_size} bytes of \
                 records, {uncompressed_size} decompressed): the chunk's opcode is corrupt, and its messages would be \
                 lost",
                if compression.is_empty() {
                    "no".to_owned()
                } else {
                    String::from_utf8_lossy(compression).into_owned()
                }
            ));
        }
        Ok(())
    }
}
