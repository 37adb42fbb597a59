"""Where numba keeps the compiled kernels between processes.

Every numba kernel of shapecond is compiled with ``cache=True``: the first
process on a machine compiles them and writes the machine code to disk; later
processes load it instead of compiling.  numba writes next to the
sources (``__pycache__`` in the installed package) or, when that folder is
read-only, under the user's cache folder (``~/.cache/numba``); when neither is
writable it refuses to import a ``cache=True`` function at all.  So, unless
the user chose ``NUMBA_CACHE_DIR``, a read-only package folder sends numba to
``<shapecond cache folder>/numba`` (``$SHAPECOND_CACHE`` or
``~/.cache/shapecond``) or, failing that, to a per-user folder in the system's
temporary directory.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path


def _writable(folder: Path) -> bool:
    """numba's own test: the folder can be created and a file written in it."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
        return True
    except OSError:
        return False


def ensure_writable_cache() -> None:
    """Set ``NUMBA_CACHE_DIR`` when numba could not cache next to the package's sources."""
    if os.environ.get("NUMBA_CACHE_DIR") or _writable(Path(__file__).parent / "shapes" / "__pycache__"):
        return
    from .cache import cache_dir

    uid = os.getuid() if hasattr(os, "getuid") else os.getpid()
    folders = [Path(tempfile.gettempdir()) / f"shapecond-numba-{uid}"]
    try:
        folders.insert(0, cache_dir() / "numba")
    except RuntimeError:  # no home folder
        pass
    for folder in folders:
        if _writable(folder):
            os.environ["NUMBA_CACHE_DIR"] = str(folder)
            if "numba" in sys.modules:  # numba read its configuration already
                sys.modules["numba"].config.CACHE_DIR = str(folder)
            return
