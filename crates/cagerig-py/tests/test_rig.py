"""The Rig class: the paper's edit scenario against `cagerig edit`, animation against
`cagerig animate`, the paper tool's reference outputs, views vs copies, save/reload."""

import json
import threading

import numpy as np
import pytest

import cagerig
from conftest import ARM_DIR, REFERENCE, SCENARIO, read_obj_vertices, run_cli

STRUCTURES = ("mesh_rest", "mesh_posed", "cage_rest", "cage_posed")


def test_edit_scenario_equals_the_cli(arm_path, cli, tmp_path):
    script = tmp_path / "scenario.json"
    script.write_text(json.dumps(SCENARIO))
    run_cli(cli, "edit", arm_path, "--script", script, "--out", tmp_path / "cli")
    rig = cagerig.Rig.load(arm_path)
    written = cagerig.replay_script(rig, script, tmp_path / "py")
    assert len(written) == 5 * (len(SCENARIO["steps"]) + 1)
    for k in range(len(SCENARIO["steps"]) + 1):
        for what in STRUCTURES:
            name = f"step{k}_{what}.obj"
            a = cagerig.read_obj(tmp_path / "cli" / name)
            b = cagerig.read_obj(tmp_path / "py" / name)
            np.testing.assert_array_equal(a[0], b[0], err_msg=name)
            np.testing.assert_array_equal(a[1], b[1], err_msg=name)
        joints_cli = json.loads((tmp_path / "cli" / f"step{k}_joints.json").read_text())
        joints_py = json.loads((tmp_path / "py" / f"step{k}_joints.json").read_text())
        assert joints_cli == joints_py


def test_run_script_equals_the_same_calls(arm):
    by_calls = arm.copy()
    arm.run_script(SCENARIO)
    by_calls.rotate_joint("lowerarm01.R", [1, 0, 0], 60)
    by_calls.move_rest_cage([0, 2, 4, 5, 6], [2, -1, 1.5])
    by_calls.move_posed_cage([20, 23, 25], [-1.5, 2, 0.5])
    by_calls.set_skinning("dqs")
    by_calls.rotate_joint(4, np.array([0.0, 0.0, 1.0]), -25)
    by_calls.reset_pose()
    for prop in ("rest_mesh", "posed_mesh", "rest_cage", "posed_cage", "rest_joints", "posed_joints"):
        np.testing.assert_array_equal(getattr(arm, prop), getattr(by_calls, prop), err_msg=prop)
    assert arm.skinning == "dqs"
    script = cagerig.EditScript(json.dumps(SCENARIO))
    assert len(script) == 6 and script.skinning == "lbs" and script.steps[0]["op"] == "rotate_joint"


def test_paper_tool_steps_ii_to_iv(arm_file_coords):
    """The scenario of reference/README.txt against the paper tool's outputs (tolerances of the
    Rust conformance test; step iii/iv joints near the shoulder differ by the tool's defect).
    Uses the tool's own Φ file, as the Rust conformance test does."""
    arm = arm_file_coords
    arm.rotate_joint("lowerarm01.R", [1, 0, 0], 60)
    np.testing.assert_allclose(arm.posed_mesh, read_obj_vertices(REFERENCE / "s2_Mdef.obj"), atol=1e-9)
    np.testing.assert_allclose(arm.posed_cage, read_obj_vertices(REFERENCE / "s2_Cdef.obj"), atol=1e-9)
    arm.move_rest_cage([0, 2, 4, 5, 6], [2, -1, 1.5])
    np.testing.assert_allclose(arm.rest_cage, read_obj_vertices(REFERENCE / "s3_C_rest.obj"), atol=1e-9)
    before = arm.posed_cage
    target = before.copy()
    target[[20, 23, 25]] += [-1.5, 2, 0.5]
    arm.move_posed_cage([20, 23, 25], [-1.5, 2, 0.5])
    np.testing.assert_allclose(arm.posed_cage, target, atol=1e-9)  # the grab lands exactly


def test_grab_lands_under_every_skinning(arm):
    # The Arm's M differs from ΦC by 1e-3 (Φ read with 6 decimals); the first cage edit adopts
    # M = ΦC, after which every grab lands exactly.
    arm.move_rest_cage(0, [0.0, 0.0, 0.0])
    for method in ("lbs", "dqs", "cor"):
        arm.set_skinning(method)
        arm.rotate_joint("wrist.R", [0, 0, 1], 20)
        target = arm.posed_cage
        target[[3, 7]] += [[0.5, 0, 0], [0, -0.5, 0.25]]
        arm.move_posed_cage([3, 7], [[0.5, 0, 0], [0, -0.5, 0.25]])
        np.testing.assert_allclose(arm.posed_cage, target, atol=1e-8, err_msg=method)


def test_the_lbs_rest_preimage_skins_to_the_cor_skin(arm):
    # What the Blender add-on shows CoR with: points whose LBS (Ω, the skinning transforms) is M'.
    arm.set_skinning("cor")
    arm.rotate_joint("lowerarm01.R", [1, 0, 0], 50)
    x = arm.lbs_rest_preimage()
    t = arm.skinning_transforms
    w = arm.skin_weights.toarray() if hasattr(arm.skin_weights, "toarray") else np.asarray(arm.skin_weights)
    blended = np.einsum("vj,jab->vab", w, t)
    lbs_of_x = np.einsum("vab,vb->va", blended[:, :3, :3], x) + blended[:, :3, 3]
    np.testing.assert_allclose(lbs_of_x, arm.posed_mesh, atol=1e-9)
    assert np.abs(x - arm.rest_mesh).max() > 1e-3  # CoR differs from LBS under this bend


def test_phi_is_a_read_only_view_and_reading_posed_mesh_does_not_copy_it(arm):
    phi = arm.cage_coords
    assert phi.shape == (2089, 58) and phi.dtype == np.float64
    assert not phi.flags.writeable and not phi.flags.owndata
    with pytest.raises(ValueError):
        phi[0, 0] = 1.0
    assert np.shares_memory(phi, arm.phi)  # the same storage every time: no copy
    np.testing.assert_allclose(phi.sum(1), 1, atol=1e-5)  # the file's 6-decimal Φ
    arm.move_rest_cage([1], [0.5, 0, 0])
    np.testing.assert_allclose(phi @ arm.rest_cage, arm.rest_mesh, atol=1e-9)  # M = ΦC after edits
    # Copies: later edits do not change an array read before.
    m = arm.posed_mesh
    arm.rotate_joint(3, [1, 0, 0], 30)
    assert not np.array_equal(m, arm.posed_mesh)
    assert not np.shares_memory(arm.posed_mesh, arm.posed_mesh)
    # The view keeps the rig alive.
    rig = arm.copy()
    view = rig.cage_coords
    del rig
    import gc

    gc.collect()
    np.testing.assert_array_equal(view, phi)


def test_copy_is_independent(arm):
    other = arm.copy()
    other.rotate_joint(3, [1, 0, 0], 45)
    np.testing.assert_array_equal(arm.posed_mesh, arm.rest_mesh * 0 + arm.posed_mesh)
    assert not np.allclose(arm.posed_mesh, other.posed_mesh)


def test_pose_round_trip_and_reset(arm):
    rest_posed = arm.posed_mesh
    arm.rotate_joint(3, [1, 0, 0], 60)
    arm.rotate_joint("wrist.R", [0, 1, 1], 25)
    rotations, motion = arm.pose
    posed = arm.posed_mesh
    arm.reset_pose()
    np.testing.assert_allclose(arm.posed_mesh, rest_posed, atol=1e-9)
    arm.set_pose(rotations, motion)
    np.testing.assert_allclose(arm.posed_mesh, posed, atol=1e-9)
    # Root motion moves everything.
    motion = np.zeros((arm.num_joints, 3))
    motion[0] = [1.0, 2.0, 3.0]
    arm.set_pose(rotations, motion)
    np.testing.assert_allclose(arm.posed_mesh, posed + [1.0, 2.0, 3.0], atol=1e-9)


def test_animation_equals_the_cli(arm_path, cli, tmp_path):
    skel, cage = ARM_DIR / "arm_skelAnim.txt", ARM_DIR / "arm_cageAnim.txt"
    times = ["0.75", "2.25", "4"]  # the CLI names files after Rust's formatting of the time
    run_cli(cli, "animate", arm_path, "--skeleton-anim", skel, "--cage-anim", cage,
            "--times", ",".join(times), "--out", tmp_path)
    rig = cagerig.Rig.load(arm_path)
    rig.set_animation(skeleton=skel, cage=cage)
    assert rig.animation_duration > 4
    for t in times:
        rig.sample_animation(float(t))
        for what, prop in (("mesh_posed", "posed_mesh"), ("cage_rest", "rest_cage"), ("cage_posed", "posed_cage")):
            np.testing.assert_array_equal(read_obj_vertices(tmp_path / f"t{t}_{what}.obj"), getattr(rig, prop))


def test_animation_from_arrays(arm):
    c0 = arm.original_rest_cage
    offsets = np.zeros((2, arm.num_cage_vertices, 3))
    offsets[1, :, 0] = 1.0  # translate the whole cage by +x at t = 1
    arm.set_animation(cage=(np.array([0.0, 1.0]), offsets))
    arm.sample_animation(0.5)
    np.testing.assert_allclose(arm.rest_cage, c0 + [0.5, 0, 0], atol=1e-12)
    np.testing.assert_allclose(arm.rest_joints[3], arm.copy().rest_joints[3], atol=1e-9)
    frames = np.repeat(np.eye(4)[None, None], arm.num_joints, axis=1).repeat(2, axis=0)
    frames[:, :, :3, :] = 0
    with pytest.raises(cagerig.RigError, match="singular"):
        arm.set_animation(skeleton=([0.0, 1.0], frames))


def test_save_and_reload(arm, tmp_path):
    arm.move_rest_cage([0, 2, 4], [1.0, 0.5, 0.0])
    arm.save(tmp_path / "out", "edited")
    back = cagerig.Rig.load(tmp_path / "out" / "edited.obj")
    for prop in ("rest_mesh", "rest_cage", "rest_joints"):
        np.testing.assert_allclose(getattr(back, prop), getattr(arm, prop), atol=1e-9, err_msg=prop)
    np.testing.assert_array_equal(back.fit_rows, arm.fit_rows)
    arm.export_obj(tmp_path / "posed.obj")
    np.testing.assert_array_equal(read_obj_vertices(tmp_path / "posed.obj"), arm.posed_mesh)
    arm.export_obj(tmp_path / "cage.obj", what="posed_cage")
    np.testing.assert_array_equal(read_obj_vertices(tmp_path / "cage.obj"), arm.posed_cage)


def test_builtin_rigs():
    bar = cagerig.Rig.builtin("bar", skinning="dqs")
    assert bar.skinning == "dqs" and bar.num_joints == 4
    bar.rotate_joint(1, [0, 0, 1], 45)
    target = bar.posed_cage
    target[0] += [0, 0.1, 0]
    bar.move_posed_cage(0, [0, 0.1, 0])
    np.testing.assert_allclose(bar.posed_cage, target, atol=1e-9)
    with pytest.raises(cagerig.RigError, match="unknown demo rig"):
        cagerig.Rig.builtin("dragon")


def test_heavy_calls_release_the_gil(arm):
    """Two threads editing two rigs both progress (a deadlock or a crash would fail)."""
    rigs = [arm, arm.copy()]
    errors = []

    def work(rig):
        try:
            for i in range(50):
                rig.rotate_joint(3, [1, 0, 0], 1 if i % 2 else -1)
                rig.move_rest_cage([1], [0.01, 0, 0])
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(r,)) for r in rigs]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    np.testing.assert_allclose(rigs[0].rest_cage, rigs[1].rest_cage)


def _partial_folders(parent):
    return [p.name for p in parent.iterdir() if ".partial-" in p.name]


def test_save_writes_one_folder_complete_or_not_at_all(arm, tmp_path):
    out = tmp_path / "saved"
    arm.save(out, "first")
    with pytest.raises(FileExistsError, match="overwrite=True"):
        arm.save(out, "second")
    assert sorted(p.name for p in out.iterdir() if p.name.startswith("first")) != []
    # An earlier output is replaced as a whole: no file of the first set lingers.
    arm.save(out, "second", overwrite=True)
    names = sorted(p.name for p in out.iterdir())
    assert names[0] == ".cagerig-output" and all(n.startswith("second") for n in names[1:])
    assert cagerig.Rig.load(out / "second.obj").num_joints == arm.num_joints
    # A folder with the user's own file is never replaced, even with overwrite=True.
    (out / "notes.txt").write_text("mine")
    with pytest.raises(FileExistsError, match="notes.txt"):
        arm.save(out, "third", overwrite=True)
    assert (out / "notes.txt").read_text() == "mine" and (out / "second.obj").is_file()
    assert _partial_folders(tmp_path) == []


def test_replay_script_folder_appears_whole_and_replaces_only_its_own(arm, tmp_path):
    script = {"steps": [{"op": "rotate_joint", "joint": 3, "axis": [1, 0, 0], "degrees": 30}]}
    out = tmp_path / "replay"
    written = cagerig.replay_script(arm.copy(), script, out)
    assert sorted(p.name for p in written) == sorted(
        f"step{k}_{w}" for k in range(2) for w in ("joints.json",) + tuple(f"{s}.obj" for s in STRUCTURES)
    )
    assert all(p.parent == out and p.is_file() for p in written)
    with pytest.raises(FileExistsError):
        cagerig.replay_script(arm.copy(), script, out)
    two = {"steps": script["steps"] * 2}
    assert len(cagerig.replay_script(arm.copy(), two, out, overwrite=True)) == 15
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "holiday.png").write_bytes(b"png")
    with pytest.raises(FileExistsError, match="holiday.png"):
        cagerig.replay_script(arm.copy(), script, mine, overwrite=True)
    assert [p.name for p in mine.iterdir()] == ["holiday.png"]
    assert _partial_folders(tmp_path) == []


def test_replay_output_folder_abandoned_on_error_leaves_nothing(tmp_path):
    out = tmp_path / "never"
    with pytest.raises(RuntimeError):
        with cagerig.OutputFolder(out) as folder:
            folder.write_text("a.json", "[]")
            assert not out.exists()
            raise RuntimeError("stop")
    assert not out.exists() and _partial_folders(tmp_path) == []
    with pytest.raises(ValueError, match="plain file name"):
        with cagerig.OutputFolder(out) as folder:
            folder.write_text("../escape.txt", "x")
    with cagerig.OutputFolder(out) as folder:
        folder.write_obj("t.obj", [[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    assert sorted(p.name for p in out.iterdir()) == [".cagerig-output", "t.obj"]
    with pytest.raises(ValueError, match="already finished"):
        folder.write_text("late.txt", "x")


def test_cage_fit_is_chosen_by_name_and_keeps_the_skin(arm_path):
    with pytest.warns(cagerig.RigWarning):
        regularised = cagerig.Rig.load(arm_path)
        paper = cagerig.Rig.load(arm_path, cage_fit="paper")
    assert regularised.cage_fit == "regularised" and paper.cage_fit == "paper"
    for rig in (regularised, paper):
        rig.rotate_joint("lowerarm01.R", [1, 0, 0], 60)
    # The skin does not depend on the fit; the handle does.
    np.testing.assert_array_equal(regularised.posed_mesh, paper.posed_mesh)
    assert np.abs(regularised.posed_cage - paper.posed_cage).max() > 1e-6
    # A grab still lands exactly under the regularised fit.
    target = regularised.posed_cage
    target[[10, 13]] += [0.5, -0.25, 0.75]
    regularised.move_posed_cage([10, 13], [0.5, -0.25, 0.75])
    np.testing.assert_allclose(regularised.posed_cage, target, atol=1e-8)
    with pytest.raises(ValueError, match="regularised or paper"):
        cagerig.Rig.builtin("bar", cage_fit="exact")


@pytest.mark.parametrize(
    "names, option",
    [
        (cagerig.SKINNING_METHODS, "skinning"),
        (cagerig.COORDS_KINDS, "coords"),
        (cagerig.CAGE_FITS, "cage_fit"),
    ],
)
def test_option_name_lists_are_what_the_rig_accepts(names, option):
    # Front ends (the Blender add-on) list their choices from these: each is accepted and read
    # back, and a wrong name's error lists the same names.
    bar = cagerig.Rig.builtin("bar")

    def build(**options):
        # From the bar's arrays, with DQ blend weights so that every skinning method applies.
        return cagerig.Rig.from_arrays(
            bar.rest_mesh, bar.triangles, bar.skin_weights, bar.rest_joints, bar.joint_parents,
            bar.rest_cage, bar.cage_triangles, dq_blend_weights=np.full(len(bar.rest_mesh), 0.5), **options,
        )

    assert len(names) >= 2 and len(set(names)) == len(names)
    for name in names:
        assert getattr(build(**{option: name}), option) == name
    with pytest.raises(ValueError) as e:
        build(**{option: "no-such-name"})
    assert all(name in str(e.value) for name in names)


def test_unfitted_cage_policy_names_are_what_the_rig_accepts():
    rig = cagerig.Rig.builtin("bar", coords="green")
    for name in cagerig.UNFITTED_CAGE_POLICIES:
        rig.set_unfitted_cage(name)
        assert rig.unfitted_cage == name
    with pytest.raises(ValueError) as e:
        rig.set_unfitted_cage("no-such-policy")
    assert all(name in str(e.value) for name in cagerig.UNFITTED_CAGE_POLICIES)
