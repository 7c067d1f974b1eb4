//! `PairSpace`: lattice pairs as segments of rows, numbered for uniform draws.

use rand::Rng;

use super::{bernoulli_indices, check_every, choose_indices};
use crate::error::Result;
use crate::interrupt::Interrupt;
use crate::loops::Loops;
use crate::memory::{try_reserve, try_with_capacity};

/// A stretch `start..=end` of columns of one row: pairs (row, j).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Segment {
    pub row: u32,
    pub start: u32,
    pub end: u32,
}

/// A set of lattice pairs given as segments of rows, numbered 0..len in segment order: uniform
/// draws pick a number, then its segment (runs weighted by length) and a column. Never a list of
/// pairs.
#[derive(Debug, Clone, Default)]
pub(crate) struct PairSpace {
    segments: Vec<Segment>,
    /// `ends[s]`: number of pairs in segments 0..=s.
    ends: Vec<u64>,
}

impl PairSpace {
    /// The off-diagonal pairs (i < j) of S_γ with `t_j − t_i ≥ min_gap_s`, row-major.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory), [`Error::Interrupted`](crate::Error::Interrupted).
    pub(crate) fn of_loops(loops: &Loops, min_gap_s: f64, interrupt: &Interrupt) -> Result<Self> {
        let mut space = Self::default();
        let first = FirstColumn::new(loops.timestamps_s(), min_gap_s);
        for (k, run) in loops.runs().enumerate() {
            check_every(interrupt, k)?;
            space.push(run.row, run.start, run.end, first.of_row(run.row))?;
        }
        Ok(space)
    }

    /// Adds the columns `start..=end` of row `i` that are ≥ `first_column`, growing fallibly.
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory).
    pub(crate) fn push(&mut self, i: usize, start: usize, end: usize, first_column: usize) -> Result<()> {
        let start = start.max(first_column);
        if start <= end {
            let total = self.len() + (end - start + 1) as u64;
            try_reserve(&mut self.segments, 1, "the pairs to draw from")?;
            try_reserve(&mut self.ends, 1, "the pairs to draw from")?;
            self.segments.push(Segment { row: i as u32, start: start as u32, end: end as u32 });
            self.ends.push(total);
        }
        Ok(())
    }

    /// Number of pairs.
    pub(crate) fn len(&self) -> u64 {
        self.ends.last().copied().unwrap_or(0)
    }

    /// Pair number `k < len()`. O(log segments).
    #[cfg(test)]
    pub(crate) fn pair(&self, k: u64) -> [u32; 2] {
        let s = self.ends.partition_point(|&end| end <= k);
        let before = if s == 0 { 0 } else { self.ends[s - 1] };
        let segment = self.segments[s];
        [segment.row, segment.start + (k - before) as u32]
    }

    /// The pairs at increasing numbers, by one walk over the segments. O(segments + k).
    ///
    /// # Errors
    /// [`Error::OutOfMemory`](crate::Error::OutOfMemory).
    pub(crate) fn pairs_at(&self, sorted: &[u64]) -> Result<Vec<[u32; 2]>> {
        let mut out = try_with_capacity(sorted.len(), "the drawn pairs")?;
        let mut s = 0;
        for &k in sorted {
            while self.ends[s] <= k {
                s += 1;
            }
            let before = if s == 0 { 0 } else { self.ends[s - 1] };
            out.push([self.segments[s].row, self.segments[s].start + (k - before) as u32]);
        }
        Ok(out)
    }

    /// Every number independently with probability `rate` in (0, 1], increasing: geometric
    /// skips, O(drawn).
    pub(crate) fn bernoulli<R: Rng + ?Sized>(&self, rate: f64, rng: &mut R) -> Vec<u64> {
        bernoulli_indices(self.len(), rate, rng)
    }

    /// `count ≤ len()` distinct numbers, uniformly, increasing. O(count) expected.
    pub(crate) fn choose<R: Rng + ?Sized>(&self, count: u64, rng: &mut R) -> Vec<u64> {
        choose_indices(self.len(), count, rng)
    }
}

/// The first column j > i with `t_j − t_i ≥ gap` of each row.
pub(crate) struct FirstColumn<'a> {
    times: &'a [f64],
    gap_s: f64,
}

impl<'a> FirstColumn<'a> {
    pub(crate) fn new(times: &'a [f64], gap_s: f64) -> Self {
        Self { times, gap_s }
    }

    pub(crate) fn of_row(&self, i: usize) -> usize {
        if self.gap_s <= 0.0 {
            return i + 1;
        }
        let t_i = self.times[i];
        let gap = self.gap_s;
        i + 1 + self.times[i + 1..].partition_point(|&t| t - t_i < gap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loops::find_loops;
    use crate::metric::Euclidean;
    use crate::trajectory::Trajectory;

    fn line() -> Trajectory {
        Trajectory::from_points(vec![0.0, 1.0, 2.0, 3.0, 4.0], &[[0.0], [1.0], [2.0], [1.0], [0.0]]).unwrap()
    }

    #[test]
    fn pair_space_numbers_every_pair_once() {
        let traj = line();
        let loops = find_loops(&traj, &Euclidean, 1.0).unwrap();
        let space = PairSpace::of_loops(&loops, 0.0, &Interrupt::new()).unwrap();
        let all: Vec<[u32; 2]> = (0..space.len()).map(|k| space.pair(k)).collect();
        let mut brute = Vec::new();
        for i in 0..5 {
            for j in i + 1..5 {
                if loops.component_of(i, j).is_some() {
                    brute.push([i as u32, j as u32]);
                }
            }
        }
        assert_eq!(all, brute);
        let indices: Vec<u64> = (0..space.len()).collect();
        assert_eq!(space.pairs_at(&indices).unwrap(), brute);
        // With a gap of 2 s only pairs at least two poses apart remain.
        let gapped = PairSpace::of_loops(&loops, 2.0, &Interrupt::new()).unwrap();
        let kept: Vec<[u32; 2]> = (0..gapped.len()).map(|k| gapped.pair(k)).collect();
        assert_eq!(kept, brute.iter().copied().filter(|p| p[1] - p[0] >= 2).collect::<Vec<_>>());
    }
}
