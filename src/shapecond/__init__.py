"""shapecond: how hard is a shape to match, why, and where to put landmarks.

Reproduces and extends Ovsjanikov, Huang and Guibas, *A Condition Number for
Non-Rigid Shape Matching*, SGP 2011.  Data flows one way::

    input -> metric shape -> scores -> landmarks -> matching -> evaluation
"""

from ._jit_cache import ensure_writable_cache

ensure_writable_cache()
del ensure_writable_cache

__version__ = "0.1.0"
