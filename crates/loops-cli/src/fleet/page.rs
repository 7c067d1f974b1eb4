//! The fleet's report, `index.html` of `loops fleet`: one self-contained page (no network, no
//! script) for all sessions, linking each session's own page (`<session>/report.html`, the
//! per-log page of [`crate::report`]), drawn with the report's plotting layer.
//!
//! Summary cards, then two figures and three tables:
//!
//! | element | what |
//! |---|---|
//! | figure `overlap-matrix` | the session-overlap matrix as a heat map: loop area α of every block (a, b), log colour scale, blank where two sessions never come within γ |
//! | figure `fleet-map` | every session's path in the plane, coloured by session, with a ring where each component between two sessions has its closest pair |
//! | `table#between` | the components between sessions, largest first: sessions, time ranges on each session's clock, pairs, area, closest pair and where it lies |
//! | `table#session-pairs` | the sparse overlap matrix as rows (α, ρ, components, pairs) |
//! | `table#sessions` | the sessions, with their own pages |
//!
//! Everything drawn is bounded (paths simplified, at most [`MAX_BINS`] rows of the matrix, at
//! most [`MAX_RINGS`] rings and [`MAX_ROWS`] table rows, said in the captions), so a fleet of
//! thousands of sessions still gives a page of a few MB.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use loops_core::{
    SampleQuality, SamplerKind,
    fleet::{Fleet, FleetComponent, SessionPair},
};
use maud::{Markup, PreEscaped, html};
use percent_encoding::utf8_percent_encode;

use super::FleetSummary;
use crate::report::numbers::{duration_text, percent, plural, thousands};
use crate::report::palette::{sampler_name, session_colour};
use crate::report::svg::{self, PathData, Plot, Rect, Scale, VIRIDIS};
use crate::report::trajectory::{MAX_SEGMENTS, MapPlot, map_axes, map_plot, plane_name, simplify, tau_scale, thin};
use crate::report::{SEGMENT, STYLE, figure, page};

/// The page's own style, after the per-log report's.
const FLEET_STYLE: &str = include_str!("page.css");

/// Rows (and columns) of the overlap matrix at most: a larger fleet's sessions are grouped into
/// this many bins of consecutive sessions.
pub(crate) const MAX_BINS: usize = 100;

/// Session names are written beside the matrix up to this many sessions (indices beyond).
const MAX_NAMED: usize = 40;

/// Rings drawn on the map at most (the largest components between sessions).
pub(crate) const MAX_RINGS: usize = 800;

/// Rows of each table at most (the largest entries).
pub(crate) const MAX_ROWS: usize = 2000;

/// Everything the fleet's page shows. Built by `loops fleet`.
#[derive(Debug)]
pub(crate) struct FleetReportInput<'a> {
    /// The fleet, its sessions named and in order.
    pub fleet: &'a Fleet,
    /// Each session's poses as read (positions for the map).
    pub tables: &'a [loops_io::PoseTable],
    /// The plane the map draws: two position axes.
    pub plane: [usize; 2],
    /// Its components, with sessions and poses ([`FleetLoops::components`](loops_core::fleet::FleetLoops::components)).
    pub components: &'a [FleetComponent],
    /// The sparse overlap matrix ([`FleetLoops::session_pairs`](loops_core::fleet::FleetLoops::session_pairs)).
    pub pairs: &'a [SessionPair],
    /// Their sampler.
    pub sampler: SamplerKind,
    /// Their quality against every component of the fleet.
    pub quality: &'a SampleQuality,
    /// summary.json: settings, counts, the sessions' pages.
    pub summary: &'a FleetSummary<'a>,
}

/// The page, as one HTML string: self-contained (inline CSS and figures, no script; links only
/// to the sessions' pages beside it).
///
/// Never panics on a valid fleet's input, including one session, no component between sessions,
/// no sample, and every pose at one place.
pub(crate) fn render(input: &FleetReportInput<'_>) -> String {
    let n = input.fleet.len();
    let title = html! { "Fleet of " (plural(n, "session", "sessions")) " — inexact loops" };
    let style = html! { (PreEscaped(STYLE)) (PreEscaped(FLEET_STYLE)) };
    let s = input.summary;
    let body = html! {
        main {
            header {
                h1 { "Fleet: " (plural(n, "session", "sessions")) }
                p.source {
                    "γ = " (s.settings.gamma) " (" (s.settings.metric) ") · " (thousands(s.poses as u64)) " poses · results in " (s.out)
                }
            }
            (cards(input))
            (warnings(input))
            section.figures {
                (overlap_figure(input))
                (map_figure(input))
            }
            (between_section(input))
            (pairs_section(input))
            (sessions_section(input))
            footer {
                "Written by loops " (env!("CARGO_PKG_VERSION"))
                " · inexact loops after E. Nelson, “Inexact Loops in Robotics Problems”."
            }
        }
    };
    page(title, style, body)
}

/// The summary cards: the fleet, its loops, its samples.
fn cards(input: &FleetReportInput<'_>) -> Markup {
    let s = input.summary;
    let n = input.fleet.len();
    let total_s: f64 = (0..n).map(|a| input.fleet.session(a).span_s()).sum();
    let possible = n * n.saturating_sub(1) / 2;
    let between_pairs: u64 = input.pairs.iter().filter(|p| p.sessions[0] != p.sessions[1]).map(|p| p.pair_count).sum();
    let within_nontrivial = input.components.iter().filter(|c| c.sessions[0] == c.sessions[1] && !c.trivial).count();
    html! {
        section.cards {
            div.card {
                h2 { "Fleet" }
                dl {
                    dt { "sessions" } dd { (n) }
                    dt { "poses" } dd { (thousands(s.poses as u64)) }
                    dt { "time, all sessions" } dd { (duration_text(total_s)) }
                    dt { "metric" } dd { code { (s.settings.metric) } }
                    dt { "γ" } dd { (s.settings.gamma) }
                    dt { "separation" }
                    dd {
                        @if s.settings.separation.path == 0.0 && s.settings.separation.time_s == 0.0 {
                            "none " span.muted { "(trivial components included)" }
                        } @else {
                            (separation_text(s)) span.muted { " within a session; pairs of two sessions all kept" }
                        }
                    }
                    dt { "pruning" } dd { (s.pruning) }
                    dt { "map plane" } dd { (plane_name(input.plane)) }
                }
            }
            div.card {
                h2 { "Loops" }
                dl {
                    dt { "within sessions" }
                    dd { b { (s.within_components) } " components (" (within_nontrivial) " non-trivial)" }
                    dt { "between sessions" } dd { b { (s.between_components) } " components" }
                    dt { "session pairs that meet" }
                    dd { (s.overlapping_session_pairs) " of " (possible) span.muted { " (" (percent(s.overlapping_session_pairs, possible)) ")" } }
                    dt { "pairs between sessions" } dd { (thousands(between_pairs)) }
                }
            }
            div.card {
                h2 { "Samples" }
                dl {
                    dt { "sampler" } dd { (sampler_name(input.sampler)) }
                    dt { "samples" }
                    dd {
                        (thousands(s.samples as u64)) " (" (s.settings.sample_size) ", seed " (s.settings.seed) ")"
                        @if s.between_only { span.muted { " between sessions only" } }
                    }
                    dt { "between sessions" } dd { (thousands(s.between_samples as u64)) }
                    dt { "P1 between sessions" }
                    dd { b { (s.between_covered) " / " (s.between_components) } span.muted { " components hold a sample" } }
                    dt { "P1 all non-trivial" }
                    dd { (input.quality.nontrivial_covered) " / " (input.quality.nontrivial_components) }
                    dt { "P2 redundant" } dd { (s.quality.redundant) span.muted { " (within ε = " (s.settings.epsilon_s) " s of another)" } }
                    dt { "files" }
                    dd { @for f in &s.files { code { (f) } " " } }
                }
            }
        }
    }
}

/// The separation within a session, as the cards print it (`pairs ≥ 160 apart along the path`).
fn separation_text(s: &FleetSummary<'_>) -> String {
    let mut parts = Vec::new();
    if s.settings.separation.path > 0.0 {
        parts.push(format!("≥ {} apart along the path", s.settings.separation.path));
    }
    if s.settings.separation.time_s > 0.0 {
        parts.push(format!("≥ {} s apart", s.settings.separation.time_s));
    }
    format!("pairs {}", parts.join(" and "))
}

/// The fleet's warnings and the sessions whose page failed.
fn warnings(input: &FleetReportInput<'_>) -> Markup {
    let s = input.summary;
    let failed: Vec<_> = s.pages.iter().filter(|p| !p.ok).collect();
    html! {
        @if !s.warnings.is_empty() || !failed.is_empty() {
            section.warnings {
                h2 { "Warnings" }
                ul {
                    @for w in &s.warnings { li { (w) } }
                    @for p in &failed { li { "session " (p.name) ": its page failed: " (p.error.as_deref().unwrap_or("unknown error")) } }
                }
            }
        }
    }
}

/// A matrix cell: α summed over the session pairs in it, and their counts.
#[derive(Debug, Default, Clone, Copy)]
struct Cell {
    area_s2: f64,
    components: usize,
    pair_count: u64,
    density: f64,
}

/// Figure: the session-overlap matrix as a heat map of α.
fn overlap_figure(input: &FleetReportInput<'_>) -> Markup {
    let n = input.fleet.len();
    let bins = n.min(MAX_BINS);
    let bin = |s: usize| s * bins / n;
    let mut cells: BTreeMap<(usize, usize), Cell> = BTreeMap::new();
    for p in input.pairs {
        let (r, c) = (bin(p.sessions[0]), bin(p.sessions[1]));
        let cell = cells.entry((r.min(c), r.max(c))).or_default();
        cell.area_s2 += p.area_s2;
        cell.components += p.components;
        cell.pair_count += p.pair_count;
        cell.density = cell.density.max(p.density);
    }
    let values: Vec<f64> = cells.values().map(|c| c.area_s2).filter(|a| *a > 0.0 && a.is_finite()).collect();
    let scale = tau_scale(&values);
    let named = bins == n && n <= MAX_NAMED;
    let short = |name: &str| -> String {
        if name.chars().count() > 18 { name.chars().take(17).collect::<String>() + "…" } else { name.to_owned() }
    };
    let longest =
        if named { input.fleet.names().iter().map(|s| short(s).chars().count()).max().unwrap_or(1) } else { 4 };
    let margin = 14.0 + 6.6 * longest as f64;
    let cell = (520.0 / bins as f64).clamp(3.0, 36.0);
    let side = cell * bins as f64;
    let area = Rect { left: margin, top: margin.max(24.0), width: side, height: side };
    let mut plot = Plot::new(
        "fig-overlap",
        area.right() + 120.0,
        area.bottom() + 36.0,
        area,
        Scale::linear(0.0, bins as f64),
        Scale::linear(0.0, bins as f64),
    );
    plot.background("#f1f3f6");
    let mut rects = String::new();
    let names = input.fleet.names();
    let escape = |text: &str| html! { (text) }.into_string();
    for (&(r, c), entry) in &cells {
        let colour =
            if entry.area_s2 > 0.0 { svg::hex(VIRIDIS.at(scale.map(entry.area_s2))) } else { "#d9dde3".into() };
        let title = if bins == n {
            format!(
                "{} × {}: α = {:.1} s², ρ = {:.4}, {}, {} pairs",
                names[r],
                names[c],
                entry.area_s2,
                entry.density,
                plural(entry.components, "component", "components"),
                entry.pair_count
            )
        } else {
            format!(
                "bins {r} × {c}: α = {:.1} s², {}",
                entry.area_s2,
                plural(entry.components, "component", "components")
            )
        };
        for (row, column) in if r == c { vec![(r, c)] } else { vec![(r, c), (c, r)] } {
            let _ = write!(
                rects,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.2}\" height=\"{:.2}\" fill=\"{colour}\" class=\"cell{}\"><title>{}</title></rect>",
                area.left + column as f64 * cell,
                area.top + row as f64 * cell,
                cell,
                cell,
                if row == column { " self" } else { "" },
                escape(&title)
            );
        }
    }
    plot.push_clipped(&rects);
    // Labels: session names (rows on the left, columns above, slanted), or session indices.
    let mut labels = String::new();
    if named {
        for (k, name) in names.iter().enumerate() {
            let middle = (k as f64 + 0.5) * cell;
            let _ = write!(
                labels,
                "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\" class=\"session-label\">{}</text>\
                 <text transform=\"translate({:.1} {:.1}) rotate(-45)\" class=\"session-label\">{}</text>",
                area.left - 5.0,
                area.top + middle + 4.0,
                escape(&short(name)),
                area.left + middle + 3.0,
                area.top - 5.0,
                escape(&short(name))
            );
        }
    } else {
        let step = ((n as f64 / 8.0).ceil() as usize).max(1);
        for k in (0..n).step_by(step) {
            let at = k as f64 / n as f64 * side;
            let _ = write!(
                labels,
                "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\" class=\"session-label\">{k}</text>\
                 <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" class=\"session-label\">{k}</text>",
                area.left - 5.0,
                area.top + at + 4.0,
                area.left + at,
                area.top - 6.0,
            );
        }
    }
    let _ = write!(
        labels,
        "<rect x=\"{}\" y=\"{}\" width=\"{side}\" height=\"{side}\" class=\"frame\"/>",
        area.left, area.top
    );
    plot.body_mut().push_str(&labels);
    plot.colour_bar(VIRIDIS, scale, "loop area α (s²)", &[]);
    let svg = plot.finish("The session-overlap matrix: loop area α between every two sessions");
    let possible = n * n.saturating_sub(1) / 2;
    let caption = html! {
        b { "Session-overlap matrix." }
        " Cell (a, b) is the loop area α of the block a × b: the time area, in s², of the pairs (t in session a, t′ in \
        session b) within γ = " (input.summary.settings.gamma) ". Off the diagonal: where two sessions overlap, symmetric; on \
        it (outlined): each session alone, its own revisits. Blank: never within γ. "
        (input.summary.overlapping_session_pairs) " of " (possible) " session pairs meet. Colour scale "
        @if scale.kind() == svg::ScaleKind::Log { "logarithmic" } @else { "linear" } "."
        @if bins < n {
            " The " (n) " sessions are grouped into " (bins) " bins of consecutive sessions (in fleet order); a cell \
            sums α over its sessions."
        } @else if !named {
            " Rows and columns are the sessions in fleet order (by index; the sessions table names them); hover a cell \
            for its numbers."
        } @else {
            " Hover a cell for its numbers."
        }
    };
    figure("overlap-matrix", &svg, caption)
}

/// Figure: every session's path, coloured by session, with rings where sessions overlap.
fn map_figure(input: &FleetReportInput<'_>) -> Markup {
    let n = input.fleet.len();
    let positions: Vec<[f64; 3]> = input.tables.iter().flat_map(|t| t.positions.iter().copied()).collect();
    let MapPlot { mut plot, pixels } = map_plot("fig-fleet", &positions, input.plane, 24.0);
    plot.background("#ffffff");
    plot.grid(6, 6);
    let budget = (MAX_SEGMENTS / n.max(1)).max(40);
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0);
    for table in input.tables {
        offsets.push(offsets[offsets.len() - 1] + table.positions.len());
    }
    let mut drawn = String::new();
    let mut segments = 0;
    for (k, w) in offsets.windows(2).enumerate() {
        let session = &pixels[w[0]..w[1]];
        let kept = thin(simplify(session, |_| false, 0.5), budget);
        let mut path = PathData::default();
        for pair in kept.windows(2) {
            path.segment(session[pair[0]], session[pair[1]]);
        }
        segments += kept.len().saturating_sub(1);
        let colour = svg::hex(session_colour(k, n));
        drawn.push_str(&path.element(&format!("stroke=\"{colour}\" class=\"session-track\"")));
    }
    let mut between: Vec<&FleetComponent> =
        input.components.iter().filter(|c| c.sessions[0] != c.sessions[1]).collect();
    between.sort_by(|x, y| y.area_s2.total_cmp(&x.area_s2).then(x.id.cmp(&y.id)));
    let rings: Vec<(f64, f64)> = between
        .iter()
        .take(MAX_RINGS)
        .filter_map(|c| pixels.get(offsets[c.sessions[0]] + c.closest_pair[0]).copied())
        .collect();
    let mut ring_paths = String::new();
    for &(x, y) in &rings {
        let _ = write!(ring_paths, "M{x:.1} {y:.1}m-5 0a5 5 0 1 0 10 0a5 5 0 1 0 -10 0");
    }
    if !ring_paths.is_empty() {
        let _ = write!(
            drawn,
            "<path d=\"{ring_paths}\" class=\"overlap-halo\"/><path d=\"{ring_paths}\" class=\"overlap\"/>"
        );
    }
    plot.push_clipped(&drawn);
    map_axes(&mut plot, input.plane);
    let plane = plane_name(input.plane);
    let svg =
        plot.finish(&format!("Every session's path in {plane}, coloured by session, rings where sessions overlap"));
    let legend = html! {
        @if n <= MAX_NAMED {
            table.legend {
                thead { tr { th {} th { "session" } th { "poses" } th { "between sessions" } } }
                tbody {
                    @for (k, name) in input.fleet.names().iter().enumerate() {
                        tr {
                            td { i.swatch style={ "background: " (svg::hex(session_colour(k, n))) } {} }
                            td { (name) }
                            td { (thousands(input.fleet.session(k).len() as u64)) }
                            td { (input.summary.sessions[k].between_components) }
                        }
                    }
                }
            }
        }
    };
    let caption = html! {
        b { "The sessions in one frame." }
        " Each session's path in " (plane) ", one colour per session"
        @if n > 10 { " (hues a golden angle apart in fleet order)" }
        ", drawn as " (plural(segments, "segment", "segments")) " (simplified to the figure's resolution). Rings: \
        the closest pair of each component between two sessions, at the pose of the earlier session"
        @if between.len() > rings.len() { " (the " (rings.len()) " largest of " (between.len()) ")" }
        "; the table below lists where each lies."
        (legend)
    };
    figure("fleet-map", &svg, caption)
}

/// Column names of the components between sessions (as in the fleet's components.csv, plus
/// the position of the closest pair), and what they mean.
const BETWEEN_COLUMNS: [(&str, &str); 14] = [
    ("id", "component id, as in components.csv"),
    ("name_a", "the earlier session in fleet order (rows, t)"),
    ("name_b", "the later session (columns, t′)"),
    ("t_min_s", "first t, seconds on session a's clock"),
    ("t_max_s", "last t, seconds on session a's clock"),
    ("t_prime_min_s", "first t′, seconds on session b's clock"),
    ("t_prime_max_s", "last t′, seconds on session b's clock"),
    ("pair_count", "pose pairs within γ"),
    ("area_s2", "area in the block, s²"),
    ("closest_distance", "δ at the closest pair"),
    ("closest_i", "pose of session a at the closest pair"),
    ("closest_j", "pose of session b at the closest pair"),
    ("where", "position of session a's pose at the closest pair, in the map's plane"),
    ("samples", "samples of the fleet's sampler in the component"),
];

/// The components between sessions, largest first.
fn between_section(input: &FleetReportInput<'_>) -> Markup {
    let mut between: Vec<&FleetComponent> =
        input.components.iter().filter(|c| c.sessions[0] != c.sessions[1]).collect();
    between.sort_by(|x, y| y.area_s2.total_cmp(&x.area_s2).then(x.id.cmp(&y.id)));
    let total = between.len();
    between.truncate(MAX_ROWS);
    let names = input.fleet.names();
    let [u, v] = input.plane;
    let time = |session: usize, pose: usize| input.fleet.session(session).timestamps_s().get(pose).copied();
    let place = |c: &FleetComponent| {
        let p = input.tables.get(c.sessions[0]).and_then(|t| t.positions.get(c.closest_pair[0]))?;
        Some(format!("({:.1}, {:.1})", p.get(u)?, p.get(v)?))
    };
    let seconds = |t: Option<f64>| t.map_or("—".to_owned(), |t| format!("{t:.1}"));
    html! {
        section.between {
            h2 { "Where sessions overlap" }
            p.note {
                (plural(total, "component", "components")) " between two sessions, largest area first; times on each \
                session's own clock."
                @if total > between.len() {
                    b { " Only the " (MAX_ROWS) " largest are listed" } " (components.csv has every one)."
                }
            }
            div.table-wrap {
                table #between .data {
                    thead { tr { @for (name, title) in BETWEEN_COLUMNS { th title=(title) { (name) } } } }
                    tbody {
                        @for c in &between {
                            @let [a, b] = c.sessions;
                            tr {
                                td { (c.id) }
                                td.name { (names[a]) }
                                td.name { (names[b]) }
                                td { (seconds(time(a, c.poses[0][0]))) }
                                td { (seconds(time(a, c.poses[0][1]))) }
                                td { (seconds(time(b, c.poses[1][0]))) }
                                td { (seconds(time(b, c.poses[1][1]))) }
                                td { (c.pair_count) }
                                td { (format!("{:.1}", c.area_s2)) }
                                td { (format!("{:.3}", c.closest_distance)) }
                                td { (c.closest_pair[0]) }
                                td { (c.closest_pair[1]) }
                                td { (place(c).unwrap_or_else(|| "—".to_owned())) }
                                td { (input.quality.per_component.get(c.id).copied().unwrap_or(0)) }
                            }
                        }
                    }
                }
            }
        }
    }
}

/// The sparse overlap matrix as rows, largest α first.
fn pairs_section(input: &FleetReportInput<'_>) -> Markup {
    let mut pairs: Vec<&SessionPair> = input.pairs.iter().collect();
    pairs.sort_by(|x, y| y.area_s2.total_cmp(&x.area_s2).then(x.sessions.cmp(&y.sessions)));
    let total = pairs.len();
    pairs.truncate(MAX_ROWS);
    let names = input.fleet.names();
    html! {
        section.pairs {
            h2 { "Session pairs" }
            p.note {
                "The overlap matrix's entries (session_pairs.csv), largest loop area first: every pair of sessions, and \
                every session alone, with a loop component. ρ = α / (T" sub { "a" } " T" sub { "b" } "), the share of \
                the block within γ."
                @if total > pairs.len() { b { " Only the " (MAX_ROWS) " largest of " (total) " are listed." } }
            }
            div.table-wrap {
                table #session-pairs .data {
                    thead {
                        tr {
                            th { "name_a" } th { "name_b" } th { "components" } th { "pair_count" }
                            th { "area_s2" } th { "density" }
                        }
                    }
                    tbody {
                        @for p in &pairs {
                            tr class=[(p.sessions[0] == p.sessions[1]).then_some("self")] {
                                td.name { (names[p.sessions[0]]) }
                                td.name { (names[p.sessions[1]]) }
                                td { (p.components) }
                                td { (p.pair_count) }
                                td { (format!("{:.1}", p.area_s2)) }
                                td { (format!("{:.5}", p.density)) }
                            }
                        }
                    }
                }
            }
        }
    }
}

/// The sessions, linking each one's own page.
fn sessions_section(input: &FleetReportInput<'_>) -> Markup {
    let s = input.summary;
    html! {
        section.sessions {
            h2 { "Sessions" }
            p.note {
                "Each session's own page is what " code { "loops run" } " writes for that log alone: its loops, with \
                the same γ and separation, and its own sampling with the same sampler and budget."
            }
            div.table-wrap {
                table #sessions .data {
                    thead {
                        tr {
                            th { "session" } th { "source" } th { "poses" } th { "t0_s" } th { "span_s" }
                            th { "within" } th { "between" } th { "samples" } th { "page" }
                        }
                    }
                    tbody {
                        @for (k, r) in s.sessions.iter().enumerate() {
                            @let ok = s.pages.get(k).is_some_and(|p| p.ok);
                            tr {
                                td.name {
                                    i.swatch style={ "background: " (svg::hex(session_colour(k, s.sessions.len()))) } {}
                                    @if ok {
                                        a href={ (utf8_percent_encode(&r.name, SEGMENT)) "/report.html" } { (r.name) }
                                    } @else {
                                        (r.name)
                                    }
                                }
                                td.name { (r.source) }
                                td { (r.poses) }
                                td { (format!("{:.1}", r.t0_s)) }
                                td { (format!("{:.1}", r.span_s)) }
                                td { (r.within_components) }
                                td { (r.between_components) }
                                td { (r.samples) }
                                td { @if ok { "ok" } @else { span.bad { "failed" } } }
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use loops_core::{
        DEFAULT_EPSILON_S, Euclidean, SampleSize, Sampler, Separation, Trajectory, UrbanDrive, UrbanFleet,
        fleet::{FleetOptions, find_fleet_loops, sample_fleet},
        sample_quality,
    };
    use loops_io::{PoseTable, QualitySummary};

    use super::*;
    use crate::fleet::{FleetSeconds, session_summaries};
    use crate::report::table_of;
    use crate::run::SettingsSummary;

    /// The page of a fleet of `sessions` at `gamma` (no session pages written).
    fn page_of(sessions: Vec<(String, Trajectory)>, gamma: f64, budget: usize) -> (String, usize) {
        let fleet = Fleet::new(sessions).unwrap();
        let options = FleetOptions { separation: Separation::for_gamma(gamma), ..FleetOptions::default() };
        let loops = find_fleet_loops(&fleet, &Euclidean, gamma, &options).unwrap();
        let sampler = Sampler::new(SamplerKind::Rho, SampleSize::Budget(budget), 0);
        let samples = sample_fleet(&fleet, &Euclidean, &loops, &sampler, false).unwrap();
        let quality = sample_quality(&samples, loops.loops(), DEFAULT_EPSILON_S).unwrap();
        let localized = fleet.localize(&samples).unwrap();
        let components = loops.components();
        let pairs = loops.session_pairs();
        let tables: Vec<PoseTable> = (0..fleet.len()).map(|a| table_of(fleet.session(a), "session.tum")).collect();
        let sources: Vec<String> = fleet.names().iter().map(|n| format!("logs/{n} <&>.tum")).collect();
        let between = components.iter().filter(|c| c.sessions[0] != c.sessions[1]).count();
        let summary = FleetSummary {
            out: "results".into(),
            poses: fleet.poses(),
            settings: SettingsSummary::new("euclidean".into(), gamma, options.separation, &sampler, DEFAULT_EPSILON_S),
            pruning: loops.pruning().name(),
            components: components.len(),
            within_components: components.len() - between,
            between_components: between,
            overlapping_session_pairs: pairs.iter().filter(|p| p.sessions[0] != p.sessions[1]).count(),
            between_only: false,
            samples: samples.len(),
            between_samples: localized.iter().filter(|s| s.sessions[0] != s.sessions[1]).count(),
            quality: QualitySummary::new(SamplerKind::Rho, &quality),
            between_covered: 0,
            sessions: session_summaries(&fleet, &sources, &components, &localized),
            warnings: vec!["a warning <b>".into()],
            seconds: FleetSeconds::default(),
            files: vec!["index.html"],
            pages: &[],
        };
        let html = render(&FleetReportInput {
            fleet: &fleet,
            tables: &tables,
            plane: [0, 1],
            components: &components,
            pairs: &pairs,
            sampler: SamplerKind::Rho,
            quality: &quality,
            summary: &summary,
        });
        (html, between)
    }

    fn assert_well_formed(html: &str) {
        assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
        for name in ["overlap-matrix", "fleet-map"] {
            assert_eq!(html.matches(&format!("class=\"figure\" data-figure=\"{name}\"")).count(), 1, "{name}");
        }
        for table in ["between", "session-pairs", "sessions"] {
            assert_eq!(html.matches(&format!(" id=\"{table}\"")).count(), 1, "{table}");
        }
        assert!(!html.contains("http:") && !html.contains("https:"), "no network references");
        assert!(!html.contains("<script") && !html.contains("<link"));
        for bad in ["NaN", ">inf", "\"inf", " inf", "-inf"] {
            assert!(!html.contains(bad), "no non-finite numbers: {bad}");
        }
        assert!(!html.contains("<&>") && !html.contains("a warning <b>"), "text is escaped");
        assert!(html.contains("a warning &lt;b&gt;") && html.contains("&lt;&amp;&gt;.tum"));
    }

    /// The rows of a table's body.
    fn rows<'a>(html: &'a str, id: &str) -> Vec<&'a str> {
        let start = html.find(&format!(" id=\"{id}\"")).expect("the table");
        let body = &html[start..];
        let body = &body[body.find("<tbody>").unwrap()..body.find("</tbody>").unwrap()];
        body.split("<tr").skip(1).collect()
    }

    #[test]
    fn a_fleet_gives_both_figures_and_a_row_per_overlap() {
        let spec = UrbanFleet {
            vehicles: 3,
            days: 1,
            drive: UrbanDrive { duration_s: 300.0, seed: 2, ..UrbanDrive::default() },
            ..UrbanFleet::default()
        };
        let fleet = spec.generate().unwrap();
        let sessions = (0..fleet.len()).map(|a| (fleet.names()[a].clone(), fleet.session(a).clone())).collect();
        let (html, between) = page_of(sessions, 40.0, 200);
        assert_well_formed(&html);
        assert!(between > 0);
        assert_eq!(rows(&html, "between").len(), between);
        assert_eq!(rows(&html, "sessions").len(), 3);
        assert!(html.contains("car0-day0 × car1-day0") || html.contains("car0-day0 × car2-day0"));
        assert!(html.len() < 1_000_000, "{} bytes", html.len());
    }

    #[test]
    fn one_session_and_no_overlap_render() {
        let points: Vec<[f64; 2]> = (0..30).map(|i| [10.0 * f64::from(i), 0.0]).collect();
        let line = Trajectory::from_points((0..30).map(f64::from).collect(), &points).unwrap();
        let (html, between) = page_of(vec![("alone".into(), line.clone())], 1.0, 5);
        assert_well_formed(&html);
        assert_eq!((between, rows(&html, "between").len()), (0, 0));
        // Every pose at one place, in two sessions: each pair of them meets.
        let still = Trajectory::from_points(vec![0.0, 1.0, 2.0], &[[3.0, -2.0]; 3]).unwrap();
        let later = Trajectory::from_points(vec![50.0, 51.0], &[[3.0, -2.0]; 2]).unwrap();
        let (html, between) = page_of(vec![("still".into(), still), ("later".into(), later)], 1.0, 5);
        assert_well_formed(&html);
        assert_eq!(between, 1);
    }

    #[test]
    fn many_sessions_are_binned_and_bounded() {
        let n = 2 * MAX_BINS + 30;
        let sessions: Vec<(String, Trajectory)> = (0..n)
            .map(|k| {
                let t0 = 10.0 * k as f64;
                let x = (k % 7) as f64;
                (format!("s{k}"), Trajectory::from_points(vec![t0, t0 + 1.0], &[[x, 0.0], [x + 0.5, 0.0]]).unwrap())
            })
            .collect();
        let (html, between) = page_of(sessions, 1.0, 50);
        assert_well_formed(&html);
        assert!(between > MAX_ROWS / 2);
        assert!(html.contains("are grouped into 100 bins"));
        let cells = html.matches("class=\"cell").count();
        assert!(cells <= MAX_BINS * MAX_BINS, "{cells} cells");
        assert!(rows(&html, "between").len() <= MAX_ROWS);
        assert!(html.len() < 5_000_000, "{} bytes", html.len());
    }
}
