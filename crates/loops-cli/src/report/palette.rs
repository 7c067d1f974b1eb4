//! The page's colours and marker shapes: one per sampler and one per component, the same on
//! every page, and the CSS classes of the components table's swatches.

use std::fmt::Write as _;

use loops_core::{LoopComponent, SamplerKind};
// Outline colours of non-trivial and trivial components: those of the viewers' scenes, so a
// component has one colour on the page and in Foxglove, RViz or Rerun.
use loops_io::{COMPONENT_RGB as OUTLINE_COLOURS, TRIVIAL_RGB as TRIVIAL_COLOUR};
use maud::{Markup, PreEscaped, html};

use super::svg::{self, Marker, Rgb};

/// One colour per sampler (as `SamplerKind::ALL`): the four samplers of the paper far apart.
const SAMPLER_COLOURS: [Rgb; 9] = [
    [0x4e, 0x79, 0xa7],
    [0xf2, 0x8e, 0x2b],
    [0x9c, 0x75, 0x5f],
    [0xe1, 0x57, 0x59],
    [0xed, 0xc9, 0x48],
    [0x59, 0xa1, 0x4f],
    [0xb0, 0x7a, 0xa1],
    [0x76, 0xb7, 0xb2],
    [0x7f, 0x7f, 0x7f],
];

/// Session colours for a fleet of at most ten sessions (Tableau 10).
const SESSION_COLOURS: [Rgb; 10] = [
    [0x4e, 0x79, 0xa7],
    [0xf2, 0x8e, 0x2b],
    [0xe1, 0x57, 0x59],
    [0x76, 0xb7, 0xb2],
    [0x59, 0xa1, 0x4f],
    [0xed, 0xc9, 0x48],
    [0xb0, 0x7a, 0xa1],
    [0xff, 0x9d, 0xa7],
    [0x9c, 0x75, 0x5f],
    [0xba, 0xb0, 0xac],
];

/// The colour of session `k` of a fleet of `n`: Tableau 10 up to ten sessions, beyond that hues
/// a golden angle apart (neighbours in fleet order far apart on the colour wheel).
pub(crate) fn session_colour(k: usize, n: usize) -> Rgb {
    if n <= SESSION_COLOURS.len() {
        return SESSION_COLOURS[k % SESSION_COLOURS.len()];
    }
    let hue = (k as f64 * 0.618_033_988_749_895).fract() * 6.0;
    // HSL with saturation 0.65 and lightness 0.45, to RGB.
    let (lightness, saturation) = (0.45, 0.65);
    let chroma = (1.0 - (2.0 * lightness - 1.0_f64).abs()) * saturation;
    let x = chroma * (1.0 - (hue % 2.0 - 1.0).abs());
    let (r, g, b) = match hue as u32 {
        0 => (chroma, x, 0.0),
        1 => (x, chroma, 0.0),
        2 => (0.0, chroma, x),
        3 => (0.0, x, chroma),
        4 => (x, 0.0, chroma),
        _ => (chroma, 0.0, x),
    };
    let m = lightness - chroma / 2.0;
    let byte = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    [byte(r), byte(g), byte(b)]
}

/// The sampler's name as HTML: its symbol in the paper, and the name `--sampler` takes.
pub(crate) fn sampler_name(kind: SamplerKind) -> Markup {
    // Fixed markup (subscripts), not text: nothing here comes from the input.
    let symbol = match kind {
        SamplerKind::One => "σ<sub>1</sub>",
        SamplerKind::Rho => "σ<sub>ρ</sub>",
        SamplerKind::RhoDispersed => "σ<sub>ρ</sub> dispersed",
        SamplerKind::Alpha => "σ<sub>α</sub>",
        SamplerKind::ClosestFirst => "closest-first σ<sub>ρ</sub>",
        SamplerKind::ClosestThenSpread => "closest-then-spread σ<sub>ρ</sub>",
        SamplerKind::NearestThenUniform => "nearest-then-uniform",
        SamplerKind::LioSam => "LIO-SAM",
        SamplerKind::HdlGraphSlam => "hdl_graph_slam",
        SamplerKind::Cartographer => "Cartographer",
        SamplerKind::TimeGap => "time gap",
    };
    html! { (PreEscaped(symbol)) " " span.cli-name { "(" (kind.name()) ")" } }
}

fn sampler_index(kind: SamplerKind) -> usize {
    SamplerKind::ALL.iter().position(|k| *k == kind).unwrap_or(0)
}

/// One colour per sampler, the same on every page.
pub(super) fn sampler_colour(kind: SamplerKind) -> Rgb {
    SAMPLER_COLOURS[sampler_index(kind) % SAMPLER_COLOURS.len()]
}

/// One marker shape per sampler, the same on every page.
pub(super) fn sampler_marker(kind: SamplerKind) -> Marker {
    Marker::ALL[sampler_index(kind) % Marker::ALL.len()]
}

/// A component's colour in the distance figure and the table: grey for trivial ones.
pub(super) fn component_colour(c: &LoopComponent) -> Rgb {
    if c.trivial { TRIVIAL_COLOUR } else { OUTLINE_COLOURS[c.id % OUTLINE_COLOURS.len()] }
}

/// The class of a component's colour swatch in the table (`kt`, `k0`, `k1`, ...).
pub(super) fn swatch_class(c: &LoopComponent) -> String {
    if c.trivial { "kt".to_owned() } else { format!("k{}", c.id % OUTLINE_COLOURS.len()) }
}

/// The style of the swatch classes, from the same colours as the figures.
pub(super) fn swatch_style() -> String {
    let mut style = format!(".kt {{ background: {}; }}", svg::hex(TRIVIAL_COLOUR));
    for (k, &colour) in OUTLINE_COLOURS.iter().enumerate() {
        let _ = write!(style, " .k{k} {{ background: {}; }}", svg::hex(colour));
    }
    style
}
