//! The maps: the trajectory coloured by loop duration τ, and the sampled pairs over it, drawn in
//! the plane the user chose (`--axes`; x–y by default) and labelled with its axes.
//!
//! A log of 10⁶ poses cannot be drawn pose by pose; the path is simplified in pixel space
//! (radial distance, then Douglas–Peucker) to at most [`MAX_SEGMENTS`] segments, breaking it
//! wherever its colour changes, so what is left looks the same at the figure's resolution.

use std::fmt::Write as _;

use super::svg::{self, PathData, Plot, Rect, Scale, ScaleKind, VIRIDIS};
use maud::{Markup, PreEscaped};

use super::{ReportInput, figure, plural, sampler_colour, sampler_name};

/// The most path segments a figure draws.
pub(crate) const MAX_SEGMENTS: usize = 4000;

/// The most sampled pairs the sampled-pairs figure draws.
pub(super) const MAX_PAIRS_DRAWN: usize = 2000;

/// The most components ringed on the loop-duration map (the largest non-trivial ones by area).
pub(super) const MAX_RINGS: usize = 60;

/// Colour levels of τ along the path (before coarsening to meet [`MAX_SEGMENTS`]).
const COLOUR_LEVELS: usize = 48;

/// Width of the plot area, pixels.
const AREA_WIDTH: f64 = 520.0;

/// The plot of positions in a plane, equal scales on both axes, with the positions as pixels.
pub(crate) struct MapPlot {
    pub(crate) plot: Plot,
    pub(crate) pixels: Vec<(f64, f64)>,
}

/// The name of a position axis (0, 1, 2: x, y, z), as the axis labels and captions print it.
fn axis_name(axis: usize) -> String {
    ["x", "y", "z"].get(axis).map_or_else(|| format!("axis {axis}"), |name| (*name).to_owned())
}

/// The plane's name, `x–z`.
pub(crate) fn plane_name([a, b]: [usize; 2]) -> String {
    format!("{}–{}", axis_name(a), axis_name(b))
}

/// Labels the axes of a map of `plane` with the axes' names, in metres.
pub(crate) fn map_axes(plot: &mut Plot, [a, b]: [usize; 2]) {
    plot.axes(&format!("{} (m)", axis_name(a)), &format!("{} (m)", axis_name(b)), 6, 6);
}

/// An equal-aspect plot of `positions` in `plane` (axis `plane[0]` across, `plane[1]` up),
/// `right` pixels of margin right of the area (for a colour bar).
pub(crate) fn map_plot(id: &str, positions: &[[f64; 3]], [a, b]: [usize; 2], right: f64) -> MapPlot {
    let coordinate = |p: &[f64; 3], axis: usize| p.get(axis).copied().unwrap_or(f64::NAN);
    let in_plane = |p: &[f64; 3]| (coordinate(p, a), coordinate(p, b));
    // Non-finite coordinates (a table never validated) are drawn at the previous finite pose.
    let finite = |(x, y): (f64, f64)| x.is_finite() && y.is_finite();
    let mut last = positions.iter().map(in_plane).find(|&p| finite(p)).unwrap_or((0.0, 0.0));
    let points: Vec<(f64, f64)> = positions
        .iter()
        .map(|p| {
            if finite(in_plane(p)) {
                last = in_plane(p);
            }
            last
        })
        .collect();
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in &points {
        (x_lo, x_hi, y_lo, y_hi) = (x_lo.min(x), x_hi.max(x), y_lo.min(y), y_hi.max(y));
    }
    if points.is_empty() {
        (x_lo, x_hi, y_lo, y_hi) = (0.0, 1.0, 0.0, 1.0);
    }
    // Extents, padded; a flat or single-point path still gets a metre-sized window.
    let floor = 1e-9 * x_lo.abs().max(x_hi.abs()).max(y_lo.abs()).max(y_hi.abs());
    let (mut dx, mut dy) = (x_hi - x_lo, y_hi - y_lo);
    if dx.max(dy) <= floor {
        (dx, dy) = (1.0, 1.0);
    }
    let (dx, dy) = (dx.max(dy * 1e-3) * 1.06, dy.max(dx * 1e-3) * 1.06);
    let width = AREA_WIDTH;
    let height = (width * dy / dx).clamp(260.0, 560.0);
    let metres_per_pixel = (dx / width).max(dy / height);
    let (cx, cy) = (0.5 * (x_lo + x_hi), 0.5 * (y_lo + y_hi));
    let (half_x, half_y) = (0.5 * width * metres_per_pixel, 0.5 * height * metres_per_pixel);
    let area = Rect { left: 72.0, top: 10.0, width, height };
    let plot = Plot::new(
        id,
        area.right() + right,
        area.bottom() + 48.0,
        area,
        Scale::linear(cx - half_x, cx + half_x),
        Scale::linear(cy - half_y, cy + half_y),
    );
    let pixels = points.iter().map(|&(x, y)| plot.point(x, y)).collect();
    MapPlot { plot, pixels }
}

/// Per pose, a colour level in `0..levels` of its colour fraction (in [0, 1]), with hysteresis
/// (a pose keeps the level of the one before unless its fraction is more than a quarter level
/// outside it), so noise at a level boundary does not break the path at every pose.
fn colour_levels(fractions: &[f64], levels: usize) -> Vec<u16> {
    let width = 1.0 / levels as f64;
    let mut current = fractions.first().map_or(0, |&f| level_of(f, levels));
    fractions
        .iter()
        .map(|&f| {
            let centre = (f64::from(current) + 0.5) * width;
            if (f - centre).abs() > 0.75 * width {
                current = level_of(f, levels);
            }
            current
        })
        .collect()
}

/// The level in `0..levels` of a fraction (clamped to [0, 1]).
fn level_of(fraction: f64, levels: usize) -> u16 {
    ((fraction * levels as f64).floor().max(0.0) as usize).min(levels - 1) as u16
}

/// Indices of the points kept to draw the polyline `pixels` within `tolerance` pixels; the
/// first and last points are kept, and every `i` with `breaks(i)` (a change of colour) at least
/// `tolerance` from the point kept before it (a change within a pixel cannot be seen).
pub(crate) fn simplify(pixels: &[(f64, f64)], breaks: impl Fn(usize) -> bool, tolerance: f64) -> Vec<usize> {
    let n = pixels.len();
    if n < 2 {
        return (0..n).collect();
    }
    // Radial distance: drop points within the tolerance of the last one kept.
    let mut kept = vec![0];
    let mut forced = vec![true];
    for i in 1..n {
        let last = pixels[kept[kept.len() - 1]];
        let far = (pixels[i].0 - last.0).hypot(pixels[i].1 - last.1) >= tolerance;
        let must = i + 1 == n || (far && breaks(i));
        if must || far {
            kept.push(i);
            forced.push(must);
        }
    }
    // Douglas–Peucker between forced points, in stretches of bounded length (bounding the
    // worst case, a spiral, to O(n · STRETCH)).
    const STRETCH: usize = 256;
    let mut keep = vec![false; kept.len()];
    let mut start = 0;
    while start + 1 < kept.len() {
        let end = (start + 1..kept.len()).find(|&k| forced[k] || k - start >= STRETCH).unwrap_or(kept.len() - 1);
        keep[start] = true;
        keep[end] = true;
        let mut stack = vec![(start, end)];
        while let Some((a, b)) = stack.pop() {
            let (pa, pb) = (pixels[kept[a]], pixels[kept[b]]);
            let (ux, uy) = (pb.0 - pa.0, pb.1 - pa.1);
            let length = ux.hypot(uy);
            let mut worst = (0.0, a);
            for k in a + 1..b {
                let p = pixels[kept[k]];
                let d = if length > 0.0 {
                    ((p.0 - pa.0) * uy - (p.1 - pa.1) * ux).abs() / length
                } else {
                    (p.0 - pa.0).hypot(p.1 - pa.1)
                };
                if d > worst.0 {
                    worst = (d, k);
                }
            }
            if worst.0 > tolerance {
                keep[worst.1] = true;
                stack.push((a, worst.1));
                stack.push((worst.1, b));
            }
        }
        start = end;
    }
    kept.into_iter().zip(keep).filter_map(|(i, k)| k.then_some(i)).collect()
}

/// At most `max + 1` of `kept` (first and last included), evenly spread.
pub(crate) fn thin(kept: Vec<usize>, max: usize) -> Vec<usize> {
    if kept.len() <= max + 1 {
        return kept;
    }
    let last = kept.len() - 1;
    (0..=max).map(|k| kept[k * last / max]).collect()
}

/// The path simplified to at most [`MAX_SEGMENTS`] segments, each with its colour level (of the
/// mean colour fraction over the poses it covers), coarsening tolerance and levels until it fits.
fn coloured_segments(pixels: &[(f64, f64)], fractions: &[f64]) -> (Vec<(usize, usize, u16)>, usize) {
    let mut prefix = Vec::with_capacity(fractions.len() + 1);
    prefix.push(0.0);
    for &f in fractions {
        prefix.push(prefix[prefix.len() - 1] + f);
    }
    let mut result = (Vec::new(), COLOUR_LEVELS);
    for attempt in 0..6 {
        let levels = (COLOUR_LEVELS >> attempt).max(8);
        let tolerance = 0.5 * f64::from(1 << attempt);
        let per_pose = colour_levels(fractions, levels);
        let kept = simplify(pixels, |i| per_pose[i] != per_pose[i - 1], tolerance);
        if kept.len() <= MAX_SEGMENTS + 1 || attempt == 5 {
            let kept = thin(kept, MAX_SEGMENTS);
            let segments = kept
                .windows(2)
                .map(|w| {
                    let (a, b) = (w[0], w[1]);
                    let mean = (prefix[b + 1] - prefix[a + 1]) / (b - a) as f64;
                    (a, b, level_of(mean, levels))
                })
                .collect();
            result = (segments, levels);
            break;
        }
    }
    result
}

/// The colour scale of τ, onto [0, 1]: logarithmic when τ spans more than a decade (the poses of
/// a long stop dwarf those of a passage), else linear from 0.
pub(crate) fn tau_scale(tau: &[f64]) -> Scale {
    let positive = tau.iter().copied().filter(|t| t.is_finite() && *t > 0.0);
    let (lo, hi) = positive.fold((f64::INFINITY, 0.0_f64), |(lo, hi), t| (lo.min(t), hi.max(t)));
    if hi <= 0.0 {
        return Scale::linear(0.0, 1.0).onto(0.0, 1.0);
    }
    let lo = lo.max(hi / 1000.0);
    let scale = if hi / lo > 10.0 { Scale::log(lo, hi) } else { Scale::linear(0.0, hi) };
    scale.onto(0.0, 1.0)
}

/// Start (open circle) and end (filled square) of the path.
fn start_and_end(plot: &mut Plot, pixels: &[(f64, f64)]) {
    if let (Some(&a), Some(&b)) = (pixels.first(), pixels.last()) {
        let _ = write!(
            plot.body_mut(),
            "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"4.5\" class=\"start\"/>\
             <rect x=\"{:.1}\" y=\"{:.1}\" width=\"8\" height=\"8\" class=\"end\"/>",
            a.0,
            a.1,
            b.0 - 4.0,
            b.1 - 4.0
        );
    }
}

/// Figure: the trajectory coloured by loop duration.
pub(super) fn loop_duration_figure(input: &ReportInput<'_>) -> Markup {
    let positions = &input.table.positions;
    let n = positions.len().min(input.loop_duration_s.len());
    let MapPlot { mut plot, pixels } = map_plot("fig-tau", &positions[..n], input.plane, 120.0);
    let tau = &input.loop_duration_s[..n];
    let scale = tau_scale(tau);
    let fractions: Vec<f64> = tau.iter().map(|&t| scale.map(t).clamp(0.0, 1.0)).collect();
    plot.background("#ffffff");
    plot.grid(6, 6);
    let (segments, levels) = coloured_segments(&pixels, &fractions);
    let mut by_level: Vec<PathData> = (0..levels).map(|_| PathData::default()).collect();
    for &(a, b, level) in &segments {
        by_level[usize::from(level)].segment(pixels[a], pixels[b]);
    }
    let mut paths = String::new();
    // Low τ first: the loops are drawn on top.
    for (level, data) in by_level.iter().enumerate() {
        let colour = svg::hex(VIRIDIS.at((level as f64 + 0.5) / levels as f64));
        paths.push_str(&data.element(&format!("stroke=\"{colour}\" class=\"track\"")));
    }
    plot.push_clipped(&paths);
    start_and_end(&mut plot, &pixels);
    let ringed = ringed_components(input);
    plot.push_clipped(&component_rings(input, &pixels, &ringed));
    map_axes(&mut plot, input.plane);
    plot.colour_bar(VIRIDIS, scale, "loop duration τ (s)", &[]);
    let plane = plane_name(input.plane);
    let svg = plot.finish(&format!("The trajectory in {plane}, coloured by loop duration"));
    let caption = format!(
        "<b>Trajectory coloured by loop duration.</b> {plane} positions of the {n} poses; colour is τ(t), the total time the \
         trajectory spends within γ = {gamma} of the pose (its own passage included), so revisited streets stand out. \
         Drawn as {segments}{simplified}; open circle: start, square: end. Rings: the closest pair of {rings}, \
         labelled with its id (the table's <i>where</i> links here).{log}",
        gamma = input.loops.gamma(),
        segments = plural(segments.len(), "segment", "segments"),
        simplified = if segments.len() + 1 < n { " (simplified to the figure's resolution)" } else { "" },
        rings = match (ringed.len(), input.loops.components().iter().filter(|c| !c.trivial).count()) {
            (shown, all) if shown < all => format!("the {shown} largest of the {all} non-trivial components"),
            (shown, _) => format!("each non-trivial component ({shown})"),
        },
        log = if scale.kind() == ScaleKind::Log {
            " The colour scale is logarithmic: a stop makes τ of its poses as long as the stop."
        } else {
            ""
        },
    );
    figure("loop-duration", &svg, PreEscaped(caption))
}

/// The components ringed on the map, by id: the [`MAX_RINGS`] largest non-trivial ones by area
/// whose closest pair's pose i is on the map.
pub(super) fn ringed_components(input: &ReportInput<'_>) -> Vec<usize> {
    let components = input.loops.components();
    let n = input.table.positions.len().min(input.loop_duration_s.len());
    let mut ids: Vec<usize> = components.iter().filter(|c| !c.trivial && c.closest_pair[0] < n).map(|c| c.id).collect();
    ids.sort_by(|&a, &b| components[b].area_s2.total_cmp(&components[a].area_s2).then(a.cmp(&b)));
    ids.truncate(MAX_RINGS);
    ids.sort_unstable();
    ids
}

/// The anchor of component `id`'s ring on the map.
pub(super) fn ring_anchor(id: usize) -> String {
    format!("map-component-{id}")
}

/// A ring at the closest pair's pose i of each component of `ids`, labelled with its id, each a
/// group the components table links to.
fn component_rings(input: &ReportInput<'_>, pixels: &[(f64, f64)], ids: &[usize]) -> String {
    let mut out = String::new();
    for &id in ids {
        let c = &input.loops.components()[id];
        let Some(&(x, y)) = pixels.get(c.closest_pair[0]) else { continue };
        let ring = format!("M{x:.1} {y:.1}m-6 0a6 6 0 1 0 12 0a6 6 0 1 0 -12 0");
        let _ = write!(
            out,
            "<g id=\"{anchor}\" class=\"component-ring\"><title>component {id}: closest pair ({i}, {j}), δ = {d:.3}</title>\
             <path d=\"{ring}\" class=\"ring-halo\"/><path d=\"{ring}\" class=\"ring\"/>\
             <text x=\"{tx:.1}\" y=\"{ty:.1}\">{id}</text></g>",
            anchor = ring_anchor(id),
            i = c.closest_pair[0],
            j = c.closest_pair[1],
            d = c.closest_distance,
            tx = x + 8.0,
            ty = y - 8.0,
        );
    }
    out
}

/// Figure: the sampled pairs, each a line between its two poses, over the trajectory in grey.
pub(super) fn sampled_pairs_figure(input: &ReportInput<'_>) -> Markup {
    let positions = &input.table.positions;
    let MapPlot { mut plot, pixels } = map_plot("fig-pairs", positions, input.plane, 24.0);
    plot.background("#ffffff");
    plot.grid(6, 6);
    let kept = thin(simplify(&pixels, |_| false, 0.5), MAX_SEGMENTS);
    let mut track = PathData::default();
    for w in kept.windows(2) {
        track.segment(pixels[w[0]], pixels[w[1]]);
    }
    let pairs: Vec<[usize; 2]> = input
        .samples
        .rows()
        .iter()
        .filter_map(|s| s.pair)
        .filter(|p| p[0] < pixels.len() && p[1] < pixels.len())
        .collect();
    let drawn: Vec<[usize; 2]> = if pairs.len() > MAX_PAIRS_DRAWN {
        (0..MAX_PAIRS_DRAWN).map(|k| pairs[k * pairs.len() / MAX_PAIRS_DRAWN]).collect()
    } else {
        pairs.clone()
    };
    let mut lines = PathData::default();
    for &[i, j] in &drawn {
        lines.segment(pixels[i], pixels[j]);
    }
    let colour = svg::hex(sampler_colour(input.samples.sampler()));
    plot.push_clipped(&format!(
        "{}{}",
        track.element("class=\"grey-track\""),
        lines.element(&format!("stroke=\"{colour}\" class=\"pair\""))
    ));
    start_and_end(&mut plot, &pixels);
    map_axes(&mut plot, input.plane);
    let svg = plot.finish(&format!("Sampled loop-closure pairs over the trajectory in {}", plane_name(input.plane)));
    let sampler = sampler_name(input.samples.sampler()).into_string();
    let mut caption = if drawn.is_empty() {
        format!("<b>Sampled pairs.</b> The {sampler} sampler drew no pair of poses to show.")
    } else {
        format!(
            "<b>Sampled pairs.</b> Each line joins the two poses x<sub>i</sub>, x<sub>j</sub> of a pair drawn by the \
             {sampler} sampler: a candidate loop closure for the scan matcher. {}.",
            if drawn.len() < pairs.len() {
                format!("An evenly spread {} of the {} are drawn (at most {MAX_PAIRS_DRAWN})", drawn.len(), pairs.len())
            } else {
                plural(drawn.len(), "pair", "pairs")
            }
        )
    };
    let unplaced = input.samples.len() - pairs.len();
    if unplaced > 0 {
        caption += &format!(" {} without pose indices not drawn.", plural(unplaced, "sample", "samples"));
    }
    figure("sampled-pairs", &svg, PreEscaped(caption))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simplify_keeps_corners_and_breaks() {
        // An L of 201 points: the corner and the ends survive, the straight runs do not.
        let mut pixels: Vec<(f64, f64)> = (0..=100).map(|k| (k as f64, 0.0)).collect();
        pixels.extend((1..=100).map(|k| (100.0, k as f64)));
        assert_eq!(simplify(&pixels, |_| false, 0.5), [0, 100, 200]);
        assert_eq!(simplify(&pixels, |i| i == 40, 0.5), [0, 40, 100, 200]);
        assert_eq!(simplify(&pixels, |i| i == 40, 1.5), [0, 40, 100, 200]);
        assert_eq!(simplify(&pixels[..1], |_| false, 0.5), [0]);
        assert!(simplify(&[], |_| false, 0.5).is_empty());
        // All points equal.
        assert_eq!(simplify(&[(3.0, 3.0); 50], |_| false, 0.5), [0, 49]);
    }

    #[test]
    fn segments_fit_the_budget() {
        // A dense random-ish walk: far more points than segments allowed.
        let pixels: Vec<(f64, f64)> =
            (0..200_000_u64).map(|k| (((k * 7919) % 5000) as f64 * 0.1, ((k * 104_729) % 5000) as f64 * 0.1)).collect();
        let fractions: Vec<f64> = (0..200_000).map(|k| f64::from(k % 97) / 96.0).collect();
        let (segments, _) = coloured_segments(&pixels, &fractions);
        assert!(segments.len() <= MAX_SEGMENTS, "{}", segments.len());
        assert_eq!(segments.first().map(|s| s.0), Some(0));
        assert_eq!(segments.last().map(|s| s.1), Some(199_999));
    }

    #[test]
    fn tau_scale_is_log_over_more_than_a_decade() {
        let mut tau = vec![10.0; 1000];
        tau[5] = 500.0;
        let scale = tau_scale(&tau);
        assert_eq!(scale.kind(), ScaleKind::Log);
        assert_eq!((scale.map(10.0), scale.map(500.0)), (0.0, 1.0));
        let scale = tau_scale(&[1.0, 2.0, 3.0]);
        assert_eq!(scale.kind(), ScaleKind::Linear);
        assert_eq!(scale.map(3.0), 1.0);
        for degenerate in [&[][..], &[0.0, 0.0][..]] {
            let scale = tau_scale(degenerate);
            assert!(scale.map(0.0).is_finite());
        }
    }
}
