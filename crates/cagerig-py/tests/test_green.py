"""Green coordinates from Python: cagerig.green_coordinates, and Rig.load(..., coords="green")
against `cagerig edit --coords green`."""

import json

import numpy as np
import pytest

import cagerig
from conftest import SCENARIO, run_cli

# A unit cube cage around the origin (12 triangles, outward).
CUBE_V = np.array(
    [[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)], dtype=np.float64
)
CUBE_F = np.array(
    [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
    ]
)


def outward_normals(v, f):
    n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    centre = v.mean(axis=0)
    if np.sum((v[f[:, 0]] - centre) * n) < 0:
        n = -n
    return n


def test_green_coordinates_reproduce_interior_points():
    rng = np.random.default_rng(3)
    points = rng.uniform(-0.9, 0.9, size=(50, 3))
    phi, psi = cagerig.green_coordinates(points, CUBE_V, CUBE_F)
    assert phi.shape == (50, 8) and psi.shape == (50, 12)
    np.testing.assert_allclose(phi.sum(axis=1), 1.0, atol=1e-13)
    assert (psi > 0).all()
    normals = outward_normals(CUBE_V, CUBE_F)
    np.testing.assert_allclose(phi @ CUBE_V + psi @ normals, points, atol=1e-13)
    # Wound inward: the same coordinates, ψ's columns still follow the triangles given.
    phi2, psi2 = cagerig.green_coordinates(points, CUBE_V, CUBE_F[:, [0, 2, 1]])
    np.testing.assert_array_equal(phi, phi2)
    np.testing.assert_array_equal(psi, psi2)


def test_rig_load_green_reproduces_the_rest_mesh_and_grabs_land(arm_path):
    mvc = cagerig.Rig.load(arm_path)
    rig = cagerig.Rig.load(arm_path, coords="green")
    assert rig.coords == "green" and mvc.coords == "mvc"
    size = np.linalg.norm(np.ptp(rig.rest_cage, axis=0))
    np.testing.assert_allclose(rig.rest_mesh, mvc.rest_mesh, atol=1e-9 * size)
    # SkelUp with the face terms (G5): rest joints = Ψ_φ C + Ψ_ψ g(C); MVC rigs have none.
    assert rig.joint_face_coords.shape == (25, 112) and rig.rest_cage_terms.shape == (112, 3)
    assert mvc.joint_face_coords.shape == (25, 0) and mvc.rest_cage_terms.shape == (0, 3)
    joints = rig.joint_coords @ rig.rest_cage + rig.joint_face_coords @ rig.rest_cage_terms
    np.testing.assert_allclose(joints, rig.rest_joints, atol=1e-9 * size)
    rig.rotate_joint("lowerarm01.R", [1, 0, 0], 60)
    before = rig.posed_cage.copy()
    rig.move_posed_cage([20, 23, 25], [-1.5, 2, 0.5])
    after = rig.posed_cage
    expected = before.copy()
    expected[[20, 23, 25]] += [-1.5, 2, 0.5]
    np.testing.assert_allclose(after, expected, atol=1e-9 * size)
    joints = rig.joint_coords @ rig.rest_cage + rig.joint_face_coords @ rig.rest_cage_terms
    np.testing.assert_allclose(joints, rig.rest_joints, atol=1e-9 * size)


def test_unknown_coords_name_lists_the_accepted_ones(arm_path):
    with pytest.raises(ValueError, match="expected mvc or green"):
        cagerig.Rig.load(arm_path, coords="harmonic")


def test_edit_scenario_under_green_equals_the_cli(arm_path, cli, tmp_path):
    scenario = {"skinning": "lbs", "steps": SCENARIO["steps"][:4]}
    script = tmp_path / "scenario.json"
    script.write_text(json.dumps(scenario))
    run_cli(cli, "edit", arm_path, "--script", script, "--coords", "green", "--out", tmp_path / "cli")
    rig = cagerig.Rig.load(arm_path, coords="green")
    cagerig.replay_script(rig, script, tmp_path / "py")
    for k in range(len(scenario["steps"]) + 1):
        for what in ("mesh_rest", "mesh_posed", "cage_rest", "cage_posed"):
            name = f"step{k}_{what}.obj"
            a = cagerig.read_obj(tmp_path / "cli" / name)
            b = cagerig.read_obj(tmp_path / "py" / name)
            np.testing.assert_array_equal(a[0], b[0], err_msg=name)


def test_keep_poses_the_skin_past_the_fold_and_refuses_grabs_until_it_fits(arm_path):
    # Lipman's face term with the fit on the rows alone meets poses with no current cage.
    rig = cagerig.Rig.load(arm_path, coords="green", green_face_term="lipman", cage_fit="paper")
    mvc = cagerig.Rig.load(arm_path)
    assert rig.unfitted_cage == "refuse" and rig.posed_cage_unfitted is None
    assert (rig.green_face_term, rig.cage_fit) == ("lipman", "paper")
    # 120° at the elbow in one edit is past that fit's fold limit (about 66°): refused by default.
    with pytest.raises(cagerig.RigError, match="Green CageUp found no current cage"):
        rig.rotate_joint("lowerarm01.R", [1, 0, 0], 120)
    rig.set_unfitted_cage("keep")
    assert rig.unfitted_cage == "keep"
    rig.rotate_joint("lowerarm01.R", [1, 0, 0], 120)
    mvc.rotate_joint("lowerarm01.R", [1, 0, 0], 120)
    assert "CageUp found no current cage" in rig.posed_cage_unfitted
    size = np.linalg.norm(np.ptp(rig.rest_cage, axis=0))
    np.testing.assert_allclose(rig.posed_mesh, mvc.posed_mesh, atol=1e-9 * size)
    with pytest.raises(cagerig.RigError, match="cannot be grabbed in this pose"):
        rig.move_posed_cage([20], [0, 1, 0])
    rig.reset_pose()
    assert rig.posed_cage_unfitted is None
    rig.move_posed_cage([20], [0, 1, 0])
    with pytest.raises(ValueError, match="expected refuse or keep"):
        rig.set_unfitted_cage("sometimes")


def test_the_default_green_rig_bends_the_elbow_without_a_refusal(arm_path):
    rig = cagerig.Rig.load(arm_path, coords="green")
    assert (rig.green_face_term, rig.cage_fit) == ("fold-safe", "regularised")
    for _ in range(5):
        rig.rotate_joint("lowerarm01.R", [1, 0, 0], 30)
        assert rig.posed_cage_unfitted is None
