"""The "cagerig" tab of the 3D view's sidebar."""

from __future__ import annotations

import bpy

from . import engine, store
from .operators import _coupled_skin


class CAGERIG_PT_main(bpy.types.Panel):
    bl_label = "cagerig"
    bl_idname = "CAGERIG_PT_main"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "cagerig"

    def draw(self, context: bpy.types.Context) -> None:
        layout = self.layout
        obj = context.active_object
        skin = _coupled_skin(context)
        if skin is None:
            col = layout.column(align=True)
            col.label(text="1. Active: skinned mesh")
            col.label(text="2. Also selected: its cage")
            if obj is not None and obj.type == "MESH":
                col = layout.column(align=True)
                col.prop(obj.cagerig, "cage_vertices")
                op = col.operator("cagerig.generate_cage", icon="MESH_ICOSPHERE")
                op.vertices = obj.cagerig.cage_vertices
            if obj is not None and obj.type == "MESH":
                _options(layout, obj)
            layout.operator("cagerig.couple", icon="LINKED")
            if obj is not None and obj.type in {"MESH", "ARMATURE"}:
                layout.operator("cagerig.auto_weights", icon="GROUP_VERTEX")
            return
        box = layout.box()
        box.label(text=skin.name, icon="MESH_DATA")
        cage = skin.cagerig.cage
        box.label(text=cage.name if cage else "(cage missing)", icon="MESH_ICOSPHERE")
        try:
            arm, _ = engine.armature_of(skin)
            box.label(text=arm.name, icon="ARMATURE_DATA")
            box.label(text=f"Cage shows: {'C (rest)' if arm.data.pose_position == 'REST' else 'C′ (pose)'}")
        except engine.SyncError as e:
            box.label(text=str(e), icon="ERROR")
        layout.prop(skin.cagerig, "live")
        _options(layout, skin)
        row = layout.row(align=True)
        row.operator("cagerig.sync", icon="FILE_REFRESH")
        row.operator("cagerig.bake", icon="REC")
        layout.operator("cagerig.uncouple", icon="UNLINKED")
        c = engine.status(skin)
        error = engine.last_error(skin)
        if error and (c is None or error not in c.messages):
            layout.label(text=error, icon="ERROR")
        if c is not None:
            if c.last_sync_ms > 0.0:
                layout.label(text=f"Last sync: {c.last_sync_ms:.2f} ms")
            for m in c.messages[:4]:
                layout.label(text=m, icon="INFO")
        if store.is_coupled(skin) and skin.cagerig.cage is not None and skin.cagerig.cage.data.shape_keys:
            layout.label(text="Cage has shape keys (baked): live sync off", icon="INFO")


def _options(layout: bpy.types.UILayout, obj: bpy.types.Object) -> None:
    """The rig options (props.py); each greyed out where the coordinates make it moot."""
    s = obj.cagerig
    col = layout.column(align=True)
    col.prop(s, "coords")
    col.prop(s, "cage_fit")
    row = col.row()
    row.active = s.coords == "green"  # the face term of Green's stretched normals
    row.prop(s, "green_face_term")
    row = col.row()
    row.active = s.coords == "green"  # only Green rigs can meet a pose with no fitted cage
    row.prop(s, "unfitted_cage")
    if any(m.type == "ARMATURE" for m in obj.modifiers):
        col.prop(s, "skinning")


CLASSES = (CAGERIG_PT_main,)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
