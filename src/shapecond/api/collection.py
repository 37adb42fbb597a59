"""A whole collection matched to one template, its landmarks read from files (``shapes.landmark_files``).

``match_to_template`` is one shape's work (``match`` with the label-matched
landmark pairs, one suggested next landmark), shared by ``match_collection``
(this process, in order) and by batch matching (``shapecond batch --what
match:TEMPLATE``, on joblib or Dask).  The direction is **template → shape**: a
map holds, for every template vertex id, the id of its image on the shape, so
that every map of a collection has the template's length and the error bar is
measured on the template, in units of the template's sqrt(area).
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..errors import InputError, ShapecondError
from ..shapes.landmark_files import check_in_range, landmarks_of, pair_by_label, read_landmark_csv
from .inputs import load
from .matching import match

#: Direction of every map of a collection.
DIRECTION = "template to shape"
#: Fewest shared labels a shape needs to be matched.
MIN_PAIRS = 3
#: A bar above this (sqrt(area) of the template) says "annotate more": the mean geodesic error of
#: 0.05 sqrt(area) is where the shape-correspondence literature counts a map as failed.
ANNOTATE_MORE = 0.05


def map_names(shapes) -> list[str]:
    """The name of each shape's map (``NAME`` of ``maps/NAME.txt``): its file name without suffix.

    ``InputError`` when two shapes share a name (their maps would overwrite each other).
    """
    names, seen = [], {}
    for s in shapes:
        s = str(s)
        name = s.replace(":", "_").replace("=", "_").replace(",", "_") if s.startswith("demo:") else Path(s).stem
        if name in seen:
            raise InputError(f"two shapes are named {name!r} ({seen[name]} and {s}): their maps would collide; "
                             "rename one")
        seen[name] = s
        names.append(name)
    return names


def template_landmarks(template, table: dict | None = None) -> dict[str, int]:
    """The template's ``{label: vertex id}`` (``landmarks_of``); ``InputError`` when it has none."""
    found = landmarks_of(template, table)
    if found is None:
        raise InputError(f"{template}: the template has no landmarks (no {Path(str(template)).stem}.lmk beside "
                         "it and no rows in the landmark table)")
    return found[0]


def write_map(path, vertex_map) -> Path:
    """One target id a line (as ``shapecond match -o``), written atomically."""
    from ..output import atomic_open

    with atomic_open(path, "w") as fh:
        np.savetxt(fh, np.asarray(vertex_map, dtype=np.int64), fmt="%d")
    return Path(path)


def match_to_template(template, shape, template_lm: dict, shape_lm: tuple | None, **match_options):
    """(the row's match fields, the map) of ``shape`` matched from ``template`` (module docstring).

    Parameters
    ----------
    template : the template (a path or a loaded ``Geometry``).
    shape : the shape (a path or a loaded ``Geometry``).
    template_lm : the template's ``{label: vertex id}``.
    shape_lm : the shape's (``{label: vertex id}``, where they were read), as ``landmarks_of`` gives them;
        None when it has none.
    **match_options : keywords of ``match`` (``matcher``, ``n_points``, ``seed``...); ``suggest`` defaults to 1.

    Returns
    -------
    (dict, ndarray): ``landmark_pairs``, ``landmark_labels``, ``bar``, ``bar_epsilon``, ``bar_epsilon_hat``,
    ``suggest_source_id``, ``suggest_image_id``, ``suggest_bar_after``; the map (template id -> shape id).
    ``InputError`` for a shape without landmarks, with fewer than ``MIN_PAIRS`` shared labels, or with an id
    out of range.
    """
    if shape_lm is None:
        raise InputError("no landmarks for this shape (no NAME.lmk beside it and no rows in the landmark table)")
    found = shape_lm
    labels, ids_t, ids_s = pair_by_label(template_lm, found[0])
    if len(labels) < MIN_PAIRS:
        raise InputError(f"{len(labels)} landmark labels shared with the template ({found[1]}); "
                         f"matching needs at least {MIN_PAIRS}")
    flags = {k: match_options[k] for k in ("largest_component", "force") if k in match_options}
    loaded = load(shape, **flags)
    if hasattr(loaded, "ids"):
        check_in_range(ids_s, int(loaded.ids.max()) + 1, found[1])
    result = match(template, loaded, ids_t, ids_s, **{"suggest": 1, **match_options})
    bar = result.summary.get("error_bar") or {}
    first = (result.summary.get("suggestions") or [{}])[0]
    fields = {"landmark_pairs": len(labels), "landmark_labels": " ".join(labels), "bar": bar.get("bar"),
              "bar_epsilon": bar.get("epsilon"), "bar_epsilon_hat": bar.get("epsilon_hat"),
              "suggest_source_id": first.get("source_id"), "suggest_image_id": first.get("image_id"),
              "suggest_bar_after": first.get("bar_after")}
    return fields, result.map


class Maps(Mapping):
    """The maps of a collection by shape name, each read on first access (a file) or kept (in memory).

    ``maps[name]`` is the map (an int64 array: shape id per template id); ``maps.path(name)`` its file
    (None when kept in memory).
    """

    def __init__(self, folder=None):
        self.folder = None if folder is None else Path(folder)
        self._kept: dict[str, np.ndarray] = {}
        self._names: list[str] = []

    def add(self, name: str, vertex_map) -> None:
        """Keep ``vertex_map`` (or write it to ``folder/NAME.txt``, atomically)."""
        if self.folder is None:
            self._kept[name] = np.asarray(vertex_map, dtype=np.int64)
        else:
            write_map(self.folder / f"{name}.txt", vertex_map)
        self._names.append(name)

    def path(self, name: str) -> Path | None:
        if name not in self._names:
            raise KeyError(name)
        return None if self.folder is None else self.folder / f"{name}.txt"

    def __getitem__(self, name: str) -> np.ndarray:
        path = self.path(name)
        if path is None:
            return self._kept[name]
        return np.loadtxt(path, dtype=np.int64, ndmin=1)

    def __iter__(self):
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)

    def __repr__(self) -> str:
        return f"Maps({len(self)} maps" + (f" in {self.folder})" if self.folder else ", in memory)")


def _table(rows: list[dict]):
    try:
        import pandas as pd
    except ImportError:
        return rows
    return pd.DataFrame(rows)


def match_collection(template, shapes, landmarks=None, *, maps_dir=None, **match_options):
    """Match ``template`` to every shape of ``shapes`` with the landmarks their files name (module docstring).

    Parameters
    ----------
    template : path of the template shape; its landmarks in ``NAME.lmk`` beside it or in ``landmarks``.
    shapes : paths of the shapes (each with ``NAME.lmk`` beside it, or rows in ``landmarks``).
    landmarks : None (the ``.lmk`` files), the path of a CSV file ``shape,label,vertex``, or a dict
        ``{shape name: {label: vertex id}}``.  Points are paired by label (``shapes.landmark_files``).
    maps_dir : a folder to write each map to (``NAME.txt``, atomically; read back on access); None keeps
        the maps in memory.
    **match_options : keywords of ``match`` (``matcher``, ``n_points``, ``dense``, ``seed``...).

    Returns
    -------
    (table, maps): ``table`` a pandas DataFrame when pandas can be imported, else a list of dicts, one
    row per shape in order: ``shape`` (map name), ``file``, ``direction``, the fields of
    ``match_to_template``, ``annotate_more`` (bar > ``ANNOTATE_MORE``), ``seconds`` and ``error`` (the
    one-line message of a shape that failed; the others are then missing).  ``maps`` a ``Maps``: name ->
    map, read lazily.  ``InputError`` when the template, its landmarks or the landmark CSV file cannot be
    read or a template id is out of range; a shape's own problem (no landmarks, a broken ``.lmk``, fewer
    than ``MIN_PAIRS`` shared labels, an id out of range, a file that does not load) is its row's error.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import shapecond as sc
    >>> from shapecond.shapes.io import write_mesh
    >>> folder, g = pathlib.Path(tempfile.mkdtemp()), sc.load("demo:animal:resolution=0.08")   # 942 vertices
    >>> for name in ("template", "cat"):
    ...     write_mesh(folder / f"{name}.off", g.vertices, g.faces)
    ...     _ = (folder / f"{name}.lmk").write_text("nose 0\\ntail 100\\npaw 200\\n")
    >>> table, maps = sc.match_collection(folder / "template.off", [folder / "cat.off"], n_points=40)
    >>> table[0]["landmark_pairs"] if isinstance(table, list) else int(table["landmark_pairs"][0])
    3
    >>> maps["cat"].shape == (g.n_vertices,)
    True
    """
    table = read_landmark_csv(landmarks) if isinstance(landmarks, (str, os.PathLike)) else landmarks
    if table is not None and not isinstance(table, dict):
        raise InputError("landmarks must be None, the path of a CSV file or a dict {shape: {label: vertex}}")
    shapes = [str(s) for s in shapes]
    names = map_names(shapes)
    flags = {k: match_options[k] for k in ("largest_component", "force") if k in match_options}
    loaded = load(template, **flags)
    template_lm = template_landmarks(template, table)
    check_in_range(template_lm.values(), int(loaded.ids.max()) + 1, f"the template {template}")
    maps, rows = Maps(maps_dir), []
    for name, shape in zip(names, shapes):
        row = {"shape": name, "file": shape, "direction": DIRECTION}
        t0 = time.perf_counter()
        try:
            fields, vertex_map = match_to_template(loaded, shape, template_lm, landmarks_of(shape, table),
                                                   **match_options)
            maps.add(name, vertex_map)
            row.update(fields, annotate_more=fields["bar"] is not None and fields["bar"] > ANNOTATE_MORE)
        except ShapecondError as exc:
            row["error"] = str(exc).splitlines()[0] if str(exc) else exc.__class__.__name__
        row["seconds"] = time.perf_counter() - t0
        rows.append({**row, "error": row.get("error")})
    return _table(rows), maps


__all__ = ["ANNOTATE_MORE", "DIRECTION", "Maps", "match_collection", "match_to_template"]
