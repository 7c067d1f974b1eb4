"""The per-log report of `loops run`, rendered by headless Chromium: every figure is laid out
and drawn, the components table matches components.csv, and nothing is fetched from the network.
A screenshot of the rendered page is kept as a test artifact. KITTI 00 run with `--axes 0,2`
(from ../shared/data; skipped without it) draws its maps in x-z: the rendered tracks span both
axes, are labelled x and z, and every drawn vertex is a pose's (x, z). The fleet's report of
`loops fleet` renders too: both figures drawn, the components between sessions as in
components.csv, every session linking its own page.

Chromium is Debian's `chromium` package (`.ci/run` installs it); where it is missing the test
is skipped with a message saying so.
"""

from __future__ import annotations

import csv
import html
import json
import os
import re
import shutil
import subprocess
from pathlib import Path
from urllib.parse import unquote, urlparse

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
ARTIFACTS = Path(os.environ.get("LOOPS_TEST_ARTIFACTS", ROOT / "target" / "test-artifacts"))
FIGURES = {"loop-duration", "pairwise-distance", "sampled-pairs", "samples-per-component"}


def check_page(src: str, body: str, result: str) -> str:
    """A page that loads the page ``src`` in a same-folder iframe and, once it is loaded, runs
    the JavaScript ``body`` on it (``doc`` its document, ``size(e)`` an element's laid-out
    width and height) and writes the JSON of the expression ``result`` into a
    ``<pre id="result">``, for --dump-dom to print."""
    return f"""<!DOCTYPE html><html><body>
<iframe id="report" src="{src}" style="width:1400px;height:4000px"></iframe>
<script>
document.getElementById("report").addEventListener("load", () => {{
  const doc = document.getElementById("report").contentDocument;
  const size = (e) => {{ const r = e.getBoundingClientRect(); return [r.width, r.height]; }};
{body}
  const out = document.createElement("pre");
  out.id = "result";
  out.textContent = JSON.stringify({result});
  document.body.appendChild(out);
}});
</script></body></html>
"""


# What the browser laid out and decoded in the report: its figures and the components table.
CHECK_PAGE = check_page(
    "report.html",
    """  const figures = [...doc.querySelectorAll(".figure")].map((f) => ({
    name: f.dataset.figure,
    size: size(f),
    images: [...f.querySelectorAll("img")].map((i) => ({
      complete: i.complete, natural: [i.naturalWidth, i.naturalHeight], size: size(i) })),
    svgs: [...f.querySelectorAll("svg")].map((s) => ({
      size: size(s),
      marks: s.querySelectorAll("path, line, polyline, polygon, circle, rect").length })),
  }));
  const table = doc.getElementById("components");
  const text = (c) => c.textContent.trim();
  const header = table ? [...table.querySelectorAll("thead th")].map(text) : [];
  const rows = table ? [...table.querySelectorAll("tbody tr")].map(
    (r) => [...r.cells].map(text)) : [];""",
    "{ title: doc.title, figures, header, rows }",
)


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path:
            return path
    pytest.skip(
        "headless Chromium is not installed (Debian: apt-get install chromium; .ci/run does it): "
        "the rendered report is not checked"
    )


def browse(browser: str, *args: str) -> subprocess.CompletedProcess[str]:
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--mute-audio"]
    flags += ["--no-first-run", "--disable-extensions", "--allow-file-access-from-files"]
    return subprocess.run(
        [browser, *flags, *args], capture_output=True, text=True, timeout=180, check=True
    )


def rendered(check: Path, page: str):
    """Writes the check page ``page`` (:func:`check_page`) to ``check`` and returns the JSON it
    writes once headless Chromium has laid out the page it loads."""
    browser = chromium()
    check.write_text(page)
    dumped = browse(
        browser,
        "--virtual-time-budget=15000",
        "--window-size=1440,4200",
        "--dump-dom",
        check.as_uri(),
    ).stdout
    found = re.search(r'<pre id="result">(.*?)</pre>', dumped, re.S)
    assert found, f"the check script did not run: {dumped[:2000]}"
    return json.loads(html.unescape(found.group(1)))


def screenshot(page: Path, name: str, height: int) -> np.ndarray:
    """Headless Chromium's screenshot of ``page`` (1440 pixels wide, ``height`` high), kept as
    ``name`` in the test artifacts: its RGB pixels, which are not nearly blank."""
    browser = chromium()
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTIFACTS / name
    shot.unlink(missing_ok=True)
    browse(
        browser,
        "--virtual-time-budget=15000",
        f"--window-size=1440,{height}",
        f"--screenshot={shot}",
        page.as_uri(),
    )
    assert shot.exists(), "Chromium wrote no screenshot"
    image = pytest.importorskip("matplotlib.image").imread(shot)
    pixels = np.asarray(image)[..., :3]
    ink = (pixels.max(axis=2) - pixels.min(axis=2) > 0.1) | (pixels.mean(axis=2) < 0.6)
    assert ink.mean() > 0.02, "the rendered page is nearly blank"
    return pixels


def assert_self_contained(page: str) -> None:
    """A whole HTML document that loads nothing from the network and links no style sheet."""
    assert page.startswith("<!DOCTYPE html>") and page.rstrip().endswith("</html>")
    fetched = re.findall(r"""(?:src|href)\s*=\s*["']?\s*(?:https?:)?//""", page)
    assert not fetched, "the report must not load anything from the network"
    assert "@import" not in page and "<link" not in page


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory, loops_cli: Path) -> Path:
    """A 20 min drive through `loops run`: its output folder."""
    root = tmp_path_factory.mktemp("report")
    log = root / "drive <&> 20min.mcap"  # a name that needs escaping
    run = [loops_cli, "synth", log, "--duration-s", "1200", "--seed", "3"]
    subprocess.run(run, check=True, capture_output=True)
    out = root / "results"
    args = [loops_cli, "run", log, "--gamma", "40", "--budget", "400", "--out", out]
    subprocess.run(args, check=True, capture_output=True)
    return out / log.stem


def test_report_is_self_contained(report: Path) -> None:
    page = (report / "report.html").read_text()
    assert_self_contained(page)
    assert "drive &lt;&amp;&gt; 20min" in page and "drive <&> 20min" not in page


def test_report_renders_in_chromium(report: Path) -> None:
    page = rendered(report / "check.html", CHECK_PAGE)
    assert "drive <&> 20min" in page["title"]

    figures = {f["name"]: f for f in page["figures"]}
    assert set(figures) == FIGURES, figures.keys()
    for name, figure in figures.items():
        width, height = figure["size"]
        assert width > 200 and height > 150, (name, figure["size"])
        assert figure["svgs"] or figure["images"], f"{name} draws nothing"
        for image in figure["images"]:
            assert image["complete"] and min(image["natural"]) > 0, (name, image)
            assert min(image["size"]) > 50, (name, image)
        drawn = [min(svg["size"]) for svg in figure["svgs"]] + [
            min(i["size"]) for i in figure["images"]
        ]
        assert max(drawn) > 150, (name, figure)  # the plot itself (legend swatches are small)
        assert sum(svg["marks"] for svg in figure["svgs"]) + len(figure["images"]) > 5, name

    # The table: a row per component, the same numbers as components.csv.
    with (report / "components.csv").open(newline="") as f:
        expected = list(csv.DictReader(f))
    assert len(page["rows"]) == len(expected) > 1
    header = page["header"]
    column = {
        name: header.index(name) for name in ("id", "trivial", "area_s2", "pair_count", "holes")
    }
    t0 = json.loads((report / "summary.json").read_text())["t0_s"]
    for row, want in zip(page["rows"], expected, strict=True):
        assert int(row[column["id"]]) == int(want["id"])
        assert row[column["trivial"]] in ("yes", "no", "true", "false")
        assert (row[column["trivial"]] in ("yes", "true")) == (want["trivial"] == "true")
        assert int(row[column["pair_count"]].replace(",", "")) == int(want["pair_count"])
        assert int(row[column["holes"]]) == int(want["holes"])
        shown = float(row[column["area_s2"]].replace(",", ""))
        assert shown == pytest.approx(float(want["area_s2"]), rel=1e-3, abs=0.06)
        if "samples" in header:
            assert int(row[header.index("samples")]) == int(want["samples"])
        if "t_min_s" in header:
            start = float(row[header.index("t_min_s")])
            assert start == pytest.approx(float(want["t_min_s"]) - t0, abs=0.06)


def test_report_screenshot_is_kept_and_not_blank(report: Path) -> None:
    pixels = screenshot(report / "report.html", "report.png", 3600)
    # Colour in the figures (viridis-coloured path, distance image), not only black text.
    colourful = pixels.max(axis=2) - pixels.min(axis=2) > 0.25
    assert colourful.mean() > 0.005


# --------------------------------------------------------------------------------------------
# KITTI 00 with --axes 0,2: the maps draw the ground plane (x-z), not the first two columns.
# --------------------------------------------------------------------------------------------

KITTI00 = ROOT / ".." / "shared" / "data" / "kitti_odometry" / "00.txt"
MAPS = ("loop-duration", "sampled-pairs")

# What the browser laid out in the two maps: the axis labels (and whether they are drawn
# upright), the tick labels, the path data of the track and its rendered box, and the start and
# end markers.
MAPS_PAGE = check_page(
    "report.html",
    """  const maps = {};
  for (const name of MAPS) {
    const svg = doc.querySelector(`.figure[data-figure="${name}"] svg`);
    if (!svg) continue;
    const texts = [...svg.querySelectorAll("text")].map((t) => {
      const r = t.getBoundingClientRect();
      const attribute = (name) => t.getAttribute(name);
      return { text: t.textContent, cls: attribute("class"), anchor: attribute("text-anchor"),
               x: +attribute("x"), y: +attribute("y"), upright: r.height > r.width };
    });
    const tracks = [...svg.querySelectorAll("path.track, path.grey-track")];
    const boxes = tracks.map((p) => p.getBBox()).filter((b) => b.width + b.height > 0);
    const least = (f) => Math.min(...boxes.map(f));
    const most = (f) => Math.max(...boxes.map(f));
    const box = boxes.length ? {
      left: least((b) => b.x), right: most((b) => b.x + b.width),
      top: least((b) => b.y), bottom: most((b) => b.y + b.height),
    } : null;
    const start = svg.querySelector("circle.start");
    const end = svg.querySelector("rect.end");
    maps[name] = {
      texts, box, paths: tracks.map((p) => p.getAttribute("d")),
      start: start && [+start.getAttribute("cx"), +start.getAttribute("cy")],
      end: end && [+end.getAttribute("x") + 4, +end.getAttribute("y") + 4],
    };
  }""".replace("MAPS", json.dumps(list(MAPS))),
    "maps",
)


def _number(text: str) -> float:
    """A tick label as a number: Unicode minus and digit separators as the report prints them."""
    return float(text.replace("−", "-").replace(",", "").replace("\u2009", "").strip())


def _scale(ticks: list[tuple[float, float]]) -> tuple[float, float]:
    """Metres = a + b · pixel, fitted to (pixel, value) tick pairs."""
    assert len(ticks) >= 2, ticks
    pixels, values = np.array(ticks).T
    b, a = np.polyfit(pixels, values, 1)
    residual = np.abs(a + b * pixels - values).max()
    assert residual < 1e-3 * (values.max() - values.min()), ticks
    return a, b


def _vertices(d: str) -> np.ndarray:
    """The points of an `M x y L x y ...` path, pixels."""
    numbers = [float(v) for v in re.findall(r"-?\d+(?:\.\d+)?", d)]
    return np.array(numbers).reshape(-1, 2)


@pytest.fixture(scope="module")
def kitti00_report(tmp_path_factory: pytest.TempPathFactory, loops_cli: Path) -> Path:
    """`loops run` on KITTI 00 with --axes 0,2 (γ = 6 m): its log folder."""
    if not KITTI00.is_file():
        pytest.skip(f"KITTI odometry not found at {KITTI00.resolve()} (not in a user's clone)")
    out = tmp_path_factory.mktemp("kitti") / "results"
    args = [loops_cli, "run", KITTI00, "--axes", "0,2", "--gamma", "6", "--out", out, "--quiet"]
    subprocess.run(args, check=True, capture_output=True)
    return out / "00"


def test_kitti00_maps_draw_the_chosen_plane_in_chromium(kitti00_report: Path) -> None:
    """The KITTI 00 report with --axes 0,2 draws its loops: both maps, as Chromium lays them out,
    span both axes, are labelled x and z, and every drawn vertex, read back through the tick
    labels, is a pose's (x, z); start and end are the first and last poses."""
    maps = rendered(kitti00_report / "check-maps.html", MAPS_PAGE)
    assert set(maps) == set(MAPS), maps.keys()

    rows = np.loadtxt(KITTI00)  # t, then the row-major 3x4 [R|t] of the camera
    ground = rows[:, [4, 12]]  # x (right) and z (forward): the ground plane
    extent = np.ptp(ground, axis=0)
    tree = scipy_spatial().cKDTree(ground)
    for name, drawn in maps.items():
        labels = [t for t in drawn["texts"] if t["cls"] == "label" and t["text"].endswith("(m)")]
        across = [t["text"] for t in labels if not t["upright"]]
        up = [t["text"] for t in labels if t["upright"]]
        assert (across, up) == (["x (m)"], ["z (m)"]), (name, labels)

        # The rendered track spans both axes in the proportions of the x-z extents (a flat
        # streak, as the first two columns x-y give, would not).
        box = drawn["box"]
        width, height = box["right"] - box["left"], box["bottom"] - box["top"]
        assert min(width, height) > 200, (name, box)
        assert width / height == pytest.approx(extent[0] / extent[1], rel=0.03), (name, box)

        # Pixels back to metres through the tick labels; each vertex is a pose's (x, z).
        ticks = [t for t in drawn["texts"] if t["cls"] is None and t["text"].strip()]
        xs = _scale([(t["x"], _number(t["text"])) for t in ticks if t["anchor"] == "middle"])
        ys = _scale([(t["y"] - 4.0, _number(t["text"])) for t in ticks if t["anchor"] == "end"])
        points = np.vstack([_vertices(d) for d in drawn["paths"]])
        assert len(points) > 100, name
        metres = np.c_[xs[0] + xs[1] * points[:, 0], ys[0] + ys[1] * points[:, 1]]
        distance, _ = tree.query(metres)
        metres_per_pixel = abs(xs[1])
        assert distance.max() < 0.15 * metres_per_pixel + 0.05, (name, distance.max())
        drawn_extent = np.ptp(metres, axis=0)
        assert np.all(drawn_extent > 0.99 * extent), (name, drawn_extent, extent)
        for marker, pose in (("start", ground[0]), ("end", ground[-1])):
            at = np.array(drawn[marker])
            at = [xs[0] + xs[1] * at[0], ys[0] + ys[1] * at[1]]
            assert np.hypot(*(np.array(at) - pose)) < 0.15 * metres_per_pixel + 0.05, (
                name,
                marker,
                at,
                pose,
            )


def scipy_spatial():
    return pytest.importorskip("scipy.spatial")


# --------------------------------------------------------------------------------------------
# The fleet's report (index.html of `loops fleet`).
# --------------------------------------------------------------------------------------------

FLEET_FIGURES = {"overlap-matrix", "fleet-map"}

# What the browser laid out in the fleet's page: its figures, tables and links.
FLEET_CHECK_PAGE = check_page(
    "index.html",
    """  const figures = [...doc.querySelectorAll(".figure")].map((f) => ({
    name: f.dataset.figure,
    size: size(f),
    svgs: [...f.querySelectorAll("svg")].map((s) => ({
      size: size(s),
      marks: s.querySelectorAll("path, rect, circle").length,
      cells: s.querySelectorAll("rect.cell").length })),
  }));
  const text = (c) => c.textContent.trim();
  const table = (id) => {
    const t = doc.getElementById(id);
    if (!t) return null;
    const rows = [...t.querySelectorAll("tbody tr")].map((r) => [...r.cells].map(text));
    return { header: [...t.querySelectorAll("thead th")].map(text), rows };
  };
  const links = [...doc.querySelectorAll("#sessions a")].map((a) => [text(a), a.href]);""",
    """{
    title: doc.title, figures, between: table("between"), pairs: table("session-pairs"),
    sessions: table("sessions"), links }""",
)

ODD = "night <&> shift"  # a session name that needs escaping, in HTML and in a link


@pytest.fixture(scope="module")
def fleet_out(tmp_path_factory: pytest.TempPathFactory, loops_cli: Path) -> Path:
    """A synthetic fleet (3 vehicles, 2 days, 10 min each) through `loops fleet`: --out."""
    root = tmp_path_factory.mktemp("fleet")
    logs = root / "logs"
    synth = [loops_cli, "synth", logs, "--vehicles", "3", "--days", "2", "--duration-s", "600"]
    subprocess.run(synth, check=True, capture_output=True)
    files = sorted(logs.glob("*.mcap"))
    out = root / "results"
    args = [loops_cli, "fleet", *files[:-1], "--session", f"{ODD}={files[-1]}"]
    args += ["--gamma", "40", "--budget", "400", "--out", out, "--quiet"]
    subprocess.run(args, check=True, capture_output=True)
    return out


def test_fleet_report_is_self_contained(fleet_out: Path) -> None:
    page = (fleet_out / "index.html").read_text()
    assert_self_contained(page)
    assert "<script" not in page
    assert "night &lt;&amp;&gt; shift" in page and ODD not in page


def test_fleet_report_renders_in_chromium(fleet_out: Path) -> None:
    page = rendered(fleet_out / "check.html", FLEET_CHECK_PAGE)
    assert "Fleet of 6 sessions" in page["title"]
    summary = json.loads((fleet_out / "summary.json").read_text())

    figures = {f["name"]: f for f in page["figures"]}
    assert set(figures) == FLEET_FIGURES, figures.keys()
    for name, figure in figures.items():
        width, height = figure["size"]
        assert width > 200 and height > 150, (name, figure["size"])
        assert max(min(svg["size"]) for svg in figure["svgs"]) > 150, (name, figure)
        assert sum(svg["marks"] for svg in figure["svgs"]) > 10, name
    # The heat map: a cell per session pair that meets (both halves), one per session alone.
    matrix = figures["overlap-matrix"]["svgs"][0]
    with (fleet_out / "session_pairs.csv").open(newline="") as f:
        pairs = list(csv.DictReader(f))
    own = sum(p["session_a"] == p["session_b"] for p in pairs)
    assert matrix["cells"] == own + 2 * (len(pairs) - own)
    assert len(page["pairs"]["rows"]) == len(pairs)

    # The components between sessions: the rows of components.csv with a != b, same numbers.
    with (fleet_out / "components.csv").open(newline="") as f:
        between = {int(r["id"]): r for r in csv.DictReader(f) if r["session_a"] != r["session_b"]}
    table = page["between"]
    assert len(table["rows"]) == len(between) == summary["between_components"] > 0
    column = {name: table["header"].index(name) for name in table["header"]}
    for row in table["rows"]:
        want = between[int(row[column["id"]])]
        assert row[column["name_a"]] == want["name_a"]
        assert row[column["name_b"]] == want["name_b"]
        assert int(row[column["pair_count"]]) == int(want["pair_count"])
        assert int(row[column["samples"]]) == int(want["samples"])
        assert float(row[column["area_s2"]]) == pytest.approx(float(want["area_s2"]), abs=0.06)
        start = float(row[column["t_prime_min_s"]])
        assert start == pytest.approx(float(want["t_prime_min_s"]), abs=0.06)
    areas = [float(r[column["area_s2"]]) for r in table["rows"]]
    assert areas == sorted(areas, reverse=True), "largest first"

    # Every session is listed and links its own page, which is there.
    names = [s["name"] for s in summary["sessions"]]
    assert [r[0] for r in page["sessions"]["rows"]] == names
    assert ODD in names
    assert [name for name, _ in page["links"]] == names
    for name, href in page["links"]:
        target = Path(unquote(urlparse(href).path))
        assert target == fleet_out / name / "report.html", (name, href)
        assert 'data-figure="loop-duration"' in target.read_text()


def test_fleet_report_screenshot_is_kept_and_not_blank(fleet_out: Path) -> None:
    pixels = screenshot(fleet_out / "index.html", "fleet-report.png", 2400)
    colourful = pixels.max(axis=2) - pixels.min(axis=2) > 0.25
    assert colourful.mean() > 0.005, "the heat map and the sessions' colours"
