"""Cost guards of the Python interface: work estimated beyond ``shapecond.limits`` is refused
before it starts (``TooLargeError`` with the estimate), unless ``force=True``.

The geodesics of a metric shape are guarded where they are computed
(``shapes.metric``), exact σ and the LP where they are solved (``symmetry.score``),
the κ probes in ``symmetry.condition``; what is guarded here is the work that
the interface composes from several searches: CNBS landmark selection, heat
maps, a matching's geodesics and LH05 affinity matrix, and the local score with
its doubt field and HTML page (``limits.local_seconds``).  Per-unit costs are
``limits.search_seconds`` (a default witness search, measured at N = 400) and
``limits.geodesic_seconds``.
"""

from __future__ import annotations

from ..errors import TooLargeError
from ..limits import (check_cost, dense_stage_seconds, geodesic_seconds, human_bytes, lh05_affinity_bytes, local_seconds, metric_bytes,
                      search_seconds)
from ..matching.nested import core_size
from ..matching.spectral import MAX_AFFINITY_BYTES, LH05Options

#: Witness searches a CNBS step or a heat map costs, in units of one default search (measured on TOSCA).
SEARCHES_PER_HEAT_MAP = 4


def guard_landmarks(shape, k: int, method: str, scores, force: bool) -> None:
    """CNBS: about ``SEARCHES_PER_HEAT_MAP`` searches per landmark; a baseline with ``scores``: one."""
    cnbs = method in ("cnbs", "cnbs-scale")
    if cnbs or scores:
        check_cost(f"{method} with {k} landmarks at N = {shape.n_samples}",
                   search_seconds(shape.n_samples, shape.n_targets, (SEARCHES_PER_HEAT_MAP if cnbs else 1) * max(k, 1)),
                   force=force)


def guard_heat_map(shape, force: bool) -> None:
    """A heat map: about ``SEARCHES_PER_HEAT_MAP`` searches."""
    check_cost(f"the heat map at N = {shape.n_samples}",
               search_seconds(shape.n_samples, shape.n_targets, SEARCHES_PER_HEAT_MAP), force=force)


def guard_local(n_vertices: int, force: bool, doubt: bool = False, html: bool = False) -> None:
    """The local score of a mesh of ``n_vertices`` vertices, with its doubt field and HTML page when
    asked for (``limits.local_seconds``): refused beyond ``limits.MAX_SECONDS``, a warning above a minute."""
    what = f"the local score of {n_vertices} vertices" + (
        " with its doubt field" if doubt or html else "") + (" and HTML page" if html else "")
    check_cost(what, local_seconds(n_vertices, doubt, html), force=force)


def matcher_bytes(n_points: int, n_landmarks: int, options, what: str) -> float:
    """Memory of the matcher itself (LH05's dense affinity matrix; ``options``: its ``LH05Options``, another
    matcher's options or None), checked before any geodesic: beyond ``spectral.MAX_AFFINITY_BYTES`` the
    matcher refuses whatever ``force`` says."""
    if not isinstance(options, LH05Options):
        return 0.0
    nested = options.nested and core_size(n_landmarks) is not None
    nbytes = lh05_affinity_bytes(n_points, core_size(n_landmarks) if nested else n_landmarks, options.k)
    if nbytes > MAX_AFFINITY_BYTES:
        raise TooLargeError(f"{what}: LH05's affinity matrix would need about {human_bytes(nbytes)}, more than the "
                            f"{human_bytes(MAX_AFFINITY_BYTES)} it allows; use fewer samples or a smaller k "
                            "(--k), or the faq matcher")
    return nbytes


def guard_match(n_vertices: int, n_points: int, n_landmarks: int, options, force: bool) -> None:
    """Two shapes' geodesics (2N sources each way), the ZoomOut dense stage when it runs
    (``limits.dense_stage_seconds``: both Laplace bases and the nearest-neighbour products, which
    dominate at scan resolution) and the matcher's memory (``matcher_bytes``).

    ``options``: the ``matching.pipeline.MatchOptions`` of the matching.
    """
    zoomout = "zoomout" in (options.matcher, options.dense)
    what = (f"matching with {n_points} samples on {n_vertices} vertices ({options.backend} distances"
            + (", ZoomOut dense stage)" if zoomout else ")"))
    nbytes = matcher_bytes(n_points, n_landmarks, options.matcher_options, what)
    seconds = 2 * geodesic_seconds(n_vertices, n_points, options.backend)
    if zoomout:
        seconds += dense_stage_seconds(n_vertices, n_vertices)
    check_cost(what, seconds, 2 * metric_bytes(n_points, n_vertices) + nbytes, force)
