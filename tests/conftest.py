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


def deadline(seconds: float):
    """Context manager: raise ``TimeoutError`` in the main thread if the block runs longer than
    ``seconds`` (a hang becomes a failure; a blocking ``open`` or ``read`` is interrupted too)."""
    import contextlib
    import signal

    @contextlib.contextmanager
    def guard():
        def expire(signum, frame):
            raise TimeoutError(f"still running after {seconds} s")

        previous = signal.signal(signal.SIGALRM, expire)
        signal.setitimer(signal.ITIMER_REAL, seconds)
        try:
            yield
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)

    return guard()


def run_shapecond(*argv, timeout: float = 10, env=None, **kw):
    """Run ``python -m shapecond ARGV`` in a child process that is killed after ``timeout`` seconds
    (``subprocess.TimeoutExpired``: a hang fails the test instead of stalling it, even when a thread
    is stuck); return (exit status, stdout, stderr)."""
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "shapecond", *map(str, argv)], capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL, env=env, **kw)
    return proc.returncode, proc.stdout, proc.stderr
