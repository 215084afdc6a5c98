"""Bad inputs raise clear Python exceptions naming the argument, never crash."""

import numpy as np
import pytest

import cagerig


def cube():
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, f


@pytest.mark.parametrize(
    "points, exc, match",
    [
        (np.zeros((4, 2)), ValueError, r"points must have shape \(n, 3\), got \(4, 2\)"),
        (np.zeros(3), ValueError, r"shape \(n, 3\), got \(3,\)"),
        (np.array([[0.5, np.nan, 0.5]]), ValueError, r"points\[0, 1\] is NaN"),
        (np.array([[0.5, np.inf, 0.5]]), ValueError, r"points\[0, 1\] is inf"),
        (np.zeros((2, 3), dtype=complex), TypeError, "real-valued"),
        (np.array([["a", "b", "c"]]), TypeError, "real-valued"),
        (np.zeros((2, 3), dtype=bool), TypeError, "real-valued"),
        ([[0, 0], [1]], TypeError, "cannot be read as an array"),
        ("points", TypeError, "real-valued"),
    ],
)
def test_bad_points(points, exc, match):
    v, f = cube()
    with pytest.raises(exc, match=match):
        cagerig.mvc(points, v, f)


def test_bad_triangles():
    v, f = cube()
    with pytest.raises(TypeError, match="cage_triangles must be an integer array, got dtype float64"):
        cagerig.mvc(v, v, f.astype(float))
    with pytest.raises(IndexError, match=r"cage_triangles\[0, 0\] = 8 is out of range \(there are 8 vertices\)"):
        cagerig.mvc(v, v, f + 8)
    with pytest.raises(IndexError, match="-1 is out of range"):
        cagerig.mvc(v, v, f - 1)
    with pytest.raises(ValueError, match=r"shape \(m, 3\)"):
        cagerig.mvc(v, v, f[:, :2])
    with pytest.raises(cagerig.RigError, match="no triangles"):
        cagerig.mvc(v, v, np.zeros((0, 3), dtype=int))


def test_bad_skinning_inputs():
    v, _ = cube()
    w = np.full((8, 2), 0.5)
    t = np.repeat(np.eye(4)[None], 2, axis=0)
    with pytest.raises(ValueError, match="one matrix per joint"):
        cagerig.lbs(v, w, t[:1])
    with pytest.raises(ValueError, match=r"one row per vertex \(8 rows\), got 7"):
        cagerig.lbs(v, w[:7], t)
    with pytest.raises(ValueError, match=r"shape \(J, 4, 4\) or \(J, 3, 4\)"):
        cagerig.lbs(v, w, np.eye(4))
    bad = t.copy()
    bad[1, 3, 3] = 2
    with pytest.raises(ValueError, match=r"transforms\[1\] is not affine"):
        cagerig.lbs(v, w, bad)
    scaled = t.copy()
    scaled[0, 0, 0] = 2
    cagerig.lbs(v, w, scaled)  # LBS takes any affine transform
    with pytest.raises(ValueError, match="rigid"):
        cagerig.dqs(v, w, scaled)
    with pytest.raises(cagerig.RigError, match="must be finite, non-negative"):
        cagerig.lbs(v, -w, t)
    with pytest.warns(cagerig.RigWarning, match="renormalised"):
        cagerig.lbs(v, w * 0.9, t)
    with pytest.raises(ValueError, match="centres must have one row per vertex"):
        cagerig.cor(v, w, t, v[:3])
    with pytest.raises(ValueError, match="sigma"):
        cagerig.cor_centres(v, cube()[1], w, sigma=-1)


def test_bad_rig_edits(arm):
    with pytest.raises(IndexError, match=r"indices\[1\] = 58 is out of range \(there are 58 cage vertices\)"):
        arm.move_rest_cage([0, 58], [1, 0, 0])
    with pytest.raises(IndexError, match="-1 is out of range"):
        arm.move_posed_cage(-1, [1, 0, 0])
    with pytest.raises(TypeError, match="integer array"):
        arm.move_rest_cage([0.5], [1, 0, 0])
    with pytest.raises(ValueError, match=r"offsets\[1\] is NaN"):
        arm.move_rest_cage([0], [0, np.nan, 0])
    with pytest.raises(ValueError, match=r"shape \(3,\) or \(2, 3\)"):
        arm.move_rest_cage([0, 1], np.zeros((3, 3)))
    with pytest.raises(ValueError, match="no cage vertex"):
        arm.move_rest_cage([], [1, 0, 0])
    with pytest.raises(ValueError, match='unknown joint "elbow.L"'):
        arm.rotate_joint("elbow.L", [1, 0, 0], 10)
    with pytest.raises(IndexError, match="joint 25 is out of range"):
        arm.rotate_joint(25, [1, 0, 0], 10)
    with pytest.raises(TypeError, match="joint name"):
        arm.rotate_joint(1.5, [1, 0, 0], 10)
    with pytest.raises(ValueError, match="non-zero"):
        arm.rotate_joint(3, [0, 0, 0], 10)
    with pytest.raises(ValueError, match="finite"):
        arm.rotate_joint(3, [1, 0, 0], float("nan"))
    with pytest.raises(ValueError, match=r"axis must have shape \(3,\)"):
        arm.rotate_joint(3, [1, 0], 10)
    with pytest.raises(
        ValueError,
        match='skinning: unknown skinning method "quaternions": expected lbs, dqs, cor or blended',
    ):
        arm.set_skinning("quaternions")
    with pytest.raises(ValueError, match=r"local_rotations must have shape \(25, 4\)"):
        arm.set_pose(np.zeros((24, 4)))
    with pytest.raises(ValueError, match="zero quaternion"):
        arm.set_pose(np.zeros((25, 4)))
    with pytest.raises(ValueError, match="no animation attached"):
        arm.sample_animation(1.0)
    with pytest.raises(ValueError, match="what must be"):
        arm.export_obj("/tmp/x.obj", what="skeleton")
    # Nothing above changed the rig.
    np.testing.assert_array_equal(arm.rest_cage, arm.original_rest_cage)


def test_bad_scripts(arm):
    with pytest.raises(cagerig.ScriptError, match="step 2"):
        cagerig.EditScript({"steps": [{"op": "reset_pose"}, {"op": "explode"}]})
    script = cagerig.EditScript({"steps": [{"op": "move_rest_cage", "vertices": [999], "offset": [1, 0, 0]}]})
    with pytest.raises(cagerig.ScriptError, match="step 1: .*cage vertex 999 is out of range"):
        arm.run_script(script)
    with pytest.raises(cagerig.ScriptError, match="not valid JSON"):
        cagerig.EditScript("{nope")
    with pytest.raises(FileNotFoundError):
        cagerig.EditScript("/nonexistent/script.json")
    with pytest.raises(IndexError, match="step index 3"):
        cagerig.EditScript({"steps": []}).run_step(arm, 3)
    np.testing.assert_array_equal(arm.rest_cage, arm.original_rest_cage)


def test_bad_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="nonexistent"):
        cagerig.Rig.load(tmp_path / "nonexistent.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 x\n")
    with pytest.raises(cagerig.RigFileError, match=r"bad.obj:2"):
        cagerig.read_obj(bad)
    lonely = tmp_path / "lonely.obj"
    lonely.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(FileNotFoundError, match="no skeleton found"):
        cagerig.Rig.load(lonely)
    with pytest.raises(ValueError, match=r"fit_rows: unknown fit rows \"some\": expected maxvol or all"):
        cagerig.Rig.load(lonely, fit_rows="some")


def test_outputs_create_missing_folders_and_name_a_file_in_the_way(tmp_path):
    v, f = cube()
    nested = tmp_path / "new" / "deeper" / "cube.obj"
    cagerig.write_obj(nested, v, f)
    assert nested.is_file()
    blocker = tmp_path / "blocker"
    blocker.write_text("a file")
    with pytest.raises(NotADirectoryError, match=f"{blocker} is a file, not a folder"):
        cagerig.write_obj(blocker / "cube.obj", v, f)
    rig = cagerig.Rig.builtin("bar")
    with pytest.raises(NotADirectoryError, match=f"{blocker} is a file, not a folder"):
        rig.save(blocker / "out", "state")
