"""Option objects that also accept their fields as keyword arguments.

A function with many tuning knobs (CNBS, the matchers) takes one frozen dataclass of
options instead of a long parameter list, and still accepts each field as a keyword
argument, so that ``heat_map(D, resolve_fraction=0.5)`` and
``heat_map(D, options=HeatMapOptions(resolve_fraction=0.5))`` are the same call::

    def heat_map(D, n_samples=None, ..., options=None, **kw):
        opts = merge_options(HeatMapOptions, options, kw, "heat_map")

The dataclass is the one declaration of the options: who needs to know them (the API's
refusal of an unknown matcher option, a default) reads its fields, not the function's signature.
"""

from __future__ import annotations

import dataclasses


def merge_options(cls, options, kw: dict, where: str):
    """``options`` (an instance of the dataclass ``cls``; None: its defaults) with the fields
    named in ``kw`` replaced.  A name that is not a field is a ``TypeError``, as for any
    unexpected keyword argument of ``where``."""
    base = cls() if options is None else options
    if not isinstance(base, cls):
        raise TypeError(f"{where}() options must be a {cls.__name__}, got {type(options).__name__}")
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(kw) - names)
    if unknown:
        raise TypeError(f"{where}() got an unexpected keyword argument {unknown[0]!r}")
    return dataclasses.replace(base, **kw) if kw else base


__all__ = ["merge_options"]
