"""User-supplied landmarks (paper Section 7: hand-picked benchmark landmarks).

A landmark file holds vertex ids, 0-based, in the input's own numbering, in the
format of ``checks.read_ids``: every id on every line (``1 2 3``, ``1,2,3`` or one
per line), and ``ID 0 0 0`` for the vertex points of the Blended Intrinsic Maps
benchmark files ``bim_benchmark_landmarks/TOSCA/<class>.pid``.  Each id becomes the sample standing
for it (``result.sample_of_vertex``): the vertex itself when it is a sample (build
the shape with ``landmarks=`` to make sure), otherwise the nearest sample.  Repeated
samples are an error: two landmarks would collapse into one.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..checks import check_ids, read_ids
from ..errors import InputError
from .result import sample_of_vertex


@dataclass(frozen=True)
class UserLandmarks:
    """The user's landmarks as ``select_landmarks`` takes them (method "user"): ``ids`` (input ids) or,
    when None, the landmark file ``path`` (``user_landmarks``)."""

    ids: tuple | None = None
    path: str | None = None


def user_landmarks(shape, ids=None, path=None) -> list[int]:
    """Sample indices of user landmarks given as input ids or as a file of ids.

    Parameters
    ----------
    shape : MetricShape
    ids : sequence of int, optional
        The input's own vertex ids (matrix row indices for a matrix input).
    path : str, optional
        A landmark file (``checks.read_ids``: 0-based ids); used when ``ids`` is None.
    """
    if ids is None:
        if path is None:
            raise InputError("user landmarks need ids or a landmark file")
        ids = read_ids(path)
    ids = check_ids(ids)
    if shape.geometry is not None:
        internal = shape.geometry.to_internal(ids)
    else:
        internal = ids
    out = [sample_of_vertex(shape, int(v)) for v in internal]
    seen = {}
    for vid, s in zip(ids, out):
        if s in seen:
            raise InputError(f"landmarks {seen[s]} and {vid} fall on the same sample; "
                             "use more points or build the shape with these landmarks")
        seen[s] = vid
    return out
