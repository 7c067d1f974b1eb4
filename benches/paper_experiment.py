#!/usr/bin/env python3
"""The sampling experiment of the paper (Sec. 5.5) through the Python API, with the exact
components route and the baselines of deployed SLAM systems; writes its table into
BENCHMARKS.md.

Usage::

    python benches/paper_experiment.py [--budget B] [--seed S] [--no-write] [--output PATH]

The reference urban drive (``il.urban_drive()``, 75,600 poses, 2.1 h at 10 Hz),
γ = 40 m, 1% of the pairs of S_γ drawn as detections, ε = 30 s, a budget of 1e4 samples per
sampler. Every sampler runs on the detection clusters (σ_1, σ_ρ, dispersed σ_ρ, σ_α) and on the
exact loop components (the same four and the baselines of LIO-SAM, hdl_graph_slam,
Cartographer and a time-gap rule), and the four again on the non-trivial components only
(``skip_trivial=True``). P1, P2 and P3 are measured against the exact components of
S_γ with ``il.sample_quality``. The same run as ``cargo run --release -p loops-core --example
paper_experiment``, through the bindings.

The section ``<!-- paper_experiment -->`` of BENCHMARKS.md is replaced (up to the next marker
line or the end of the file; a new one goes before the other marker sections), the rest of the
file is left as it is.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from harness import REPO, machine_facts, write_section

import inexact_loops as il

GAMMA_M = 40.0
EPSILON_S = 30.0
DETECTION_RATE = 0.01
SECTION = "paper_experiment"
SAMPLERS = ("one", "rho", "rho-dispersed", "alpha")
BASELINES = ("lio-sam", "hdl-graph-slam", "cartographer", "time-gap")
LARGEST = 10

HEADER = (
    "| route | sampler | samples | P1 all | P1 non-trivial | P1 small half | largest missed "
    "non-trivial (s²) | P2 redundant | P2 spacing (s) | P2 spacing non-trivial (s) | P3 slope | "
    "trivial | big10 | mean distance (m) | time (s) | notes |"
)


def row(route: str, samples: il.Samples, loops: il.Loops, seconds: float) -> tuple[str, dict]:
    """One line of the table, and the numbers the summary reads."""
    quality = il.sample_quality(samples, loops, epsilon_s=EPSILON_S)
    table = loops.components
    trivial, area = table["trivial"], table["area_s2"]
    per = quality.per_component
    comp = quality.sample_components
    missed = quality.missed
    nontrivial = np.flatnonzero(~trivial)
    biggest = nontrivial[np.argsort(-area[nontrivial], kind="stable")][:LARGEST]
    # P1 over the smaller half (by area) of the samplable non-trivial components.
    samplable = np.zeros(len(trivial), bool)
    samplable[per > 0] = True
    samplable[missed["id"]] = True
    candidates = np.flatnonzero(samplable & ~trivial)
    small = candidates[np.argsort(area[candidates], kind="stable")][: len(candidates) // 2]
    small_covered = int((per[small] > 0).sum())
    in_nontrivial = (comp >= 0) & ~trivial[np.maximum(comp, 0)]
    nontrivial_samples = int(in_nontrivial.sum())
    trivial_samples = quality.samples - nontrivial_samples - quality.outside
    spacing = np.sort(
        quality.nearest_spacing_s[in_nontrivial & ~np.isnan(quality.nearest_spacing_s)]
    )
    spacing_nontrivial = spacing[len(spacing) // 2] if len(spacing) else None
    missed_nontrivial = missed["area_s2"][~missed["trivial"]]
    distances = samples.distance[in_nontrivial]

    def optional(value: float | None, digits: int) -> str:
        return "-" if value is None else f"{value:.{digits}f}"

    numbers = {
        "samples": quality.samples,
        "covered": quality.covered,
        "components": quality.components,
        "small_covered": small_covered,
        "small": len(small),
        "big10_share": per[biggest].sum() / max(nontrivial_samples, 1),
        "big10_area_share": area[biggest].sum() / area[nontrivial].sum(),
        "p3": quality.p3_slope,
    }
    warnings = "; ".join(samples.warnings)
    line = (
        f"| {route} | {samples.sampler} | {quality.samples} | {quality.covered}/"
        f"{quality.components} | {quality.nontrivial_covered}/{quality.nontrivial_components} | "
        f"{small_covered}/{len(small)} | "
        f"{f'{missed_nontrivial[0]:.0f}' if len(missed_nontrivial) else '-'} | "
        f"{100 * quality.redundancy:.1f}% | {optional(quality.median_spacing_s, 1)} | "
        f"{optional(spacing_nontrivial, 1)} | {optional(quality.p3_slope, 2)} | "
        f"{100 * trivial_samples / max(quality.samples, 1):.1f}% | "
        f"{100 * numbers['big10_share']:.1f}% | "
        f"{distances.mean() if len(distances) else 0.0:.1f} | {seconds:.3f} | {warnings} |"
    )
    return line, numbers


def slope_text(slope: float | None) -> str:
    return "-" if slope is None else f"{slope:.2f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--budget", type=int, default=10_000, help="samples per sampler")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--output", type=Path, default=REPO / "BENCHMARKS.md", metavar="PATH")
    parser.add_argument("--no-write", action="store_true", help="print the report only")
    args = parser.parse_args()
    budget, seed = args.budget, args.seed

    traj = il.urban_drive()
    start = time.perf_counter()
    loops = il.find_loops(traj, gamma=GAMMA_M, separation=None)
    loops_s = time.perf_counter() - start
    table = loops.components
    start = time.perf_counter()
    detections = il.draw_detections(loops, rate=DETECTION_RATE, seed=seed)
    draw_s = time.perf_counter() - start
    start = time.perf_counter()
    clusters = il.cluster_detections(detections, epsilon_s=EPSILON_S)
    cluster_s = time.perf_counter() - start
    nontrivial = ~table["trivial"]
    area = table["area_s2"]
    pairs_upper = (loops.pair_count - len(traj)) // 2

    lines = [HEADER, "|---|---|" + "---:|" * 13 + "---|"]
    numbers: dict[tuple[str, str], dict] = {}
    for sampler in SAMPLERS:
        start = time.perf_counter()
        samples = il.sample(clusters, sampler, budget=budget, seed=seed)
        seconds = time.perf_counter() - start
        samples = samples.measure(traj)
        line, numbers[("detections", sampler)] = row("detections", samples, loops, seconds)
        lines.append(line)
    for sampler in SAMPLERS + BASELINES:
        start = time.perf_counter()
        samples = il.sample(loops, sampler, budget=budget, seed=seed, trajectory=traj)
        seconds = time.perf_counter() - start
        route = "baseline" if sampler in BASELINES else "exact components"
        line, numbers[(route, sampler)] = row(route, samples, loops, seconds)
        lines.append(line)
    # Beyond the paper: the budget spent on the revisits only, not on simple loops.
    for sampler in SAMPLERS:
        start = time.perf_counter()
        samples = il.sample(
            loops, sampler, budget=budget, seed=seed, trajectory=traj, skip_trivial=True
        )
        seconds = time.perf_counter() - start
        route = "non-trivial components"
        line, numbers[(route, sampler)] = row(route, samples, loops, seconds)
        lines.append(line)

    one, rho, alpha = (numbers[("detections", s)] for s in ("one", "rho", "alpha"))
    reading = [
        f"- σ_α (uniform over detections) covers {alpha['small_covered']}/{alpha['small']} of "
        f"the smaller half of the non-trivial components; σ_1 {one['small_covered']}/"
        f"{one['small']}, σ_ρ {rho['small_covered']}/{rho['small']}.",
        f"- The {LARGEST} largest non-trivial components hold "
        f"{100 * one['big10_area_share']:.0f}% of the non-trivial area; they get "
        f"{100 * one['big10_share']:.0f}% of σ_1's non-trivial samples, "
        f"{100 * rho['big10_share']:.0f}% of σ_ρ's and {100 * alpha['big10_share']:.0f}% of "
        "σ_α's.",
        "- P3 slopes (ln samples on ln area; 0 = the same for every component, 1 = "
        "proportional to area): "
        + ", ".join(
            f"{route} {sampler} {slope_text(n['p3'])}"
            for (route, sampler), n in numbers.items()
            if sampler in SAMPLERS
        )
        + ".",
    ]
    body = "\n".join(
        [
            "## Sampling experiment of the paper (Sec. 5.5)",
            "",
            "Generated by `python benches/paper_experiment.py"
            f"{' ' + ' '.join(sys.argv[1:]) if sys.argv[1:] else ''}` through the Python API "
            "(the same run as `cargo run --release -p loops-core --example paper_experiment`); "
            "do not edit by hand.",
            "",
            *machine_facts(("numpy",)),
            f"- Urban drive: {len(traj):,} poses, γ = {GAMMA_M:g} m: {pairs_upper:,} pairs "
            f"i < j in S_γ, {len(area)} loop components ({int(nontrivial.sum())} non-trivial), "
            f"found in {loops_s:.2f} s. Detections: {len(detections):,} "
            f"({100 * DETECTION_RATE:g}% of the pairs, drawn in {draw_s:.3f} s, seed {seed}); "
            f"ε = {EPSILON_S:g} s: {len(clusters)} clusters in {cluster_s:.3f} s. Budget "
            f"{budget:,} samples per sampler, seed {seed}.",
            "- Columns. P1: components covered (all / non-trivial / the smaller half of the "
            "non-trivial ones by area); the area of the largest non-trivial component without a "
            f"sample. P2: samples with another sample of their component within {EPSILON_S:g} s "
            "in the (t, t′) plane; median distance to the nearest such sample (all / non-trivial "
            "components). P3: least-squares slope of ln samples on ln area across the covered "
            "components. *trivial*: share of the samples in the trivial component (simple loops, "
            f"t′ near t). *big10*: share of the non-trivial samples in the {LARGEST} largest "
            "non-trivial components. *mean distance*: of the sampled pairs in non-trivial "
            "components, metres. *time*: the sampler alone (not the distances or the quality).",
            "- Routes: *detections* samples the ε-clusters of the detections (the paper's "
            "setting; a component no detection reaches cannot be covered); *exact components* "
            "samples S_γ's components directly; *non-trivial components* does the same without "
            "the trivial component (`skip_trivial=True`: no simple loops, the whole budget on "
            "revisits); *baseline* runs the candidate rule of a deployed system with a radius of "
            "γ and thins it to the budget.",
            "",
            *lines,
            "",
            "Reading:",
            "",
            *reading,
        ]
    )
    print(body)
    if not args.no_write:
        # Before the other marker sections (the ε-clustering comparison comes after it).
        write_section(args.output, SECTION, body, first=True)
        print(f"wrote the section <!-- {SECTION} --> of {args.output}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
