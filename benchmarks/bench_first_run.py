"""First-run cost: numba compilation in a fresh install, and none in the second process (issue 16 item 4).

Usage: python benchmarks/bench_first_run.py [--runs 2]

Installs this checkout *non-editably* (``pip install --no-deps --target``) into
a temporary folder and runs ``shapecond demo`` there in fresh interpreters,
counting numba compilations (numba's ``numba:compile`` events) and timing each
process from the outside.  The distance cache is emptied before every run, so
that only compiled kernels carry over from one process to the next.  Cases:

``package writable``   numba caches next to the installed sources;
``package read-only``  the package belongs to root and the demo runs as user
                       nobody (only when this script runs as root): numba's
                       cache goes to ``~/.cache/shapecond/numba``
                       (``shapecond._jit_cache``);
``no home folder``     the same with ``HOME=/nonexistent``: the temporary
                       directory is the fallback.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _results import command_line, machine, write_section  # noqa: E402

REPO = Path(__file__).resolve().parent.parent

CHILD = """
import json, resource, sys, time
t0 = time.perf_counter()
import shapecond  # first, as the shapecond command does
from numba.core import event
from shapecond.cli import main
with event.install_recorder("numba:compile") as rec:
    try:
        main(["demo", "--out", sys.argv[1]])
    except SystemExit as exc:
        code = exc.code
kernels = sorted({e.data["dispatcher"].py_func.__qualname__ for _, e in rec.buffer if e.is_start})
ru = resource.getrusage(resource.RUSAGE_SELF)
print("__RESULT__" + json.dumps({"code": code, "compiled": kernels, "inside": time.perf_counter() - t0,
                                 "cpu": ru.ru_utime + ru.ru_stime}))
"""


def install(target: Path) -> None:
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(target), str(REPO)],
                   check=True, capture_output=True)


def run_demo(site: Path, work: Path, user: str | None, home: str) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "SHAPECOND_"))}
    env.update(PYTHONPATH=str(site), HOME=home, PYTHONDONTWRITEBYTECODE="1")
    cmd = [sys.executable, "-c", CHILD, str(work / "out")]
    if user:
        cmd = ["setpriv", f"--reuid={user}", f"--regid={user}", "--clear-groups"] + cmd  # numeric ids
    for stale in Path(home).glob(".cache/shapecond/metric-*.npz") if Path(home).exists() else []:
        stale.unlink()  # distances are recomputed every run: only compiled kernels carry over
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=work)
    wall = time.perf_counter() - t
    if "__RESULT__" not in proc.stdout:
        raise RuntimeError(proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else "demo failed")
    out = json.loads(proc.stdout.split("__RESULT__", 1)[1])
    out["wall"] = wall
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=2)
    args = ap.parse_args()
    rows = ["| case | run | numba compilations | wall (s) | CPU (s) | load before |", "|---|---|---|---|---|---|"]
    with tempfile.TemporaryDirectory(prefix="shapecond-first-run-") as tmp:
        tmp = Path(tmp)
        os.chmod(tmp, 0o755)
        cases = [("package writable", None, "home-root")]
        if hasattr(os, "geteuid") and os.geteuid() == 0 and shutil.which("setpriv"):
            cases += [("package read-only", "65534", "home-nobody"), ("no home folder", "65534", "/nonexistent")]
        for name, user, home in cases:
            site = tmp / f"site-{len(rows)}"
            install(site)
            work = tmp / f"work-{len(rows)}"
            work.mkdir()
            if not home.startswith("/"):
                home = str(tmp / home)
                Path(home).mkdir()
            if user:
                os.chown(work, int(user), int(user))
                if Path(home).exists():
                    os.chown(home, int(user), int(user))
            for run in range(1, args.runs + 1):
                load = os.getloadavg()[0]
                r = run_demo(site, work, user, home)
                compiled = f"{len(r['compiled'])}" + (f" ({', '.join(r['compiled'][:3])}, ...)" if r["compiled"] else "")
                rows.append(f"| {name} | {run} | {compiled} | {r['wall']:.1f} | {r['cpu']:.1f} | {load:.2f} |")
                print(rows[-1], flush=True)
    body = "\n".join([
        "## First run: numba compilation (issue 16 item 4)", "",
        f"Machine: {machine()}. Command: `{command_line()}` (as root; the read-only cases run the demo as "
        "user nobody, uid 65534).", "",
        "Each run is a fresh process running `shapecond demo` from a non-editable install with an empty "
        "distance cache; only numba's on-disk kernels carry over. Load: the 1-minute load average just "
        "before the run (other agents share the machine).", ""] + rows)
    write_section("first-run", body)


if __name__ == "__main__":
    main()
