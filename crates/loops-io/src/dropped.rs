//! What the lenient reading options drop, so that every caller can say how many and where.

use std::path::PathBuf;

/// The rows a lenient option dropped from a file: poses repeating the stamp before them
/// ([`PoseTable::drop_duplicate_stamps`](crate::PoseTable::drop_duplicate_stamps)), detections
/// outside the trajectory's time span
/// ([`DetectionTable::drop_outside_span`](crate::DetectionTable::drop_outside_span)). Strict
/// reading stays the default; a caller that drops says so, with [`count`](Self::count) and
/// [`lines_text`](Self::lines_text).
///
/// # Examples
/// ```
/// let dropped = loops_io::Dropped { path: "desk.tum".into(), count: 1, lines: vec![10863] };
/// assert_eq!(dropped.lines_text().as_deref(), Some("line 10863"));
/// let many = loops_io::Dropped { path: "in.txt".into(), count: 5, lines: vec![7, 9, 12, 40, 41] };
/// assert_eq!(many.lines_text().as_deref(), Some("lines 7, 9, 12 and 2 more"));
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Dropped {
    /// The file the rows came from.
    pub path: PathBuf,
    /// How many rows were dropped.
    pub count: usize,
    /// The 1-based lines of the dropped rows, in file order; empty for poses from MCAP files
    /// and bags (they have messages, not lines).
    pub lines: Vec<usize>,
}

impl Dropped {
    /// The lines shown by [`lines_text`](Self::lines_text) before "and N more".
    const SHOWN: usize = 3;

    /// Whether nothing was dropped.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Where the dropped rows were, for a message: `line 10863`, `lines 7, 9 and 12`, `lines 7,
    /// 9, 12 and 2 more`; `None` without lines.
    pub fn lines_text(&self) -> Option<String> {
        let (first, rest) = match self.lines.as_slice() {
            [] => return None,
            [line] => return Some(format!("line {line}")),
            lines if lines.len() <= Self::SHOWN => {
                (&lines[..lines.len() - 1], format!(" and {}", lines[lines.len() - 1]))
            }
            lines => (&lines[..Self::SHOWN], format!(" and {} more", lines.len() - Self::SHOWN)),
        };
        let first: Vec<String> = first.iter().map(ToString::to_string).collect();
        Some(format!("lines {}{rest}", first.join(", ")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_text_lists_a_few() {
        let text = |lines: Vec<usize>| Dropped { path: "f".into(), count: lines.len(), lines }.lines_text();
        assert_eq!(text(vec![]), None);
        assert_eq!(text(vec![4]).as_deref(), Some("line 4"));
        assert_eq!(text(vec![4, 5]).as_deref(), Some("lines 4 and 5"));
        assert_eq!(text(vec![4, 5, 9]).as_deref(), Some("lines 4, 5 and 9"));
        assert_eq!(text(vec![4, 5, 9, 10]).as_deref(), Some("lines 4, 5, 9 and 1 more"));
    }
}
