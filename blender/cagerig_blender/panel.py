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
                layout.prop(obj.cagerig, "cage_fit")
            layout.operator("cagerig.couple", icon="LINKED")
            return
        box = layout.box()
        box.label(text=skin.name, icon="MESH_DATA")
        cage = skin.cagerig.cage
        box.label(text=cage.name if cage else "(cage missing)", icon="MESH_ICOSPHERE")
        try:
            arm, mod = engine.armature_of(skin)
            box.label(text=f"{arm.name} · {'DQS' if mod.use_deform_preserve_volume else 'LBS'}",
                      icon="ARMATURE_DATA")
            box.label(text=f"Cage shows: {'C (rest)' if arm.data.pose_position == 'REST' else 'C′ (pose)'}")
        except engine.SyncError as e:
            box.label(text=str(e), icon="ERROR")
        layout.prop(skin.cagerig, "live")
        layout.prop(skin.cagerig, "cage_fit")
        row = layout.row(align=True)
        row.operator("cagerig.sync", icon="FILE_REFRESH")
        row.operator("cagerig.bake", icon="REC")
        layout.operator("cagerig.uncouple", icon="UNLINKED")
        c = engine.status(skin)
        if c is not None:
            if c.last_sync_ms > 0.0:
                layout.label(text=f"Last sync: {c.last_sync_ms:.2f} ms")
            for m in c.messages[:4]:
                layout.label(text=m, icon="INFO")
        if store.is_coupled(skin) and skin.cagerig.cage is not None and skin.cagerig.cage.data.shape_keys:
            layout.label(text="Cage has shape keys (baked): live sync off", icon="INFO")


CLASSES = (CAGERIG_PT_main,)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister() -> None:
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
