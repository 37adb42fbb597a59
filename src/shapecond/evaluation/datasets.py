"""Class folders of an evaluation: which shapes, which null shape, and which ground truth.

Two layouts are read:

``"shared"`` (TOSCA): a class folder holds mesh files (``.off``, ``.obj``,
    ``.ply``) with one vertex count and vertex order, so the ground truth is the
    identity on vertex ids.
``"remeshed"`` (the remeshed FAUST and SCAPE releases, SHREC'19, SMAL_r,
    DT4D-H): a class folder holds ``shapes/NAME.off`` (any mesh format read
    here) and ``corres/NAME.vts`` (``shapes.vts``): every shape has its own
    triangulation, and shapes ``a``, ``b`` correspond at the reference points
    ``(vts_a[j], vts_b[j])``.  A folder is read this way when it has a
    ``corres`` sub-folder; a dataset folder that is itself such a class (the
    FAUST_r release) is one class named after the folder.  An optional
    ``corres/reference.sym`` (line ``j``: the 1-based reference point mirroring
    ``j``) lets the evaluation count left–right flips.

The null shape of a class is the one whose name ends with the lowest number
(``cat0``, ``tr_reg_080``), else the first by name.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..shapes.formats import check_file, off_header

MESH_SUFFIXES = (".off", ".obj", ".ply")
LAYOUTS = ("shared", "remeshed")


@dataclass(frozen=True)
class ClassFolder:
    """One class: its shapes (null shape first) and how their ground truth is given.

    Attributes
    ----------
    name : the class name (folder name).
    shapes : mesh paths, null shape first.
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
        return Path(shape).parent.parent / "corres" / f"{Path(shape).stem}.vts"

    def symmetry_path(self) -> Path | None:
        """``corres/reference.sym`` of a remeshed class, when there is one."""
        p = Path(self.null).parent.parent / "corres" / "reference.sym"
        return p if self.layout == "remeshed" and p.is_file() else None


def _mesh_files(folder: Path) -> list[Path]:
    return [p for p in folder.iterdir() if p.suffix.lower() in MESH_SUFFIXES and p.is_file()]


def _number_order(p: Path):
    m = re.search(r"(\d+)$", p.stem)
    return (int(m.group(1)) if m else math.inf, p.stem)


def read_class(folder) -> ClassFolder:
    """The class in ``folder`` (module docstring); ``InputError`` when it is not one."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: not a folder")
    remeshed = (folder / "corres").is_dir()
    shape_dir = folder / "shapes" if remeshed else folder
    if remeshed and not shape_dir.is_dir():
        raise InputError(f"{folder}: a remeshed class needs a shapes/ folder beside corres/")
    files = sorted(_mesh_files(shape_dir), key=_number_order)
    if len(files) < 2:
        raise InputError(f"{shape_dir}: a class needs at least two shapes, found {len(files)}")
    if remeshed:
        missing = [p.stem for p in files if not (folder / "corres" / f"{p.stem}.vts").is_file()]
        if missing:
            raise InputError(f"{folder.name}: no corres/{missing[0]}.vts for shapes/{missing[0]} "
                             "(every shape of a remeshed class needs its .vts ground truth)")
    return ClassFolder(folder.name, tuple(files), "remeshed" if remeshed else "shared")


def _is_class(p: Path) -> bool:
    return p.is_dir() and ((p / "corres").is_dir() or any(q.suffix.lower() in MESH_SUFFIXES for q in p.iterdir()))


def find_classes(dataset_dir, classes=None) -> dict[str, ClassFolder]:
    """Class name -> ClassFolder for the class folders of ``dataset_dir``; ``classes`` restricts."""
    root = Path(dataset_dir)
    if not root.is_dir():
        raise InputError(f"{root}: not a folder")
    if (root / "corres").is_dir():
        found = {root.name: read_class(root)}
    else:
        found = {p.name: read_class(p) for p in sorted(root.iterdir()) if _is_class(p)}
    if classes:
        missing = [c for c in classes if c not in found]
        if missing:
            raise InputError(f"class {missing[0]!r} not found in {root} (found: {', '.join(found) or 'none'})")
        found = {c: found[c] for c in classes}
    if not found:
        raise InputError(f"{root}: no class folders with meshes")
    return found


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
    ``.vts`` must be readable with ids in range of its mesh's header count, and
    all of them must have the same number of reference points.
    """
    from ..shapes.vts import read_vts

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
    if len(set(refs.values())) > 1:
        raise InputError(f"class {cls.name}: the .vts files have unequal reference counts "
                         f"({', '.join(f'{k}: {v}' for k, v in refs.items())})")


def reference_symmetry(cls: ClassFolder, n_references: int) -> np.ndarray | None:
    """0-based mirror reference point of every reference point (``corres/reference.sym``), or None."""
    from ..shapes.vts import read_vts

    p = cls.symmetry_path()
    if p is None:
        return None
    sym = read_vts(p, n_references, f"{cls.name}/corres/reference.sym")
    if sym.size != n_references:
        raise InputError(f"{cls.name}/corres/reference.sym has {sym.size} lines for {n_references} reference points")
    return sym
