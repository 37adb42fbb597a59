"""``shapecond batch`` among hostile files: FIFOs, devices and dangling links as inputs; links, FIFOs,
foreign files, a read-only folder and a full disk at the output.  Every case ends within 10 s, exits 2
with one line (or gives error rows, exit 3, for bad inputs) and leaves every file that is not the
batch's own exactly as it was."""

import os

from tests.batch.test_batch import read_table
from tests.conftest import run_shapecond


def test_fifos_devices_and_dangling_links_among_the_inputs_are_error_rows_not_hangs(tmp_path):
    fifo = tmp_path / "pipe.off"
    os.mkfifo(fifo)
    dangling = tmp_path / "gone.off"
    dangling.symlink_to(tmp_path / "no-such-target.off")
    status, _, err = run_shapecond("batch", fifo, "/dev/zero", dangling, "--points", 12, "--out", tmp_path / "t.jsonl")
    assert status == 3, err
    rows = {r["file"]: r["error"] for r in read_table(tmp_path / "t.jsonl")}
    assert "is a FIFO" in rows[str(fifo)] and "is a device" in rows["/dev/zero"]
    assert "a symbolic link to a missing file" in rows[str(dangling)]
    assert not any("on worker" in e for e in rows.values())  # this process could not read them either
