"""Where numba's compiled kernels go when the package folder is read-only (shapecond._jit_cache)."""

from pathlib import Path

from shapecond import _jit_cache


def test_read_only_package_sends_numba_to_the_shapecond_cache(monkeypatch, tmp_path):
    import numba

    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)  # restored afterwards
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path / "cache"))
    package = Path(_jit_cache.__file__).parent
    real = _jit_cache._writable
    monkeypatch.setattr(_jit_cache, "_writable", lambda folder: False if package in folder.parents else real(folder))
    _jit_cache.ensure_writable_cache()
    assert Path(_jit_cache.os.environ["NUMBA_CACHE_DIR"]) == tmp_path / "cache" / "numba"
    assert (tmp_path / "cache" / "numba").is_dir()
    assert numba.config.CACHE_DIR == str(tmp_path / "cache" / "numba")  # numba was imported already


def test_nothing_changes_when_numba_can_cache_next_to_the_sources(monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setattr(_jit_cache, "_writable", lambda folder: True)
    _jit_cache.ensure_writable_cache()
    assert "NUMBA_CACHE_DIR" not in _jit_cache.os.environ


def test_the_users_choice_is_kept(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_jit_cache, "_writable", lambda folder: False)
    _jit_cache.ensure_writable_cache()
    assert _jit_cache.os.environ["NUMBA_CACHE_DIR"] == str(tmp_path)
