#!/usr/bin/env python3
"""Takes the screenshots of the viewers page (``docs/images/viewer_*.png``): the project's own
results, written by :func:`inexact_loops.viewers.to_rerun`, shown by Rerun's web viewer (the one
``rerun-sdk`` ships) in headless Chromium with software WebGL (SwiftShader). Nothing is drawn
by hand: what you see is what ``rerun results.rrd`` shows a user, in the layout below.

    python docs/scripts/screenshots.py            # every screenshot; existing files replaced
    python docs/scripts/screenshots.py --only fleet

Needs ``rerun-sdk`` (``pip install '.[rerun]'``), Pillow and Chromium (Debian:
``apt-get install chromium``). The data are the built-in synthetic drives, seeded; nothing is
read from outside the repository. Each capture is checked before it is kept: the colours of
the loop components it shows must be on screen (in the 3-D view and on the plane), or the
script fails, naming what is missing, and keeps nothing.
"""

from __future__ import annotations

import argparse
import io
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

import inexact_loops as il
from inexact_loops import viewers

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "images"
#: The browser window, in CSS pixels.
WINDOW = (1280, 720)
#: Virtual time Chromium gives the page to load the viewer and the recording (milliseconds).
BUDGET_MS = 90_000
#: A screenshot is kept under this many bytes (PNG, quantized if need be).
MAX_BYTES = 300_000
#: A component's colour counts as shown when this many pixels are within TOLERANCE of it.
MIN_PIXELS = 5
TOLERANCE = 12


def drive() -> tuple[object, object, object, str]:
    """One urban drive of 30 minutes, its loops (γ = 40 m) and 60 candidate pairs."""
    traj = il.urban_drive(duration_s=1800.0, seed=1)
    loops = il.find_loops(traj, gamma=40.0)
    samples = il.sample(loops, il.DEFAULT_SAMPLER, budget=60, seed=0, trajectory=traj)
    return loops, samples, traj, "urban-drive"


def fleet() -> tuple[object, object, None, str]:
    """Three synthetic sessions of the built-in fleet, their loops within and between them,
    and 80 candidate pairs over the fleet."""
    sessions = il.urban_fleet(vehicles=3, days=1, duration_s=900.0, seed=2)
    loops = il.find_fleet_loops(sessions, gamma=40.0)
    samples = il.sample_fleet(loops, il.DEFAULT_SAMPLER, budget=80, seed=0)
    return loops, samples, None, "fleet"


SHOTS = {"drive": drive, "fleet": fleet}


def blueprint(path: Path, positions: np.ndarray) -> None:
    """The layout of a shot, saved for the recording's application: the 3-D view (the path
    coloured by τ, the components and the candidates, seen from above the south edge of
    ``positions``) beside the (t, t′) plane, the side panels folded away."""
    import rerun.blueprint as rrb

    low, high = positions.min(axis=0), positions.max(axis=0)
    centre, extent = (low + high) / 2, float((high - low).max())
    eye = rrb.EyeControls3D(
        position=centre + [0.0, -0.6 * extent, 1.1 * extent],
        look_target=centre,
        eye_up=[0.0, 0.0, 1.0],
    )
    view = rrb.Spatial3DView(
        origin="/",
        contents=["+ /loops/tau/**", "+ /loops/components/**", "+ /loops/candidates"],
        name="path, τ, components, candidates",
        background=[20, 20, 24],
        line_grid=False,
        eye_controls=eye,
    )
    plane = rrb.Spatial2DView(origin="/loops/plane", name="(t, t′) plane", background=[20, 20, 24])
    layout = rrb.Blueprint(rrb.Horizontal(view, plane, column_shares=[3, 2]), collapse_panels=True)
    layout.save("inexact-loops", path)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        if path := shutil.which(name):
            return path
    sys.exit("screenshots.py: needs Chromium (Debian: apt-get install chromium)")


def rerun_binary() -> str:
    """The viewer binary that ``rerun-sdk`` ships (not a wrapper script that would outlive a
    stop)."""
    try:
        import rerun_cli
    except ImportError:
        sys.exit("screenshots.py: needs rerun-sdk (pip install '.[rerun]')")
    return str(Path(rerun_cli.__file__).with_name("rerun"))


def capture(rrd: Path, layout: Path, png: Path) -> None:
    """Serves ``rrd`` with ``layout`` to Rerun's web viewer and screenshots it into ``png``,
    in a browser profile of its own (beside ``png``)."""
    web, grpc = free_port(), free_port()
    command = [rerun_binary(), str(rrd), str(layout), "--web-viewer", "--renderer", "webgl"]
    command += ["--web-viewer-port", str(web), "--port", str(grpc)]
    # BROWSER=true: the viewer is not opened in a browser of the user's.
    env = {"BROWSER": "true", "RERUN_ANALYTICS": "0", "PATH": "/usr/bin:/bin", "NO_COLOR": "1"}
    log = png.with_suffix(".log")
    with open(log, "wb") as out:
        server = subprocess.Popen(
            command, stdout=out, stderr=subprocess.STDOUT, env=env, start_new_session=True
        )
    try:
        # The address the viewer prints, as it prints it ("... connect at http://...").
        deadline = time.monotonic() + 60
        while not (found := re.search(r"connect at (http://\S+)", log.read_text(errors="replace"))):
            if server.poll() is not None or time.monotonic() > deadline:
                sys.exit(
                    f"screenshots.py: rerun's web viewer did not start: {log.read_text()[-800:]}"
                )
            time.sleep(0.2)
        url = found.group(1)
        flags = ["--headless", "--no-sandbox", "--hide-scrollbars", "--mute-audio"]
        flags += ["--no-first-run", "--disable-extensions", "--timeout=120000"]
        flags += [f"--user-data-dir={png.with_suffix('.profile')}"]
        # Software WebGL: no GPU is needed.
        flags += ["--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
        flags += [f"--window-size={WINDOW[0]},{WINDOW[1]}", f"--virtual-time-budget={BUDGET_MS}"]
        subprocess.run(
            [chromium(), *flags, f"--screenshot={png}", url],
            capture_output=True,
            timeout=300,
            check=True,
        )
    finally:
        os.killpg(server.pid, signal.SIGTERM)  # its own session: the server and what it started
        server.wait(timeout=30)


def component_colours(made: viewers.Scene) -> list[tuple[int, ...]]:
    """The RGB colours of the non-trivial components of the scene, as the viewer draws them."""
    colours = {
        tuple(round(255 * v) for v in c["rgba"][:3]) for c in made.components if not c["trivial"]
    }
    return sorted(colours)


def problem(png: Path, colours: list[tuple[int, ...]]) -> str | None:
    """What is wrong with ``png``, if anything: it must show the components, each colour of
    ``colours`` on at least :data:`MIN_PIXELS` pixels of the 3-D view (the left 60 %) and of
    the plane (the right)."""
    rgb = np.asarray(Image.open(png).convert("RGB"), dtype=np.int16)
    if rgb.std() < 10:
        return f"blank (pixel spread {rgb.std():.1f})"
    split = int(rgb.shape[1] * 0.6)
    missing = []
    for side, pixels in (("3-D view", rgb[:, :split]), ("plane", rgb[:, split:])):
        for colour in colours:
            near = (np.abs(pixels - np.array(colour)).max(axis=2) <= TOLERANCE).sum()
            if near < MIN_PIXELS:
                missing.append(f"{side}: {colour} on {near} pixels")
    return f"the components are not shown ({'; '.join(missing)})" if missing else None


def save_small(png: Path, target: Path) -> int:
    """Writes ``png`` to ``target`` under :data:`MAX_BYTES` (optimized, then quantized)."""
    image = Image.open(png).convert("RGB")
    for colours in (None, 256, 128, 64):
        out = io.BytesIO()
        shown = image if colours is None else image.quantize(colours=colours, dither=0)
        shown.save(out, format="PNG", optimize=True)
        if out.tell() <= MAX_BYTES:
            target.write_bytes(out.getvalue())
            return out.tell()
    sys.exit(f"screenshots.py: {target.name} stays over {MAX_BYTES} bytes")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", choices=sorted(SHOTS), action="append")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="loops-screenshots-") as folder:
        for name in args.only or sorted(SHOTS):
            loops, samples, traj, label = SHOTS[name]()
            made = viewers.scene(loops, samples, traj, name=label)
            layout = Path(folder) / f"{name}.rbl"
            blueprint(layout, np.concatenate([p["positions"] for p in made.paths]))
            rrd = Path(folder) / f"{name}.rrd"
            viewers.to_rerun(loops, samples, rrd, trajectory=traj, name=label)
            shot = Path(folder) / f"{name}.png"
            # The viewer loads in the page's virtual time, which a busy machine can outrun: a
            # few tries before giving up.
            for _ in range(3):
                capture(rrd, layout, shot)
                if (wrong := problem(shot, component_colours(made))) is None:
                    break
            else:
                failed = Path(tempfile.gettempdir()) / f"viewer_{name}.failed.png"
                shutil.copyfile(shot, failed)
                sys.exit(f"screenshots.py: the {name} capture is wrong: {wrong}; see {failed}")
            size = save_small(shot, OUT / f"viewer_{name}.png")
            print(f"wrote docs/images/viewer_{name}.png ({size // 1000} kB)")


if __name__ == "__main__":
    main()
