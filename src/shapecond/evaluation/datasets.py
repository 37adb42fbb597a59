"""Class folders of an evaluation: which shapes, which source and targets, and which ground truth.

Shapes with one vertex order (``"shared"``, TOSCA): a class folder holds mesh
files (``.off``, ``.obj``, ``.ply``) with one vertex count and vertex order, so
the ground truth is the identity on vertex ids.

Differently meshed shapes (``"remeshed"``): every shape has its own
triangulation and a ``NAME.vts`` file in a ``corres`` folder (``shapes.vts``):
shapes ``a``, ``b`` correspond at the reference points ``(vts_a[j], vts_b[j])``.
The field's releases ship in three layouts, all read here:

* **per class** (ours): ``CLASS/shapes/NAME.off`` + ``CLASS/corres/NAME.vts``; a
  dataset folder that is itself such a class is one class named after it;
* **flat** (Ren et al. 2018, TOSCA_r and the non-isometric TOSCA): ``DIR/NAME.off``
  + ``DIR/corres/NAME.vts`` (+ ``NAME.sym.vts``), a ``test_pairs.txt`` beside;
* **split** (GeomFmaps, DUO-FM: SMAL_r, FAUST_r, SCAPE_r): ``DIR/shapes_train/``,
  ``DIR/shapes_test/`` (any ``shapes_*`` folder) + ``DIR/corres/NAME.vts``.

A flat or split folder holds several classes when every shape's name is a class
name followed by a number with at least two shapes per class (``cat0``,
``cat10``, ``david3``: TOSCA_r), else one class named after the folder (SMAL_r's
animals, FAUST_r's ``tr_reg_080``).  A dataset folder holding one flat release
folder (``TOSCA_r/vtx_5k``) is read as that folder.

Left–right flips are counted when the ground truth says where each reference
point's mirror image is: ``corres/NAME.sym.vts`` (the vertex of ``NAME`` at the
mirror of reference point ``j``; Ren et al.'s releases) or
``corres/reference.sym`` (line ``j``: the 1-based reference point mirroring ``j``).

Without a pairs list the null shape of each class (the one whose name ends with
the lowest number, ``cat0``, ``tr_reg_080``, else the first by name) is matched
to the rest of its class.  A pairs list (``shapes.pairs_list.read_pairs``: two shape names a line,
as the releases' ``test_pairs.txt``) gives exactly the pairs the field's tables
evaluate, across classes too (gorilla → human); each source is then a group of
its own, named after it.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..shapes.formats import check_file, off_header
from ..shapes.vts import read_vts

MESH_SUFFIXES = (".off", ".obj", ".ply")
LAYOUTS = ("shared", "remeshed")


@dataclass(frozen=True)
class ClassFolder:
    """One class, or one source with its targets: shapes (source first) and their ground truth.

    Attributes
    ----------
    name : the class name (folder or name prefix), or the source's name in a pairs list.
    shapes : mesh paths, the source (null shape) first.
    layout : "shared" (same vertex ids) or "remeshed" (``.vts`` files).
    """

    name: str
    shapes: tuple
    layout: str = "shared"

    @property
    def null(self) -> Path:
        return self.shapes[0]

    @property
    def targets(self) -> tuple:
        return self.shapes[1:]

    def vts_path(self, shape: Path) -> Path:
        """The ``corres/NAME.vts`` file of a shape of a remeshed class."""
        return self._corres(shape) / f"{Path(shape).stem}.vts"

    @staticmethod
    def _corres(shape) -> Path:
        """A shape's ``corres`` folder: beside it (flat layout) or beside its folder (per class, split)."""
        here = Path(shape).parent
        return here / "corres" if (here / "corres").is_dir() else here.parent / "corres"

    def mirror_path(self, shape: Path) -> Path | None:
        """``corres/NAME.sym.vts`` of a shape (its reference points' mirror images), when there is one."""
        p = self._corres(shape) / f"{Path(shape).stem}.sym.vts"
        return p if self.layout == "remeshed" and p.is_file() else None

    def symmetry_path(self) -> Path | None:
        """``corres/reference.sym`` of a remeshed class, when there is one."""
        p = self._corres(self.null) / "reference.sym"
        return p if self.layout == "remeshed" and p.is_file() else None


def _mesh_files(folder: Path) -> list[Path]:
    """The mesh files of a folder, by suffix; one named like a mesh that is not a readable regular file
    (a FIFO, a device, a dangling link or a link loop) is refused, not dropped."""
    out = []
    for p in sorted(folder.iterdir()):
        if p.suffix.lower() not in MESH_SUFFIXES:
            continue
        try:
            regular = p.is_file()
        except OSError:  # a link loop
            regular = False
        if not regular:
            raise InputError(f"{p}: not a regular file (a FIFO, a device, a dangling link or a link loop)")
        out.append(p)
    return out


def _number_order(p: Path):
    m = re.search(r"(\d+)$", p.stem)
    return (int(m.group(1)) if m else math.inf, p.stem)


def _release_shapes(folder: Path) -> list[Path] | None:
    """Mesh files of a flat or split release folder (module docstring), or None when it is neither."""
    if not (folder / "corres").is_dir():
        return None
    split = sorted(p for p in folder.iterdir() if p.is_dir() and p.name.startswith("shapes_"))
    if split:
        return [f for d in split for f in _mesh_files(d)]
    flat = _mesh_files(folder)
    return flat or None


def _by_prefix(files: list[Path], fallback: str) -> dict[str, list[Path]]:
    """Classes of a flat or split release: name prefixes when every name is PREFIX + number with at
    least two shapes each, else one class ``fallback`` (module docstring)."""
    groups: dict[str, list[Path]] = {}
    for p in files:
        m = re.fullmatch(r"(.*?[^\d_-])[_-]?(\d+)", p.stem)
        if m is None:
            return {fallback: files}
        groups.setdefault(m.group(1), []).append(p)
    if len(groups) > 1 and all(len(v) >= 2 for v in groups.values()):
        return groups
    return {fallback: files}


def _remeshed_class(name: str, files: list[Path], corres: Path) -> ClassFolder:
    files = sorted(files, key=_number_order)
    if len(files) < 2:
        raise InputError(f"class {name}: a class needs at least two shapes, found {len(files)}")
    _unique_names(name, files)
    missing = [p for p in files if not (corres / f"{p.stem}.vts").is_file()]
    if missing:
        raise InputError(f"{name}: no corres/{missing[0].stem}.vts for {missing[0].name} "
                         "(every shape of a remeshed class needs its .vts ground truth)")
    return ClassFolder(name, tuple(files), "remeshed")


def read_class(folder) -> ClassFolder:
    """The class in ``folder`` (per-class or shared layout); ``InputError`` when it is not one."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: not a folder")
    if (folder / "corres").is_dir():
        if not (folder / "shapes").is_dir():
            raise InputError(f"{folder}: a remeshed class needs a shapes/ folder beside corres/ "
                             "(or the shapes themselves, or shapes_train/ / shapes_test/ folders)")
        return _remeshed_class(folder.name, _mesh_files(folder / "shapes"), folder / "corres")
    files = sorted(_mesh_files(folder), key=_number_order)
    if len(files) < 2:
        raise InputError(f"{folder}: a class needs at least two shapes, found {len(files)}")
    _unique_names(folder.name, files)
    return ClassFolder(folder.name, tuple(files), "shared")


def _unique_names(name: str, files: list[Path]) -> None:
    """Refuse two shapes of one name (``blob1.off`` beside ``blob1.ply``): records, ``.vts`` files and
    pairs lists name shapes without their suffix."""
    stems = [p.stem for p in files]
    dup = next((s for s in stems if stems.count(s) > 1), None)
    if dup is not None:
        raise InputError(f"class {name}: two shapes named {dup!r} ({', '.join(p.name for p in files if p.stem == dup)})")


def _is_class(p: Path) -> bool:
    return p.is_dir() and ((p / "corres").is_dir() or any(q.suffix.lower() in MESH_SUFFIXES for q in p.iterdir()))


def _release_root(root: Path) -> Path:
    """``root``, or the one flat/split release folder inside it (``TOSCA_r`` holding ``vtx_5k``)."""
    if (root / "corres").is_dir():
        return root
    inner = [p for p in sorted(root.iterdir()) if p.is_dir() and _release_shapes(p) and not (p / "shapes").is_dir()]
    return inner[0] if len(inner) == 1 and not any(_mesh_files(root)) else root


def all_classes(dataset_dir) -> dict[str, ClassFolder]:
    """Class name -> ClassFolder for every class of ``dataset_dir`` in any layout (module docstring)."""
    root = Path(dataset_dir)
    if not root.is_dir():
        raise InputError(f"{root}: not a folder")
    root = _release_root(root)
    if (root / "corres").is_dir() and not (root / "shapes").is_dir():
        files = _release_shapes(root)
        if not files:
            raise InputError(f"{root}: a release folder with corres/ but no shapes (NAME.off beside corres/, "
                             "or shapes_train/ / shapes_test/ folders)")
        return {n: _remeshed_class(n, fs, root / "corres") for n, fs in sorted(_by_prefix(files, root.name).items())}
    if (root / "corres").is_dir():
        return {root.name: read_class(root)}
    return {p.name: read_class(p) for p in sorted(root.iterdir()) if _is_class(p)}


def find_classes(dataset_dir, classes=None) -> dict[str, ClassFolder]:
    """Class name -> ClassFolder for the classes of ``dataset_dir``; ``classes`` restricts."""
    root = Path(dataset_dir)
    found = all_classes(root)
    if classes:
        missing = [c for c in classes if c not in found]
        if missing:
            raise InputError(f"class {missing[0]!r} not found in {root} (found: {', '.join(found) or 'none'})")
        found = {c: found[c] for c in classes}
    if not found:
        raise InputError(f"{root}: no class folders with meshes")
    return found


def pair_groups(dataset_dir, pairs) -> dict[str, ClassFolder]:
    """One group per source of ``pairs`` (names), with its targets in the list's order.

    Names are looked up among every shape of ``dataset_dir`` (any class); a name
    that is not there is refused before any work.  A group is remeshed when its
    shapes are (their ``.vts`` folder is the source's).
    """
    classes = all_classes(dataset_dir)
    where = {}
    for c in classes.values():
        for p in c.shapes:
            where.setdefault(p.stem, (p, c))
    groups: dict[str, list] = {}
    for a, b in pairs:
        for n in (a, b):
            if n not in where:
                raise InputError(f"the pairs list names {n!r}, which is not a shape of {dataset_dir}")
        groups.setdefault(a, [where[a][0]])
        if where[b][0] not in groups[a]:
            groups[a].append(where[b][0])
    out = {}
    for a, shapes in groups.items():
        c = where[a][1]
        if any(where[p.stem][1].layout != c.layout for p in shapes):
            raise InputError(f"the pair {a} -> {shapes[1].stem} mixes shapes with and without .vts ground truth")
        out[a] = ClassFolder(a, tuple(shapes), c.layout)
    return out


def off_vertex_count(path: Path) -> int | None:
    """Vertex count from an OFF header without reading the mesh (None if not OFF)."""
    path = Path(path)
    if path.suffix.lower() != ".off":
        return None
    check_file(path)
    with open(path, "rb") as fh:
        head = fh.read(4096).decode("latin-1")
    lines = [ln.split("#", 1)[0].split() for ln in head.splitlines()[:-1] or head.splitlines()]
    return off_header([ln for ln in lines if ln], path.name)[0]


def check_layout(cls: ClassFolder) -> None:
    """Refuse a class whose ground truth cannot hold, before any work.

    Shared layout: every OFF header must give one vertex count.  Remeshed: every
    ``.vts`` (and ``.sym.vts``) must be readable with ids in range of its mesh's
    header count, and all of them must have the same number of reference points.
    """
    counts = {p.name: off_vertex_count(p) for p in cls.shapes}
    if cls.layout == "shared":
        if len({c for c in counts.values() if c is not None}) > 1:
            raise InputError(f"class {cls.name}: shapes have different vertex counts "
                             f"({', '.join(f'{k}: {v}' for k, v in counts.items())}); shapes of a class need "
                             "one vertex order, or a corres/ folder of .vts files")
        return
    refs = {}
    for p in cls.shapes:
        refs[p.stem] = read_vts(cls.vts_path(p), counts[p.name], f"{cls.name}/corres/{p.stem}.vts").size
        mirror = cls.mirror_path(p)
        if mirror is not None:
            n = read_vts(mirror, counts[p.name], f"{cls.name}/corres/{mirror.name}").size
            if n != refs[p.stem]:
                raise InputError(f"class {cls.name}: corres/{mirror.name} has {n} lines but {p.stem}.vts has "
                                 f"{refs[p.stem]}")
    if len(set(refs.values())) > 1:
        raise InputError(f"class {cls.name}: the .vts files have unequal reference counts "
                         f"({', '.join(f'{k}: {v}' for k, v in refs.items())})")


def reference_symmetry(cls: ClassFolder, n_references: int) -> np.ndarray | None:
    """0-based mirror reference point of every reference point (``corres/reference.sym``), or None."""
    p = cls.symmetry_path()
    if p is None:
        return None
    sym = read_vts(p, n_references, f"{cls.name}/corres/reference.sym")
    if sym.size != n_references:
        raise InputError(f"{cls.name}/corres/reference.sym has {sym.size} lines for {n_references} reference points")
    return sym
