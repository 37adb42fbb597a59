"""Cache entries are checked, never trusted; an unusable cache is a warning, never a failure."""

import hashlib
import json
import os
import stat
import warnings

import numpy as np
import pytest

from shapecond import cache
from shapecond.shapes.metric import Sampling, build_metric_shape
from shapecond.shapes.synthetic import generate
from tests.helpers import deadline, run_cli


@pytest.fixture
def folder(tmp_path, monkeypatch):
    monkeypatch.setenv("SHAPECOND_CACHE", str(tmp_path))
    return tmp_path


def _shape(**kw):
    return build_metric_shape(generate("blob", {"subdivisions": 2}), n_points=12,
                              sampling=Sampling(target="dense", target_factor=2, **kw))


def _only_entry(folder):
    (entry,) = [p for p in folder.iterdir() if p.name.startswith("metric-")]
    return entry


def test_an_entry_written_for_another_key_is_recomputed_not_used(folder):
    fresh = _shape()
    entry = _only_entry(folder)
    other = build_metric_shape(generate("blob", {"subdivisions": 2, "seed": 3}), n_points=12, sampling=Sampling(target="dense", target_factor=2, cache=False))
    with np.load(entry) as z:  # craft: another shape's content under this key, still a valid archive
        data = {k: z[k] for k in z.files}
    forged = dict(data, D=other.D, samples=other.samples)
    content = {k: v for k, v in forged.items() if not k.startswith("__")}
    forged["__tag__"] = np.array(cache._tag("0" * 32, content, cache.cache_secret()))  # valid for its own key
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


def _forge(entry, D, samples, tag):
    """Rewrite ``entry`` with another matrix and samples and the given checksum (a tampering user)."""
    with np.load(entry) as z:
        data = {k: z[k] for k in z.files}
    np.savez(entry, **dict(data, D=D, samples=samples, __tag__=np.array(tag)))


def test_an_entry_rewritten_with_a_recomputed_plain_checksum_is_recomputed_not_used(folder):
    """The audit's case: another shape's content under this key with an unkeyed SHA-256 recomputed
    (what the checksum was) changed σ and shifted every sample id, exit 0."""
    fresh = _shape()
    entry = _only_entry(folder)
    other = build_metric_shape(generate("blob", {"subdivisions": 2, "seed": 3}), n_points=12, sampling=Sampling(target="dense", target_factor=2, cache=False))
    with np.load(entry) as z:
        content = {k: z[k] for k in z.files if not k.startswith("__")}
    content.update(D=other.D, samples=other.samples)
    h = hashlib.sha256()
    for name in sorted(content):
        a = np.ascontiguousarray(content[name])
        h.update(f"{name}{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    _forge(entry, other.D, other.samples, h.hexdigest())
    with pytest.warns(cache.CacheWarning, match="keyed checksum"):
        again = _shape()
    assert np.array_equal(again.D, fresh.D) and np.array_equal(again.samples, fresh.samples)
    # a keyed checksum made with another secret (an entry copied from another user's cache) fails too
    _forge(_only_entry(folder), other.D, other.samples, cache._tag(entry.name[7:-4], content, b"x" * 32))
    with pytest.warns(cache.CacheWarning, match="keyed checksum"):
        assert np.array_equal(_shape().samples, fresh.samples)


def test_the_secret_is_private_and_a_secret_that_is_not_disables_the_cache(folder):
    _shape()
    secret = folder / cache.SECRET_NAME
    assert stat.S_IMODE(secret.stat().st_mode) == 0o600 and len(secret.read_bytes()) == cache.SECRET_BYTES
    secret.chmod(0o644)  # readable by others: whoever reads it can forge entries
    with pytest.warns(cache.CacheWarning, match="may be read by others"):
        _shape()
    secret.chmod(0o600)
    real = folder / "elsewhere"
    os.replace(secret, real)
    secret.symlink_to(real)  # a planted link is not followed
    with pytest.warns(cache.CacheWarning, match="symbolic link"):
        _shape()
    secret.unlink()
    os.replace(real, secret)
    if os.geteuid() == 0:  # root can give it away: a secret of another user is not ours
        os.chown(secret, 65534, 65534)
        with pytest.warns(cache.CacheWarning, match="another user"):
            _shape()


def test_a_fifo_planted_at_an_entry_is_skipped_without_blocking(folder):
    fresh = _shape()
    entry = _only_entry(folder)
    entry.unlink()
    os.mkfifo(entry)
    with deadline(10), pytest.warns(cache.CacheWarning, match="FIFO"):
        again = _shape()
    assert np.array_equal(again.D, fresh.D)
    key = "j" * 32
    os.mkfifo(folder / f"landmarks-{key}.json")
    with deadline(10), pytest.warns(cache.CacheWarning, match="FIFO"):
        assert cache.load_json("landmarks", key) is None


def test_clear_removes_only_the_caches_own_files(folder, capsys):
    """Any *-*.json / *-*.npz counted as an entry: a user's files in the folder were deleted."""
    _shape()
    (entry,) = cache.entries()
    planted = {"my-notes.json": b'{"note": 1}', "report-final.json": b'{"key": "x", "tag": "y", "payload": 1}'}
    for name, data in planted.items():
        (folder / name).write_bytes(data)
    np.savez(folder / "scan-01.npz", V=np.zeros((3, 3)))
    forged = folder / f"metric-{'0' * 32}.npz"  # named like an entry, but not one
    np.savez(forged, D=np.zeros(2))
    (folder / "notes.txt").write_text("keep me\n")
    os.symlink(entry, folder / f"metric-{'1' * 32}.npz")  # a link named like an entry
    code, out, _ = run_cli(capsys, "cache", "info", "--json")
    report = json.loads(out)
    assert report["entries"] == 1 and report["other_files"] == 6
    code, out, err = run_cli(capsys, "cache", "clear")
    assert code == 0 and "removed 1 entries" in out and "kept 6 files" in err
    assert sorted(p.name for p in folder.iterdir()) == sorted(
        ["my-notes.json", "report-final.json", "scan-01.npz", forged.name, "notes.txt", f"metric-{'1' * 32}.npz"])
    assert (folder / "my-notes.json").read_bytes() == planted["my-notes.json"]


def test_clear_keeps_a_file_at_the_secrets_name_that_is_not_a_secret(folder, capsys):
    (folder / ".secret").write_text("my password list\n")
    code, out, err = run_cli(capsys, "cache", "clear")
    assert code == 0 and (folder / ".secret").read_text() == "my password list\n" and "kept 1 files" in err


def test_keys_and_checksums_hash_the_arrays_bytes_as_before():
    """Arrays are hashed through their buffers, not copies: the same digests as of ``tobytes()``, so
    the entries of earlier versions keep their keys and checksums."""
    arrays = {"rows": np.arange(12, dtype=np.float32).reshape(3, 4), "unit": np.array(1.5),
              "flags": np.array([True, False]), "name": np.array("abc"), "F": np.asfortranarray(np.eye(3))}
    h = hashlib.sha256(cache.FORMAT.encode())
    for a in arrays.values():
        a = np.ascontiguousarray(a)
        h.update(f"array{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    assert cache.key_of(*arrays.values()) == h.hexdigest()[:32]
    import hmac
    secret = b"s" * 32
    t = hmac.new(secret, f"{cache.FORMAT}:key".encode(), hashlib.sha256)
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        t.update(f"{name}{a.dtype.str}{a.shape}".encode())
        t.update(a.tobytes())
    assert cache._tag("key", arrays, secret) == t.hexdigest()
