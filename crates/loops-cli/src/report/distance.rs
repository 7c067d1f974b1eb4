//! The pairwise-distance figure: δ(x_i, x_j) over the time × time plane, downsampled to at most
//! [`MAX_GRID`]² pixels, with the γ isocontour, the loop-component outlines and the samples
//! drawn over it.
//!
//! Pixel (a, b) shows the pair of poses nearest the centre times of column a (t) and row b (t′),
//! and carries that pair's component (`Loops::component_of`). The isocontour (marching squares
//! on the pixel centres) and the outlines (edges between pixels of different components) are
//! drawn in pixel units under one transform, so their coordinates are small numbers.

use std::collections::BTreeMap;
use std::fmt::Write as _;

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

/// The downsampled plane: `m × m` pixels, index `b · m + a` for column a (time t) and row b
/// (time t′, upwards).
struct Grid {
    m: usize,
    /// δ of each pixel's pair.
    distance: Vec<f64>,
    /// The component of each pixel's pair (`None`: not in S_γ, or no labels available).
    label: Vec<Option<u32>>,
}

/// For `m` pixels evenly over `[0, span]`, the pose nearest each pixel's centre time
/// (`relative_s`: pose times from the first, increasing).
fn pixel_poses(relative_s: &[f64], m: usize) -> Vec<usize> {
    let span = relative_s.last().copied().unwrap_or(0.0);
    (0..m)
        .map(|k| {
            let centre = (k as f64 + 0.5) * span / m as f64;
            let after = relative_s.partition_point(|&t| t < centre).min(relative_s.len() - 1);
            if after > 0 && centre - relative_s[after - 1] <= relative_s[after] - centre { after - 1 } else { after }
        })
        .collect()
}

fn grid(input: &ReportInput<'_>, poses: &[usize], relative_s: &[f64]) -> Grid {
    let (traj, loops) = (input.traj, input.loops);
    let m = poses.len();
    let mut distance = vec![0.0; m * m];
    for b in 0..m {
        for a in 0..=b {
            let d = input.metric.distance(traj.point(poses[a]), traj.point(poses[b]));
            (distance[b * m + a], distance[a * m + b]) = (d, d);
        }
    }
    // Labels from the runs of S_γ: every component gets the pixels its cells fall in, however
    // small it is. Where components share a pixel, a non-trivial one wins over a trivial one,
    // then the larger area.
    let mut label: Vec<Option<u32>> = vec![None; m * m];
    let components = loops.components();
    if loops.len() == relative_s.len() && m > 0 {
        let span_s = relative_s[relative_s.len() - 1];
        let pixel = |i: usize| ((relative_s[i] / span_s * m as f64) as usize).min(m - 1);
        let rank = |c: u32| components.get(c as usize).map(|c| (!c.trivial, c.area_s2));
        let mut claim = |at: usize, c: u32| {
            let wins = match label[at] {
                None => true,
                Some(old) => old != c && rank(c).partial_cmp(&rank(old)) == Some(std::cmp::Ordering::Greater),
            };
            if wins {
                label[at] = Some(c);
            }
        };
        for run in loops.runs() {
            let a = pixel(run.row);
            for b in pixel(run.start)..=pixel(run.end) {
                claim(b * m + a, run.component as u32);
                claim(a * m + b, run.component as u32);
            }
        }
    }
    Grid { m, distance, label }
}

/// Joins edges (pairs of vertex ids) into polylines, each a list of vertex ids (closed ones end
/// where they start). Deterministic: chains start at the first unused edge, in input order.
fn chains(edges: &[(u32, u32)]) -> Vec<Vec<u32>> {
    let mut ends: Vec<(u32, u32)> =
        edges.iter().enumerate().flat_map(|(k, &(a, b))| [(a, k as u32), (b, k as u32)]).collect();
    ends.sort_unstable();
    let mut used = vec![false; edges.len()];
    let next = |vertex: u32, used: &[bool]| -> Option<usize> {
        let first = ends.partition_point(|e| e.0 < vertex);
        ends[first..].iter().take_while(|e| e.0 == vertex).map(|e| e.1 as usize).find(|&k| !used[k])
    };
    let extend = |line: &mut Vec<u32>, used: &mut Vec<bool>| {
        while let Some(&end) = line.last() {
            let Some(k) = next(end, used) else { break };
            used[k] = true;
            let (a, b) = edges[k];
            line.push(if a == end { b } else { a });
        }
    };
    let mut result = Vec::new();
    for k in 0..edges.len() {
        if used[k] {
            continue;
        }
        used[k] = true;
        let (a, b) = edges[k];
        let mut forward = vec![a, b];
        extend(&mut forward, &mut used);
        let mut backward = vec![a];
        if forward.last() != Some(&a) {
            extend(&mut backward, &mut used);
        }
        backward.reverse();
        backward.pop();
        backward.extend(forward);
        result.push(backward);
    }
    result
}

/// The `level` isocontour of `values` (m × m, pixel centres at (a + ½, b + ½)) by marching
/// squares, as polylines in pixel units. Saddles are resolved by the cell's mean.
fn isocontour(values: &[f64], m: usize, level: f64) -> Vec<Vec<(f64, f64)>> {
    let v = |a: usize, b: usize| values[b * m + a] - level;
    // Grid edges between pixel centres: 2(b·m + a) to the right of (a, b), + 1 above it.
    let right = |a: usize, b: usize| 2 * (b * m + a) as u32;
    let up = |a: usize, b: usize| 2 * (b * m + a) as u32 + 1;
    let mut segments = Vec::new();
    for b in 0..m.saturating_sub(1) {
        for a in 0..m - 1 {
            let corners = [v(a, b), v(a + 1, b), v(a + 1, b + 1), v(a, b + 1)];
            let case = corners.iter().enumerate().fold(0, |acc, (k, &c)| acc | (usize::from(c <= 0.0) << k));
            let (bottom, east, top, west) = (right(a, b), up(a + 1, b), right(a, b + 1), up(a, b));
            let centre_inside = corners.iter().sum::<f64>() <= 0.0;
            let pairs: &[(u32, u32)] = match case {
                0 | 15 => &[],
                1 | 14 => &[(west, bottom)],
                2 | 13 => &[(bottom, east)],
                3 | 12 => &[(west, east)],
                4 | 11 => &[(east, top)],
                6 | 9 => &[(bottom, top)],
                7 | 8 => &[(west, top)],
                5 if centre_inside => &[(bottom, east), (top, west)],
                5 => &[(west, bottom), (east, top)],
                10 if centre_inside => &[(west, bottom), (east, top)],
                _ => &[(bottom, east), (top, west)],
            };
            segments.extend_from_slice(pairs);
        }
    }
    let point = |edge: u32| {
        let (cell, vertical) = ((edge / 2) as usize, edge % 2 == 1);
        let (a, b) = (cell % m, cell / m);
        let (v0, v1) = if vertical { (v(a, b), v(a, b + 1)) } else { (v(a, b), v(a + 1, b)) };
        let f = if v0 == v1 { 0.5 } else { (v0 / (v0 - v1)).clamp(0.0, 1.0) };
        let (x, y) = (a as f64 + 0.5, b as f64 + 0.5);
        if vertical { (x, y + f) } else { (x + f, y) }
    };
    chains(&segments).into_iter().map(|line| line.into_iter().map(point).collect()).collect()
}

/// Per component (by id, ascending), the edges between its pixels and the others, as polylines
/// of lattice vertices `(x, y)` (pixel corners, in pixel units).
fn outlines(grid: &Grid) -> BTreeMap<u32, Vec<Vec<(u32, u32)>>> {
    let m = grid.m;
    let side = m as u32 + 1;
    let label = |a: usize, b: usize| grid.label[b * m + a];
    let mut edges: BTreeMap<u32, Vec<(u32, u32)>> = BTreeMap::new();
    let mut add = |c: Option<u32>, edge: (u32, u32)| {
        if let Some(c) = c {
            edges.entry(c).or_default().push(edge);
        }
    };
    let vertex = |a: usize, b: usize| b as u32 * side + a as u32;
    for b in 0..m {
        for a in 0..=m {
            // The vertical edge left of pixel (a, b).
            let left = if a > 0 { label(a - 1, b) } else { None };
            let here = if a < m { label(a, b) } else { None };
            if left != here {
                let edge = (vertex(a, b), vertex(a, b + 1));
                add(left, edge);
                add(here, edge);
            }
        }
    }
    for b in 0..=m {
        for a in 0..m {
            // The horizontal edge below pixel (a, b).
            let below = if b > 0 { label(a, b - 1) } else { None };
            let here = if b < m { label(a, b) } else { None };
            if below != here {
                let edge = (vertex(a, b), vertex(a + 1, b));
                add(below, edge);
                add(here, edge);
            }
        }
    }
    edges
        .into_iter()
        .map(|(c, edges)| {
            let lines = chains(&edges)
                .into_iter()
                .map(|line| line.into_iter().map(|v| (v % side, v / side)).collect())
                .collect();
            (c, lines)
        })
        .collect()
}

/// Path data of lattice polylines: absolute start, then relative `h`/`v` moves, one per
/// straight run.
fn lattice_path(lines: &[Vec<(u32, u32)>]) -> String {
    let mut d = String::new();
    for line in lines {
        let Some(&(x0, y0)) = line.first() else { continue };
        let _ = write!(d, "M{x0} {y0}");
        let mut run: Option<(bool, i64)> = None; // (horizontal, length)
        for w in line.windows(2) {
            let (dx, dy) = (i64::from(w[1].0) - i64::from(w[0].0), i64::from(w[1].1) - i64::from(w[0].1));
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

/// Figure: the pairwise distance with the γ isocontour, component outlines and samples.
pub(super) fn distance_figure(input: &ReportInput<'_>) -> Markup {
    let (traj, loops) = (input.traj, input.loops);
    let t0 = traj.timestamps_s()[0];
    let relative_s: Vec<f64> = traj.timestamps_s().iter().map(|t| t - t0).collect();
    let span_s = traj.span_s();
    let m = traj.len().min(MAX_GRID);
    let poses = pixel_poses(&relative_s, m);
    let grid = grid(input, &poses, &relative_s);
    let gamma = loops.gamma();
    // A square-root colour scale: the small distances, where S_γ and its near misses are, get
    // most of the colours.
    let d_max = grid.distance.iter().copied().filter(|d| d.is_finite()).fold(0.0, f64::max);
    let colour_scale = Scale::sqrt(0.0, if d_max > 0.0 { d_max } else { gamma }).onto(0.0, 1.0);
    let area = Rect { left: 64.0, top: 10.0, width: AREA_SIDE, height: AREA_SIDE };
    let mut plot = Plot::new(
        "fig-distance",
        area.right() + 120.0,
        area.bottom() + 48.0,
        area,
        Scale::linear(0.0, span_s),
        Scale::linear(0.0, span_s),
    );

    // The image, in 256 shades: row 0 at the top is the last t′.
    let palette = (0..=255).map(|k| ICE.at(f64::from(k) / 255.0)).collect();
    let mut image = PaletteImage::new(m as u32, m as u32, palette);
    for b in 0..m {
        for a in 0..m {
            let shade = (colour_scale.map(grid.distance[b * m + a]).clamp(0.0, 1.0) * 255.0).round() as u8;
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
    let outlined = outlines(&grid);
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
    for line in isocontour(&grid.distance, m, gamma) {
        for (k, &(x, y)) in line.iter().enumerate() {
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

    // Components whose every pixel a larger one holds: a cross at their closest pair.
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
         (dark: close). White line: the γ = {gamma} isocontour of these δ. Coloured: the pixels holding pairs of the \
         {nontrivial} non-trivial loop components, in both halves (grey: the trivial one{trivials}, along the \
         diagonal), so that every component shows however small{labelled}. \
         {small}Red dots: {dots_text} at (t, t′), t ≤ t′.",
        down = if m < traj.len() {
            format!(
                " of {} s each, showing the pair of poses nearest its centre ({} poses downsampled)",
                three_digits(span_s / m as f64),
                traj.len()
            )
        } else {
            String::new()
        },
        trivials = if components.iter().filter(|c| c.trivial).count() > 1 { "s" } else { "" },
        labelled = match LABELLED_COMPONENTS.min(nontrivial) {
            0 => String::new(),
            1 => "; it is labelled with its id".to_owned(),
            count => format!("; the {count} largest are labelled with their id"),
        },
        small = match small.len() {
            0 => String::new(),
            count => format!(
                "{count} component{s} sharing every pixel with larger ones {are} marked + at {their} closest \
                 pair{shown}. ",
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
    fn pixels_take_the_nearest_pose() {
        let relative_s = [0.0, 1.0, 2.0, 10.0];
        // Centres at 1.25, 3.75, 6.25 and 8.75 s.
        assert_eq!(pixel_poses(&relative_s, 4), [1, 2, 3, 3]);
        assert_eq!(pixel_poses(&relative_s, 1), [2]);
    }

    #[test]
    fn three_digits_are_shown() {
        assert_eq!(three_digits(18.9), "18.9");
        assert_eq!(three_digits(0.125), "0.125");
        assert_eq!(three_digits(2500.4), "2500");
        assert_eq!(three_digits(1.0), "1.00");
    }

    #[test]
    fn chains_join_edges_into_closed_and_open_lines() {
        // A unit square (out of order) and a separate open path.
        let square = [(0, 1), (2, 3), (1, 2), (3, 0)];
        let got = chains(&square);
        assert_eq!(got.len(), 1);
        assert_eq!(got[0].len(), 5);
        assert_eq!(got[0].first(), got[0].last());
        assert_eq!(chains(&[(5, 6), (7, 8), (6, 7)]), [vec![5, 6, 7, 8]]);
        assert!(chains(&[]).is_empty());
    }

    #[test]
    fn isocontour_of_a_bump_is_one_closed_line() {
        let m = 9;
        let values: Vec<f64> = (0..m * m)
            .map(|k| {
                let (a, b) = ((k % m) as f64 - 4.0, (k / m) as f64 - 4.0);
                a.hypot(b)
            })
            .collect();
        let lines = isocontour(&values, m, 2.5);
        assert_eq!(lines.len(), 1);
        assert_eq!(lines[0].first(), lines[0].last());
        for &(x, y) in &lines[0] {
            let r = (x - 4.5).hypot(y - 4.5);
            assert!((r - 2.5).abs() < 0.3, "{r}");
        }
        assert!(isocontour(&values, m, -1.0).is_empty());
        assert!(isocontour(&[0.0], 1, 1.0).is_empty());
    }

    #[test]
    fn lattice_paths_merge_straight_runs() {
        let square = vec![vec![(0, 0), (1, 0), (2, 0), (2, 1), (2, 2), (1, 2), (0, 2), (0, 1), (0, 0)]];
        assert_eq!(lattice_path(&square), "M0 0h2v2h-2v-2z");
    }
}
