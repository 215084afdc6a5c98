"""cagerig's automatic weights inside Blender: the geodesic voxel weights of ``cagerig.skin_weights``
(``cagerig weights`` on the command line, docs/weights.md) written as vertex groups, so that
Blender's own Armature modifier deforms with them, coupled or not.

Two ways in: Object ▸ Parent ▸ With cagerig Automatic Weights (meshes selected, the armature
active, as Blender's own With Automatic Weights), and the cagerig panel (the active mesh; its
armature from its Armature modifier, its parent or the selection).
"""

from __future__ import annotations

import time

import bpy
import numpy as np
from bpy.props import BoolProperty, IntProperty

from . import convert, store


class WeightsError(Exception):
    """Weights could not be computed; the message says what to do."""


def compute(
    skin: bpy.types.Object, arm: bpy.types.Object, max_influences: int, cage: bpy.types.Object | None
) -> tuple[list[str], np.ndarray]:
    """cagerig's weights of ``skin`` for the deforming bones of ``arm``: the bone names and an
    (n, J) array (rows sum to 1; columns of non-deforming bones are zero). Joint j of cagerig is
    bone j's head (its bones: the segments to its children's heads, docs/weights.md)."""
    import cagerig

    names, heads, parents, deform = convert.rest_skeleton(arm)
    if not any(deform):
        raise WeightsError(f"{arm.name!r} has no deforming bone (Bone ▸ Deform is off on every bone)")
    points = convert.world_coords(skin)
    tris = convert.triangles(skin.data)
    if len(tris) == 0:
        raise WeightsError(f"{skin.name!r} has no face: cagerig's weights need a surface to voxelise")
    cage_arrays = None
    if cage is not None:
        cage_arrays = (convert.world_coords(cage), convert.triangles(cage.data))
    try:
        w = np.asarray(
            cagerig.skin_weights(points, tris, heads, parents, max_influences, cage_arrays, joint_names=names)
        )
    except (ValueError, IndexError) as e:
        raise WeightsError(f"cagerig could not weight {skin.name!r} for {arm.name!r}: {e}") from None
    # Blender's Armature modifier ignores non-deforming bones: their share goes to the others.
    w[:, ~np.asarray(deform, dtype=bool)] = 0.0
    sums = w.sum(axis=1)
    lost = np.flatnonzero(sums <= 0.0)
    if len(lost):
        raise WeightsError(
            f"{len(lost)} of {len(w)} vertices of {skin.name!r} (first: {lost[0]}) are weighted only by "
            f"non-deforming bones of {arm.name!r}: switch Deform on for those bones"
        )
    return names, w / sums[:, None]


def write_groups(skin: bpy.types.Object, names: list[str], w: np.ndarray) -> int:
    """Writes the weights as vertex groups named after the bones (an existing group of a bone is
    replaced: its old weights are cleared); groups of other names are kept. Returns the number of
    groups written."""
    written = 0
    n = len(skin.data.vertices)
    everyone = list(range(n))
    for j, name in enumerate(names):
        col = w[:, j]
        rows = np.flatnonzero(col > 0.0)
        group = skin.vertex_groups.get(name)
        if group is None and len(rows) == 0:
            continue
        if group is None:
            group = skin.vertex_groups.new(name=name)
        else:
            group.remove(everyone)
        add = group.add
        for i, v in zip(rows.tolist(), col[rows].tolist()):
            add((i,), v, "REPLACE")
        written += 1
    return written


def ensure_armature_modifier(skin: bpy.types.Object, arm: bpy.types.Object) -> bpy.types.ArmatureModifier:
    mod = next((m for m in skin.modifiers if m.type == "ARMATURE"), None)
    if mod is None:
        mod = skin.modifiers.new(name="Armature", type="ARMATURE")
        # First in the stack, as Blender's own parenting puts it: the mesh it deforms is the mesh.
        if skin.modifiers[0] != mod:
            with bpy.context.temp_override(object=skin, active_object=skin):
                bpy.ops.object.modifier_move_to_index(modifier=mod.name, index=0)
    mod.object = arm
    mod.use_vertex_groups = True
    mod.use_bone_envelopes = False
    return mod


def _armature_for(context: bpy.types.Context, skin: bpy.types.Object) -> bpy.types.Object | None:
    mod = next((m for m in skin.modifiers if m.type == "ARMATURE" and m.object is not None), None)
    if mod is not None and mod.object.type == "ARMATURE":
        return mod.object
    if skin.parent is not None and skin.parent.type == "ARMATURE":
        return skin.parent
    arms = [o for o in context.selected_objects if o.type == "ARMATURE"]
    return arms[0] if len(arms) == 1 else None


class CAGERIG_OT_auto_weights(bpy.types.Operator):
    """Weight the mesh to the armature with cagerig's geodesic voxel weights (vertex groups for
    Blender's Armature modifier); with an armature active: every selected mesh, parented to it"""

    bl_idname = "cagerig.auto_weights"
    bl_label = "cagerig Automatic Weights"
    bl_options = {"REGISTER", "UNDO"}

    max_influences: IntProperty(  # type: ignore[valid-type]
        name="Max influences", description="Most bones per vertex", default=4, min=1, max=16
    )
    use_cage: BoolProperty(  # type: ignore[valid-type]
        name="Bound by the cage",
        description="The mesh's cage (its cagerig cage, or a second selected mesh) bounds the volume: "
        "for meshes with holes too wide to close",
        default=True,
    )

    def execute(self, context: bpy.types.Context) -> set[str]:
        active = context.active_object
        if active is not None and active.type == "ARMATURE":
            # Object ▸ Parent: the selected meshes, to the active armature.
            arm = active
            skins = [o for o in context.selected_objects if o.type == "MESH"]
            if not skins:
                self.report({"ERROR"}, f"Select the meshes to weight, then the armature {arm.name!r} last (active)")
                return {"CANCELLED"}
            extra_cage = None
        elif active is not None and active.type == "MESH":
            skins = [active]
            arm = _armature_for(context, active)
            if arm is None:
                self.report({"ERROR"}, f"{active.name!r} has no armature: give it an Armature modifier, parent it "
                            "to the armature, or select the armature too")
                return {"CANCELLED"}
            others = [o for o in context.selected_objects if o.type == "MESH" and o != active]
            extra_cage = others[0] if len(others) == 1 else None
        else:
            self.report({"ERROR"}, "Make a mesh (or, from Object ▸ Parent, the armature) the active object")
            return {"CANCELLED"}
        if arm.mode == "EDIT":
            self.report({"ERROR"}, f"Leave Edit Mode of {arm.name!r} first")
            return {"CANCELLED"}
        for skin in skins:
            if store.is_coupled(skin):
                self.report({"ERROR"}, f"{skin.name!r} is coupled with the weights it had: uncouple it, weight it, "
                            "then couple again")
                return {"CANCELLED"}
            if skin.mode == "EDIT":
                self.report({"ERROR"}, f"Leave Edit Mode of {skin.name!r} first")
                return {"CANCELLED"}
        done = []
        for skin in skins:
            cage = None
            if self.use_cage:
                cage = skin.cagerig.cage or extra_cage
            t0 = time.perf_counter()
            try:
                names, w = compute(skin, arm, self.max_influences, cage)
            except WeightsError as e:
                self.report({"ERROR"}, str(e))
                return {"CANCELLED"}
            t1 = time.perf_counter()
            groups = write_groups(skin, names, w)
            ensure_armature_modifier(skin, arm)
            if skin.parent != arm:  # parented keeping its place, as Blender's Parent does
                m = skin.matrix_world.copy()
                skin.parent = arm
                skin.parent_type = "OBJECT"
                skin.matrix_parent_inverse = arm.matrix_world.inverted()
                skin.matrix_basis = m
            t2 = time.perf_counter()
            done.append(f"{skin.name!r}: {groups} groups, {len(w)} vertices"
                        f"{f', bounded by {cage.name!r}' if cage else ''} ({t1 - t0:.2f} s + {t2 - t1:.2f} s to write)")
        self.report({"INFO"}, f"cagerig weights for {arm.name!r}: " + "; ".join(done))
        return {"FINISHED"}


def _parent_menu(self: bpy.types.Menu, _context: bpy.types.Context) -> None:
    self.layout.separator()
    self.layout.operator(CAGERIG_OT_auto_weights.bl_idname, text="With cagerig Automatic Weights")


CLASSES = (CAGERIG_OT_auto_weights,)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.VIEW3D_MT_object_parent.append(_parent_menu)


def unregister() -> None:
    bpy.types.VIEW3D_MT_object_parent.remove(_parent_menu)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
