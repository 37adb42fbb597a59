"""``.vts`` ground-truth files: 1-based ids, read strictly."""

import numpy as np
import pytest

from shapecond.errors import InputError
from shapecond.shapes.vts import read_vts


def _write(tmp_path, text, name="a.vts"):
    p = tmp_path / name
    p.write_bytes(text) if isinstance(text, bytes) else p.write_text(text, encoding="utf-8")
    return p


def test_ids_are_made_zero_based_and_may_repeat(tmp_path):
    ids = read_vts(_write(tmp_path, "5\n1\n5\n\n2\n"), n_vertices=5)
    np.testing.assert_array_equal(ids, [4, 0, 4, 1])


@pytest.mark.parametrize("text, message", [
    ("1\n0\n2\n", "1-based"),
    ("1\n7\n", "out of range"),
    ("1 2\n3\n", "one positive integer"),
    ("1,2\n", "one positive integer"),
    ("1\n2.0\n", "one positive integer"),
    ("1\n-2\n", "one positive integer"),
    ("", "empty"),
    ("\n\n", "no reference points"),
    (b"\x00\x01\x02", "binary"),
    ("1\n99999999999999999999999\n", "out of range"),  # was an OverflowError (exit 1)
    ("1\n\u00b2\n", "one positive integer"),           # '²' passed isdigit(): a ValueError (exit 1)
])
def test_bad_files_are_one_input_error(tmp_path, text, message):
    with pytest.raises(InputError, match=message):
        read_vts(_write(tmp_path, text), n_vertices=6)
