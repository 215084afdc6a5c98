"""`cagerig.save_state`: one state's five files written as a set into a folder that may hold
other things; a failure leaves the earlier state with that prefix as it was."""

import json

import numpy as np
import pytest

import cagerig
import cagerig.states

NAMES = ("mesh_rest.obj", "mesh_posed.obj", "cage_rest.obj", "cage_posed.obj", "joints.json")


def test_states_accumulate_beside_other_files_and_read_back(arm, tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    first = cagerig.save_state(arm, tmp_path, "step0")
    arm.rotate_joint("lowerarm01.R", [1, 0, 0], 30)
    second = cagerig.save_state(arm, tmp_path, "step1")
    assert [p.name for p in first] == [f"step0_{n}" for n in NAMES]
    assert [p.name for p in second] == [f"step1_{n}" for n in NAMES]
    assert (tmp_path / "notes.txt").read_text() == "mine"
    posed, _ = cagerig.read_obj(tmp_path / "step1_mesh_posed.obj")
    np.testing.assert_array_equal(posed, arm.posed_mesh)
    joints = json.loads((tmp_path / "step1_joints.json").read_text())
    assert [j["name"] for j in joints] == list(arm.joint_names)
    # No temporary file is left.
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


def test_a_failure_while_writing_leaves_the_earlier_state_whole(arm, tmp_path, monkeypatch):
    cagerig.save_state(arm, tmp_path, "pose")
    before = {n: (tmp_path / f"pose_{n}").read_bytes() for n in NAMES}
    arm.rotate_joint("lowerarm01.R", [1, 0, 0], 45)
    calls = []
    real = cagerig.states.write_obj

    def failing_third(path, *arrays):
        calls.append(path)
        if len(calls) == 3:
            raise OSError(28, "No space left on device", str(path))
        real(path, *arrays)

    monkeypatch.setattr(cagerig.states, "write_obj", failing_third)
    with pytest.raises(OSError, match="No space left"):
        cagerig.save_state(arm, tmp_path, "pose")
    after = {n: (tmp_path / f"pose_{n}").read_bytes() for n in NAMES}
    assert after == before, "a failed save changed the earlier state"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"pose_{n}" for n in NAMES)


def test_a_directory_in_the_way_or_a_path_prefix_is_refused_before_writing(arm, tmp_path):
    (tmp_path / "x_joints.json").mkdir()
    with pytest.raises(IsADirectoryError, match="x_joints.json"):
        cagerig.save_state(arm, tmp_path, "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x_joints.json"]
    for bad in ("", "../up", "a/b", ".hidden"):
        with pytest.raises(ValueError, match="prefix"):
            cagerig.save_state(arm, tmp_path, bad)
