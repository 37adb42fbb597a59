"""Local symmetry score for deformation-based matching (paper Section 5).

* ``energy``      E(P) (point-to-plane proximity + edge springs or ARAP) and its exact Hessian at 0
* ``solver``      sparse Cholesky (CHOLMOD) factor of H + sM, reused for every landmark set
* ``rigid``       naming zero modes by the six rigid motions
* ``local_score`` sigma_inf = sqrt(2 / lambda_min(H, M)), ``LocalScore``, ``LocalProblem``
* ``heatmap``     the score with each vertex fixed, greedy landmarks (local CNBS)
"""

from .heatmap import LocalHeatmap, LocalLandmarks, local_heatmap, select_local_landmarks
from .local_score import LocalProblem, LocalScore, local_score_of_geometry, local_symmetry_score

__all__ = ["LocalHeatmap", "LocalLandmarks", "LocalProblem", "LocalScore", "local_heatmap",
           "local_score_of_geometry", "local_symmetry_score", "select_local_landmarks"]
