"""Option objects that also accept their fields as keyword arguments.

A function with many tuning knobs (CNBS, the matchers) takes one frozen dataclass of
options instead of a long parameter list, and still accepts each field as a keyword
argument, so that ``heat_map(D, resolve_fraction=0.5)`` and
``heat_map(D, options=HeatMapOptions(resolve_fraction=0.5))`` are the same call::

    @with_options(HeatMapOptions)
    def heat_map(D, n_samples=None, ..., options=None, **kw):
        opts = merge_options(HeatMapOptions, options, kw, "heat_map")

``with_options`` shows the fields in the function's signature (``inspect.signature``,
``help``), which the callers that read a function's options from its signature rely on.
"""

from __future__ import annotations

import dataclasses
import inspect


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


def with_options(cls, more: bool = False):
    """Decorator: the signature of the function shows the fields of the dataclass ``cls`` as
    keyword-only parameters (with their defaults) in place of its ``**kw``, or before it when
    ``more`` (the function takes other keywords too)."""

    def decorate(func):
        sig = inspect.signature(func)
        params = [p for p in sig.parameters.values() if p.kind is not inspect.Parameter.VAR_KEYWORD]
        rest = [p for p in sig.parameters.values() if p.kind is inspect.Parameter.VAR_KEYWORD and more]
        taken = {p.name for p in params}
        params += [inspect.Parameter(f.name, inspect.Parameter.KEYWORD_ONLY, default=f.default)
                   for f in dataclasses.fields(cls) if f.name not in taken]
        func.__signature__ = sig.replace(parameters=params + rest)
        return func

    return decorate


__all__ = ["merge_options", "with_options"]
