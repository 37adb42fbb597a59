"""A table of malformed inputs and option values, generated in a folder (no data files needed).

``make_files(folder)`` writes every bad file; ``cli_cases(folder)`` returns
``(class, argv)`` pairs, each of which must end with exit status 2, one
``error:`` line on stderr, no traceback and no file written; ``api_cases(folder)``
returns ``(class, callable)`` pairs that must raise one ``InputError``.  Kept
apart from the test so that the same table can be run against any build
(``python tests/cli/bad_inputs.py SHAPECOND_EXECUTABLE``) to count how many of
its cases a build handles.
"""

from __future__ import annotations

import os
import struct
import sys
from pathlib import Path

import numpy as np

TETRA_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
TETRA_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])

#: A small valid mesh argument and a cheap shape option set used around each bad value.
GOOD = "demo:sphere:subdivisions=1"
SMALL = ["--points", "8", "--no-cache"]


def _off(V, F, extra=""):
    return ("OFF\n" + f"{len(V)} {len(F)} 0\n" + "\n".join(" ".join(f"{x:g}" for x in v) for v in V) + "\n"
            + "\n".join(f"3 {a} {b} {c}" for a, b, c in F) + "\n" + extra)


def _ply_ascii(V, F, n_faces_declared=None, extra=""):
    nf = len(F) if n_faces_declared is None else n_faces_declared
    head = (f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n")
    return head + "\n".join(" ".join(f"{x:g}" for x in v) for v in V) + "\n" + \
        "\n".join(f"3 {a} {b} {c}" for a, b, c in F) + "\n" + extra


def _ply_binary(V, F, n_faces_declared):
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(V)}\nproperty float x\n"
            f"property float y\nproperty float z\nelement face {n_faces_declared}\n"
            "property list uchar int vertex_indices\nend_header\n").encode()
    body = b"".join(struct.pack("<3f", *v) for v in V) + b"".join(struct.pack("<B3i", 3, *f) for f in F)
    return head + body


def _sphere():
    """(V, F) of a 162-vertex icosphere (enough vertices for ``match -n 30``)."""
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=2)
    return np.asarray(s.vertices), np.asarray(s.faces)


def _special_files(d: Path) -> dict:
    """Files that are not regular (FIFOs, a device) and the files a batch output must leave alone."""
    made = {}

    def fifo(name):
        if not os.path.lexists(d / name):
            os.mkfifo(d / name)
        made[name] = d / name

    def link(name, target):
        if not os.path.lexists(d / name):
            (d / name).parent.mkdir(parents=True, exist_ok=True)
            os.symlink(target, d / name)
        made[name] = d / name

    fifo("fifo.off")
    fifo("ids_fifo")
    link("dev_zero.off", "/dev/zero")
    for name, text in {"notes.jsonl": '{"note": 1}\n{"note": 2}\n{"tor', "victim.csv": "a,b\n1,2\n3,",
                       "victim.txt": "precious\n"}.items():
        (d / name).write_text(text)
        made[name] = d / name
    link("link.csv", d / "victim.csv")
    link("planted_lock/.t.csv.lock", d / "victim.txt")
    link("planted_journal/.t.parquet.journal", d / "victim.txt")
    fifo("fifo.jsonl")
    return made


def make_files(folder) -> dict:
    """Write every bad (and one good) file into ``folder``; return name -> path."""
    d = Path(folder)
    d.mkdir(parents=True, exist_ok=True)
    V, F = TETRA_V, TETRA_F
    files = {
        # landmark / id files
        "ids_binary": b"\x00\xff\xfe\x01\x02",
        "ids_latin1": b"\xe9t\xe9\n",
        "ids_nan": "nan\n",
        "ids_inf": "inf\n",
        "ids_huge": f"{2**70}\n",
        "ids_negative": "-3\n",
        "ids_fraction": "1.5\n",
        "ids_repeated": "1\n1\n",
        "ids_empty_lines": "\n\n# nothing\n",
        "ids_words": "left paw\n",
        "ids_fraction_in_line": "5, 7.5, 9\n",  # was read as [5]
        "ids_bim_face_point": "12 0.5 0.5 0\n",  # a .pid point inside triangle 12, not vertex 12
        "ids_coordinates": "12 0.25 0.5 0.75 1.5\n",  # an id followed by coordinates: was read as [12]
        # meshes
        "off_truncated_faces.off": _off(V, F[:1]).replace(f"4 1 0", "4 4 0"),
        "off_truncated_vertices.off": "OFF\n4 4 0\n0 0 0\n1 0 0\n",
        "off_trailing.off": _off(V, F, "garbage after the faces\n"),
        "off_short_face.off": _off(V, F).replace("3 1 2 3", "3 1 2"),
        "off_words.off": _off(V, F).replace("1 0 0", "one 0 0"),
        "off_header_only.off": "OFF\n",
        "off_not_off.off": "this is not a mesh\n",
        "off_binary.off": b"\x00\x01\x02\x03" * 64,
        "off_empty.off": "",
        "off_bad_index.off": _off(V, np.vstack([F, [[1, 2, 9]]])),
        "off_negative_counts.off": "OFF\n-4 2 0\n",
        "off_nan.off": _off(np.vstack([V[:3], [[np.nan, 0, 1]]]), F),
        "off_zero_area.off": _off(V, np.vstack([F, [[1, 1, 2]]])),
        "off_disconnected.off": _off(np.vstack([V, V + 5]), np.vstack([F, F + 4])),
        "off_huge_scale.off": _off(V * 1e200, F),
        "off_tiny_scale.off": _off(V * 1e-200, F),
        # a mesh scaled by 1e-25 and written with 10 decimals (trimesh's OFF export): every vertex at 0
        "off_zero_size.off": _off(np.round(V * 1e-25, 10) + 0.0, F),
        "off_zero_size_sphere.off": _off(np.round(_sphere()[0] * 1e-25, 10) + 0.0, _sphere()[1]),
        "ply_truncated.ply": _ply_ascii(V, F[:2], n_faces_declared=4),
        "ply_trailing.ply": _ply_ascii(V, F, extra="1 2 3\n"),
        "ply_binary_truncated.ply": _ply_binary(V, F[:1], 4),
        "ply_garbage.ply": "ply\nthis is not a header\n",
        "obj_short_face.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2\n",
        "obj_missing_vertex.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n",
        "obj_unknown.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nbanana 1 2\n",
        "obj_short_vertex.obj": "v 0 0 0\nv 1 0\n",
        "stl_truncated.stl": b"\0" * 80 + struct.pack("<I", 10) + b"\0" * 100,
        "unknown_suffix.docx": "hello",
        # point clouds and matrices
        "cloud_collinear.xyz": "\n".join(f"{t:g} {2 * t:g} {3 * t:g}" for t in np.linspace(0, 1, 60)) + "\n",
        "cloud_ragged.xyz": "0 0 0\n1 1\n",
        "cloud_two_columns.xyz": "0 0\n1 1\n2 2\n",
        "cloud_binary.xyz": b"\x00\x80" * 40,
    }
    out = {}
    for name, content in files.items():
        p = d / name
        if isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content, encoding="utf-8")
        out[name] = p
    arrays = {
        "cloud_identical.npy": np.ones((100, 3)),
        "cloud_nan.npy": np.vstack([np.random.default_rng(0).random((40, 3)), [[np.nan, 0, 0]]]),
        "cloud_small.npy": np.random.default_rng(1).random((10, 3)),
        "matrix_complex.npy": (np.ones((5, 5)) - np.eye(5)) * (1 + 1j),
        "matrix_asymmetric.npy": np.array([[0, 1, 2, 1], [1, 0, 1, 1], [3, 1, 0, 1], [1, 1, 1, 0.0]]),
        "matrix_negative.npy": np.array([[0, -1, 2, 1], [-1, 0, 1, 1], [2, 1, 0, 1], [1, 1, 1, 0.0]]),
        "matrix_nan.npy": np.array([[0, np.nan, 2, 1], [np.nan, 0, 1, 1], [2, 1, 0, 1], [1, 1, 1, 0.0]]),
        "matrix_diagonal.npy": np.ones((4, 4)),
        "matrix_zero.npy": np.zeros((4, 4)),
        "matrix_duplicate_points.npy": np.array([[0, 0, 1, 1], [0, 0, 1, 1], [1, 1, 0, 1], [1, 1, 1, 0.0]]),
        "matrix_two.npy": np.array([[0, 1], [1, 0.0]]),
        "array_3x3_bad.npy": np.arange(9.0).reshape(3, 3),
        "array_3d.npy": np.zeros((2, 2, 2)),
        "array_strings.npy": np.array(["a", "b", "c"]),
    }
    for name, arr in arrays.items():
        np.save(d / name, arr)
        out[name] = d / name
    np.savez(d / "npz_named.npy", D=np.ones((4, 4)) - np.eye(4))
    os.replace(d / "npz_named.npy.npz", d / "npz_named.npy")
    out["npz_named.npy"] = d / "npz_named.npy"
    np.savez(d / "npz_without_D.npz", X=np.zeros(3))
    out["npz_without_D.npz"] = d / "npz_without_D.npz"
    out.update(_special_files(d))
    (d / "good.off").write_text(_off(*_sphere()))  # a valid mesh and an id file, to be named as outputs too
    (d / "good_ids").write_text("1\n")
    np.save(d / "matrix_good.npy", np.abs(np.subtract.outer(np.arange(8.0), np.arange(8.0))))
    out["matrix_good.npy"] = d / "matrix_good.npy"
    n_good = len(_sphere()[0])  # ground-truth maps of the 162-vertex good.off onto itself
    for name, ids in (("truth_negative", [0, -5]), ("truth_range", list(range(n_good - 1)) + [n_good + 5]),
                      ("truth_words", ["left", "paw"])):
        (d / name).write_text("\n".join(map(str, ids)) + "\n")
        out[name] = d / name
    out.update({"good.off": d / "good.off", "good_ids": d / "good_ids"})
    for name, make in (("good_link.off", os.symlink), ("good_hardlink.off", os.link)):
        if not os.path.lexists(d / name):
            make(d / "good.off", d / name)
        out[name] = d / name
    (d / "a_folder.off").mkdir(exist_ok=True)
    out["a_folder.off"] = d / "a_folder.off"
    out["missing.off"] = d / "missing.off"
    # symmetry maps
    for name, content in {"sym_binary.sym": b"\x00\x01", "sym_zero.sym": "0\n1\n", "sym_fraction.sym": "1.5\n2\n",
                          "sym_short.sym": "2\n1\n"}.items():
        p = d / name
        p.write_bytes(content) if isinstance(content, bytes) else p.write_text(content)
        out[name] = p
    # evaluation datasets: one bad file among good shapes
    good = _off(V, F)
    for kind, content in {"empty": "", "off_only": "OFF\n", "garbage": "not a mesh at all\n",
                          "binary": b"\x00\xff" * 50}.items():
        cls = d / f"dataset_{kind}" / "cls"
        cls.mkdir(parents=True, exist_ok=True)
        (cls / "shape0.off").write_text(good)
        bad = cls / "shape1.off"
        bad.write_bytes(content) if isinstance(content, bytes) else bad.write_text(content)
        out[f"dataset_{kind}"] = d / f"dataset_{kind}"
    out.update(_remeshed_datasets(d, good))
    return out


#: Remeshed class folders (shapes/ + corres/*.vts) whose ground truth cannot hold.
BAD_VTS = {"vts_short": ("1\n2\n3\n4\n", "1\n2\n3\n"),       # unequal reference counts
           "vts_out_of_range": ("1\n2\n3\n4\n", "1\n2\n3\n9\n"),  # the tetrahedron has 4 vertices
           "vts_zero_based": ("1\n2\n3\n4\n", "0\n1\n2\n3\n"),   # a 0: 0-based by mistake
           "vts_two_per_line": ("1\n2\n3\n4\n", "1 2\n3\n4\n1\n"),
           "vts_fraction": ("1\n2\n3\n4\n", "1\n2.5\n3\n4\n"),
           "vts_missing": ("1\n2\n3\n4\n", None),             # shape1 has no .vts
           "vts_huge": ("1\n2\n3\n4\n", "1\n2\n3\n99999999999999999999999\n"),  # beyond int64
           "vts_superscript": ("1\n2\n3\n4\n", "1\n2\n3\n\u00b2\n")}  # '²'.isdigit() is True


def _remeshed_datasets(d, good) -> dict:
    out = {}
    for kind, (first, second) in BAD_VTS.items():
        cls = d / f"dataset_{kind}" / "cls"
        (cls / "shapes").mkdir(parents=True, exist_ok=True)
        (cls / "corres").mkdir(exist_ok=True)
        for name, vts in (("shape0", first), ("shape1", second)):
            (cls / "shapes" / f"{name}.off").write_text(good)
            if vts is not None:
                (cls / "corres" / f"{name}.vts").write_text(vts, encoding="utf-8")
        out[f"dataset_{kind}"] = d / f"dataset_{kind}"
    plain = d / "dataset_no_corres" / "cls"  # a class with one vertex order asked for the remeshed protocol
    plain.mkdir(parents=True, exist_ok=True)
    for name in ("shape0", "shape1"):
        (plain / f"{name}.off").write_text(good)
    out["dataset_no_corres"] = d / "dataset_no_corres"
    return out


#: Generated shapes with parameters out of range.
BAD_DEMOS = ["demo:sphere:radius=0", "demo:sphere:radius=-1", "demo:sphere:radius=nan",
             "demo:sphere:subdivisions=1.5", "demo:sphere:subdivisions=14", "demo:sphere:subdivisions=-1",
             "demo:animal:delta=nan", "demo:animal:delta=inf", "demo:animal:resolution=5",
             "demo:animal:resolution=0", "demo:torus:n_major=0", "demo:torus:minor=0", "demo:torus:minor=2",
             "demo:plane:n=-3", "demo:cylinder:radius=0", "demo:blob:seed=-1", "demo:nosuchshape",
             "demo:sphere:bogus=1", "demo:sphere:radius", "demo:sphere:radius=1,radius=2"]

#: Files that are not a usable shape (keys of ``make_files``).
BAD_SHAPES = ["off_truncated_faces.off", "off_truncated_vertices.off", "off_trailing.off", "off_short_face.off",
              "off_words.off", "off_header_only.off", "off_not_off.off", "off_binary.off", "off_empty.off",
              "off_bad_index.off", "off_negative_counts.off", "off_nan.off", "off_zero_area.off",
              "off_disconnected.off", "off_huge_scale.off", "off_tiny_scale.off", "off_zero_size.off",
              "ply_truncated.ply",
              "ply_trailing.ply", "ply_binary_truncated.ply", "ply_garbage.ply", "obj_short_face.obj",
              "obj_missing_vertex.obj", "obj_unknown.obj", "obj_short_vertex.obj", "stl_truncated.stl",
              "unknown_suffix.docx", "cloud_collinear.xyz", "cloud_ragged.xyz", "cloud_two_columns.xyz",
              "cloud_binary.xyz", "cloud_identical.npy", "cloud_nan.npy", "matrix_complex.npy",
              "matrix_asymmetric.npy", "matrix_negative.npy", "matrix_nan.npy", "matrix_diagonal.npy",
              "matrix_zero.npy", "matrix_duplicate_points.npy", "matrix_two.npy", "array_3x3_bad.npy",
              "array_3d.npy", "array_strings.npy", "npz_named.npy", "npz_without_D.npz", "a_folder.off",
              "missing.off", "fifo.off", "dev_zero.off"]

BAD_IDS = ["ids_binary", "ids_latin1", "ids_nan", "ids_inf", "ids_huge", "ids_negative", "ids_fraction",
           "ids_repeated", "ids_empty_lines", "ids_words", "ids_fraction_in_line", "ids_bim_face_point",
           "ids_coordinates", "ids_fifo"]
BAD_ID_TEXT = ["-1", "1,1", "a,b", "1.5", "nan", str(2**70), "3,,x"]

#: (option, bad values, command line around it) for numeric options.
BAD_OPTIONS = [
    ("--seed", ["-1", "nan", "1.5", str(2**64)], ["score", GOOD] + SMALL),
    ("--points", ["0", "-5", "abc", "2"], ["score", GOOD, "--no-cache"]),
    ("--target-factor", ["0", "-1", "x"], ["score", GOOD] + SMALL),
    ("--time-limit", ["0", "-1", "nan", "inf"], ["score", GOOD] + SMALL),
    ("--alpha", ["0", "-1", "nan", "inf", "1e300", "1e16"], ["local", GOOD]),
    ("--zero-tol", ["nan", "-1", "0", "1", "inf"], ["local", GOOD]),
    ("--scale", ["inf", "0", "-1", "nan"], ["kappa", GOOD, "--points", "5", "--no-cache"]),
    ("--trials", ["0", "-1", "1e3"], ["kappa", GOOD, "--points", "5", "--no-cache"]),
    ("-k", ["-1", "x"], ["landmarks", GOOD, "--method", "fps"] + SMALL),
    ("--resolve-fraction", ["2", "nan", "-0.5"], ["heatmap", GOOD] + SMALL + ["--png", "OUT.png"]),
    ("--jobs", ["0", "-3"], ["evaluate", "DATASET", "--out", "OUT_DIR"]),
    ("--max-targets", ["-1", "0"], ["evaluate", "DATASET", "--out", "OUT_DIR"]),
    ("--points", ["0", "-1"], ["evaluate", "DATASET", "--out", "OUT_DIR"]),
    ("--delta", ["nan", "inf", "5"], ["demo", "--out", "OUT_DIR"]),
    ("--landmark-points", ["1", "-1"], ["demo", "--out", "OUT_DIR"]),
]

#: ``shapecond match`` around a bad option value of its table (``api.matching.MATCH_PARAMS``, ``match_option_cases``).
MATCH_ARGV = ["match", GOOD, GOOD, "--landmarks-source", "1", "--landmarks-target", "1", "--points", "8", "--no-cache",
              "-o", "OUT.txt"]


def bad_values(constraint, cli: bool) -> list:
    """Values a constraint of ``shapecond.api.params`` refuses: command-line words (``cli``) or Python values
    (past each end of a range, a fraction, a word, NaN, a boolean, None where None is not allowed; for ids a
    word, a negative id and a fraction; a file option: a folder on the command line, nothing in Python, where
    it is checked when read)."""
    from shapecond.api.params import Choice, File, Flag, FlagOr, Ids, IntRange

    none = [] if getattr(constraint, "none", False) else [None]
    if isinstance(constraint, File):
        return ["."] if cli else []
    if isinstance(constraint, Ids):
        return ["x", "-1", "1.5"] if cli else ["x", -1, 1.5]
    if isinstance(constraint, (Choice, Flag, FlagOr)):
        words = ["magic"] if isinstance(constraint, Choice) else []  # a flag takes no word
        return words if cli else ["magic", 1] + none
    ends = [constraint.lo - (0 if getattr(constraint, "lo_open", False) else 1)] if constraint.lo is not None else []
    ends += [constraint.hi + (0 if getattr(constraint, "hi_open", False) else 1)] if constraint.hi is not None else []
    odd = [1.5] if isinstance(constraint, IntRange) else [float("nan"), float("inf")]
    if cli:
        return [str(v) for v in ends + odd] + ["x"]
    return ends + odd + ["x", True] + none


def table_cases(table, cli: bool) -> list[tuple[str, object, object]]:
    """(class, the row of ``table``, bad value) for every bad value (``bad_values``) of every row of a parameter
    table (on the command line, the rows that have an option there)."""
    return [(f"{p.name} {v!r}", p, v) for p in table if p.cli or not cli for v in bad_values(p.constraint, cli)]


def match_option_cases(cli: bool) -> list[tuple[str, object, object, dict]]:
    """(class, the row of ``MATCH_PARAMS``, bad value, the other keywords of ``sc.match``) for every bad value of
    every row (``bad_values``; on the command line, rows that have an option there), each with the matcher the row
    belongs to; and every option of a sample matcher with a matcher that has no such option (Python only)."""
    from shapecond.api.matching import MATCH_PARAMS, inapplicable

    cases = []
    for p in MATCH_PARAMS:
        if cli and not p.cli:
            continue
        own = {"matcher": p.feeds[0]} if p.feeds[0] in ("lh05", "faq") else {}
        cases += [(f"match {p.name} {v!r}", p, v, own) for v in bad_values(p.constraint, cli)]
        if not cli:
            cases += [(f"match {p.name} with matcher {m}", p, p.default, {"matcher": m})
                      for m in ("lh05", "faq", "zoomout")
                      if not any(q.name == p.name and q.feeds[0] not in inapplicable(m) for q in MATCH_PARAMS)]
    return cases


#: Commands that read an INPUT, each with the arguments that make it cheap.
SHAPE_COMMANDS = {
    "info": lambda s: ["info", s],
    "sample": lambda s: ["sample", s, "--points", "4", "--no-cache", "-o", "OUT.npz"],
    "score": lambda s: ["score", s, "--no-cache", "--witness-png", "OUT.png"],
    "kappa": lambda s: ["kappa", s, "--no-cache"],
    "local": lambda s: ["local", s, "--heatmap-png", "OUT.png"],
    "landmarks": lambda s: ["landmarks", s, "-k", "2", "--method", "fps", "--no-cache", "--png", "OUT.png"],
    "heatmap": lambda s: ["heatmap", s, "--no-cache", "--png", "OUT.png"],
    "match-source": lambda s: ["match", s, GOOD, "--landmarks-source", "0", "--landmarks-target", "0",
                               "--no-cache", "-o", "OUT.txt"],
    "match-target": lambda s: ["match", GOOD, s, "--landmarks-source", "0", "--landmarks-target", "0",
                               "--no-cache", "-o", "OUT.txt"],
}

#: Commands that read vertex ids: (argv builder taking the ids argument).
ID_COMMANDS = {
    "sample --landmarks": lambda ids: ["sample", GOOD, "--landmarks", ids] + SMALL + ["-o", "OUT.npz"],
    "score --landmarks": lambda ids: ["score", GOOD, "--landmarks", ids] + SMALL,
    "kappa --landmarks": lambda ids: ["kappa", GOOD, "--landmarks", ids, "--points", "6", "--no-cache"],
    "local --landmarks": lambda ids: ["local", GOOD, "--landmarks", ids],
    "heatmap --landmarks": lambda ids: ["heatmap", GOOD, "--landmarks", ids] + SMALL + ["--png", "OUT.png"],
    "landmarks --user-landmarks": lambda ids: ["landmarks", GOOD, "-k", "0", "--method", "user",
                                               "--user-landmarks", ids] + SMALL,
    "match --landmarks-source": lambda ids: ["match", GOOD, GOOD, "--landmarks-source", ids,
                                             "--landmarks-target", "1", "--points", "8", "--no-cache",
                                             "-o", "OUT.txt"],
    "match --landmarks-target": lambda ids: ["match", GOOD, GOOD, "--landmarks-source", "1",
                                             "--landmarks-target", ids, "--points", "8", "--no-cache",
                                             "-o", "OUT.txt"],
}


def cli_cases(folder) -> list[tuple[str, list[str]]]:
    """Every (class, argv) of the table; OUT* stand for paths in ``folder/out``."""
    f = make_files(folder)
    out = Path(folder) / "out"
    cases = []

    def add(cls, argv):
        argv = [str(out / a) if str(a).startswith("OUT") else str(a) for a in argv]
        cases.append((cls, argv))

    for name in BAD_SHAPES:
        for cmd, build in SHAPE_COMMANDS.items():
            if cmd == "info" and name in ("off_zero_area.off", "off_disconnected.off", "off_nan.off",
                                          "off_bad_index.off", "off_huge_scale.off", "off_tiny_scale.off",
                                          "off_zero_size.off"):
                continue  # info reports these as problems (exit 0) instead of refusing
            add(f"shape file {name} / {cmd}", build(str(f[name])))
    for spec in BAD_DEMOS:
        for cmd, build in SHAPE_COMMANDS.items():
            add(f"generated shape {spec} / {cmd}", build(spec))
    for name in BAD_IDS:
        for cmd, build in ID_COMMANDS.items():
            add(f"id file {name} / {cmd}", build(str(f[name])))
    for text in BAD_ID_TEXT:
        for cmd, build in ID_COMMANDS.items():
            add(f"id list {text!r} / {cmd}", build(text))
    for option, values, base in BAD_OPTIONS:
        for v in values:
            argv = [str(f["dataset_garbage"].parent / "dataset_empty") if a == "DATASET" else a for a in base]
            if argv[0] == "evaluate":  # a valid dataset so that only the option is wrong
                good = Path(folder) / "dataset_good" / "cls"
                good.mkdir(parents=True, exist_ok=True)
                for k in range(2):
                    (good / f"shape{k}.off").write_text(_off(TETRA_V, TETRA_F))
                argv[1] = str(good.parent)
            add(f"option {option} {v}", argv + [option, v])
    for cls, p, v, own in match_option_cases(cli=True):
        add(f"option {cls}", MATCH_ARGV + [w for k, m in own.items() for w in (f"--{k}", m)] + [p.cli[0], v])
    add("option match unknown --zoomout-stp", MATCH_ARGV + ["--zoomout-stp", "3"])
    for name in ("sym_binary.sym", "sym_zero.sym", "sym_fraction.sym", "sym_short.sym"):
        add(f"symmetry map {name}", ["score", GOOD, "--symmetry-map", str(f[name])] + SMALL)
    for kind in ("empty", "off_only", "garbage", "binary"):
        add(f"evaluate dataset with a {kind} file", ["evaluate", str(f[f"dataset_{kind}"]), "--out", "OUT_DIR",
                                                     "--no-cache"])
    for kind in BAD_VTS:
        add(f"evaluate dataset remeshed {kind}", ["evaluate", str(f[f"dataset_{kind}"]), "--out", "OUT_DIR",
                                                  "--no-cache"])
    add("evaluate dataset without corres/ under --protocol remeshed",
        ["evaluate", str(f["dataset_no_corres"]), "--protocol", "remeshed", "--out", "OUT_DIR", "--no-cache"])
    add("evaluate dataset with .vts files under --protocol corresponding",
        ["evaluate", str(f["dataset_vts_short"]), "--protocol", "corresponding", "--out", "OUT_DIR", "--no-cache"])
    add("match of a mesh scaled by 1e-25 (written with 10 decimals) against itself at -n 30",
        ["match", f["off_zero_size_sphere.off"], f["off_zero_size_sphere.off"], "--landmarks-source", "0",
         "--landmarks-target", "0", "-n", "30", "--no-cache", "-o", "OUT.txt"])
    big = "demo:sphere:subdivisions=6"  # 40,962 vertices: LH05 at -n 5000 needs a 37 GB affinity matrix
    for force in ([], ["--force"]):
        add(f"match -n 5000 refused up front for LH05's memory {' '.join(force)}".strip(),
            ["match", big, big, "--landmarks-source", "0", "--landmarks-target", "0", "-n", "5000", "--no-cache",
             "-o", "OUT.txt"] + force)
    small = [GOOD, "--points", "8", "--no-cache"]
    for mode in ([], ["--resume"], ["--overwrite"]):
        for name in ("notes.jsonl", "victim.csv", "link.csv", "fifo.jsonl"):
            add(f"batch output {name} {' '.join(mode)}".strip(), ["batch", *small, "--out", f[name], *mode])
    add("batch output with a planted lock link",
        ["batch", *small, "--out", f["planted_lock/.t.csv.lock"].parent / "t.csv"])
    add("batch output with a planted journal link",
        ["batch", *small, "--out", f["planted_journal/.t.parquet.journal"].parent / "t.parquet"])
    for name in ("ids_fifo", "dev_zero.off", "missing.off", "victim.txt", "good.off"):  # not a pairs list
        add(f"batch pairs list {name}", ["batch", f["good.off"], "--pairs", f[name], "--out", "OUT.csv"])
    # an output that is an input or another output (same file through links), or has no name
    g = str(f["good.off"])
    pair = ["match", GOOD, GOOD, "--landmarks-source", "0", "--landmarks-target", "0", "--points", "8", "--no-cache"]
    add("output is the input: score --html", ["score", g, *SMALL, "--html", g])
    add("output is the input through a link: score --witness-png", ["score", g, *SMALL, "--witness-png",
                                                                     f["good_link.off"]])
    add("output is the input through a hard link: landmarks --ply", ["landmarks", g, "-k", "2", "--method", "fps",
                                                                      *SMALL, "--ply", f["good_hardlink.off"]])
    add("output is the landmark file: heatmap --png", ["heatmap", GOOD, "--landmarks", f["good_ids"], *SMALL,
                                                       "--png", f["good_ids"]])
    add("output is the source: match -o", [*pair[:1], g, *pair[2:], "-o", g])
    add("output is another output: match -o --html", [*pair, "-o", "OUT.txt", "--html", "OUT.txt"])
    add("output is another output: score --html --witness-png", ["score", GOOD, *SMALL, "--html", "OUT.html",
                                                                 "--witness-png", "OUT.html"])
    add("output is another output: local --html --heatmap-png", ["local", GOOD, "--html", "OUT.x",
                                                                 "--heatmap-png", "OUT.x"])
    # --truth and drawings, refused before the matching (-o was written first)
    gg = ["match", g, g, "--landmarks-source", "0", "--landmarks-target", "0", "--points", "8", "--no-cache",
          "-o", "OUT.txt", "--html", "OUT.html", "--truth"]
    for name in ("ids_fifo", "dev_zero.off", "truth_negative", "truth_range", "truth_words", "missing.off"):
        add(f"match --truth {name}", gg + [f[name]])
    vts = f["dataset_vts_short"] / "cls" / "corres"
    add("match --truth of two .vts files of unequal counts", gg + [f"{vts / 'shape0.vts'},{vts / 'shape1.vts'}"])
    add("match --truth of two files that are not .vts", gg + [f"{g},{g}"])
    m = str(f["matrix_good.npy"])
    for option in ("--doubt-ply", "--html", "--doubt-png"):
        add(f"match of distance matrices {option}", ["match", m, m, "--landmarks-source", "0", "--landmarks-target",
                                                     "0", "-o", "OUT.txt", option, "OUT.x"])
    for argv in (["score", GOOD, *SMALL, "--html", ""], [*pair, "-o", "OUT.txt", "--doubt-ply", ""],
                 [*pair, "-o", ""], ["heatmap", GOOD, *SMALL, "--png", ""], ["batch", GOOD, *SMALL, "--out", ""]):
        add(f"output with an empty name: {argv[0]} {argv[-2]} ''", argv)
    add("output is a folder", ["sample", GOOD, "--points", "4", "--no-cache", "-o", str(f["a_folder.off"])])
    add("sample output not .npz", ["sample", GOOD, "--points", "4", "--no-cache", "-o", "OUT.txt"])
    for name in ("off_truncated_faces.off", "off_nan.off", "fifo.off"):  # the shape the level is read against
        for cmd in (["score", GOOD, *SMALL], ["landmarks", GOOD, "-k", "2", "--method", "cnbs-scale", *SMALL]):
            add(f"--epsilon-from {name} / {cmd[0]}", cmd + ["--epsilon-from", f[name], "--json"])
    add("--epsilon and --epsilon-from together", ["score", GOOD, *SMALL, "--epsilon", "0.1", "--epsilon-from", GOOD])
    return cases


def time_limit(cls: str) -> float:
    """Seconds a case may take: 10 for those that used to hang (FIFOs, devices, batch outputs),
    otherwise enough for a slow machine's first compilation of the numba kernels."""
    return 10.0 if any(w in cls for w in ("fifo", "dev_zero", "batch output")) else 300.0


_RESULTS: dict = {}


def _result(kind: str):
    """A small result of each public function (made once, when a case first needs it)."""
    import shapecond as sc

    if kind not in _RESULTS:
        _RESULTS[kind] = {
            "score": lambda: sc.score(GOOD, 8, cache=False),
            "heatmap": lambda: sc.heatmap(GOOD, n_points=8, cache=False),
            "landmarks": lambda: sc.landmarks(GOOD, 2, "fps", 8, cache=False),
            "match": lambda: sc.match(GOOD, GOOD, [0, 5, 9], [0, 5, 9], n_points=8, cache=False, error_bar=True),
            "local_score": lambda: sc.local_score(GOOD, [0, 5, 9]),
        }[kind]()
    return _RESULTS[kind]


def api_cases(folder) -> list[tuple[str, object]]:
    """(class, zero-argument callable) pairs that must raise one ``InputError``."""
    import shapecond as sc

    f = make_files(folder)
    V, F = TETRA_V, TETRA_F
    cases = []
    bad_inputs = [str(f[name]) for name in BAD_SHAPES] + BAD_DEMOS + [
        np.array([[0, 1, 2], [1, 0, 1], [3, 1, 0.0]]), -(np.ones((4, 4)) - np.eye(4)), np.ones((100, 3)),
        (np.vstack([V, [[np.nan, 0, 0]]]), F), (V, F + 10), (V, F.astype(float) + 0.5), "not a file.off", 42,
        (V, np.array([["a", "b", "c"]])), np.zeros((0, 3)), object()]
    funcs = {
        "load": lambda x: sc.load(x),
        "metric_shape": lambda x: sc.metric_shape(x, 8, cache=False),
        "score": lambda x: sc.score(x, 8, cache=False),
        "local_score": lambda x: sc.local_score(x),
        "landmarks": lambda x: sc.landmarks(x, 2, "fps", 8, cache=False),
        "heatmap": lambda x: sc.heatmap(x, n_points=8, cache=False),
        "match": lambda x: sc.match(x, GOOD, [0], [0], n_points=8, cache=False),
        "SymmetryProblem": lambda x: sc.SymmetryProblem(x, 8, cache=False),
    }
    for i, x in enumerate(bad_inputs):
        for fname, fn in funcs.items():
            cases.append((f"input {i} ({str(x)[:40]!r}) / {fname}", lambda fn=fn, x=x: fn(x)))
    for text in BAD_ID_TEXT + [[1, 1], [-1], [1.5], [float("nan")], [2**70], "x"]:
        cases.append((f"landmarks {text!r} / score", lambda t=text: sc.score(GOOD, 8, landmarks=t, cache=False)))
        cases.append((f"landmarks {text!r} / local_score", lambda t=text: sc.local_score(GOOD, t)))
    for name in BAD_IDS:
        cases.append((f"id file {name} / score", lambda p=f[name]: sc.score(GOOD, 8, landmarks=p, cache=False)))
    cases += [
        ("n_points 0", lambda: sc.score(GOOD, 0, cache=False)),
        ("n_points 4.0", lambda: sc.score(GOOD, 4.0, cache=False)),
        ("seed -1", lambda: sc.score(GOOD, 8, seed=-1, cache=False)),
        ("time_limit nan", lambda: sc.score(GOOD, 8, time_limit=float("nan"), cache=False)),
        ("alpha 0", lambda: sc.local_score(GOOD, alpha=0)),
        ("alpha 1e300", lambda: sc.local_score(GOOD, alpha=1e300)),
        ("zero_tol nan", lambda: sc.local_score(GOOD, zero_tol=float("nan"))),
        ("k -1", lambda: sc.landmarks(GOOD, -1, "fps", 8, cache=False)),
        ("unknown method", lambda: sc.landmarks(GOOD, 2, "magic", 8, cache=False)),
        ("unknown matcher", lambda: sc.match(GOOD, GOOD, [0], [0], matcher="magic", n_points=8, cache=False)),
        ("resolve_fraction 2", lambda: sc.heatmap(GOOD, n_points=8, resolve_fraction=2, cache=False)),
        ("unknown score option", lambda: sc.score(GOOD, 8, colour="red")),
        ("sc.match(..., refin=False)", lambda: sc.match(GOOD, GOOD, [0], [0], n_points=8, cache=False, refin=False)),
        ("sc.landmarks(..., methd=)", lambda: sc.landmarks(GOOD, 2, "cnbs", 8, cache=False, methd="fps")),
        ("sc.landmarks fps with a cnbs option", lambda: sc.landmarks(GOOD, 2, "fps", 8, cache=False, n_maps=3)),
        ('sc.score(..., exact="yes")', lambda: sc.score(GOOD, 8, exact="yes", cache=False)),
        ("evaluate garbage", lambda: sc.evaluate(f["dataset_garbage"], cache=False)),
        ("evaluate unknown option", lambda: sc.evaluate(f["dataset_garbage"], cache=False, matcher="lh05")),
        ("evaluate n_jobs 0", lambda: sc.evaluate(f["dataset_garbage"], cache=False, n_jobs=0)),
        *[(f"evaluate remeshed {kind}", lambda kind=kind: sc.evaluate(f[f"dataset_{kind}"], cache=False))
          for kind in BAD_VTS],
        *[(f"{kind} result .{call}", lambda kind=kind, call=call: eval(f"r.{call}", {"r": _result(kind),
                                                                                  "p": Path(folder) / "out" / "x"}))
          for kind in ("score", "heatmap", "landmarks", "match", "local_score")
          for call in ("to_html(123)", "to_html(p, bogus=1)", "plot(fig='x')", "plot(path=123)", "to_html('')")],
        *[(f"heatmap epsilon {e!r}", lambda e=e: sc.heatmap(GOOD, n_points=8, epsilon=e, cache=False))
          for e in ("abc", float("inf"), float("nan"), -1.0)],
        *[(f"landmarks {m} epsilon {e!r}", lambda m=m, e=e: sc.landmarks(GOOD, 2, m, 8, epsilon=e, cache=False))
          for m in ("fps", "cnbs-scale") for e in ("abc", float("inf"), float("nan"))],
        *[(cls, lambda name=p.name, v=v, own=own: sc.match(GOOD, GOOD, [0], [0], **{"n_points": 8, "cache": False,
                                                                                **own, name: v}))
          for cls, p, v, own in match_option_cases(cli=False)],
        ("match zoomout with 2 landmarks", lambda: sc.match(GOOD, GOOD, [0, 1], [0, 1], matcher="zoomout",
                                                           cache=False)),
        ("match zoomout on matrices", lambda: sc.match(np.ones((4, 4)) - np.eye(4), np.ones((4, 4)) - np.eye(4),
                                                       [0, 1, 2], [0, 1, 2], matcher="zoomout")),
    ]
    return cases


def main(argv) -> int:  # pragma: no cover - a measuring tool, run by hand
    """Run the CLI table against an executable; print the share handled as exit 2 + one line."""
    import subprocess
    import tempfile

    exe = argv[1] if len(argv) > 1 else "shapecond"
    with tempfile.TemporaryDirectory() as tmp:
        cases = cli_cases(tmp)
        ok = 0
        for cls, args in cases:
            p = subprocess.run([exe, *args], capture_output=True, text=True, timeout=600, stdin=subprocess.DEVNULL)
            lines = p.stderr.strip().splitlines()
            good = p.returncode == 2 and len(lines) == 1 and lines[0].startswith("error: ")
            ok += good
            if not good:
                print(f"FAIL {cls}: exit {p.returncode}: {(lines or [''])[-1][:120]}")
        print(f"{ok}/{len(cases)} cases handled ({100 * ok / len(cases):.0f} %)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main(sys.argv))
