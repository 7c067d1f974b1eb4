//! The components table: one row per loop component, the columns of `components.csv`.

use std::fmt::Write as _;

use super::{ReportInput, escape, swatch_class};

/// The most rows shown; beyond it, the largest components by area.
pub(super) const MAX_ROWS: usize = 5000;

/// Column names (as in `components.csv`) and what they mean.
const COLUMNS: [(&str, &str); 14] = [
    ("id", "component id (order of first cell, row by row)"),
    ("trivial", "holds diagonal cells (i, i): its pairs are simple loops"),
    ("area_s2", "area in the (t, t′) plane, s² (the half with t ≤ t′)"),
    ("pairs", "lattice cells (i, j)"),
    ("runs", "row intervals"),
    ("holes", "holes in the full plane"),
    ("t_min_s", "first t, seconds from the first pose (components.csv: the pose's own time)"),
    ("t_max_s", "last t, seconds from the first pose"),
    ("t_prime_min_s", "first t′, seconds from the first pose"),
    ("t_prime_max_s", "last t′, seconds from the first pose"),
    ("closest_i", "pose index i of the closest pair"),
    ("closest_j", "pose index j of the closest pair"),
    ("closest_distance", "δ at the closest pair"),
    ("samples", "samples of the run's sampler in the component"),
];

/// The section with the table, largest [`MAX_ROWS`] components by area when there are more,
/// shown in id order.
pub(super) fn components_section(input: &ReportInput<'_>) -> String {
    let components = input.loops.components();
    let timestamps = input.traj.timestamps_s();
    let t0 = timestamps[0];
    let time = |i: usize| timestamps.get(i).map_or(f64::NAN, |t| t - t0);
    let mut shown: Vec<usize> = (0..components.len()).collect();
    if shown.len() > MAX_ROWS {
        shown.sort_by(|&a, &b| components[b].area_s2.total_cmp(&components[a].area_s2).then(a.cmp(&b)));
        shown.truncate(MAX_ROWS);
        shown.sort_unstable();
    }
    let mut out = String::from("<section class=\"components\"><h2>Loop components</h2><p class=\"note\">");
    let nontrivial = components.iter().filter(|c| !c.trivial).count();
    let _ = write!(
        out,
        "{} component{} ({nontrivial} non-trivial), in id order; times in seconds from the first pose \
         (t<sub>0</sub> = {t0} s). ",
        components.len(),
        if components.len() == 1 { "" } else { "s" },
    );
    if shown.len() < components.len() {
        let _ = write!(
            out,
            "<b>Only the {MAX_ROWS} largest by area are listed</b> ({} smaller ones are left out; components.csv has \
             every one).",
            components.len() - shown.len()
        );
    }
    out.push_str("</p><div class=\"table-wrap\"><table id=\"components\"><thead><tr>");
    for (name, title) in COLUMNS {
        let _ = write!(out, "<th title=\"{}\">{name}</th>", escape(title));
    }
    out.push_str("</tr></thead><tbody>");
    for &id in &shown {
        let c = &components[id];
        let samples = input.quality.per_component.get(id).copied().unwrap_or(0);
        let _ = write!(
            out,
            "<tr{class}><td><i class=\"swatch {swatch}\"></i>{id}</td><td>{trivial}</td>\
             <td>{area:.1}</td><td>{pairs}</td><td>{runs}</td><td>{holes}</td><td>{t_start:.2}</td><td>{t_end:.2}</td>\
             <td>{tp_start:.2}</td><td>{tp_end:.2}</td><td>{ci}</td><td>{cj}</td><td>{distance:.3}</td>\
             <td>{samples}</td></tr>",
            class = if c.trivial { " class=\"trivial\"" } else { "" },
            swatch = swatch_class(c),
            id = c.id,
            trivial = if c.trivial { "yes" } else { "no" },
            area = c.area_s2,
            pairs = c.pairs,
            runs = c.runs,
            holes = c.holes,
            t_start = time(c.rows[0]),
            t_end = time(c.rows[1]),
            tp_start = time(c.columns[0]),
            tp_end = time(c.columns[1]),
            ci = c.closest_pair[0],
            cj = c.closest_pair[1],
            distance = c.closest_distance,
        );
    }
    out.push_str("</tbody></table></div></section>");
    out
}
