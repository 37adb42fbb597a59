"""HTML heat-map page of a TOSCA mesh: file size and time to the first frame in headless Chromium (issue 26).

Usage: python benchmarks/bench_html.py DATASET_DIR [--shape cat/cat0.off] [--points 150] [--runs 5]

DATASET_DIR is ``shared/data/tosca_hires`` (class folders of .off meshes).  Runs
``shapecond heatmap SHAPE --points N --html FILE`` in a fresh process (the heat map
itself is not what is measured; a small N keeps it to a minute or two), then opens
the page ``--runs`` times in the system's Chromium, driven by Playwright, each time
in a fresh browser profile with every network request refused, and reads:

* time to first frame: from navigation start to the animation frame that shows the
  viewer's first drawing (``viewer.firstFrame``, ``performance.now()``);
* hover: milliseconds for one vertex pick under the pointer (``vertexAt`` at the
  canvas centre, the ray cast against every triangle), median of 20.

Targets (issue 26): a 28k-vertex heat-map page at most 5 MB, first frame within 3 s.
Writes the ``html`` section of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _results import OUT, command_line, machine, write_section  # noqa: E402

#: How the browser is started (the tests use the same flags); WebGL runs on SwiftShader (software).
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--proxy-server=127.0.0.1:9"]

READY = ("window.shapecond && (window.shapecond.error || (window.shapecond.ready && "
         "window.shapecond.viewers.every(v => v.firstFrame !== null)))")
PICK = """() => { const v = window.shapecond.viewers[0], r = v.canvas.getBoundingClientRect();
  const t = []; let hit = -1;
  for (let k = 0; k < 20; k++) { const t0 = performance.now(); hit = v.vertexAt(r.left + r.width / 2,
    r.top + r.height / 2); t.push(performance.now() - t0); }
  t.sort((a, b) => a - b); return [t[10], hit]; }"""


def make_page(shape: Path, points: int, out: Path) -> tuple[float, dict]:
    """Run ``shapecond heatmap --html``; return (wall seconds, its JSON)."""
    exe = Path(sys.executable).with_name("shapecond")
    cmd = [str(exe), "heatmap", str(shape), "--points", str(points), "--effort", "quick", "--html", str(out),
           "--json"]
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return time.perf_counter() - t, json.loads(proc.stdout)


def open_page(p, exe: str, path: Path) -> dict:
    """One fresh browser: time to first frame, pick time, errors and requests."""
    with tempfile.TemporaryDirectory() as profile:
        ctx = p.chromium.launch_persistent_context(profile, executable_path=exe, args=CHROMIUM_ARGS,
                                                   headless=True, viewport={"width": 1100, "height": 800})
        try:
            page = ctx.new_page()
            errors, requests = [], []
            page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
            page.on("request", lambda r: requests.append(r.url))
            t = time.perf_counter()
            page.goto(path.resolve().as_uri())
            page.wait_for_function(READY, timeout=60_000)
            wall = time.perf_counter() - t
            first = page.evaluate("window.shapecond.viewers[0].firstFrame") / 1000.0
            pick, hit = page.evaluate(PICK)
            n = page.evaluate("window.shapecond.viewers[0].n")
            return dict(first=first, wall=wall, pick_ms=pick, hit=hit, n=n, errors=errors,
                        offline=all(u.startswith(("file:", "blob:", "data:")) for u in requests),
                        version=ctx.browser.version if ctx.browser else "")
        finally:
            ctx.close()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dataset", type=Path)
    ap.add_argument("--shape", default="cat/cat0.off")
    ap.add_argument("--points", type=int, default=150)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    from playwright.sync_api import sync_playwright

    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        sys.exit("no Chromium: apt-get install chromium")
    shape = args.dataset / args.shape
    out = OUT / f"{shape.stem}_heatmap.html"
    out.parent.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg()
    seconds, hm = make_page(shape, args.points, out)
    size = out.stat().st_size
    with sync_playwright() as p:
        runs = [open_page(p, exe, out) for _ in range(args.runs)]
    chromium = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.strip()
    firsts = [r["first"] for r in runs]
    body = "\n".join([
        "## HTML heat-map page (bench_html.py)", "",
        f"Machine: {machine()}. Command: `{command_line()}`. Load average before: "
        f"{load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f} (1 / 5 / 15 min). Browser: {chromium}, headless, "
        f"`{' '.join(CHROMIUM_ARGS)}` (WebGL 2 on SwiftShader, no GPU), through Playwright; every run a "
        "fresh profile, every network request refused. Targets (issue 26): ≤ 5 MB, first frame ≤ 3 s.", "",
        "| shape | vertices shown | N | page | first frame, median (min-max) of "
        f"{len(runs)} | page load to ready (median) | one hover pick | offline | console errors |",
        "|---|---|---|---|---|---|---|---|---|",
        f"| {args.shape} | {runs[0]['n']:,} | {args.points} | {size / 1e6:.2f} MB | "
        f"{statistics.median(firsts):.2f} s ({min(firsts):.2f}-{max(firsts):.2f}) | "
        f"{statistics.median(r['wall'] for r in runs):.2f} s | {statistics.median(r['pick_ms'] for r in runs):.1f} ms "
        f"| {'yes' if all(r['offline'] for r in runs) else 'NO'} | {sum(len(r['errors']) for r in runs)} |", "",
        f"Making the page (`shapecond heatmap --points {args.points} --effort quick --html`, geodesics, heat "
        f"map and page, one fresh process, cold cache or not as found): {seconds:.1f} s; its own report "
        f"{hm['seconds']:.1f} s.", "",
        "First frame: from navigation start to the animation frame after the viewer's first drawing "
        "(`performance.now()` in the page: reading 2.3 MB of HTML, decoding the base64 arrays, compiling "
        "three.js and the shaders, drawing with WebGL on SwiftShader). Page load to ready: Python's wall "
        "time from `page.goto` to the ready flag, Playwright's round trips included. Hover pick: one ray "
        "cast against every triangle of the mesh (three.js `Raycaster`), then the nearest corner.",
    ])
    write_section("html", body)
    print(body)


if __name__ == "__main__":
    main()
