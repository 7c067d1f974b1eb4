//! The summary cards at the top of the page (trajectory, loops, samples with their P1–P3) and
//! the warnings of the run.

use loops_core::{Scale, Selection, Side};
use maud::{Markup, html};

use super::ReportInput;
use super::numbers::{duration_text, percent, plural, thousands};
use super::palette::sampler_name;

/// What the samples were chosen from, named as the loops card names them: detections, or
/// pose pairs (i < j).
fn candidates_name(samples: &loops_core::Samples) -> &'static str {
    if samples.rows().iter().any(|s| s.detection.is_some()) { "detections" } else { "pose pairs" }
}

/// The summary cards: trajectory, loops, samples.
pub(super) fn cards(input: &ReportInput<'_>) -> Markup {
    let (traj, loops, samples, quality) = (input.traj, input.loops, input.samples, input.quality);
    let t = traj.timestamps_s();
    let span_s = traj.span_s();
    let components = loops.components();
    let nontrivial = components.iter().filter(|c| !c.trivial).count();
    let density = loops
        .loop_density(t[0], t[t.len() - 1], Selection::All, Side::Both, Scale::Seconds)
        .ok()
        .filter(|d| d.is_finite());
    let count = thousands(samples.len() as u64);
    html! {
        section.cards {
            div.card {
                h2 { "Trajectory" }
                dl {
                    dt { "poses" } dd { (thousands(traj.len() as u64)) }
                    dt { "time span" } dd { (duration_text(span_s)) }
                    dt { "metric" } dd { code { (loops.metric_name()) } }
                    dt { "measured" } dd { (input.measured) }
                    dt { "map plane" } dd { (super::trajectory::plane_name(input.plane)) }
                    dt { "γ" } dd { (loops.gamma()) }
                    dt { "separation" }
                    dd {
                        @if loops.is_separated() {
                            "revisits: pairs " (loops.separation().to_string().replace(">=", "≥"))
                            span.muted { " apart along the trajectory" }
                        } @else {
                            "none " span.muted { "(the paper's S" sub { "γ" } ", trivial components included)" }
                        }
                    }
                }
            }
            div.card {
                h2 { "Loops" }
                dl {
                    dt { "components" }
                    dd { b { (nontrivial) } " non-trivial, " (components.len() - nontrivial) " trivial" }
                    dt { "pose pairs in S" sub { "γ" } }
                    dd { (thousands(loops.pose_pair_count())) span.muted { " (i < j)" } }
                    dt { "loop density ρ" }
                    dd {
                        @if let Some(d) = density {
                            (format!("{d:.1}")) " s "
                            span.muted { "(mean loop duration; " (format!("{:.2}", 100.0 * d / span_s)) " % of the span)" }
                        } @else {
                            "—"
                        }
                    }
                    dt { "time to find" } dd { (format!("{:.3}", input.seconds)) " s" }
                }
            }
            div.card {
                h2 { "Samples" }
                dl {
                    dt { "sampler" }
                    dd {
                        (sampler_name(samples.sampler())) ": " b { (count) } " samples of "
                        (thousands(samples.available())) " " (candidates_name(samples))
                        @if input.skip_trivial { " (trivial components skipped)" }
                    }
                    dt { "P1 coverage" }
                    dd {
                        b { (quality.covered) " / " (quality.components) } " components ("
                        (percent(quality.covered, quality.components)) "); non-trivial "
                        (quality.nontrivial_covered) " / " (quality.nontrivial_components)
                    }
                    @if !quality.missed.is_empty() {
                        dt { "missed" }
                        dd {
                            (quality.missed.iter().take(5).map(|m| format!("#{} ({:.0} s²)", m.id, m.area_s2))
                                .collect::<Vec<_>>().join(", "))
                            @if quality.missed.len() > 5 { " and " (quality.missed.len() - 5) " more" }
                        }
                    }
                    dt { "P2 redundant" }
                    dd {
                        b { (quality.redundant) } " of " (count) " (" (percent(quality.redundant, quality.samples))
                        ") within ε = " (input.epsilon_s) " s"
                        @if let Some(s) = quality.median_spacing_s { "; median spacing " (format!("{s:.1}")) " s" }
                    }
                    dt { "P3 slope" }
                    dd {
                        b { (quality.p3_slope.map_or("—".to_owned(), |s| format!("{s:.2}"))) } " "
                        span.muted {
                            "(ln samples on ln area, " (plural(quality.p3_components, "component", "components"))
                            "; σ" sub { "1" } " ≈ 0, σ" sub { "α" } " ≈ 1)"
                        }
                    }
                    @if quality.outside_components() > 0 {
                        dt { "in no component" }
                        dd {
                            (quality.outside_components()) " of " (quality.samples)
                            span.muted { " samples (not a pair of S" sub { "γ" } "): P1 counts the others" }
                        }
                    }
                    @if quality.outside > 0 {
                        dt { "outside S" sub { "γ" } } dd { (quality.outside) }
                    }
                }
            }
        }
    }
}

/// The warnings of the loops and of the samples, if any.
pub(super) fn warnings(input: &ReportInput<'_>) -> Markup {
    let all: Vec<String> = input
        .loops
        .warnings()
        .iter()
        .map(ToString::to_string)
        .chain(input.samples.warnings().iter().map(ToString::to_string))
        .collect();
    html! {
        @if !all.is_empty() {
            section.warnings {
                h2 { "Warnings" }
                ul { @for warning in &all { li { (warning) } } }
            }
        }
    }
}
