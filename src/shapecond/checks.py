"""One place that parses and validates every value a user gives shapecond.

The command line and the Python functions call the same checks, so the same
bad value gets the same one-line ``InputError`` from both:

* numbers: :func:`check_int`, :func:`check_float` (ranges, NaN, infinities,
  overflow, booleans passed as numbers), :func:`check_seed`, :func:`check_choice`;
* vertex ids: :func:`parse_ids` (``"3,5,9"``, a file of ids, or a sequence) and
  :func:`read_ids` (a file: every id on every line; ``ID 0 0 0`` is a BIM ``.pid``
  vertex point);
* files: :func:`open_regular` opens a file only if it is a regular file (a FIFO,
  a device or a socket is refused before it is read, without blocking), and
  optionally without following a symbolic link;
* distance matrices: :func:`check_distance_matrix`, with the strictness of
  :func:`scipy.spatial.distance.is_valid_dm` (square, symmetric, zero diagonal)
  plus finite, real and non-negative entries;
* point clouds: :func:`check_point_cloud` (finite (n, 3) coordinates that span
  at least a plane).

Examples
--------
>>> from shapecond.checks import check_float, parse_ids
>>> parse_ids("12, 405,877")
[12, 405, 877]
>>> check_float(0.5, "alpha", lo=0, lo_open=True)
0.5
"""

from __future__ import annotations

import errno
import math
import numbers
import os
import stat
import weakref
from pathlib import Path

import numpy as np
from scipy.spatial.distance import is_valid_dm

from .errors import InputError, OutputError

#: Largest file of vertex ids read (a landmark file holds a few dozen lines).
MAX_ID_FILE_BYTES = 16 * 2**20
#: Largest vertex id (ids index int64 arrays).
MAX_ID = 2**62
#: Seeds are non-negative integers below 2**63 (numpy's ``default_rng``).
MAX_SEED = 2**63 - 1
#: Relative tolerance of symmetry and diagonal checks of a distance matrix:
#: |D - Dᵀ| and |diag D| at most this fraction of the largest distance.
DM_RTOL = 1e-8


def _fmt(value) -> str:
    text = repr(value) if isinstance(value, str) else str(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _num(v) -> str:
    return str(v) if isinstance(v, int) else f"{v:g}"


def _range_text(lo, hi, lo_open, hi_open) -> str:
    if lo is not None and hi is not None:
        return f"in {'(' if lo_open else '['}{_num(lo)}, {_num(hi)}{')' if hi_open else ']'}"
    if lo is not None:
        return f"{'>' if lo_open else '>='} {_num(lo)}"
    if hi is not None:
        return f"{'<' if hi_open else '<='} {_num(hi)}"
    return "finite"


def check_int(value, name: str, *, lo: int | None = None, hi: int | None = None) -> int:
    """``value`` as an int in ``[lo, hi]``; ``InputError`` naming ``name`` otherwise.

    Accepts Python and numpy integers and decimal strings (command line); refuses
    booleans, floats (even integral ones: ``n_points=4.0`` is a slip) and NaN.
    """
    if isinstance(value, str):
        text = value.strip()
        try:
            value = int(text, 10)
        except ValueError:
            raise InputError(f"{name} must be an integer, got {_fmt(value)}") from None
    elif isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise InputError(f"{name} must be an integer, got {_fmt(value)}")
    value = int(value)
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        raise InputError(f"{name} must be an integer {_range_text(lo, hi, False, False)}, got {value}")
    return value


def check_float(value, name: str, *, lo: float | None = None, hi: float | None = None,
                lo_open: bool = False, hi_open: bool = False) -> float:
    """``value`` as a finite float in the given range; ``InputError`` otherwise.

    ``lo_open``/``hi_open`` exclude the end points (``lo=0, lo_open=True``: positive).
    """
    if isinstance(value, str):
        try:
            value = float(value.strip())
        except ValueError:
            raise InputError(f"{name} must be a number, got {_fmt(value)}") from None
    elif isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise InputError(f"{name} must be a number, got {_fmt(value)}")
    value = float(value)
    bad = not math.isfinite(value)
    if not bad and lo is not None:
        bad = value <= lo if lo_open else value < lo
    if not bad and hi is not None:
        bad = value >= hi if hi_open else value > hi
    if bad:
        what = _range_text(lo, hi, lo_open, hi_open)
        raise InputError(f"{name} must be a {'finite ' if what != 'finite' else ''}number"
                         f"{'' if what == 'finite' else ' ' + what}, got {value:g}")
    return value


def check_seed(seed, name: str = "seed") -> int:
    """A seed for ``numpy.random.default_rng``: an integer in [0, 2**63 - 1]."""
    return check_int(seed, name, lo=0, hi=MAX_SEED)


def check_choice(value, name: str, choices) -> str:
    """``value`` if it is one of ``choices``; ``InputError`` listing them otherwise."""
    if value not in choices:
        raise InputError(f"{name} must be one of {', '.join(map(str, choices))}, got {_fmt(value)}")
    return value


def check_flag(value, name: str) -> bool:
    """``value`` if it is a bool (NumPy's included); ``InputError`` otherwise: ``"yes"`` or 1 is not a flag."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise InputError(f"{name} must be True or False, got {_fmt(value)}")


# --- vertex ids --------------------------------------------------------------------

def check_ids(values, name: str = "landmarks") -> list[int]:
    """Non-negative, distinct integer ids from a sequence; ``InputError`` otherwise."""
    out = []
    for v in np.asarray(values, dtype=object).ravel() if isinstance(values, np.ndarray) else values:
        if isinstance(v, (float, np.floating)) and math.isfinite(v) and float(v).is_integer():
            v = int(v)
        out.append(check_int(v, f"{name} id", lo=0, hi=MAX_ID))
    seen = set()
    for v in out:
        if v in seen:
            raise InputError(f"{name}: id {v} is repeated")
        seen.add(v)
    return out


def check_landmark_count(k, n: int, fixed=()) -> list[int]:
    """``k`` more landmarks among ``n`` samples beside ``fixed`` (sample indices, returned as a
    list of int): ``InputError`` when they do not fit."""
    fixed = [int(i) for i in fixed]
    if k < 0 or k + len(fixed) > n:
        raise InputError(f"cannot choose {k} landmarks among {n} samples ({len(fixed)} already fixed)")
    return fixed


def _id_value(token: str, where: str) -> int:
    """One vertex id: a non-negative integer (``12`` or ``12.0``); fractions, words and NaN refused."""
    try:
        value = int(token, 10)
    except ValueError:
        try:
            f = float(token)
        except ValueError:
            raise InputError(f"{where}: {_fmt(token)} is not a vertex id") from None
        if not (math.isfinite(f) and f.is_integer()):
            raise InputError(f"{where}: {_fmt(token)} is not an integer vertex id") from None
        value = int(f)
    if not 0 <= value <= MAX_ID:
        raise InputError(f"{where}: {_fmt(token)} is not a vertex id (0 .. {MAX_ID})")
    return value


def _line_ids(tokens: list[str], where: str) -> list[int]:
    """The ids of one line of an id file: every column, except that a BIM ``.pid`` vertex point
    ``ID 0 0 0`` is ``ID`` (as ids it would repeat 0) and a BIM point inside a triangle
    (``FACE b1 b2 b3`` with fractional barycentric coordinates) is refused."""
    if len(tokens) == 4:
        try:
            rest = [float(t) for t in tokens[1:]]
        except ValueError:
            rest = None
        if rest is not None and all(math.isfinite(v) for v in rest):
            if rest == [0.0, 0.0, 0.0]:
                return [_id_value(tokens[0], where)]
            if not all(v.is_integer() for v in rest):
                raise InputError(f"{where}: {_fmt(' '.join(tokens))} is a point inside a triangle (BIM barycentric "
                                 "coordinates), not vertex ids; give vertex ids (a .pid vertex line is ID 0 0 0)")
    return [_id_value(t, where) for t in tokens]


def _id_tokens(line: str) -> list[str]:
    """The columns of one line of ids: ``#`` starts a comment; spaces, tabs and commas separate."""
    return line.split("#")[0].replace(",", " ").split()


def read_ids(path, name: str | None = None) -> list[int]:
    """Vertex ids from a text file: every id on every non-empty line, in order.

    Ids are separated by spaces, tabs, commas or new lines (``1 2 3``, ``1,2,3``
    and one id per line are the same file); ``#`` starts a comment.  A line
    ``ID 0 0 0`` is a vertex point of the Blended Intrinsic Maps benchmark's
    ``.pid`` files and gives ``ID``; a ``.pid`` point inside a triangle (fractional
    barycentric coordinates) is refused.  Nothing is dropped: fractional,
    negative, huge, repeated or non-numeric ids, binary content, an empty file,
    a file that is not a regular file (FIFO, device) and files larger than
    ``MAX_ID_FILE_BYTES`` are refused, naming the file and line.
    """
    path = Path(path)
    label = name or path.name
    fd = open_regular(path)
    try:
        size = os.fstat(fd).st_size
        if size > MAX_ID_FILE_BYTES:
            raise InputError(f"{label}: {size / 2**20:.0f} MB is too large for a file of vertex ids "
                             f"(at most {MAX_ID_FILE_BYTES // 2**20} MB)")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            data = fh.read(MAX_ID_FILE_BYTES + 1)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from None
    finally:
        os.close(fd)
    if b"\0" in data:
        raise InputError(f"{label}: binary data, not a text file of vertex ids")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{label}: not UTF-8 text, expected vertex ids") from None
    ids = []
    for k, line in enumerate(text.splitlines(), 1):
        ids += _line_ids(_id_tokens(line), f"{label}:{k}")
    if not ids:
        raise InputError(f"{label}: no vertex ids found")
    return check_ids(ids, label)


def parse_ids(spec, name: str = "landmarks") -> list[int]:
    """Vertex ids from ``"3,5,9"`` (or ``"3 5 9"``), the path of a file of ids, or a sequence of ints.

    ``None`` and ``""`` give ``[]``.  A string naming an existing file is read with
    :func:`read_ids`.
    """
    if spec is None:
        return []
    if isinstance(spec, Path):
        return read_ids(spec)
    if not isinstance(spec, str):
        if isinstance(spec, numbers.Integral):
            return check_ids([spec], name)
        try:
            return check_ids(list(spec), name)
        except TypeError:
            raise InputError(f"{name} must be vertex ids, got {_fmt(spec)}") from None
    text = spec.strip()
    if not text:
        return []
    if len(text) < 4096 and os.path.lexists(text) and not os.path.isdir(text):
        return read_ids(text)
    ids = []
    for tok in _id_tokens(text):
        try:
            ids.append(_id_value(tok, name))
        except InputError:
            raise InputError(f"{name}: {_fmt(tok)} is not a vertex id "
                             "(expected e.g. 12,405,877 or a file of ids)") from None
    return check_ids(ids, name)


# --- files -----------------------------------------------------------------------------

def _kind_problem(mode: int) -> str | None:
    """Why a file of this ``st_mode`` is not a regular file (None if it is one)."""
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "is a folder, not a file"
    if stat.S_ISFIFO(mode):
        return "is a FIFO (named pipe), not a regular file"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "is a device, not a regular file"
    if stat.S_ISSOCK(mode):
        return "is a socket, not a regular file"
    return "is a symbolic link, which shapecond does not follow here"


def open_regular(path, flags: int = os.O_RDONLY, *, follow_links: bool = True, create_mode: int = 0o644,
                 output: bool = False) -> int:
    """A descriptor of ``path`` opened with ``flags``, only if it is a regular file.

    A folder, FIFO, device or socket is refused before anything is read from or
    written to it: its kind is checked with ``stat`` before opening and with
    ``fstat`` on the descriptor, which is opened with ``O_NONBLOCK`` (a FIFO
    nobody writes to cannot make ``open`` block) and then made blocking.
    ``follow_links=False`` refuses a symbolic link (``O_NOFOLLOW``): shapecond's
    own files (batch tables, journals, locks, cache entries) are never reached
    through one.

    Parameters
    ----------
    path : str or path-like
    flags : ``os.open`` flags, e.g. ``os.O_RDONLY`` or ``os.O_RDWR | os.O_CREAT``.
    follow_links : open what a symbolic link points to (user inputs) or refuse the link.
    create_mode : permissions of a file that ``O_CREAT`` creates (before the umask).
    output : raise :class:`OutputError` ("cannot write") instead of :class:`InputError`.

    Returns
    -------
    int : the descriptor (blocking); the caller closes it.
    """
    error, verb = (OutputError, "write") if output else (InputError, "read")
    path = os.fspath(path)
    try:
        st = os.stat(path) if follow_links else os.lstat(path)
    except FileNotFoundError:
        st = None
        if os.path.islink(path):
            raise error(f"{path}: a symbolic link to a missing file ({os.readlink(path)})") from None
        if not flags & os.O_CREAT:
            raise error(f"{path}: no such file") from None
    except OSError as exc:
        raise error(f"{path}: cannot {verb} ({exc.strerror or exc})") from None
    problem = None if st is None else _kind_problem(st.st_mode)
    if problem:
        raise error(f"{path}: {problem}")
    nofollow = 0 if follow_links else getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0) | nofollow, create_mode)
    except OSError as exc:  # changed since the check: a link (ELOOP), a socket (ENXIO), a folder
        if exc.errno in (errno.ELOOP, errno.ENXIO, errno.EISDIR):
            raise error(f"{path}: not a regular file") from None
        raise error(f"{path}: cannot {verb} ({exc.strerror or exc})") from None
    problem = _kind_problem(os.fstat(fd).st_mode)
    if problem:
        os.close(fd)
        raise error(f"{path}: {problem}")
    os.set_blocking(fd, True)
    return fd


# --- distance matrices ---------------------------------------------------------------

#: Matrices that passed :func:`check_distance_matrix`, by id; they are read-only
#: copies owned here, so they cannot have changed since (searches re-check them
#: in O(1)).
_VALID: dict[int, weakref.ref] = {}


def _known_valid(D) -> bool:
    if not isinstance(D, np.ndarray) or D.flags.writeable or D.dtype != np.float64:
        return False
    base = D
    while base is not None:
        ref = _VALID.get(id(base))
        if ref is not None and ref() is base:
            # a leading principal block of a valid matrix (D[:k, :k]) is valid too
            return base is D or (D.ndim == 2 and D.shape[0] == D.shape[1] and D.strides == base.strides
                                 and D.__array_interface__["data"][0] == base.__array_interface__["data"][0])
        base = base.base if isinstance(base.base, np.ndarray) else None
    return False


def _remember(D: np.ndarray) -> np.ndarray:
    D.flags.writeable = False
    key = id(D)
    _VALID[key] = weakref.ref(D, lambda _, key=key: _VALID.pop(key, None))
    return D


def check_distance_matrix(D, name: str = "distance matrix", *, min_points: int = 2,
                          distinct: bool = False) -> np.ndarray:
    """A usable distance matrix: real, square, finite, non-negative, symmetric, zero diagonal.

    Symmetry and the diagonal are checked by :func:`scipy.spatial.distance.is_valid_dm`
    with tolerance ``DM_RTOL`` times the largest entry.  ``distinct`` also refuses
    two different points at distance 0.  Returns a read-only float64 copy
    symmetrised as (D + Dᵀ)/2 with an exactly zero diagonal; passing that copy
    again is checked in O(1).
    """
    if _known_valid(D):
        return D
    arr = np.asarray(D)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1]:
        raise InputError(f"{name}: expected a square N x N matrix, got shape {arr.shape}")
    if np.iscomplexobj(arr):
        raise InputError(f"{name}: complex entries; distances are real numbers")
    if not (np.issubdtype(arr.dtype, np.number) or arr.dtype == bool):
        raise InputError(f"{name}: entries are not numbers (dtype {arr.dtype})")
    n = arr.shape[0]
    if n < min_points:
        raise InputError(f"{name}: needs at least {min_points} points, got {n}")
    arr = np.array(arr, dtype=np.float64, order="C")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name}: contains NaN or infinite entries")
    if np.any(arr < 0):
        raise InputError(f"{name}: contains negative distances")
    scale = float(arr.max())
    if not scale > 0:
        raise InputError(f"{name}: all distances are zero (zero diameter)")
    if not is_valid_dm(arr, tol=DM_RTOL * scale):
        if np.max(np.abs(np.diag(arr))) > DM_RTOL * scale:
            raise InputError(f"{name}: has a non-zero diagonal")
        raise InputError(f"{name}: is not symmetric")
    if distinct and np.min(arr + np.eye(n) * scale) <= 0:
        raise InputError(f"{name}: two distinct points are at distance zero")
    out = 0.5 * (arr + arr.T)
    np.fill_diagonal(out, 0.0)
    return _remember(out)


# --- point clouds --------------------------------------------------------------------

#: Singular values of the centred points below this fraction of the largest one
#: count as zero: a cloud must span a plane (two of them non-zero).
RANK_RTOL = 1e-5


def check_point_cloud(points, name: str = "point cloud", min_points: int = 3) -> np.ndarray:
    """Finite (n, 3) coordinates spanning at least a plane; ``InputError`` otherwise.

    Identical or collinear points have no surface to measure geodesics on (the
    point-cloud heat method fails on them inside geometry-central).
    """
    V = np.asarray(points)
    if np.iscomplexobj(V) or not np.issubdtype(V.dtype, np.number):
        raise InputError(f"{name}: coordinates must be real numbers")
    V = np.asarray(V, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise InputError(f"{name}: expected an (n, 3) array of points, got shape {V.shape}")
    if V.shape[0] < min_points:
        raise InputError(f"{name}: needs at least {min_points} points, got {V.shape[0]}")
    if not np.all(np.isfinite(V)):
        raise InputError(f"{name}: {int(np.sum(~np.all(np.isfinite(V), axis=1)))} points have NaN "
                         "or infinite coordinates")
    C = V - V.mean(axis=0)
    top = np.max(np.abs(C))
    s = np.linalg.svd(C / top, compute_uv=False) if top > 0 else np.zeros(3)
    if s[0] == 0 or s[1] <= RANK_RTOL * s[0]:
        what = "identical" if s[0] == 0 else "collinear"
        raise InputError(f"{name}: all {V.shape[0]} points are {what}; a shape needs points spanning a surface")
    return V
