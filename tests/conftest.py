"""Test-wide settings: a private distance cache per test session, removed when the session ends
(only when this file created it: a ``$SHAPECOND_CACHE`` set by the caller is left alone).  Shared
helpers are in ``tests/helpers.py``."""

import atexit
import os
import shutil
import tempfile

if "SHAPECOND_CACHE" not in os.environ:
    _session_cache = tempfile.mkdtemp(prefix="shapecond-test-cache-")
    os.environ["SHAPECOND_CACHE"] = _session_cache
    # atexit, not a session fixture: child processes the tests start inherit the variable and may
    # still be writing to the folder while fixtures are torn down
    atexit.register(shutil.rmtree, _session_cache, ignore_errors=True)
