//! Loop-closure detections from text: `t t_prime [score]` rows (CSV or whitespace, header
//! allowed), and the TUC datasets' `loop t1 t2 score` lines.

use std::path::{Path, PathBuf};

use loops_core::{Detections, Error, Timeline};

use crate::dropped::Dropped;
use crate::error::{IoError, Result};
use crate::text::{self, Delimiter, Takes, is_header, open_lines, parse_finite};
use crate::tuc::{LIBRSF_TAGS, is_librsf_tag, unknown_tag};

/// Detections as read: times of the two poses of each detected loop, seconds, an optional
/// score (higher is more confident), and the file line of each.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectionTable {
    /// The file read.
    pub path: PathBuf,
    /// Time of the first pose of each detection, seconds.
    pub t_s: Vec<f64>,
    /// Time of the second pose, seconds.
    pub t_prime_s: Vec<f64>,
    /// Scores, when every row has one.
    pub scores: Option<Vec<f64>>,
    /// The 1-based line of each detection.
    pub source_lines: Vec<usize>,
}

/// Reads detections: rows of `t, t_prime[, score]` separated by commas, semicolons, tabs or
/// spaces, a header row allowed, `#` comments skipped; or lines `loop t1 t2 [score]` as in the
/// TUC SLAM datasets (the other libRSF record types, e.g. `odom2`, are skipped; a line of a
/// keyword that is none of them is an error).
///
/// # Errors
/// [`IoError::Open`]; [`IoError::Parse`] naming line and column for a row of other than 2 or 3
/// columns (3 or 4 with `loop`; naming the first column past the record: two rows run together
/// are not read as one) or a non-finite value, or naming an unknown keyword; [`IoError::Empty`] without any
/// detection.
///
/// # Examples
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-det.txt", std::process::id()));
/// std::fs::write(&path, "odom2 0 0 0 0\nloop 21.2 19.3 1\nloop 25.0 19.3 0.66\n")?;
/// let table = loops_io::read_detections(&path)?;
/// assert_eq!(table.t_s, vec![21.2, 25.0]);
/// assert_eq!(table.source_lines, vec![2, 3]);
/// # std::fs::remove_file(&path)?;
/// # Ok(())
/// # }
/// ```
pub fn read_detections(path: impl AsRef<Path>) -> Result<DetectionTable> {
    let path = path.as_ref();
    let mut lines = open_lines(path)?;
    let mut table = DetectionTable {
        path: path.to_path_buf(),
        t_s: Vec::new(),
        t_prime_s: Vec::new(),
        scores: None,
        source_lines: Vec::new(),
    };
    let mut scores = Vec::new();
    let mut all_scored = true;
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    while let Some((number, line)) = lines.next_data()? {
        let delimiter =
            [',', ';', '\t'].into_iter().find(|c| line.contains(*c)).map_or(Delimiter::Whitespace, Delimiter::Char);
        let mut fields: Vec<&str> = delimiter.split(line).collect();
        // A `loop` line is a detection, never a header row: a corrupt one is an error.
        let mut keyword = false;
        match fields.first() {
            Some(&"loop") => {
                fields.remove(0);
                keyword = true;
            }
            Some(word)
                if word.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
                    && fields.len() > 1
                    && !is_header(fields.iter().copied()) =>
            {
                // Another record type of a keyword-led file (odom2, point2, ...), or a typo.
                if LIBRSF_TAGS.contains(word) {
                    text::check_one_record(delimiter.split(line), is_librsf_tag).map_err(|m| parse_error(number, m))?;
                    continue;
                }
                return Err(parse_error(number, unknown_tag(word)));
            }
            _ => {}
        }
        if !keyword && table.t_s.is_empty() && is_header(fields.iter().copied()) {
            continue;
        }
        let (takes, layout) = if keyword {
            (Takes::Either(3, 4), " (loop t t_prime, then a score or none)")
        } else {
            (Takes::Either(2, 3), " (t, t_prime, then a score or none)")
        };
        text::record(delimiter.split(line), takes, || layout.to_owned()).map_err(|m| parse_error(number, m))?;
        let column_offset = usize::from(keyword);
        let t = parse_finite(fields[0], 1 + column_offset).map_err(|m| parse_error(number, m))?;
        let t_prime = parse_finite(fields[1], 2 + column_offset).map_err(|m| parse_error(number, m))?;
        match fields.get(2) {
            Some(field) if !field.is_empty() => {
                scores.push(parse_finite(field, 3 + column_offset).map_err(|m| parse_error(number, m))?);
            }
            _ => all_scored = false,
        }
        table.t_s.push(t);
        table.t_prime_s.push(t_prime);
        table.source_lines.push(number);
    }
    if table.t_s.is_empty() {
        return Err(IoError::Empty { path: path.to_path_buf() });
    }
    if all_scored {
        table.scores = Some(scores);
    }
    Ok(table)
}

impl DetectionTable {
    /// Drops the detections with a time outside `timeline`'s time span (before its first pose
    /// or after its last: the TUC Corridor's input ends 0.4 s after its ground truth, and 39 of
    /// its 10,019 detections lie in those 0.4 s), and says which it dropped. Placing them
    /// ([`to_detections`](Self::to_detections)) is an error by default; this is the lenient
    /// option (`--drop-detections-outside-span`, `drop_outside_span=True`), and its callers say
    /// how many it dropped.
    ///
    /// Time O(n).
    ///
    /// # Examples
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// let path = std::env::temp_dir().join(format!("loops-io-doc-{}-span.txt", std::process::id()));
    /// std::fs::write(&path, "loop 2.0 0.5 1\nloop 9.5 1.0 1\nloop 3.0 1.0 1\n")?;
    /// let traj = loops_core::Trajectory::new(vec![0.0, 1.0, 2.0, 3.0], vec![0.0; 4], 1)?;
    /// let mut table = loops_io::read_detections(&path)?;
    /// assert!(table.to_detections(&traj).is_err()); // strict: 9.5 s is after the last pose
    /// let dropped = table.drop_outside_span(&traj);
    /// assert_eq!((dropped.count, dropped.lines.as_slice()), (1, &[2][..]));
    /// assert_eq!(table.to_detections(&traj)?.len(), 2);
    /// # std::fs::remove_file(&path)?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn drop_outside_span<T: Timeline + ?Sized>(&mut self, timeline: &T) -> Dropped {
        let times = timeline.pose_times_s();
        let mut dropped = Dropped { path: self.path.clone(), count: 0, lines: Vec::new() };
        let (Some(&first), Some(&last)) = (times.first(), times.last()) else { return dropped };
        // As the core places a time: inside when first ≤ t ≤ last (NaN is outside).
        let inside = |t: f64| t >= first && t <= last;
        let keep: Vec<bool> = self.t_s.iter().zip(&self.t_prime_s).map(|(&a, &b)| inside(a) && inside(b)).collect();
        dropped.lines = keep.iter().zip(&self.source_lines).filter(|(k, _)| !**k).map(|(_, &line)| line).collect();
        dropped.count = keep.iter().filter(|k| !**k).count();
        let retain = |rows: &mut Vec<_>| {
            let mut index = 0;
            rows.retain(|_| {
                index += 1;
                keep[index - 1]
            });
        };
        retain(&mut self.t_s);
        retain(&mut self.t_prime_s);
        if let Some(scores) = &mut self.scores {
            retain(scores);
        }
        let mut index = 0;
        self.source_lines.retain(|_| {
            index += 1;
            keep[index - 1]
        });
        dropped
    }

    /// The detections, placed on `timeline` (each time snapped to the nearest pose).
    ///
    /// # Errors
    /// [`IoError::Detections`] naming the line of a detection outside the trajectory's time
    /// span (or whatever else the core rejects).
    pub fn to_detections<T: Timeline + ?Sized>(&self, timeline: &T) -> Result<Detections> {
        self.to_unplaced()?.locate(timeline).map_err(|error| self.locate(error))
    }

    /// The detections with their times (and scores), not placed on a trajectory.
    ///
    /// # Errors
    /// [`IoError::Detections`] naming the line of a detection the core rejects (a table built
    /// by hand with no row, or a non-finite time).
    pub fn to_unplaced(&self) -> Result<Detections> {
        let mut detections =
            Detections::new(self.t_s.clone(), self.t_prime_s.clone()).map_err(|error| self.locate(error))?;
        if let Some(scores) = &self.scores {
            detections = detections.with_scores(scores.clone()).map_err(|error| self.locate(error))?;
        }
        Ok(detections)
    }

    /// A core error placed in the file: the detection index it names becomes a line.
    fn locate(&self, error: Error) -> IoError {
        let line = match error {
            Error::DetectionOutsideSpan { index, .. } | Error::NonFiniteDetection { index, .. } => {
                self.source_lines.get(index).copied()
            }
            _ => None,
        };
        IoError::Detections { path: self.path.clone(), line, error }
    }
}
