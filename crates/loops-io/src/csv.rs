//! Delimited position tables: `t,x,y` or `t,x,y,z`, with or without a header row.

use std::io::BufRead;
use std::path::Path;

use crate::error::{IoError, Result};
use crate::table::PoseTable;
use crate::text::{self, Delimiter, Lines, Takes};

/// Reads positions from a delimited text file: `t,x,y` (2-D) or `t,x,y,z` (3-D) a line, time
/// in seconds.
///
/// - The delimiter is the first of `,` `;` tab found in the first line; with none of them,
///   runs of spaces.
/// - A first line with no number in it is a header. A header naming columns `t` (or `time`,
///   `timestamp`), `x`, `y` and optionally `z` (any case, any order, other columns ignored)
///   maps them by name; a header naming none of them is skipped and the columns are taken in
///   order, as without a header: 3 columns are `t, x, y`, 4 are `t, x, y, z`.
/// - Fields may be padded with spaces and quoted (`"x"`); blank lines and `#` comment lines
///   are skipped; `\n` and `\r\n` line ends both work.
///
/// Every line has the columns of the first. For a 2-D file the table's `z` is 0 and its `dim`
/// 2. Timestamp order is checked by [`PoseTable::to_trajectory`], not here.
///
/// Time O(file size); the file is read into memory at once.
///
/// # Errors
/// - [`IoError::Open`] when the file cannot be read;
/// - [`IoError::Parse`] for a line whose column count differs from the first line's (naming
///   the first column past the record), a field that is not a finite number, a header naming
///   some of `t`, `x`, `y` but not all or one of them twice, or columns that neither a header
///   nor their count (3 or 4) explains;
/// - [`IoError::Empty`] when there is no data line (an empty file, or a header alone).
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}.csv", std::process::id()));
/// std::fs::write(&path, "Time;Y;X;speed\n0.0;5;1;0.0\n0.1;6;2;9.5\n")?;
/// let table = loops_io::read_csv(&path)?;
/// assert_eq!((table.dim, table.positions[1]), (2, [2.0, 6.0, 0.0]));
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_csv(path: impl AsRef<Path>) -> Result<PoseTable> {
    let path = path.as_ref();
    parse_csv(path, &mut text::open_lines(path)?)
}

/// Which field holds what, and how many fields a line has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Layout {
    t: usize,
    x: usize,
    y: usize,
    z: Option<usize>,
    /// Fields on every line.
    width: usize,
}

impl Layout {
    /// Columns taken in order: `t, x, y` or `t, x, y, z`.
    fn in_order(width: usize) -> Option<Self> {
        match width {
            3 => Some(Self { t: 0, x: 1, y: 2, z: None, width }),
            4 => Some(Self { t: 0, x: 1, y: 2, z: Some(3), width }),
            _ => None,
        }
    }
}

/// The positions in `lines`, the data lines of `path`.
pub(crate) fn parse_csv(path: &Path, lines: &mut Lines<impl BufRead>) -> Result<PoseTable> {
    let Some((first_line, first)) = lines.peek()? else {
        return Err(IoError::Empty { path: path.to_path_buf() });
    };
    let delimiter = delimiter_of(first);
    let fields: Vec<&str> = delimiter.split(first).collect();
    let layout = if text::is_header(fields.iter().copied()) {
        let layout = layout_of_header(&fields);
        lines.next_data()?;
        layout
    } else {
        Layout::in_order(fields.len()).ok_or_else(|| unexplained_columns(fields.len(), delimiter))
    }
    .map_err(|message| IoError::parse(path, first_line, message))?;

    let mut table = PoseTable::empty(path, if layout.z.is_some() { 3 } else { 2 });
    while let Some((line, content)) = lines.next_data()? {
        let (t, position) = text::record(delimiter.split(content), Takes::Exactly(layout.width), || {
            format!(" as on line {first_line}")
        })
        .and_then(|fields| parse_row(&layout, &fields))
        .map_err(|message| IoError::parse(path, line, message))?;
        table.timestamps_s.push(t);
        table.positions.push(position);
        table.source_lines.push(line);
    }
    if table.timestamps_s.is_empty() {
        return Err(IoError::Empty { path: path.to_path_buf() });
    }
    Ok(table)
}

/// The first of `,` `;` tab in `line`; runs of spaces when it has none.
fn delimiter_of(line: &str) -> Delimiter {
    [',', ';', '\t'].into_iter().find(|&c| line.contains(c)).map_or(Delimiter::Whitespace, Delimiter::Char)
}

/// The time and position of a data row, or what is wrong with it.
fn parse_row(layout: &Layout, fields: &[&str]) -> Result<(f64, [f64; 3]), String> {
    let number = |column: usize| text::parse_finite(fields[column], column + 1);
    let t = number(layout.t)?;
    let x = number(layout.x)?;
    let y = number(layout.y)?;
    let z = match layout.z {
        Some(column) => number(column)?,
        None => 0.0,
    };
    Ok((t, [x, y, z]))
}

/// The names a header may give each column, lower case.
const NAMES: [(&str, &[&str]); 4] = [("t", &["t", "time", "timestamp"]), ("x", &["x"]), ("y", &["y"]), ("z", &["z"])];

/// The layout a header row gives, or what is wrong with it.
fn layout_of_header(names: &[&str]) -> Result<Layout, String> {
    let mut found: [Option<usize>; 4] = [None; 4];
    for (column, name) in names.iter().enumerate() {
        let name = name.to_lowercase();
        let Some(role) = NAMES.iter().position(|(_, aliases)| aliases.contains(&name.as_str())) else {
            continue;
        };
        if let Some(earlier) = found[role] {
            return Err(format!(
                "header names column {} twice: columns {} ({:?}) and {} ({:?})",
                NAMES[role].0,
                earlier + 1,
                names[earlier],
                column + 1,
                names[column]
            ));
        }
        found[role] = Some(column);
    }
    match found {
        [Some(t), Some(x), Some(y), z] => Ok(Layout { t, x, y, z, width: names.len() }),
        [None, None, None, None] => Layout::in_order(names.len()).ok_or_else(|| {
            format!(
                "the header names no column t, x, y or z, and {} columns are not t, x, y[, z] in order",
                names.len()
            )
        }),
        _ => {
            let missing: Vec<&str> = NAMES[..3]
                .iter()
                .zip(found)
                .filter(|(_, column)| column.is_none())
                .map(|((role, _), _)| *role)
                .collect();
            Err(format!("the header names no column {} (t may be called time or timestamp)", missing.join(", ")))
        }
    }
}

/// Why a first row that is not a header has columns this reader cannot place.
fn unexplained_columns(count: usize, delimiter: Delimiter) -> String {
    let hint = match (count, delimiter) {
        (8, Delimiter::Whitespace) => {
            "; 8 columns separated by spaces look like TUM (timestamp tx ty tz qx qy qz qw): read it as TUM"
        }
        _ => "",
    };
    format!("expected 3 columns (t, x, y) or 4 (t, x, y, z), or a header row naming them; found {count}{hint}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<PoseTable> {
        parse_csv(Path::new("drive.csv"), &mut Lines::new(Path::new("drive.csv"), text.as_bytes()))
    }

    #[test]
    fn delimiter_is_the_first_found() {
        assert_eq!(delimiter_of("t,x;y"), Delimiter::Char(','));
        assert_eq!(delimiter_of("t;x\ty"), Delimiter::Char(';'));
        assert_eq!(delimiter_of("t\tx y"), Delimiter::Char('\t'));
        assert_eq!(delimiter_of("t x  y"), Delimiter::Whitespace);
    }

    #[test]
    fn header_maps_names_in_any_case_and_order() {
        let layout = layout_of_header(&["Z", "speed", "TimeStamp", "y", "X"]).unwrap();
        assert_eq!(layout, Layout { t: 2, x: 4, y: 3, z: Some(0), width: 5 });
        let layout = layout_of_header(&["stamp", "east", "north"]).unwrap();
        assert_eq!(layout, Layout::in_order(3).unwrap());
    }

    #[test]
    fn header_errors() {
        let error = layout_of_header(&["time", "lat", "lon"]).unwrap_err();
        assert_eq!(error, "the header names no column x, y (t may be called time or timestamp)");
        let error = layout_of_header(&["t", "time", "x", "y"]).unwrap_err();
        assert_eq!(error, r#"header names column t twice: columns 1 ("t") and 2 ("time")"#);
        let error = layout_of_header(&["a", "b", "c", "d", "e"]).unwrap_err();
        assert!(error.contains("5 columns"), "{error}");
    }

    #[test]
    fn rows_must_match_the_first() {
        let error = parse("0,1,2\n1,1,2,3\n").unwrap_err();
        assert_eq!(
            error.to_string(),
            r#"drive.csv line 2: expected 3 columns as on line 1, found 4: column 4 ("3") is past the end of the record, at column 3 (two records run together on one line?)"#
        );
        let table = parse("0 1 2\n1 3 4\n").unwrap();
        assert_eq!(table.positions, [[1.0, 2.0, 0.0], [3.0, 4.0, 0.0]]);
    }
}
