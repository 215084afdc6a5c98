"""Headless checks of the cagerig add-on on the paper's Arm, run inside Blender by run.sh:

    blender -b --factory-startup --python-exit-code 1 --python blender/tests/test_addon.py -- \
        ZIP ARM_GLB ARM_CAGE_OBJ WORKDIR

Installs the zip and enables the add-on, imports the Arm (glTF) and its cage (OBJ), couples,
then checks the three interactions against Blender's own evaluation, save/reopen, undo, bake,
the error reports, and the same edits through the cagerig Python package (what `cagerig edit`
computes). Every check prints its measured error; the first failure raises (exit code 1).
"""

from __future__ import annotations

import math
import os
import sys
import time
import types

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:]
ZIP, ARM_GLB, ARM_CAGE, WORK, FOX_GLB = argv[:5]
TOL = 1e-5  # of the bounding-box diagonal

results: list[str] = []


def check(name: str, ok: bool, detail: str) -> None:
    line = f"{'ok  ' if ok else 'FAIL'} {name}: {detail}"
    print(line, flush=True)
    results.append(line)
    if not ok:
        raise AssertionError(line)


# ---- install + enable ---------------------------------------------------------------------------
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from install_addon import install  # noqa: E402

_addon = install(ZIP)
import cagerig  # noqa: E402  (importable once the add-on is enabled)

convert, engine, store = _addon.convert, _addon.engine, _addon.store
check("enabled", _addon.__name__ in bpy.context.preferences.addons, _addon.__name__)
check("import cagerig", hasattr(cagerig.Rig, "from_arrays"), f"cagerig {cagerig.__version__} from {cagerig.__file__}")



def update() -> None:
    bpy.context.view_layer.update()


def world(obj: bpy.types.Object) -> np.ndarray:
    return convert.world_coords(obj)


def deformed_skin(obj: bpy.types.Object) -> np.ndarray:
    dg = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(dg)
    me = ev.to_mesh()
    try:
        return convert.world_coords(obj, me)
    finally:
        ev.to_mesh_clear()


def bone_heads(arm: bpy.types.Object) -> np.ndarray:
    return convert.rest_skeleton(arm)[1]


def load_arm(**gltf_options: object) -> tuple[bpy.types.Object, bpy.types.Object, bpy.types.Object]:
    for o in list(bpy.data.objects):  # an empty scene (read_factory_settings would disable the add-on)
        bpy.data.objects.remove(o)
    bpy.ops.import_scene.gltf(filepath=ARM_GLB, **gltf_options)
    skin = next(o for o in bpy.data.objects if o.type == "MESH" and any(m.type == "ARMATURE" for m in o.modifiers))
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    # The glb carries the cage as a node too; the test uses the cage OBJ, as a user would.
    for o in list(bpy.data.objects):
        if o.type == "MESH" and o is not skin:
            bpy.data.objects.remove(o)
    bpy.ops.wm.obj_import(filepath=ARM_CAGE)
    cage = bpy.context.selected_objects[0]
    return skin, arm, cage


def couple(skin: bpy.types.Object, cage: bpy.types.Object) -> None:
    bpy.ops.object.select_all(action="DESELECT")
    skin.select_set(True)
    cage.select_set(True)
    bpy.context.view_layer.objects.active = skin
    bpy.ops.cagerig.couple()


def rotate_bone(arm: bpy.types.Object, name: str, axis_world: np.ndarray, degrees: float) -> None:
    """Rotates pose bone ``name`` about a world axis through its head (the armature is not
    transformed in this test), composing with its current pose."""
    from mathutils import Quaternion, Vector

    pb = arm.pose.bones[name]
    pb.rotation_mode = "QUATERNION"
    # World rotation of the bone's frame in the pose: R_world · (pose frame) → new basis.
    pose_rot = pb.matrix.to_3x3().normalized()
    r = Quaternion(Vector(axis_world.tolist()), math.radians(degrees)).to_matrix()
    basis_rot = pb.matrix_basis.to_3x3().normalized()
    new_basis = basis_rot @ pose_rot.inverted() @ r @ pose_rot
    pb.rotation_quaternion = new_basis.to_quaternion()


def fit_row_error(skin: bpy.types.Object, cage: bpy.types.Object, c: engine.Coupling) -> float:
    rows = c.rig.fit_rows
    phi = np.asarray(c.rig.cage_coords)
    shown = world(cage)
    return float(np.abs(phi[rows] @ shown - deformed_skin(skin)[rows]).max())


# ---- errors explained to the user ---------------------------------------------------------------
skin, arm, cage = load_arm()
diag = float(np.linalg.norm(world(skin).max(0) - world(skin).min(0)))
print(f"Arm: {len(skin.data.vertices)} vertices, {len(arm.data.bones)} bones, "
      f"cage {len(cage.data.vertices)}, diag {diag:.4g}")
mod = next(m for m in skin.modifiers if m.type == "ARMATURE")
mod.show_viewport = True
saved_object = mod.object
mod.object = None
try:
    couple(skin, cage)
    check("no armature object refused", False, "Couple accepted a modifier without armature")
except RuntimeError as e:
    check("no armature object refused", "no armature object" in str(e), str(e).strip())
mod.object = saved_object
small = cage.copy()
small.data = cage.data.copy()
bpy.context.scene.collection.objects.link(small)
centre = world(cage).mean(0)
convert.write_world_coords(small, centre + 0.5 * (world(cage) - centre))
try:
    couple(skin, small)
    check("cage not enclosing refused", False, "Couple accepted a cage at half size")
except RuntimeError as e:
    check("cage not enclosing refused", "does not enclose" in str(e) or "outside" in str(e), str(e).strip()[:200])
pb0 = arm.pose.bones["wrist.R"]
pb0.rotation_mode = "XYZ"
pb0.rotation_euler = (0.3, 0.0, 0.0)
try:
    couple(skin, cage)
    check("posed armature refused", False, "Couple accepted a posed armature")
except RuntimeError as e:
    check("posed armature refused", "is posed" in str(e), str(e).strip()[:160])
pb0.rotation_euler = (0.0, 0.0, 0.0)
pb0.rotation_mode = "QUATERNION"
keyed = cage.copy()
keyed.data = cage.data.copy()
bpy.context.scene.collection.objects.link(keyed)
keyed.shape_key_add(name="Basis")
try:
    couple(skin, keyed)
    check("cage with shape keys refused", False, "Couple accepted a cage with shape keys")
except RuntimeError as e:
    check("cage with shape keys refused", "shape keys" in str(e), str(e).strip()[:160])
keyed_mesh = keyed.data
bpy.data.objects.remove(keyed)
bpy.data.meshes.remove(keyed_mesh)
check("refusals keep the skin uncoupled", not store.is_coupled(skin), "no binding stored")
bpy.data.objects.remove(small)

# ---- couple --------------------------------------------------------------------------------------
# The suite checks the paper's CageUp, which interpolates the skin at the fitting rows
# (Φ_R·C' = M'_R); the regularised default is checked at the end.
check("the current cage fit defaults to regularised", skin.cagerig.cage_fit == "regularised",
      skin.cagerig.cage_fit)
skin.cagerig.cage_fit = "paper"
rest_skin0 = world(skin)
couple(skin, cage)
check("couple", store.is_coupled(skin) and skin.cagerig.cage == cage, "binding stored with the skin")
c = engine.coupling(skin)
check("skin data untouched by couple", np.abs(world(skin) - rest_skin0).max() == 0.0, "rest skin as imported")

reported = engine.last_bind_progress
check("couple shows the binding's progress", reported is not None and reported[0] == "cage coordinates"
      and reported[1] == reported[2] > 0, f"last report {reported}")

# ---- the same edits through the Python package (what `cagerig edit` computes), step by step ---
# Blender's importers turn glTF/OBJ's +Y up into +Z up: (x, y, z)_file = (x, z, -y)_Blender.
to_file = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])
ref = cagerig.Rig.load(ARM_GLB, cage=ARM_CAGE, skinning="lbs", cage_fit="paper")
order = [ref.joint_names.index(n) for n in c.rig.joint_names]
# Vertex order: the glTF importer keeps it when it does not split vertices; check it.
e = float(np.abs(np.asarray(ref.rest_mesh) - rest_skin0 @ to_file.T).max())
check("glTF import keeps the vertex order", e <= TOL * diag, f"rest skins agree row by row ({e / diag:.2e})")


def compare_with_package(step: str) -> None:
    for what, ours, theirs in (
        ("rest skin M", world(skin) @ to_file.T, np.asarray(ref.rest_mesh)),
        ("posed skin M'", deformed_skin(skin) @ to_file.T, np.asarray(ref.posed_mesh)),
        ("rest cage C", np.asarray(c.rig.rest_cage) @ to_file.T, np.asarray(ref.rest_cage)),
        ("posed cage C'", np.asarray(c.rig.posed_cage) @ to_file.T, np.asarray(ref.posed_cage)),
        ("rest bones S", bone_heads(arm) @ to_file.T, np.asarray(ref.rest_joints)[order]),
    ):
        e = float(np.abs(ours - theirs).max())
        check(f"{step}: same as the Python package: {what}", e <= TOL * diag, f"{e / diag:.2e}")


# ---- 1. pose a bone: CageUp ---------------------------------------------------------------------
JOINT = "lowerarm01.R"
AXIS_BL = np.array([1.0, 0.0, 0.0])
heads0 = bone_heads(arm)
rotate_bone(arm, JOINT, AXIS_BL, 60.0)
update()
err = fit_row_error(skin, cage, c)
check("pose: Φ_R·C' = Blender's deformed skin (fit rows)", err <= TOL * diag, f"{err / diag:.2e} of the diagonal")
err_all = float(np.abs(np.asarray(c.rig.posed_mesh) - deformed_skin(skin)).max())
check("pose: rig's M' = Blender's deformed skin (all rows)", err_all <= TOL * diag, f"{err_all / diag:.2e}")
check("pose: cage shows C'", np.abs(world(cage) - c.rig.posed_cage).max() <= TOL * diag, "cage mesh = rig C'")
ref.rotate_joint(JOINT, to_file @ AXIS_BL, 60.0)
compare_with_package("pose")

# ---- 2. move three posed-cage vertices: CageRev + SkelUp ----------------------------------------
GRAB = [10, 13, 15]
OFFSET_BL = np.array([-0.15, -0.05, 0.2]) * diag / 10
before = world(cage)
target = before.copy()
target[GRAB] += OFFSET_BL
m_inv = np.linalg.inv(convert.matrix_np(cage.matrix_world))
for i in GRAB:
    cage.data.vertices[i].co = (m_inv[:3, :3] @ target[i] + m_inv[:3, 3]).tolist()
cage.data.update()
update()
after = world(cage)
others = np.setdiff1d(np.arange(len(after)), GRAB)
e_grab = float(np.abs(after[GRAB] - target[GRAB]).max())
e_others = float(np.abs(after[others] - before[others]).max())
check("grab: the three vertices stay where put", e_grab <= TOL * diag, f"{e_grab / diag:.2e}")
check("grab: the other cage vertices stay", e_others <= TOL * diag, f"{e_others / diag:.2e}")
err = fit_row_error(skin, cage, c)
check("grab: Φ_R·C' = Blender's new deformed skin", err <= TOL * diag, f"{err / diag:.2e}")
moved = float(np.abs(bone_heads(arm) - heads0).max())
check("grab: rest bones moved (SkelUp)", moved > 1e-4 * diag, f"max head move {moved / diag:.2e} of the diagonal")
e_bones = float(np.abs(bone_heads(arm) - c.rig.rest_joints).max())
check("grab: rest bones = rig's S", e_bones <= TOL * diag, f"{e_bones / diag:.2e}")
e_m = float(np.abs(world(skin) - c.rig.rest_mesh).max())
check("grab: skin mesh data = rig's M", e_m <= TOL * diag, f"{e_m / diag:.2e}")
ref.move_posed_cage(GRAB, (to_file @ OFFSET_BL)[None, :].repeat(len(GRAB), 0))
compare_with_package("grab")
check("grab: sync time", True, f"{c.last_sync_ms:.2f} ms (last sync, in the handler)")

# ---- 3. Rest Position: move rest-cage vertices --------------------------------------------------
arm.data.pose_position = "REST"
update()
check("rest position: cage shows C", np.abs(world(cage) - c.rig.rest_cage).max() <= TOL * diag, "cage mesh = rig C")
REST_MOVE = [0, 2, 4, 5, 6]
REST_OFFSET_BL = np.array([0.2, -0.15, -0.1]) * diag / 10
heads1 = bone_heads(arm)
target = world(cage)
target[REST_MOVE] += REST_OFFSET_BL
for i in REST_MOVE:
    cage.data.vertices[i].co = (m_inv[:3, :3] @ target[i] + m_inv[:3, 3]).tolist()
cage.data.update()
update()
phi = np.asarray(c.rig.cage_coords)
e_rest = float(np.abs(world(skin) - phi @ world(cage)).max())
check("rest edit: skin mesh data = Φ·C", e_rest <= TOL * diag, f"{e_rest / diag:.2e}")
moved = float(np.abs(bone_heads(arm) - heads1).max())
check("rest edit: bones moved (SkelUp)", moved > 1e-4 * diag, f"max head move {moved / diag:.2e}")
e_bones = float(np.abs(bone_heads(arm) - c.rig.rest_joints).max())
check("rest edit: rest bones = rig's S", e_bones <= TOL * diag, f"{e_bones / diag:.2e}")
ref.move_rest_cage(REST_MOVE, (to_file @ REST_OFFSET_BL)[None, :].repeat(len(REST_MOVE), 0))
arm.data.pose_position = "POSE"
update()
compare_with_package("rest edit, back in the pose")
err = fit_row_error(skin, cage, c)
check("back to pose: Φ_R·C' = Blender's deformed skin", err <= TOL * diag, f"{err / diag:.2e}")

# ---- save, reopen, sync again -------------------------------------------------------------------
path = os.path.join(WORK, "arm_coupled.blend")
snapshot = {"cage": world(cage), "skin": world(skin), "heads": bone_heads(arm)}
names = (skin.name, arm.name)
bpy.ops.wm.save_as_mainfile(filepath=path)
bpy.ops.wm.open_mainfile(filepath=path)
skin, arm = (bpy.data.objects[n] for n in names)
cage = skin.cagerig.cage
check("reopen: binding survived", store.is_coupled(skin) and cage is not None, f"cage {cage.name if cage else None}")
t0 = time.perf_counter()
c = engine.coupling(skin)
rebuild_ms = 1000 * (time.perf_counter() - t0)
e = max(float(np.abs(np.asarray(c.rig.posed_cage) - snapshot["cage"]).max()),
        float(np.abs(np.asarray(c.rig.rest_mesh) - snapshot["skin"]).max()),
        float(np.abs(np.asarray(c.rig.rest_joints) - snapshot["heads"]).max()))
check("reopen: rebuilt rig = state before saving", e <= TOL * diag, f"{e / diag:.2e} (rebuild {rebuild_ms:.0f} ms)")
rotate_bone(arm, "upperarm02.R", np.array([0.0, 1.0, 0.0]), 25.0)
update()
err = fit_row_error(skin, cage, c)
check("reopen: pose syncs (Φ_R·C' = deformed skin)", err <= TOL * diag, f"{err / diag:.2e}")
cage.data.vertices[20].co.z += 0.02 * diag
cage.data.update()
update()
err = fit_row_error(skin, cage, c)
check("reopen: grab syncs (Φ_R·C' = deformed skin)", err <= TOL * diag, f"{err / diag:.2e}")

# ---- a cage edit in Edit Mode: synced live (skin), bones when leaving Edit Mode -------------------
import bmesh  # noqa: E402

bpy.ops.object.select_all(action="DESELECT")
cage.select_set(True)
bpy.context.view_layer.objects.active = cage
bpy.ops.object.mode_set(mode="EDIT")
bm = bmesh.from_edit_mesh(cage.data)
bm.verts.ensure_lookup_table()
rest_skin_before = world(skin)
bm.verts[30].co.z -= 0.02 * diag
bmesh.update_edit_mesh(cage.data)
update()
e = float(np.abs(world(skin) - rest_skin_before).max())
check("edit mode: rest skin updated live", e > 1e-6 * diag, f"rest skin moved by {e / diag:.2e}")
bpy.ops.object.mode_set(mode="OBJECT")
update()
err = fit_row_error(skin, cage, c)
check("edit mode: after leaving it, Φ_R·C' = deformed skin", err <= TOL * diag, f"{err / diag:.2e}")
e_bones = float(np.abs(bone_heads(arm) - c.rig.rest_joints).max())
check("edit mode: rest bones = rig's S after leaving it", e_bones <= TOL * diag, f"{e_bones / diag:.2e}")
bpy.context.view_layer.objects.active = skin

# ---- undo ---------------------------------------------------------------------------------------
# Background Blender keeps an undo stack when pushed explicitly; Ctrl+Z runs ed.undo.
try:
    bpy.ops.ed.undo_push(message="before grab")
    before_cage = world(cage)
    before_store = store.load(skin).rest_cage
    cage.data.vertices[21].co.x += 0.03 * diag
    cage.data.update()
    update()
    bpy.ops.ed.undo_push(message="grab")
    skin_name = skin.name
    bpy.ops.ed.undo()
    update()
    skin = bpy.data.objects[skin_name]
    cage = skin.cagerig.cage
    c = engine.coupling(skin)
    e1 = float(np.abs(world(cage) - before_cage).max())
    e2 = float(np.abs(store.load(skin).rest_cage - before_store).max())
    err = fit_row_error(skin, cage, c)
    check("undo: cage and stored C restored", e1 <= TOL * diag and e2 <= TOL * diag,
          f"{e1 / diag:.2e}, {e2 / diag:.2e}")
    check("undo: consistent after undo (Φ_R·C' = deformed skin)", err <= TOL * diag, f"{err / diag:.2e}")
except RuntimeError as e:
    print(f"skip undo: {e}")
    results.append(f"skip undo: {e}")

# ---- bake ---------------------------------------------------------------------------------------
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 5
arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
pb = arm.pose.bones[JOINT]
pb.rotation_mode = "QUATERNION"
q0 = pb.rotation_quaternion.copy()
from mathutils import Quaternion  # noqa: E402

for f, deg in ((1, 0.0), (5, 40.0)):
    pb.rotation_quaternion = q0 @ Quaternion((1.0, 0.0, 0.0), math.radians(deg))
    pb.keyframe_insert("rotation_quaternion", frame=f)
scene.frame_set(3)  # the frame-change handler syncs (no explicit call)
err = fit_row_error(skin, cage, c)
check("animation: at frame 3, Φ_R·C' = deformed skin", err <= TOL * diag, f"{err / diag:.2e}")
live_cage_f3 = world(cage)
bpy.context.view_layer.objects.active = skin
bpy.ops.cagerig.bake()
keys = cage.data.shape_keys.key_blocks if cage.data.shape_keys else []
check("bake: one shape key per frame", len(keys) == 6, f"{len(keys)} keys (basis + 5)")
scene.frame_set(3)
dg = bpy.context.evaluated_depsgraph_get()
ev = cage.evaluated_get(dg)
baked = convert.world_coords(cage, ev.data)
e = float(np.abs(baked - live_cage_f3).max())
check("bake: the baked cage at frame 3 = the live sync's", e <= TOL * diag, f"{e / diag:.2e}")
check("bake: live sync off", not skin.cagerig.live, "skin.cagerig.live = False")

# ---- Preserve Volume = DQS --------------------------------------------------------------------
for sk in list(cage.data.shape_keys.key_blocks)[::-1] if cage.data.shape_keys else []:
    cage.shape_key_remove(sk)
arm.animation_data_clear()
skin.cagerig.live = True
arm.data.pose_position = "REST"  # the cage shows C: the rest cage to couple again with
update()
bpy.context.view_layer.objects.active = skin
bpy.ops.cagerig.uncouple()
check("uncouple", not store.is_coupled(skin), "binding removed, state kept")
arm.data.pose_position = "POSE"
mod = next(m for m in skin.modifiers if m.type == "ARMATURE")
mod.use_deform_preserve_volume = True
for p in arm.pose.bones:
    p.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)
update()
couple(skin, cage)
c = engine.coupling(skin)
check("preserve volume couples as DQS", c.rig.skinning == "dqs", c.rig.skinning)
rotate_bone(arm, JOINT, AXIS_BL, 70.0)
rotate_bone(arm, "wrist.R", np.array([0.0, 0.0, 1.0]), 30.0)
update()
e = float(np.abs(np.asarray(c.rig.posed_mesh) - deformed_skin(skin)).max())
check("DQS: rig's M' = Blender's Preserve Volume skin", e <= TOL * diag, f"{e / diag:.2e}")
rows = c.rig.fit_rows
ghost = cagerig.lbs(c.rig.rest_mesh, c.rig.skin_weights, c.rig.skinning_transforms)
e = float(np.abs(np.asarray(c.rig.cage_coords)[rows] @ world(cage) - ghost[rows]).max())
check("DQS: Φ_R·C' = the LBS ghost of the fitting rows", e <= TOL * diag, f"{e / diag:.2e}")

# ---- Generate Cage, then couple with it ---------------------------------------------------------
arm.data.pose_position = "REST"
update()
bpy.context.view_layer.objects.active = skin
bpy.ops.cagerig.uncouple()
arm.data.pose_position = "POSE"
mod.use_deform_preserve_volume = False  # LBS: Φ_R·C' fits the displayed skin (DQS: its LBS ghost)
for p in arm.pose.bones:
    p.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)
update()
bpy.ops.object.select_all(action="DESELECT")
skin.select_set(True)
bpy.context.view_layer.objects.active = skin
bpy.ops.cagerig.generate_cage(vertices=80)
generated = skin.cagerig.cage
check("generate cage", generated is not None and generated != cage and 40 <= len(generated.data.vertices) <= 200,
      f"{generated.name if generated else None}: {len(generated.data.vertices) if generated else 0} vertices")
couple(skin, generated)
c = engine.coupling(skin)
rotate_bone(arm, JOINT, AXIS_BL, 45.0)
update()
err = fit_row_error(skin, generated, c)
check("generated cage: Φ_R·C' = deformed skin after a pose", err <= TOL * diag, f"{err / diag:.2e}")

# ---- the regularised current cage: switched on the coupled skin, stored with the binding -----------
paper_cage = world(generated)
skin.cagerig.cage_fit = "regularised"
update()
c = engine.coupling(skin)
applied = store.applied_options(skin)
check("cage fit switch: the rig is rebuilt with it", c.rig.cage_fit == "regularised" and
      applied.cage_fit == "regularised", f"{c.rig.cage_fit}, stored {applied.cage_fit}")
e = float(np.abs(np.asarray(c.rig.posed_mesh) - deformed_skin(skin)).max())
check("regularised: rig's M' = Blender's deformed skin", e <= TOL * diag, f"{e / diag:.2e}")
e = float(np.abs(world(generated) - np.asarray(c.rig.posed_cage)).max())
check("regularised: the cage shows the rig's C'", e <= TOL * diag, f"{e / diag:.2e}")
moved = float(np.abs(world(generated) - paper_cage).max())
check("regularised: C' differs from the paper's", moved > TOL * diag, f"{moved / diag:.2e}")



# ---- every rig option: stored with the skin, a change rebinds, undo restores it ------------------
def consistent(step: str, skin: bpy.types.Object, cage: bpy.types.Object, arm: bpy.types.Object) -> None:
    """What Blender shows is what the rig computes: posed skin, cage, rest skin, rest bones."""
    c = engine.coupling(skin)
    shown_cage = world(cage)
    target = np.asarray(c.rig.posed_cage if arm.data.pose_position == "POSE" else c.rig.rest_cage)
    for what, e in (
        ("rig's M' = Blender's deformed skin", float(np.abs(np.asarray(c.rig.posed_mesh) - deformed_skin(skin)).max())),
        ("the cage shows the rig's cage", float(np.abs(shown_cage - target).max())),
        ("skin mesh data = rig's M", float(np.abs(world(skin) - np.asarray(c.rig.rest_mesh)).max())),
        ("rest bones = rig's S", float(np.abs(bone_heads(arm) - np.asarray(c.rig.rest_joints)).max())),
    ):
        check(f"{step}: {what}", e <= TOL * diag, f"{e / diag:.2e}")


def set_option(skin: bpy.types.Object, name: str, value: str) -> None:
    bpy.ops.ed.undo_push(message=f"before {name}")
    setattr(skin.cagerig, name, value)
    update()
    bpy.ops.ed.undo_push(message=f"{name} = {value}")


# On the Arm's own cage (Green's CageUp is the fragile one, docs/green-coordinates.md: the Arm's
# elbow bends in 6° steps there; the generated cage refuses steps of that size), from the rest pose.
arm.data.pose_position = "REST"
update()
bpy.context.view_layer.objects.active = skin
bpy.ops.cagerig.uncouple()
for p in arm.pose.bones:
    p.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)
arm.data.pose_position = "POSE"
update()
couple(skin, cage)
c = engine.coupling(skin)
mvc_rest_skin = world(skin)
check("options: the names are the package's", [i.identifier for i in skin.cagerig.bl_rna.properties["coords"].enum_items]
      == list(cagerig.COORDS_KINDS), str(list(cagerig.COORDS_KINDS)))
set_option(skin, "coords", "green")
c = engine.coupling(skin)
applied = store.applied_options(skin)
check("coords = green rebinds", c.rig.coords == "green" and applied.coords == "green",
      f"rig {c.rig.coords}, stored {applied.coords}")
consistent("green", skin, cage, arm)
rotate_bone(arm, JOINT, AXIS_BL, 6.0)
update()
consistent("green, posed", skin, cage, arm)
cage.data.vertices[5].co.z += 0.02 * diag
cage.data.update()
update()
consistent("green, after a grab", skin, cage, arm)
# The default Green rig (fold-safe face term, regularised fit) bends the elbow on in 30° steps
# to 156° without a refusal.
error, bent = "", 6.0
while not error and bent < 150.0:
    rotate_bone(arm, JOINT, AXIS_BL, 30.0)
    bent += 30.0
    update()
    error = engine.last_error(skin) or ""
check("green (fold-safe, regularised): the elbow bends to 156° with a fitted cage", not error and bent > 150.0,
      f"bent to {bent:.0f}°" + (f", refused: {error[:120]}" if error else ", no refusal"))
consistent("green, bent far", skin, cage, arm)
# Lipman's face term with the rows alone still meets poses with no fitted cage: back to 6°, switch,
# and bend on until one.
rotate_bone(arm, JOINT, AXIS_BL, 6.0 - bent)
bent = 6.0
update()
set_option(skin, "green_face_term", "lipman")
set_option(skin, "cage_fit", "paper")
c = engine.coupling(skin)
check("green_face_term = lipman rebinds", c.rig.green_face_term == "lipman" and c.rig.cage_fit == "paper",
      f"{c.rig.green_face_term}, {c.rig.cage_fit}")
error = engine.last_error(skin) or ""
before = {"skin": world(skin), "bones": bone_heads(arm), "cage": world(cage)}
while not error and bent < 400.0:
    before = {"skin": world(skin), "bones": bone_heads(arm), "cage": world(cage)}
    rotate_bone(arm, JOINT, AXIS_BL, 30.0)
    bent += 30.0
    update()
    error = engine.last_error(skin) or ""
print(f"green: first refusal at {bent:.0f}°")
e = max(float(np.abs(world(skin) - before["skin"]).max()), float(np.abs(bone_heads(arm) - before["bones"]).max()),
        float(np.abs(world(cage) - before["cage"]).max()))
check("green: a pose with no fitted cage is refused, said, and changes nothing", "refused" in error and e == 0.0,
      f"{error[:120]}… ; skin, bones, cage moved by {e:.1e}")
set_option(skin, "unfitted_cage", "keep")
c = engine.coupling(skin)
check("unfitted_cage = keep keeps that pose, the cage unfitted, and says so",
      c.rig.unfitted_cage == "keep" and store.applied_options(skin).unfitted_cage == "keep"
      and c.rig.posed_cage_unfitted is not None and any("closest fit" in m for m in c.messages),
      f"{c.rig.unfitted_cage}; {c.rig.posed_cage_unfitted}; panel: {c.messages[:1]}")
consistent("green, unfitted cage kept", skin, cage, arm)
skin_name, arm_name = skin.name, arm.name
# Undo, step by step, the unfitted-cage policy, the cage fit, the face term, the grab and the
# switch to Green (the pose steps between them are the armature's own).
for _ in range(10):
    if bpy.data.objects[skin_name].cagerig.coords == "mvc":
        break
    bpy.ops.ed.undo()
update()
skin, arm = bpy.data.objects[skin_name], bpy.data.objects[arm_name]
cage = skin.cagerig.cage
c = engine.coupling(skin)
applied = store.applied_options(skin)
check("undo: the options come back",
      (skin.cagerig.coords, skin.cagerig.unfitted_cage, skin.cagerig.green_face_term, skin.cagerig.cage_fit,
       applied.coords, c.rig.coords) == ("mvc", "refuse", "fold-safe", "regularised", "mvc", "mvc"),
      f"{skin.cagerig.coords}, {skin.cagerig.unfitted_cage}, {skin.cagerig.green_face_term}, "
      f"{skin.cagerig.cage_fit}, stored {applied.coords}")
e = float(np.abs(world(skin) - mvc_rest_skin).max())
check("undo: the mean value rest skin comes back", e <= TOL * diag, f"{e / diag:.2e}")
consistent("undo of the green rebind", skin, cage, arm)
mod = next(m for m in skin.modifiers if m.type == "ARMATURE")
set_option(skin, "skinning", "dqs")
c = engine.coupling(skin)
check("skinning = dqs is the modifier's Preserve Volume", mod.use_deform_preserve_volume and c.rig.skinning == "dqs"
      and store.applied_options(skin).skinning == "dqs", f"preserve volume {mod.use_deform_preserve_volume}, rig {c.rig.skinning}")
consistent("dqs", skin, cage, arm)
mod.use_deform_preserve_volume = False  # in the modifier's own panel: the same setting
update()
c = engine.coupling(skin)
check("Preserve Volume off in the modifier rebinds as LBS", skin.cagerig.skinning == "lbs" and c.rig.skinning == "lbs",
      f"{skin.cagerig.skinning}, rig {c.rig.skinning}")
consistent("lbs", skin, cage, arm)
set_option(skin, "skinning", "cor")
c = engine.coupling(skin)
keys = skin.data.shape_keys
check("skinning = cor rebinds, shown through a corrective key on the modifier's LBS",
      c.rig.skinning == "cor" and not mod.use_deform_preserve_volume and keys is not None
      and engine.COR_KEY in keys.key_blocks, f"rig {c.rig.skinning}, keys {list(keys.key_blocks.keys()) if keys else None}")
rotate_bone(arm, JOINT, AXIS_BL, 50.0)
update()
c = engine.coupling(skin)
lbs_ghost = cagerig.lbs(c.rig.rest_mesh, c.rig.skin_weights, c.rig.skinning_transforms)
e = float(np.abs(np.asarray(c.rig.posed_mesh) - lbs_ghost).max())
check("cor: the CoR skin differs from LBS at a 50° elbow", e > 1e-4 * diag, f"{e / diag:.2e}")
consistent("cor, posed", skin, cage, arm)
cage.data.vertices[7].co.y += 0.02 * diag
cage.data.update()
update()
consistent("cor, after a grab", skin, cage, arm)
arm.data.pose_position = "REST"
update()
e = float(np.abs(deformed_skin(skin) - np.asarray(engine.coupling(skin).rig.rest_mesh)).max())
check("cor, Rest Position: Blender shows the rest skin M", e <= TOL * diag, f"{e / diag:.2e}")
arm.data.pose_position = "POSE"
update()
consistent("cor, back in the pose", skin, cage, arm)
set_option(skin, "skinning", "lbs")
check("skinning back to lbs removes the corrective key", skin.data.shape_keys is None, "no shape keys")
consistent("lbs after cor", skin, cage, arm)
bpy.ops.ed.undo()
update()
skin, arm = bpy.data.objects[skin_name], bpy.data.objects[arm_name]
cage = skin.cagerig.cage
c = engine.coupling(skin)
check("undo: back to cor with its key", skin.cagerig.skinning == "cor" and c.rig.skinning == "cor"
      and skin.data.shape_keys is not None, f"{skin.cagerig.skinning}, rig {c.rig.skinning}")
consistent("undo to cor", skin, cage, arm)

# ---- a bone added after coupling: the sync pauses, says why, changes nothing; removed, it goes on --
shown_before = {"skin": world(skin), "cage": world(cage)}
bpy.ops.object.select_all(action="DESELECT")
bpy.context.view_layer.objects.active = arm
bpy.ops.object.mode_set(mode="EDIT")
extra = arm.data.edit_bones.new("extra")
extra.head, extra.tail = (0.0, 0.0, 0.0), (0.0, 0.0, 0.1 * diag)
bpy.ops.object.mode_set(mode="OBJECT")
update()
rotate_bone(arm, "wrist.R", np.array([0.0, 0.0, 1.0]), 20.0)
update()
error = engine.last_error(skin) or ""
e = max(float(np.abs(world(skin) - shown_before["skin"]).max()), float(np.abs(world(cage) - shown_before["cage"]).max()))
check("a bone added after coupling: the sync pauses and says so, nothing changes",
      "added extra" in error and e == 0.0, f"{error[:140]}; moved {e:.1e}")
bpy.ops.object.mode_set(mode="EDIT")
arm.data.edit_bones.remove(arm.data.edit_bones["extra"])
bpy.ops.object.mode_set(mode="OBJECT")
bpy.context.view_layer.objects.active = skin
update()
check("the bone removed again: the sync goes on", engine.last_error(skin) is None, str(engine.last_error(skin)))
consistent("bone removed again", skin, cage, arm)



# ---- the panel draws (headless Blender draws no UI: its draw() runs on a recording layout) -------
class RecordingLayout:
    """Records the panel's prop/operator/label calls; rows, columns and boxes are itself."""

    def __init__(self) -> None:
        self.props: list[str] = []
        self.operators: list[str] = []

    def prop(self, data: object, name: str, **_kw: object) -> None:
        if name not in data.bl_rna.properties:
            raise AttributeError(f"the panel draws {name!r}, which {data!r} does not have")
        self.props.append(name)

    def operator(self, idname: str, **_kw: object) -> object:
        module, name = idname.split(".")
        getattr(getattr(bpy.ops, module), name).get_rna_type()  # raises for an unknown operator
        self.operators.append(idname)
        return types.SimpleNamespace()

    def label(self, **_kw: object) -> None:
        pass

    def separator(self, **_kw: object) -> None:
        pass

    def column(self, **_kw: object) -> RecordingLayout:
        return self

    row = box = column


def draw_panel() -> RecordingLayout:
    layout = RecordingLayout()
    _addon.panel.CAGERIG_PT_main.draw(types.SimpleNamespace(layout=layout), bpy.context)
    return layout


bpy.context.view_layer.objects.active = skin
drawn = draw_panel()
check("panel of a coupled skin: the four rig options, Sync, Bake, Uncouple",
      {"coords", "cage_fit", "skinning", "unfitted_cage"} <= set(drawn.props)
      and {"cagerig.sync", "cagerig.bake", "cagerig.uncouple"} <= set(drawn.operators), f"{drawn.props}, {drawn.operators}")
bpy.context.view_layer.objects.active = skin
arm.data.pose_position = "REST"
update()
bpy.ops.cagerig.uncouple()
check("uncouple a CoR skin: the key goes, the skin shows its rest state", skin.data.shape_keys is None
      and not store.is_coupled(skin), "no shape keys, no binding")
arm.data.pose_position = "POSE"
update()


# ---- automatic weights: cagerig's and Blender's bone heat, each against the artist's --------------
def weights_matrix(obj: bpy.types.Object, names: list[str]) -> np.ndarray:
    rows, cols, vals = convert.skin_weights_sparse(obj, names, [True] * len(names))
    w = np.zeros((len(obj.data.vertices), len(names)))
    w[rows, cols] = vals
    return w


def dominant(w: np.ndarray) -> np.ndarray:
    d = w.argmax(axis=1)
    d[w.max(axis=1) <= 0.0] = -1  # no weight at all: agrees with nothing
    return d


def weighted_copy(skin: bpy.types.Object, arm: bpy.types.Object, how: str) -> tuple[bpy.types.Object, float]:
    """A copy of ``skin`` without vertex groups, weighted by Object ▸ Parent with cagerig's or
    Blender's automatic weights (the armature active, the copy selected); and the seconds it took."""
    obj = skin.copy()
    obj.data = skin.data.copy()
    obj.name = f"{skin.name}.{how}"
    bpy.context.scene.collection.objects.link(obj)
    obj.vertex_groups.clear()
    for m in [m for m in obj.modifiers if m.type == "ARMATURE"]:
        obj.modifiers.remove(m)
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    arm.select_set(True)
    bpy.context.view_layer.objects.active = arm
    t0 = time.perf_counter()
    if how == "cagerig":
        bpy.ops.cagerig.auto_weights(max_influences=4)
    else:
        bpy.ops.object.parent_set(type="ARMATURE_AUTO")
    seconds = time.perf_counter() - t0
    mods = [m for m in obj.modifiers if m.type == "ARMATURE"]
    check(f"{how} weights of {skin.name}: one Armature modifier on {arm.name}",
          len(mods) == 1 and mods[0].object == arm and obj.parent == arm, f"{len(mods)} modifier(s)")
    return obj, seconds


def compare_weights(skin: bpy.types.Object, arm: bpy.types.Object, label: str) -> dict[str, object]:
    names, _, _, deform = convert.rest_skeleton(arm)
    artist = dominant(weights_matrix(skin, names))
    out: dict[str, object] = {}
    for how in ("cagerig", "heat"):
        obj, seconds = weighted_copy(skin, arm, how)
        w = weights_matrix(obj, names)
        agreement = float(np.mean(dominant(w) == artist))
        out[how] = (obj, agreement, seconds)
        print(f"weights {label} {how}: agreement {agreement:.3f}, {seconds:.2f} s", flush=True)
        if how == "cagerig":
            per_vertex = (w > 0).sum(axis=1)
            sums = w.sum(axis=1)
            check(f"{label}: cagerig weights as vertex groups (rows sum to 1, at most 4 bones, deforming bones only)",
                  np.abs(sums - 1).max() < 1e-5 and per_vertex.max() <= 4
                  and not w[:, ~np.asarray(deform, dtype=bool)].any(),
                  f"max |sum - 1| {np.abs(sums - 1).max():.1e}, max influences {per_vertex.max()}")
    cg, heat = out["cagerig"][1], out["heat"][1]
    check(f"{label}: dominant-joint agreement with the artist's, cagerig ≥ Blender's bone heat", cg >= heat,
          f"cagerig {cg:.3f} ({out['cagerig'][2]:.2f} s), bone heat {heat:.3f} ({out['heat'][2]:.2f} s)")
    return out


# Bone heat weights each bone's head → tail segment. glTF has joints, not tails: the importer's
# "Temperance" heuristic points each bone at its child (Blender 3.4's default; >= 4.2's default,
# "Blender", points it along the joint's own Y axis, which bone heat then follows: Arm 0.50, Fox
# 0.35, Walk deviation 0.021). cagerig's weights use the joints only.
HEAT_IMPORT = {"bone_heuristic": "TEMPERANCE"}
menu = bpy.types.VIEW3D_MT_object_parent._dyn_ui_initialize()
check("Object ▸ Parent lists With cagerig Automatic Weights", any(f.__module__ == _addon.weights.__name__ for f in menu),
      f"{len(menu)} draw functions")
skin, arm, cage = load_arm(**HEAT_IMPORT)
compare_weights(skin, arm, "Arm")
# The panel's way in: the active mesh, its Armature modifier's armature, its cage selected too.
bpy.ops.object.select_all(action="DESELECT")
copy = skin.copy()
copy.data = skin.data.copy()
bpy.context.scene.collection.objects.link(copy)
copy.vertex_groups.clear()
copy.select_set(True)
cage.select_set(True)
bpy.context.view_layer.objects.active = copy
bpy.ops.cagerig.auto_weights(max_influences=2)
w = weights_matrix(copy, convert.rest_skeleton(arm)[0])
check("panel: the active mesh weighted for its modifier's armature, bounded by the selected cage, 2 influences",
      (w > 0).sum(axis=1).max() <= 2 and np.abs(w.sum(axis=1) - 1).max() < 1e-5, f"{len(copy.vertex_groups)} groups")
drawn = draw_panel()
check("panel of an uncoupled mesh: the options, Generate Cage, Couple, Automatic Weights",
      {"coords", "cage_fit", "skinning", "unfitted_cage", "cage_vertices"} <= set(drawn.props)
      and {"cagerig.generate_cage", "cagerig.couple", "cagerig.auto_weights"} <= set(drawn.operators),
      f"{drawn.props}, {drawn.operators}")
skin_name = skin.name
skin.cagerig.cage_fit = "regularised"
couple(skin, cage)
bpy.ops.object.select_all(action="DESELECT")
skin.select_set(True)
bpy.context.view_layer.objects.active = skin
try:
    bpy.ops.cagerig.auto_weights()
    check("a coupled skin is not re-weighted", False, "the operator re-weighted a coupled skin")
except RuntimeError as e:
    check("a coupled skin is not re-weighted", "uncouple" in str(e), str(e).strip()[:160])

for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
bpy.ops.import_scene.gltf(filepath=FOX_GLB, **HEAT_IMPORT)
fox = next(o for o in bpy.data.objects if o.type == "MESH" and any(m.type == "ARMATURE" for m in o.modifiers))
fox_arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
print(f"Fox: {len(fox.data.vertices)} vertices, {len(fox_arm.data.bones)} bones")
res = compare_weights(fox, fox_arm, "Fox")
# The Walk at t = 0.45 s, skinned by Blender's Armature modifier with each set of weights.
walk = next(a for a in bpy.data.actions if "walk" in a.name.lower())
fox_arm.animation_data_create()
fox_arm.animation_data.action = walk
if hasattr(fox_arm.animation_data, "action_slot") and fox_arm.animation_data.action_slot is None and walk.slots:
    fox_arm.animation_data.action_slot = walk.slots[0]
scene = bpy.context.scene
t = walk.frame_range[0] + 0.45 * scene.render.fps / scene.render.fps_base
scene.frame_set(int(math.floor(t)), subframe=t - math.floor(t))
rest = world(fox)
fox_diag = float(np.linalg.norm(rest.max(0) - rest.min(0)))
artist_pose = deformed_skin(fox)
moved = float(np.linalg.norm(artist_pose - rest, axis=1).mean()) / fox_diag
check("Fox Walk: the artist's skin moves at t = 0.45 s", moved > 1e-3, f"mean move {moved:.3f} of the diagonal")
dev = {how: float(np.linalg.norm(deformed_skin(res[how][0]) - artist_pose, axis=1).mean()) / fox_diag
       for how in ("cagerig", "heat")}
check("Fox Walk deviation from the artist's skin, cagerig ≤ Blender's bone heat", dev["cagerig"] <= dev["heat"],
      f"cagerig {dev['cagerig']:.4f}, bone heat {dev['heat']:.4f} of the diagonal")


# ---- undo and redo across a couple, a pose and a grab --------------------------------------------
skin, arm, cage = load_arm()
names = (skin.name, arm.name, cage.name)
skin.cagerig.cage_fit = "regularised"
update()
bpy.ops.ed.undo_push(message="imported")
imported = {"skin": world(skin), "cage": world(cage), "heads": bone_heads(arm)}
couple(skin, cage)
bpy.ops.ed.undo_push(message="couple")
rotate_bone(arm, JOINT, AXIS_BL, 40.0)
update()
cage.data.vertices[12].co.x += 0.03 * diag
cage.data.update()
update()
bpy.ops.ed.undo_push(message="pose and grab")
grabbed = {"skin": world(skin), "cage": world(cage), "heads": bone_heads(arm)}


def objects() -> tuple[bpy.types.Object, bpy.types.Object, bpy.types.Object]:
    return tuple(bpy.data.objects[n] for n in names)  # type: ignore[return-value]


def same(state: dict[str, np.ndarray], skin: bpy.types.Object, cage: bpy.types.Object, arm: bpy.types.Object) -> float:
    return max(float(np.abs(world(skin) - state["skin"]).max()), float(np.abs(world(cage) - state["cage"]).max()),
               float(np.abs(bone_heads(arm) - state["heads"]).max()))


bpy.ops.ed.undo()
update()
skin, arm, cage = objects()
check("undo of a pose and a grab: still coupled, consistent", store.is_coupled(skin), "coupled")
consistent("undo of a pose and a grab", skin, cage, arm)
bpy.ops.ed.undo()
update()
skin, arm, cage = objects()
e = same(imported, skin, cage, arm)
check("undo of the couple: uncoupled, skin, cage and bones as imported", not store.is_coupled(skin) and e == 0.0,
      f"moved {e:.1e}")
bpy.ops.ed.redo()
bpy.ops.ed.redo()
update()
skin, arm, cage = objects()
e = same(grabbed, skin, cage, arm)
check("redo of both: coupled, the grab's state back", store.is_coupled(skin) and e <= TOL * diag, f"{e / diag:.2e}")
consistent("redo of the couple, the pose and the grab", skin, cage, arm)

# ---- Ctrl-Z in the cage's Edit Mode: the edit-mesh step is undone, the coupling follows ----------
bpy.ops.object.select_all(action="DESELECT")
bpy.context.view_layer.objects.active = cage
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.ed.undo_push(message="edit mode entered")
bm = bmesh.from_edit_mesh(cage.data)
bm.verts.ensure_lookup_table()
bm.verts[25].co.z += 0.03 * diag
bmesh.update_edit_mesh(cage.data)
update()
e = float(np.abs(world(skin) - grabbed["skin"]).max())
check("Edit Mode grab: the rest skin follows live", e > 1e-4 * diag, f"moved {e / diag:.2e}")
bpy.ops.ed.undo_push(message="edit-mode grab")
bpy.ops.ed.undo()
update()
skin, arm, cage = objects()
bpy.context.view_layer.objects.active = cage
bpy.ops.object.mode_set(mode="OBJECT")
update()
e = same(grabbed, skin, cage, arm)
check("Ctrl-Z in Edit Mode: the edit-mode grab undone, skin, cage and bones as before it", e <= TOL * diag,
      f"{e / diag:.2e}")
consistent("after Ctrl-Z in Edit Mode", skin, cage, arm)

# ---- dead ends a Blender user runs into: each works, or is refused saying what to do ------------
from mathutils import Matrix  # noqa: E402


def import_arm_beside() -> tuple[bpy.types.Object, bpy.types.Object, bpy.types.Object]:
    """One more Arm with its cage, next to what the scene holds (load_arm empties the scene)."""
    before = set(bpy.data.objects)
    bpy.ops.import_scene.gltf(filepath=ARM_GLB)
    new = [o for o in bpy.data.objects if o not in before]
    skin_ = next(o for o in new if o.type == "MESH" and any(m.type == "ARMATURE" for m in o.modifiers))
    arm_ = next(o for o in new if o.type == "ARMATURE")
    for o in new:
        if o.type == "MESH" and o is not skin_:
            bpy.data.objects.remove(o)
    bpy.ops.wm.obj_import(filepath=ARM_CAGE)
    return skin_, arm_, bpy.context.selected_objects[0]


def refused(what: str, skin_: bpy.types.Object, cage_: bpy.types.Object, *needles: str) -> None:
    try:
        couple(skin_, cage_)
        check(f"{what}: refused", False, "Couple accepted it")
    except RuntimeError as e:
        message = str(e).strip()
        check(f"{what}: refused saying what to do", all(n in message for n in needles) and not store.is_coupled(skin_),
              message[:200])


def edit_cage(cage_: bpy.types.Object, edit) -> None:  # noqa: ANN001
    bm = bmesh.new()
    bm.from_mesh(cage_.data)
    edit(bm)
    bm.to_mesh(cage_.data)
    bm.free()
    cage_.data.update()


skin, arm, cage = load_arm()
bpy.context.view_layer.objects.active = cage
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
bpy.ops.mesh.tris_convert_to_quads()
bpy.ops.object.mode_set(mode="OBJECT")


def dissolve_one_edge_between_quads(bm: bmesh.types.BMesh) -> None:
    edge = next(e for e in bm.edges if len(e.link_faces) == 2 and all(len(f.verts) == 4 for f in e.link_faces))
    bmesh.ops.dissolve_edges(bm, edges=[edge])


edit_cage(cage, dissolve_one_edge_between_quads)
sides = sorted({len(p.vertices) for p in cage.data.polygons})
check("a cage of quads and an n-gon: made", 4 in sides and max(sides) > 4, f"face sizes {sides}")
couple(skin, cage)
rotate_bone(arm, JOINT, AXIS_BL, 40.0)
update()
consistent("a cage of quads and an n-gon, posed", skin, cage, arm)

skin, arm, cage = load_arm()
edit_cage(cage, lambda bm: (bm.faces.ensure_lookup_table(),
                            bmesh.ops.delete(bm, geom=[bm.faces[0]], context="FACES_ONLY")))
refused("a cage with a hole", skin, cage, "must be closed", "Non Manifold")
skin, arm, cage = load_arm()
far = Matrix.Translation((50.0 * diag, 0.0, 0.0))
edit_cage(cage, lambda bm: bmesh.ops.create_cube(bm, size=0.1 * diag, matrix=far))
refused("a cage with a loose part", skin, cage, "2 separate parts", "loose parts")

skin, arm, cage = load_arm()
skin.shape_key_add(name="Basis")
refused("a skin with a shape key", skin, cage, "shape keys", "apply or remove")
skin, arm, cage = load_arm()
for m in [m for m in skin.modifiers if m.type == "ARMATURE"]:
    skin.modifiers.remove(m)
refused("vertex groups and no Armature modifier", skin, cage, "no Armature modifier", "add one")

skin, arm, cage = load_arm()
subsurf = skin.modifiers.new("Subdivision", "SUBSURF")
couple(skin, cage)
rotate_bone(arm, JOINT, AXIS_BL, 40.0)
update()
subsurf.show_viewport = False
consistent("a Subdivision Surface after the Armature modifier (the skin under it)", skin, cage, arm)
subsurf.show_viewport = True
update()
check("a Subdivision Surface after the Armature modifier: it subdivides the posed skin",
      len(deformed_skin(skin)) > len(skin.data.vertices), f"{len(deformed_skin(skin))} evaluated vertices")

skin, arm, cage = load_arm()
parent = bpy.data.objects.new("character", None)
bpy.context.scene.collection.objects.link(parent)
parent.location = (0.5 * diag, -0.2 * diag, 0.1 * diag)
parent.rotation_euler = (0.3, 0.0, 0.7)
parent.scale = (2.0, 2.0, 2.0)
for o in (arm, cage):
    o.parent = parent
update()
couple(skin, cage)
rotate_bone(arm, JOINT, AXIS_BL, 40.0)
update()
diag_scaled, diag = diag, 2.0 * diag  # the character is twice as large in the world
consistent("a character parented, moved, turned and scaled ×2", skin, cage, arm)
diag = diag_scaled

skin, arm, cage = load_arm()
second = import_arm_beside()
couple(skin, cage)
couple(second[0], second[2])
second_cage = world(second[2])
rotate_bone(arm, JOINT, AXIS_BL, 40.0)
update()
consistent("two characters: the posed one", skin, cage, arm)
check("two characters: the other stays", float(np.abs(world(second[2]) - second_cage).max()) == 0.0, "its cage unmoved")
rotate_bone(second[1], JOINT, AXIS_BL, -30.0)
update()
consistent("two characters: the other posed", second[0], second[2], second[1])

# A .blend saved coupled, opened and edited where the add-on is missing, then re-enabled.
skin, arm, cage = load_arm()
couple(skin, cage)
rotate_bone(arm, JOINT, AXIS_BL, 20.0)
update()
coupled_blend = os.path.join(WORK, "dead_ends_coupled.blend")
bpy.ops.wm.save_as_mainfile(filepath=coupled_blend)
names = (skin.name, arm.name, cage.name)
bpy.ops.preferences.addon_disable(module=_addon.__name__)
bpy.ops.wm.open_mainfile(filepath=coupled_blend)
skin, arm, cage = objects()
rotate_bone(arm, JOINT, AXIS_BL, 20.0)  # posed further without cagerig
update()
without = os.path.join(WORK, "dead_ends_edited_without.blend")
bpy.ops.wm.save_as_mainfile(filepath=without)
bpy.ops.preferences.addon_enable(module=_addon.__name__)
engine, store = sys.modules[_addon.__name__].engine, sys.modules[_addon.__name__].store
bpy.ops.wm.open_mainfile(filepath=without)
skin, arm, cage = objects()
update()
check("opened where the add-on was missing, then re-enabled: still coupled", store.is_coupled(skin), "coupled")
engine.sync(skin)
consistent("opened where the add-on was missing, then re-enabled", skin, cage, arm)

# A character linked from another .blend: nothing written where Blender would not save it.
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
with bpy.data.libraries.load(coupled_blend, link=True) as (source, linked):
    linked.objects = list(source.objects)
for o in linked.objects:
    bpy.context.scene.collection.objects.link(o)
skin, arm, cage = objects()
before_sync = world(cage)
try:
    engine.sync(skin)
    check("a linked character: its sync refused", False, "synced into linked data")
except engine.SyncError as e:
    check("a linked character: its sync refused saying what to do", "linked from" in str(e)
          and "Make Local" in str(e) and float(np.abs(world(cage) - before_sync).max()) == 0.0, str(e)[:200])

print("\n".join(["", "summary:"] + results))
