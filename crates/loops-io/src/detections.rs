//! Loop-closure detections from text: `t t_prime [score]` rows (CSV or whitespace, header
//! allowed), and the TUC datasets' `loop t1 t2 score` lines.

use std::path::{Path, PathBuf};

use loops_core::{Detections, Error, Timeline};

use crate::error::{IoError, Result};
use crate::text::{Delimiter, data_lines, is_header, parse_finite, read_text};

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
/// spaces, a header row allowed, `#` comments skipped; or lines `loop t1 t2 score ...` as in the
/// TUC SLAM datasets (other keyword lines, e.g. `odom2`, are skipped).
///
/// # Errors
/// [`IoError::Open`]; [`IoError::Parse`] naming line and column for a row with fewer than two
/// numbers or a non-finite value; [`IoError::Empty`] without any detection.
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
    let text = read_text(path)?;
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
    for (number, line) in data_lines(&text) {
        let delimiter =
            [',', ';', '\t'].into_iter().find(|c| line.contains(*c)).map_or(Delimiter::Whitespace, Delimiter::Char);
        let mut fields: Vec<&str> = delimiter.split(line).collect();
        match fields.first() {
            Some(&"loop") => {
                fields.remove(0);
            }
            Some(word)
                if word.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
                    && fields.len() > 1
                    && !is_header(fields.iter().copied()) =>
            {
                continue; // another record type of a keyword-led file (odom2, point2, ...)
            }
            _ => {}
        }
        if table.t_s.is_empty() && is_header(fields.iter().copied()) {
            continue;
        }
        if fields.len() < 2 {
            return Err(parse_error(number, format!("found {} column(s), need t and t_prime", fields.len())));
        }
        let column_offset = usize::from(line.starts_with("loop"));
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
    /// The detections, placed on `timeline` (each time snapped to the nearest pose).
    ///
    /// # Errors
    /// [`IoError::Detections`] naming the line of a detection outside the trajectory's time
    /// span (or whatever else the core rejects).
    pub fn to_detections<T: Timeline + ?Sized>(&self, timeline: &T) -> Result<Detections> {
        let locate = |error: Error| {
            let line = match error {
                Error::DetectionOutsideSpan { index, .. } | Error::NonFiniteDetection { index, .. } => {
                    self.source_lines.get(index).copied()
                }
                _ => None,
            };
            IoError::Detections { path: self.path.clone(), line, error }
        };
        let mut detections = Detections::new(self.t_s.clone(), self.t_prime_s.clone()).map_err(locate)?;
        if let Some(scores) = &self.scores {
            detections = detections.with_scores(scores.clone()).map_err(locate)?;
        }
        detections.locate(timeline).map_err(locate)
    }
}
