"""Shared by the benchmark scripts: machine description and RESULTS.md sections."""

from __future__ import annotations

import os
import platform
import re
import resource
import subprocess
import sys
import tarfile
import tempfile
import time
from datetime import date
from pathlib import Path

RESULTS = Path(__file__).with_name("RESULTS.md")
ROOT = Path(__file__).resolve().parent.parent
OUT = Path(__file__).parent / "out"


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    return f"{os.cpu_count()} cores ({cpu}), {mem:.0f} GiB, Python {platform.python_version()}, {date.today()}"


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far, in MB (Linux: ru_maxrss is in kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def write_section(name: str, body: str) -> None:
    """Replace (or append) the section between <!-- BEGIN name --> and <!-- END name -->."""
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    block = f"{begin}\n{body.rstrip()}\n{end}"
    text = RESULTS.read_text() if RESULTS.exists() else "# Benchmark results\n\nEach section is written by the script it names; rerun the command shown to refresh it.\n"
    pattern = re.compile(re.escape(begin) + r".*?" + re.escape(end), re.S)
    text = pattern.sub(lambda _: block, text) if pattern.search(text) else text.rstrip() + "\n\n" + block + "\n"
    RESULTS.write_text(text)


def command_line() -> str:
    return "python " + " ".join([Path(sys.argv[0]).as_posix()] + sys.argv[1:])


def run_isolated(code: str, timeout: float = 3600) -> tuple[str, float]:
    """Run Python ``code`` in a fresh interpreter; return (stdout, its peak RSS in MB)."""
    r = run_variant(code, timeout=timeout)
    return r["stdout"].strip(), r["rss"]


def git(*args: str) -> str:
    return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, check=True).stdout.strip()


def baseline_src(rev: str) -> tuple[str, Path]:
    """(sha, src folder) of the package at git revision ``rev``, extracted once under benchmarks/out/
    (a stable path: numba caches its kernels).  Put the folder first on PYTHONPATH to run it."""
    sha = git("rev-parse", rev)
    dest = OUT / f"baseline-{sha[:10]}"
    if not (dest / "src" / "shapecond").exists():
        dest.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", sha, "src"], capture_output=True, check=True)
        with tempfile.TemporaryFile() as f:
            f.write(archive.stdout)
            f.seek(0)
            with tarfile.open(fileobj=f) as tar:
                tar.extractall(dest, filter="data")
    return sha, dest / "src"


def run_variant(code: str, src: Path | None = None, cache: Path | None = None, timeout: float | None = None) -> dict:
    """Python ``code`` in a fresh interpreter, with ``src`` first on the path (a ``baseline_src``; None:
    the working tree) and ``SHAPECOND_CACHE=cache`` if given: wall, CPU (the process and the children it
    waited for: not loky's reusable workers, which are not reaped), ``tree_cpu`` (the CPU of the whole
    process tree, loky's workers included: they are reaped when the interpreter exits), its peak RSS in
    MB, the 1-minute load average before, stdout.  Raises on a non-zero exit."""
    env = dict(os.environ)
    if cache is not None:
        env["SHAPECOND_CACHE"] = str(cache)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    load = os.getloadavg()[0]
    t = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run([sys.executable, "-c", code + "\nimport resource\nru, rc = resource.getrusage("
                           "resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)\n"
                           "print('__CPU__', ru.ru_utime + ru.ru_stime + rc.ru_utime + rc.ru_stime, "
                           "ru.ru_maxrss / 1024)"],
                          capture_output=True, text=True, env=env, timeout=timeout)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    tree = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else "child failed")
    out, tail = proc.stdout.rsplit("__CPU__", 1)
    cpu, rss = tail.split()
    return dict(wall=wall, cpu=float(cpu), tree_cpu=tree, rss=float(rss), load=load, stdout=out)
