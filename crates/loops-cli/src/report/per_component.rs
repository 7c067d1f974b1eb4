//! The samples-per-component figure (the paper's last figure): for every sampler compared,
//! samples per loop component against the component's area, log–log, with the P3 fit.

use std::collections::HashSet;
use std::fmt::Write as _;

use loops_core::{SampleQuality, SamplerKind};
use maud::{Markup, PreEscaped, html};

use super::svg::{self, PathData, Plot, Rect, Scale};
use super::{ReportInput, figure, sampler_colour, sampler_marker, sampler_name};

/// The most markers drawn per sampler (after merging markers that share a pixel).
pub(super) const MAX_MARKERS: usize = 3000;

/// One sampler's points: (area s², samples) of its components with a sample.
struct Series<'a> {
    kind: SamplerKind,
    quality: &'a SampleQuality,
    points: Vec<(f64, f64)>,
}

/// Figure: samples per component against component area, one series per sampler.
pub(super) fn per_component_figure(input: &ReportInput<'_>) -> Markup {
    let compared: Vec<(SamplerKind, &SampleQuality)> = if input.comparison.is_empty() {
        vec![(input.samples.sampler(), input.quality)]
    } else {
        input.comparison.iter().map(|(kind, quality)| (*kind, quality)).collect()
    };
    let components = input.loops.components();
    let series: Vec<Series<'_>> = compared
        .iter()
        .map(|(kind, quality)| {
            let points = components
                .iter()
                .filter_map(|c| {
                    let samples = quality.per_component.get(c.id).copied().unwrap_or(0);
                    (samples > 0 && c.area_s2 > 0.0 && c.area_s2.is_finite()).then_some((c.area_s2, samples as f64))
                })
                .collect();
            Series { kind: *kind, quality, points }
        })
        .collect();

    let all = series.iter().flat_map(|s| s.points.iter());
    let (x_lo, x_hi, y_hi) =
        all.fold((f64::INFINITY, 0.0_f64, 1.0_f64), |(lo, hi, top), &(x, y)| (lo.min(x), hi.max(x), top.max(y)));
    let (x_lo, x_hi) = if x_lo.is_finite() { (x_lo / 1.6, x_hi * 1.6) } else { (1.0, 1e4) };
    let area = Rect { left: 72.0, top: 10.0, width: 520.0, height: 360.0 };
    let mut plot = Plot::new(
        "fig-growth",
        area.right() + 24.0,
        area.bottom() + 48.0,
        area,
        Scale::log(x_lo, x_hi),
        Scale::log(0.7, y_hi * 1.6),
    );
    plot.background("#ffffff");
    plot.grid(8, 6);

    let mut drawn = String::new();
    let mut thinned = Vec::new();
    for s in &series {
        let colour = svg::hex(sampler_colour(s.kind));
        // The least-squares line of P3 through this series' points.
        if let (Some(slope), false) = (s.quality.p3_slope, s.points.is_empty()) {
            let count = s.points.len() as f64;
            let mean_x = s.points.iter().map(|p| p.0.ln()).sum::<f64>() / count;
            let mean_y = s.points.iter().map(|p| p.1.ln()).sum::<f64>() / count;
            let (lo, hi) = s.points.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
            let fit = |x: f64| (mean_y + slope * (x.ln() - mean_x)).exp();
            let mut line = PathData::default();
            line.segment(plot.point(lo, fit(lo)), plot.point(hi, fit(hi)));
            drawn.push_str(&line.element(&format!("stroke=\"{colour}\" class=\"fit\"")));
        }
        // Markers, one per pixel.
        let mut seen = HashSet::new();
        let pixels: Vec<(f64, f64)> = s
            .points
            .iter()
            .map(|&(x, y)| plot.point(x, y))
            .filter(|p| seen.insert(((p.0 * 2.0).round() as i64, (p.1 * 2.0).round() as i64)))
            .collect();
        let shown: Vec<(f64, f64)> = if pixels.len() > MAX_MARKERS {
            thinned.push(s.kind);
            (0..MAX_MARKERS).map(|k| pixels[k * pixels.len() / MAX_MARKERS]).collect()
        } else {
            pixels
        };
        let mut d = String::new();
        for &p in &shown {
            sampler_marker(s.kind).path(&mut d, p, 3.2);
        }
        if !d.is_empty() {
            let _ = write!(drawn, "<path d=\"{d}\" stroke=\"{colour}\" class=\"marker\"/>");
        }
    }
    if series.iter().all(|s| s.points.is_empty()) {
        let _ = write!(
            drawn,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" class=\"empty\">no component has a sample</text>",
            area.left + 0.5 * area.width,
            area.top + 0.5 * area.height
        );
    }
    plot.push_clipped(&drawn);
    plot.axes("component area (s²)", "samples in the component", 8, 6);
    let svg = plot.finish("Samples per loop component against component area, per sampler");

    // The legend, as a table: what each series is, and what the log axes cannot show.
    let legend = html! {
        table.legend {
            thead {
                tr {
                    th {} th { "sampler" } th { "samples" } th { "components covered" } th { "missed (not drawn)" }
                    th { "P3 slope" }
                }
            }
            tbody {
                @for s in &series {
                    tr {
                        td { (PreEscaped(sampler_marker(s.kind).swatch(sampler_colour(s.kind)))) }
                        td { (sampler_name(s.kind)) }
                        td { (s.quality.samples) }
                        td { (s.quality.covered) " / " (s.quality.components) }
                        td { (s.quality.missed.len()) }
                        td { (s.quality.p3_slope.map_or("—".to_owned(), |v| format!("{v:.2}"))) }
                    }
                }
            }
        }
    };
    let caption = html! {
        b { "Samples per component against component area." }
        " Each marker is one loop component holding at least one sample; dashed lines are the least-squares \
        fits whose slopes are P3 (≈ 0 for σ" sub { "1" } ", ≈ 1 for σ" sub { "α" } ", in between for σ" sub { "ρ" }
        "). Components without a sample cannot sit on the log axis: their count is the “missed” column."
        @if !thinned.is_empty() {
            " For " (thinned.iter().map(|k| k.name()).collect::<Vec<_>>().join(", "))
            ", markers are thinned to " (MAX_MARKERS) "."
        }
        (legend)
    };
    figure("samples-per-component", &svg, caption)
}
