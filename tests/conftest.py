"""Test-wide settings: a private distance cache per test session."""

import os
import tempfile

os.environ.setdefault("SHAPECOND_CACHE", tempfile.mkdtemp(prefix="shapecond-test-cache-"))
