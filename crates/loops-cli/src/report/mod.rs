//! `report.html`: one self-contained page per log (no network; figures inline as SVG or PNG).
//!
//! The page has a summary (trajectory, loops, samples and their P1–P3), then four figures and
//! the components table:
//!
//! | `data-figure` | what | module |
//! |---|---|---|
//! | `loop-duration` | x–y path coloured by loop duration τ | [`trajectory`] |
//! | `pairwise-distance` | δ over the (t, t′) plane, γ isocontour, component outlines, samples | [`distance`] |
//! | `sampled-pairs` | each sample as a line between its two poses | [`trajectory`] |
//! | `samples-per-component` | samples per component against area, every sampler compared | [`per_component`] |
//!
//! and `<table id="components">`, one row per component ([`table`]). Every figure is drawn from
//! a bounded amount of data (paths simplified to the figure's resolution, at most 400 × 400
//! distances, capped sample and marker counts, stated in the captions), so a log of 10⁶ poses
//! still gives a page of a few MB, rendered in well under a second.
//!
//! Plotting (scales, ticks, colour maps) is in [`svg`], PNG and base64 in [`png`].

mod distance;
mod per_component;
mod png;
mod svg;
mod table;
mod trajectory;

use std::fmt::Write as _;

pub(crate) use crate::html::escape;

use loops_core::{
    LoopComponent, Loops, MetricSpec, SampleQuality, SamplerKind, Samples, Scale, Selection, Side, Trajectory,
};

use svg::{Marker, Rgb};

/// Everything one log's report shows. Built by `loops run` after the log is processed.
#[derive(Debug)]
pub(crate) struct ReportInput<'a> {
    /// The log's name (its file name), the page title.
    pub name: &'a str,
    /// The log's path as given on the command line.
    pub source: &'a str,
    /// The poses as read (x, y, z positions for drawing; orientations when the file has them).
    pub table: &'a loops_io::PoseTable,
    /// The trajectory the engine ran on (the metric's coordinates).
    pub traj: &'a Trajectory,
    /// The metric, for the downsampled pairwise-distance image.
    pub metric: &'a MetricSpec,
    /// The loop components.
    pub loops: &'a Loops,
    /// Loop duration τ(t_i) of every pose, seconds (Side::Both, Selection::All).
    pub loop_duration_s: &'a [f64],
    /// The samples of the run's sampler (samples.csv).
    pub samples: &'a Samples,
    /// Their quality against the exact components.
    pub quality: &'a SampleQuality,
    /// Every sampler at the same size and seed, for the samples-per-component figure (the run's
    /// own sampler among them).
    pub comparison: &'a [(SamplerKind, SampleQuality)],
    /// ε of P2, seconds.
    pub epsilon_s: f64,
    /// Whether the sampler left out the trivial components.
    pub skip_trivial: bool,
    /// Seconds spent finding the loops.
    pub seconds: f64,
}

/// The page, as one HTML string: self-contained (inline CSS and figures, no script, no link).
///
/// Never panics on a valid run's input, including logs with no non-trivial component, no
/// sample, or every pose at one position.
pub(crate) fn render(input: &ReportInput<'_>) -> String {
    let mut page = String::with_capacity(1 << 20);
    let _ = write!(
        page,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{name} — inexact loops</title><style>{STYLE}{swatches}</style></head><body><main>\
         <header><h1>{name}</h1><p class=\"source\">{source}</p></header>",
        name = escape(input.name),
        source = escape(input.source),
        swatches = swatch_style(),
    );
    page.push_str(&summary(input));
    page.push_str(&warnings(input));
    page.push_str("<section class=\"figures\">");
    page.push_str(&trajectory::loop_duration_figure(input));
    page.push_str(&distance::distance_figure(input));
    page.push_str(&trajectory::sampled_pairs_figure(input));
    page.push_str(&per_component::per_component_figure(input));
    page.push_str("</section>");
    page.push_str(&table::components_section(input));
    let _ = writeln!(
        page,
        "<footer>Written by loops {} · inexact loops after E. Nelson, “Inexact Loops in Robotics Problems”.</footer>\
         </main></body></html>",
        env!("CARGO_PKG_VERSION")
    );
    page
}

/// A figure element the page's tests can find: `class="figure"`, `data-figure="name"`.
fn figure(name: &str, svg: &str, caption: &str) -> String {
    format!("<figure class=\"figure\" data-figure=\"{name}\">{svg}<figcaption>{caption}</figcaption></figure>")
}

/// The sampler's name as HTML: its symbol in the paper, and the name `--sampler` takes.
fn sampler_name(kind: SamplerKind) -> String {
    let symbol = match kind {
        SamplerKind::One => "σ<sub>1</sub>",
        SamplerKind::Rho => "σ<sub>ρ</sub>",
        SamplerKind::RhoDispersed => "σ<sub>ρ</sub> dispersed",
        SamplerKind::Alpha => "σ<sub>α</sub>",
        SamplerKind::LioSam => "LIO-SAM",
        SamplerKind::HdlGraphSlam => "hdl_graph_slam",
        SamplerKind::Cartographer => "Cartographer",
        SamplerKind::TimeGap => "time gap",
    };
    format!("{symbol} <span class=\"cli-name\">({})</span>", kind.name())
}

fn sampler_index(kind: SamplerKind) -> usize {
    SamplerKind::ALL.iter().position(|k| *k == kind).unwrap_or(0)
}

/// One colour per sampler, the same on every page.
fn sampler_colour(kind: SamplerKind) -> Rgb {
    SAMPLER_COLOURS[sampler_index(kind) % SAMPLER_COLOURS.len()]
}

/// One marker shape per sampler, the same on every page.
fn sampler_marker(kind: SamplerKind) -> Marker {
    Marker::ALL[sampler_index(kind) % Marker::ALL.len()]
}

/// Outline colours of non-trivial components: bright on the dark inside of S_γ, none of them
/// red (the samples' colour there).
const OUTLINE_COLOURS: [Rgb; 6] = [
    [0xf2, 0x8e, 0x2b],
    [0x8c, 0xd1, 0x7d],
    [0x4f, 0xd1, 0xe8],
    [0xf1, 0xce, 0x63],
    [0xd4, 0xa6, 0xc8],
    [0xb6, 0x99, 0x2d],
];

/// One colour per sampler (as `SamplerKind::ALL`): the four samplers of the paper far apart.
const SAMPLER_COLOURS: [Rgb; 8] = [
    [0x4e, 0x79, 0xa7],
    [0xf2, 0x8e, 0x2b],
    [0x9c, 0x75, 0x5f],
    [0xe1, 0x57, 0x59],
    [0x59, 0xa1, 0x4f],
    [0xb0, 0x7a, 0xa1],
    [0x76, 0xb7, 0xb2],
    [0x7f, 0x7f, 0x7f],
];

/// The colour of trivial components.
const TRIVIAL_COLOUR: Rgb = [0xc8, 0xd0, 0xdc];

/// A component's colour in the distance figure and the table: grey for trivial ones.
fn component_colour(c: &LoopComponent) -> Rgb {
    if c.trivial { TRIVIAL_COLOUR } else { OUTLINE_COLOURS[c.id % OUTLINE_COLOURS.len()] }
}

/// The class of a component's colour swatch in the table (`kt`, `k0`, `k1`, ...).
fn swatch_class(c: &LoopComponent) -> String {
    if c.trivial { "kt".to_owned() } else { format!("k{}", c.id % OUTLINE_COLOURS.len()) }
}

/// The style of the swatch classes.
fn swatch_style() -> String {
    let mut style = format!(".kt {{ background: {}; }}", svg::hex(TRIVIAL_COLOUR));
    for (k, &colour) in OUTLINE_COLOURS.iter().enumerate() {
        let _ = write!(style, " .k{k} {{ background: {}; }}", svg::hex(colour));
    }
    style
}

/// `7560.0 s (2 h 06 min)`.
fn duration_text(seconds: f64) -> String {
    if !(seconds.is_finite() && seconds >= 60.0) {
        return format!("{seconds:.1} s");
    }
    let minutes = (seconds / 60.0).round() as u64;
    if minutes < 60 {
        format!("{seconds:.1} s ({minutes} min)")
    } else {
        format!("{seconds:.1} s ({} h {:02} min)", minutes / 60, minutes % 60)
    }
}

/// `1 pair`, `2 pairs`.
fn plural(count: usize, one: &str, many: &str) -> String {
    format!("{count} {}", if count == 1 { one } else { many })
}

/// `65,431,618`.
fn thousands(count: impl Into<u64>) -> String {
    let digits = count.into().to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (k, c) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn percent(part: usize, whole: usize) -> String {
    if whole == 0 { "—".to_owned() } else { format!("{:.1} %", 100.0 * part as f64 / whole as f64) }
}

/// The summary cards: trajectory, loops, samples.
fn summary(input: &ReportInput<'_>) -> String {
    let (traj, loops, samples, quality) = (input.traj, input.loops, input.samples, input.quality);
    let t = traj.timestamps_s();
    let span_s = traj.span_s();
    let components = loops.components();
    let nontrivial = components.iter().filter(|c| !c.trivial).count();
    let density = loops
        .loop_density(t[0], t[t.len() - 1], Selection::All, Side::Both, Scale::Seconds)
        .ok()
        .filter(|d| d.is_finite());
    let mut out = String::from("<section class=\"cards\">");

    let _ = write!(
        out,
        "<div class=\"card\"><h2>Trajectory</h2><dl>\
         <dt>poses</dt><dd>{poses}</dd>\
         <dt>time span</dt><dd>{span}</dd>\
         <dt>metric</dt><dd><code>{metric}</code></dd>\
         <dt>γ</dt><dd>{gamma}</dd>\
         </dl></div>",
        poses = thousands(traj.len() as u64),
        span = duration_text(span_s),
        metric = escape(&input.metric.name()),
        gamma = loops.gamma(),
    );

    let _ = write!(
        out,
        "<div class=\"card\"><h2>Loops</h2><dl>\
         <dt>components</dt><dd><b>{nontrivial}</b> non-trivial, {trivial} trivial</dd>\
         <dt>pairs in S<sub>γ</sub></dt><dd>{pairs}</dd>\
         <dt>loop density ρ</dt><dd>{density}</dd>\
         <dt>time to find</dt><dd>{seconds:.3} s</dd>\
         </dl></div>",
        trivial = components.len() - nontrivial,
        pairs = thousands(loops.pairs()),
        density = density.map_or("—".to_owned(), |d| format!(
            "{d:.1} s <span class=\"muted\">(mean loop duration; {:.2} % of the span)</span>",
            100.0 * d / span_s
        )),
        seconds = input.seconds,
    );

    let missed = if quality.missed.is_empty() {
        String::new()
    } else {
        let largest: Vec<String> =
            quality.missed.iter().take(5).map(|m| format!("#{} ({:.0} s²)", m.id, m.area_s2)).collect();
        format!(
            "<dt>missed</dt><dd>{}{}</dd>",
            largest.join(", "),
            if quality.missed.len() > 5 { format!(" and {} more", quality.missed.len() - 5) } else { String::new() }
        )
    };
    let _ = write!(
        out,
        "<div class=\"card\"><h2>Samples</h2><dl>\
         <dt>sampler</dt><dd>{sampler}: <b>{count}</b> samples of {available} candidates{skipped}</dd>\
         <dt>P1 coverage</dt><dd><b>{covered} / {total}</b> components ({coverage}); non-trivial {nt_covered} / {nt_total}</dd>\
         {missed}\
         <dt>P2 redundant</dt><dd><b>{redundant}</b> of {count} ({redundancy}) within ε = {epsilon} s{spacing}</dd>\
         <dt>P3 slope</dt><dd><b>{slope}</b> <span class=\"muted\">(ln samples on ln area, {p3}; \
         σ<sub>1</sub> ≈ 0, σ<sub>α</sub> ≈ 1)</span></dd>{outside}\
         </dl></div>",
        sampler = sampler_name(samples.sampler()),
        count = thousands(samples.len() as u64),
        available = thousands(samples.available()),
        skipped = if input.skip_trivial { " (trivial components skipped)" } else { "" },
        covered = quality.covered,
        total = quality.components,
        coverage = percent(quality.covered, quality.components),
        nt_covered = quality.nontrivial_covered,
        nt_total = quality.nontrivial_components,
        redundant = quality.redundant,
        redundancy = percent(quality.redundant, quality.samples),
        epsilon = input.epsilon_s,
        spacing = quality.median_spacing_s.map_or(String::new(), |s| format!("; median spacing {s:.1} s")),
        slope = quality.p3_slope.map_or("—".to_owned(), |s| format!("{s:.2}")),
        p3 = plural(quality.p3_components, "component", "components"),
        outside = if quality.outside > 0 {
            format!("<dt>outside S<sub>γ</sub></dt><dd>{}</dd>", quality.outside)
        } else {
            String::new()
        },
    );
    out.push_str("</section>");
    out
}

/// The warnings of the loops and of the samples, if any.
fn warnings(input: &ReportInput<'_>) -> String {
    let all: Vec<String> = input
        .loops
        .warnings()
        .iter()
        .map(ToString::to_string)
        .chain(input.samples.warnings().iter().map(ToString::to_string))
        .collect();
    if all.is_empty() {
        return String::new();
    }
    let items: String = all.iter().map(|w| format!("<li>{}</li>", escape(w))).collect();
    format!("<section class=\"warnings\"><h2>Warnings</h2><ul>{items}</ul></section>")
}

const STYLE: &str = r#"
:root { --ink: #1d2330; --muted: #5d6574; --line: #dde1e8; --bg: #f5f6f8; }
* { box-sizing: border-box; }
body { margin: 0; background: var(--bg); color: var(--ink);
  font: 15px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
main { max-width: 1500px; margin: 0 auto; padding: 22px 28px 40px; }
h1 { font-size: 26px; margin: 0; overflow-wrap: anywhere; }
h2 { font-size: 18px; margin: 26px 0 8px; }
code, .source { font-family: ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; font-size: 13px; }
.source { color: var(--muted); margin: 2px 0 16px; overflow-wrap: anywhere; }
.muted, .cli-name { color: var(--muted); }
.cli-name { font-size: 12px; }
.cards { display: grid; grid-template-columns: repeat(auto-fit, minmax(min(320px, 100%), 1fr)); gap: 14px; }
.card { background: #fff; border: 1px solid var(--line); border-radius: 8px; padding: 12px 16px; }
.card h2 { font-size: 12px; text-transform: uppercase; letter-spacing: .07em; color: var(--muted); margin: 0 0 6px; }
.card dl { display: grid; grid-template-columns: max-content 1fr; gap: 3px 14px; margin: 0; }
.card dt { color: var(--muted); }
.card dd { margin: 0; font-variant-numeric: tabular-nums; }
.warnings { background: #fff7e6; border: 1px solid #f1c36b; border-radius: 8px; padding: 6px 16px; margin-top: 14px; }
.warnings h2 { font-size: 14px; margin: 6px 0 2px; }
.warnings ul { margin: 4px 0 8px; padding-left: 20px; }
.figures { display: grid; grid-template-columns: repeat(auto-fit, minmax(min(600px, 100%), 1fr)); gap: 16px; margin-top: 16px; }
figure.figure { margin: 0; background: #fff; border: 1px solid var(--line); border-radius: 8px; padding: 12px 16px; }
figure svg { display: block; width: 100%; max-width: 760px; height: auto; margin: 0 auto; }
figcaption { font-size: 13.5px; color: #39404d; margin-top: 8px; }
svg text { font-size: 12px; fill: #454c5a; }
svg text.label { font-size: 13px; fill: var(--ink); }
.grid { fill: none; stroke: #eceff3; }
.frame { fill: none; stroke: #9aa2b0; }
.tick { fill: none; stroke: #9aa2b0; }
.bar { stroke: #9aa2b0; stroke-width: .5; }
.mark { stroke: #e4572e; stroke-width: 2; }
svg text.mark-label { fill: #e4572e; font-weight: 600; }
.track { fill: none; stroke-width: 2.2; stroke-linecap: round; stroke-linejoin: round; }
.grey-track { fill: none; stroke: #bfc4cc; stroke-width: 1.6; stroke-linejoin: round; }
.pair { fill: none; stroke-width: 1.6; stroke-linecap: round; opacity: .75; }
.start { fill: #fff; stroke: #111; stroke-width: 1.6; }
.end { fill: #111; }
.raster { image-rendering: pixelated; }
.pixels path { vector-effect: non-scaling-stroke; }
.contour { fill: none; stroke: #fff; stroke-width: .9; opacity: .85; }
.outline { fill-opacity: .4; fill-rule: evenodd; stroke-width: 1.4; stroke-linejoin: round; }
.outline.trivial { fill-opacity: .25; stroke-width: 1; }
.small { fill: none; stroke-width: 1.5; }
.dots-halo { fill: none; stroke: #fff; stroke-width: 3.4; stroke-linecap: round; }
.dots { fill: none; stroke: #e8112d; stroke-width: 2.2; stroke-linecap: round; }
svg text.component-label { font-size: 11px; font-weight: 700; fill: #fff; paint-order: stroke;
  stroke: #0b1d3a; stroke-width: 3px; }
.marker { fill: none; stroke-width: 1.3; opacity: .8; }
.fit { fill: none; stroke-width: 1.6; stroke-dasharray: 7 4; }
svg text.empty { fill: var(--muted); font-size: 15px; }
table { border-collapse: collapse; font-variant-numeric: tabular-nums; }
.legend { margin-top: 8px; font-size: 13px; }
.legend th, .legend td { padding: 2px 10px 2px 0; text-align: left; }
.legend th { color: var(--muted); font-weight: 500; }
.legend td svg { display: inline; width: 16px; height: 16px; vertical-align: -3px; }
.note { color: var(--muted); margin: 0 0 8px; }
.table-wrap { max-height: 680px; overflow: auto; background: #fff; border: 1px solid var(--line); border-radius: 8px; }
#components { width: 100%; font-size: 13px; }
#components th { position: sticky; top: 0; background: #eef1f5; font-weight: 600; text-align: right; padding: 6px 10px;
  border-bottom: 1px solid var(--line); cursor: help; }
#components td { padding: 3px 10px; text-align: right; border-bottom: 1px solid #f0f2f5; white-space: nowrap; }
#components tbody tr:hover { background: #f4f8fd; }
#components tr.trivial td { color: var(--muted); }
.swatch { display: inline-block; width: 10px; height: 10px; border-radius: 2px; margin-right: 6px;
  border: 1px solid rgba(0, 0, 0, .25); }
footer { color: var(--muted); font-size: 12px; margin-top: 24px; }
"#;

#[cfg(test)]
mod tests {
    use loops_core::{DEFAULT_EPSILON_S, SampleSize, Sampler, UrbanDrive, sample_quality};

    use super::*;

    /// Everything a report borrows, owned.
    struct Case {
        table: loops_io::PoseTable,
        traj: Trajectory,
        metric: MetricSpec,
        loops: Loops,
        tau: Vec<f64>,
        samples: Samples,
        quality: SampleQuality,
        comparison: Vec<(SamplerKind, SampleQuality)>,
    }

    impl Case {
        fn new(traj: Trajectory, gamma: f64, kind: SamplerKind, budget: usize) -> Self {
            let metric = MetricSpec::Euclidean;
            let loops = metric.find_loops(&traj, gamma).unwrap();
            let tau = loops.loop_duration(Selection::All, Side::Both, Scale::Seconds).unwrap();
            let sample = |kind| {
                let sampler = Sampler::new(kind, SampleSize::Budget(budget), 7);
                let samples = metric.sample_loops(&traj, &loops, &sampler).unwrap();
                let quality = sample_quality(&samples, &loops, DEFAULT_EPSILON_S).unwrap();
                (samples, quality)
            };
            let (samples, quality) = sample(kind);
            let comparison = [SamplerKind::One, SamplerKind::Rho, SamplerKind::Alpha, SamplerKind::LioSam]
                .into_iter()
                .map(|k| (k, sample(k).1))
                .collect();
            let positions = traj
                .coords()
                .chunks_exact(traj.dim())
                .map(|p| [p[0], p.get(1).copied().unwrap_or(0.0), p.get(2).copied().unwrap_or(0.0)])
                .collect();
            let table = loops_io::PoseTable {
                path: "drive <1> & co.tum".into(),
                timestamps_s: traj.timestamps_s().to_vec(),
                timestamps_ns: None,
                positions,
                orientations_xyzw: None,
                dim: traj.dim(),
                source_lines: (1..=traj.len()).collect(),
                messages: None,
            };
            Self { table, traj, metric, loops, tau, samples, quality, comparison }
        }

        fn input(&self) -> ReportInput<'_> {
            ReportInput {
                name: "drive <1> & co.tum",
                source: "logs/drive <1> & co.tum",
                table: &self.table,
                traj: &self.traj,
                metric: &self.metric,
                loops: &self.loops,
                loop_duration_s: &self.tau,
                samples: &self.samples,
                quality: &self.quality,
                comparison: &self.comparison,
                epsilon_s: DEFAULT_EPSILON_S,
                skip_trivial: false,
                seconds: 0.25,
            }
        }
    }

    fn drive(duration_s: f64) -> Trajectory {
        UrbanDrive { duration_s, ..Default::default() }.generate().unwrap().trajectory
    }

    /// The text of every `<tr>` in the components table's body.
    fn table_rows(html: &str) -> Vec<&str> {
        let start = html.find("<table id=\"components\">").expect("the components table");
        let body = &html[start..];
        let body = &body[body.find("<tbody>").unwrap()..body.find("</tbody>").unwrap()];
        body.split("<tr").skip(1).collect()
    }

    const FIGURES: [&str; 4] = ["loop-duration", "pairwise-distance", "sampled-pairs", "samples-per-component"];

    /// `html` without the base64 of its images (whose letters may spell anything).
    fn without_images(html: &str) -> String {
        let mut out = String::new();
        let mut rest = html;
        while let Some(at) = rest.find("base64,") {
            out.push_str(&rest[..at]);
            rest = &rest[at..];
            rest = &rest[rest.find('"').unwrap_or(rest.len())..];
        }
        out + rest
    }

    fn assert_well_formed(html: &str) {
        let text = without_images(html);
        assert!(html.starts_with("<!DOCTYPE html>"));
        assert!(html.trim_end().ends_with("</html>"));
        for name in FIGURES {
            assert_eq!(html.matches(&format!("class=\"figure\" data-figure=\"{name}\"")).count(), 1, "{name}");
        }
        assert!(!html.contains("http:") && !html.contains("https:"), "no network references");
        assert!(!html.contains("<script") && !html.contains("<link"));
        for bad in ["NaN", ">inf", "\"inf", " inf", "-inf"] {
            assert!(!text.contains(bad), "no non-finite numbers: {bad} at {:?}", text.find(bad));
        }
    }

    #[test]
    fn a_drive_gives_every_figure_and_one_row_per_component() {
        let case = Case::new(drive(300.0), 40.0, SamplerKind::Rho, 200);
        let html = render(&case.input());
        assert_well_formed(&html);
        let rows = table_rows(&html);
        assert_eq!(rows.len(), case.loops.components().len());
        assert!(case.loops.components().iter().filter(|c| !c.trivial).count() > 0);
        // Rows in id order, samples as counted.
        for (row, c) in rows.iter().zip(case.loops.components()) {
            let cells: Vec<&str> = row.split("<td>").skip(1).map(|c| c.split("</td>").next().unwrap()).collect();
            assert_eq!(cells.len(), 14);
            assert!(cells[0].ends_with(&format!("</i>{}", c.id)), "{}", cells[0]);
            assert_eq!(cells[13], case.quality.per_component[c.id].to_string());
        }
        assert!(html.contains("data:image/png;base64,iVBORw0KGgo"));
        assert!(html.contains("<title>drive &lt;1&gt; &amp; co.tum — inexact loops</title>"));
        assert!(!html.contains("drive <1>"));
        assert!(html.len() < 2_000_000, "{} bytes", html.len());
    }

    #[test]
    fn thousands_are_separated() {
        assert_eq!(thousands(0u64), "0");
        assert_eq!(thousands(999u64), "999");
        assert_eq!(thousands(1000u64), "1,000");
        assert_eq!(thousands(65_431_618u64), "65,431,618");
    }

    #[test]
    fn all_poses_at_one_place_is_one_trivial_component() {
        let traj = Trajectory::from_points((0..50).map(f64::from).collect(), &[[3.0, -2.0]; 50]).unwrap();
        let case = Case::new(traj, 1.0, SamplerKind::One, 10);
        assert_eq!(case.loops.components().len(), 1);
        let html = render(&case.input());
        assert_well_formed(&html);
        assert_eq!(table_rows(&html).len(), 1);
    }

    #[test]
    fn no_loops_and_no_samples_render() {
        // A straight line with steps wider than γ: every pose alone, nothing to sample.
        let points: Vec<[f64; 2]> = (0..30).map(|i| [10.0 * f64::from(i), 0.0]).collect();
        let traj = Trajectory::from_points((0..30).map(f64::from).collect(), &points).unwrap();
        let case = Case::new(traj, 1.0, SamplerKind::TimeGap, 5);
        assert!(case.samples.is_empty());
        let html = render(&case.input());
        assert_well_formed(&html);
        assert_eq!(table_rows(&html).len(), case.loops.components().len());
        assert!(html.contains("Warnings"), "the broken diagonal is reported");
    }

    #[test]
    fn two_poses_and_a_mismatched_table_render() {
        let traj = Trajectory::from_points(vec![0.0, 1.0], &[[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]).unwrap();
        let mut case = Case::new(traj, 1.0, SamplerKind::Alpha, 3);
        case.table.positions.truncate(1); // a table shorter than the trajectory
        case.tau.clear();
        let html = render(&case.input());
        assert_well_formed(&html);
    }
}
