"""The queries of a fleet store against brute force over the stored sessions.

:meth:`FleetStore.near` against numpy distances to a point and, for polygons, against
matplotlib's point-in-polygon test plus numpy distances to the edges; :meth:`FleetStore.revisits`
against the store's components table read by DuckDB; :attr:`FleetStore.added` against the
components of the added sessions by name (pandas). ``loops store near|revisits|added`` on the
command line print and write (CSV) what Python answers.
"""

from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import inexact_loops as il

duckdb = pytest.importorskip("duckdb")
pd = pytest.importorskip("pandas")
mpath = pytest.importorskip("matplotlib.path")

quiet = pytest.mark.filterwarnings("ignore::inexact_loops.errors.LoopsWarning")

GAMMA = 40.0
BLOCK = 700


@pytest.fixture(scope="module")
def fleet(
    tmp_path_factory: pytest.TempPathFactory,
) -> tuple[il.FleetStore, dict[str, il.Trajectory]]:
    """Three cars on two days, stored day by day (the last update adds the second day)."""
    urban = il.urban_fleet(vehicles=3, days=2, duration_s=300.0, seed=5)
    sessions = {name: urban.session(name) for name in urban.names}
    names = sorted(sessions)
    first, second = names[::2], names[1::2]
    store = il.FleetStore.open(tmp_path_factory.mktemp("queries") / "city")
    store.update(add={n: sessions[n] for n in first}, gamma=GAMMA, block=BLOCK)
    store.update(add={n: sessions[n] for n in second})
    return store, sessions


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Maximal runs of True in `mask`, as inclusive (first, last) indices."""
    padded = np.r_[False, mask, False].astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def brute_passes(
    store: il.FleetStore, sessions: dict[str, il.Trajectory], near: callable
) -> list[tuple]:
    """The passes as rows (session, name, i_start, i_end, t_start_s, t_end_s)."""
    rows = []
    for k, name in enumerate(store.names):
        traj = sessions[name]
        xy, t = traj.positions[:, :2], traj.timestamps
        for a, b in runs(near(xy)):
            rows.append((k, name, a, b, float(t[a]), float(t[b])))
    return rows


def rows_of(table: il.Table) -> list[tuple]:
    columns = ("session", "name", "i_start", "i_end", "t_start_s", "t_end_s")
    return [
        (int(s), str(n), int(a), int(b), float(ta), float(tb))
        for s, n, a, b, ta, tb in zip(*(table[c] for c in columns), strict=True)
    ]


def segment_distances(xy: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Distance from each point of `xy` to the closed polyline of `vertices`."""
    a, b = vertices, np.roll(vertices, -1, axis=0)
    d = b - a
    rel = xy[:, None, :] - a[None, :, :]
    u = np.clip((rel * d).sum(-1) / (d * d).sum(-1), 0.0, 1.0)
    return np.linalg.norm(rel - u[..., None] * d, axis=-1).min(axis=1)


@quiet
def test_near_a_point_matches_numpy_distances(fleet) -> None:
    store, sessions = fleet
    rng = np.random.default_rng(11)
    everywhere = np.concatenate([sessions[n].positions[:, :2] for n in store.names])
    total = 0
    for _ in range(25):
        centre = everywhere[rng.integers(len(everywhere))] + rng.normal(0, 30, 2)
        radius = float(rng.uniform(5, 80))
        got = rows_of(store.near(tuple(centre), radius=radius))
        want = brute_passes(
            store, sessions, lambda xy, c=centre, r=radius: np.hypot(*(xy - c).T) <= r
        )
        assert got == want
        total += len(got)
    assert total > 25  # the places are visited, some more than once


@quiet
def test_near_a_polygon_matches_matplotlib_and_edge_distances(fleet) -> None:
    store, sessions = fleet
    rng = np.random.default_rng(12)
    everywhere = np.concatenate([sessions[n].positions[:, :2] for n in store.names])
    total = 0
    for _ in range(20):
        centre = everywhere[rng.integers(len(everywhere))]
        n = int(rng.integers(3, 9))
        angles = np.sort(rng.uniform(0, 2 * np.pi, n))
        vertices = centre + rng.uniform(10, 120, n)[:, None] * np.c_[np.cos(angles), np.sin(angles)]
        radius = float(rng.uniform(1, 40))
        polygon = mpath.Path(vertices)

        def near(xy: np.ndarray, vertices=vertices, polygon=polygon, radius=radius) -> np.ndarray:
            return polygon.contains_points(xy) | (segment_distances(xy, vertices) <= radius)

        got = rows_of(store.near(vertices, radius=radius))
        assert got == brute_passes(store, sessions, near)
        total += len(got)
    assert total > 20


@quiet
def test_near_defaults_to_gamma(fleet) -> None:
    store, sessions = fleet
    centre = sessions[store.names[0]].positions[50, :2]
    assert rows_of(store.near(centre)) == rows_of(store.near(centre, radius=GAMMA))


def components_table(store: il.FleetStore):
    state = json.loads((Path(store.path) / "store.json").read_text())["state"]
    return str(Path(store.path) / state / "components.parquet")


@quiet
def test_revisits_match_the_components_table(fleet) -> None:
    store, _ = fleet
    table = components_table(store)
    seen = 0
    for k, name in enumerate(store.names):
        want = duckdb.sql(
            f"""
            SELECT CASE WHEN a = {k} THEN b ELSE a END AS other,
                   count(*) AS components, sum(pair_count) AS pairs
            FROM '{table}'
            WHERE a <> b AND (a = {k} OR b = {k})
            GROUP BY other ORDER BY other
            """
        ).fetchall()
        got = store.revisits(name)
        assert list(
            zip(
                got["session"].tolist(),
                got["components"].tolist(),
                got["pair_count"].tolist(),
                strict=True,
            )
        ) == [(int(o), int(c), int(p)) for o, c, p in want]
        assert got["name"].tolist() == [store.names[int(o)] for o, _, _ in want]
        assert store.revisits(k)["session"].tolist() == got["session"].tolist()
        seen += len(want)
    assert seen > 0  # some sessions revisit others


@quiet
def test_added_are_the_components_of_the_added_sessions(fleet) -> None:
    store, _ = fleet
    added = set(store.last_update["added"])
    assert added
    frame = pd.read_parquet(components_table(store))
    want = frame[frame["session_a"].isin(added) | frame["session_b"].isin(added)]["id"]
    np.testing.assert_array_equal(store.added, np.sort(want.to_numpy()))
    assert 0 < len(store.added) < len(frame)


@pytest.mark.parametrize(
    ("place", "radius", "message"),
    [
        ([(0.0, 0.0), (1.0, 0.0)], None, "at least 3 vertices, got 2"),
        ([(0.0, 0.0), (1.0, np.nan), (0.0, 1.0)], None, "vertex 1 has y = NaN"),
        ((np.inf, 0.0), None, "point has x = inf"),
        ((0.0, 0.0), -1.0, "radius = -1"),
        ((0.0, 0.0, 0.0), None, "shape [3]"),
    ],
)
def test_bad_places_are_named(fleet, place, radius, message) -> None:
    store, _ = fleet
    with pytest.raises(il.errors.InvalidParameterError) as error:
        store.near(place, radius=radius)
    assert message in str(error.value)
    assert "\n" not in str(error.value)


def test_an_unknown_session_is_named(fleet) -> None:
    store, _ = fleet
    with pytest.raises(KeyError, match="no-such-car"):
        store.revisits("no-such-car")
    with pytest.raises(IndexError, match="99"):
        store.revisits(99)


def cli(*args) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "inexact_loops._cli", *map(str, args)],
        capture_output=True,
        text=True,
        check=False,
    )


def cli_csv(*args):
    """The CSV that ``loops store ... --csv -`` prints, as a DataFrame."""
    done = cli("store", *args, "--csv", "-")
    assert done.returncode == 0, done.stderr
    return pd.read_csv(io.StringIO(done.stdout), keep_default_na=False)


def same_columns(frame, table) -> None:
    """The CSV's columns are the table's, with its values (floats to the bit)."""
    assert list(frame.columns) == list(table.keys())
    for column in frame.columns:
        assert frame[column].tolist() == np.asarray(table[column]).tolist(), column


@quiet
def test_the_command_line_queries_answer_as_python(fleet, tmp_path) -> None:
    store, sessions = fleet
    centre = sessions[store.names[1]].positions[40, :2]
    x, y = (float(v) for v in centre)
    same_columns(
        cli_csv("near", store.path, "--point", f"{x!r},{y!r}", "--radius", 25),
        store.near(centre, radius=25.0),
    )
    vertices = centre + np.array([[-60.0, -40.0], [70.0, -30.0], [10.0, 80.0]])
    polygon = " ".join(f"{float(a)!r},{float(b)!r}" for a, b in vertices)
    same_columns(cli_csv("near", store.path, "--polygon", polygon), store.near(vertices))
    for name in store.names:
        same_columns(cli_csv("revisits", store.path, name), store.revisits(name))
    added = cli_csv("added", store.path)
    np.testing.assert_array_equal(added["id"].to_numpy(), store.added)
    assert set(added["session_a"]) | set(added["session_b"]) >= set(store.last_update["added"])

    # The table on stdout, the CSV to a file: never over one without --force, never in the store.
    target = tmp_path / "passes.csv"
    args = ("store", "near", store.path, "--point", f"{x},{y}", "--csv", target)
    done = cli(*args)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0].split() == list(store.near(centre).keys())
    written = target.read_bytes()
    assert len(pd.read_csv(target)) == len(store.near(centre)["session"]) > 0
    again = cli(*args)
    assert again.returncode == 2 and len(again.stderr.strip().splitlines()) == 1, again.stderr
    assert target.read_bytes() == written
    assert cli(*args, "--force").returncode == 0
    inside = cli("store", "added", store.path, "--csv", Path(store.path) / "added.csv")
    assert inside.returncode == 2 and "--csv" in inside.stderr, inside.stderr
    assert not (Path(store.path) / "added.csv").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("near", "--point", "1;2"), '--point "1;2": expected X,Y'),
        (("near", "--point", "nan,0"), "point has x = NaN"),
        (("near", "--polygon", "-1,0 1,0"), "at least 3 vertices, got 2"),
        (("near", "--point", "0,0", "--radius", "-1"), "radius = -1"),
        (("revisits", "no-such-car"), 'session "no-such-car" is not in the store'),
    ],
)
def test_the_command_line_names_bad_queries(fleet, args, message) -> None:
    store, _ = fleet
    query, *rest = args
    done = cli("store", query, store.path, *rest)
    assert done.returncode == 2
    assert message in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
