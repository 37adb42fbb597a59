"""The OFF reader: plain files parsed in numpy, everything else line by line, the same arrays and errors."""

import numpy as np
import pytest

import shapecond.shapes.formats as formats
from shapecond.errors import InputError

PLAIN = ("OFF\n4 4 0\n0.0 0.0 0.0\n1.5 -2.0 1e-3\n0 1.0 +2.5E+2\n-0.25 .5 7.\n"
         "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")


def _read_both(path):
    """``read_off`` as it is, and with the numpy parse switched off."""
    fast = formats.read_off(path)
    plain, formats._plain_off = formats._plain_off, lambda text, name: None
    try:
        slow = formats.read_off(path)
    finally:
        formats._plain_off = plain
    return fast, slow


@pytest.mark.parametrize("text,plain", [
    (PLAIN, True),
    (PLAIN.replace("\n", "\r\n"), True),
    ("OFF 4 4 0\n" + PLAIN.split("\n", 2)[2], True),
    ("  OFF\n\n 4 4 0\n" + PLAIN.split("\n", 2)[2].replace(" ", " \t "), True),
    (PLAIN.replace("3 0 2 1", "3 0 2 1 # a comment"), False),
    (PLAIN.replace("3 0 2 1\n", "3 0 2 1\n\n"), False),
    (PLAIN.replace("3 0 2 1\n", "4 0 2 1 3\n"), False),  # a quad
    (PLAIN.replace("0.0 0.0 0.0\n", "0.0 0.0 0.0 255 0 0\n"), False),  # a colour
    (PLAIN.replace("0.0 0.0 0.0\n", "0.0 0.0\r0.0\n"), False),  # a bare carriage return: two lines
    (PLAIN.replace("3 0 2 1\n", "3 0 2 1\x0c"), False),
    (PLAIN.replace("-2.0", "-2.0e"), False),
])
def test_plain_files_are_parsed_in_numpy_to_the_arrays_of_the_line_reader(tmp_path, text, plain):
    path = tmp_path / "m.off"
    path.write_bytes(text.encode())
    assert (formats._plain_off(text, path.name) is not None) == plain
    try:
        (Vf, Ff), (Vs, Fs) = _read_both(path)
    except InputError as exc:  # the slow reader's error, when it refuses the file
        assert not plain
        with pytest.raises(InputError, match=str(exc).split(":")[-1].strip()[:20]):
            formats.read_off(path)
        return
    np.testing.assert_array_equal(Vf, Vs)
    np.testing.assert_array_equal(Ff, Fs)
    assert Vf.dtype == np.float64 and Ff.dtype == np.int64 and Ff.flags.c_contiguous


@pytest.mark.parametrize("edit,match", [
    (lambda t: t.replace("4 4 0", "4 5 0"), "truncated"),
    (lambda t: t + "3 0 1 2\n", "trailing data"),
    (lambda t: t.replace("3 0 2 1", "3 0 2 1.5"), "not a vertex index|not a number"),
    (lambda t: t.replace("3 0 2 1", "3 0 2 99999999999999999999999"), "not a number"),
    (lambda t: t.replace("1.5 -2.0", "1.5 -2-0"), "not a number"),
])
def test_a_broken_plain_file_gets_the_line_readers_error(tmp_path, edit, match):
    path = tmp_path / "m.off"
    path.write_text(edit(PLAIN))
    with pytest.raises(InputError, match=match):
        formats.read_off(path)
