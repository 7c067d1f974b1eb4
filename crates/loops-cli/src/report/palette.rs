//! The page's colours and marker shapes: one per sampler and one per component, the same on
//! every page, and the CSS classes of the components table's swatches.

use std::fmt::Write as _;

use loops_core::{LoopComponent, SamplerKind};
use maud::{Markup, PreEscaped, html};

use super::svg::{self, Marker, Rgb};

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

/// The sampler's name as HTML: its symbol in the paper, and the name `--sampler` takes.
pub(super) fn sampler_name(kind: SamplerKind) -> Markup {
    // Fixed markup (subscripts), not text: nothing here comes from the input.
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
