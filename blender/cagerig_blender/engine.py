"""The coupling at run time: one cagerig.Rig per coupled skin, kept in step with Blender.

Where each state lives (docs/blender.md):

* the skin's mesh data holds the rest skin M (Blender's Armature modifier poses it into M');
* the armature's bones hold the rest skeleton S, its pose bones the pose S';
* the cage object's mesh data holds C' while the armature shows its pose, C in Rest Position;
* the Rig holds all six; the .blend holds the binding and C (store.py).

A sync compares what Blender shows with what the add-on last wrote and runs the paper's chain
for what changed: a pose change → set_pose (skinning, CageUp) → C' written into the cage; a
posed-cage edit → move_posed_cage (CageRev, SkelUp) → M into the skin, S into the bones; a
rest-cage edit (Rest Position) → move_rest_cage (M = Φ·C, SkelUp) → M and S written.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import convert, store

# Base rigs (Φ, MaxVol, Ψ computed) by bind id: reopening or undoing copies one instead of
# recomputing the coordinates.
_base_rigs: dict[str, object] = {}
_couplings: dict[str, Coupling] = {}
_busy = False


class SyncError(Exception):
    """A sync could not run; the message says what the user should do."""


def armature_of(skin: bpy.types.Object) -> tuple[bpy.types.Object, bpy.types.ArmatureModifier]:
    """The skin's Armature modifier and its armature object, or SyncError saying what is wrong."""
    mods = [m for m in skin.modifiers if m.type == "ARMATURE"]
    if not mods:
        raise SyncError(f"{skin.name!r} has no Armature modifier: add one that points at the armature")
    mod = mods[0]
    if mod.object is None or mod.object.type != "ARMATURE":
        raise SyncError(f"the Armature modifier of {skin.name!r} has no armature object set")
    return mod.object, mod


def linked_part(skin: bpy.types.Object, arm: bpy.types.Object, cage: bpy.types.Object) -> str | None:
    """Why the coupling cannot write its result, when the skin, the cage or their mesh data come
    from a linked library (Blender would not save what cagerig writes there): None otherwise.
    The armature may be linked through a library override: cagerig only reads its pose."""
    for obj, what in ((skin, "skin"), (cage, "cage")):
        for block in (obj, obj.data):
            if block.library is not None:
                return (f"the {what} {obj.name!r} is linked from {block.library.filepath!r}: cagerig cannot write "
                        "to linked data (Blender would not save it); couple the character in its own file, or "
                        "make it local (Object ▸ Relations ▸ Make Local ▸ Selected Objects and Data)")
    if arm.library is not None and arm.override_library is None:
        return (f"the armature {arm.name!r} is linked from {arm.library.filepath!r} and cannot be posed here: "
                "add a library override (Object ▸ Library Override ▸ Make)")
    return None


def cage_of(skin: bpy.types.Object) -> bpy.types.Object:
    cage = skin.cagerig.cage
    if cage is None:
        raise SyncError(f"{skin.name!r} has no cage object (it was deleted?): couple again")
    return cage


def options_of(skin: bpy.types.Object) -> store.RigOptions:
    """The rig options the user chose for ``skin``: its settings (props.py), and the skinning its
    Armature modifier shows (Preserve Volume: DQS)."""
    _, mod = armature_of(skin)
    s = skin.cagerig
    return store.RigOptions(
        coords=s.coords, cage_fit=s.cage_fit, skinning=convert.skinning_of(mod, s.use_cor),
        unfitted_cage=s.unfitted_cage, green_face_term=s.green_face_term,
    )


@dataclass
class Coupling:
    skin_name: str
    bind_id: str
    options: store.RigOptions  # the options this rig was built with
    rig: object  # cagerig.Rig
    parents: np.ndarray
    names: list[str]  # the bones coupled, joint j = bone j
    rest_heads: np.ndarray  # S as last written into the bones (world)
    last_cage: np.ndarray  # the cage as last written / seen (world, float32-rounded)
    last_transforms: tuple[np.ndarray, np.ndarray] | None  # last pose set (rotations, motion)
    last_mode: str
    bones_pending: bool = False
    # Built with options other than those the shown state was computed with: the next sync
    # writes the skin, the cage and the bones from this rig instead of reading them as edits.
    rebound: bool = False
    last_matrices: np.ndarray | None = None  # Blender's skinning transforms at the last pose read
    last_sync_ms: float = 0.0
    messages: list[str] = field(default_factory=list)


def _base_rig(b: store.Binding, options: store.RigOptions) -> object:
    import cagerig

    key = f"{b.bind_id}:{options.rig_key()}"
    rig = _base_rigs.get(key)
    if rig is None:
        n, nj = len(b.mesh), len(b.joints)
        weights = convert.SparseWeights((n, nj), b.weight_rows, b.weight_cols, b.weight_values)
        rig = with_progress(lambda progress: cagerig.Rig.from_arrays(
            b.mesh, b.triangles, weights, b.joints, b.parents, b.cage, b.cage_triangles,
            b.names, skinning=options.skinning, cage_fit=options.cage_fit, coords=options.coords,
            green_face_term=options.green_face_term, progress=progress,
        ))
        _base_rigs[key] = rig
    return rig.copy()


# The last report of a binding's progress: (stage, done, total), for the panel's tests.
last_bind_progress: tuple[str, int, int] | None = None


def with_progress(build) -> object:  # noqa: ANN001
    """``build(progress)`` on a worker thread while Blender's main thread shows its progress in
    the mouse cursor (``window_manager.progress_update``, which may only be called from the main
    thread). The library calls ``progress(stage, done, total)`` from its own threads; the binding
    releases Python's lock, so both threads run. An exception of ``build`` is raised here."""
    global last_bind_progress
    latest: list[float] = [0.0]
    outcome: dict[str, object] = {}

    def progress(stage: str, done: int, total: int) -> None:
        global last_bind_progress
        last_bind_progress = (stage, done, total)
        latest[0] = done / total if total else 0.0

    def run() -> None:
        try:
            outcome["rig"] = build(progress)
        except BaseException as e:  # noqa: BLE001  (raised again on the main thread)
            outcome["error"] = e

    last_bind_progress = None
    worker = threading.Thread(target=run, name="cagerig bind")
    wm = bpy.context.window_manager
    worker.start()
    if wm is not None:
        wm.progress_begin(0, 100)
    try:
        while worker.is_alive():
            if wm is not None:
                wm.progress_update(int(100 * latest[0]))
            worker.join(0.05)
    finally:
        if wm is not None:
            wm.progress_end()
    if "error" in outcome:
        raise outcome["error"]  # type: ignore[misc]
    return outcome["rig"]


def build_rig(b: store.Binding, options: store.RigOptions | None = None) -> object:
    """The rig in the stored state: the bind-time rig, built with ``options`` (default: the
    applied ones), with the stored rest cage applied."""
    options = options or b.options
    rig = _base_rig(b, options)
    rig.set_unfitted_cage(options.unfitted_cage)
    delta = b.rest_cage - b.cage
    moved = np.flatnonzero(np.any(delta != 0.0, axis=1))
    if len(moved):
        rig.move_rest_cage(moved, delta[moved])
    return rig


_suspended = False


def suspend(on: bool) -> None:
    """Stops (or resumes) every sync: while Blender restores an undo step."""
    global _suspended
    _suspended = on


def forget(skin_name: str | None = None) -> None:
    """Drops the run-time state (all of it, or one skin's); the next sync rebuilds it."""
    if skin_name is None:
        _couplings.clear()
    else:
        _couplings.pop(skin_name, None)


def forget_bases() -> None:
    _base_rigs.clear()


def displayed_cage(cage: bpy.types.Object) -> np.ndarray:
    edit = convert.edit_mode_world_coords(cage)
    return edit if edit is not None else convert.world_coords(cage)


def coupling(skin: bpy.types.Object) -> Coupling:
    """The run-time coupling of ``skin``, rebuilt from the stored binding when missing (file
    opened, undo) or when the user changed a rig option (a rebind: the next sync writes what the
    new rig shows). A rebuilt coupling with the applied options takes the cage as Blender shows
    it for a user edit, so that the next sync brings everything into step."""
    options = options_of(skin)
    c = _couplings.get(skin.name)
    if c is not None and c.bind_id == store.bind_id(skin) and c.options == options:
        return c
    b = store.load(skin)
    arm, _ = armature_of(skin)
    check_bones(arm, b.names)
    rig = build_rig(b, options)
    mode = arm.data.pose_position
    if mode == "POSE":
        t = convert.skinning_transforms(arm)
        q, motion, problems = convert.cagerig_pose(t, rig.rest_joints, b.parents, _tolerance(rig))
        rig.set_pose(q, motion)
        messages = _pose_messages(rig, problems)
        pose: tuple[np.ndarray, np.ndarray] | None = (q, motion)
        matrices: np.ndarray | None = t
        shown = rig.posed_cage
    else:
        pose = None
        matrices = None
        messages = []
        shown = rig.rest_cage
    c = Coupling(
        skin_name=skin.name,
        bind_id=b.bind_id,
        options=options,
        rig=rig,
        parents=b.parents,
        names=b.names,
        rest_heads=rig.rest_joints,
        last_cage=convert.as_displayed(cage_of(skin), shown),
        last_transforms=pose,
        last_mode=mode,
        rebound=options != b.options,
        messages=messages,
        last_matrices=matrices,
    )
    _couplings[skin.name] = c
    return c


def apply_options(skin: bpy.types.Object) -> None:
    """After the user changed a rig option of a coupled skin: rebinds now (the sync writes what
    the rebuilt rig shows). Errors go to the panel, as a live sync's do."""
    if store.is_coupled(skin):
        _sync_reporting(skin)


_tolerances: dict[int, float] = {}


def _tolerance(rig: object) -> float:
    """1e-6 of the rest skin's bounding-box diagonal (cached per rig: reading M copies it)."""
    t = _tolerances.get(id(rig))
    if t is None:
        m = rig.rest_mesh
        t = 1e-6 * float(np.linalg.norm(m.max(axis=0) - m.min(axis=0)))
        if len(_tolerances) > 64:
            _tolerances.clear()
        _tolerances[id(rig)] = t
    return t


def _mode_set(mode: str) -> None:
    """object.mode_set without an undo step and without the full view-layer evaluation that
    ``bpy.ops`` runs before and after every call from Python (at 133k vertices that is two
    evaluations of the skin per call). Falls back to ``bpy.ops`` where the low-level call differs."""
    try:
        from _bpy import ops as _ops  # type: ignore[import-not-found]

        if bpy.app.version >= (4, 0, 0):  # the context-dictionary argument was removed in 4.0
            _ops.call("object.mode_set", {"mode": mode}, "EXEC_DEFAULT", False)
        else:
            _ops.call("OBJECT_OT_mode_set", None, {"mode": mode}, "EXEC_DEFAULT", False)
    except (ImportError, TypeError, AttributeError):
        bpy.ops.object.mode_set("EXEC_DEFAULT", False, mode=mode)


def write_rest_bones(arm: bpy.types.Object, heads_world: np.ndarray) -> None:
    """Moves the rest bones' heads to ``heads_world`` (SkelUp's S) keeping each bone's
    orientation and length, so that the pose's local rotations mean what they meant. Bones are
    disconnected where needed (a connected child's head is its parent's tail). Enters the
    armature's Edit Mode for this and restores the previous mode and active object."""
    a_inv = np.linalg.inv(convert.matrix_np(arm.matrix_world))
    local = heads_world @ a_inv[:3, :3].T + a_inv[:3, 3]
    view_layer = bpy.context.view_layer
    prev_active = view_layer.objects.active
    prev_mode = arm.mode
    hidden = arm.hide_get()
    if hidden:
        arm.hide_set(False)
    try:
        view_layer.objects.active = arm
        with bpy.context.temp_override(active_object=arm, object=arm, edit_object=None):
            _mode_set("EDIT")
        ebones = arm.data.edit_bones
        names = [b.name for b in arm.data.bones]
        for eb in ebones:
            eb.use_connect = False
        for j, name in enumerate(names):
            eb = ebones[name]
            d = eb.tail - eb.head
            eb.head = local[j]
            eb.tail = eb.head + d
        with bpy.context.temp_override(active_object=arm, object=arm, edit_object=arm):
            _mode_set(prev_mode if prev_mode != "EDIT" else "OBJECT")
    finally:
        view_layer.objects.active = prev_active
        if hidden:
            arm.hide_set(True)


def sync(skin: bpy.types.Object) -> bool:
    """Runs one sync of ``skin``'s coupling; True when something was written."""
    global _busy
    if _busy or _suspended:
        return False
    _busy = True
    try:
        return _sync(skin)
    finally:
        _busy = False


def _sync(skin: bpy.types.Object) -> bool:
    start = time.perf_counter()
    arm, _mod = armature_of(skin)
    cage = cage_of(skin)
    linked = linked_part(skin, arm, cage)
    if linked is not None:
        raise SyncError(linked)
    if arm.mode == "EDIT":
        return False  # the user is editing the bones: Blender's rest data is in flux
    c = coupling(skin)
    check_bones(arm, c.names)
    rig = c.rig
    cage_in_edit = cage.mode == "EDIT"
    wrote = False
    if c.rebound:
        if cage_in_edit:
            raise SyncError(f"leave Edit Mode of {cage.name!r} to rebind with the new options ({c.options.describe()})")
        if c.options.skinning != "cor":
            remove_cor_key(skin)
        _write_rest_skin(skin, rig.rest_mesh)
        c.last_cage = _write_cage(cage, rig.posed_cage if c.last_mode == "POSE" else rig.rest_cage)
        store.save_applied_options(skin, c.options)
        c.rebound = False
        c.bones_pending = True
        wrote = True
    shown = displayed_cage(cage)
    if shown.shape != c.last_cage.shape:
        raise SyncError(
            f"the cage {cage.name!r} has {len(shown)} vertices, it had {len(c.last_cage)} when coupled: "
            "couple again after changing its topology"
        )
    mode = arm.data.pose_position
    rest_changed = False
    if mode != c.last_mode:
        # Pose Position <-> Rest Position: the cage shows the other state.
        if mode == "POSE":
            _set_pose_from(arm, c)
            target = rig.posed_cage
        else:
            target = rig.rest_cage
        c.last_mode = mode
        c.last_cage = _write_cage(cage, target) if not cage_in_edit else shown
        wrote = True
    elif mode == "POSE":
        changed = np.flatnonzero(np.any(shown != c.last_cage, axis=1))
        moved_by = shown[changed] - c.last_cage[changed]
        pose_changed = _set_pose_from(arm, c)
        if len(changed):
            # A grab lands where the user put the vertices; with a pose change in the same
            # update (rare), the user's displacement is applied to the new C'.
            offsets = moved_by if pose_changed else shown[changed] - rig.posed_cage[changed]
            rig.move_posed_cage(changed, offsets)
            rest_changed = True
        if pose_changed or rest_changed:
            if cage_in_edit:
                c.last_cage = shown
            else:
                c.last_cage = _write_cage(cage, rig.posed_cage)
            wrote = True
    else:
        changed = np.flatnonzero(np.any(shown != c.last_cage, axis=1))
        if len(changed):
            rig.move_rest_cage(changed, shown[changed] - rig.rest_cage[changed])
            c.last_cage = shown.copy()
            rest_changed = True
            wrote = True
    if rest_changed:
        _write_rest_skin(skin, rig.rest_mesh)
        store.save_rest_cage(skin, rig.rest_cage)
        c.bones_pending = True
    if c.bones_pending and not cage_in_edit:
        try:
            write_rest_bones(arm, rig.rest_joints)
        except RuntimeError as e:  # mode_set refused: the armature is not editable here
            raise SyncError(
                f"could not write SkelUp's rest bones into {arm.name!r} ({e}); is it in the view layer and "
                "editable? They will be written at the next sync"
            ) from None
        c.rest_heads = rig.rest_joints
        c.bones_pending = False
        wrote = True
    if wrote and c.options.skinning == "cor":
        _write_cor_key(skin, c)
    if wrote:
        c.last_sync_ms = 1000.0 * (time.perf_counter() - start)
    return wrote


# CoR skinning: Blender's Armature modifier has no CoR, so the skin shows it as the modifier's LBS
# of a corrective shape key. Per vertex, LBS is an affine map x ↦ L_v·x + t_v (Ω-blended skinning
# transforms); the key holds x = L_v⁻¹·(M'_v − t_v), whose LBS is cagerig's CoR skin M'_v. It is
# rewritten at every sync that changes what is shown (in Rest Position it is the rest skin).
COR_KEY = "cagerig CoR"


def _write_rest_skin(skin: bpy.types.Object, rest_mesh: np.ndarray) -> None:
    """M into the skin's mesh data, and into its basis shape key when it has keys (CoR)."""
    convert.write_world_coords(skin, rest_mesh)
    keys = skin.data.shape_keys
    if keys is not None:
        convert.write_key_world_coords(skin, keys.reference_key, rest_mesh)


def _write_cor_key(skin: bpy.types.Object, c: Coupling) -> None:
    rig = c.rig
    keys = skin.data.shape_keys
    if keys is None or COR_KEY not in keys.key_blocks:
        if keys is None:
            skin.shape_key_add(name="Basis", from_mix=False)  # the mesh data: M
        skin.shape_key_add(name=COR_KEY, from_mix=False).value = 1.0
        keys = skin.data.shape_keys
    key = keys.key_blocks[COR_KEY]
    if c.last_mode != "POSE":
        convert.write_key_world_coords(skin, key, rig.rest_mesh)
        return
    # The points whose LBS (the modifier's) is cagerig's CoR skin M', from the library.
    convert.write_key_world_coords(skin, key, np.asarray(rig.lbs_rest_preimage()))


def remove_cor_key(skin: bpy.types.Object) -> None:
    """Removes the CoR corrective key (and the basis, when no other key is left)."""
    keys = skin.data.shape_keys
    if keys is None or COR_KEY not in keys.key_blocks:
        return
    skin.shape_key_remove(keys.key_blocks[COR_KEY])
    keys = skin.data.shape_keys
    if keys is not None and len(keys.key_blocks) == 1:
        skin.shape_key_clear()


def check_bones(arm: bpy.types.Object, names: list[str]) -> None:
    """SyncError unless the armature has the coupled bones, in the coupled order."""
    now = [b.name for b in arm.data.bones]
    if now == names:
        return
    added = [n for n in now if n not in names]
    missing = [n for n in names if n not in now]
    what = "; ".join(
        part for part in (
            f"added {', '.join(added[:3])}{'…' if len(added) > 3 else ''}" if added else "",
            f"missing {', '.join(missing[:3])}{'…' if len(missing) > 3 else ''}" if missing else "",
            "the same bones in another order" if not added and not missing else "",
        ) if part
    )
    raise SyncError(
        f"{arm.name!r} has {len(now)} bones, {len(names)} when coupled ({what}): the coupling is paused; undo the "
        "change, or couple again (Uncouple, Rest Position, Couple)"
    )


def _write_cage(cage: bpy.types.Object, world: np.ndarray) -> np.ndarray:
    """Writes the cage and returns it as read back (float32-rounded, through matrix_world), so
    that the next comparison with what Blender shows is exact."""
    convert.write_world_coords(cage, world)
    return convert.world_coords(cage)


def _set_pose_from(arm: bpy.types.Object, c: Coupling) -> bool:
    """Reads Blender's pose; when it changed, sets it on the rig (skinning + CageUp).

    Compared as cagerig's pose (local rotations, root motion), not as Blender's matrices: after
    SkelUp rewrites the rest bones Blender's matrices change by float32 rounding alone."""
    rig = c.rig
    t = convert.skinning_transforms(arm)
    if c.last_matrices is not None and np.array_equal(t, c.last_matrices):
        return False  # Blender's matrices unchanged bit for bit since the rig took them: the same pose
    q, motion, problems = convert.cagerig_pose(t, rig.rest_joints, c.parents, _tolerance(rig))
    if c.last_transforms is not None:
        q0, m0 = c.last_transforms
        same_q = np.all(np.minimum(np.abs(q - q0).max(axis=1), np.abs(q + q0).max(axis=1)) < 1e-7)
        if same_q and np.abs(motion - m0).max() <= _tolerance(rig):
            c.last_matrices = t
            return False
    rig.set_pose(q, motion)  # a refused pose (Green) raises: retried, and reported, at every sync
    c.last_matrices = t
    c.last_transforms = (q, motion)
    c.messages = _pose_messages(rig, problems)
    return True


def _pose_messages(rig: object, problems: list[str]) -> list[str]:
    """What the panel says about a pose: what the pose model cannot represent, and a current
    cage left unfitted (Green coordinates, Unfitted cage: Keep)."""
    unfitted = rig.posed_cage_unfitted
    return problems + ([f"the cage shows the closest fit: {unfitted}"] if unfitted else [])


_last_errors: dict[str, str] = {}


def sync_all(scene: bpy.types.Scene, updated: set[int] | None = None) -> None:
    """Live sync of every coupled skin in the scene. ``updated``: pointers of the IDs the
    depsgraph update touched (None: sync all); a coupling none of whose objects (skin, armature,
    cage, their data) changed is skipped. Errors are kept for the panel and printed once."""
    for obj in scene.objects:
        if not store.is_coupled(obj) or not obj.cagerig.live:
            continue
        if updated is not None and not _touched(obj, updated):
            continue
        _sync_reporting(obj)


def _sync_reporting(skin: bpy.types.Object) -> None:
    """sync(skin), its error kept for the panel and printed once."""
    try:
        sync(skin)
        _last_errors.pop(skin.name, None)
    except (SyncError, ValueError) as e:
        c = _couplings.get(skin.name)
        if c is not None:
            c.messages = [str(e)]
        if _last_errors.get(skin.name) != str(e):
            _last_errors[skin.name] = str(e)
            print(f"cagerig: {e}")


def _touched(skin: bpy.types.Object, updated: set[int]) -> bool:
    ids: list[bpy.types.ID] = [skin, skin.data]
    cage = skin.cagerig.cage
    if cage is not None:
        ids += [cage, cage.data]
    for m in skin.modifiers:
        if m.type == "ARMATURE" and m.object is not None:
            ids += [m.object, m.object.data]
    return any(i.as_pointer() in updated for i in ids)


def last_error(skin: bpy.types.Object) -> str | None:
    """The last live sync's error for ``skin`` (None once a sync succeeds)."""
    return _last_errors.get(skin.name)


def status(skin: bpy.types.Object) -> Coupling | None:
    return _couplings.get(skin.name)
