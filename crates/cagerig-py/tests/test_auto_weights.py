"""`cagerig.skin_weights` and `Rig.load(..., auto_weights=True)`: the invariants (rows sum to 1,
at most `max_influences`), an analytic two-bone bar, the same weights as `cagerig weights`, and
an OBJ rig with no `.skw` loaded with computed weights."""

import shutil

import numpy as np
import pytest

import cagerig
from conftest import ARM_DIR, read_triplets, run_cli


def bar(n=40, length=4.0, half=0.2):
    """A closed box [0, length] × [-half, half]² as rings of 4 vertices along x, plus end caps."""
    vertices, triangles = [], []
    for s in range(n + 1):
        x = length * s / n
        vertices += [[x, -half, -half], [x, half, -half], [x, half, half], [x, -half, half]]
    for s in range(n):
        for k in range(4):
            a, b = 4 * s + k, 4 * s + (k + 1) % 4
            triangles += [[a, a + 4, b + 4], [a, b + 4, b]]
    triangles += [[0, 2, 1], [0, 3, 2]]
    e = 4 * n
    triangles += [[e, e + 1, e + 2], [e, e + 2, e + 3]]
    return np.array(vertices, float), np.array(triangles)


def check_rows(w, k):
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=1e-12)
    assert (w >= 0).all()
    assert ((w > 0).sum(axis=1) <= k).all()
    assert ((w > 0).sum(axis=1) >= 1).all()


def test_two_bone_bar_follows_the_nearest_bone():
    v, f = bar()
    joints = [[0, 0, 0], [2, 0, 0], [4, 0, 0]]
    w = cagerig.skin_weights(v, f, joints, [-1, 0, 1], joint_names=["a", "b", "b_end"])
    assert w.shape == (len(v), 3)
    check_rows(w, 4)
    np.testing.assert_array_equal(w[:, 2], 0.0)  # an end marker does not deform
    assert (w[v[:, 0] < 1.5, 0] > 0.95).all()
    assert (w[v[:, 0] > 2.5, 1] > 0.95).all()
    # With every tip deforming, the bar's far end follows the tip (its bone continues the
    # parent's, 3 → 4).
    joints = [[0, 0, 0], [2, 0, 0], [3, 0, 0]]
    w = cagerig.skin_weights(v, f, joints, [-1, 0, 1], 2, joint_names=["a", "b", "b_end"],
                             tips="all")
    check_rows(w, 2)
    assert w[v[:, 0] == 4.0].argmax(axis=1).tolist() == [2] * 4


def test_bad_inputs_are_errors():
    v, f = bar()
    with pytest.raises(ValueError, match="max_influences"):
        cagerig.skin_weights(v, f, [[0, 0, 0], [2, 0, 0]], [-1, 0], 0)
    with pytest.raises(IndexError):
        cagerig.skin_weights(v, f, [[0, 0, 0], [2, 0, 0]], [-1, 5])
    with pytest.raises(ValueError, match="tips"):
        cagerig.skin_weights(v, f, [[0, 0, 0], [2, 0, 0]], [-1, 0], tips="some")


def test_the_arm_matches_the_cli(arm, cli, tmp_path):
    out = tmp_path / "arm.skw"
    run_cli(cli, "weights", ARM_DIR / "arm.obj", "--skeleton", ARM_DIR / "arm.skt", "--out", out)
    expected = read_triplets(out, (arm.num_vertices, arm.num_joints), transpose=True)
    skeleton = arm.rest_joints
    w = cagerig.skin_weights(arm.rest_mesh, arm.triangles, skeleton, arm.joint_parents,
                             joint_names=arm.joint_names)
    check_rows(w, 4)
    # The rig's rest joints come back from SkelUp to ≤ 1e-9 of the file's.
    np.testing.assert_allclose(w, expected, atol=1e-6)


def test_rig_load_with_auto_weights_needs_no_skw(tmp_path):
    for name in ("arm.obj", "arm.skt", "arm_cage.obj"):
        shutil.copy(ARM_DIR / name, tmp_path / name)
    with pytest.raises(FileNotFoundError):
        cagerig.Rig.load(tmp_path / "arm.obj")
    rig = cagerig.Rig.load(tmp_path / "arm.obj", auto_weights=True)
    w = rig.skin_weights
    check_rows(w, 4)
    rig.rotate_joint("lowerarm01.R", [1, 0, 0], 60)
    assert np.abs(rig.posed_mesh - rig.rest_mesh).max() > 1.0
