"""Test-wide settings: a private distance cache per test session.  Shared helpers are in ``tests/helpers.py``."""

import os
import tempfile

os.environ.setdefault("SHAPECOND_CACHE", tempfile.mkdtemp(prefix="shapecond-test-cache-"))
