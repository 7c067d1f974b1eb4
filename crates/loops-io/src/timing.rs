//! Times for files that do not carry them: a rate, or a times file.

use std::path::{Path, PathBuf};

use crate::error::{IoError, Result};
use crate::text::{self, Takes};

/// Where the times of poses come from, for formats whose lines may have none (KITTI poses
/// without a time column, MulRan, pose graphs).
#[derive(Debug, Clone, PartialEq, Default)]
#[non_exhaustive]
pub enum Timing {
    /// From the file: its time column (KITTI with 13 numbers a line). Pose graphs have no time
    /// and take the vertex id as seconds (one pose a second). KITTI lines of 12 numbers are an
    /// error: they need one of the other two.
    #[default]
    FromFile,
    /// Pose `i` (vertex id `i` in a graph) at `i / rate_hz` seconds; a time column in the file
    /// is ignored.
    RateHz(f64),
    /// One time a line, in seconds, in a separate file (KITTI's `times.txt`), one per pose in
    /// order; a time column in the pose file is ignored.
    TimesFile(PathBuf),
}

/// A rate and a times file given together ([`Timing::given`]): both would time the poses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("rate_hz and times both give the poses' times: give one")]
#[non_exhaustive]
pub struct TimingConflict;

impl Timing {
    /// The timing of a reader's options: `rate_hz`, a `times` file, or neither (the file's own
    /// times). Every surface (the CLI's `--rate-hz`/`--times`, Python's `rate_hz=`/`times=`)
    /// takes its timing here.
    ///
    /// # Errors
    /// [`TimingConflict`] when both are given.
    ///
    /// # Examples
    /// ```
    /// use loops_io::Timing;
    /// assert_eq!(Timing::given(Some(10.0), None), Ok(Timing::RateHz(10.0)));
    /// assert_eq!(Timing::given(None, None), Ok(Timing::FromFile));
    /// assert!(Timing::given(Some(10.0), Some("times.txt".into())).is_err());
    /// ```
    pub fn given(rate_hz: Option<f64>, times: Option<PathBuf>) -> Result<Self, TimingConflict> {
        match (rate_hz, times) {
            (Some(_), Some(_)) => Err(TimingConflict),
            (Some(rate_hz), None) => Ok(Self::RateHz(rate_hz)),
            (None, Some(times)) => Ok(Self::TimesFile(times)),
            (None, None) => Ok(Self::FromFile),
        }
    }

    /// Whether the times come from elsewhere than the pose file.
    pub(crate) fn is_given(&self) -> bool {
        !matches!(self, Self::FromFile)
    }

    /// The times of `count` poses at the indices `indices` (`0..count` unless a graph's ids),
    /// or `None` for [`Timing::FromFile`].
    ///
    /// # Errors
    /// An invalid rate; a times file that cannot be read, has a line that is not one number, or
    /// has another count of times than of poses.
    pub(crate) fn times(&self, pose_file: &Path, indices: &[f64]) -> Result<Option<Vec<f64>>> {
        match self {
            Self::FromFile => Ok(None),
            Self::RateHz(rate_hz) => {
                if !(rate_hz.is_finite() && *rate_hz > 0.0) {
                    return Err(IoError::invalid(pose_file, "rate_hz", *rate_hz, "a positive finite rate in Hz"));
                }
                Ok(Some(indices.iter().map(|i| i / rate_hz).collect()))
            }
            Self::TimesFile(path) => {
                let mut lines = text::open_lines(path)?;
                let mut times = Vec::new();
                while let Some((line, content)) = lines.next_data()? {
                    let time = text::record(content.split_ascii_whitespace(), Takes::Exactly(1), || {
                        " (one time in seconds a line)".to_owned()
                    })
                    .and_then(|fields| text::parse_finite(fields[0], 1))
                    .map_err(|message| IoError::parse(path, line, message))?;
                    times.push(time);
                }
                if times.len() != indices.len() {
                    return Err(IoError::Trajectory {
                        path: path.as_path().into(),
                        line: None,
                        previous_line: None,
                        messages: None,
                        error: loops_core::Error::LengthMismatch { timestamps: times.len(), poses: indices.len() },
                    });
                }
                Ok(Some(times))
            }
        }
    }
}
