"""Landmark-nested matching: more correct landmarks never end on a worse objective.

A matcher maximises an objective ``F`` (``consistency.objective`` for LH05,
``Σ D_s · D_t[T, T]`` for FAQ) over the maps ``Π(L)`` that send every landmark
of ``L`` to its image.  For landmark lists ``L ⊆ L'`` (with the same images)
``Π(L') ⊆ Π(L)``, so an *exact* maximiser is consistent: when the optimum for
``L`` already sends the landmarks of ``L'`` to their images, it is the optimum
for ``L'`` too, and a correct landmark changes nothing.  A local search has no
such property: the extra landmarks change its start (the descriptors, the
candidates, the first rounding) and it may end in another local maximum,
lower on ``F`` and less accurate, although the map found with fewer landmarks
was still feasible (TOSCA dog1, 12 HKS landmarks: 0.96 % error at 0.9958 of the
true map's ``F`` against 0.06 % at 1.0006 with the first three).

The matchers therefore solve the problem with the first ``CORE_LANDMARKS``
landmarks as well, by the very same call, send its map to the remaining
landmarks (``with_landmarks``), climb ``F`` from there with all the landmarks
fixed, and keep whichever of the two results has the larger ``F``.  This gives,
for the landmark list ``L`` and its prefix ``C = L[:3]``, on the same distance
matrices:

    F(match(L)) ≥ F(with_landmarks(match(C), L)),

and ``= F(match(C))`` whenever ``match(C)`` sends every landmark of ``L`` to its
image.  Three because that is the fewest landmarks that can exclude every
non-trivial isometry of a surface: an isometry of a connected surface that
fixes a point and two independent directions there is the identity, and three
points off one geodesic fix those (generically), while two points leave the
reflection across the geodesic through them (the mirror of a bilaterally
symmetric shape when both lie on its plane).  Fewer landmarks may leave several exact optima,
so a map "good for fewer landmarks" is not well defined below three.

What is not guaranteed: ``F`` is not the error, so a larger ``F`` is not always
a more accurate map (where the true map is not ``F``'s maximum, e.g. on
strongly non-isometric pairs); and between two prefixes both longer than three
only the bound through their common core holds (a chain through every prefix
would cost one full solve per landmark).
"""

from __future__ import annotations

import numpy as np

#: landmarks of the core problem every longer landmark list is nested on (module docstring)
CORE_LANDMARKS = 3


def with_landmarks(t, landmarks_source, landmarks_target) -> np.ndarray:
    """The map ``t`` changed as little as possible so that it sends each landmark to its image.

    For each landmark ``x → y`` in turn with ``t[x] ≠ y``: the source sample
    that had ``y`` (if any) takes ``t[x]``, and ``x`` takes ``y`` (a swap), so
    an injective map stays injective and samples off the landmarks keep their
    images except those swaps.  ``t`` is not modified.
    """
    t = np.array(t, dtype=np.int64)
    ls = np.asarray(landmarks_source, dtype=np.int64).reshape(-1)
    lt = np.asarray(landmarks_target, dtype=np.int64).reshape(-1)
    for x, y in zip(ls.tolist(), lt.tolist()):
        if t[x] != y:
            holder = np.flatnonzero(t == y)
            if holder.size:
                t[holder[0]] = t[x]
            t[x] = y
    return t


def core_size(n_landmarks: int) -> int | None:
    """Length of the prefix to nest a problem with ``n_landmarks`` on, or None (no nesting)."""
    return CORE_LANDMARKS if n_landmarks > CORE_LANDMARKS else None
