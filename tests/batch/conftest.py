"""Shared fixtures of the batch tests: small shape files and one 2-worker Dask cluster."""

import numpy as np
import pytest

from shapecond.shapes.io import write_mesh
from shapecond.shapes.synthetic import bumpy_blob, sphere


@pytest.fixture(scope="session")
def shape_dir(tmp_path_factory):
    """Three small asymmetric blobs and a sphere (162-642 vertices), one in a sub-folder."""
    root = tmp_path_factory.mktemp("shapes")
    (root / "sub").mkdir()
    for k in range(3):
        g = bumpy_blob(subdivisions=2, seed=k + 1)
        write_mesh(root / f"blob{k}.off", g.vertices, g.faces)
    g = sphere(subdivisions=3)
    write_mesh(root / "sub" / "ball.off", g.vertices, g.faces)
    return root


@pytest.fixture(scope="session")
def broken_dir(tmp_path_factory):
    """One good mesh and every kind of bad input a collection can hold."""
    root = tmp_path_factory.mktemp("broken")
    g = bumpy_blob(subdivisions=2, seed=7)
    write_mesh(root / "good.off", g.vertices, g.faces)
    (root / "empty.off").write_text("")
    (root / "garbage.off").write_text("this is not a mesh\n")
    (root / "binary.ply").write_bytes(bytes(range(256)) * 4)
    np.save(root / "wrong_shape.npy", np.zeros((4, 5)))
    V = g.vertices.copy()
    V[3] = np.nan
    write_mesh(root / "nan.off", V, g.faces)
    two = np.vstack([g.vertices, g.vertices + [5.0, 0, 0]])
    write_mesh(root / "two_parts.off", two, np.vstack([g.faces, g.faces + len(g.vertices)]))
    (root / "dangling.off").symlink_to(root / "no-such-target.off")
    return root


@pytest.fixture(scope="session")
def dask_client():
    """A LocalCluster of 2 single-threaded worker processes on the loopback interface."""
    import dask
    from dask.distributed import Client, LocalCluster

    # a task that kills its worker fails after two deaths instead of four (faster test); one task
    # per worker at a time, so that no innocent task queued beside it is blamed as well
    with dask.config.set({"distributed.scheduler.allowed-failures": 1,
                          "distributed.scheduler.worker-saturation": 1.0}), \
            LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                         dashboard_address=":0") as cluster, Client(cluster) as client:
        yield client
