"""Naming zero modes of the deformation Hessian by projection onto the six rigid motions.

A zero mode of ``H v = lambda M v`` is a
displacement field that a deformation-based matcher cannot see, e.g. a rotation
of a sphere or the axial rotation of a cylinder.  We describe each one in terms
of rigid motions ``v(x) = t + w x (x - c)`` with ``c`` the area centroid:

1. each of the six canonical motions (translation along world x, y, z; rotation
   about the world x, y, z axes through the centroid) whose M-norm lies at
   least ``CONTAINED`` inside the zero-mode space is named
   (``"translation x"``, ``"rotation about z"``);
2. the part of the zero-mode space orthogonal to those is compared with the
   rigid motions through principal angles; a direction that is rigid to within
   ``CONTAINED`` is named by its screw axis (``"rotation about axis (a, b, c)
   through (px, py, pz)"``, coordinates in the input's units) or its direction
   (``"translation along (a, b, c)"``); anything else is ``"non-rigid (rigid
   part r)"``.

World axes rather than principal axes: a user reads the answer against the
coordinates of their file.  A symmetric shape not aligned with the world axes
falls to case 2 and still gets its axis, as a vector.
"""

from __future__ import annotations

import numpy as np

CONTAINED = 0.99  # fraction of M-norm (squared) that must lie in the zero space


def rigid_motions(V: np.ndarray) -> np.ndarray:
    """(3n, 6) fields: translations x, y, z then rotations about x, y, z through the origin."""
    n = V.shape[0]
    R = np.zeros((3 * n, 6))
    for k in range(3):
        R[k::3, k] = 1.0
    for k in range(3):  # e_k x v
        a, b = (k + 1) % 3, (k + 2) % 3
        R[a::3, 3 + k] = -V[:, b]
        R[b::3, 3 + k] = V[:, a]
    return R


_NAMES = ["translation x", "translation y", "translation z",
          "rotation about x", "rotation about y", "rotation about z"]


def _m_orthonormal(X: np.ndarray, mass: np.ndarray, tol: float = 1e-10) -> np.ndarray:
    """M-orthonormal basis of the columns of X (rank-revealing, drops dependent columns)."""
    if X.shape[1] == 0:
        return X
    s = np.sqrt(mass)[:, None]
    Q, r, _ = np.linalg.svd(s * X, full_matrices=False)
    keep = r > tol * max(r.max(), 1e-300)
    return Q[:, keep] / s


def _fmt(v) -> str:
    return "(" + ", ".join(f"{x:.3g}" for x in v) + ")"


def name_zero_modes(Z: np.ndarray, V: np.ndarray, mass: np.ndarray, fixed_dofs=(),
                    scale: float = 1.0, centroid=np.zeros(3)) -> list[str]:
    """Names of the zero-mode space spanned by the columns of ``Z``.

    Parameters
    ----------
    Z : (3n, z) zero modes (any basis; zero on fixed coordinates)
    V : (n, 3) the vertices in which the modes were computed (centred at the centroid)
    mass : (3n,) lumped mass diagonal
    fixed_dofs : coordinates removed by landmarks (rigid motions are restricted to the others)
    scale, centroid : ``V = (input - centroid) * scale``; axis points are reported in input units.

    Returns
    -------
    list of ``z`` strings.
    """
    if Z.shape[1] == 0:
        return []
    free = np.ones(Z.shape[0], dtype=bool)
    free[np.asarray(fixed_dofs, dtype=np.int64)] = False
    m = mass[free]                       # rigid motions restricted to the free coordinates
    Q = _m_orthonormal(Z[free], m)
    R = rigid_motions(V)[free]
    names: list[str] = []
    named = []
    for k in range(6):
        r = R[:, k]
        norm2 = float(r @ (m * r))
        if norm2 <= 0.0:
            continue
        c = Q.T @ (m * r)
        if float(c @ c) / norm2 >= CONTAINED:
            names.append(_NAMES[k])
            named.append(r)
    # the rest of the zero space, orthogonal to what has been named
    rest = Q
    if named:
        N = _m_orthonormal(np.column_stack(named), m)
        rest = Q - N @ (N.T @ (m[:, None] * Q))
        rest = _m_orthonormal(rest, m, tol=1e-6)
    n_left = Q.shape[1] - len(names)
    if n_left <= 0 or rest.shape[1] == 0:
        return names[: Q.shape[1]]
    Rb = _m_orthonormal(R, m)
    C = rest.T @ (m[:, None] * Rb)                        # cosines between the two spaces
    U, cos, Wt = np.linalg.svd(C, full_matrices=False)
    for j in range(min(n_left, len(cos))):
        if cos[j] ** 2 < CONTAINED:
            names.append(f"non-rigid (rigid part {cos[j] ** 2:.2f})")
            continue
        field = Rb @ Wt[j]                                 # the rigid motion closest to the mode
        coef, *_ = np.linalg.lstsq(R, field, rcond=None)   # t, w in the normalised frame
        t, w = coef[:3], coef[3:]
        if np.linalg.norm(w) * np.sqrt(np.mean(np.sum(V * V, axis=1))) < 1e-3 * np.linalg.norm(t):
            names.append("translation along " + _fmt(t / np.linalg.norm(t)))
        else:
            axis = w / np.linalg.norm(w)
            point = np.cross(w, t) / float(w @ w) / scale + centroid
            names.append(f"rotation about axis {_fmt(axis)} through {_fmt(point)}")
    names += ["non-rigid (rigid part 0.00)"] * (Q.shape[1] - len(names))
    return names[: Q.shape[1]]
