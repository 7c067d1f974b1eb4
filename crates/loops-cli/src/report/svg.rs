//! A small plotting layer for the page: scales (linear, log) with ticks, a plot frame with axes,
//! path data, colour maps and colour bars, written as inline SVG.
//!
//! Coordinates are SVG pixels, y down. Numbers are written with one decimal: a figure of a few
//! hundred pixels needs no more, and it keeps the page small.
//!
//! The elements are written with `write!` rather than with the page's template (maud): path
//! data of thousands of points is formatted number by number into one string, which a template
//! would only pass through. Text in them (labels, titles) is escaped by maud all the same.

use std::fmt::Write as _;

/// `text` escaped for SVG content and attributes, by the page's template engine.
fn escape(text: &str) -> String {
    maud::html! { (text) }.into_string()
}

/// An RGB colour.
pub(crate) type Rgb = [u8; 3];

/// `#rrggbb`.
pub(crate) fn hex(rgb: Rgb) -> String {
    format!("#{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2])
}

/// A pixel coordinate, one decimal, no trailing `.0`.
pub(crate) fn px(out: &mut String, value: f64) {
    let tenths = (value * 10.0).round();
    let tenths = if tenths.is_finite() { tenths as i64 } else { 0 };
    let sign = if tenths < 0 { "-" } else { "" };
    let (whole, tenth) = (tenths.unsigned_abs() / 10, tenths.unsigned_abs() % 10);
    let _ = if tenth == 0 { write!(out, "{sign}{whole}") } else { write!(out, "{sign}{whole}.{tenth}") };
}

/// A sequential colour map: evenly spaced stops, interpolated linearly in RGB.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ColourMap(&'static [Rgb]);

/// Viridis (matplotlib), eleven stops: dark purple (low) to yellow (high).
pub(crate) const VIRIDIS: ColourMap = ColourMap(&[
    [0x44, 0x01, 0x54],
    [0x48, 0x24, 0x75],
    [0x41, 0x44, 0x87],
    [0x35, 0x5f, 0x8d],
    [0x2a, 0x78, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x22, 0xa8, 0x84],
    [0x44, 0xbf, 0x70],
    [0x7a, 0xd1, 0x51],
    [0xbd, 0xdf, 0x26],
    [0xfd, 0xe7, 0x25],
]);

/// Dark navy (low) through mid blue to white (high): distances, under coloured overlays.
pub(crate) const ICE: ColourMap = ColourMap(&[
    [0x0b, 0x1d, 0x3a],
    [0x1c, 0x3b, 0x6b],
    [0x3e, 0x6d, 0x9c],
    [0x8d, 0xb3, 0xd9],
    [0xd6, 0xe4, 0xf2],
    [0xff, 0xff, 0xff],
]);

impl ColourMap {
    /// The colour at `fraction` of the way along (clamped to [0, 1]; NaN is 0).
    pub fn at(self, fraction: f64) -> Rgb {
        let stops = self.0;
        let f = if fraction.is_nan() { 0.0 } else { fraction.clamp(0.0, 1.0) };
        let position = f * (stops.len() - 1) as f64;
        let k = (position.floor() as usize).min(stops.len() - 2);
        let w = position - k as f64;
        let mix = |a: u8, b: u8| (f64::from(a) + w * (f64::from(b) - f64::from(a))).round() as u8;
        [mix(stops[k][0], stops[k + 1][0]), mix(stops[k][1], stops[k + 1][1]), mix(stops[k][2], stops[k + 1][2])]
    }

    /// An SVG `<linearGradient>` bottom (low) to top (high), for a vertical colour bar.
    fn gradient(self, id: &str) -> String {
        let mut out = format!("<linearGradient id=\"{id}\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">");
        let last = (self.0.len() - 1) as f64;
        for (k, &stop) in self.0.iter().enumerate() {
            let _ = write!(out, "<stop offset=\"{:.3}\" stop-color=\"{}\"/>", k as f64 / last, hex(stop));
        }
        out.push_str("</linearGradient>");
        out
    }
}

/// How a scale maps its domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ScaleKind {
    Linear,
    /// Square root: spreads small values, as a colour scale of distances where the small ones
    /// matter.
    Sqrt,
    Log,
}

/// A map from a data interval (the domain) onto a pixel interval (the range, possibly reversed).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Scale {
    kind: ScaleKind,
    domain: [f64; 2],
    range: [f64; 2],
}

impl Scale {
    /// A linear scale of `[lo, hi]`; an empty or non-finite domain is widened to a usable one
    /// (a single value `v` becomes `[v − 0.5, v + 0.5]`), so mapping never divides by zero.
    pub fn linear(lo: f64, hi: f64) -> Self {
        let (lo, hi) = if lo.is_finite() && hi.is_finite() { (lo.min(hi), lo.max(hi)) } else { (0.0, 1.0) };
        let (lo, hi) = if hi - lo > 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
            (lo, hi)
        } else {
            let half = 0.5 * lo.abs().max(1.0);
            (lo - half, hi + half)
        };
        Self { kind: ScaleKind::Linear, domain: [lo, hi], range: [0.0, 1.0] }
    }

    /// A square-root scale of `[lo, hi]` (negative values are taken as 0), widened as
    /// [`linear`](Self::linear).
    pub fn sqrt(lo: f64, hi: f64) -> Self {
        let linear = Self::linear(lo.max(0.0), hi.max(0.0));
        Self { kind: ScaleKind::Sqrt, domain: [linear.domain[0].max(0.0), linear.domain[1]], ..linear }
    }

    /// A log scale of `[lo, hi]` (positive); a non-positive or empty domain is widened (a single
    /// value `v` becomes `[v / 2, 2v]`).
    pub fn log(lo: f64, hi: f64) -> Self {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        let (lo, hi) = match (ok(lo), ok(hi)) {
            (true, true) => (lo.min(hi), lo.max(hi)),
            (true, false) => (lo, lo),
            (false, true) => (hi, hi),
            (false, false) => (1.0, 10.0),
        };
        let (lo, hi) = if hi / lo > 1.0 + 1e-9 { (lo, hi) } else { (lo / 2.0, hi * 2.0) };
        Self { kind: ScaleKind::Log, domain: [lo, hi], range: [0.0, 1.0] }
    }

    /// The same scale onto the pixel interval `from → to`.
    pub fn onto(self, from: f64, to: f64) -> Self {
        Self { range: [from, to], ..self }
    }

    /// Linear or log.
    pub fn kind(&self) -> ScaleKind {
        self.kind
    }

    /// The domain, as widened.
    #[cfg(test)]
    pub fn domain(&self) -> [f64; 2] {
        self.domain
    }

    /// The pixel of `value` (values outside the domain map outside the range; a non-positive
    /// value on a log scale maps below its low end).
    pub fn map(&self, value: f64) -> f64 {
        let [lo, hi] = self.domain;
        let f = match self.kind {
            ScaleKind::Linear => (value - lo) / (hi - lo),
            ScaleKind::Sqrt => (value.max(0.0).sqrt() - lo.sqrt()) / (hi.sqrt() - lo.sqrt()),
            ScaleKind::Log if value > 0.0 => (value / lo).ln() / (hi / lo).ln(),
            ScaleKind::Log => -1.0,
        };
        self.range[0] + f * (self.range[1] - self.range[0])
    }

    /// Round tick values inside the domain, about `target` of them.
    pub fn ticks(&self, target: usize) -> Vec<f64> {
        let [lo, hi] = self.domain;
        match self.kind {
            ScaleKind::Sqrt => {
                // Round values (1, 2, 5 × 10ᵏ and 0), kept where they are far enough apart on the
                // square-root axis.
                let gap = 1.0 / (target.max(1) as f64 + 1.0);
                let fraction = |v: f64| (v.sqrt() - lo.sqrt()) / (hi.sqrt() - lo.sqrt());
                let top = hi.log10().floor() as i32;
                let mut candidates = vec![0.0];
                for k in (top - 6)..=top {
                    candidates.extend([1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)));
                }
                let mut ticks: Vec<f64> = Vec::new();
                for v in candidates.into_iter().filter(|v| (lo..=hi).contains(v)) {
                    if ticks.last().is_none_or(|&last| fraction(v) - fraction(last) >= gap) {
                        ticks.push(v);
                    }
                }
                ticks
            }
            ScaleKind::Linear => {
                let step = nice_step((hi - lo) / target.max(1) as f64);
                let first = (lo / step).ceil() as i64;
                let last = (hi / step + 1e-9).floor() as i64;
                (first..=last).map(|k| k as f64 * step).map(|v| if v.abs() < step * 1e-9 { 0.0 } else { v }).collect()
            }
            ScaleKind::Log => {
                let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
                let decades = (hi / lo).log10();
                let mantissas: &[f64] = if decades <= 2.5 {
                    &[1.0, 2.0, 5.0]
                } else if decades <= 4.0 {
                    &[1.0, 3.0]
                } else {
                    &[1.0]
                };
                let every = ((last - first) as usize).div_ceil(target.max(1)).max(1);
                (first..=last)
                    .filter(|d| ((d - first) as usize).is_multiple_of(every))
                    .flat_map(|d| mantissas.iter().map(move |m| m * 10f64.powi(d)))
                    .filter(|v| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9))
                    .collect()
            }
        }
    }

    /// The text of a tick value among `ticks` (as many decimals as the spacing needs).
    pub fn tick_label(&self, value: f64, ticks: &[f64]) -> String {
        match self.kind {
            ScaleKind::Linear => {
                let step = ticks.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min);
                let decimals =
                    if step.is_finite() && step > 0.0 { (-step.log10().floor()).max(0.0) as usize } else { 1 };
                format!("{value:.decimals$}")
            }
            ScaleKind::Log | ScaleKind::Sqrt => log_label(value),
        }
    }
}

/// 1, 2 or 5 times a power of ten, the first at least `raw`.
fn nice_step(raw: f64) -> f64 {
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let magnitude = 10f64.powf(raw.log10().floor());
    let norm = raw / magnitude;
    let nice = if norm <= 1.0 {
        1.0
    } else if norm <= 2.0 {
        2.0
    } else if norm <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * magnitude
}

/// A label of a 1, 2, 5 × 10ᵏ tick: plain between 0.001 and 99,999 (and 0), else `m·10ᵏ`.
fn log_label(value: f64) -> String {
    if value == 0.0 {
        return "0".to_owned();
    }
    if (1e-3..1e5).contains(&value) {
        let decimals = (-value.log10().floor()).max(0.0) as usize;
        return format!("{value:.decimals$}");
    }
    let exponent = value.log10().floor() as i32;
    let mantissa = (value / 10f64.powi(exponent)).round();
    let superscript: String = exponent
        .to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            d => ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'][d.to_digit(10).unwrap_or(0) as usize],
        })
        .collect();
    if mantissa == 1.0 { format!("10{superscript}") } else { format!("{mantissa}·10{superscript}") }
}

/// A rectangle in pixels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rect {
    pub left: f64,
    pub top: f64,
    pub width: f64,
    pub height: f64,
}

impl Rect {
    pub fn right(&self) -> f64 {
        self.left + self.width
    }

    pub fn bottom(&self) -> f64 {
        self.top + self.height
    }
}

/// SVG path data (`M x y L x y ...`), continuing a polyline when the next segment starts where
/// the last ended.
#[derive(Debug, Default)]
pub(crate) struct PathData {
    d: String,
    end: Option<(f64, f64)>,
}

impl PathData {
    /// Adds the segment `a → b`.
    pub fn segment(&mut self, a: (f64, f64), b: (f64, f64)) {
        if self.end.is_none_or(|e| (e.0 - a.0).abs() > 0.05 || (e.1 - a.1).abs() > 0.05) {
            self.d.push('M');
            px(&mut self.d, a.0);
            self.d.push(' ');
            px(&mut self.d, a.1);
        }
        self.d.push('L');
        px(&mut self.d, b.0);
        self.d.push(' ');
        px(&mut self.d, b.1);
        self.end = Some(b);
    }

    /// A `<path>` element with these data and `attributes` (already escaped), or nothing when
    /// empty.
    pub fn element(&self, attributes: &str) -> String {
        if self.d.is_empty() { String::new() } else { format!("<path d=\"{}\" {attributes}/>", self.d) }
    }
}

/// One SVG figure: a plot area with an x and a y scale, and the elements drawn so far.
#[derive(Debug)]
pub(crate) struct Plot {
    /// Unique prefix of this figure's element ids (clip path, gradients).
    id: String,
    width: f64,
    height: f64,
    pub area: Rect,
    pub x: Scale,
    pub y: Scale,
    defs: String,
    body: String,
}

impl Plot {
    /// A `width × height` figure whose data go in `area`: `x` maps onto it left to right, `y`
    /// bottom to top.
    pub fn new(id: &str, width: f64, height: f64, area: Rect, x: Scale, y: Scale) -> Self {
        Self {
            id: id.to_owned(),
            width,
            height,
            area,
            x: x.onto(area.left, area.right()),
            y: y.onto(area.bottom(), area.top),
            defs: format!(
                "<clipPath id=\"{id}-clip\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/></clipPath>",
                area.left, area.top, area.width, area.height
            ),
            body: String::new(),
        }
    }

    /// The pixel of data point (`x`, `y`).
    pub fn point(&self, x: f64, y: f64) -> (f64, f64) {
        (self.x.map(x), self.y.map(y))
    }

    /// The SVG drawn so far, to append to (already escaped).
    pub fn body_mut(&mut self) -> &mut String {
        &mut self.body
    }

    /// Appends `svg`, clipped to the plot area.
    pub fn push_clipped(&mut self, svg: &str) {
        let _ = write!(self.body, "<g clip-path=\"url(#{}-clip)\">{svg}</g>", self.id);
    }

    /// A filled background for the plot area.
    pub fn background(&mut self, fill: &str) {
        let a = self.area;
        let _ = write!(
            self.body,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{fill}\"/>",
            a.left, a.top, a.width, a.height
        );
    }

    /// Grid lines at the ticks of both scales (under the data: call before drawing them).
    pub fn grid(&mut self, x_ticks: usize, y_ticks: usize) {
        let a = self.area;
        let mut d = PathData::default();
        for v in self.x.ticks(x_ticks) {
            let x = self.x.map(v);
            d.segment((x, a.top), (x, a.bottom()));
        }
        for v in self.y.ticks(y_ticks) {
            let y = self.y.map(v);
            d.segment((a.left, y), (a.right(), y));
        }
        self.body.push_str(&d.element("class=\"grid\""));
    }

    /// The frame, ticks with labels, and axis labels (`x_label`, `y_label` are plain text).
    pub fn axes(&mut self, x_label: &str, y_label: &str, x_ticks: usize, y_ticks: usize) {
        let a = self.area;
        let mut d = PathData::default();
        let mut labels = String::new();
        let ticks = self.x.ticks(x_ticks);
        for &v in &ticks {
            let x = self.x.map(v);
            d.segment((x, a.bottom()), (x, a.bottom() + 4.0));
            let _ = write!(
                labels,
                "<text x=\"{x:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{}</text>",
                a.bottom() + 16.0,
                escape(&self.x.tick_label(v, &ticks))
            );
        }
        let ticks = self.y.ticks(y_ticks);
        for &v in &ticks {
            let y = self.y.map(v);
            d.segment((a.left - 4.0, y), (a.left, y));
            let _ = write!(
                labels,
                "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">{}</text>",
                a.left - 7.0,
                y + 4.0,
                escape(&self.y.tick_label(v, &ticks))
            );
        }
        let _ = write!(
            self.body,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" class=\"frame\"/>{}{labels}\
             <text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\" class=\"label\">{}</text>\
             <text transform=\"translate({:.1} {:.1}) rotate(-90)\" text-anchor=\"middle\" class=\"label\">{}</text>",
            a.left,
            a.top,
            a.width,
            a.height,
            d.element("class=\"tick\""),
            a.left + 0.5 * a.width,
            a.bottom() + 36.0,
            escape(x_label),
            a.left - 46.0,
            a.top + 0.5 * a.height,
            escape(y_label)
        );
    }

    /// A vertical colour bar right of the plot area for `map` over `scale`'s domain, labelled
    /// `label`; `marks` are extra labelled ticks (e.g. γ) drawn across the bar.
    pub fn colour_bar(&mut self, map: ColourMap, scale: Scale, label: &str, marks: &[(f64, &str)]) {
        let a = self.area;
        let (left, width) = (a.right() + 16.0, 14.0);
        let scale = scale.onto(a.bottom(), a.top);
        let gradient_id = format!("{}-bar", self.id);
        self.defs.push_str(&map.gradient(&gradient_id));
        let _ = write!(
            self.body,
            "<rect x=\"{left}\" y=\"{}\" width=\"{width}\" height=\"{}\" fill=\"url(#{gradient_id})\" class=\"bar\"/>",
            a.top, a.height
        );
        let ticks = scale.ticks(6);
        let mut d = PathData::default();
        for &v in &ticks {
            let y = scale.map(v);
            d.segment((left + width, y), (left + width + 4.0, y));
            let _ = write!(
                self.body,
                "<text x=\"{:.1}\" y=\"{:.1}\">{}</text>",
                left + width + 7.0,
                y + 4.0,
                escape(&scale.tick_label(v, &ticks))
            );
        }
        self.body.push_str(&d.element("class=\"tick\""));
        for &(value, text) in marks {
            let y = scale.map(value);
            if (a.top - 0.5..=a.bottom() + 0.5).contains(&y) {
                let _ = write!(
                    self.body,
                    "<path d=\"M{:.1} {y:.1}H{:.1}\" class=\"mark\"/><text x=\"{:.1}\" y=\"{:.1}\" \
                     text-anchor=\"end\" class=\"mark-label\">{}</text>",
                    left - 3.0,
                    left + width + 3.0,
                    left - 5.0,
                    y + 4.0,
                    escape(text)
                );
            }
        }
        let _ = write!(
            self.body,
            "<text transform=\"translate({:.1} {:.1}) rotate(90)\" text-anchor=\"middle\" class=\"label\">{}</text>",
            left + width + 50.0,
            a.top + 0.5 * a.height,
            escape(label)
        );
    }

    /// The figure as an `<svg>` element, described by `title` for screen readers.
    pub fn finish(self, title: &str) -> String {
        format!(
            "<svg viewBox=\"0 0 {w} {h}\" width=\"{w}\" height=\"{h}\" \
             role=\"img\"><title>{title}</title><defs>{defs}</defs>{body}</svg>",
            w = self.width,
            h = self.height,
            title = escape(title),
            defs = self.defs,
            body = self.body
        )
    }
}

/// A marker shape, one per category of a scatter plot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Marker {
    Circle,
    Square,
    Triangle,
    Diamond,
    Cross,
    Plus,
    TriangleDown,
    Star,
}

impl Marker {
    pub const ALL: [Marker; 8] = [
        Marker::Circle,
        Marker::Square,
        Marker::Triangle,
        Marker::Diamond,
        Marker::Cross,
        Marker::Plus,
        Marker::TriangleDown,
        Marker::Star,
    ];

    /// Path data for the marker centred at (`x`, `y`), about `r` pixels in radius.
    pub fn path(self, out: &mut String, (x, y): (f64, f64), r: f64) {
        let mut point = |command: char, dx: f64, dy: f64| {
            out.push(command);
            px(out, x + dx);
            out.push(' ');
            px(out, y + dy);
        };
        match self {
            Marker::Circle => {
                // Two arcs.
                point('M', -r, 0.0);
                let _ = write!(out, "a{r:.1} {r:.1} 0 1 0 {:.1} 0a{r:.1} {r:.1} 0 1 0 {:.1} 0", 2.0 * r, -2.0 * r);
            }
            Marker::Square => {
                let s = 0.85 * r;
                point('M', -s, -s);
                point('L', s, -s);
                point('L', s, s);
                point('L', -s, s);
                out.push('Z');
            }
            Marker::Triangle | Marker::TriangleDown => {
                let flip = if self == Marker::Triangle { 1.0 } else { -1.0 };
                point('M', 0.0, -1.15 * r * flip);
                point('L', r, 0.75 * r * flip);
                point('L', -r, 0.75 * r * flip);
                out.push('Z');
            }
            Marker::Diamond => {
                let s = 1.2 * r;
                point('M', 0.0, -s);
                point('L', s, 0.0);
                point('L', 0.0, s);
                point('L', -s, 0.0);
                out.push('Z');
            }
            Marker::Cross => {
                point('M', -r, -r);
                point('L', r, r);
                point('M', -r, r);
                point('L', r, -r);
            }
            Marker::Plus => {
                let s = 1.2 * r;
                point('M', -s, 0.0);
                point('L', s, 0.0);
                point('M', 0.0, -s);
                point('L', 0.0, s);
            }
            Marker::Star => {
                let s = 1.2 * r;
                point('M', -s, 0.0);
                point('L', s, 0.0);
                point('M', -0.5 * s, -0.87 * s);
                point('L', 0.5 * s, 0.87 * s);
                point('M', -0.5 * s, 0.87 * s);
                point('L', 0.5 * s, -0.87 * s);
            }
        }
    }

    /// A small standalone SVG of the marker, for an HTML legend.
    pub fn swatch(self, colour: Rgb) -> String {
        let mut d = String::new();
        self.path(&mut d, (8.0, 8.0), 4.5);
        format!(
            "<svg viewBox=\"0 0 16 16\" width=\"16\" height=\"16\" \
             aria-hidden=\"true\"><path d=\"{d}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.6\"/></svg>",
            hex(colour)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_survive_degenerate_domains() {
        for scale in [Scale::linear(3.0, 3.0), Scale::linear(0.0, 0.0), Scale::linear(f64::NAN, 1.0)] {
            let s = scale.onto(0.0, 100.0);
            let [lo, hi] = s.domain();
            assert!(lo < hi);
            assert!(s.map(lo).is_finite() && s.map(hi).is_finite());
            assert!(!s.ticks(5).is_empty());
        }
        for scale in [Scale::sqrt(0.0, 0.0), Scale::sqrt(-3.0, -1.0)] {
            let [lo, hi] = scale.domain();
            assert!(0.0 <= lo && lo < hi);
            assert!(scale.map(lo).is_finite() && scale.map(-1.0).is_finite());
        }
        let s = Scale::sqrt(0.0, 100.0).onto(0.0, 1.0);
        assert_eq!((s.map(25.0), s.map(100.0)), (0.5, 1.0));
        let s = Scale::sqrt(0.0, 1150.0);
        let ticks = s.ticks(6);
        assert_eq!(ticks, [0.0, 50.0, 200.0, 500.0, 1000.0]);
        assert_eq!(s.tick_label(0.0, &ticks), "0");
        for scale in [Scale::log(5.0, 5.0), Scale::log(0.0, 0.0), Scale::log(-1.0, 10.0)] {
            let [lo, hi] = scale.domain();
            assert!(0.0 < lo && lo < hi);
            assert!(scale.map(lo).is_finite());
        }
    }

    #[test]
    fn ticks_are_round_and_labels_short() {
        let s = Scale::linear(0.0, 7560.0);
        let ticks = s.ticks(5);
        assert_eq!(ticks, [0.0, 2000.0, 4000.0, 6000.0]);
        assert_eq!(s.tick_label(2000.0, &ticks), "2000");
        let s = Scale::linear(-0.13, 0.27);
        let ticks = s.ticks(4);
        assert_eq!(s.tick_label(ticks[1], &ticks), "0.0");
        let s = Scale::log(3.0, 2.0e6);
        assert_eq!(s.ticks(8), [10.0, 100.0, 1000.0, 1e4, 1e5, 1e6]);
        assert_eq!(s.tick_label(1e6, &[]), "10⁶");
        assert_eq!(s.tick_label(100.0, &[]), "100");
        assert_eq!(Scale::log(2.0, 9.0).ticks(5), [2.0, 5.0]);
    }

    #[test]
    fn colour_maps_interpolate_and_clamp() {
        assert_eq!(VIRIDIS.at(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(VIRIDIS.at(1.0), [0xfd, 0xe7, 0x25]);
        assert_eq!(VIRIDIS.at(7.0), VIRIDIS.at(1.0));
        assert_eq!(VIRIDIS.at(f64::NAN), VIRIDIS.at(0.0));
        assert_eq!(hex(ICE.at(0.0)), "#0b1d3a");
        assert_eq!(hex(ICE.at(1.0)), "#ffffff");
    }

    #[test]
    fn path_data_continues_polylines() {
        let mut d = PathData::default();
        d.segment((0.0, 0.0), (1.25, 2.0));
        d.segment((1.25, 2.0), (-3.0, 4.04));
        d.segment((9.0, 9.0), (10.0, 10.0));
        assert_eq!(d.element("x"), "<path d=\"M0 0L1.3 2L-3 4M9 9L10 10\" x/>");
    }
}
