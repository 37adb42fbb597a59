"""Kill campaign: ``kill -9`` (and SIGTERM) at random moments of ``batch`` and ``evaluate``, then resume.

Usage: python benchmarks/bench_kills.py [--trials 20] [--match-trials 10] [--seed 0] [--keep DIR] [--only CMD]
       [--no-write]

Inputs are generated (no data needed): five bumpy blobs (642 vertices) for
``batch``; a template strip and two bent, renumbered strips with ``.lmk`` landmark
files for ``batch --what match:TEMPLATE --both-directions`` (a map file per row);
the three-strip class of the evaluation tests for ``evaluate``.  Each command is
first run once, complete, from an empty cache: its duration sets the range of the
kill moments and its outputs are the reference.

Each trial starts the command in its own session (process group) with an empty
cache folder, sleeps a seeded random time in [0.05, 0.95] of the reference
duration (every 5th trial: until its first result is on disk, ``first_output``), and sends SIGKILL (every 7th trial: SIGTERM) to the main process only, as
a user's ``kill`` would; every 4th trial runs with ``--jobs 2`` (loky workers).
Five seconds later it lists the processes of the group and of the command's tree
(taken just before the kill) still running, then, with those still alive, runs
the resume: ``batch ... --resume``, or for ``evaluate`` (which has no resume) the
same command again.  The checks:

* right after the kill: every output file present is whole (the table readable,
  each map equal to the reference's, JSON parseable, PNGs ending in IEND, HTML
  closed); for ``evaluate``, every other trial starts on the folder of a complete
  earlier run (another seed), and a folder mixing files of that run and of the
  killed one (``results.json`` new, ``report.md`` old) counts as not whole;
* the resume exits 0; the table holds every reference row exactly once, equal to
  the reference (volatile columns aside); every map equals the reference's; no
  lock, journal or temporary file is left; ``evaluate``'s records equal the
  reference's.

Writes the ``kills`` section of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import csv
import json
import math
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.helpers: the shapes and process tree the suite uses
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _results import command_line, machine, write_section  # noqa: E402

#: Seconds after the kill at which surviving processes are counted (the issue's target).
GRACE = 5.0
#: Row columns that differ between runs of the same rows.
VOLATILE = ("seconds", "cpu_seconds", "peak_memory_mib", "worker", "map_file")
RESUME_TIMEOUT = 300
#: The measurements of the last run, for ``--from-json``.
MEASURES = Path(__file__).with_name("out") / "bench_kills.json"


# --- generated inputs ---------------------------------------------------------------------------

def _write_off(path: Path, V, F) -> None:
    path.write_text(f"OFF\n{len(V)} {len(F)} 0\n" + "".join(f"{x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in V)
                    + "".join(f"3 {a} {b} {c}\n" for a, b, c in F))


def _strip(folder: Path, name: str, n: int, bend=None, seed=None) -> None:
    """A 1 x 0.55 rectangle meshed n x n, bent onto a cylinder and renumbered on request, with a
    ``.lmk`` file of four labelled points off its axes."""
    import numpy as np

    from tests.helpers import bent_strip

    V, F, uv = bent_strip(n, bend, seed)
    _write_off(folder / f"{name}.off", V, F)
    points = {"a": (0.1, 0.1), "b": (0.85, 0.2), "c": (0.3, 0.45), "d": (0.6, 0.4)}
    ids = {k: int(np.argmin(((uv - p) ** 2).sum(1))) for k, p in points.items()}
    (folder / f"{name}.lmk").write_text("".join(f"{k} {v}\n" for k, v in ids.items()))


def make_inputs(root: Path) -> dict:
    """The three input sets (module docstring) under ``root``."""
    import numpy as np

    from shapecond.shapes.synthetic import bumpy_blob, plane_patch

    blobs, coll, data = root / "blobs", root / "coll", root / "data" / "strip"
    for d in (blobs, coll, data):
        d.mkdir(parents=True)
    for k in range(5):
        g = bumpy_blob(subdivisions=3, seed=20 + k)
        _write_off(blobs / f"b{k}.off", g.vertices, g.faces)
    _strip(coll, "template", 13)
    _strip(coll, "s1", 15, 0.5, 1)
    _strip(coll, "s2", 11, 0.35, 2)
    g = plane_patch(n=19)
    V = g.vertices * [1.0, 0.55, 0.0]

    def bent(r):
        th = V[:, 0] / r
        return np.column_stack([r * np.sin(th), V[:, 1], r * (1 - np.cos(th))])

    _write_off(data / "strip0.off", V, g.faces)
    _write_off(data / "strip7.off", bent(0.5), g.faces)
    _write_off(data / "strip12.off", bent(0.3) + [1.0, 2.0, 3.0], g.faces)
    return {"blobs": blobs, "coll": coll, "data": data.parent}


#: The commands of the campaign (``commands``).
NAMES = ("batch", "batch --what match:TEMPLATE", "evaluate")


def commands(inputs: dict) -> dict:
    """name -> (kind, argv after ``shapecond`` without the output, output name)."""
    coll = inputs["coll"]
    return {
        "batch": ("batch", ["batch", str(inputs["blobs"]), "-n", "60"], "t.parquet"),
        "batch --what match:TEMPLATE": ("batch", ["batch", str(coll), "--what", f"match:{coll / 'template.off'}",
                                                  "--matcher", "faq", "--both-directions", "-n", "30"], "m.csv"),
        "evaluate": ("evaluate", ["evaluate", str(inputs["data"]), "--methods", "fps", "--matchers", "faq",
                                  "-n", "30"], "ev"),
    }


# --- processes ----------------------------------------------------------------------------------

def _stat(pid: int):
    """(state, parent pid) of a process from /proc, None when it is gone."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            fields = fh.read().rsplit(b")", 1)[1].split()
        return fields[0].decode(), int(fields[1])
    except (OSError, IndexError, ValueError):
        return None


def _pids() -> list[int]:
    try:
        import psutil

        return psutil.pids()
    except ImportError:
        return [int(n) for n in os.listdir("/proc") if n.isdigit()]


def running(pid: int) -> bool:
    """Whether ``pid`` is a process that has not ended (a zombie has)."""
    try:
        import psutil

        return psutil.Process(pid).status() not in (psutil.STATUS_ZOMBIE, psutil.STATUS_DEAD)
    except ImportError:
        st = _stat(pid)
        return st is not None and st[0] not in ("Z", "X")
    except Exception:  # noqa: BLE001 - NoSuchProcess, AccessDenied
        return False


def tree(pid: int) -> set[int]:
    """The processes below ``pid`` (``tests.helpers.descendants``)."""
    from tests.helpers import descendants

    return descendants(pid)


def group(pgid: int) -> set[int]:
    """The running processes of the process group ``pgid``."""
    out = set()
    for p in _pids():
        try:
            if os.getpgid(p) == pgid and running(p):
                out.add(p)
        except OSError:
            continue
    return out


def _describe(pids) -> str:
    names = []
    for p in sorted(pids):
        try:
            cmd = Path(f"/proc/{p}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace").strip()
        except OSError:
            cmd = "?"
        names.append(f"{p} ({cmd[:60]})")
    return ", ".join(names)


# --- outputs ------------------------------------------------------------------------------------

def read_rows(path: Path) -> list[dict]:
    """The rows of a batch table, typed as the batch writes them; raises if it is not whole."""
    from shapecond.batch import schema

    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        return [schema.coerce_row(r) for r in pq.read_table(path).to_pylist()]
    text = path.read_text()
    if text and not text.endswith("\n"):
        raise ValueError(f"{path.name}: a torn last line")
    if path.suffix == ".csv":
        return [schema.coerce_row(r) for r in csv.DictReader(text.splitlines())]
    return [schema.coerce_row(json.loads(line)) for line in text.splitlines()]


def whole_file(path: Path) -> str | None:
    """Why a report file is not whole (None when it is)."""
    data = path.read_bytes()
    if path.suffix == ".json":
        try:
            json.loads(data)
        except ValueError:
            return f"{path.name}: not JSON"
    elif path.suffix == ".png" and not data.endswith(b"IEND\xaeB`\x82"):
        return f"{path.name}: a PNG without its end"
    elif path.suffix == ".html" and not data.rstrip().endswith(b"</html>"):
        return f"{path.name}: an HTML page without its end"
    elif path.suffix == ".md" and not data.strip():
        return f"{path.name}: empty"
    return None


def leftovers(folder: Path) -> list[str]:
    """Temporary files, journals, locks and staging folders left below ``folder`` (the cache aside)."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob(".*")
                  if "cache" not in p.relative_to(folder).parts
                  and (p.name.endswith((".tmp", ".journal", ".lock")) or p.name.startswith(".staged-")))


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and not (math.isinf(a) or math.isnan(a)):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b or (a != a and b != b)


class Reference:
    """A complete run: its duration and outputs."""

    def __init__(self, kind: str, out: Path, seconds: float):
        self.kind, self.seconds = kind, seconds
        if kind == "batch":
            from shapecond.batch import schema

            self.rows = {schema.row_key(r): r for r in read_rows(out)}
            self.maps = {p.name: p.read_bytes() for p in (out.parent / "maps").glob("*.txt")}
        else:
            self.records = _records(out / "results.json")


def _records(path: Path) -> list:
    data = json.loads(path.read_text())
    return sorted((r["cls"], r["target"], r["method"], r["matcher"], r["n_landmarks"], r["protocol"], r["error"])
                  for r in data["records"])


def check_batch(out: Path, ref: Reference) -> dict:
    """Rows duplicated and missing, and why the table or its maps are not whole (None when they are)."""
    from shapecond.batch import schema

    try:
        rows = read_rows(out) if out.exists() else []
    except Exception as exc:  # noqa: BLE001 - any reader failure: not whole
        return dict(dup=None, missing=None, rows=None, problem=f"{out.name} unreadable: {exc}")
    keys = [schema.row_key(r) for r in rows]
    dup = len(keys) - len(set(keys))
    missing = len(set(ref.rows) - set(keys))
    problems = []
    for r in rows:
        want = ref.rows.get(schema.row_key(r))
        bad = [k for k in schema.NAMES if k not in VOLATILE and want is not None and not _same(r[k], want[k])]
        if want is None or bad:
            problems.append(f"{Path(r['file']).name}: differs from the reference in {bad or 'its key'}")
        if r.get("map_file"):
            path = Path(r["map_file"])
            if not path.exists() or path.read_bytes() != ref.maps.get(path.name):
                problems.append(f"maps/{path.name} is not the reference's map")
    return dict(dup=dup, missing=missing, rows=len(rows), problem="; ".join(problems[:2]) or None)


def check_evaluation(folder: Path, since_ns: int | None) -> str | None:
    """Why an evaluation's folder is not whole: a torn file, or (``since_ns``: the folder held an
    earlier run) a mix of files of the earlier run and of the killed one."""
    files = sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith("."))
    for p in files:
        why = whole_file(p)
        if why:
            return why
    if since_ns is not None:
        new = [p.name for p in files if p.stat().st_mtime_ns >= since_ns]
        old = [p.name for p in files if p.stat().st_mtime_ns < since_ns]
        if new and old:
            return f"mixed runs: {', '.join(new)} new beside {', '.join(old)} of the earlier run"
    return None


# --- one trial ----------------------------------------------------------------------------------

def first_output(kind: str, out: Path, since: int | None) -> bool:
    """Whether the run has written its first result: a row (batch; the journal's first line for Parquet),
    or results.json (evaluate, newer than ``since``, in the folder or its staging folder)."""
    try:
        if kind == "evaluate":  # in its staging folder first (output.staged_outputs)
            return any(p.stat().st_mtime_ns >= (since or 0)
                       for p in [out / "results.json", *out.glob(".staged-*/results.json")] if p.exists())
        if out.suffix == ".parquet":  # a row waits in the journal until the next rewrite
            import pyarrow.parquet as pq

            journal = out.with_name(f".{out.name}.journal")
            return (journal.exists() and journal.read_bytes().count(b"\n") >= 1) or pq.read_metadata(out).num_rows >= 1
        return out.read_bytes().count(b"\n") >= (2 if out.suffix == ".csv" else 1)
    except Exception:  # noqa: BLE001 - not there yet, or replaced while read
        return False


def _env(cache: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "SHAPECOND_WORKERS"}  # the geodesic helper is allowed
    env["SHAPECOND_CACHE"] = str(cache)
    src = Path(__file__).resolve().parents[1] / "src"
    env["PYTHONPATH"] = os.pathsep.join([str(src)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    return env


def _argv(kind: str, argv: list, work: Path, out_name: str) -> list:
    return [sys.executable, "-m", "shapecond", *argv, "--out", str(work / out_name)] + (
        ["--json"] if kind == "evaluate" else [])


def reference(kind: str, argv: list, work: Path, out_name: str) -> Reference:
    work.mkdir(parents=True)
    t0 = time.perf_counter()
    proc = subprocess.run(_argv(kind, argv, work, out_name), env=_env(work / "cache"), capture_output=True,
                          text=True, timeout=600)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"reference run failed: {proc.stderr.strip().splitlines()[-1:]}")
    return Reference(kind, work / out_name, seconds)


def _last_line(path: Path) -> str:
    lines = [s for s in path.read_text(errors="replace").splitlines() if s.strip()]
    return lines[-1][:160] if lines else ""


def trial(name: str, kind: str, argv: list, out_name: str, ref: Reference, work: Path, k: int,
          rng: random.Random, earlier: Path | None) -> dict:
    """One kill and its resume (module docstring); a dict of what was seen."""
    work.mkdir(parents=True)
    out = work / out_name
    since = None
    on_event = k % 5 == 4
    if kind == "evaluate" and earlier is not None and (k % 2 == 1 or on_event):
        shutil.copytree(earlier, out, copy_function=shutil.copy2)
        since = time.time_ns()
    jobs = ["--jobs", "2"] if k % 4 == 1 else []
    sig = signal.SIGTERM if k % 7 == 3 else signal.SIGKILL
    cmd = _argv(kind, argv + jobs, work, out_name)
    env = _env(work / "cache")
    wait = rng.uniform(0.05, 0.95) * ref.seconds  # drawn for every trial: the same moments with or without events
    res = dict(command=name, trial=k, signal=sig.name, event=on_event, jobs=2 if jobs else 1, at=wait, killed=False, children=0,
               done_at_kill=0, left=0,
               left_which="", after_kill=None, resumed=False, whole=False, dup=None, missing=None, message="")
    with open(work / "killed.err", "wb") as err:
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=err, start_new_session=True)
        t0 = time.monotonic()
        if on_event:
            while proc.poll() is None and not first_output(kind, out, since) and time.monotonic() - t0 < 3 * ref.seconds:
                time.sleep(0.005)
            res["at"] = time.monotonic() - t0
        else:
            time.sleep(wait)
        below = tree(proc.pid)
        res["children"] = len(below)
        if proc.poll() is None:
            os.kill(proc.pid, sig)
            res["killed"] = True
        proc.wait()
    t_kill = time.monotonic()
    suspects = below | group(proc.pid)
    while any(map(running, suspects)) and time.monotonic() - t_kill < GRACE:
        time.sleep(0.1)
    time.sleep(max(0.0, GRACE - (time.monotonic() - t_kill)))
    left = {p for p in suspects | group(proc.pid) if running(p)}
    res["left"], res["left_which"] = len(left), _describe(left)
    # what the kill left, before anything else touches it
    if kind == "batch":
        after = check_batch(out, ref)
        res["after_kill"], res["done_at_kill"] = after["problem"], after["rows"] or 0
    else:
        res["after_kill"] = check_evaluation(out, since) if out.is_dir() else None
        res["done_at_kill"] = int(out.is_dir() and any(p.stat().st_mtime_ns >= (since or 0)
                                                       for p in out.iterdir() if p.name == "results.json"))
    rerun = cmd + (["--resume"] if kind == "batch" else [])
    try:
        with open(work / "resume.err", "wb") as err:
            done = subprocess.run(rerun, env=env, stdout=subprocess.DEVNULL, stderr=err, timeout=RESUME_TIMEOUT,
                                  start_new_session=True)
        res["resumed"] = done.returncode == 0
        if not res["resumed"]:
            res["message"] = f"resume exit {done.returncode}: {_last_line(work / 'resume.err')}"
    except subprocess.TimeoutExpired:
        res["message"] = f"resume ran past {RESUME_TIMEOUT} s"
    for p in left:  # only now: a survivor must not be hidden from the resume
        try:
            os.kill(p, signal.SIGKILL)
        except OSError:
            pass
    problems = [f"after the kill: {res['after_kill']}"] if res["after_kill"] else []
    if kind == "batch":
        final = check_batch(out, ref)
        res["dup"], res["missing"] = final["dup"], final["missing"]
        if final["problem"]:
            problems.append(final["problem"])
    elif out.is_dir():
        why = check_evaluation(out, None)
        if why:
            problems.append(why)
        elif res["resumed"] and _records(out / "results.json") != ref.records:
            problems.append("results.json records differ from the reference")
    left_files = leftovers(work)
    if left_files:
        problems.append(f"left: {', '.join(left_files)}")
    res["whole"] = res["resumed"] and not problems and (kind != "batch" or (res["dup"] == 0 and res["missing"] == 0))
    res["message"] = "; ".join(([res["message"]] if res["message"] else []) + problems)
    if left:
        res["message"] = f"alive after {GRACE:.0f} s: {res['left_which']}; " + res["message"]
    return res


# --- the campaign -------------------------------------------------------------------------------

def measure(trials: int, match_trials: int, seed: int, root: Path, only: str | None = None) -> dict:
    inputs = make_inputs(root / "inputs")
    rng = random.Random(seed)
    results, refs = [], {}
    for name, (kind, argv, out_name) in commands(inputs).items():
        if only is not None and name != only:
            continue
        slug = name.split()[0] + ("-match" if "match" in name else "")
        ref = reference(kind, argv, root / f"{slug}-reference", out_name)
        refs[name] = ref.seconds
        earlier = None
        if kind == "evaluate":  # a complete earlier run (another seed) for the odd trials to start on
            earlier = reference(kind, argv + ["--seed", "1"], root / f"{slug}-earlier", out_name)
            earlier = root / f"{slug}-earlier" / out_name
        print(f"{name}: reference {ref.seconds:.1f} s", file=sys.stderr, flush=True)
        for k in range(match_trials if "match" in name else trials):
            r = trial(name, kind, argv, out_name, ref, root / f"{slug}-{k:02d}", k, rng, earlier)
            results.append(r)
            print(f"  {k:2d} {r['signal']} {'on its first result ' if r['event'] else ''}at {r['at']:.1f} s, jobs {r['jobs']}, {r['children']} children, "
                  f"{r['done_at_kill']} done: left {r['left']}, "
                  f"resumed {r['resumed']}, whole {r['whole']} {r['message']}", file=sys.stderr, flush=True)
    return dict(results=results, references=refs, command=command_line(), machine=machine())


def section(m: dict) -> str:
    lines = ["## Kill campaign: kill -9 at random moments of batch and evaluate (bench_kills.py)", "",
             f"`{m.get('command') or command_line()}` — {m.get('machine') or machine()}.", "",
             "Generated inputs (5 blobs of 642 vertices, N = 60; a template and 2 strips with `.lmk` files, "
             "matched both ways, N = 30; the 3-strip evaluation class, N = 30), an empty cache per trial, "
             "the kill moment uniform in [0.05, 0.95] of a complete run's time; SIGKILL to the main process "
             "(every 7th trial SIGTERM), every 4th trial with `--jobs 2`; every 5th trial (#4, #9, ...) is killed instead "
             "the moment the first result is on disk (batch: the first row; evaluate: results.json, on an "
             "earlier run's folder), where a set of outputs is most likely to be left half-replaced. Resume: `--resume` for batch, the "
             "same command again for evaluate (it has no resume). Whole: after the kill and after the resume, "
             "every output file whole (the table readable, maps equal to a complete run's), no lock, journal "
             "or temporary file left, the rows (records) equal to a complete run's; evaluate's odd trials start "
             "on an earlier complete run's folder, which must not be left mixing two runs.", "",
             "| command | complete run (s) | trials | killed mid-run | with child processes at the kill | "
             "rows in the table file at the kill | processes left after 5 s | resume completed | outputs whole | "
             "rows duplicated / missing | failures |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for name, seconds in m["references"].items():
        rs = [r for r in m["results"] if r["command"] == name]
        dup = sum(r["dup"] or 0 for r in rs)
        miss = sum(r["missing"] or 0 for r in rs)
        fails = [f"#{r['trial']} ({r['signal']}): {r['message']}" for r in rs if r["message"]]
        rows = f"{dup} / {miss}" if name.startswith("batch") else "–"
        at_kill = [r["done_at_kill"] for r in rs]
        at_kill = (f"{min(at_kill)}–{max(at_kill)} (0 in {at_kill.count(0)})" if name.startswith("batch")
                   else f"results.json written in {sum(at_kill)}")
        lines.append(f"| `{name}` | {seconds:.1f} | {len(rs)} | {sum(r['killed'] for r in rs)} | "
                     f"{sum(r['children'] > 0 for r in rs)} | {at_kill} | "
                     f"{sum(r['left'] for r in rs)} | {sum(r['resumed'] for r in rs)}/{len(rs)} | "
                     f"{sum(r['whole'] for r in rs)}/{len(rs)} | {rows} | "
                     f"{'<br>'.join(fails) if fails else 'none'} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20, help="trials of batch and of evaluate")
    parser.add_argument("--match-trials", type=int, default=10, help="trials of batch --what match:TEMPLATE")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--keep", type=Path, default=None, help="work in this (new) folder and keep it")
    parser.add_argument("--only", choices=NAMES, default=None,
                        help="run the trials of this command alone; they replace that command's trials in the "
                             "last saved full run, and the section is written when there is one")
    parser.add_argument("--no-write", action="store_true")
    parser.add_argument("--from-json", action="store_true",
                        help=f"rebuild the section from the measurements saved in {MEASURES.name}")
    args = parser.parse_args(argv)
    if args.from_json:
        m = json.loads(MEASURES.read_text())
    else:
        root = args.keep or Path(tempfile.mkdtemp(prefix="bench-kills-"))
        try:
            m = measure(args.trials, args.match_trials, args.seed, root, args.only)
        finally:
            if args.keep is None:
                shutil.rmtree(root, ignore_errors=True)
        if args.only and MEASURES.exists():  # one command's trials replace its own in the last full run
            full = json.loads(MEASURES.read_text())
            full["results"] = [r for r in full["results"] if r["command"] != args.only] + m["results"]
            full["references"][args.only] = m["references"][args.only]
            full["command"] += f"; then {m['command']}"
            m = full
        if set(m["references"]) == set(NAMES):
            MEASURES.parent.mkdir(exist_ok=True)
            MEASURES.write_text(json.dumps(m, indent=1))
    text = section(m)
    print(text)
    if not args.no_write and set(m["references"]) == set(NAMES):
        write_section("kills", text)


if __name__ == "__main__":
    main()
