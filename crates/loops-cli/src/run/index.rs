//! `index.html`: the batch of `loops run` at a glance, a row per log linking to its report.

use maud::{PreEscaped, html};
use percent_encoding::utf8_percent_encode;

use super::BatchSummary;
use crate::report::{SEGMENT, page};

/// The page's style sheet.
const STYLE: &str = include_str!("index.css");

/// The page, as one HTML string (inline CSS, no script, no link but to the logs' reports).
pub(crate) fn render(batch: &BatchSummary<'_>) -> String {
    let title = html! { "loops run: " (batch.logs) " logs" };
    let body = html! {
        h1 { "Inexact loops: " (batch.logs) " logs" }
        p {
            "γ = " (batch.settings.gamma) " (" (batch.settings.metric) "); sampler " (batch.settings.sampler) " (" (batch.settings.sample_size)
            ", seed " (batch.settings.seed) @if batch.settings.skip_trivial { ", trivial components skipped" } "); ε = "
            (batch.settings.epsilon_s) " s. " (batch.succeeded) " done, " (batch.failed) " failed, in "
            (format!("{:.1}", batch.seconds)) " s."
        }
        table #logs {
            thead {
                tr {
                    th { "log" } th { "source" } th { "poses" } th { "span (s)" } th { "components" }
                    th { "non-trivial" } th { "pose pairs (i < j)" } th { "loop density (s)" } th { "samples" }
                    th { "P1 (non-trivial)" } th { "time (s)" } th { "status" }
                }
            }
            tbody {
                @for r in batch.results {
                    @if let Some(s) = &r.summary {
                        tr {
                            td { a href={ (utf8_percent_encode(&r.name, SEGMENT)) "/report.html" } { (r.name) } }
                            td { (r.source) }
                            td { (s.poses) }
                            td { (format!("{:.1}", s.span_s)) }
                            td { (s.components) }
                            td { (s.nontrivial_components) }
                            td { (s.pose_pair_count) }
                            td { (format!("{:.2}", s.loop_density_s)) }
                            td { (s.samples) }
                            td { (s.quality.nontrivial_covered) "/" (s.quality.nontrivial_components) }
                            td { (format!("{:.2}", s.seconds.total)) }
                            td.ok { "ok" }
                        }
                    } @else {
                        tr.failed {
                            td { (r.name) }
                            td { (r.source) }
                            td colspan="9" { (r.error.as_deref().unwrap_or("unknown error")) }
                            td.bad { "failed" }
                        }
                    }
                }
            }
        }
    };
    page(title, PreEscaped(STYLE.to_string()), body)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folder_names_are_percent_encoded_as_before() {
        let encode = |name: &str| utf8_percent_encode(name, SEGMENT).to_string();
        assert_eq!(encode("urban-drive_0.v2~x"), "urban-drive_0.v2~x");
        assert_eq!(encode("drive <&> a"), "drive%20%3C%26%3E%20a");
        assert_eq!(encode("é#?/"), "%C3%A9%23%3F%2F");
    }
}
