"""Shared fixtures of the picture tests: a headless Chromium for the HTML pages."""

import shutil
import tempfile

import pytest

CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--proxy-server=127.0.0.1:9", "--proxy-bypass-list=<-loopback>"]


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    return None


@pytest.fixture(scope="module")
def browser():
    """A headless Chromium context (the system's browser driven by playwright), offline."""
    sync = pytest.importorskip("playwright.sync_api", reason="playwright is not installed (the 'test' extra)")
    exe = _chromium()
    if exe is None:
        pytest.skip("no Chromium on this machine (apt-get install chromium)")
    with sync.sync_playwright() as p:
        with tempfile.TemporaryDirectory() as profile:
            ctx = p.chromium.launch_persistent_context(profile, executable_path=exe, args=CHROMIUM_ARGS,
                                                       headless=True, viewport={"width": 1100, "height": 800})
            yield ctx
            ctx.close()
