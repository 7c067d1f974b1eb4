"""The documentation site (``docs/``, ``mkdocs.yml``) and the README, checked as a reader meets
them:

- the site builds with MkDocs in strict mode (every warning an error: broken links and anchors,
  pages left out of the navigation, API names that do not resolve);
- every code example runs: on each page (and the README), in document order in a folder of its
  own, each ``python`` block is executed and each ``console`` block's ``$ ...`` commands are run,
  printing every line shown under them (``...`` stands for any text). Examples on the public data
  sets run in a folder that holds them and skip, saying so, when ``../shared/data`` is absent. A
  block preceded by ``<!-- docs-test: skip (reason) -->`` is not run; the reason is required;
- every internal link and image of the built HTML resolves, anchors included;
- headless Chromium renders the home page, a tutorial and the API reference (screenshots kept as
  test artifacts, not blank, their headings present), follows the navigation and finds a known
  term with the site's search, served over http from 127.0.0.1;
- every public Python name and every command and option of the command line appears in the
  generated reference.

Needs the ``docs`` extra (MkDocs Material, mkdocstrings) and Chromium (Debian's ``chromium``);
each part skips with a message where they are missing.
"""

from __future__ import annotations

import contextlib
import functools
import html
import http.server
import importlib
import json
import os
import pkgutil
import re
import shutil
import subprocess
import sys
import threading
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote, urlparse

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: The public data sets beside the checkout (``LOOPS_DOCS_DATA`` names another folder, e.g. a
#: missing one to see the examples on data skip).
DATA = Path(os.environ.get("LOOPS_DOCS_DATA", ROOT.parent / "shared" / "data"))
ARTIFACTS = Path(os.environ.get("LOOPS_TEST_ARTIFACTS", ROOT / "target" / "test-artifacts"))
SKIP = re.compile(r"<!--\s*docs-test:\s*skip\s*\((.+?)\)\s*-->")
FENCE = re.compile(r"^```(\S*)")
#: The console scripts the examples call, run with this interpreter's package.
SCRIPTS = {
    "loops": "inexact_loops._cli",
    "loops-eval": "inexact_loops.evaluate",
    "loops-dask": "inexact_loops.dask",
}


# --- The examples -------------------------------------------------------------------------


@dataclass
class Block:
    """A fenced code block of a page: its language, text, first line and skip reason."""

    language: str
    code: str
    line: int
    skip: str | None = None
    commands: list[tuple[str, list[str]]] = field(default_factory=list)


def pages() -> list[Path]:
    return [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]


def blocks(path: Path) -> list[Block]:
    """The fenced blocks of ``path``, with each console block's commands and shown lines."""
    found: list[Block] = []
    lines = path.read_text().splitlines()
    index = 0
    while index < len(lines):
        opened = FENCE.match(lines[index])
        if not opened:
            index += 1
            continue
        previous = next((line for line in reversed(lines[:index]) if line.strip()), "")
        marker = SKIP.search(previous)
        start = index
        index += 1
        body = []
        while index < len(lines) and not lines[index].startswith("```"):
            body.append(lines[index])
            index += 1
        index += 1
        block = Block(opened.group(1), "\n".join(body) + "\n", start + 1)
        block.skip = marker.group(1) if marker else None
        if block.language == "console":
            for line in body:
                if line.startswith("$ "):
                    block.commands.append((line[2:], []))
                elif block.commands:
                    block.commands[-1][1].append(line)
        found.append(block)
    return found


def shown_in(shown: str, printed: list[str]) -> bool:
    """Whether a shown line is among the printed ones; ``...`` in it stands for any text."""
    if shown.strip() == "...":
        return True
    pattern = re.compile(".*".join(re.escape(part) for part in shown.split("...")) + "$")
    return any(pattern.match(line) for line in printed)


def data_entries() -> list[str]:
    return sorted(entry.name for entry in DATA.iterdir()) if DATA.is_dir() else []


DATA_FOLDERS = (
    "kitti_odometry",
    "kitti_loop_gt",
    "tuc",
    "tum_rgbd",
    "mulran_kaist",
    "pose_graphs",
    "euroc",
    "urbannav_hk",
)


def needs_data(block: Block) -> list[str]:
    """The data folders a block names (``kitti_odometry/...``)."""
    names = {*DATA_FOLDERS, *data_entries()}
    return sorted(n for n in names if re.search(rf"(?<![\w/.-]){n}/", block.code))


@pytest.fixture(scope="module")
def scripts(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of ``loops``, ``loops-eval`` and ``loops-dask`` that run this interpreter's
    package, as the wheel's console scripts do."""
    folder = tmp_path_factory.mktemp("bin")
    for name, module in SCRIPTS.items():
        script = folder / name
        script.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m {module} "$@"\n')
        script.chmod(0o755)
    return folder


def readme_inputs(folder: Path, scripts: Path) -> None:
    """The README's "your own file" and "your bag": a synthetic drive as MCAP, and the same
    poses as a rosbag2 bag (nav_msgs/Odometry on /odom, sqlite3 storage)."""
    loops = [str(scripts / "loops")]
    subprocess.run(
        [*loops, "synth", "my_drive.mcap", "--duration-s", "900"],
        cwd=folder,
        check=True,
        capture_output=True,
    )
    rosbag2 = pytest.importorskip("rosbags.rosbag2", reason="rosbags writes the README's bag")
    typesys = pytest.importorskip("rosbags.typesys")
    store = typesys.get_typestore(typesys.Stores.ROS2_HUMBLE)
    types = store.types
    import inexact_loops as il

    drive = il.urban_drive(duration_s=300.0, seed=2)
    with rosbag2.Writer(folder / "my_bag", version=8) as writer:
        topic = writer.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=store)
        for t, (x, y, z) in zip(drive.timestamps, drive.positions, strict=True):
            ns = int(round(t * 1e9)) + 10**9
            stamp = types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
            header = types["std_msgs/msg/Header"](stamp=stamp, frame_id="odom")
            point = types["geometry_msgs/msg/Point"](x=x, y=y, z=z)
            quaternion = types["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
            pose = types["geometry_msgs/msg/Pose"](position=point, orientation=quaternion)
            covariance = np.zeros(36)
            message = types["nav_msgs/msg/Odometry"](
                header=header,
                child_frame_id="base_link",
                pose=types["geometry_msgs/msg/PoseWithCovariance"](
                    pose=pose, covariance=covariance
                ),
                twist=types["geometry_msgs/msg/TwistWithCovariance"](
                    twist=types["geometry_msgs/msg/Twist"](
                        linear=types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                        angular=types["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                    ),
                    covariance=covariance,
                ),
            )
            writer.write(topic, ns, store.serialize_cdr(message, "nav_msgs/msg/Odometry"))


def run_commands(block: Block, where: str, folder: Path, scripts: Path) -> list[str]:
    """Runs a console block's commands in ``folder``: what failed, or is not printed."""
    failures = []
    path = f"{scripts}{os.pathsep}{os.environ.get('PATH', '')}"
    env = {**os.environ, "PATH": path, "NO_COLOR": "1", "MPLBACKEND": "Agg"}
    for command, shown in block.commands:
        done = subprocess.run(
            ["sh", "-c", command], cwd=folder, env=env, capture_output=True, text=True, timeout=600
        )
        printed = (done.stdout + done.stderr).splitlines()
        if done.returncode != 0:
            failures.append(f"{where}: `{command}` exited {done.returncode}:\n{done.stderr}")
            continue
        failures += [
            f"{where}: `{command}` does not print {line!r}; it printed:\n" + "\n".join(printed)
            for line in shown
            if not shown_in(line, printed)
        ]
    return failures


@pytest.mark.parametrize("page", pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_example_runs(page: Path, tmp_path: Path, scripts: Path, monkeypatch) -> None:
    """The page's python blocks run and its console blocks print what they show."""
    found = blocks(page)
    runnable = [b for b in found if b.skip is None and b.language in ("python", "console")]
    if not runnable:
        pytest.skip(f"{page.name} has no runnable example")
    # Without the public data sets, the blocks that read them are left out, saying so, and so
    # are the blocks after the first of them (they may use what it read or wrote).
    on_data = []
    if not DATA.is_dir():
        first = next((k for k, b in enumerate(runnable) if needs_data(b)), len(runnable))
        runnable, on_data = runnable[:first], runnable[first:]
    if on_data:
        lines = ", ".join(str(b.line) for b in on_data)
        message = f"{page.name}: the examples at lines {lines} need {DATA}, which is absent"
        if not runnable:
            pytest.skip(message)
        print(message)
    folder = tmp_path / "work"
    folder.mkdir()
    for entry in data_entries():
        (folder / entry).symlink_to(DATA / entry)
    if page.name == "README.md":
        readme_inputs(folder, scripts)
    monkeypatch.chdir(folder)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("PATH", f"{scripts}{os.pathsep}{os.environ.get('PATH', '')}")
    namespace: dict = {"__name__": "__docs__"}
    failures = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for block in runnable:
            where = f"{page.relative_to(ROOT)} line {block.line}"
            if block.language == "python":
                try:
                    exec(compile(block.code, where, "exec"), namespace)  # noqa: S102
                except Exception as error:  # noqa: BLE001 - every failure is reported
                    failures.append(f"{where}: {type(error).__name__}: {error}")
            else:
                failures += run_commands(block, where, folder, scripts)
    with contextlib.suppress(Exception):
        importlib.import_module("matplotlib.pyplot").close("all")
    assert not failures, "\n\n".join(failures)


def test_skipped_examples_say_why_and_no_command_hides_in_a_shell_block() -> None:
    """Every skip marker precedes a block and gives a reason; `loops` commands are shown as
    console blocks (which run), never in bash/sh blocks (which do not)."""
    problems = []
    for page in pages():
        text = page.read_text()
        markers = len(re.findall(r"docs-test", text))
        skipped = sum(block.skip is not None for block in blocks(page))
        if markers != skipped:
            problems.append(f"{page.name}: {markers} markers, {skipped} skipped blocks")
        for block in blocks(page):
            if block.language in ("bash", "sh", "shell"):
                problems += [
                    f"{page.name} line {block.line}: {line!r}"
                    for line in block.code.splitlines()
                    if re.match(r"\s*(\$ )?loops(-eval|-dask)? ", line)
                ]
    assert not problems, problems


def test_readme_links_name_files_of_the_repository() -> None:
    """The README is read on its own (on a forge, in a clone): its relative links name files of
    the checkout, not pages that exist only in the built site."""
    text = (ROOT / "README.md").read_text()
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)|<img src=\"([^\"]+)\"", text)
    targets = [a or b for a, b in links if not (a or b).startswith(("http:", "https:"))]
    assert len(targets) > 15, targets
    missing = [t for t in targets if not (ROOT / t).exists()]
    assert not missing, missing


def test_the_checker_fails_on_a_wrong_example(tmp_path: Path, scripts: Path) -> None:
    """The runner itself: a command that prints something else, or fails, is reported."""
    page = tmp_path / "page.md"
    page.write_text(
        "<!-- docs-test: skip (shown only) -->\n```console\n$ false\n```\n\n"
        "```console\n$ echo 'a b c'\na ... c\n$ echo x\ny\n$ false\n```\n"
    )
    found = blocks(page)
    assert [b.skip for b in found] == ["shown only", None]
    failures = run_commands(found[1], "page", tmp_path, scripts)
    assert len(failures) == 2 and "'y'" in failures[0] and "exited 1" in failures[1], failures


# --- The site -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The site, built with ``mkdocs build --strict`` into a temporary folder."""
    pytest.importorskip("mkdocs", reason="the docs extra (pip install '.[docs]') builds the site")
    pytest.importorskip("material", reason="the docs extra installs MkDocs Material")
    pytest.importorskip("mkdocstrings", reason="the docs extra installs mkdocstrings")
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-5000:]
    assert "WARNING" not in done.stderr, done.stderr
    return out


def html_pages(site: Path) -> list[Path]:
    return sorted(p for p in site.rglob("*.html") if "assets" not in p.parts)


def test_site_builds_strict_with_every_page(site: Path) -> None:
    built = {p.relative_to(site).as_posix() for p in html_pages(site)}
    for page in DOCS.rglob("*.md"):
        name = page.relative_to(DOCS).with_suffix("").as_posix()
        if name.endswith("index"):
            want = name[: -len("index")] + "index.html"
        else:
            want = f"{name}/index.html"
        assert want in built, f"{page} was not built ({want})"
    for generated in ("reference/cli/index.html", "benchmarks/index.html"):
        assert generated in built


def test_internal_links_resolve(site: Path) -> None:
    """Every relative href and src of every built page names a file of the site, and every
    fragment an element id of the page it points to."""
    ids: dict[Path, set[str]] = {}

    def ids_of(page: Path) -> set[str]:
        if page not in ids:
            text = page.read_text(errors="replace")
            ids[page] = {html.unescape(i) for i in re.findall(r'\bid="([^"]+)"', text)}
        return ids[page]

    broken = []
    checked = 0
    for page in html_pages(site):
        text = page.read_text(errors="replace")
        for link in re.findall(r'\b(?:href|src)="([^"]+)"', text):
            link = html.unescape(link)
            parsed = urlparse(link)
            if parsed.scheme or link.startswith(("//", "mailto:", "javascript:")):
                continue
            if not parsed.path:
                target = page
            elif parsed.path.startswith("/"):  # 404.html links from the site's root
                target = (site / unquote(parsed.path).lstrip("/")).resolve()
            else:
                target = (page.parent / unquote(parsed.path)).resolve()
            if target.is_dir():
                target = target / "index.html"
            checked += 1
            if site.resolve() not in target.resolve().parents and target != page:
                broken.append(f"{page.relative_to(site)}: {link} leaves the site")
            elif not target.exists():
                broken.append(f"{page.relative_to(site)}: {link} (no {target})")
            elif parsed.fragment and target.suffix == ".html":
                if unquote(parsed.fragment) not in ids_of(target):
                    broken.append(f"{page.relative_to(site)}: {link} (no #{parsed.fragment})")
    assert checked > 1000, checked
    assert not broken, "\n".join(broken[:50])


def test_every_public_python_name_is_in_the_reference(site: Path) -> None:
    import inexact_loops as il

    api = site / "reference" / "python"
    anchors = set()
    for page in api.rglob("index.html"):
        anchors |= set(re.findall(r'\bid="([^"]+)"', page.read_text()))
    missing = [
        f"inexact_loops.{name}"
        for name in il.__all__
        if f"inexact_loops.{name}" not in anchors and name != "metrics"
    ]
    # Every public submodule (found by pkgutil, whether a module or a package): each public
    # name in its own page's reference, or re-exported and in the package's.
    submodules = [m.name for m in pkgutil.iter_modules(il.__path__) if not m.name.startswith("_")]
    assert {"plot", "evaluate", "dask", "metrics", "viewers"} <= set(submodules), submodules
    for sub in submodules:
        module = importlib.import_module(f"inexact_loops.{sub}")
        names = getattr(module, "__all__", None) or [
            n
            for n, v in vars(module).items()
            if not n.startswith("_") and getattr(v, "__module__", None) == module.__name__
        ]
        missing += [
            f"inexact_loops.{sub}.{n}"
            for n in names
            if f"inexact_loops.{sub}.{n}" not in anchors and f"inexact_loops.{n}" not in anchors
        ]
    assert not missing, missing


def test_every_command_and_option_is_in_the_cli_reference(site: Path, scripts: Path) -> None:
    """The commands of `loops --help` and the options of each command's `--help`, parsed here
    independently of the page's generator, all appear on the generated page."""
    page = html.unescape((site / "reference" / "cli" / "index.html").read_text())

    def help_of(*args: str, script: str = "loops") -> str:
        done = subprocess.run(
            [str(scripts / script), *args, "--help"], capture_output=True, text=True, check=True
        )
        return done.stdout

    top = help_of()
    commands = re.findall(r"^  (\w+)  ", top.split("Commands:")[1].split("Options:")[0], re.M)
    commands = [c for c in commands if c != "help"]
    assert len(commands) >= 8, commands
    missing = []
    for command in commands:
        section = page.split(f'id="loops-{command}"', 1)
        if len(section) != 2:
            missing.append(f"loops {command}")
            continue
        text = section[1].split('<h2 id="', 1)[0]
        options = set(re.findall(r"(?<![\w-])(--[a-z][\w-]*)", help_of(command)))
        missing += [f"loops {command} {o}" for o in sorted(options) if o not in text]
    for script in ("loops-eval", "loops-dask"):
        options = set(re.findall(r"(?<![\w-])(--[a-z][\w-]*)", help_of(script=script)))
        text = page.split(f'id="{script}"', 1)[-1]
        missing += [f"{script} {o}" for o in sorted(options) if o not in text]
    assert not missing, missing


# --- In a browser ---------------------------------------------------------------------------


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path:
            return path
    pytest.skip("headless Chromium is not installed (Debian: apt-get install chromium)")


def browse(*args: str) -> str:
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--mute-audio"]
    # --timeout: a safety net under virtual time (a page still busy then is dumped as it is).
    flags += ["--no-first-run", "--disable-extensions", "--timeout=90000"]
    done = subprocess.run(
        [chromium(), *flags, *args], capture_output=True, text=True, timeout=180, check=True
    )
    return done.stdout


@pytest.fixture(scope="module")
def served(site: Path):
    """The built site on http://127.0.0.1:<port>/ (search needs it served, not a file)."""
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(site))
    handler.log_message = lambda *args: None  # type: ignore[method-assign]
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()


def check(site: Path, served: str, name: str, body: str, result: str, budget: int) -> dict:
    """Writes a page into the site that runs ``body`` (JavaScript, with ``frame`` an iframe and
    ``done(value)`` to report) and returns the JSON it reports once Chromium has run it."""
    page = f"""<!DOCTYPE html><html><body>
<iframe id="frame" style="width:1280px;height:1000px"></iframe>
<script>
const frame = document.getElementById("frame");
function done(value) {{
  const out = document.createElement("pre");
  out.id = "result";
  out.textContent = JSON.stringify(value);
  document.body.appendChild(out);
}}
{body}
</script></body></html>"""
    (site / f"_check_{name}.html").write_text(page)
    dumped = browse(f"--virtual-time-budget={budget}", "--dump-dom", f"{served}_check_{name}.html")
    found = re.search(r'<pre id="result">(.*?)</pre>', dumped, re.S)
    assert found, f"the check page did not report ({result}): {dumped[:2000]}"
    return json.loads(html.unescape(found.group(1)))


@pytest.mark.parametrize(
    ("path", "heading", "name"),
    [
        ("", "inexact-loops", "home"),
        ("tutorials/kitti/", "KITTI 00 and its loop labels", "tutorial"),
        ("reference/python/", "inexact_loops", "api"),
    ],
)
def test_pages_render_in_chromium(site: Path, served: str, path: str, heading: str, name: str):
    """A screenshot of the page (kept in the test artifacts) that is not blank, and its DOM,
    as laid out, with the expected heading and the navigation."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTIFACTS / f"docs-{name}.png"
    shot.unlink(missing_ok=True)
    url = served + path
    browse("--virtual-time-budget=10000", "--window-size=1280,1400", f"--screenshot={shot}", url)
    assert shot.exists(), "Chromium wrote no screenshot"
    pixels = np.asarray(pytest.importorskip("matplotlib.image").imread(shot))[..., :3]
    ink = (pixels.max(axis=2) - pixels.min(axis=2) > 0.1) | (pixels.mean(axis=2) < 0.6)
    assert ink.mean() > 0.03, f"the rendered page is nearly blank ({ink.mean():.3f})"
    # The header bar is drawn in the theme's colour, the body mostly white.
    assert pixels[:40].mean() < 0.6 < pixels[200:].mean()
    dom = browse("--virtual-time-budget=10000", "--dump-dom", url)
    h1 = re.search(r"<h1[^>]*>(.*?)</h1>", dom, re.S)
    assert h1 and heading in re.sub(r"<[^>]+>", "", html.unescape(h1.group(1))), h1
    for section in ("Getting started", "Tutorials", "How-to guides", "Concepts", "Reference"):
        assert section in dom, section


def test_navigation_leads_to_every_page(site: Path, served: str) -> None:
    """The home page as Chromium lays it out: every entry of its navigation leads (fetched from
    the server, as a click would) to a page whose heading or title names the entry, and the
    sections a reader looks for are there."""
    report = check(
        site,
        served,
        "nav",
        """
frame.addEventListener("load", async () => {
  const doc = frame.contentDocument;
  const links = [...doc.querySelectorAll("nav.md-nav--primary a.md-nav__link[href]")]
    .filter((a) => !a.getAttribute("href").startsWith("#"));
  const pages = [];
  for (const a of links) {
    const response = await fetch(a.href);
    const page = new DOMParser().parseFromString(await response.text(), "text/html");
    const h1 = page.querySelector("h1");
    pages.push({ text: a.textContent.trim(), path: new URL(a.href).pathname,
                 status: response.status, h1: h1 ? h1.textContent : null,
                 title: page.title });
  }
  done(pages);
});
frame.src = "index.html";
""",
        "the pages the navigation leads to",
        30000,
    )
    by_text = {page["text"]: page for page in report}
    assert len(by_text) >= 25, report
    for page in report:
        assert page["status"] == 200, page
        assert page["h1"], page
    assert by_text["KITTI and its loop labels"]["path"] == "/tutorials/kitti/"
    assert "KITTI 00" in by_text["KITTI and its loop labels"]["h1"]
    assert "Command line" in by_text["Command line"]["h1"]
    assert "inexact_loops" in by_text["inexact_loops.plot"]["h1"]
    assert set(by_text) >= {"A ROS bag (SLAM engineer)", "Run on a cluster", "Benchmarks"}


def test_search_finds_a_known_term(site: Path, served: str) -> None:
    """The site's search (a web worker over the built index) finds the sublevel set on the
    concepts page and a CLI option in the reference."""
    for term, page in (("sublevel", "/concepts/"), ("quaternion-tolerance", "/reference/cli/")):
        report = check(
            site,
            served,
            "search",
            f"""
let tries = 0;
frame.src = "index.html?q={term}";
const poll = setInterval(() => {{
  const doc = frame.contentDocument;
  const items = doc ? [...doc.querySelectorAll(".md-search-result__item a")] : [];
  tries += 1;
  if (items.length || tries > 300000) {{
    clearInterval(poll);
    done({{ tries, links: items.map((a) => new URL(a.href).pathname) }});
  }}
}}, 100);
""",
            "the search results",
            60000000,
        )
        assert report["links"], f"no search result for {term!r}: {report}"
        assert any(link.startswith(page) for link in report["links"]), (term, report)
