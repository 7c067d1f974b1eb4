//! Walking the records of an MCAP file: schemas, channels and messages, at the top level and in
//! chunks, each with its byte offset.
//!
//! The top level is walked by hand, next to the `mcap` crate, for three reasons:
//! - every error names the byte offset of the record at fault and what is wrong with it (`the
//!   chunk record is 4096 bytes long, but the file has 100 bytes left: it is truncated`), and a
//!   message's offset is kept for the errors the core raises later (duplicate timestamps at a
//!   message); the crate's readers report `UnexpectedEof` or a parse error without the offset;
//! - records not needed (attachments, metadata, message indexes, the summary section) are
//!   skipped by seeking, never read: the crate's sans-I/O `LinearReader` has no skip and
//!   buffers each record whole before handing it over, and `MessageStream` / `Summary` want
//!   the whole file in memory or mapped;
//! - memory stays bounded: a chunk is read once, its buffers bounded by its declared size (and
//!   1 GiB), so a corrupt length cannot make the reader allocate without limit.
//!
//! The records themselves are parsed by the crate (`mcap::parse_record`), and the contents of a
//! chunk (decompression with zstd or lz4, CRC, the records inside) go through the crate's
//! `LinearReader`, one chunk at a time.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use mcap::records::{Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::error::{IoError, Result};

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
    pub(crate) channel_id: u16,
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

/// An `mcap` error with its causes, for a message.
fn describe(error: &mcap::McapError) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(cause) = source {
        text += &format!(": {cause}");
        source = cause.source();
    }
    text
}

/// Largest record in a chunk, and largest buffer for one: bounds what a corrupt length can make
/// the reader allocate.
const MAX_CHUNK_BUFFER: u64 = 1 << 30;

/// The bytes between records: opcode and length.
const RECORD_HEADER: u64 = 9;

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
    let mut walker = Walker { path, reader, len, schemas: HashMap::new(), channels: HashMap::new(), body: Vec::new() };
    walker.run(visitor)
}

/// A schema as a channel needs it.
#[derive(Debug, Clone)]
struct SchemaInfo {
    name: String,
    encoding: String,
}

#[derive(Debug)]
struct Walker<'p> {
    path: &'p Path,
    reader: BufReader<File>,
    /// The file's length in bytes.
    len: u64,
    schemas: HashMap<u16, SchemaInfo>,
    /// MCAP channel id to the visitor's index.
    channels: HashMap<u16, usize>,
    /// Reused buffer for record bodies.
    body: Vec<u8>,
}

impl Walker<'_> {
    fn error(&self, offset: u64, message: impl Into<String>) -> IoError {
        IoError::mcap(self.path, offset, message)
    }

    fn read_error(&self, offset: u64, error: std::io::Error) -> IoError {
        self.error(offset, format!("cannot read the file: {error}"))
    }

    fn run(&mut self, visitor: &mut impl Visitor) -> Result<()> {
        let mut magic = [0u8; 8];
        let start = self.reader.read_exact(&mut magic);
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
        let mut pos = 8u64;
        let mut in_summary = false;
        loop {
            if self.len - pos < RECORD_HEADER {
                let what = if pos == self.len { "ends" } else { "ends in the middle of a record header" };
                return Err(self.error(pos, format!("the file {what} before its footer: it is truncated")));
            }
            let mut head = [0u8; 9];
            self.reader.read_exact(&mut head).map_err(|e| self.read_error(pos, e))?;
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
            match opcode {
                op::FOOTER => return self.finish(body_start, body_len),
                op::DATA_END => in_summary = true,
                _ => {}
            }
            match opcode {
                op::SCHEMA | op::CHANNEL | op::MESSAGE if !in_summary => {
                    self.read_body(body_start, body_len)?;
                    let body = std::mem::take(&mut self.body);
                    let result = self.record(opcode, &body, At { offset: pos, in_chunk: None }, visitor);
                    self.body = body;
                    result?;
                }
                op::CHUNK if !in_summary => self.chunk(pos, body_len, visitor)?,
                _ => self.reader.seek_relative(body_len as i64).map_err(|e| self.read_error(pos, e))?,
            }
            pos = body_start + body_len;
        }
    }

    /// After the footer: the closing magic, and nothing after it.
    fn finish(&mut self, body_start: u64, body_len: u64) -> Result<()> {
        let magic_at = body_start + body_len;
        if self.len - magic_at < 8 {
            return Err(self.error(magic_at, "the file ends before the closing MCAP magic bytes: it is truncated"));
        }
        self.reader.seek_relative(body_len as i64).map_err(|e| self.read_error(magic_at, e))?;
        let mut magic = [0u8; 8];
        self.reader.read_exact(&mut magic).map_err(|e| self.read_error(magic_at, e))?;
        if magic != mcap::MAGIC {
            return Err(self.error(magic_at, "bad magic: the footer is not followed by the MCAP magic bytes"));
        }
        Ok(())
    }

    fn read_body(&mut self, offset: u64, len: u64) -> Result<()> {
        self.body.clear();
        self.body.resize(len as usize, 0);
        let Self { reader, body, .. } = self;
        reader.read_exact(body).map_err(|e| IoError::mcap(self.path, offset, format!("cannot read the file: {e}")))
    }

    /// A schema, channel or message record, at the top level or in a chunk.
    fn record(&mut self, opcode: u8, body: &[u8], at: At, visitor: &mut impl Visitor) -> Result<()> {
        let located = |message: String| match at.in_chunk {
            Some(inner) => format!("in the record at byte {inner} of this chunk: {message}"),
            None => message,
        };
        match opcode {
            op::MESSAGE => {
                let Some((head, data)) = body.split_first_chunk::<22>() else {
                    return Err(self.error(
                        at.offset,
                        located(format!(
                            "the message record is {} bytes long, shorter than its 22-byte header",
                            body.len()
                        )),
                    ));
                };
                let header = MessageHeader {
                    channel_id: u16::from_le_bytes([head[0], head[1]]),
                    log_time: u64::from_le_bytes(head[6..14].try_into().expect("8 bytes")),
                    publish_time: u64::from_le_bytes(head[14..22].try_into().expect("8 bytes")),
                };
                let Some(&channel) = self.channels.get(&header.channel_id) else {
                    return Err(self.error(
                        at.offset,
                        located(format!(
                            "a message on channel {}, which no earlier channel record defines",
                            header.channel_id
                        )),
                    ));
                };
                visitor.message(channel, header, data, at)
            }
            op::SCHEMA => {
                match mcap::parse_record(opcode, body) {
                    Ok(Record::Schema { header, .. }) => {
                        self.schemas
                            .entry(header.id)
                            .or_insert(SchemaInfo { name: header.name, encoding: header.encoding });
                        Ok(())
                    }
                    Ok(_) => unreachable!("a schema opcode parses as a schema"),
                    Err(error) => Err(self
                        .error(at.offset, located(format!("the schema record does not parse: {}", describe(&error))))),
                }
            }
            op::CHANNEL => {
                match mcap::parse_record(opcode, body) {
                    Ok(Record::Channel(channel)) => {
                        if self.channels.contains_key(&channel.id) {
                            return Ok(());
                        }
                        let schema = match channel.schema_id {
                            0 => SchemaInfo { name: String::new(), encoding: String::new() },
                            id => match self.schemas.get(&id) {
                                Some(schema) => schema.clone(),
                                None => {
                                    return Err(self.error(
                                    at.offset,
                                    located(format!(
                                        "channel {} ({:?}) refers to schema {id}, which no earlier schema record defines",
                                        channel.id, channel.topic
                                    )),
                                ));
                                }
                            },
                        };
                        let key = ChannelKey {
                            topic: channel.topic,
                            schema_name: schema.name,
                            schema_encoding: schema.encoding,
                            message_encoding: channel.message_encoding,
                        };
                        let index = visitor.channel(key, at);
                        self.channels.insert(channel.id, index);
                        Ok(())
                    }
                    Ok(_) => unreachable!("a channel opcode parses as a channel"),
                    Err(error) => Err(self
                        .error(at.offset, located(format!("the channel record does not parse: {}", describe(&error))))),
                }
            }
            _ => Ok(()),
        }
    }

    /// A chunk record at `offset`: decompressed (and its CRC checked) by the `mcap` crate's
    /// reader, one record at a time.
    fn chunk(&mut self, offset: u64, body_len: u64, visitor: &mut impl Visitor) -> Result<()> {
        let total = (RECORD_HEADER + body_len) as usize;
        self.read_body(offset + RECORD_HEADER, body_len)?;
        // The declared uncompressed size, to bound the buffers (bytes 16..24 of the header).
        let declared = self.body.get(16..24).map_or(0, |b| u64::from_le_bytes(b.try_into().expect("8 bytes")));
        let limit = declared.max(body_len).min(MAX_CHUNK_BUFFER) as usize;
        let mut reader = LinearReader::new_with_options(
            LinearReaderOptions::default()
                .with_skip_start_magic(true)
                .with_skip_end_magic(true)
                .with_validate_chunk_crcs(true)
                .with_record_length_limit(limit),
        );
        let buffer = reader.insert(total);
        buffer[0] = op::CHUNK;
        buffer[1..9].copy_from_slice(&body_len.to_le_bytes());
        buffer[9..].copy_from_slice(&self.body);
        reader.notify_read(total);
        let mut inner = 0u64;
        let mut at_end = false;
        loop {
            match reader.next_event() {
                None => return Ok(()),
                Some(Ok(LinearReadEvent::ReadRequest(_))) if !at_end => {
                    // The whole chunk is in: asking for more means it ended cleanly (the next
                    // record would start here) or it is inconsistent, which EOF tells apart.
                    at_end = true;
                    reader.notify_read(0);
                }
                Some(Ok(LinearReadEvent::ReadRequest(_))) => {
                    return Err(self.error(offset, "the chunk's records do not fit its length"));
                }
                Some(Ok(LinearReadEvent::Record { opcode, data })) => {
                    let at = At { offset, in_chunk: Some(inner) };
                    inner += RECORD_HEADER + data.len() as u64;
                    self.record(opcode, data, at, visitor)?;
                }
                Some(Err(error)) => {
                    let what = match error {
                        mcap::McapError::BadChunkCrc { .. } => "the chunk is corrupt",
                        mcap::McapError::UnexpectedEof | mcap::McapError::UnexpectedEoc => {
                            "the chunk ends in the middle of a record"
                        }
                        _ => "the chunk does not decode",
                    };
                    return Err(self.error(offset, format!("{what}: {}", describe(&error))));
                }
            }
        }
    }
}
