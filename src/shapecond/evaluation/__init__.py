"""The paper's evaluation of landmark methods (Section 7, Figure 7): an application of matching.

    datasets        class folders: shared vertex order, or remeshed with .vts ground truth
    landmark_sets   each method's landmarks on a null shape, their scores, cached
    protocols       per target: corresponding, independent, remeshed; errors
    deformation_level  a class's ε from its ground truth, δ(ε) at it
    run             EvaluationOptions, evaluate (``sc.evaluate``) and evaluate_dataset (the phases, in parallel)
    report          Markdown, HTML, JSON and plots of an Evaluation
"""

from .protocols import PROTOCOLS
from .records import Evaluation, MatchRecord
from .run import PROTOCOL_CHOICES, EvaluationOptions, evaluate, evaluate_dataset, evaluation_options

__all__ = ["Evaluation", "EvaluationOptions", "MatchRecord", "PROTOCOLS", "PROTOCOL_CHOICES", "evaluate",
           "evaluate_dataset", "evaluation_options"]
