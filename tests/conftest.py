"""Test-wide settings: a private distance cache per test session."""

import os
import tempfile

os.environ.setdefault("SHAPECOND_CACHE", tempfile.mkdtemp(prefix="shapecond-test-cache-"))


def run_cli(capsys, *argv):
    """Run ``shapecond ARGV`` in-process; return (exit status, stdout, stderr)."""
    import pytest

    from shapecond.cli import main

    with pytest.raises(SystemExit) as exit_info:
        main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return exit_info.value.code, out, err
