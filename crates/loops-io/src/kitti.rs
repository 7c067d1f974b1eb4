//! KITTI odometry poses: a row-major 3×4 `[R|t]` a line, with or without a leading time.

use std::io::BufRead;
use std::path::Path;

use loops_core::FILE_QUATERNION_TOLERANCE;

use crate::error::{IoError, Result};
use crate::rotation::quaternion_from_matrix;
use crate::table::PoseTable;
use crate::text::{self, Lines, Takes};
use crate::timing::Timing;

/// Reads KITTI poses: each line the 12 numbers of a row-major 3×4 matrix `[R|t]` (the pose of
/// the camera in the first camera's frame), after a time in seconds when the line has 13.
///
/// - 13 numbers a line: the first is the time (the ground truth shipped with this project's
///   data); 12 numbers (KITTI's `poses/XX.txt`, MulRan): the times come from `timing`, a rate
///   or a times file, and [`Timing::FromFile`] is an error. A given rate or times file also
///   replaces a time column.
/// - Orientations are the unit quaternions of the rotations (normalised: printed matrices are
///   not quite orthonormal). A block that is no rotation within [`ROTATION_MATRIX_TOLERANCE`] (zero,
///   a reflection, not orthonormal) is an error. The table is 3-D; KITTI's camera frame has y down and the ground
///   in the x-z plane, so plane axes `[0, 2]` give the map.
/// - Blank lines and `#` comments are skipped; numbers are separated by spaces or tabs; every
///   line has the count of the first.
///
/// Time O(file size).
///
/// # Errors
/// - [`IoError::Open`] when a file cannot be read;
/// - [`IoError::Parse`] for a line with other than 12 or 13 numbers, or another count than the
///   first line (naming the first column past the record), or a field that is not a finite
///   number, naming line and column; for 12
///   numbers without a rate or times file; for a rotation block that is not a rotation,
///   saying how;
/// - [`IoError::Empty`] without data lines;
/// - [`IoError::Trajectory`] holding [`loops_core::Error::InvalidParameter`] for a rate that is
///   not positive and finite, or [`loops_core::Error::LengthMismatch`] for a times file with
///   another count of times.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use loops_io::{Timing, read_kitti};
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-kitti.txt", std::process::id()));
/// std::fs::write(&path, "1 0 0 5 0 1 0 6 0 0 1 7\n0 -1 0 8 1 0 0 9 0 0 1 10\n")?;
/// let table = read_kitti(&path, &Timing::RateHz(10.0))?;
/// assert_eq!(table.timestamps_s, [0.0, 0.1]);
/// assert_eq!(table.positions[1], [8.0, 9.0, 10.0]);
/// let [_, _, z, w] = table.orientations_xyzw.as_ref().unwrap()[1];
/// assert!((z - 0.5f64.sqrt()).abs() < 1e-15 && (w - 0.5f64.sqrt()).abs() < 1e-15); // 90° about z
/// assert!(read_kitti(&path, &Timing::FromFile).is_err()); // 12 numbers: no time
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_kitti(path: impl AsRef<Path>, timing: &Timing) -> Result<PoseTable> {
    let path = path.as_ref();
    parse_kitti(path, &mut text::open_lines(path)?, timing)
}

/// The KITTI poses in `lines`, the data lines of `path`.
pub(crate) fn parse_kitti(path: &Path, lines: &mut Lines<impl BufRead>, timing: &Timing) -> Result<PoseTable> {
    let mut table = PoseTable::empty(path, 3);
    let mut orientations = Vec::new();
    let mut width: Option<(usize, usize)> = None;
    let mut values = [0.0; 13];
    while let Some((line, content)) = lines.next_data()? {
        let parse_error = |message: String| IoError::parse(path, line, message);
        let takes = width.map_or(Takes::Either(12, 13), |(count, _)| Takes::Exactly(count));
        let fields = text::record(content.split_ascii_whitespace(), takes, || match width {
            Some((_, first_line)) => format!(" as on line {first_line}"),
            None => " (a row-major 3×4 pose [R|t], after a time when 13)".to_owned(),
        })
        .map_err(parse_error)?;
        for (column, (value, field)) in values.iter_mut().zip(&fields).enumerate() {
            *value = text::parse_finite(field, column + 1).map_err(parse_error)?;
        }
        let count = fields.len();
        width.get_or_insert((count, line));
        let (time, matrix) = match count {
            13 => (values[0], &values[1..13]),
            _ if timing.is_given() => (f64::NAN, &values[..12]),
            _ => {
                return Err(parse_error(
                    "12 numbers (a 3×4 pose) and no time: give the poses' times, a rate (rate_hz, --rate-hz) \
                     or KITTI's times.txt (times, --times)"
                        .to_owned(),
                ));
            }
        };
        let m = |row: usize, column: usize| matrix[4 * row + column];
        let rotation = [[m(0, 0), m(0, 1), m(0, 2)], [m(1, 0), m(1, 1), m(1, 2)], [m(2, 0), m(2, 1), m(2, 2)]];
        check_rotation(&rotation).map_err(parse_error)?;
        table.timestamps_s.push(time);
        table.positions.push([m(0, 3), m(1, 3), m(2, 3)]);
        orientations.push(quaternion_from_matrix(rotation));
        table.source_lines.push(line);
    }
    if table.is_empty() {
        return Err(IoError::Empty { path: path.to_path_buf() });
    }
    let indices: Vec<f64> = (0..table.len()).map(|i| i as f64).collect();
    if let Some(times) = timing.times(path, &indices)? {
        table.timestamps_s = times;
    }
    table.orientations_xyzw = Some(orientations);
    Ok(table)
}

/// How far a rotation block read from a file may be from orthonormal: the largest entry of
/// `RᵀR − I`, as [`FILE_QUATERNION_TOLERANCE`] bounds a quaternion's norm (KITTI's files print 7
/// digits, `%f` prints 6: their blocks are ~1e-6 from orthonormal).
pub const ROTATION_MATRIX_TOLERANCE: f64 = FILE_QUATERNION_TOLERANCE;

/// Whether `r` (rows) is a rotation within [`ROTATION_MATRIX_TOLERANCE`]: orthonormal, determinant
/// +1; or what is wrong with it. A zero block or a reflection would otherwise become some
/// quaternion (the identity, a rotation by π), and the pose a wrong one.
fn check_rotation(r: &[[f64; 3]; 3]) -> Result<(), String> {
    const WHAT: &str = "the rotation block (columns 1-3, 5-7, 9-11 of the pose)";
    if r.iter().flatten().all(|&v| v == 0.0) {
        return Err(format!("{WHAT} is zero, not a rotation"));
    }
    let mut off = 0.0f64;
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| r[k][i] * r[k][j]).sum();
            off = off.max((dot - if i == j { 1.0 } else { 0.0 }).abs());
        }
    }
    if off.is_nan() || off > ROTATION_MATRIX_TOLERANCE {
        return Err(format!(
            "{WHAT} is not orthonormal: RᵀR differs from the identity by up to {off:.3e} (at most \
             {ROTATION_MATRIX_TOLERANCE:e} allowed), not a rotation"
        ));
    }
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    if det < 0.0 {
        return Err(format!("{WHAT} is a reflection (determinant {det:.6}), not a rotation"));
    }
    Ok(())
}
