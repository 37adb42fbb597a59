"""The objective's formulas (paper Eqs. 2-3) against their definitions, entry by entry."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings, strategies as st

from shapecond.symmetry import objective as obj


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(2, 9), extra=st.integers(0, 9), fortran=st.booleans())
def test_image_block_and_dist2_are_their_definitions(seed, n, extra, fortran):
    """``image_block`` is D[T x, T x'] (also for a D that is not C-contiguous) and ``dist2`` the double
    sum of Eq. 3, bit for bit as the fancy index gives it."""
    rng = np.random.default_rng(seed)
    m = n + extra
    P = rng.normal(size=(m, 3))
    D = np.linalg.norm(P[:, None] - P[None], axis=2)
    if fortran:  # not C-contiguous: the fancy-index path
        D = np.asfortranarray(D)
    t = rng.choice(m, size=n, replace=False)
    block = obj.image_block(D, t)
    assert block.shape == (n, n)
    np.testing.assert_array_equal(block, [[D[t[i], t[j]] for j in range(n)] for i in range(n)])
    want = sum((D[i, j] - D[t[i], t[j]]) ** 2 for i in range(n) for j in range(n))
    assert np.isclose(obj.dist2(D, t), want, rtol=1e-12, atol=0.0)
    assert obj.dist2(D, t) == float(np.sum((D[:n, :n] - D[np.ix_(t, t)]) ** 2))
