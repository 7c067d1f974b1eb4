//! The pairwise-distance figure: δ(x_i, x_j) over the time × time plane, downsampled to at most
//! [`MAX_GRID`]² pixels, with the γ isocontour, the loop-component outlines and the samples
//! drawn over it.
//!
//! Everything on the plane comes from `loops_core::plane`, as `inexact_loops.plot` gets it: the
//! grid of poses ([`PlaneGrid`]), the distance of each pixel's pair
//! ([`MetricSpec::distance_image`](loops_core::MetricSpec::distance_image)), its component ([`Loops::label_image`](loops_core::Loops::label_image)), the outlines
//! ([`component_outlines`], closed along the border so they can be filled) and the γ isocontour
//! ([`isocontour`]). They are in pixel units, drawn under one affine transform onto the plot
//! (whose axes span the grid's pixel edges), so their coordinates are small numbers. This module
//! only draws them.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use loops_core::plane::{Border, PlaneGrid, component_outlines, isocontour};

use super::png::PaletteImage;
use super::svg::{self, ICE, Plot, Rect, Rgb, Scale, px};
use maud::{Markup, PreEscaped};

use super::{ReportInput, component_colour, figure};

/// The most pixels along each side of the image.
pub(super) const MAX_GRID: usize = 400;

/// The most samples drawn as dots.
pub(super) const MAX_DOTS: usize = 2000;

/// The most markers for components hidden under larger ones in every pixel.
const MAX_SMALL_MARKERS: usize = 2000;

/// The largest non-trivial components get their id written beside them.
const LABELLED_COMPONENTS: usize = 8;

/// Side of the plot area, pixels.
const AREA_SIDE: f64 = 440.0;

/// Path data of lattice polylines: absolute start, then relative `h`/`v` moves, one per
/// straight run.
fn lattice_path(lines: &[Vec<[u32; 2]>]) -> String {
    let mut d = String::new();
    for line in lines {
        let Some(&[x0, y0]) = line.first() else { continue };
        let _ = write!(d, "M{x0} {y0}");
        let mut run: Option<(bool, i64)> = None; // (horizontal, length)
        for w in line.windows(2) {
            let (dx, dy) = (i64::from(w[1][0]) - i64::from(w[0][0]), i64::from(w[1][1]) - i64::from(w[0][1]));
            let step = if dy == 0 { (true, dx) } else { (false, dy) };
            run = match run {
                Some((h, length)) if h == step.0 && length.signum() == step.1.signum() => Some((h, length + step.1)),
                Some((h, length)) => {
                    let _ = write!(d, "{}{length}", if h { 'h' } else { 'v' });
                    Some(step)
                }
                None => Some(step),
            };
        }
        if let Some((h, length)) = run {
            let _ = write!(d, "{}{length}", if h { 'h' } else { 'v' });
        }
        if line.len() > 2 && line.first() == line.last() {
            d.push('z');
        }
    }
    d
}

/// The plane as the core derives it: the grid, the distance and the component of each pixel.
struct Plane {
    grid: PlaneGrid,
    distance: Vec<f64>,
    labels: Vec<Option<u32>>,
}

fn plane(input: &ReportInput<'_>) -> loops_core::Result<Plane> {
    let grid = PlaneGrid::new(input.traj, None, MAX_GRID)?;
    let distance = input.metric.distance_image(input.traj, &grid)?;
    let labels = input.loops.label_image(&grid)?;
    Ok(Plane { grid, distance, labels })
}

/// Figure: the pairwise distance with the γ isocontour, component outlines and samples.
pub(super) fn distance_figure(input: &ReportInput<'_>) -> Markup {
    let (traj, loops) = (input.traj, input.loops);
    let t0 = traj.timestamps_s()[0];
    let relative_s: Vec<f64> = traj.timestamps_s().iter().map(|t| t - t0).collect();
    let plane = match plane(input) {
        Ok(plane) => plane,
        Err(err) => {
            let caption = maud::html! { b { "Pairwise distance." } " Not drawn: " (err) };
            return figure("pairwise-distance", "", caption);
        }
    };
    let grid = &plane.grid;
    // A square image (no window): its side in pixels, and the time span its pixels stand for.
    let m = grid.width();
    let edges = grid.column_edges_s();
    let (start_s, end_s) = (edges[0], edges[m]);
    let gamma = loops.gamma();
    // A square-root colour scale: the small distances, where S_γ and its near misses are, get
    // most of the colours.
    let d_max = plane.distance.iter().copied().filter(|d| d.is_finite()).fold(0.0, f64::max);
    let colour_scale = Scale::sqrt(0.0, if d_max > 0.0 { d_max } else { gamma }).onto(0.0, 1.0);
    let area = Rect { left: 64.0, top: 10.0, width: AREA_SIDE, height: AREA_SIDE };
    let mut plot = Plot::new(
        "fig-distance",
        area.right() + 120.0,
        area.bottom() + 48.0,
        area,
        Scale::linear(start_s, end_s),
        Scale::linear(start_s, end_s),
    );

    // The image, in 256 shades: row 0 at the top is the last t′.
    let palette = (0..=255).map(|k| ICE.at(f64::from(k) / 255.0)).collect();
    let mut image = PaletteImage::new(m as u32, m as u32, palette);
    for b in 0..m {
        for a in 0..m {
            let shade = (colour_scale.map(plane.distance[b * m + a]).clamp(0.0, 1.0) * 255.0).round() as u8;
            image.set(a, m - 1 - b, shade);
        }
    }
    if let Some(uri) = image.data_uri() {
        let _ = write!(
            plot.body_mut(),
            "<image href=\"{uri}\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" preserveAspectRatio=\"none\" \
             class=\"raster\"/>",
            area.left,
            area.top,
            area.width,
            area.height
        );
    }

    // Isocontour and outlines, in pixel units: x = left + a·(W/m), y = bottom − b·(H/m).
    let cell = AREA_SIDE / m.max(1) as f64;
    let mut overlay = format!(
        "<g transform=\"matrix({cell:.6} 0 0 {:.6} {} {})\" class=\"pixels\">",
        -cell,
        area.left,
        area.bottom()
    );
    let components = loops.components();
    let outlined = component_outlines(&plane.labels, m, m, Border::Closed).unwrap_or_default();
    // One path per colour (components never overlap, so even-odd filling stays right).
    let mut by_colour: BTreeMap<(bool, Rgb), String> = BTreeMap::new();
    for (&c, lines) in &outlined {
        let Some(component) = components.get(c as usize) else { continue };
        by_colour.entry((!component.trivial, component_colour(component))).or_default().push_str(&lattice_path(lines));
    }
    for ((nontrivial, colour), d) in &by_colour {
        let class = if *nontrivial { "outline" } else { "outline trivial" };
        let _ = write!(
            overlay,
            "<path d=\"{d}\" stroke=\"{colour}\" fill=\"{colour}\" class=\"{class}\"/>",
            colour = svg::hex(*colour)
        );
    }
    let mut contour = String::new();
    for line in isocontour(&plane.distance, m, m, gamma).unwrap_or_default() {
        for (k, &[x, y]) in line.iter().enumerate() {
            contour.push(if k == 0 { 'M' } else { 'L' });
            px(&mut contour, x);
            contour.push(' ');
            px(&mut contour, y);
        }
    }
    if !contour.is_empty() {
        let _ = write!(overlay, "<path d=\"{contour}\" class=\"contour\"/>");
    }
    overlay.push_str("</g>");

    // Components that hold none of the pixels' pairs: a cross at their closest pair.
    let time = |i: usize| relative_s.get(i).copied().unwrap_or(0.0);
    let small: Vec<_> = components.iter().filter(|c| !outlined.contains_key(&(c.id as u32))).collect();
    let mut crosses: BTreeMap<Rgb, String> = BTreeMap::new();
    for c in small.iter().take(MAX_SMALL_MARKERS) {
        let (x, y) = plot.point(time(c.closest_pair[0]), time(c.closest_pair[1]));
        let _ =
            write!(crosses.entry(component_colour(c)).or_default(), "M{:.1} {y:.1}h6M{x:.1} {:.1}v6", x - 3.0, y - 3.0);
    }
    for (colour, d) in &crosses {
        let _ = write!(overlay, "<path d=\"{d}\" stroke=\"{}\" class=\"small\"/>", svg::hex(*colour));
    }

    // The largest non-trivial components, labelled by id outside the top left corner of their
    // box, or inside it where that would leave the plot.
    let mut largest: Vec<_> = components.iter().filter(|c| !c.trivial).collect();
    largest.sort_by(|a, b| b.area_s2.total_cmp(&a.area_s2).then(a.id.cmp(&b.id)));
    for c in largest.iter().take(LABELLED_COMPONENTS) {
        let (x, y) = plot.point(time(c.i_range[0]), time(c.j_range[1]));
        let label = format!("#{}", c.id);
        let width = 7.0 * label.len() as f64;
        let (x, anchor) = if x - width - 2.0 < area.left { (x + 2.0, "start") } else { (x - 2.0, "end") };
        let y = if y - 12.0 < area.top { y + 12.0 } else { y - 2.0 };
        let _ = write!(
            overlay,
            "<text x=\"{x:.1}\" y=\"{y:.1}\" text-anchor=\"{anchor}\" class=\"component-label\">{label}</text>"
        );
    }

    // The samples, at (t, t′) with t ≤ t′.
    let rows = input.samples.rows();
    let at = |k: usize| {
        let s = &rows[k];
        let (t, t_prime) = match s.pair {
            Some([i, j]) if i < relative_s.len() && j < relative_s.len() => (relative_s[i], relative_s[j]),
            _ => (s.t_s - t0, s.t_prime_s - t0),
        };
        (t.min(t_prime), t.max(t_prime))
    };
    let drawn: Vec<usize> = if rows.len() > MAX_DOTS {
        (0..MAX_DOTS).map(|k| k * rows.len() / MAX_DOTS).collect()
    } else {
        (0..rows.len()).collect()
    };
    let mut dots = String::new();
    for &k in &drawn {
        let (t, t_prime) = at(k);
        let (x, y) = plot.point(t, t_prime);
        dots.push('M');
        px(&mut dots, x);
        dots.push(' ');
        px(&mut dots, y);
        dots.push_str("h0");
    }
    if !dots.is_empty() {
        let _ = write!(overlay, "<path d=\"{dots}\" class=\"dots-halo\"/><path d=\"{dots}\" class=\"dots\"/>");
    }
    plot.push_clipped(&overlay);
    plot.axes("t (s from the first pose)", "t′ (s from the first pose)", 6, 6);
    plot.colour_bar(ICE, colour_scale, &format!("δ ({}), square-root scale", loops.metric_name()), &[(gamma, "γ")]);
    let svg = plot.finish("Pairwise distance over the time × time plane");

    let nontrivial = components.iter().filter(|c| !c.trivial).count();
    let caption = format!(
        "<b>Pairwise distance.</b> δ(x<sub>i</sub>, x<sub>j</sub>) over the (t, t′) plane, {m} × {m} pixels{down} \
         (dark: close). White line: the γ = {gamma} isocontour of these δ. Coloured: the pixels whose pair lies in one \
         of the {nontrivial} {kind}, in both halves{trivial_note}{labelled}. \
         {small}Red dots: {dots_text} at (t, t′), t ≤ t′.",
        down = if m < traj.len() {
            format!(
                " of {} s each, showing the pair of poses nearest its centre ({} poses downsampled)",
                three_digits((end_s - start_s) / m as f64),
                traj.len()
            )
        } else {
            String::new()
        },
        kind = if loops.is_separated() {
            format!(
                "revisit components (pairs {} apart along the trajectory; those nearer are left out)",
                loops.separation()
            )
        } else {
            "non-trivial loop components".to_owned()
        },
        trivial_note = match components.iter().filter(|c| c.trivial).count() {
            0 => "",
            1 => " (grey: the trivial one, along the diagonal)",
            _ => " (grey: the trivial ones, along the diagonal)",
        },
        labelled = match LABELLED_COMPONENTS.min(nontrivial) {
            0 => String::new(),
            1 => "; it is labelled with its id".to_owned(),
            count => format!("; the {count} largest are labelled with their id"),
        },
        small = match small.len() {
            0 => String::new(),
            count => format!(
                "{count} component{s} smaller than a pixel, holding none of the pixels' pairs, {are} marked + \
                 at {their} closest pair{shown}. ",
                s = if count == 1 { "" } else { "s" },
                are = if count == 1 { "is" } else { "are" },
                their = if count == 1 { "its" } else { "their" },
                shown =
                    if count > MAX_SMALL_MARKERS { format!(" (the first {MAX_SMALL_MARKERS})") } else { String::new() }
            ),
        },
        dots_text = if drawn.len() < rows.len() {
            format!("an evenly spread {} of the {} samples", drawn.len(), rows.len())
        } else {
            format!("the {} samples", rows.len())
        },
    );
    figure("pairwise-distance", &svg, PreEscaped(caption))
}

/// `value` to about three significant digits (`18.9`, `0.125`, `2500`).
fn three_digits(value: f64) -> String {
    let decimals = if value >= 100.0 { 0 } else { (2.0 - value.abs().log10().floor()).clamp(0.0, 9.0) as usize };
    format!("{value:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_digits_are_shown() {
        assert_eq!(three_digits(18.9), "18.9");
        assert_eq!(three_digits(0.125), "0.125");
        assert_eq!(three_digits(2500.4), "2500");
        assert_eq!(three_digits(1.0), "1.00");
    }

    #[test]
    fn lattice_paths_merge_straight_runs() {
        let square = vec![vec![[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2], [0, 1], [0, 0]]];
        assert_eq!(lattice_path(&square), "M0 0h2v2h-2v-2z");
    }
}
