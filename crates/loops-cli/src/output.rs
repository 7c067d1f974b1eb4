//! What `loops` prints and writes: the terminal table, the JSON report, atomic file writes.

use std::io::Write;

use anyhow::Result;
use loops_core::{LoopComponent, Loops, Scale, Selection, Side, Trajectory};
use serde::Serialize;

/// The summary line and the components table, largest area first, at most `limit` rows (0: all).
pub(crate) fn write_table(
    out: &mut impl Write,
    source: &str,
    traj: &Trajectory,
    loops: &Loops,
    seconds: f64,
    limit: usize,
) -> Result<()> {
    let components = loops.components();
    let nontrivial = components.iter().filter(|c| !c.trivial).count();
    let density = loops.loop_density(
        traj.timestamps_s()[0],
        traj.timestamps_s()[traj.len() - 1],
        Selection::All,
        Side::Both,
        Scale::Seconds,
    )?;
    writeln!(out, "{source}")?;
    let t0 = traj.timestamps_s()[0];
    writeln!(
        out,
        "  {} poses over {:.1} s; gamma {} ({}): {} components ({} non-trivial), {} pairs, \
         mean loop duration {:.1} s; {:.3} s",
        traj.len(),
        traj.span_s(),
        loops.gamma(),
        loops.metric(),
        components.len(),
        nontrivial,
        loops.pairs(),
        density,
        seconds
    )?;
    let mut order: Vec<&LoopComponent> = components.iter().collect();
    order.sort_by(|a, b| b.area_s2.total_cmp(&a.area_s2).then(a.id.cmp(&b.id)));
    let shown = if limit == 0 { order.len() } else { limit.min(order.len()) };
    writeln!(out, "  times in seconds from the first pose (t0 = {t0})")?;
    writeln!(
        out,
        "{:>6} {:>7} {:>12} {:>10} {:>5}  {:>21}  {:>21}  {:>10}",
        "id", "trivial", "area_s2", "pairs", "holes", "t range (s)", "t' range (s)", "closest"
    )?;
    let t: Vec<f64> = traj.timestamps_s().iter().map(|t| t - t0).collect();
    for c in &order[..shown] {
        writeln!(
            out,
            "{:>6} {:>7} {:>12.1} {:>10} {:>5}  {:>10.1}–{:<10.1}  {:>10.1}–{:<10.1}  {:>10.3}",
            c.id,
            if c.trivial { "yes" } else { "no" },
            c.area_s2,
            c.pairs,
            c.holes,
            t[c.rows[0]],
            t[c.rows[1]],
            t[c.columns[0]],
            t[c.columns[1]],
            c.closest_distance
        )?;
    }
    if shown < order.len() {
        writeln!(out, "  ... {} more (--limit 0 shows all)", order.len() - shown)?;
    }
    Ok(())
}

#[derive(Serialize)]
struct JsonReport<'a> {
    source: &'a str,
    poses: usize,
    span_s: f64,
    gamma: f64,
    metric: &'a str,
    pairs: u64,
    loop_density_s: f64,
    warnings: Vec<String>,
    components: Vec<JsonComponent>,
}

#[derive(Serialize)]
struct JsonComponent {
    id: usize,
    trivial: bool,
    area_s2: f64,
    pairs: u64,
    runs: usize,
    holes: u64,
    t_range_s: [f64; 2],
    t_prime_range_s: [f64; 2],
    index_range: [usize; 2],
    index_prime_range: [usize; 2],
    closest_pair: [usize; 2],
    closest_distance: f64,
}

/// The result as a JSON document (every component, by id).
pub(crate) fn json_report(source: &str, traj: &Trajectory, loops: &Loops) -> Result<String> {
    let t = traj.timestamps_s();
    let report = JsonReport {
        source,
        poses: traj.len(),
        span_s: traj.span_s(),
        gamma: loops.gamma(),
        metric: loops.metric(),
        pairs: loops.pairs(),
        loop_density_s: loops.loop_density(t[0], t[t.len() - 1], Selection::All, Side::Both, Scale::Seconds)?,
        warnings: loops.warnings().iter().map(ToString::to_string).collect(),
        components: loops
            .components()
            .iter()
            .map(|c| JsonComponent {
                id: c.id,
                trivial: c.trivial,
                area_s2: c.area_s2,
                pairs: c.pairs,
                runs: c.runs,
                holes: c.holes,
                t_range_s: [t[c.rows[0]], t[c.rows[1]]],
                t_prime_range_s: [t[c.columns[0]], t[c.columns[1]]],
                index_range: c.rows,
                index_prime_range: c.columns,
                closest_pair: c.closest_pair,
                closest_distance: c.closest_distance,
            })
            .collect(),
    };
    Ok(serde_json::to_string_pretty(&report)? + "\n")
}
