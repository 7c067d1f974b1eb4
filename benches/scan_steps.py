"""How many distances a row scan needs to decide every column of S_γ, by three rules, on the
positions of a drive (BENCHMARKS.md, "What fewer steps could give at most").

A measured column j decides the columns within |δ_j − γ| of path of it, on both sides (the
triangle inequality through the path): inside S_γ when δ_j ≤ γ, outside otherwise. Each rule
decides the columns of a stretch from its first, one measurement at a time:

- *forward* (the engine's): measure the first undecided column, move past its bound;
- *oracle*: knowing every δ, measure, of the columns whose bound reaches back to the first
  undecided one, the one whose bound reaches furthest (a bound no real scan knows in advance);
- *probe*: from the slope of the last two distances along the path, measure ahead where the
  bound would reach back if the slope held (a fraction ``--reach`` of that distance), and fall
  back to the first undecided column when it does not.

The stretches stand in for the hierarchy's candidates: the columns within γ + ``--pad`` of the
row's pose, cut where that fails. Rows: every ``--every``-th. The positions are what
``engine_rounds`` writes with ``POINTS_OUT`` (little-endian f64, x y z a pose)::

    POINTS_OUT=/tmp/drive.bin cargo run --release -p loops-core --example engine_rounds -- drive:2.1
    python benches/scan_steps.py /tmp/drive.bin
"""

from __future__ import annotations

import argparse

import numpy as np


def bound_end(ss, inside, reach, p):
    """The first column past the bound of a measurement at column p."""
    if inside[p]:
        return int(np.searchsorted(ss, ss[p] + reach[p], side="right"))
    return max(p + 1, int(np.searchsorted(ss, ss[p] + reach[p], side="left")))


def forward(ss, inside, reach, a, b):
    j, count = a, 0
    while j < b:
        count += 1
        j = bound_end(ss, inside, reach, j)
    return count


def oracle(ss, inside, reach, a, b):
    j, count = a, 0
    ends, starts = ss[a:b] + reach[a:b], ss[a:b] - reach[a:b]
    while j < b:
        count += 1
        rest = slice(j - a, b - a)
        covering = (starts[rest] <= ss[j]) & (inside[a:b][rest] == inside[j])
        end = ends[rest][covering].max()
        side = "right" if inside[j] else "left"
        j = max(j + 1, int(np.searchsorted(ss, end, side=side)))
    return count


def probe(ss, d, gamma, inside, reach, a, b, fraction):
    j, count, measured = a, 0, []
    while j < b:
        if len(measured) >= 2 and ss[measured[-1]] > ss[measured[-2]]:
            q1, q2 = measured[-2], measured[-1]
            slope = np.clip((d[q2] - d[q1]) / (ss[q2] - ss[q1]), -0.99, 0.99)
            at_j = d[q2] + slope * (ss[j] - ss[q2])
            if at_j <= gamma:
                ahead = fraction * (gamma - at_j) / (1 + slope)
            else:
                ahead = fraction * (at_j - gamma) / (1 - slope)
            p = int(np.searchsorted(ss, ss[j] + ahead, side="left"))
            if j + 1 < p < b:
                count += 1
                measured.append(p)
                measured.sort()
                if ss[p] - reach[p] <= ss[j]:
                    j = bound_end(ss, inside, reach, p)
                    continue
        count += 1
        measured.append(j)
        measured.sort()
        j = bound_end(ss, inside, reach, j)
    return count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("positions", help="little-endian f64, x y z a pose")
    parser.add_argument("--gamma", type=float, default=40.0)
    parser.add_argument("--pad", type=float, default=20.0, help="metres beyond γ a stretch reaches")
    parser.add_argument("--every", type=int, default=50, help="scan every this many rows")
    parser.add_argument("--reach", type=float, default=0.6, help="the probe rule's fraction")
    args = parser.parse_args()
    x = np.fromfile(args.positions, dtype="<f8").reshape(-1, 3)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))])
    totals = {"runs": 0, "forward": 0, "oracle": 0, "probe": 0}
    for i in range(0, len(x), args.every):
        d = np.linalg.norm(x[i:] - x[i], axis=1)
        ss, inside = s[i:], d <= args.gamma
        reach = np.abs(d - args.gamma)
        entries = np.count_nonzero(np.diff(inside.astype(np.int8)) == 1)
        totals["runs"] += int(entries) + int(inside[0])
        near = np.diff(np.concatenate([[0], (d <= args.gamma + args.pad).astype(np.int8), [0]]))
        edges = np.flatnonzero(near)
        for a, b in zip(edges[::2], edges[1::2], strict=True):
            totals["forward"] += forward(ss, inside, reach, a, b)
            totals["oracle"] += oracle(ss, inside, reach, a, b)
            totals["probe"] += probe(ss, d, args.gamma, inside, reach, a, b, args.reach)
    runs = totals["runs"]
    print(f"{len(x)} poses, every {args.every}th row: {runs} runs")
    for rule in ("forward", "oracle", "probe"):
        print(f"{rule}: {totals[rule] / runs:.2f} distances a run")


if __name__ == "__main__":
    main()
