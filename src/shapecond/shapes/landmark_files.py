"""Named landmarks of a collection, read from files a user can write with any annotation tool.

Two conventions:

* beside each shape ``NAME.off`` a file ``NAME.lmk`` with one landmark a line,
  ``LABEL VERTEX_ID`` (the vertex id 0-based, as in the shape file; ``#`` starts
  a comment; blank lines are skipped); a label is one word;
* one CSV file (``landmarks.csv``) with the columns ``shape,label,vertex``,
  ``shape`` the shape's file name or its name without the suffix.

Points are matched **by label** across shapes (``pair_by_label``): a shape
missing a label simply has fewer pairs.  A label given twice for one shape, an
id that is not an integer, or a negative id is one ``InputError`` naming the
file and the line.  Whether an id lies in range is only known once the shape is
loaded (``check_in_range``).  Files are read through ``formats.read_text``
(regular files only, size limit, no binary data).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from ..errors import InputError
from .formats import read_text

#: Suffix of a per-shape landmark file.
LMK_SUFFIX = ".lmk"
#: Columns of a collection's landmark CSV file.
CSV_COLUMNS = ("shape", "label", "vertex")


def _vertex_id(token: str, where: str) -> int:
    try:
        value = int(token)
    except ValueError:
        raise InputError(f"{where}: the vertex id {token[:30]!r} is not an integer") from None
    if value < 0:
        raise InputError(f"{where}: the vertex id {value} is negative (ids are 0-based)")
    return value


def _add(labels: dict, label: str, vertex: int, where: str, first: dict) -> None:
    if label in labels:
        raise InputError(f"{where}: the label {label!r} is given twice for this shape (first at line {first[label]})")
    labels[label] = vertex


def read_lmk(path) -> dict[str, int]:
    """``{label: vertex id}`` of a ``.lmk`` file, in the file's order.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "cat.lmk"
    >>> _ = p.write_text("# tip of the nose\\nnose 12\\ntail 40  # end\\n")
    >>> read_lmk(p)
    {'nose': 12, 'tail': 40}
    """
    path = Path(path)
    labels, first = {}, {}
    for k, line in enumerate(read_text(path).splitlines(), 1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        where = f"{path}:{k}"
        if len(words) != 2:
            raise InputError(f"{where}: expected 'LABEL VERTEX_ID', found {len(words)} words")
        _add(labels, words[0], _vertex_id(words[1], where), where, first)
        first.setdefault(words[0], k)
    return labels


def read_landmark_csv(path) -> dict[str, dict[str, int]]:
    """``{shape: {label: vertex id}}`` of a CSV file with the columns ``shape,label,vertex``."""
    path = Path(path)
    rows = csv.reader(io.StringIO(read_text(path)))
    header = [h.strip().lower() for h in next(rows, [])]
    if tuple(header) != CSV_COLUMNS:
        raise InputError(f"{path}:1: expected the header 'shape,label,vertex', found {','.join(header)[:60]!r}")
    out, first = {}, {}
    for k, row in enumerate(rows, 2):
        if not any(c.strip() for c in row):
            continue
        where = f"{path}:{k}"
        if len(row) != 3 or not row[0].strip() or not row[1].strip():
            raise InputError(f"{where}: expected three fields shape,label,vertex")
        shape, label = row[0].strip(), row[1].strip()
        _add(out.setdefault(shape, {}), label, _vertex_id(row[2].strip(), where), where,
             first.setdefault(shape, {}))
        first[shape].setdefault(label, k)
    return out


def landmarks_of(shape, table: dict | None = None) -> tuple[dict[str, int], str] | None:
    """(``{label: vertex id}``, where they were read) of the shape file ``shape``, or None when it has none.

    ``table`` (``read_landmark_csv``'s result) is looked up by file name then by
    name without suffix; without an entry there, ``NAME.lmk`` beside the shape is read.
    """
    path = Path(str(shape))
    for key in (path.name, path.stem):
        if table is not None and key in table:
            return table[key], f"the landmark table's rows of {key}"
    lmk = path.with_suffix(LMK_SUFFIX)
    if lmk.exists() or lmk.is_symlink():
        return read_lmk(lmk), str(lmk)
    return None


def pair_by_label(template: dict[str, int], shape: dict[str, int]) -> tuple[list[str], list[int], list[int]]:
    """(shared labels in the template's order, their template ids, their shape ids)."""
    labels = [lab for lab in template if lab in shape]
    return labels, [template[lab] for lab in labels], [shape[lab] for lab in labels]


def check_in_range(ids, n_ids: int, where: str) -> None:
    """``InputError`` naming ``where`` when a vertex id is not below ``n_ids`` (the shape's vertex count)."""
    bad = [v for v in ids if v >= n_ids]
    if bad:
        raise InputError(f"{where}: landmark vertex id {bad[0]} is out of range (the shape has ids 0..{n_ids - 1})")


__all__ = ["CSV_COLUMNS", "LMK_SUFFIX", "check_in_range", "landmarks_of", "pair_by_label", "read_landmark_csv",
           "read_lmk"]
