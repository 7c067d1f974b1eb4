//! The TU Chemnitz (libRSF) ground-truth files: `point2 t x y ...`, `point3 t X Y Z ...` (ECEF),
//! `angle t yaw ...` lines.

use std::collections::HashMap;
use std::io::BufRead;
use std::path::Path;

use crate::error::{IoError, Result};
use crate::rotation::{ecef_to_enu, quaternion_from_yaw};
use crate::table::PoseTable;
use crate::text::{self, Lines, Takes};

/// Reads a libRSF ground-truth file (the TUC SLAM, Chemnitz City and smartLoc data sets): lines
/// tagged by their first word.
///
/// - `point2 t x y ...`: a 2-D position in metres at time `t` (seconds); the covariance that
///   libRSF writes after it (4 numbers; 9 after `point3`, 1 after `angle`) is ignored, but must
///   be whole or absent: a record is never read from a line holding more (two lines run
///   together). `angle t yaw ...` lines at the same times give the heading
///   (radians): when every `point2` has one, the table has orientations (rotations about z).
/// - `point3 t X Y Z ...`: an ECEF position (metres, ≈ 4·10⁶ from the centre of the Earth). The
///   table holds it in the east-north-up frame at the first fix: the first position is
///   `[0, 0, 0]`, x points east, y north, z up. That is a rotation of ECEF minus the first fix,
///   so every distance is kept, and the plane axes `[0, 1]` are the horizontal.
/// - The other record types of libRSF (`odom2`, `loop`, ... [`LIBRSF_TAGS`]) are skipped; a
///   line of any other tag (a misspelled `poitn2`) is an error. A file has `point2` or `point3`
///   lines, not both.
///
/// Time O(file size).
///
/// # Errors
/// - [`IoError::Open`] when the file cannot be read;
/// - [`IoError::Parse`] for a line whose tag is not libRSF's, a `point2`, `point3` or `angle`
///   line with another count of columns than its record takes (naming the first column past
///   it), a field that is not a finite number, or `point2` and `point3`
///   in one file;
/// - [`IoError::Empty`] without `point2` or `point3` lines.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-tuc.txt", std::process::id()));
/// std::fs::write(&path, "point2 0 1 2 0 0 0 0\nangle 0 1.5 0\npoint2 0.2 3 4 0 0 0 0\nangle 0.2 1.6 0\n")?;
/// let table = loops_io::read_tuc(&path)?;
/// assert_eq!((table.dim, table.positions[1]), (2, [3.0, 4.0, 0.0]));
/// assert!(table.orientations_xyzw.is_some());
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_tuc(path: impl AsRef<Path>) -> Result<PoseTable> {
    let path = path.as_ref();
    parse_tuc(path, &mut text::open_lines(path)?)
}

/// The record types of libRSF's text files (its `DataType` names): the lines a libRSF file may
/// hold. The TUC reader reads `point2`, `point3` and `angle`, the detection reader `loop`.
pub const LIBRSF_TAGS: &[&str] = &[
    "point1",
    "point2",
    "point3",
    "angle",
    "quaternion",
    "unit_circle",
    "pose2",
    "pose3",
    "pose_between2",
    "pose_between3",
    "point_id2",
    "point_conf_id2",
    "bounding_box_3",
    "clock",
    "clock_drift",
    "imu_bias",
    "switch",
    "cov1",
    "cov2",
    "gmm1",
    "gmm2",
    "odom2",
    "odom2diff",
    "odom3",
    "odom3radar",
    "odom3laser",
    "odom3vio",
    "imu",
    "pseudorange2",
    "pseudorange3",
    "range2",
    "range3",
    "range_lm2",
    "range_lm3",
    "point2radar",
    "point1set",
    "point2set",
    "point3set",
    "point2setradar",
    "bearing_range_id_2",
    "pressure",
    "pressure_diff",
    "loop",
    "error1",
    "error2",
    "error3",
    "error6",
    "cost",
    "cost_gradient1",
    "cost_gradient2",
    "cost_gradient3",
    "solver_summary",
    "val1",
];

/// Whether `word` is the tag of a libRSF record.
pub(crate) fn is_librsf_tag(word: &str) -> bool {
    LIBRSF_TAGS.contains(&word)
}

/// The message for a line whose first word is no libRSF record type.
pub(crate) fn unknown_tag(word: &str) -> String {
    const SHOWN_CHARS: usize = 40;
    let shown: String = word.chars().take(SHOWN_CHARS).collect();
    let cut = if word.chars().count() > SHOWN_CHARS { "…" } else { "" };
    format!("unknown record type {shown:?}{cut}: expected a libRSF record (point2, point3, angle, loop, odom2, ...)")
}

/// The tag, the columns its record needs (the tag, the time and the mean), the entries of the
/// covariance that may follow them, and what a line looks like, for messages.
fn columns_of(tag: &str) -> Option<(&'static str, usize, usize, &'static str)> {
    match tag {
        "point2" => Some(("point2", 4, 4, "point2 t x y, then the covariance's 4 entries or none")),
        "point3" => Some(("point3", 5, 9, "point3 t X Y Z, then the covariance's 9 entries or none")),
        "angle" => Some(("angle", 3, 1, "angle t yaw, then its variance or none")),
        _ => None,
    }
}

/// The TUC poses in `lines`, the data lines of `path`.
pub(crate) fn parse_tuc(path: &Path, lines: &mut Lines<impl BufRead>) -> Result<PoseTable> {
    let mut table = PoseTable::empty(path, 2);
    let mut kind: Option<(&'static str, usize)> = None;
    // Heading by the bits of its time: point2 and angle lines of one instant share the text.
    let mut yaw_at: HashMap<u64, f64> = HashMap::new();
    while let Some((line, content)) = lines.next_data()? {
        let Some(word) = content.split_ascii_whitespace().next() else { continue };
        let parse_error = |message: String| IoError::parse(path, line, message);
        let Some((tag, needed, covariance, layout)) = columns_of(word) else {
            if LIBRSF_TAGS.contains(&word) {
                text::check_one_record(content.split_ascii_whitespace(), is_librsf_tag).map_err(parse_error)?;
                continue;
            }
            return Err(parse_error(unknown_tag(word)));
        };
        // The numbers first, then their count: a second record's tag is named where it starts.
        let fields: Vec<&str> = content.split_ascii_whitespace().collect();
        let mut values = [0.0; 4];
        for (k, (value, field)) in values.iter_mut().zip(fields.iter().take(needed).skip(1)).enumerate() {
            *value = text::parse_finite(field, k + 2).map_err(parse_error)?;
        }
        text::check_numbers(fields.get(needed..).unwrap_or_default(), needed + 1).map_err(parse_error)?;
        let takes = Takes::Either(needed, needed + covariance);
        text::record(fields.into_iter(), takes, || format!(" ({layout})")).map_err(parse_error)?;
        if tag == "angle" {
            yaw_at.insert(values[0].to_bits(), values[1]);
            continue;
        }
        match kind {
            Some((first, first_line)) if first != tag => {
                return Err(parse_error(format!("a {tag} line in a file of {first} lines (line {first_line})")));
            }
            _ => kind = Some((tag, line)),
        }
        table.timestamps_s.push(values[0]);
        table.positions.push(match tag {
            "point2" => [values[1], values[2], 0.0],
            _ => [values[1], values[2], values[3]],
        });
        table.source_lines.push(line);
    }
    match kind {
        None => Err(IoError::Empty { path: path.to_path_buf() }),
        Some(("point3", _)) => {
            table.dim = 3;
            let origin = table.positions[0];
            let rotation = ecef_to_enu(origin);
            for (position, line) in table.positions.iter_mut().zip(&table.source_lines) {
                let delta = [position[0] - origin[0], position[1] - origin[1], position[2] - origin[2]];
                *position = rotation.map(|row| row[0] * delta[0] + row[1] * delta[1] + row[2] * delta[2]);
                if !position.iter().all(|v| v.is_finite()) {
                    let message = "the ECEF position is too far from the first one to subtract it (overflow)";
                    return Err(IoError::parse(path, *line, message));
                }
            }
            Ok(table)
        }
        Some(_) => {
            let headings: Option<Vec<[f64; 4]>> = table
                .timestamps_s
                .iter()
                .map(|t| yaw_at.get(&t.to_bits()).map(|&yaw| quaternion_from_yaw(yaw)))
                .collect();
            table.orientations_xyzw = headings;
            Ok(table)
        }
    }
}

/// Whether the first data line starts with a libRSF tag this reader knows.
pub(crate) fn looks_like_tuc(first_lines: &[String]) -> bool {
    first_lines
        .first()
        .is_some_and(|line| line.split_ascii_whitespace().next().is_some_and(|tag| columns_of(tag).is_some()))
}
