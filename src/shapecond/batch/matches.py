"""A collection matched to a template (``--what match:TEMPLATE``) or in listed pairs: landmarks, parameters, maps.

Before any row is computed, this process reads the template's landmarks and
loads the template (a template without landmarks, a bad landmark file of the
template, an id out of its range or a template that does not load stop the
batch: one line, exit status 2), and reads every shape's landmarks
(``shapes.landmark_files``: ``NAME.lmk`` beside the shape or the rows of
``--landmarks FILE``).  A shape whose landmark file is broken, or that has
none, becomes an error row; the batch goes on.  The label-matched pairs enter
the row's ``params``, so that ``--resume`` recomputes a shape whose landmarks
were changed, and only it.

With ``--pairs FILE`` (``--what match``) the shapes are matched as the file
lists them (``api.collection.listed_pairs``: two shape names a line, the
first matched to the second); a name that is not one of the inputs, a pair
listed twice, an empty list or a shape paired with itself stops the batch
before anything is written.  Each line is one task whose row's ``file`` is
the second shape; the first takes the template's part (its landmarks give the
label order) and its path and content hash enter the row's ``params``.

The workers match (``api.collection.match_to_template``, reference → shape;
with ``--both-directions`` ``match_both_ways``: both maps in one task, so that
each gets its cycle error without a geodesic on this side) and return the
maps with the row; this process writes each map (``map_name``) in ``maps/``
beside the table, atomically (``output.atomic_open``), **before** appending
its row, so that a row in the table always has its whole map on disk, and a
batch killed at any moment leaves no torn map.  A task's rows that are
already in the table (a kill between the two rows of a shape) are not
appended again.

Each map also gets its compact view (``viz.mapview.map_view``: the map's
target drawn coarsely with the transfer colours and the error bar's doubt),
computed by the worker beside the map and written before it, atomically, to
``views/NAME.json`` with the key of its row (content hash and parameters), so
that ``--resume`` keeps it and ``report.html`` shows a view only with the row
it was computed for (``read_view``).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

from .. import api
from ..api.collection import (DIRECTION, PAIR_DIRECTIONS, REVERSE, listed_pairs, map_names, pair_map_name,
                              reverse_name, template_landmarks, write_map)
from ..errors import InputError
from ..output import write_text
from ..shapes.formats import read_text
from ..shapes.landmark_files import check_in_range, landmarks_of, pair_by_label, read_landmark_csv
from .rows import parse_what

#: The folder of the maps, beside the table.
MAPS_FOLDER = "maps"
#: The folder of the maps' compact views (``viz.mapview``), beside the table.
VIEWS_FOLDER = "views"


#: The columns that belong to one map (``api.collection.match_to_template``'s fields and the cycle error).
MAP_FIELDS = ("landmark_pairs", "landmark_labels", "bar", "bar_epsilon", "bar_epsilon_hat", "suggest_source_id",
              "suggest_image_id", "suggest_bar_after", "cycle_error", "map_file")


@dataclass(frozen=True)
class MatchJob:
    """What a worker needs to match one shape (``rows.shape_row``'s ``match``).

    Attributes
    ----------
    reference : the template, or the first shape of a listed pair: the first map's source.
    reference_lm : its ``{label: vertex id}`` (their order is the pairs' order).
    shape_lm : the shape's ``landmarks_of`` result (None: none).
    directions : the ``match_direction`` of each map, reference → shape first.
    template : the ``match_template`` column (None with ``--pairs``).
    reference_words : how messages name the reference.
    """

    reference: str
    reference_lm: dict
    shape_lm: tuple | None
    directions: tuple
    template: str | None = None
    reference_words: str = "the template"


@dataclass
class MatchPlan:
    """What matching needs besides the batch's options; inactive (``template`` and ``pairs`` None) without it.

    A *unit* is one task: (shape, reference), the reference the template or the first shape of a pair.
    """

    template: str | None = None
    template_lm: dict = field(default_factory=dict)
    shape_lm: dict = field(default_factory=dict)     # spec -> landmarks_of result (or None)
    errors: dict = field(default_factory=dict)       # spec -> why its landmarks cannot be read
    names: dict = field(default_factory=dict)        # spec -> map name
    maps_dir: Path | None = None
    pairs: list | None = None                        # --pairs: [(first spec, second spec)]
    both: bool = False                               # --both-directions

    @property
    def active(self) -> bool:
        return self.template is not None or self.pairs is not None

    @property
    def directions(self) -> tuple:
        """The ``match_direction`` of each row of a unit."""
        pair = PAIR_DIRECTIONS if self.pairs is not None else (DIRECTION, REVERSE)
        return pair if self.both else pair[:1]

    def with_template(self, options: dict) -> dict:
        """``options`` with ``match:TEMPLATE`` naming the template's file (``template_path``: a template
        given by its name among the inputs), as the table's key and the rows' params record it."""
        if self.template is None:
            return options
        return {**options, "what": replace(parse_what(options["what"]), match=self.template).items()}

    def units(self, specs) -> list[tuple]:
        """(shape, reference) of every task: each shape with the template, each listed pair, or each shape."""
        if self.pairs is not None:
            return [(second, first) for first, second in self.pairs]
        return [(spec, self.template) for spec in specs]

    def _reference_lm(self, reference) -> dict:
        if self.pairs is None:
            return self.template_lm
        found = self.shape_lm.get(reference)
        return {} if found is None else found[0]

    def params(self, params: str, unit, hashes: dict) -> list[str]:
        """The ``params`` of each row of ``unit``: the batch's, plus its label-matched landmark pairs (and, with
        ``--pairs``, the first shape's path and content hash; with both directions, the row's direction)."""
        if not self.active:
            return [params]
        spec, reference = unit
        found = self.shape_lm.get(spec)
        pairs = (None if found is None else
                 [list(p) for p in zip(*pair_by_label(self._reference_lm(reference), found[0]))])
        one = {**json.loads(params), "pairs": pairs}
        if self.pairs is not None:
            one.update(reference=reference, reference_hash=hashes.get(reference))
        rows = [one] if not self.both else [{**one, "direction": d} for d in self.directions]
        return [json.dumps(r, sort_keys=True, separators=(",", ":")) for r in rows]

    def unit_error(self, unit, unreadable: dict) -> str | None:
        """Why ``unit`` cannot be sent to a worker (its shape, or its pair's first shape, is unreadable)."""
        spec, reference = unit
        if spec in unreadable:
            return unreadable[spec]
        if self.pairs is not None and reference in unreadable:
            return f"the pair's first shape {self.names[reference]}: {unreadable[reference]}"
        return None

    def task_kwargs(self, unit) -> dict:
        """The keywords of ``rows.shape_row`` for ``unit``."""
        if not self.active:
            return {}
        spec, reference = unit
        words = "the template" if self.pairs is None else f"the pair's first shape {self.names[reference]}"
        return {"match": MatchJob(reference, self._reference_lm(reference), self.shape_lm.get(spec),
                                  self.directions, self.template, words)}

    def map_name(self, unit, k: int) -> str:
        """The name of the ``k``-th map of ``unit`` (``maps/NAME.txt``): ``NAME`` with one direction to a
        template (as before there were two), ``NAME.to_template`` for the way back, ``FIRST.to.SECOND``
        (and ``SECOND.to.FIRST``) for a listed pair."""
        spec, reference = unit
        if self.pairs is None:
            return self.names[spec] if k == 0 else reverse_name(self.names[spec])
        ends = (self.names[reference], self.names[spec])
        return pair_map_name(*(ends if k == 0 else ends[::-1]))

    def rows_of(self, row: dict, unit, params: list[str]) -> list[dict]:
        """The rows of one task's result ``row`` (one per direction), each map written first (atomically)."""
        if not self.active:
            return [row]
        rows = [row]
        if self.both:
            back = row.pop("_reverse", None)
            if back is None:  # the task failed before its second map: the same error
                back = {"match_direction": self.directions[1], "match_source": unit[0], "match_target": unit[1]}
            rows.append({**row, **dict.fromkeys(MAP_FIELDS), "_map": None, "_view": None, **back,
                         "params": params[1]})
        for k, r in enumerate(rows):
            self._write_map(r, self.map_name(unit, k))
        return rows

    def _write_map(self, row: dict, name: str) -> None:
        """Write a row's view (``"_view"``) and map (``"_map"``), both removed from the row, and name the map's
        file in the row."""
        vertex_map, view = row.pop("_map", None), row.pop("_view", None)
        if vertex_map is None:
            row["map_file"] = None
            return
        path = self.maps_dir / f"{name}.txt"
        if view is not None:
            write_view(view_path(path), view, row)
        write_map(path, vertex_map)
        row["map_file"] = str(path)


def view_path(map_file) -> Path:
    """Where the compact view of the map ``map_file`` (``maps/NAME.txt``) lies: ``views/NAME.json``."""
    map_file = Path(map_file)
    return map_file.parent.parent / VIEWS_FOLDER / f"{map_file.stem}.json"


def _view_key(row: dict) -> list:
    """What a view belongs to: its row's content hash and parameters (the map is a function of them)."""
    return [row.get("content_hash"), row.get("params")]


def write_view(path, view: dict, row: dict) -> None:
    """Write the view payload ``view`` of ``row``'s map to ``path`` (atomically), with the row's key."""
    from ..viz.mapview import payload_json

    write_text(path, payload_json({**view, "key": _view_key(row)}))


def read_view(row: dict) -> dict | None:
    """The view of ``row``'s map, or None: no map, no view file (a batch from before views), an unreadable
    one, or one written for another row (other landmarks, shape or options since)."""
    if not row.get("map_file"):
        return None
    try:
        view = json.loads(read_text(view_path(row["map_file"])))
    except (InputError, ValueError):
        return None
    from ..viz.mapview import VIEW_FORMAT

    ok = isinstance(view, dict) and view.get("format") == VIEW_FORMAT and view.get("key") == _view_key(row)
    return view if ok else None


def _shape_landmarks(specs, table) -> tuple[dict, dict]:
    """(spec -> ``landmarks_of``, spec -> why not): a broken file, or no landmarks, is that shape's error."""
    found, errors = {}, {}
    for spec in specs:
        try:
            found[spec] = None if spec.startswith("demo:") else landmarks_of(spec, table)
        except InputError as exc:
            errors[spec] = str(exc).splitlines()[0]
            continue
        if found[spec] is None:
            errors[spec] = ("no landmarks for this shape (no NAME.lmk beside it and no rows in the landmark "
                            "table)")
    return found, errors


def plan_matching(specs, options: dict, out) -> MatchPlan:
    """The ``MatchPlan`` of a batch (module docstring); ``InputError`` for an unusable template or pairs list."""
    what = parse_what(options["what"])
    if not what.matching:
        return MatchPlan()
    names = dict(zip(specs, map_names(specs)))
    both, maps_dir = bool(options["both_directions"]), Path(out).absolute().parent / MAPS_FOLDER
    if what.pairs:
        pairs = listed_pairs(options["pairs"], specs, names, both)
        table = read_landmark_csv(options["landmark_table"]) if options.get("landmark_table") else None
        found, errors = _shape_landmarks(list(dict.fromkeys(s for p in pairs for s in p)), table)
        return MatchPlan(None, {}, found, errors, names, maps_dir, pairs, both)
    table = read_landmark_csv(options["landmark_table"]) if options.get("landmark_table") else None
    template = template_path(what.match, names)
    loaded = api.load(template, largest_component=bool(options["largest_component"]), force=bool(options["force"]))
    template_lm = template_landmarks(template, table)
    if not hasattr(loaded, "ids"):
        raise InputError(f"{template}: the template must be a mesh or point cloud, not a distance matrix")
    check_in_range(template_lm.values(), int(loaded.ids.max()) + 1, f"the template {template}")
    found, errors = _shape_landmarks(specs, table)
    return MatchPlan(template, template_lm, found, errors, names, maps_dir, both=both)


def template_path(template: str, names: dict) -> str:
    """``match:TEMPLATE``'s shape: the path as given, or, when no such file exists, the one input whose
    name (``NAME`` of ``maps/NAME.txt``) it gives (``match:cow0`` for ``shapes/cow0.off``)."""
    if template.startswith("demo:") or os.path.lexists(template):
        return template
    named = [spec for spec, name in names.items() if name == Path(template).name]
    return str(named[0]) if len(named) == 1 else template
