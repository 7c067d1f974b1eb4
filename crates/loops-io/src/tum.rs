//! The TUM RGB-D trajectory format: `timestamp tx ty tz qx qy qz qw` a line.

use std::io::BufRead;
use std::path::Path;

use crate::error::{IoError, Result};
use crate::table::PoseTable;
use crate::text::{self, Delimiter, Lines, Takes};

/// The columns of a TUM line, in order.
const COLUMNS: usize = 8;

/// Reads a trajectory in the TUM RGB-D format: one pose a line, `timestamp tx ty tz qx qy qz
/// qw` (seconds, metres, unit quaternion), fields separated by spaces or tabs (or commas).
///
/// Blank lines and `#` comment lines are skipped, and so is a first line of column names with
/// no number in it (`timestamp tx ty tz qx qy qz qw` without the `#`). `\n` and `\r\n` line
/// ends both work. The table is 3-D and keeps the quaternions as read, not normalised.
/// Timestamp order is checked by [`PoseTable::to_trajectory`], not here.
///
/// Time O(file size); the file is read into memory at once.
///
/// # Errors
/// - [`IoError::Open`] when the file cannot be read;
/// - [`IoError::Parse`] for a line with other than 8 columns (naming the first column past the
///   record: two lines run together are not read as one pose), or a field that is not a finite
///   number, naming the line and the column;
/// - [`IoError::Empty`] when there is no data line.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}.tum", std::process::id()));
/// std::fs::write(&path, "# timestamp tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.5\t2 0 0\t0 0 0 1\n")?;
/// let table = loops_io::read_tum(&path)?;
/// assert_eq!(table.positions, [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]);
/// assert_eq!(table.source_lines, [2, 3]);
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_tum(path: impl AsRef<Path>) -> Result<PoseTable> {
    let path = path.as_ref();
    parse_tum(path, &mut text::open_lines(path)?)
}

/// The TUM poses in `lines`, the data lines of `path`.
pub(crate) fn parse_tum(path: &Path, lines: &mut Lines<impl BufRead>) -> Result<PoseTable> {
    let mut table = PoseTable::empty(path, 3);
    let mut orientations_xyzw = Vec::new();
    let mut first = true;
    while let Some((line, content)) = lines.next_data()? {
        let delimiter = delimiter_of(content);
        if std::mem::take(&mut first) && text::is_header(delimiter.split(content)) {
            continue;
        }
        let [t, x, y, z, qx, qy, qz, qw] =
            parse_pose(delimiter, content).map_err(|message| IoError::parse(path, line, message))?;
        table.timestamps_s.push(t);
        table.positions.push([x, y, z]);
        orientations_xyzw.push([qx, qy, qz, qw]);
        table.source_lines.push(line);
    }
    if table.timestamps_s.is_empty() {
        return Err(IoError::Empty { path: path.to_path_buf() });
    }
    table.orientations_xyzw = Some(orientations_xyzw);
    Ok(table)
}

/// Commas when the line has one, else spaces and tabs.
fn delimiter_of(line: &str) -> Delimiter {
    if line.contains(',') { Delimiter::Char(',') } else { Delimiter::Whitespace }
}

/// The 8 numbers of a data line, or what is wrong with it.
fn parse_pose(delimiter: Delimiter, line: &str) -> Result<[f64; COLUMNS], String> {
    let mut values = [0.0; COLUMNS];
    // The numbers first: a line of words (a header of another tool) is named by its first word.
    for (column, (value, field)) in values.iter_mut().zip(delimiter.split(line)).enumerate() {
        *value = text::parse_finite(field, column + 1)?;
    }
    text::record(delimiter.split(line), Takes::Exactly(COLUMNS), || {
        " (timestamp tx ty tz qx qy qz qw)".to_owned()
    })
    .map_err(|message| {
        // KITTI lines: a 3×4 pose, after a time when there are 13 numbers.
        match delimiter.split(line).count() {
            count @ (12 | 13) => format!(
                "expected {COLUMNS} columns (timestamp tx ty tz qx qy qz qw), found {count}: a KITTI pose line? read \
                 the file as kitti (format=\"kitti\", --format kitti)"
            ),
            _ => message,
        }
    })?;
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<PoseTable> {
        parse_tum(Path::new("drive.tum"), &mut Lines::new(Path::new("drive.tum"), text.as_bytes()))
    }

    #[test]
    fn reads_poses_with_their_lines() {
        let table = parse("# c\n1 2 3 4 0 0 0 1\n\n2,5,6,7,0.1,0.2,0.3,0.9\r\n").unwrap();
        assert_eq!(table.timestamps_s, [1.0, 2.0]);
        assert_eq!(table.positions, [[2.0, 3.0, 4.0], [5.0, 6.0, 7.0]]);
        assert_eq!(table.orientations_xyzw, Some(vec![[0.0, 0.0, 0.0, 1.0], [0.1, 0.2, 0.3, 0.9]]));
        assert_eq!(table.source_lines, [2, 4]);
        assert_eq!(table.dim, 3);
    }

    #[test]
    fn errors_name_line_and_column() {
        let error = parse("1 2 3 4 0 0 0 1\n2 2 3\n").unwrap_err();
        assert_eq!(
            error.to_string(),
            r#"drive.tum line 2: expected 8 columns (timestamp tx ty tz qx qy qz qw), found 3: the line ends after column 3 ("3")"#
        );
        let error = parse("1 2 x 4 0 0 0 1\n").unwrap_err();
        assert_eq!(error.to_string(), r#"drive.tum line 1: column 3 ("x") is not a number"#);
        let error = parse("1 2 3 4 0 0 0 1\n2 2 3 4 0 0 0 1 9\n").unwrap_err();
        assert!(error.to_string().contains(r#"found 9: column 9 ("9") is past the end"#), "{error}");
        assert!(matches!(parse("# only\n\n").unwrap_err(), IoError::Empty { .. }));
    }

    #[test]
    fn only_the_first_data_line_may_be_a_header() {
        let table = parse("t x y z qx qy qz qw\n1 2 3 4 0 0 0 1\n").unwrap();
        assert_eq!(table.source_lines, [2]);
        let error = parse("1 2 3 4 0 0 0 1\nt x y z qx qy qz qw\n").unwrap_err();
        assert_eq!(error.line(), Some(2));
    }
}
