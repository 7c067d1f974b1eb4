//! rosbag2's sqlite3 storage (`.db3`): the `topics` and `messages` tables, read with `rusqlite`
//! (SQLite compiled in, the `bundled` feature, so no system library is needed).
//!
//! Only four columns of each table are read, the ones every rosbag2 version has (Foxy to
//! Jazzy): `topics(id, name, type, serialization_format)` and `messages(id, topic_id,
//! timestamp, data)`. Messages come in row order (`id`, the insertion order); the poses are
//! sorted by time afterwards. The blob of a message is borrowed from SQLite, not copied, and
//! read only for topics whose poses are read: for the others SQLite is not asked for the column,
//! so their (large) blobs stay on disk. The row id stands in for the byte offset in errors.
//!
//! The database is opened read-only. SQLite checks its own file structure, so a corrupt or
//! truncated file is an SQLite error ("database disk image is malformed"), reported with the
//! file and, when it arises while stepping through messages, the last row read.

use std::collections::HashMap;
use std::path::Path;

use rusqlite::types::ValueRef;
use rusqlite::{Connection, OpenFlags};

use crate::compression::MAX_MESSAGE_BYTES;
use crate::error::{IoError, Result};
use crate::mcap_records::{At, ChannelKey, MessageHeader, Visitor};
use crate::printable::one_line;

/// The first 16 bytes of every SQLite 3 database.
const MAGIC: &[u8; 16] = b"SQLite format 3\0";

/// Checks the 100-byte database header: the magic string, and a file as long as the header
/// says (SQLite itself reads a cut file up to the cut without a word when the missing pages
/// are not visited).
fn check_header(file: &Path, shown: &Path) -> Result<()> {
    use std::io::Read;

    let error = |message: String| IoError::Sqlite { path: shown.to_path_buf(), row: None, message };
    let open_error = |error| IoError::Open { path: shown.to_path_buf(), error };
    let mut handle = std::fs::File::open(file).map_err(open_error)?;
    let len = handle.metadata().map_err(open_error)?.len();
    let mut header = [0u8; 100];
    let read = handle.by_ref().take(100).read(&mut header).map_err(open_error)?;
    if read < MAGIC.len() || &header[..16] != MAGIC {
        return Err(error(format!(
            "not an SQLite database: it does not start with \"SQLite format 3\"; the file is {len} bytes long"
        )));
    }
    if len < 100 {
        return Err(error(format!(
            "the file is {len} bytes long, shorter than the 100-byte SQLite header: it is truncated"
        )));
    }
    let be32 = |at: usize| u32::from_be_bytes(header[at..at + 4].try_into().expect("4 bytes"));
    let page_size = match u16::from_be_bytes([header[16], header[17]]) {
        1 => 65536,
        size => u64::from(size),
    };
    let pages = u64::from(be32(28));
    // The page count is valid when the change counter matches "version-valid-for"; a database
    // with a write-ahead log may keep pages in the log instead.
    let mut wal = shown.as_os_str().to_owned();
    wal.push("-wal");
    if be32(24) == be32(92) && pages > 0 && !Path::new(&wal).exists() && len < pages * page_size {
        return Err(error(format!(
            "the file is {len} bytes long, but its header says {pages} pages of {page_size} bytes ({} bytes): it is \
             truncated",
            pages * page_size
        )));
    }
    Ok(())
}

/// The rosbag2 sqlite3 file `file` opened read-only, its header checked; errors name `shown`
/// (the file as the user knows it: the compressed file, for a decompressed copy).
///
/// A `copy` (a decompressed copy, private to this process) is opened immutable: SQLite then
/// locks nothing and looks for no journal or write-ahead log beside it, so it creates no `-shm`
/// file there and keeps reading after the copy's name is removed.
pub(crate) fn open(file: &Path, shown: &Path, copy: bool) -> Result<Connection> {
    check_header(file, shown)?;
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let opened = match file.to_str().filter(|_| copy) {
        // A URI's path ends at `?` or `#`, and `%` starts an escape.
        Some(path) => Connection::open_with_flags(
            format!("file:{}?immutable=1", path.replace('%', "%25").replace('?', "%3f").replace('#', "%23")),
            flags | OpenFlags::SQLITE_OPEN_URI,
        ),
        None => Connection::open_with_flags(file, flags),
    };
    opened.map_err(|e| IoError::Sqlite {
        path: shown.to_path_buf(),
        row: None,
        message: format!("SQLite cannot open the database: {}", one_line(&e)),
    })
}

/// Walks the messages of the rosbag2 sqlite3 database `db` (see [`open`]), reporting topics (as
/// channels) and messages to `visitor`; errors name `shown`.
pub(crate) fn walk(db: &Connection, shown: &Path, visitor: &mut impl Visitor) -> Result<()> {
    let error = |row: Option<i64>, message: String| IoError::Sqlite { path: shown.to_path_buf(), row, message };
    let sql = |row: Option<i64>, what: &'static str| {
        move |e: rusqlite::Error| error(row, format!("{what}: {}", one_line(&e)))
    };

    let mut topics: HashMap<i64, usize> = HashMap::new();
    let mut decoded: Vec<i64> = Vec::new();
    {
        let mut statement = db
            .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
            .map_err(sql(None, "not a rosbag2 sqlite3 file: cannot read its topics table"))?;
        let mut rows = statement.query([]).map_err(sql(None, "cannot read the topics table"))?;
        while let Some(row) = rows.next().map_err(sql(None, "cannot read the topics table"))? {
            let text = |index: usize, column: &str| -> Result<String> {
                match row.get_ref(index) {
                    Ok(ValueRef::Text(bytes)) => std::str::from_utf8(bytes)
                        .map(str::to_owned)
                        .map_err(|_| error(None, format!("the topics table's {column} is not UTF-8"))),
                    Ok(other) => {
                        Err(error(None, format!("the topics table's {column} is {:?}, not text", other.data_type())))
                    }
                    Err(e) => Err(error(None, format!("cannot read the topics table's {column}: {}", one_line(&e)))),
                }
            };
            let id = match row.get_ref(0) {
                Ok(ValueRef::Integer(id)) if id >= 0 => id,
                _ => {
                    return Err(error(
                        None,
                        "the topics table has an id that is not a non-negative integer".to_owned(),
                    ));
                }
            };
            let key = ChannelKey {
                topic: text(1, "name")?,
                schema_name: text(2, "type")?,
                schema_encoding: "ros2msg".to_owned(),
                message_encoding: text(3, "serialization_format")?,
            };
            let channel = visitor.channel(key, At { offset: id as u64, in_chunk: None });
            if visitor.decodes(channel) {
                decoded.push(id);
            }
            topics.insert(id, channel);
        }
    }

    // The data column only for the topics decoded, and only up to the size of a message (its
    // length instead); NULL (never read from disk) for the others.
    let wanted = decoded.iter().map(i64::to_string).collect::<Vec<_>>().join(",");
    let query = format!(
        "SELECT id, topic_id, timestamp, CASE WHEN topic_id IN ({wanted}) THEN \
         CASE WHEN length(data) <= {MAX_MESSAGE_BYTES} THEN data ELSE length(data) END END FROM messages ORDER BY id"
    );
    let mut statement =
        db.prepare(&query).map_err(sql(None, "not a rosbag2 sqlite3 file: cannot read its messages table"))?;
    let mut rows = statement.query([]).map_err(sql(None, "cannot read the messages table"))?;
    let mut last_row = None;
    loop {
        let row = match rows.next() {
            Ok(Some(row)) => row,
            Ok(None) => return Ok(()),
            Err(e) => {
                let after = last_row.map_or(String::new(), |row| format!(" after row {row}"));
                return Err(error(last_row, format!("cannot read the messages table{after}: {}", one_line(&e))));
            }
        };
        let integer = |index: usize| match row.get_ref(index) {
            Ok(ValueRef::Integer(value)) => Some(value),
            _ => None,
        };
        let Some(id) = integer(0).filter(|&id| id >= 0) else {
            return Err(error(last_row, "a message row whose id is not a non-negative integer".to_owned()));
        };
        // Ids are the table's rowid: a valid database gives them in increasing order. Out of order,
        // its b-tree is corrupt, and SQLite's walk of it may pass over rows without a word.
        if let Some(last) = last_row.filter(|&last| id <= last) {
            return Err(error(
                Some(id),
                format!(
                    "the messages table gives row {id} after row {last}: its b-tree is corrupt (rows out of order)"
                ),
            ));
        }
        last_row = Some(id);
        let Some(topic_id) = integer(1) else {
            return Err(error(Some(id), "the message's topic_id is not an integer".to_owned()));
        };
        let Some(&channel) = topics.get(&topic_id) else {
            return Err(error(
                Some(id),
                format!("the message is on topic {topic_id}, which the topics table does not hold"),
            ));
        };
        let timestamp = match integer(2).map(u64::try_from) {
            Some(Ok(timestamp)) => timestamp,
            Some(Err(_)) => return Err(error(Some(id), "the message's timestamp is negative".to_owned())),
            None => return Err(error(Some(id), "the message's timestamp is not an integer".to_owned())),
        };
        let data = match row.get_ref(3) {
            Ok(ValueRef::Blob(data)) => data,
            Ok(ValueRef::Null) if !decoded.contains(&topic_id) => &[],
            Ok(ValueRef::Integer(len)) if decoded.contains(&topic_id) => {
                return Err(error(
                    Some(id),
                    format!(
                        "the message is {len} bytes long, over the limit of {} MiB for a pose message",
                        MAX_MESSAGE_BYTES >> 20
                    ),
                ));
            }
            Ok(other) => {
                return Err(error(Some(id), format!("the message's data is {:?}, not a blob", other.data_type())));
            }
            Err(e) => return Err(error(Some(id), format!("cannot read the message's data: {}", one_line(&e)))),
        };
        let header = MessageHeader { log_time: timestamp, publish_time: timestamp };
        visitor.message(channel, header, data, At { offset: id as u64, in_chunk: None })?;
    }
}
