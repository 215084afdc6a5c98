"""Every plain function against the Rust library's results on the Arm (through the CLI or a
Rig, which runs the same Rust code), and against analytic cases."""

import json

import numpy as np
import pytest

import cagerig
from conftest import ARM_DIR, REFERENCE, read_triplets, run_cli


def test_mvc_equals_the_cli_coords(arm, cli, tmp_path):
    out = tmp_path / "phi.txt"
    run_cli(cli, "coords", ARM_DIR / "arm.obj", "--out", out)
    expected = read_triplets(out, (arm.num_vertices, arm.num_cage_vertices), transpose=True)
    phi = cagerig.mvc(arm.rest_mesh, arm.rest_cage, arm.cage_triangles)
    assert phi.shape == (2089, 58)
    np.testing.assert_array_equal(phi, expected)  # round-trip floats: bit-exact
    np.testing.assert_allclose(phi.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(phi @ arm.rest_cage, arm.rest_mesh, atol=1e-9)


def test_mvc_accepts_lists_and_other_dtypes():
    cube_v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.int32)
    cube_f = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
              [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    points = [[0.5, 0.5, 0.5], [0.1, 0.2, 0.9]]
    phi = cagerig.mvc(points, cube_v, np.array(cube_f, dtype=np.uint16))
    np.testing.assert_allclose(phi @ cube_v, points, atol=1e-14)  # linear precision
    np.testing.assert_allclose(phi.sum(1), 1, atol=1e-14)
    assert (phi > 0).all()  # inside a convex cage
    np.testing.assert_array_equal(phi, cagerig.mvc(np.array(points), cube_v.astype(float), cube_f))


def test_maxvol_rows_equal_the_cli(arm_file_coords, cli, tmp_path):
    arm = arm_file_coords  # `cagerig maxvol` selects rows of the shipped Φ
    report = json.loads(
        run_cli(cli, "maxvol", ARM_DIR / "arm.obj", "--out", tmp_path / "r.maxvol", "--json").stdout
    )
    rows, log_abs_det = cagerig.maxvol_rows(arm.cage_coords)  # Φ as loaded, like the CLI
    assert rows.dtype == np.int64 and rows.shape == (58,)
    np.testing.assert_array_equal(rows, report["rows"])
    assert log_abs_det == pytest.approx(report["log_abs_det"], rel=1e-12)
    sign, logdet = np.linalg.slogdet(np.asarray(arm.cage_coords)[rows])
    assert logdet == pytest.approx(log_abs_det, rel=1e-9)


def test_lbs_equals_the_rig_and_the_paper_tool(arm):
    arm.rotate_joint("lowerarm01.R", [1, 0, 0], 60)
    posed = cagerig.lbs(arm.rest_mesh, arm.skin_weights, arm.skinning_transforms)
    np.testing.assert_allclose(posed, arm.posed_mesh, rtol=0, atol=1e-12)
    # Step ii of the paper's tool (reference/README.txt): M' to ~1e-9.
    expected = cagerig.read_obj(REFERENCE / "s2_Mdef.obj")[0]
    np.testing.assert_allclose(posed, expected, rtol=0, atol=1e-9)
    # (J, 3, 4) transforms and scipy-free sparse input through a duck-typed tocoo().
    np.testing.assert_array_equal(
        cagerig.lbs(arm.rest_mesh, arm.skin_weights, arm.skinning_transforms[:, :3, :]), posed
    )


class Coo:
    """The part of scipy.sparse's interface the functions use."""

    def __init__(self, dense):
        self.row, self.col = np.nonzero(dense)
        self.data = dense[self.row, self.col]
        self.shape = dense.shape

    def tocoo(self):
        return self


def test_sparse_weights_equal_dense(arm):
    arm.rotate_joint(3, [1, 0, 0], 40)
    w = arm.skin_weights
    args = (arm.rest_mesh, Coo(w), arm.skinning_transforms)
    np.testing.assert_array_equal(cagerig.lbs(*args), cagerig.lbs(arm.rest_mesh, w, args[2]))


@pytest.mark.parametrize("method", ["dqs", "cor"])
def test_dqs_and_cor_equal_the_rig(arm, method):
    arm.set_skinning(method)
    arm.rotate_joint("lowerarm01.R", [1, 0, 0], 60)
    arm.rotate_joint("wrist.R", [0, 1, 0], -30)
    if method == "dqs":
        posed = cagerig.dqs(arm.rest_mesh, arm.skin_weights, arm.skinning_transforms)
    else:
        posed = cagerig.cor(arm.rest_mesh, arm.skin_weights, arm.skinning_transforms, arm.cor_centres)
    np.testing.assert_allclose(posed, arm.posed_mesh, rtol=0, atol=1e-10)


def test_cor_centres_equal_the_rigs_centres(arm):
    # A rig built from arrays has no CoR file: it computes Λ = S·Φ itself (exact form), so its
    # centres Λ·C equal S·M for M = ΦC.
    arm.move_rest_cage([0], [0.0, 0.0, 0.0])  # M := ΦC (the loaded M differs by 1e-3)
    m = arm.rest_mesh
    rig = cagerig.Rig.from_arrays(
        m, arm.triangles, arm.skin_weights, arm.rest_joints, arm.joint_parents,
        arm.rest_cage, arm.cage_triangles, arm.joint_names,
    )
    rig.set_skinning("cor")
    centres = cagerig.cor_centres(m, arm.triangles, arm.skin_weights)
    diag = np.linalg.norm(m.max(0) - m.min(0))
    assert np.abs(centres - rig.cor_centres).max() < 1e-9 * diag
    # And close to the paper tool's centres (arm_corWeights.txt) as the Rust tests require.
    s = read_triplets(ARM_DIR / "arm_corWeights.txt", (len(m), len(m)))
    tool = s @ cagerig.read_obj(ARM_DIR / "arm.obj")[0]
    assert np.median(np.linalg.norm(centres - tool, axis=1)) / diag < 0.02


def test_max_entropy_coordinates_analytic():
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    w = cagerig.max_entropy_coordinates(cube, np.ones(8), [0.5, 0.5, 0.5])
    np.testing.assert_allclose(w, 1 / 8, atol=1e-14)
    targets = np.random.default_rng(1).uniform(0.1, 0.9, (20, 3))
    prior = np.arange(1.0, 9.0)
    for signed in (False, True):
        w = cagerig.max_entropy_coordinates(cube, prior, targets, signed=signed)
        assert w.shape == (20, 8)
        np.testing.assert_allclose(w @ cube, targets, atol=1e-10)
        np.testing.assert_allclose(w.sum(1), 1, atol=1e-12)
        assert (w > 0).all()
    # Outside the hull: least-squares fallback, both constraints still exact.
    w = cagerig.max_entropy_coordinates(cube, np.ones(8), [2.0, 0.5, 0.5])
    np.testing.assert_allclose(w @ cube, [2.0, 0.5, 0.5], atol=1e-10)


def test_max_entropy_reproduces_a_rest_joint_from_psi_support(arm):
    # Ψ's rows (SkelUp, MEC with the articulation prior) reproduce each rest joint exactly; the
    # function with Ψ's row as prior returns a row that does too.
    psi = arm.joint_coords
    joints = arm.rest_joints
    np.testing.assert_allclose(psi @ arm.rest_cage, joints, atol=1e-8)
    w = cagerig.max_entropy_coordinates(arm.rest_cage, np.abs(psi[5]) + 1e-6, joints[5])
    np.testing.assert_allclose(w @ arm.rest_cage, joints[5], atol=1e-8)


def test_validate_cage(arm):
    tris = cagerig.validate_cage(arm.rest_cage, arm.cage_triangles)
    np.testing.assert_array_equal(tris, arm.cage_triangles)
    with pytest.warns(cagerig.RigWarning, match="flipped"):
        flipped = cagerig.validate_cage(arm.rest_cage, arm.cage_triangles[:, ::-1])
    def directed_edges(tris):
        return {(a, b) for t in tris for a, b in zip(t, np.roll(t, -1))}

    assert directed_edges(flipped) == directed_edges(arm.cage_triangles)
    with pytest.raises(cagerig.RigError, match="open boundary"):
        cagerig.validate_cage(arm.rest_cage, arm.cage_triangles[:-1])


def test_subdivide_equals_the_cli(arm, cli, tmp_path):
    run_cli(cli, "subdivide", ARM_DIR / "arm.obj", "--levels", "1", "--out", tmp_path, "--name", "arm1")
    v, f, w = cagerig.subdivide(
        cagerig.read_obj(ARM_DIR / "arm.obj")[0], arm.triangles, 1, weights=arm.skin_weights
    )
    v_cli, f_cli = cagerig.read_obj(tmp_path / "arm1.obj")
    np.testing.assert_array_equal(v, v_cli)
    np.testing.assert_array_equal(f, f_cli)
    assert v.shape == (8333, 3) and f.shape == (4 * 4156, 3)
    w_cli = read_triplets(tmp_path / "arm1.skw", (arm.num_joints, len(v))).T
    np.testing.assert_allclose(w, w_cli, rtol=0, atol=1e-15)
    v2, f2 = cagerig.subdivide(v, f, levels=1)
    assert v2.shape == (33289, 3)


def test_obj_round_trip(tmp_path, arm):
    path = tmp_path / "m.obj"
    cagerig.write_obj(path, arm.posed_mesh, arm.triangles)
    v, f = cagerig.read_obj(path)
    np.testing.assert_array_equal(v, arm.posed_mesh)
    np.testing.assert_array_equal(f, arm.triangles)
