"""Landmark-guided matching and the paper's evaluation (Section 7).

Data flow, always **source to target**::

    Geometry --sampled.sample_surface--> SampledSurface (FPS samples + distance rows)
             --spectral.lh05_match / seeded.faq_match--> SampleMatch (sample map t)
             --dense.dense_map--> one target vertex per source vertex
             --metrics--> geodesic errors (% of half diameter, / sqrt(area))

``problem.MatchProblem`` runs the chain for one pair and keeps what is read off it; ``evaluation`` and
``report`` run the Figure 7 protocol on class folders.
"""

from .dense import dense_map
from .metrics import cumulative_curve, errors_from_rows, normalise
from .pipeline import DenseMatch, match_samples
from .problem import MatchProblem, match_shapes, match_surfaces
from .seeded import faq_match
from .spectral import SampleMatch, lh05_match

__all__ = ["DenseMatch", "MatchProblem", "SampleMatch", "cumulative_curve", "dense_map", "errors_from_rows",
           "faq_match", "lh05_match", "match_samples", "match_shapes", "match_surfaces", "normalise"]
