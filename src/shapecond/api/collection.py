"""A whole collection matched to one template, its landmarks read from files (``shapes.landmark_files``).

``match_to_template`` is one shape's work (``match`` with the label-matched
landmark pairs, one suggested next landmark), shared by ``match_collection``
(this process, in order) and by batch matching (``shapecond batch --what
match:TEMPLATE``, on joblib or Dask).  The direction is **template → shape**: a
map holds, for every template vertex id, the id of its image on the shape, so
that every map of a collection has the template's length and the error bar is
measured on the template, in units of the template's sqrt(area).

On request (``both_directions``) each shape is also matched to the template
(**shape → template**, ``REVERSE``: the map has the shape's length, its bar is
in the shape's sqrt(area)), and both maps get their **cycle error**
(``cycle_error``): the mean geodesic distance, on the source's samples, between
each sample and its image under the map followed by the opposite one (A → T →
A for the shape → template map), in units of the source's sqrt(area).  The
geodesics are the rows of the samples the matcher itself used
(``matching.sampled.sample_surface``, cached), so a cycle costs no new solve when
the cache is on.  A map that sends its source onto one point of the target and
back scores like a bad map; a faithful pair of maps scores near 0.

Instead of a template, ``match_collection(None, shapes, pairs=...)`` matches the
pairs a list gives (``listed_pairs``, as ``shapecond batch --pairs``): each
pair's first shape takes the template's part (its labels give the order), its
maps are named ``FIRST.to.SECOND`` (``pair_map_name``).
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..errors import InputError, ShapecondError
from ..output import atomic_open
from ..shapes.landmark_files import check_in_range, landmarks_of, pair_by_label, read_landmark_csv
from ..shapes.pairs_list import read_pairs
from ..matching.sampled import sample_surface
from .inputs import load
from .matching import MatchSettings, checked_match
from .matching import match_options as checked_keywords  # match_collection's **match_options are the keywords
from .params import DEFAULT_POINTS

#: Direction of every map of a collection.
DIRECTION = "template to shape"
#: Direction of the second map of a shape matched both ways.
REVERSE = "shape to template"
#: The directions of the maps of a listed pair (``pairs``), the first as the list gives it.
PAIR_DIRECTIONS = ("first to second", "second to first")
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


def pair_map_name(first: str, second: str) -> str:
    """The name of the map of a listed pair (``FIRST.to.SECOND``, from the shapes' map names)."""
    return f"{first}.to.{second}"


def _pair_list(pairs) -> tuple[list[tuple[str, str]], str]:
    """(the pairs as two names each, how messages name the list): ``read_pairs`` of a file, or a list."""
    if isinstance(pairs, (str, os.PathLike)):
        return read_pairs(pairs), str(pairs)
    if isinstance(pairs, Mapping) or not hasattr(pairs, "__iter__"):
        raise InputError(f"pairs must be the path of a pairs list or a list of (first, second) shape names, "
                         f"got {type(pairs).__name__}")
    out = []
    for k, pair in enumerate(pairs, 1):
        if isinstance(pair, (str, bytes)) or not hasattr(pair, "__len__") or len(pair) != 2 or not all(
                isinstance(n, (str, os.PathLike)) for n in pair):
            raise InputError(f"pairs: item {k} is not two shape names: {str(pair)[:60]!r}")
        out.append((os.fspath(pair[0]), os.fspath(pair[1])))
    if not out:
        raise InputError("pairs: no pairs")
    return out, "pairs"


def listed_pairs(pairs, specs, names: dict, both: bool = False) -> list[tuple[str, str]]:
    """(first spec, second spec) of every listed pair, the first matched to the second.

    Parameters
    ----------
    pairs : the path of a pairs list (``shapes.pairs_list.read_pairs``: two shape names a line, ``#``
        comments) or a list of (first, second) names.
    specs : the input shapes; a name in ``pairs`` is a shape's map name (``map_names``), its file name or
        the spec itself.
    names : spec -> map name.
    both : the pairs are matched both ways (a pair listed in either order is then listed twice).

    ``InputError`` for a name that is not one of ``specs``, a shape paired with itself, a pair listed twice
    or an empty list.
    """
    pairs, where = _pair_list(pairs)
    by_name = {}
    for spec in specs:
        for key in (names[spec], Path(spec).name, spec):
            by_name.setdefault(key, spec)
    out, seen = [], set()
    for a, b in pairs:
        missing = next((n for n in (a, b) if n not in by_name), None)
        if missing is not None:
            raise InputError(f"{where}: the pairs list names {missing!r}, which is not one of the input shapes")
        pair = (by_name[a], by_name[b])
        if pair[0] == pair[1]:
            raise InputError(f"{where}: {a} and {b} are one shape, paired with itself")
        if pair in seen or (both and pair[::-1] in seen):
            raise InputError(f"{where}: the pair {a} {b} is listed twice" + (" (in either order: with both "
                             "directions each pair is matched both ways)" if both else ""))
        seen.add(pair)
        out.append(pair)
    return out


def template_landmarks(template, table: dict | None = None) -> dict[str, int]:
    """The template's ``{label: vertex id}`` (``landmarks_of``); ``InputError`` when it has none."""
    found = landmarks_of(template, table)
    if found is None:
        raise InputError(f"{template}: the template has no landmarks (no {Path(str(template)).stem}.lmk beside "
                         "it and no rows in the landmark table)")
    return found[0]


def write_map(path, vertex_map) -> Path:
    """One target id a line (as ``shapecond match -o``), written atomically."""
    with atomic_open(path, "w") as fh:
        np.savetxt(fh, np.asarray(vertex_map, dtype=np.int64), fmt="%d")
    return Path(path)


def label_pairs(reference_lm: dict, shape_lm: tuple | None, reference: str = "the template"):
    """(shared labels, the reference's ids, the shape's ids) of ``pair_by_label``; ``InputError`` for a shape
    without landmarks or with fewer than ``MIN_PAIRS`` labels shared with ``reference``."""
    if shape_lm is None:
        raise InputError("no landmarks for this shape (no NAME.lmk beside it and no rows in the landmark table)")
    labels, ids_r, ids_s = pair_by_label(reference_lm, shape_lm[0])
    if len(labels) < MIN_PAIRS:
        raise InputError(f"{len(labels)} landmark labels shared with {reference} ({shape_lm[1]}); "
                         f"matching needs at least {MIN_PAIRS}")
    return labels, ids_r, ids_s


def _match_fields(template, shape, template_lm: dict, shape_lm: tuple | None, settings: MatchSettings,
                  reverse: bool, view: bool, reference: str):
    """(the row's match fields, the ``MatchResult``) of one direction (``match_to_template``); with ``view``,
    the fields hold the map's compact view under ``"_view"``."""
    labels, ids_t, ids_s = label_pairs(template_lm, shape_lm, reference)
    flags = settings.flags
    loaded = load(shape, largest_component=flags["largest_component"], force=flags["force"])
    if hasattr(loaded, "ids"):
        check_in_range(ids_s, int(loaded.ids.max()) + 1, shape_lm[1])
    pair = (loaded, template, ids_s, ids_t) if reverse else (template, loaded, ids_t, ids_s)
    result = checked_match(*pair, settings)
    bar = result.summary.get("error_bar") or {}
    first = (result.summary.get("suggestions") or [{}])[0]
    fields = {"landmark_pairs": len(labels), "landmark_labels": " ".join(labels), "bar": bar.get("bar"),
              "bar_epsilon": bar.get("epsilon"), "bar_epsilon_hat": bar.get("epsilon_hat"),
              "suggest_source_id": first.get("source_id"), "suggest_image_id": first.get("image_id"),
              "suggest_bar_after": first.get("bar_after")}
    if view:
        from ..viz.mapview import map_view

        fields["_view"] = map_view(result)
    return fields, result


def collection_settings(keywords: dict, caller: str = "match_collection") -> MatchSettings:
    """The keywords of ``match`` for every map of a collection, checked once before any work
    (``matching.match_options``); ``suggest`` defaults to 1 (each row names the next landmark)."""
    return checked_keywords({"suggest": 1, **keywords}, caller)


def match_to_template(template, shape, template_lm: dict, shape_lm: tuple | None, settings: MatchSettings, *,
                      reverse: bool = False, view: bool = False, reference: str = "the template"):
    """(the row's match fields, the map) of ``shape`` matched from ``template`` (module docstring).

    Parameters
    ----------
    template : the template (a path or a loaded ``Geometry``).
    shape : the shape (a path or a loaded ``Geometry``).
    template_lm : the template's ``{label: vertex id}``.
    shape_lm : the shape's (``{label: vertex id}``, where they were read), as ``landmarks_of`` gives them;
        None when it has none.
    settings : the keywords of ``match``, checked (``collection_settings``: ``matcher``, ``n_points``,
        ``seed``...; ``suggest`` 1 unless told otherwise).
    reverse : match the shape to the template instead (``REVERSE``; the suggestion is then a shape vertex).
    view : also compute the map's compact view (``viz.mapview.map_view``: its target drawn coarsely with the
        transfer colours and the error bar's doubt), returned in the fields under ``"_view"`` (not a column).
    reference : how messages name the template.

    Returns
    -------
    (dict, ndarray): ``landmark_pairs``, ``landmark_labels``, ``bar``, ``bar_epsilon``, ``bar_epsilon_hat``,
    ``suggest_source_id``, ``suggest_image_id``, ``suggest_bar_after``; the map (template id -> shape id,
    or shape id -> template id with ``reverse``).  ``InputError`` for a shape without landmarks, with fewer
    than ``MIN_PAIRS`` shared labels, or with an id out of range.
    """
    fields, result = _match_fields(template, shape, template_lm, shape_lm, settings, reverse, view, reference)
    return fields, result.map


def cycle_error(geometry, there, back, landmarks=(), *, n_points: int = DEFAULT_POINTS, backend: str = "heat",
                seed: int = 0, cache: bool = True) -> float | None:
    """Mean geodesic distance between each sample ``x`` of ``geometry`` and ``back[there[x]]``, in units of
    sqrt(area) (of the sample diameter for a point cloud: ``matching.sampled.surface_unit``).

    Parameters
    ----------
    geometry : the loaded source shape (``Geometry``).
    there : its map to another shape (one target id per source id, -1: dropped).
    back : the other shape's map to this one (one source id per target id, -1: dropped).
    landmarks : internal vertex indices sampled first (as the matcher sampled them, so that the rows are
        the cached ones of ``matching.sampled.sample_surface``).
    n_points, backend, seed, cache : of the samples (those of ``match``).

    Returns
    -------
    float, or None when no sample makes the round trip (every one dropped on the way).
    """
    surf = sample_surface(geometry, min(int(n_points), geometry.n_vertices), backend, seed, landmarks, cache)
    there, back = np.asarray(there, dtype=np.int64), np.asarray(back, dtype=np.int64)
    mid = there[geometry.ids[surf.samples]]
    ok = (mid >= 0) & (mid < back.size)
    end = np.full(mid.shape, -1, dtype=np.int64)
    end[ok] = back[mid[ok]]
    lookup = np.full(int(geometry.ids.max()) + 1, -1, dtype=np.int64)
    lookup[geometry.ids] = np.arange(geometry.n_vertices)
    ok &= (end >= 0) & (end < lookup.size)
    ok[ok] = lookup[end[ok]] >= 0
    if not ok.any():
        return None
    rows = surf.rows[np.flatnonzero(ok), lookup[end[ok]]].astype(np.float64)
    return float(rows.mean() / surf.unit)


def _cycle(result, back, opts) -> float | None:
    """``cycle_error`` of a ``MatchResult`` followed by the map ``back``, on the samples ``match`` used
    (``opts``: its ``MatchOptions``)."""
    source, _, landmarks, _ = result.drawing
    return cycle_error(source, result.map, back, landmarks, n_points=opts.n_points, backend=opts.backend,
                       seed=opts.seed, cache=opts.cache)


def match_both_ways(template, shape, template_lm: dict, shape_lm: tuple | None, settings: MatchSettings, *,
                    view: bool = False, reference: str = "the template"):
    """[(fields, map) template -> shape, (fields, map | None) shape -> template], each with ``cycle_error``.

    ``match_to_template`` in both directions (``settings``, ``view`` and ``reference`` as there, for each map);
    ``InputError`` as it when the first direction fails.  When only the second fails, its fields are
    ``{"error": the one-line message}`` and both cycle errors None.
    """
    fields, result = _match_fields(template, shape, template_lm, shape_lm, settings, False, view, reference)
    try:
        back_fields, back = _match_fields(template, shape, template_lm, shape_lm, settings, True, view, reference)
    except ShapecondError as exc:
        return [({**fields, "cycle_error": None}, result.map), ({"error": _one_line(exc)}, None)]
    opts = settings.options
    return [({**fields, "cycle_error": _cycle(result, back.map, opts)}, result.map),
            ({**back_fields, "cycle_error": _cycle(back, result.map, opts)}, back.map)]


def _one_line(exc) -> str:
    return str(exc).splitlines()[0] if str(exc) else exc.__class__.__name__


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


def reverse_name(name: str) -> str:
    """The name of a shape's map to the template (``NAME.to_template``), beside ``NAME``, its map from it."""
    return f"{name}.to_template"


def _shape_rows(reference, shape, heads: list[dict], found, settings: MatchSettings) -> list[tuple[dict, object]]:
    """[(row, map or None)] of one task of ``match_collection``: ``reference`` (a loaded shape, its ``{label:
    vertex id}``, how messages name it; or the exception that made it unusable) matched to ``shape``, one
    direction or both (one head each)."""
    t0 = time.perf_counter()
    try:
        if isinstance(reference, Exception):
            raise reference
        if found is None or isinstance(found, Exception):
            raise found or InputError("no landmarks for this shape (no NAME.lmk beside it and no rows in the "
                                      "landmark table)")
        loaded, reference_lm, words = reference
        done = (match_both_ways(loaded, shape, reference_lm, found, settings, reference=words) if len(heads) == 2
                else [match_to_template(loaded, shape, reference_lm, found, settings, reference=words)])
    except ShapecondError as exc:
        done = [({"error": _one_line(exc)}, None)] * len(heads)
    seconds = time.perf_counter() - t0
    out = []
    for head, (fields, vertex_map) in zip(heads, done):
        row = {**head, **fields}
        if "error" not in fields:
            row["annotate_more"] = fields["bar"] is not None and fields["bar"] > ANNOTATE_MORE
        out.append(({**row, "seconds": seconds, "error": fields.get("error")}, vertex_map))
    return out


def _landmarks_or_error(shape, table):
    try:
        return landmarks_of(shape, table)
    except ShapecondError as exc:
        return exc


def _template_tasks(template, shapes, names: dict, table, both: bool, flags: dict):
    """(reference, shape, heads) of every shape matched from ``template``; ``InputError`` for an unusable
    template."""
    loaded = load(template, **flags)
    template_lm = template_landmarks(template, table)
    if not hasattr(loaded, "ids"):
        raise InputError(f"{template}: the template must be a mesh or point cloud, not a distance matrix")
    check_in_range(template_lm.values(), int(loaded.ids.max()) + 1, f"the template {template}")
    reference, tname = (loaded, template_lm, "the template"), Path(str(template)).stem
    for shape in shapes:
        name = names[shape]
        heads = [{"shape": name, "map": name, "file": shape, "direction": DIRECTION, "source": tname,
                  "target": name}]
        if both:
            heads.append({"shape": name, "map": reverse_name(name), "file": shape, "direction": REVERSE,
                          "source": name, "target": tname})
        yield reference, shape, heads


def _first_shape(spec: str, name: str, table, flags: dict):
    """(loaded, ``{label: vertex id}``, how messages name it) of a pair's first shape, or the ``InputError``
    saying why it cannot be used."""
    words = f"the pair's first shape {name}"
    try:
        found = landmarks_of(spec, table)
        if found is None:
            raise InputError("no landmarks (no NAME.lmk beside it and no rows in the landmark table)")
        loaded = load(spec, **flags)
        if not hasattr(loaded, "ids"):
            raise InputError("a distance matrix cannot be matched")
        check_in_range(found[0].values(), int(loaded.ids.max()) + 1, found[1])
    except ShapecondError as exc:
        return InputError(f"{words}: {_one_line(exc)}")
    return loaded, found[0], words


def _pair_tasks(pairs, shapes, names: dict, table, both: bool, flags: dict):
    """(reference, shape, heads) of every listed pair (``listed_pairs``), each first shape loaded once."""
    firsts = {}
    for first, second in listed_pairs(pairs, shapes, names, both):
        if first not in firsts:
            firsts[first] = _first_shape(first, names[first], table, flags)
        ends = (names[first], names[second])
        heads = [{"shape": ends[1], "map": pair_map_name(*ends), "file": second, "direction": PAIR_DIRECTIONS[0],
                  "source": ends[0], "target": ends[1]}]
        if both:
            heads.append({"shape": ends[1], "map": pair_map_name(*ends[::-1]), "file": second,
                          "direction": PAIR_DIRECTIONS[1], "source": ends[1], "target": ends[0]})
        yield firsts[first], second, heads


def _checked_call(template, landmarks, pairs, both_directions) -> dict | None:
    """``match_collection``'s landmark table (``read_landmark_csv`` of a path, the dict given, or None),
    after refusing a bad ``landmarks``, ``both_directions`` or template/pairs combination."""
    table = read_landmark_csv(landmarks) if isinstance(landmarks, (str, os.PathLike)) else landmarks
    if table is not None and not isinstance(table, dict):
        raise InputError("landmarks must be None, the path of a CSV file or a dict {shape: {label: vertex}}")
    if not isinstance(both_directions, bool):
        raise InputError(f"both_directions must be True or False, got {both_directions!r}")
    if (template is None) == (pairs is None):
        raise InputError("give a template, or pairs=... without a template (template=None), not both"
                         if pairs is not None else "give a template, or pairs=... with template=None")
    return table


def match_collection(template, shapes, landmarks=None, *, pairs=None, maps_dir=None, both_directions: bool = False,
                     **match_options):
    """Match ``template`` to every shape of ``shapes`` with the landmarks their files name (module docstring),
    or match the pairs ``pairs`` lists.

    Parameters
    ----------
    template : path of the template shape; its landmarks in ``NAME.lmk`` beside it or in ``landmarks``.
        None with ``pairs``.
    shapes : paths of the shapes (each with ``NAME.lmk`` beside it, or rows in ``landmarks``).
    landmarks : None (the ``.lmk`` files), the path of a CSV file ``shape,label,vertex``, or a dict
        ``{shape name: {label: vertex id}}``.  Points are paired by label (``shapes.landmark_files``).
    pairs : instead of a template, the pairs of ``shapes`` to match, the first of each to the second (the
        labels in the first's order): the path of a pairs list (two shape names a line, ``#`` comments, as
        ``shapecond batch --pairs``) or a list of (first, second) names; a name is a shape's name (its file
        name without suffix), its file name or its path as given in ``shapes``.  Maps are named
        ``FIRST.to.SECOND`` (``pair_map_name``), with the directions of ``PAIR_DIRECTIONS``.
    maps_dir : a folder to write each map to (``NAME.txt``, atomically; read back on access); None keeps
        the maps in memory.
    both_directions : also match each shape to the template (``REVERSE``, its map named
        ``NAME.to_template``, ``reverse_name``), or each pair's second shape to its first, and give both
        maps their ``cycle_error``.
    **match_options : keywords of ``match`` (``matcher``, ``n_points``, ``dense``, ``seed``...; ``suggest``
        defaults to 1), checked before any work (``collection_settings``).

    Returns
    -------
    (table, maps): ``table`` a pandas DataFrame when pandas can be imported, else a list of dicts, one
    row per shape (or pair) in order (two with ``both_directions``, template to shape first): ``shape``
    (its name; a pair's second shape), ``map`` (the map's name), ``file`` (the shape's), ``direction``,
    ``source`` and ``target`` (the names of the map's two shapes: the map gives the target's vertex id of
    each source vertex id), the fields of ``match_to_template`` (with ``both_directions`` also
    ``cycle_error``: ``match_both_ways``), ``annotate_more`` (bar > ``ANNOTATE_MORE``), ``seconds`` (the
    task's, both directions together) and ``error`` (the one-line message of a map that failed; the others
    are then missing).  ``maps`` a ``Maps``: map name -> map, read lazily.  ``InputError`` when the
    template, its landmarks or the landmark CSV file cannot be read or a template id is out of range, and
    for a template given with ``pairs`` (or neither) or a bad pairs list (``listed_pairs``: an unknown name,
    a shape paired with itself, a pair listed twice, no pairs); a shape's own problem (no landmarks, a
    broken ``.lmk``, fewer than ``MIN_PAIRS`` shared labels, an id out of range, a file that does not
    load; a pair's first shape with such a problem) is its row's error.

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
    >>> shapes = [folder / "template.off", folder / "cat.off"]
    >>> list(sc.match_collection(None, shapes, pairs=[("cat", "template")], n_points=40)[1])
    ['cat.to.template']
    """
    table = _checked_call(template, landmarks, pairs, both_directions)
    settings = collection_settings(match_options)
    shapes = [str(s) for s in shapes]
    names = dict(zip(shapes, map_names(shapes)))
    flags = {k: settings.flags[k] for k in ("largest_component", "force")}
    tasks = (_template_tasks(template, shapes, names, table, both_directions, flags) if pairs is None
             else _pair_tasks(pairs, shapes, names, table, both_directions, flags))
    tasks = list(tasks)  # every input problem of the call before any work
    maps, rows, found = Maps(maps_dir), [], {}
    for reference, shape, heads in tasks:
        if shape not in found:
            found[shape] = _landmarks_or_error(shape, table)
        for row, vertex_map in _shape_rows(reference, shape, heads, found[shape], settings):
            if vertex_map is not None:
                maps.add(row["map"], vertex_map)
            rows.append(row)
    return _table(rows), maps


__all__ = ["ANNOTATE_MORE", "DIRECTION", "PAIR_DIRECTIONS", "REVERSE", "Maps", "collection_settings", "cycle_error",
           "listed_pairs", "match_both_ways", "match_collection", "match_to_template", "pair_map_name", "reverse_name"]
