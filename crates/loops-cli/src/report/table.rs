//! The components table: one row per loop component, the columns of `components.csv`.

use maud::{Markup, html};

use super::trajectory::{ring_anchor, ringed_components};
use super::{ReportInput, swatch_class};

/// The most rows shown; beyond it, the largest components by area.
pub(super) const MAX_ROWS: usize = 5000;

/// Column names (as in `components.csv`) and what they mean.
const COLUMNS: [(&str, &str); 15] = [
    ("id", "component id (order of first cell, row by row)"),
    ("trivial", "holds diagonal cells (i, i): its pairs are simple loops"),
    ("area_s2", "area in the (t, t′) plane, s² (the half with t ≤ t′)"),
    ("pair_count", "lattice cells (i, j)"),
    ("run_count", "row intervals"),
    ("holes", "holes in the full plane"),
    ("t_min_s", "first t, seconds from the first pose (components.csv: the pose's own time)"),
    ("t_max_s", "last t, seconds from the first pose"),
    ("t_prime_min_s", "first t′, seconds from the first pose"),
    ("t_prime_max_s", "last t′, seconds from the first pose"),
    ("closest_i", "pose index i of the closest pair"),
    ("closest_j", "pose index j of the closest pair"),
    ("closest_distance", "δ at the closest pair"),
    (
        "where",
        "position of pose i of the closest pair in the map's plane (components.csv: closest_i_x, closest_i_y, closest_i_z); a link to its ring on the map",
    ),
    ("samples", "samples of the run's sampler in the component"),
];

/// The section with the table, largest [`MAX_ROWS`] components by area when there are more,
/// shown in id order.
pub(super) fn components_section(input: &ReportInput<'_>) -> Markup {
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
    let nontrivial = components.iter().filter(|c| !c.trivial).count();
    let ringed = ringed_components(input);
    let [u, v] = input.plane;
    let place = |i: usize| {
        let p = input.table.positions.get(i)?;
        Some(format!("({:.1}, {:.1})", p.get(u)?, p.get(v)?))
    };
    html! {
        section.components {
            h2 { "Loop components" }
            p.note {
                (components.len()) " component" @if components.len() != 1 { "s" } " (" (nontrivial)
                " non-trivial), in id order; times in seconds from the first pose (t" sub { "0" } " = " (t0) " s). "
                @if shown.len() < components.len() {
                    b { "Only the " (MAX_ROWS) " largest by area are listed" }
                    " (" (components.len() - shown.len())
                    " smaller ones are left out; components.csv has every one)."
                }
            }
            div.table-wrap {
                table #components {
                    thead { tr { @for (name, title) in COLUMNS { th title=(title) { (name) } } } }
                    tbody {
                        @for &id in &shown {
                            @let c = &components[id];
                            tr class=[c.trivial.then_some("trivial")] {
                                td { i.swatch.(swatch_class(c)) {} (c.id) }
                                td { @if c.trivial { "yes" } @else { "no" } }
                                td { (format!("{:.1}", c.area_s2)) }
                                td { (c.pair_count) }
                                td { (c.run_count) }
                                td { (c.holes) }
                                td { (format!("{:.2}", time(c.i_range[0]))) }
                                td { (format!("{:.2}", time(c.i_range[1]))) }
                                td { (format!("{:.2}", time(c.j_range[0]))) }
                                td { (format!("{:.2}", time(c.j_range[1]))) }
                                td { (c.closest_pair[0]) }
                                td { (c.closest_pair[1]) }
                                td { (format!("{:.3}", c.closest_distance)) }
                                td {
                                    @match (place(c.closest_pair[0]), ringed.binary_search(&id).is_ok()) {
                                        (Some(p), true) => a href={ "#" (ring_anchor(id)) } { (p) },
                                        (Some(p), false) => (p),
                                        (None, _) => "—",
                                    }
                                }
                                td { (input.quality.per_component.get(id).copied().unwrap_or(0)) }
                            }
                        }
                    }
                }
            }
        }
    }
}
