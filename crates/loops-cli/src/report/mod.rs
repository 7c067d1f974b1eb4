//! `report.html`: one self-contained page per log (no network; figures inline as SVG or PNG).
//! The batch's `index.html` belongs to `loops run` (`run/index.rs`); the fleet's `index.html`
//! to `loops fleet` (`fleet/page.rs`), drawn with the same plotting layer.
//!
//! The page has a summary (trajectory, loops, samples and their P1–P3; [`summary`]), then four
//! figures and the components table:
//!
//! | `data-figure` | what | module |
//! |---|---|---|
//! | `loop-duration` | the path in the chosen plane (`--axes`, x–y by default) coloured by loop duration τ | [`trajectory`] |
//! | `pairwise-distance` | δ over the (t, t′) plane, γ isocontour, component outlines, samples | [`distance`] |
//! | `sampled-pairs` | each sample as a line between its two poses, in the same plane | [`trajectory`] |
//! | `samples-per-component` | samples per component against area, every sampler compared | [`per_component`] |
//!
//! and `<table id="components">`, one row per component ([`table`]). Every figure is drawn from
//! a bounded amount of data (paths simplified to the figure's resolution, at most 400 × 400
//! distances, capped sample and marker counts, stated in the captions), so a log of 10⁶ poses
//! still gives a page of a few MB, rendered in well under a second.
//!
//! The HTML is written with maud's `html!`: text is escaped unless marked `PreEscaped`, and
//! the markup is checked when the crate compiles. maud rather than askama because it builds
//! here with the fewest new crates (maud, maud_macros, proc-macro2-diagnostics and
//! version_check, over the syn the workspace already has; askama adds six, a TOML parser and a
//! glob matcher among them), and because the figures are built in Rust anyway: a template file
//! per figure would only pass strings through. The style sheet is a file of its own
//! (`report.css`), included at compile time.
//!
//! Plotting (scales, ticks, colour maps) is in [`svg`], PNG images in [`png`], colours and
//! markers in [`palette`], number formats in [`numbers`].

mod distance;
pub(crate) mod numbers;
pub(crate) mod palette;
mod per_component;
mod png;
mod summary;
pub(crate) mod svg;
mod table;
pub(crate) mod trajectory;

use loops_core::{Loops, MetricSpec, SampleQuality, SamplerKind, Samples, Trajectory};
use maud::{DOCTYPE, Markup, PreEscaped, html};
use percent_encoding::{AsciiSet, NON_ALPHANUMERIC};

use numbers::plural;
use palette::{component_colour, sampler_colour, sampler_marker, sampler_name, swatch_class};

/// What a folder name keeps in a relative URL path segment (a link to a log's or a session's
/// page): letters, digits and `-._~` (RFC 3986 unreserved); everything else is percent-encoded.
pub(crate) const SEGMENT: &AsciiSet = &NON_ALPHANUMERIC.remove(b'-').remove(b'.').remove(b'_').remove(b'~');

/// The page's style sheet.
pub(crate) const STYLE: &str = include_str!("report.css");

/// Everything one log's report shows. Built by `loops run` after the log is processed.
#[derive(Debug)]
pub(crate) struct ReportInput<'a> {
    /// The log's name (its file name), the page title.
    pub name: &'a str,
    /// The log's path as given on the command line.
    pub source: &'a str,
    /// The poses as read (x, y, z positions for drawing; orientations when the file has them).
    pub table: &'a loops_io::PoseTable,
    /// The plane the maps draw: two axes of the table's positions (0 = x, 1 = y, 2 = z).
    pub plane: [usize; 2],
    /// The trajectory the engine ran on (the metric's coordinates).
    pub traj: &'a Trajectory,
    /// The metric, for the downsampled pairwise-distance image.
    pub metric: &'a MetricSpec,
    /// What the metric measures of the file (`InputArgs::measured`).
    pub measured: &'a str,
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
    let title = html! { (input.name) " — inexact loops" };
    let style = html! { (PreEscaped(STYLE)) (PreEscaped(palette::swatch_style())) };
    let body = html! {
        main {
            header {
                h1 { (input.name) }
                p.source { (input.source) }
            }
            (summary::cards(input))
            (summary::warnings(input))
            section.figures {
                (trajectory::loop_duration_figure(input))
                (distance::distance_figure(input))
                (trajectory::sampled_pairs_figure(input))
                (per_component::per_component_figure(input))
            }
            (table::components_section(input))
            footer {
                "Written by loops " (env!("CARGO_PKG_VERSION"))
                " · inexact loops after E. Nelson, “Inexact Loops in Robotics Problems”."
            }
        }
    };
    page(title, style, body)
}

/// A self-contained HTML page as one string (ending in a newline): UTF-8, a viewport for
/// phones, `title`, the inline `style` and `body`.
pub(crate) fn page(title: Markup, style: Markup, body: Markup) -> String {
    let page = html! {
        (DOCTYPE)
        html lang="en" {
            head {
                meta charset="utf-8";
                meta name="viewport" content="width=device-width, initial-scale=1";
                title { (title) }
                style { (style) }
            }
            body { (body) }
        }
    };
    page.into_string() + "\n"
}

/// A figure element the page's tests can find: `class="figure"`, `data-figure="name"`, around
/// an `svg` element and a caption (markup: the figures' modules build it from numbers and fixed
/// text).
pub(crate) fn figure(name: &str, svg: &str, caption: Markup) -> Markup {
    html! {
        figure.figure data-figure=(name) {
            (PreEscaped(svg))
            figcaption { (caption) }
        }
    }
}

/// A pose table of `traj`'s first three coordinates as if read from `path`, for the pages' tests.
#[cfg(test)]
pub(crate) fn table_of(traj: &Trajectory, path: &str) -> loops_io::PoseTable {
    let positions = traj
        .coords()
        .chunks_exact(traj.dim())
        .map(|p| [p[0], p.get(1).copied().unwrap_or(0.0), p.get(2).copied().unwrap_or(0.0)])
        .collect();
    loops_io::PoseTable {
        path: path.into(),
        timestamps_s: traj.timestamps_s().to_vec(),
        timestamps_ns: None,
        positions,
        orientations_xyzw: None,
        dim: traj.dim(),
        source_lines: (1..=traj.len()).collect(),
        messages: None,
    }
}

#[cfg(test)]
mod tests {
    use loops_core::{DEFAULT_EPSILON_S, SampleSize, Sampler, Scale, Selection, Side, UrbanDrive, sample_quality};

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
            let table = table_of(&traj, "drive <1> & co.tum");
            Self { table, traj, metric, loops, tau, samples, quality, comparison }
        }

        fn input(&self) -> ReportInput<'_> {
            ReportInput {
                name: "drive <1> & co.tum",
                source: "logs/drive <1> & co.tum",
                table: &self.table,
                plane: [0, 1],
                traj: &self.traj,
                metric: &self.metric,
                measured: "positions x, y, z",
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
            assert_eq!(cells.len(), 15);
            assert!(cells[0].ends_with(&format!("</i>{}", c.id)), "{}", cells[0]);
            assert_eq!(cells[14], case.quality.per_component[c.id].to_string());
            // Where its closest pair is, in the map's plane (x-y); a non-trivial one links to
            // its ring on the map, which is at that pose.
            let [x, y, _] = case.table.positions[c.closest_pair[0]];
            let place = format!("({x:.1}, {y:.1})");
            if c.trivial {
                assert_eq!(cells[13], place);
            } else {
                let anchor = format!("map-component-{}", c.id);
                assert_eq!(cells[13], format!("<a href=\"#{anchor}\">{place}</a>"));
                let ring =
                    &html[html.find(&format!("<g id=\"{anchor}\" class=\"component-ring\">")).expect("its ring")..];
                let ring = &ring[..ring.find("</g>").unwrap()];
                let [i, j] = c.closest_pair;
                assert!(ring.contains(&format!("component {}: closest pair ({i}, {j})", c.id)), "{ring}");
                assert!(ring.contains(&format!(">{}</text>", c.id)), "{ring}");
            }
        }
        assert!(html.contains("data:image/png;base64,iVBORw0KGgo"));
        assert!(html.contains("<title>drive &lt;1&gt; &amp; co.tum — inexact loops</title>"));
        assert!(!html.contains("drive <1>"));
        assert!(html.len() < 2_000_000, "{} bytes", html.len());
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
