"""A collection matched to a template (``--what match:TEMPLATE``): landmarks, parameters and maps.

Before any row is computed, this process reads the template's landmarks and
loads the template (a template without landmarks, a bad landmark file of the
template, an id out of its range or a template that does not load stop the
batch: one line, exit status 2), and reads every shape's landmarks
(``shapes.landmark_files``: ``NAME.lmk`` beside the shape or the rows of
``--landmarks FILE``).  A shape whose landmark file is broken, or that has
none, becomes an error row; the batch goes on.  The label-matched pairs enter
the row's ``params``, so that ``--resume`` recomputes a shape whose landmarks
were changed, and only it.

The workers match (``api.collection.match_to_template``, template → shape) and
return the map with the row; this process writes it to ``maps/NAME.txt``
beside the table, atomically (``output.atomic_open``), **before** appending the
row, so that a row in the table always has its whole map on disk, and a batch
killed at any moment leaves no torn map.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError
from .rows import parse_what

#: The folder of the maps, beside the table.
MAPS_FOLDER = "maps"


@dataclass
class MatchPlan:
    """What matching needs besides the batch's options; empty (``template`` None) without it."""

    template: str | None = None
    template_lm: dict = field(default_factory=dict)
    shape_lm: dict = field(default_factory=dict)     # spec -> landmarks_of result (or None)
    errors: dict = field(default_factory=dict)       # spec -> why its landmarks cannot be read
    names: dict = field(default_factory=dict)        # spec -> map name
    maps_dir: Path | None = None

    def params(self, params: str, specs) -> list[str]:
        """Each shape's ``params``: the batch's, plus its label-matched landmark pairs."""
        if self.template is None:
            return [params] * len(specs)
        from ..shapes.landmark_files import pair_by_label

        base, out = json.loads(params), []
        for spec in specs:
            found = self.shape_lm.get(spec)
            pairs = None if found is None else [list(p) for p in zip(*pair_by_label(self.template_lm, found[0]))]
            out.append(json.dumps({**base, "pairs": pairs}, sort_keys=True, separators=(",", ":")))
        return out

    def task_kwargs(self, spec: str) -> dict:
        """The keywords of ``rows.shape_row`` for ``spec``."""
        return {} if self.template is None else {"landmarks": (self.template_lm, self.shape_lm.get(spec))}

    def write_map(self, row: dict) -> None:
        """Write a row's map (``"_map"``, removed from the row) and name its file in the row."""
        vertex_map = row.pop("_map", None)
        if vertex_map is None or self.template is None:
            return
        from ..api.collection import write_map

        path = self.maps_dir / f"{self.names[row['file']]}.txt"
        write_map(path, vertex_map)
        row["map_file"] = str(path)


def _shape_landmarks(specs, table) -> tuple[dict, dict]:
    """(spec -> ``landmarks_of``, spec -> why not): a broken file, or no landmarks, is that shape's error."""
    from ..shapes.landmark_files import landmarks_of

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
    """The ``MatchPlan`` of a batch (module docstring); ``InputError`` for an unusable template."""
    template = parse_what(options["what"]).match
    if template is None:
        return MatchPlan()
    from .. import api
    from ..api.collection import map_names, template_landmarks
    from ..shapes.landmark_files import check_in_range, read_landmark_csv

    table = read_landmark_csv(options["landmark_table"]) if options.get("landmark_table") else None
    loaded = api.load(template, largest_component=bool(options["largest_component"]), force=bool(options["force"]))
    template_lm = template_landmarks(template, table)
    if not hasattr(loaded, "ids"):
        raise InputError(f"{template}: the template must be a mesh or point cloud, not a distance matrix")
    check_in_range(template_lm.values(), int(loaded.ids.max()) + 1, f"the template {template}")
    found, errors = _shape_landmarks(specs, table)
    return MatchPlan(template, template_lm, found, errors, dict(zip(specs, map_names(specs))),
                     Path(out).absolute().parent / MAPS_FOLDER)
