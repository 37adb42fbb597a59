"""Cache entries are checked, never trusted; an unusable cache is a warning, never a failure."""

import json
import os
import warnings

import numpy as np
import pytest

from shapecond import cache
from shapecond.shapes.metric import metric_shape
from shapecond.shapes.synthetic import generate
from tests.conftest import run_cli


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path))
    return tmp_path


def _shape(**kw):
    return metric_shape(generate("blob", subdivisions=2), n_points=12, target="dense", target_factor=2, **kw)


def _only_entry(folder):
    (entry,) = [p for p in folder.iterdir() if p.name.startswith("metric-")]
    return entry


def test_an_entry_written_for_another_key_is_recomputed_not_used(folder):
    fresh = _shape()
    entry = _only_entry(folder)
    other = metric_shape(generate("blob", subdivisions=2, seed=3), n_points=12, target="dense", target_factor=2,
                         cache=False)
    with np.load(entry) as z:  # craft: another shape's content under this key, still a valid archive
        data = {k: z[k] for k in z.files}
    forged = dict(data, D=other.D, samples=other.samples)
    forged["__checksum__"] = np.array(cache._checksum({k: v for k, v in forged.items() if not k.startswith("__")}))
    forged["__key__"] = np.array("0" * 32)
    np.savez(entry, **forged)
    with pytest.warns(cache.CacheWarning, match="another input"):
        again = _shape()
    assert np.array_equal(again.D, fresh.D) and np.array_equal(again.samples, fresh.samples)


def test_an_edited_entry_fails_its_checksum_and_is_recomputed(folder):
    fresh = _shape()
    entry = _only_entry(folder)
    with np.load(entry) as z:
        data = {k: z[k] for k in z.files}
    D = data["D"].copy()
    D[1, 2] = D[2, 1] = 0.5 * D[1, 2]  # still a valid distance matrix, but not this shape's
    np.savez(entry, **dict(data, D=D))
    with pytest.warns(cache.CacheWarning, match="checksum"):
        again = _shape()
    assert np.array_equal(again.D, fresh.D)


def test_a_folder_at_the_entry_path_or_a_read_only_cache_only_warn(folder):
    fresh = _shape(cache=False)
    key_path = _only_entry(folder) if any(folder.iterdir()) else None
    assert key_path is None
    _shape()
    entry = _only_entry(folder)
    entry.unlink()
    entry.mkdir()  # a folder where the entry should be
    with pytest.warns(cache.CacheWarning):
        again = _shape()
    assert np.array_equal(again.D, fresh.D)
    entry.rmdir()
    os.chmod(folder, 0o500)
    try:
        if os.access(folder, os.W_OK):  # root ignores permissions: make the write fail another way
            entry.mkdir()
        with pytest.warns(cache.CacheWarning, match="not written|ignoring"):
            _shape()
    finally:
        os.chmod(folder, 0o700)


def test_an_edited_landmark_entry_is_recomputed(folder):
    key = "k" * 32
    cache.save_json("landmarks", key, {"cls": "x", "method": "fps", "vertices": [1, 2], "ids": [1, 2],
                                       "scores": {"1": "inf"}, "floor": {"1": 0.5}, "seconds": 1.0})
    assert cache.load_json("landmarks", key)["scores"] == {"1": "inf"}
    path = folder / f"landmarks-{key}.json"
    entry = json.loads(path.read_text())
    entry["payload"]["vertices"] = [7, 8]
    path.write_text(json.dumps(entry))
    with pytest.warns(cache.CacheWarning, match="checksum"):
        assert cache.load_json("landmarks", key) is None


def test_cache_info_and_clear(folder, capsys):
    _shape()
    code, out, _ = run_cli(capsys, "cache", "info", "--json")
    report = json.loads(out)
    assert code == 0 and report["folder"] == str(folder) and report["entries"] == 1
    assert report["kinds"]["metric"]["bytes"] > 0
    code, out, _ = run_cli(capsys, "cache", "clear")
    assert code == 0 and "removed 1 entries" in out and list(folder.iterdir()) == []


def test_the_default_folder_is_the_platform_cache_folder(monkeypatch):
    import platformdirs

    monkeypatch.delenv("SHAPECOND_CACHE", raising=False)
    assert str(cache.cache_dir()) == platformdirs.user_cache_dir("shapecond", appauthor=False)


def test_no_warning_for_a_healthy_cache(folder):
    _shape()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _shape()


def test_integer_keys_survive_the_checksum(folder, recwarn):
    """JSON turns {1: .., 3: .., 10: ..} into string keys, which sort differently: still the same entry."""
    payload = {"scores": {1: 0.5, 3: 0.25, 10: "inf"}}
    cache.save_json("landmarks", "k10", payload)
    assert cache.load_json("landmarks", "k10") == {"scores": {"1": 0.5, "3": 0.25, "10": "inf"}}
    assert not [w for w in recwarn if issubclass(w.category, cache.CacheWarning)]
