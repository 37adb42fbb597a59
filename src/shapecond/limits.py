"""Estimates of time and memory, checked before long computations start.

A request that would take hours or exhaust memory is refused up front with its
estimate and the option that forces it (``--force``, ``force=True``); one that
takes more than a minute starts with a :class:`CostWarning` saying how long.
The constants are per-unit costs measured on the 2-core reference machine
(by the project's benchmarks, not shipped with the package); estimates are meant to be right
within a small factor, which is all a refusal needs.
"""

from __future__ import annotations

import time
import warnings

from .errors import TooLargeError

#: Refuse work estimated above this many seconds unless forced.
MAX_SECONDS = 1800.0
#: Warn (one line on stderr from the command line) above this many seconds.
WARN_SECONDS = 60.0
#: Refuse work estimated to need more memory than this unless forced.
MAX_BYTES = 6 * 2**30

#: Seconds per (source x vertex) of one geodesic solve, per backend; ``exact``
#: grows like n^1.5 (MMP), so its constant multiplies n^1.5.
GEODESIC_COST = {"heat": 5e-7, "fmm": 1.1e-6, "euclidean": 2.5e-8, "exact": 4e-7}
#: Seconds of the default witness search at N = 400 samples, M = 3200 targets
#: (``search_seconds`` scales it).
SEARCH_SECONDS_400 = 12.0


#: Seconds of each of the exact and LP solves of a score given no time limit of its own.
SOLVE_SECONDS = 10.0


class Deadline:
    """The seconds left of a time limit that starts when this is made (``None``: no limit).

    Examples
    --------
    >>> Deadline(None).left() is None
    True
    >>> 0.0 < Deadline(5.0).left() <= 5.0
    True
    >>> Deadline(5.0).left(reserve=10.0)
    0.0
    """

    def __init__(self, seconds: float | None):
        self.end = None if seconds is None else time.perf_counter() + float(seconds)

    def left(self, reserve: float = 0.0) -> float | None:
        """Seconds until the limit less ``reserve`` (at least 0), or None without a limit."""
        return None if self.end is None else max(0.0, self.end - time.perf_counter() - reserve)

    def passed(self, reserve: float = 0.0) -> bool:
        """Whether the limit (less ``reserve``) is reached; never without a limit."""
        return self.end is not None and self.left(reserve) == 0.0


#: The local score (``deformation.local_score``): seconds per n^1.5 of building and factorising the
#: 3n x 3n Hessian and its few smallest eigenpairs, plus a fixed part, reading included (demo:blob, 2.5k-41k vertices,
#: 9 s at 41k; 73 s at 163k).
LOCAL_SCORE_COST = (1.0, 1.1e-6)
#: The local doubt field (``deformation.heatmap``, K = 24 eigenpairs and the modal field): seconds
#: per n^1.25 (demo:blob: 3.7 s at 10k, 15 s at 41k vertices).
LOCAL_DOUBT_COST = 2.6e-5
#: An HTML page's scene (``viz``): seconds per vertex drawn, plus a fixed part.
HTML_SCENE_COST = (0.5, 2e-5)


def local_seconds(n_vertices: int, doubt: bool = False, html: bool = False) -> float:
    """Estimated seconds of the local score of a mesh of ``n_vertices`` vertices, with its doubt field
    (``doubt``: the local score with each vertex fixed) and an HTML page of it (``html``).

    Examples
    --------
    >>> round(local_seconds(40962))
    10
    >>> local_seconds(163842, doubt=True, html=True) > local_seconds(163842) > local_seconds(40962)
    True
    """
    base, per = LOCAL_SCORE_COST
    s = base + per * n_vertices**1.5
    if doubt or html:
        s += LOCAL_DOUBT_COST * n_vertices**1.25
    if html:
        s += html_seconds(n_vertices)
    return s


#: A Laplace basis of k eigenpairs (``shapes.laplace``, ARPACK shift-invert): seconds per shape plus
#: per vertex and eigenpair (demo:blob, k = 150: 10 s at 2.5k, 38 s at 41k vertices).
LAPLACE_COST = (8.0, 4.8e-6)
#: Seconds per (source point x target vertex x basis function) of the dense stage's float32
#: nearest-neighbour products (``matching.zoomout.nearest_rows``; 7-8e-11 at 2.5k-41k vertices).
NEAREST_COST = 7.5e-11
#: Subsample cells' worth of target vertices a final-pass region holds (``matching.zoomout``), measured:
#: the pass took 0.9 s where the search of every target vertex took 16.9 s (52,565 vertices, k = 150,
#: 1,500 cells of 35 vertices: about 2,800 candidates, 80 cells).
REGION_CELLS = 80


def dense_stage_seconds(n_source: int, n_target: int, k: int = 150, subsample: int = 10) -> float:
    """Estimated seconds of the ZoomOut dense stage (``matching.zoomout``) between meshes of
    ``n_source`` and ``n_target`` vertices with a basis of ``k`` functions: both Laplace bases, the
    iterations (``subsample`` k source points against every target vertex at k = 20, 30, ..., k) and
    the final map of every source vertex, searched in a region of ``REGION_CELLS`` cells.

    Examples
    --------
    >>> dense_stage_seconds(163842, 163842) > 3 * dense_stage_seconds(40962, 40962) > 0
    True
    """
    base, per = LAPLACE_COST
    bases = 2 * base + per * (n_source + n_target) * k
    levels = sum(subsample * j * j for j in range(20, k + 1, 10))
    region = min(n_target, REGION_CELLS * n_target / (subsample * k))
    return bases + NEAREST_COST * (n_target * levels + region * n_source * k)


def html_seconds(n_vertices: int) -> float:
    """Estimated seconds of writing an HTML page whose scene draws ``n_vertices`` vertices."""
    base, per = HTML_SCENE_COST
    return base + per * n_vertices


class CostWarning(UserWarning):
    """A computation was started although it is estimated to take minutes."""


def human_seconds(s: float) -> str:
    if s < 120:
        return f"{s:.0f} s"
    if s < 7200:
        return f"{s / 60:.0f} min"
    return f"{s / 3600:.1f} h"


def human_bytes(b: float) -> str:
    return f"{b / 2**30:.1f} GB" if b >= 2**30 else f"{b / 2**20:.0f} MB"


#: How a refusal says to force the work: the Python parameter and the command-line flag.
FORCE_HINT = "pass force=True (--force on the command line)"


def check_cost(what: str, seconds: float = 0.0, nbytes: float = 0.0, force: bool = False,
               hint: str = FORCE_HINT) -> None:
    """Refuse (``TooLargeError``) or warn (``CostWarning``) according to the estimates."""
    if not force and nbytes > MAX_BYTES:
        raise TooLargeError(f"{what} needs about {human_bytes(nbytes)} of memory, more than the "
                            f"{human_bytes(MAX_BYTES)} allowed; {hint}")
    if not force and seconds > MAX_SECONDS:
        raise TooLargeError(f"{what} would take about {human_seconds(seconds)} (limit "
                            f"{human_seconds(MAX_SECONDS)}); {hint}")
    if seconds > WARN_SECONDS:
        warnings.warn(f"{what} will take about {human_seconds(seconds)}", CostWarning, stacklevel=3)


def geodesic_seconds(n_vertices: int, n_sources: int, backend: str) -> float:
    """Estimated seconds of ``n_sources`` distance solves on ``n_vertices`` vertices."""
    per = GEODESIC_COST.get(backend, GEODESIC_COST["heat"])
    size = n_vertices ** 1.5 if backend == "exact" else n_vertices
    return per * size * n_sources


def metric_bytes(n_targets: int, n_vertices: int) -> float:
    """Peak bytes of sampling M targets: D and two working copies, plus the kept rows."""
    return 3 * 8.0 * n_targets**2 + min(4.0 * n_targets * n_vertices, 512 * 2**20)


def lh05_affinity_bytes(n_points: int, n_landmarks: int, k: int = 20) -> float:
    """Bytes of the dense float32 affinity matrix of LH05's first spectral round (``matching.spectral``).

    Its C candidates are the landmark pairs and the ``k`` best free target samples of every free
    source sample: C = L + (N - L) min(k, N - L), and the matrix holds C² entries (N = 5000, k = 20:
    37 GB).  Matched with its first ``CORE_LANDMARKS`` landmarks as well (``matching.nested``), a
    problem with more landmarks builds the larger matrix of fewer; pass that smaller L.
    """
    free = max(int(n_points) - int(n_landmarks), 0)
    c = int(n_landmarks) + free * min(int(k), free)
    return 4.0 * c * c


def search_seconds(n_samples: int, n_targets: int | None = None, searches: float = 1.0) -> float:
    """Estimated seconds of ``searches`` default-effort witness searches (N samples, M targets).

    One move costs O(N M) and a search makes O(N) of them, so the time grows
    like N² M from the measured N = 400, M = 3200 case.
    """
    m = 8 * n_samples if n_targets is None else n_targets
    return searches * SEARCH_SECONDS_400 * (n_samples / 400.0) ** 2 * (m / 3200.0)

