"""Shape-space exploration on a local Dask cluster: variants written as files, reproducible
from their seed, equal to the in-process loop, and replayable as edit scripts."""

import json

import numpy as np
import pytest

import cagerig
from cagerig import shape_space
from conftest import ARM

distributed = pytest.importorskip("distributed")


def test_random_scripts_are_deterministic_and_within_bounds(arm):
    bounds = shape_space.Bounds(joint_edits=4, max_degrees=20, cage_edits=3, cage_neighbours=4)
    a = shape_space.random_script(arm, 7, bounds)
    assert a == shape_space.random_script(arm, 7, bounds)
    assert a != shape_space.random_script(arm, 8, bounds)
    rotations = [s for s in a["steps"] if s["op"] == "rotate_joint"]
    moves = [s for s in a["steps"] if s["op"] == "move_rest_cage"]
    assert len(rotations) == 4 and len(moves) == 12
    assert all(abs(s["degrees"]) <= 20 for s in rotations)
    diag = np.linalg.norm(np.ptp(arm.rest_cage, axis=0))
    assert all(np.linalg.norm(s["offset"]) <= bounds.max_inflation * diag + 1e-12 for s in moves)


def test_variants_on_a_local_dask_cluster_equal_the_local_loop(tmp_path):
    source = str(ARM)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        remote = shape_space.explore(source, 6, str(tmp_path / "dask"), client=client, batch=2)
    local = shape_space.explore(source, 6, str(tmp_path / "local"))
    assert [r["seed"] for r in remote] == list(range(6))
    for r, l in zip(remote, local):
        for fr, fl in zip(r["files"][:2], l["files"][:2]):
            np.testing.assert_array_equal(cagerig.read_obj(fr)[0], cagerig.read_obj(fl)[0])
    # A variant's JSON is an edit script: replaying it on the loaded rig gives the variant.
    meta = json.loads(open(remote[3]["files"][2]).read())
    rig = cagerig.Rig.load(ARM)
    rig.run_script({"steps": meta["steps"]})
    np.testing.assert_array_equal(rig.posed_mesh, cagerig.read_obj(remote[3]["files"][0])[0])
    # Variants differ from each other and from the loaded arm.
    first, second = (cagerig.read_obj(r["files"][0])[0] for r in remote[:2])
    assert np.abs(first - second).max() > 1.0
