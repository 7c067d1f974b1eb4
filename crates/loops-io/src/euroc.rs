//! EuRoC MAV ground truth: `timestamp [ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z, ...`.

use std::io::BufRead;
use std::path::Path;

use crate::error::{IoError, Result};
use crate::table::{PoseTable, seconds_of_ns};
use crate::text::{self, Delimiter, Lines, Takes};

/// The columns a EuRoC line needs: time, position, quaternion.
const COLUMNS: usize = 8;

/// Reads a EuRoC ground-truth CSV: `timestamp [ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z` and any
/// further columns (velocities, biases), ignored: numbers, as many on every line as on the
/// first (two lines run together are an error, not one pose with extra columns).
///
/// The timestamp is integer nanoseconds, kept exactly in [`PoseTable::timestamps_ns`]; the
/// quaternion is `w` first in the file and stored `[x, y, z, w]` as everywhere else. The header
/// starts with `#` (a header without `#`, with no number in it, is skipped too). Fields are
/// separated by commas, optionally padded with spaces.
///
/// Time O(file size).
///
/// # Errors
/// - [`IoError::Open`] when the file cannot be read;
/// - [`IoError::Parse`] for a line with fewer than 8 columns or another count than the first
///   line's (naming the first column past the record), a timestamp that is not an integer, a
///   field that is not a finite number, or a further column that is not a number, naming line
///   and column;
/// - [`IoError::Empty`] without data lines.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-euroc.csv", std::process::id()));
/// std::fs::write(&path, "#timestamp, p_x, p_y, p_z, q_w, q_x, q_y, q_z\n1403715524912143104,1,2,3,1,0,0,0,0.5\n")?;
/// let table = loops_io::read_euroc(&path)?;
/// assert_eq!(table.timestamps_ns, Some(vec![1403715524912143104]));
/// assert_eq!(table.orientations_xyzw, Some(vec![[0.0, 0.0, 0.0, 1.0]]));
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_euroc(path: impl AsRef<Path>) -> Result<PoseTable> {
    let path = path.as_ref();
    parse_euroc(path, &mut text::open_lines(path)?)
}

/// The EuRoC poses in `lines`, the data lines of `path`.
pub(crate) fn parse_euroc(path: &Path, lines: &mut Lines<impl BufRead>) -> Result<PoseTable> {
    let mut table = PoseTable::empty(path, 3);
    let mut stamps_ns = Vec::new();
    let mut orientations = Vec::new();
    let delimiter = Delimiter::Char(',');
    let mut first = true;
    // The columns of the first data line, which every line has, and that line.
    let mut width: Option<(usize, usize)> = None;
    while let Some((line, content)) = lines.next_data()? {
        if std::mem::take(&mut first) && text::is_header(delimiter.split(content)) {
            continue;
        }
        let parse_error = |message: String| IoError::parse(path, line, message);
        let takes = width.map_or(Takes::AtLeast(COLUMNS), |(count, _)| Takes::Exactly(count));
        let fields = text::record(delimiter.split(content), takes, || match width {
            Some((_, first_line)) => format!(" as on line {first_line}"),
            None => " (timestamp [ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z)".to_owned(),
        })
        .map_err(parse_error)?;
        if let Some(&next) = fields.get(COLUMNS)
            && is_stamp_ns(next)
        {
            // A first line of further columns sets every line's count; but a further column
            // that is a timestamp starts a second record (a file of two lines run together).
            return Err(parse_error(format!(
                "column {} ({next:?}) is a timestamp in nanoseconds, not a further column: two records run together \
                 on one line?",
                COLUMNS + 1
            )));
        }
        width.get_or_insert((fields.len(), line));
        let stamp = fields[0];
        let stamp_ns: i64 = stamp
            .parse()
            .map_err(|_| parse_error(format!("column 1 ({stamp:?}) is not an integer timestamp in nanoseconds")))?;
        let mut values = [0.0; COLUMNS - 1];
        for (k, (value, field)) in values.iter_mut().zip(&fields[1..]).enumerate() {
            *value = text::parse_finite(field, k + 2).map_err(parse_error)?;
        }
        text::check_numbers(&fields[COLUMNS..], COLUMNS + 1).map_err(parse_error)?;
        let [x, y, z, qw, qx, qy, qz] = values;
        stamps_ns.push(stamp_ns);
        table.timestamps_s.push(seconds_of_ns(stamp_ns));
        table.positions.push([x, y, z]);
        orientations.push([qx, qy, qz, qw]);
        table.source_lines.push(line);
    }
    if table.is_empty() {
        return Err(IoError::Empty { path: path.to_path_buf() });
    }
    table.timestamps_ns = Some(stamps_ns);
    table.orientations_xyzw = Some(orientations);
    Ok(table)
}

/// Whether `field` is written as a EuRoC timestamp: an integer of 16 digits or more
/// (nanoseconds since 1970).
fn is_stamp_ns(field: &str) -> bool {
    field.len() >= 16 && field.bytes().all(|b| b.is_ascii_digit())
}

/// Whether `text` looks like EuRoC: a first data line of at least 8 comma-separated numbers, the
/// first an integer of 16 digits or more (nanoseconds since 1970).
pub(crate) fn looks_like_euroc(first_lines: &[String]) -> bool {
    first_lines.iter().find(|line| !text::is_header(Delimiter::Char(',').split(line))).is_some_and(|line| {
        let fields: Vec<&str> = Delimiter::Char(',').split(line).collect();
        fields.len() >= COLUMNS && is_stamp_ns(fields[0]) && fields.iter().all(|field| text::is_number(field))
    })
}
