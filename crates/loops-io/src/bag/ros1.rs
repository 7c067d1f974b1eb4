//! ROS 1 bags, format 2.0: the records, walked by hand; chunks decompressed (none, bz2, lz4)
//! one at a time.
//!
//! A bag is `#ROSBAG V2.0\n`, then records: a `u32` header length, the header (fields `u32
//! length, name=value`; `op` says the record's kind), a `u32` data length, the data. The bag
//! header (op 3) comes first and says where the index starts; then chunks (op 5: compressed
//! connection (op 7) and message data (op 2) records), each followed by its index data records
//! (op 4: the time and offset of every message of one connection in the chunk); then the index:
//! connection records and chunk info records (op 6: per chunk, the message count of each
//! connection). The file is walked from the start, so every record has an offset to name in
//! errors; the index records are checked for their declared sizes and otherwise skipped, since
//! the walk sees every message. A bag whose index was never written (a recording that died:
//! the bag header's index offset is 0) is read as far as its records are whole.
//!
//! Why by hand: the `rosbag` crate (0.6) reads this format, but maps the file into memory
//! (undefined behaviour if the file changes while mapped, which our `unsafe_code = "deny"`
//! rules out for our own code), panics on index records whose data does not fit their count,
//! pre-allocates a chunk's declared size (up to 4 GiB) before decompressing, links the C `lz4`
//! library, and reports errors without the offset of the record at fault. The format is small
//! (six record kinds of a few fixed fields), so a walker of our own costs less than working
//! around those, and gives errors of the same shape as the MCAP reader's.
//!
//! Every length is checked against what is left of its container (the file, or the
//! decompressed chunk) before anything is read or allocated. A chunk is decompressed as a
//! stream and its records read one at a time: memory holds one record header (at most
//! [`MAX_HEADER_BYTES`]) and one message of a topic decoded (at most 64 MiB), never the chunk,
//! whatever size it declares (a `u32`: at most 4 GiB); the messages of other topics are skipped.
//! A chunk must decompress to exactly the size it declares.

use std::collections::HashMap;
use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::Path;

use crate::compression::{ChunkCompression, MAX_MESSAGE_BYTES, chunk_decoder};
use crate::error::{IoError, Result};
use crate::mcap_records::{At, ChannelKey, ChunkCount, MessageHeader, Visitor, open_records};
use crate::printable::one_line;

/// The first line of a bag of format 2.0.
const VERSION: &[u8; 13] = b"#ROSBAG V2.0\n";

/// Largest record header read: 1 MiB (a header holds a few short fields: op, conn, time,
/// topic, compression, size).
const MAX_HEADER_BYTES: u64 = 1 << 20;

/// Record kinds (`op`).
mod op {
    pub(super) const MESSAGE_DATA: u8 = 0x02;
    pub(super) const BAG_HEADER: u8 = 0x03;
    pub(super) const INDEX_DATA: u8 = 0x04;
    pub(super) const CHUNK: u8 = 0x05;
    pub(super) const CHUNK_INFO: u8 = 0x06;
    pub(super) const CONNECTION: u8 = 0x07;
}

fn record_name(op: u8) -> String {
    match op {
        op::MESSAGE_DATA => "message data".into(),
        op::BAG_HEADER => "bag header".into(),
        op::INDEX_DATA => "index data".into(),
        op::CHUNK => "chunk".into(),
        op::CHUNK_INFO => "chunk info".into(),
        op::CONNECTION => "connection".into(),
        other => format!("unknown (op 0x{other:02x})"),
    }
}

/// The fields of a record header this reader uses (a header may hold others; they are
/// ignored, as the format allows).
#[derive(Debug, Default, Clone)]
struct Fields {
    op: Option<u8>,
    conn: Option<u32>,
    /// `time`, as nanoseconds.
    time_ns: Option<u64>,
    index_pos: Option<u64>,
    compression: Option<ChunkCompression>,
    size: Option<u32>,
    /// `topic`, as a byte range of the header.
    topic: Option<(usize, usize)>,
    ver: Option<u32>,
    count: Option<u32>,
}

/// The `name=value` fields of a record header or connection header, each `u32 length` first.
fn header_fields(bytes: &[u8]) -> impl Iterator<Item = std::result::Result<(&str, usize, &[u8]), String>> {
    let mut pos = 0usize;
    std::iter::from_fn(move || {
        if pos >= bytes.len() {
            return None;
        }
        let result = (|| {
            let len_bytes = bytes
                .get(pos..pos + 4)
                .ok_or_else(|| format!("a field length at byte {pos} is cut short by the end of the header"))?;
            let len = u32::from_le_bytes(len_bytes.try_into().expect("4 bytes")) as usize;
            let start = pos + 4;
            let field = start
                .checked_add(len)
                .and_then(|end| bytes.get(start..end))
                .ok_or_else(|| format!("the field at byte {pos} is {len} bytes long, past the end of the header"))?;
            let equals = field
                .iter()
                .position(|&b| b == b'=')
                .ok_or_else(|| format!("the field at byte {pos} has no '=' between name and value"))?;
            let name = std::str::from_utf8(&field[..equals])
                .map_err(|_| format!("the name of the field at byte {pos} is not UTF-8"))?;
            pos = start + len;
            Ok((name, start + equals + 1, &field[equals + 1..]))
        })();
        if result.is_err() {
            pos = bytes.len();
        }
        Some(result)
    })
}

/// A fixed-width little-endian field.
fn fixed<const N: usize>(name: &str, value: &[u8]) -> std::result::Result<[u8; N], String> {
    value.try_into().map_err(|_| format!("the field {name} is {} bytes long, not {N}", value.len()))
}

fn parse_header(bytes: &[u8]) -> std::result::Result<Fields, String> {
    let mut out = Fields::default();
    for field in header_fields(bytes) {
        let (name, start, value) = field?;
        match name {
            "op" => out.op = Some(fixed::<1>(name, value)?[0]),
            "conn" => out.conn = Some(u32::from_le_bytes(fixed(name, value)?)),
            "ver" => out.ver = Some(u32::from_le_bytes(fixed(name, value)?)),
            "count" => out.count = Some(u32::from_le_bytes(fixed(name, value)?)),
            "size" => out.size = Some(u32::from_le_bytes(fixed(name, value)?)),
            "index_pos" => out.index_pos = Some(u64::from_le_bytes(fixed(name, value)?)),
            "time" => {
                let time: [u8; 8] = fixed(name, value)?;
                let sec = u32::from_le_bytes(time[..4].try_into().expect("4 bytes"));
                let nsec = u32::from_le_bytes(time[4..].try_into().expect("4 bytes"));
                crate::pose_type::check_nanoseconds("the field time", i64::from(nsec))?;
                out.time_ns = Some(u64::from(sec) * 1_000_000_000 + u64::from(nsec));
            }
            "compression" => {
                out.compression = Some(match value {
                    b"none" => ChunkCompression::None,
                    b"bz2" => ChunkCompression::Bz2,
                    b"lz4" => ChunkCompression::Lz4,
                    other => {
                        return Err(format!(
                            "unknown chunk compression {:?}: expected none, bz2 or lz4",
                            String::from_utf8_lossy(other)
                        ));
                    }
                })
            }
            "topic" => out.topic = Some((start, start + value.len())),
            _ => {}
        }
    }
    Ok(out)
}

/// Walks the records of the ROS 1 bag at `path`, reporting connections (as channels) and
/// messages to `visitor`.
pub(crate) fn walk(path: &Path, visitor: &mut impl Visitor) -> Result<()> {
    let (reader, len) = open_records(path)?;
    let mut walker = Walker {
        reader,
        len,
        records: Records { path, connections: HashMap::new(), header: Vec::new(), data: Vec::new(), chunk: None },
    };
    walker.run(visitor)
}

#[derive(Debug)]
struct Walker<'p> {
    reader: BufReader<File>,
    /// The file's length in bytes.
    len: u64,
    records: Records<'p>,
}

/// What the records need, apart from the file: the connections seen, and reused buffers for a
/// record's header and data.
#[derive(Debug)]
struct Records<'p> {
    path: &'p Path,
    /// Connection id to the visitor's channel.
    connections: HashMap<u32, usize>,
    header: Vec<u8>,
    data: Vec<u8>,
    /// The last chunk walked and its messages per connection, until its index data records
    /// have been checked.
    chunk: Option<ChunkCount<u32>>,
}

/// `len` bytes of `reader` into `buffer` (cleared first).
fn read_into(reader: &mut impl Read, buffer: &mut Vec<u8>, len: u64) -> io::Result<()> {
    buffer.clear();
    buffer.resize(len as usize, 0);
    reader.read_exact(buffer)
}

/// `len` bytes of `reader`, dropped.
fn skip(reader: &mut impl Read, len: u64) -> io::Result<()> {
    let copied = io::copy(&mut reader.take(len), &mut io::sink())?;
    if copied < len {
        return Err(io::Error::new(io::ErrorKind::UnexpectedEof, format!("{copied} of {len} bytes")));
    }
    Ok(())
}

fn read_u32(reader: &mut impl Read) -> io::Result<u32> {
    let mut bytes = [0u8; 4];
    reader.read_exact(&mut bytes)?;
    Ok(u32::from_le_bytes(bytes))
}

impl Walker<'_> {
    fn error(&self, offset: u64, message: impl Into<String>) -> IoError {
        self.records.error(offset, message)
    }

    fn read_error(&self, offset: u64, error: &io::Error) -> IoError {
        self.error(offset, format!("cannot read the file: {}", one_line(error)))
    }

    fn run(&mut self, visitor: &mut impl Visitor) -> Result<()> {
        let mut version = [0u8; 13];
        let start = self.reader.read_exact(&mut version);
        if start.is_err() || &version != VERSION {
            let what = if version.starts_with(b"#ROSBAG V") {
                let line = version.split(|&b| b == b'\n').next().unwrap_or(&version);
                format!(
                    "a ROS bag of format {:?}, which this crate does not read: it reads format 2.0 (#ROSBAG V2.0)",
                    String::from_utf8_lossy(&line[9..])
                )
            } else {
                format!("not a ROS 1 bag: it does not start with \"#ROSBAG V2.0\"; the file is {} bytes long", self.len)
            };
            return Err(self.error(0, what));
        }
        let mut pos = VERSION.len() as u64;
        let mut index_pos: Option<u64> = None;
        let mut index_found = false;
        while pos < self.len {
            let at = pos;
            let left = self.len - pos;
            if left < 4 {
                return Err(self.error(at, "the file ends in the middle of a record's header length: it is truncated"));
            }
            let header_len = u64::from(read_u32(&mut self.reader).map_err(|e| self.read_error(at, &e))?);
            if header_len > left - 4 {
                return Err(self.error(
                    at,
                    format!(
                        "the record header is {header_len} bytes long, but the file has {} bytes left: it is truncated",
                        left - 4
                    ),
                ));
            }
            if header_len > MAX_HEADER_BYTES {
                return Err(self.error(
                    at,
                    format!(
                        "the record header is {header_len} bytes long, over the limit of {} MiB for a header: the \
                         file is corrupt",
                        MAX_HEADER_BYTES >> 20
                    ),
                ));
            }
            read_into(&mut self.reader, &mut self.records.header, header_len).map_err(|e| self.read_error(at, &e))?;
            let fields = parse_header(&self.records.header)
                .map_err(|message| self.error(at, format!("the record header does not parse: {message}")))?;
            let Some(op) = fields.op else {
                return Err(self.error(at, "the record header has no op field"));
            };
            let left = left - 4 - header_len;
            if left < 4 {
                return Err(self.error(
                    at,
                    format!("the file ends before the data length of the {} record: it is truncated", record_name(op)),
                ));
            }
            let data_len = u64::from(read_u32(&mut self.reader).map_err(|e| self.read_error(at, &e))?);
            if data_len > left - 4 {
                return Err(self.error(
                    at,
                    format!(
                        "the {} record's data is {data_len} bytes long, but the file has {} bytes left: it is truncated",
                        record_name(op),
                        left - 4
                    ),
                ));
            }
            if index_pos.is_none() {
                if op != op::BAG_HEADER {
                    return Err(
                        self.error(at, format!("the first record is a {} record, not the bag header", record_name(op)))
                    );
                }
                let Some(declared) = fields.index_pos else {
                    return Err(self.error(at, "the bag header has no index_pos field"));
                };
                index_pos = Some(declared);
                skip(&mut self.reader, data_len).map_err(|e| self.read_error(at, &e))?;
                pos = at + 8 + header_len + data_len;
                continue;
            }
            if Some(at) == index_pos {
                index_found = true;
            }
            if op != op::INDEX_DATA {
                self.check_chunk_messages()?;
            }
            match op {
                op::CHUNK => self.chunk(at, &fields, data_len, visitor)?,
                op::CONNECTION | op::MESSAGE_DATA => {
                    let at = At { offset: at, in_chunk: None };
                    self.records.record(op, &fields, &mut self.reader, data_len, at, visitor).map_err(|failure| {
                        failure.into_error(&self.records, at, |e| format!("cannot read the file: {}", one_line(e)))
                    })?;
                }
                op::INDEX_DATA | op::CHUNK_INFO => {
                    let (entry, what) =
                        if op == op::INDEX_DATA { (12, "time and offset") } else { (8, "connection and count") };
                    if fields.ver != Some(1) {
                        return Err(self
                            .error(at, format!("the {} record has version {:?}, not 1", record_name(op), fields.ver)));
                    }
                    let count = fields
                        .count
                        .ok_or_else(|| self.error(at, format!("the {} record has no count field", record_name(op))))?;
                    if u64::from(count) * entry != data_len {
                        return Err(self.error(
                            at,
                            format!(
                                "the {} record declares {count} entries ({what}, {entry} bytes each), but its data is {data_len} bytes",
                                record_name(op)
                            ),
                        ));
                    }
                    skip(&mut self.reader, data_len).map_err(|e| self.read_error(at, &e))?;
                    if op == op::INDEX_DATA
                        && let (Some(chunk), Some(conn)) = (&mut self.records.chunk, fields.conn)
                        && chunk.indexed.insert(conn, (u64::from(count), at)).is_some()
                    {
                        return Err(self.error(
                            at,
                            format!("a second index data record for connection {conn} after the same chunk"),
                        ));
                    }
                }
                op::BAG_HEADER => return Err(self.error(at, "a second bag header")),
                other => return Err(self.error(at, format!("a record of unknown kind (op 0x{other:02x})"))),
            }
            pos = at + 8 + header_len + data_len;
        }
        self.check_chunk_messages()?;
        match index_pos {
            None => Err(self.error(pos, "the file ends before its bag header: it is truncated")),
            Some(declared) if declared != 0 && declared >= self.len => Err(self.error(
                self.len,
                format!(
                    "the file ends before the index at offset {declared} that its bag header declares: it is truncated"
                ),
            )),
            Some(declared) if declared != 0 && !index_found => Err(self.error(
                declared,
                "no record starts at the index offset that the bag header declares: the file is corrupt",
            )),
            Some(_) => Ok(()),
        }
    }

    /// The index data records after the last chunk, checked against its messages: called at the
    /// first record that is not one, and at the end of the file. A message whose record is
    /// corrupt (its connection changed) would otherwise leave its topic without a word.
    fn check_chunk_messages(&mut self) -> Result<()> {
        let Some(chunk) = self.records.chunk.take() else { return Ok(()) };
        // None without index data: the recording stopped before writing it.
        let Some(m) = chunk.mismatch() else { return Ok(()) };
        Err(self.error(
            chunk.offset,
            format!(
                "the chunk holds {} messages on connection {}, but its index data (the record at offset {}) lists {}{}",
                m.read,
                m.key,
                m.index_at,
                m.declared,
                m.lost()
            ),
        ))
    }

    /// A chunk record at `at`, its data not read yet: decompressed as a stream, its records read
    /// one at a time.
    fn chunk(&mut self, at: u64, fields: &Fields, data_len: u64, visitor: &mut impl Visitor) -> Result<()> {
        let (Some(compression), Some(size)) = (fields.compression, fields.size) else {
            return Err(self.error(at, "the chunk record lacks its compression or size field"));
        };
        let size = u64::from(size);
        if compression == ChunkCompression::None && data_len != size {
            return Err(self.error(at, format!("the uncompressed chunk holds {data_len} bytes but declares {size}")));
        }
        let name = compression.name();
        let describe = |error: &io::Error| match error.kind() {
            io::ErrorKind::UnexpectedEof => {
                format!("the {name} chunk decompresses to fewer bytes than the {size} it declares")
            }
            _ => format!("the {name} chunk does not decompress: {}", one_line(error)),
        };
        self.records.chunk = Some(ChunkCount::new(at));
        let mut compressed = (&mut self.reader).take(data_len);
        // Buffered: headers and lengths are read a few bytes at a time.
        let mut chunk = BufReader::with_capacity(64 << 10, chunk_decoder(compression, &mut compressed));
        let records = &mut self.records;
        let path = records.path;
        let mut pos = 0u64;
        while pos < size {
            let inner = pos;
            let fail = |message: String| IoError::Ros1 {
                path: path.to_path_buf(),
                offset: at,
                message: format!("in the record at byte {inner} of this chunk: {message}"),
            };
            let left = size - pos;
            if left < 4 {
                return Err(fail("the chunk ends in the middle of the record's header length".into()));
            }
            let header_len = u64::from(read_u32(&mut chunk).map_err(|e| fail(describe(&e)))?);
            if header_len > left - 4 {
                return Err(fail(format!(
                    "the record header is {header_len} bytes long, past the end of the chunk ({size} bytes)"
                )));
            }
            if header_len > MAX_HEADER_BYTES {
                return Err(fail(format!(
                    "the record header is {header_len} bytes long, over the limit of {} MiB for a header",
                    MAX_HEADER_BYTES >> 20
                )));
            }
            read_into(&mut chunk, &mut records.header, header_len).map_err(|e| fail(describe(&e)))?;
            let fields = parse_header(&records.header)
                .map_err(|message| fail(format!("the record header does not parse: {message}")))?;
            let op = fields.op.ok_or_else(|| fail("the record header has no op field".into()))?;
            let left = left - 4 - header_len;
            if left < 4 {
                return Err(fail("the chunk ends in the middle of the record's data length".into()));
            }
            let data_len = u64::from(read_u32(&mut chunk).map_err(|e| fail(describe(&e)))?);
            if data_len > left - 4 {
                return Err(fail(format!(
                    "the {} record's data is {data_len} bytes long, past the end of the chunk ({size} bytes)",
                    record_name(op)
                )));
            }
            if !matches!(op, op::CONNECTION | op::MESSAGE_DATA) {
                return Err(fail(format!("a {} record inside a chunk", record_name(op))));
            }
            let record_at = At { offset: at, in_chunk: Some(inner) };
            records
                .record(op, &fields, &mut chunk, data_len, record_at, visitor)
                .map_err(|failure| failure.into_error(records, record_at, describe))?;
            pos += 8 + header_len + data_len;
        }
        let mut extra = [0u8; 1];
        match chunk.read(&mut extra) {
            Ok(0) => {}
            Ok(_) => {
                return Err(records
                    .error(at, format!("the {name} chunk decompresses to more bytes than the {size} it declares")));
            }
            Err(e) => return Err(records.error(at, describe(&e))),
        }
        drop(chunk);
        // What the decompressor did not read of the chunk's data.
        let unread = compressed.limit();
        skip(&mut self.reader, unread).map_err(|e| self.read_error(at, &e))
    }
}

/// Why a record failed: what is wrong with it, an I/O error reading its data, or an error
/// already complete (from the visitor).
#[derive(Debug)]
enum Failure {
    Fault(String),
    Read(io::Error),
    Error(Box<IoError>),
}

impl Failure {
    /// The error, located at `at`; `describe` says what a read error means where it happened.
    fn into_error(self, records: &Records<'_>, at: At, describe: impl Fn(&io::Error) -> String) -> IoError {
        let message = match self {
            Failure::Error(error) => return *error,
            Failure::Fault(message) => message,
            Failure::Read(error) => describe(&error),
        };
        let message = match at.in_chunk {
            Some(inner) => format!("in the record at byte {inner} of this chunk: {message}"),
            None => message,
        };
        records.error(at.offset, message)
    }
}

impl Records<'_> {
    fn error(&self, offset: u64, message: impl Into<String>) -> IoError {
        IoError::Ros1 { path: self.path.to_path_buf(), offset, message: message.into() }
    }

    /// A connection or message data record, at the top level or in a chunk, whose header
    /// `fields` are parsed (from `self.header`) and whose `data_len` bytes of data `reader` is
    /// at: read when needed (a connection, a message of a topic the visitor decodes), else
    /// skipped.
    fn record(
        &mut self,
        op: u8,
        fields: &Fields,
        reader: &mut impl Read,
        data_len: u64,
        at: At,
        visitor: &mut impl Visitor,
    ) -> std::result::Result<(), Failure> {
        let Some(conn) = fields.conn else {
            return Err(Failure::Fault(format!("the {} record has no conn field", record_name(op))));
        };
        if op == op::MESSAGE_DATA {
            let Some(&channel) = self.connections.get(&conn) else {
                return Err(Failure::Fault(format!(
                    "a message on connection {conn}, which no earlier connection record defines"
                )));
            };
            let Some(time_ns) = fields.time_ns else {
                return Err(Failure::Fault("the message data record has no time field".into()));
            };
            let header = MessageHeader { log_time: time_ns, publish_time: time_ns };
            if let Some(chunk) = &mut self.chunk
                && at.in_chunk.is_some()
            {
                *chunk.read.entry(conn).or_default() += 1;
            }
            let mut data = std::mem::take(&mut self.data);
            data.clear();
            if visitor.decodes(channel) {
                if data_len > MAX_MESSAGE_BYTES {
                    return Err(Failure::Fault(format!(
                        "the message on connection {conn} is {data_len} bytes long, over the limit of {} MiB for a \
                         pose message",
                        MAX_MESSAGE_BYTES >> 20
                    )));
                }
                read_into(reader, &mut data, data_len).map_err(Failure::Read)?;
            } else {
                skip(reader, data_len).map_err(Failure::Read)?;
            }
            let result = visitor.message(channel, header, &data, at);
            self.data = data;
            return result.map_err(|error| Failure::Error(Box::new(error)));
        }
        if data_len > MAX_MESSAGE_BYTES {
            return Err(Failure::Fault(format!(
                "the connection record's data is {data_len} bytes long, over the limit of {} MiB",
                MAX_MESSAGE_BYTES >> 20
            )));
        }
        let mut data = std::mem::take(&mut self.data);
        let result = read_into(reader, &mut data, data_len)
            .map_err(Failure::Read)
            .and_then(|()| self.connection(conn, fields, &data, at, visitor));
        self.data = data;
        result
    }

    /// A connection record: its topic (from the record header) and type (from its data).
    fn connection(
        &mut self,
        conn: u32,
        fields: &Fields,
        data: &[u8],
        at: At,
        visitor: &mut impl Visitor,
    ) -> std::result::Result<(), Failure> {
        if self.connections.contains_key(&conn) {
            return Ok(());
        }
        let topic = match fields.topic {
            Some((start, end)) => std::str::from_utf8(&self.header[start..end])
                .map_err(|_| Failure::Fault(format!("the topic of connection {conn} is not UTF-8")))?,
            None => return Err(Failure::Fault(format!("connection {conn} has no topic field"))),
        };
        let mut schema_name = None;
        for field in header_fields(data) {
            let (name, _, value) =
                field.map_err(|message| Failure::Fault(format!("the connection header does not parse: {message}")))?;
            if name == "type" {
                schema_name = Some(
                    std::str::from_utf8(value)
                        .map_err(|_| Failure::Fault(format!("the type of connection {conn} is not UTF-8")))?
                        .to_owned(),
                );
            }
        }
        let Some(schema_name) = schema_name else {
            return Err(Failure::Fault(format!(
                "the connection header of connection {conn} ({topic}) has no type field"
            )));
        };
        let key = ChannelKey {
            topic: topic.to_owned(),
            schema_name,
            schema_encoding: "ros1msg".to_owned(),
            message_encoding: "ros1".to_owned(),
        };
        let channel = visitor.channel(key, at);
        self.connections.insert(conn, channel);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(name: &str, value: &[u8]) -> Vec<u8> {
        let mut out = ((name.len() + 1 + value.len()) as u32).to_le_bytes().to_vec();
        out.extend(name.as_bytes());
        out.push(b'=');
        out.extend(value);
        out
    }

    #[test]
    fn headers_parse_and_bad_ones_say_why() {
        let mut header = field("op", &[2]);
        header.extend(field("conn", &7u32.to_le_bytes()));
        header.extend(field("time", &[1, 0, 0, 0, 2, 0, 0, 0]));
        header.extend(field("topic", b"/odom"));
        header.extend(field("other", b"x=y"));
        let fields = parse_header(&header).unwrap();
        assert_eq!((fields.op, fields.conn, fields.time_ns), (Some(2), Some(7), Some(1_000_000_002)));
        let (start, end) = fields.topic.unwrap();
        assert_eq!(&header[start..end], b"/odom");

        let error = parse_header(&field("conn", &[1, 2])).unwrap_err();
        assert_eq!(error, "the field conn is 2 bytes long, not 4");
        let error = parse_header(&[9, 0, 0, 0, b'a']).unwrap_err();
        assert!(error.contains("past the end of the header"), "{error}");
        let error = parse_header(&[1, 0, 0, 0, b'a']).unwrap_err();
        assert!(error.contains("no '='"), "{error}");
        assert!(parse_header(&[1, 0]).unwrap_err().contains("cut short"));
        let error = parse_header(&field("compression", b"zip")).unwrap_err();
        assert!(error.contains("unknown chunk compression \"zip\""), "{error}");
    }
}
