"""glTF / FBX characters and automatic cages from Python."""

import json
import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import cagerig

DATA = Path(__file__).resolve().parents[3] / "data"


def test_fox_loads_from_gltf_with_its_cage_and_exports_back(tmp_path):
    fox = DATA / "fox"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cagerig.RigWarning)
        rig = cagerig.Rig.load(fox / "Fox.glb", fox / "Fox_cage.obj")
    assert rig.rest_mesh.shape[0] > 1000
    rig.rotate_joint(3, [1.0, 0.0, 0.0], 20.0)
    for name in ("fox.glb", "fox.gltf"):
        rig.export_gltf(tmp_path / name)
    uri = json.loads((tmp_path / "fox.gltf").read_text())["buffers"][0]["uri"]
    assert uri.startswith("fox-") and uri.endswith(".bin")
    assert (tmp_path / uri).is_file()
    assert len(list(tmp_path.glob("fox-*.bin"))) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cagerig.RigWarning)
        back = cagerig.Rig.load(tmp_path / "fox.gltf", fox / "Fox_cage.obj")
    assert back.rest_mesh.shape == rig.rest_mesh.shape
    diagonal = np.linalg.norm(rig.rest_mesh.max(0) - rig.rest_mesh.min(0))
    assert np.abs(back.rest_mesh - rig.rest_mesh).max() < 1e-5 * diagonal


def test_a_character_without_a_cage_fails_clearly_or_gets_a_generated_one():
    fox = DATA / "fox" / "Fox.glb"
    with pytest.raises(cagerig.RigFileError, match="auto_cage"):
        cagerig.Rig.load(fox)
    with pytest.warns(cagerig.RigWarning, match="generated"):
        rig = cagerig.Rig.load(fox, auto_cage=80)
    assert 72 <= rig.rest_cage.shape[0] <= 88


def test_the_generated_cage_layout_is_chosen_by_name():
    fox = DATA / "fox" / "Fox.glb"
    with pytest.warns(cagerig.RigWarning, match="generated"):
        by_skeleton = cagerig.Rig.load(fox, auto_cage=80)
    with pytest.warns(cagerig.RigWarning, match="generated"):
        offset = cagerig.Rig.load(fox, auto_cage=80, cage_layout="offset")
    assert by_skeleton.rest_cage.shape != offset.rest_cage.shape or not np.allclose(
        by_skeleton.rest_cage, offset.rest_cage
    )
    with pytest.raises(ValueError, match="cage_layout.*skeleton or offset"):
        cagerig.Rig.load(fox, auto_cage=80, cage_layout="bones")


def test_generate_cage_encloses_the_mesh_and_validates():
    v, f = cagerig.read_obj(DATA / "arm" / "arm.obj")
    cv, cf = cagerig.generate_cage(v, f, target_vertices=60)
    assert cv.dtype == np.float64 and cf.dtype == np.int64
    assert 54 <= cv.shape[0] <= 66
    # A valid, outward cage: validate_cage keeps its triangles as they are.
    assert np.array_equal(cagerig.validate_cage(cv, cf), cf)
    # Mean value coordinates reproduce the mesh (it is inside).
    phi = cagerig.mvc(v, cv, cf)
    assert np.abs(phi @ cv - v).max() < 1e-9


def test_export_gltf_refuses_other_extensions(tmp_path):
    rig = cagerig.Rig.builtin("bar")
    with pytest.raises(ValueError, match=r"\.glb or \.gltf"):
        rig.export_gltf(tmp_path / "x.obj")


def test_fbx_loads_with_the_files_skinning_method_unless_one_is_chosen():
    fbx = DATA / "fbx" / "blender_279_sausage_7400_binary.fbx"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cagerig.RigWarning)
        rig = cagerig.Rig.load(fbx, auto_cage=40)
        chosen = cagerig.Rig.load(fbx, auto_cage=40, skinning="dqs")
    assert rig.skinning == "lbs"  # Blender skins linearly, and the file says so
    assert chosen.skinning == "dqs"


def test_export_gltf_bakes_a_dqs_pose_and_reads_back_without_it(tmp_path):
    arm = DATA / "arm"
    rig = cagerig.Rig.load(arm / "arm.obj", skinning="dqs")
    rig.rotate_joint("lowerarm01.R", [1.0, 0.0, 0.0], 90.0)
    rig.export_gltf(tmp_path / "baked.gltf", bake=True)
    rig.export_gltf(tmp_path / "plain.gltf")
    baked = json.loads((tmp_path / "baked.gltf").read_text())["meshes"][0]
    plain = json.loads((tmp_path / "plain.gltf").read_text())["meshes"][0]
    # One target at default weight 1, marked as cagerig's baked DQS (the viewer-side check of
    # the skin it gives is in cagerig-formats' tests); the plain export has none.
    assert len(baked["primitives"][0]["targets"]) == 1 and baked["weights"] == [1.0]
    assert baked["extras"]["cagerig_baked_skinning"]["method"] == "dqs"
    assert "targets" not in plain["primitives"][0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cagerig.RigWarning)
        back = cagerig.Rig.load(tmp_path / "baked.gltf", arm / "arm_cage.obj")
    diagonal = np.linalg.norm(rig.rest_mesh.max(0) - rig.rest_mesh.min(0))
    assert np.abs(back.rest_mesh - rig.rest_mesh).max() < 1e-5 * diagonal
    # Under LBS there is nothing to bake.
    lbs = cagerig.Rig.load(arm / "arm.obj")
    lbs.export_gltf(tmp_path / "lbs.gltf", bake=True)
    assert "targets" not in json.loads((tmp_path / "lbs.gltf").read_text())["meshes"][0]["primitives"][0]


def _brainstem_from_sweep():
    """The first BrainStem.glb under the folders of CAGERIG_GLTF_SWEEP (searched recursively).

    The repository does not ship it (© Smith Micro Software, Poser EULA)."""
    for folder in os.environ.get("CAGERIG_GLTF_SWEEP", "").split(os.pathsep):
        if folder:
            found = sorted(Path(folder).rglob("BrainStem.glb"))
            if found:
                return found[0]
    return None


def test_a_skin_of_a_file_with_several_is_chosen_by_name_or_index():
    brainstem = _brainstem_from_sweep()
    if brainstem is None:
        pytest.skip(
            "no BrainStem.glb under CAGERIG_GLTF_SWEEP (the repository does not ship it; "
            "set CAGERIG_GLTF_SWEEP to a folder holding it to run this test)"
        )
    # BrainStem's 59 skins share one skeleton: by default they are one rig of 34,159 vertices;
    # skin="3" imports that skin's mesh alone.
    one = cagerig.Rig.load(brainstem, auto_cage=40, skin="3")
    assert one.num_vertices == 1064 and len(one.joint_names) == 18
    with pytest.raises(cagerig.RigFileError, match=r'no skin named or numbered "nope".*and 51 more'):
        cagerig.Rig.load(brainstem, auto_cage=40, skin="nope")
    with pytest.raises(ValueError, match="chooses a skin of a glTF or FBX character"):
        cagerig.Rig.load(DATA / "arm" / "arm.obj", skin="0")
