//! # loops-io
//!
//! Pose files in, for [`loops_core`]: a reader returns a [`PoseTable`] (timestamps, positions,
//! orientations when the format has them, and the line each pose came from), and
//! [`PoseTable::to_trajectory`] turns it into a [`loops_core::Trajectory`], reporting the
//! core's complaints (duplicate timestamps, ...) at their line in the file.
//!
//! | format | reader | lines | extensions |
//! |---|---|---|---|
//! | TUM RGB-D | [`read_tum`] | `timestamp tx ty tz qx qy qz qw` | `.tum`, `.txt` |
//! | CSV | [`read_csv`] | `t,x,y` or `t,x,y,z`, optional header | `.csv` |
//!
//! [`read_trajectory`] picks the reader by [`Format`] or by extension. Every error is an
//! [`IoError`] whose message starts with the file and line: `drive.tum line 12: column 3
//! ("abc") is not a number`.
//!
//! What it does not do (yet): write files; read KITTI poses, EuRoC CSV (nanosecond
//! timestamps), g2o/TORO graphs or bags; normalise quaternions; drop duplicate timestamps
//! (they are reported, not fixed).
//!
//! ## Quickstart
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use loops_core::{Euclidean, find_loops};
//!
//! // A square driven twice, one pose a second.
//! let path = std::env::temp_dir().join(format!("loops-io-quickstart-{}.tum", std::process::id()));
//! let mut text = String::from("# timestamp tx ty tz qx qy qz qw\n");
//! for i in 0..8 {
//!     let [x, y] = [[0, 0], [10, 0], [10, 10], [0, 10]][i % 4];
//!     text += &format!("{i}.0 {x} {y} 0 0 0 0 1\n");
//! }
//! std::fs::write(&path, text)?;
//!
//! let table = loops_io::read_tum(&path)?;
//! assert_eq!((table.timestamps_s.len(), table.source_lines[0]), (8, 2));
//! let trajectory = table.to_trajectory_plane([0, 1])?;
//! let loops = find_loops(&trajectory, &Euclidean, 1.0)?;
//! assert!(loops.components().iter().any(|c| !c.trivial)); // the second lap revisits the first
//! # std::fs::remove_file(&path)?;
//! # Ok(())
//! # }
//! ```
#![warn(missing_docs)]

mod csv;
mod error;
mod format;
mod table;
mod text;
mod tum;

pub use csv::read_csv;
pub use error::{IoError, Result};
pub use format::{Format, read_trajectory};
pub use table::PoseTable;
pub use tum::read_tum;
