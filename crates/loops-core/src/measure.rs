//! Loop duration τ, loop area α and loop density ρ (paper, Sec. 4, Eqs. 6–8), from runs.

use std::str::FromStr;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::memory::try_filled;
use crate::sublevel::{PhaseTimer, SublevelSet};

/// Which partners t′ of a time t count towards τ(t) (paper, after Eq. 6).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Side {
    /// Every t′: τ over the full symmetric set.
    #[default]
    Both,
    /// Only t′ > t: loops that begin at t.
    Begin,
    /// Only t′ < t: loops that end at t.
    End,
}

impl Side {
    /// The accepted names.
    pub const NAMES: &'static str = "both, begin, end";
}

impl FromStr for Side {
    type Err = Error;

    fn from_str(name: &str) -> Result<Self, Error> {
        match name {
            "both" => Ok(Self::Both),
            "begin" => Ok(Self::Begin),
            "end" => Ok(Self::End),
            _ => Err(Error::UnknownName { kind: "side", name: name.to_owned(), expected: Self::NAMES }),
        }
    }
}

/// The unit of times and measures.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum Scale {
    /// Seconds; τ and ρ in s, α in s².
    #[default]
    Seconds,
    /// The paper's units: time rescaled so the trajectory spans [0, 1]; τ, α, ρ in [0, 1].
    Normalized,
}

/// Which part X of S_γ a measure is taken over.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Selection<'a> {
    /// All of S_γ.
    #[default]
    All,
    /// The union of these components (ids from [`Loops::components`](crate::Loops::components));
    /// a non-trivial component brings its mirror.
    Components(&'a [usize]),
}

/// Rows a task of [`loop_duration_s`] sums at a time.
const ROWS_PER_TAU_TASK: usize = 4096;

/// τ_X(t_i) for every sample i, seconds, from the runs of `set` that `keep` (by index into its
/// runs) selects. O(runs + n).
///
/// Each upper-half run (row r, columns a..=b) adds its time width to τ(r), and by symmetry adds
/// w_r to τ(j) for every column j > r. The diagonal cell (r, r) counts half to `Begin` and half to
/// `End`, so `Begin + End = Both`.
///
/// The rows' own widths are summed in parallel, each row in its order; the columns' shares go
/// into a difference array in row order, on one thread, so that every τ is the same bit for bit
/// on any number of threads.
///
/// A fleet's sessions (the set's breaks) are summed apart: no run crosses a session start, and
/// each session's τ is bit for bit that of the session alone.
pub(crate) fn loop_duration_s(
    cell_widths_s: &[f64],
    set: &SublevelSet,
    keep: impl Fn(usize) -> bool + Sync,
    side: Side,
) -> Result<Vec<f64>> {
    let n = cell_widths_s.len();
    let breaks = set.breaks();
    let prefix = crate::trajectory::prefix_sums_by_session(cell_widths_s, breaks)?;
    let width = |a: usize, b: usize| if a > b { 0.0 } else { (prefix[b] + cell_widths_s[b]) - prefix[a] };
    let is_break = |k: usize| breaks.binary_search(&(k as u32)).is_ok();
    let mut tau = try_filled(n, 0.0, "the loop durations")?;
    let timer = PhaseTimer::start("tau: rows' own widths, parallel");
    tau.par_chunks_mut(ROWS_PER_TAU_TASK).enumerate().for_each(|(task, chunk)| {
        for (r, tau_r) in (task * ROWS_PER_TAU_TASK..).zip(chunk) {
            let w_r = cell_widths_s[r];
            for (index, run) in (set.row_offset(r)..).zip(set.row(r)) {
                if !keep(index) {
                    continue;
                }
                let (a, b) = (run.start as usize, run.end as usize);
                let diagonal = a == r;
                let off_start = if diagonal { r + 1 } else { a };
                *tau_r += match side {
                    Side::Both => width(a, b),
                    Side::Begin => width(off_start, b) + if diagonal { 0.5 * w_r } else { 0.0 },
                    Side::End => {
                        if diagonal {
                            0.5 * w_r
                        } else {
                            0.0
                        }
                    }
                };
            }
        }
    });
    timer.finish();
    if side == Side::Begin {
        return Ok(tau);
    }
    let _timer = PhaseTimer::start("tau: columns' shares in row order, serial");
    // Column contributions as a difference array over j (n + 1 entries), in the room of the
    // prefix sums, which the rows' widths were the last to read: one array of n fewer at the
    // peak, and no fresh pages.
    let mut column_diff = prefix;
    column_diff.fill(0.0);
    for (r, &w_r) in cell_widths_s.iter().enumerate() {
        for (index, run) in (set.row_offset(r)..).zip(set.row(r)) {
            let (a, b) = (run.start as usize, run.end as usize);
            let off_start = if a == r { r + 1 } else { a };
            if off_start <= b && keep(index) {
                column_diff[off_start] += w_r;
                // At a session start the running sum restarts instead.
                if breaks.is_empty() || !is_break(b + 1) {
                    column_diff[b + 1] -= w_r;
                }
            }
        }
    }
    let mut running = 0.0;
    for (k, (t, diff)) in tau.iter_mut().zip(&column_diff).enumerate() {
        if !breaks.is_empty() && is_break(k) {
            running = 0.0;
        }
        running += diff;
        *t += running;
    }
    Ok(tau)
}

/// α_X(a, b) = ∫_a^b τ_X: Σ_i |cell_i ∩ [a, b]| τ(i), seconds in, s² out.
pub(crate) fn integrate_s(tau_s: &[f64], cell_s: impl Fn(usize) -> (f64, f64), a_s: f64, b_s: f64) -> f64 {
    tau_s
        .iter()
        .enumerate()
        .map(|(i, tau)| {
            let (start, end) = cell_s(i);
            let overlap = end.min(b_s) - start.max(a_s);
            if overlap > 0.0 { overlap * tau } else { 0.0 }
        })
        .sum()
}
