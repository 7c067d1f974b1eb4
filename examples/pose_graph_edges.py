#!/usr/bin/env python3
"""Where the loop closures of a pose graph fall against its exact loops.

    python examples/pose_graph_edges.py                          # INTEL, beside the checkout
    python examples/pose_graph_edges.py GRAPH.g2o [--gamma 3] [--no-separation] [--csv out.csv]
    python examples/pose_graph_edges.py EDGES.graph --chain-edges  # a file of edges alone

Reads a g2o or TORO pose graph (``il.read_pose_graph``), takes γ as the longest translation any
loop-closure edge measures (the scan matcher's reach, rounded up to 0.1) unless ``--gamma`` is
given, finds the loops of the vertices (``il.find_loops``) and prints how many loop-closure
edges fall in a loop component, in a trivial one, within γ but not separated, or outside S_γ
(``PoseGraph.edge_verdicts``: the verdicts of ``loops components GRAPH --edges``), with the
components that hold the most closures. ``--csv`` writes one row per closure (needs pandas).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import inexact_loops as il

DEFAULT = (
    Path(__file__).resolve().parents[2] / "shared" / "data" / "pose_graphs" / "input_INTEL_g2o.g2o"
)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "graph", nargs="?", type=Path, default=DEFAULT, help="a .g2o or .graph file"
    )
    parser.add_argument(
        "--gamma", type=float, help="metres (default: the closures' longest translation)"
    )
    parser.add_argument(
        "--no-separation",
        action="store_true",
        help="the paper's S_gamma, trivial components included",
    )
    parser.add_argument(
        "--chain-edges",
        action="store_true",
        help="chain the odometry edges of a file without vertices",
    )
    parser.add_argument("--csv", type=Path, help="write one row per loop-closure edge")
    args = parser.parse_args()

    graph = il.read_pose_graph(args.graph, chain_edges=args.chain_edges)
    edges = graph.edges
    closures = edges["loop_closure"]
    print(f"{args.graph.name}: {graph!r}")
    if not closures.any():
        print("no loop-closure edges (none joins vertices more than one id apart)")
        return
    if args.gamma is None:
        if graph.dim == 2:
            reach = np.hypot(edges["dx"], edges["dy"])[closures].max()
        else:
            reach = np.sqrt(edges["dx"] ** 2 + edges["dy"] ** 2 + edges["dz"] ** 2)[closures].max()
        gamma = math.ceil(reach * 10) / 10
        print(f"gamma {gamma} m: the longest loop-closure edge measures {reach:.2f} m")
    else:
        gamma = args.gamma
    separation = None if args.no_separation else "auto"
    loops = il.find_loops(graph.trajectory, gamma=gamma, separation=separation)
    print(f"{loops!r}")

    verdicts = graph.edge_verdicts(loops)
    names, counts = np.unique(verdicts["verdict"], return_counts=True)
    for name in ["component", "trivial", "not-separated", "outside"]:
        count = int(counts[names == name].sum())
        print(f"  {name:<14} {count:>5}  ({count / verdicts.num_rows:.0%})")
    held = verdicts["component"][verdicts["component"] >= 0]
    if held.size:
        ids, per = np.unique(held, return_counts=True)
        order = np.argsort(-per)[:5]
        area = loops.components["area_s2"]
        print("components holding the most closures:")
        for k in order:
            print(f"  component {ids[k]}: {per[k]} closures, {area[ids[k]]:.0f} s²")
    if args.csv is not None:
        verdicts.to_pandas().to_csv(args.csv, index=False)
        print(f"wrote {verdicts.num_rows} rows to {args.csv}")


if __name__ == "__main__":
    main()
