"""Operators: Couple, Generate cage, Sync, Bake, Uncouple."""

from __future__ import annotations


import bpy
import numpy as np
from bpy.props import IntProperty

from . import convert, engine, store


def _skin_with_armature(
    op: bpy.types.Operator, obj: bpy.types.Object | None
) -> tuple[bpy.types.Object, bpy.types.ArmatureModifier] | None:
    """The armature of the skin ``obj``, or None after reporting what is missing."""
    if obj is None or obj.type != "MESH":
        op.report({"ERROR"}, "Make the skinned mesh (a mesh with an Armature modifier) the active object")
        return None
    try:
        return engine.armature_of(obj)
    except engine.SyncError as e:
        op.report({"ERROR"}, str(e))
        return None


def _is_posed(arm: bpy.types.Object, skin: bpy.types.Object) -> bool:
    """Whether the armature's pose moves the skin (beyond float32 noise: a glTF import leaves
    rounding in the pose bones)."""
    t = convert.skinning_transforms(arm)
    pts = convert.world_coords(skin)
    diag = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) or 1.0
    rot = float(np.abs(t[:, :3, :3] - np.eye(3)).max())
    centre = pts.mean(axis=0)
    shift = float(np.abs(np.einsum("jab,b->ja", t[:, :3, :3], centre) + t[:, :3, 3] - centre).max())
    return rot > 1e-5 or shift > 1e-5 * diag


def _coupled_skin(context: bpy.types.Context) -> bpy.types.Object | None:
    """The coupled skin the user means: the active object, or the skin whose cage is active."""
    obj = context.active_object
    if obj is None:
        return None
    if store.is_coupled(obj):
        return obj
    for o in context.scene.objects:
        if store.is_coupled(o) and o.cagerig.cage == obj:
            return o
    return None


def _coupled_skin_or_report(op: bpy.types.Operator, context: bpy.types.Context) -> bpy.types.Object | None:
    """The coupled skin the user means (see `_coupled_skin`); when there is none, `op` reports
    the error that says what to select."""
    skin = _coupled_skin(context)
    if skin is None:
        op.report({"ERROR"}, "Make a coupled skin (or its cage) the active object")
    return skin


class CAGERIG_OT_generate_cage(bpy.types.Operator):
    """Generate a closed cage around the active skinned mesh (cagerig's cage generator)"""

    bl_idname = "cagerig.generate_cage"
    bl_label = "Generate Cage"
    bl_options = {"REGISTER", "UNDO"}

    vertices: IntProperty(  # type: ignore[valid-type]
        name="Vertices", description="Target vertex count of the cage", default=100, min=8, max=5000
    )

    def execute(self, context: bpy.types.Context) -> set[str]:
        import cagerig

        skin = context.active_object
        if skin is None or skin.type != "MESH":
            self.report({"ERROR"}, "Make the mesh to enclose the active object")
            return {"CANCELLED"}
        points = convert.world_coords(skin)
        tris = convert.triangles(skin.data)
        try:
            cv, ct = cagerig.generate_cage(points, tris, target_vertices=self.vertices)
        except (ValueError, TypeError) as e:
            self.report({"ERROR"}, f"cagerig could not generate a cage around {skin.name!r}: {e}")
            return {"CANCELLED"}
        mesh = bpy.data.meshes.new(f"{skin.name}_cage")
        mesh.from_pydata(cv.tolist(), [], ct.tolist())
        mesh.update()
        cage = bpy.data.objects.new(f"{skin.name}_cage", mesh)
        cage.display_type = "WIRE"
        cage.show_in_front = True
        for coll in skin.users_collection[:1]:
            coll.objects.link(cage)
        if not cage.users_collection:
            context.scene.collection.objects.link(cage)
        cage.select_set(True)
        skin.select_set(True)
        context.view_layer.objects.active = skin
        if not store.is_coupled(skin):
            skin.cagerig.cage = cage
        self.report({"INFO"}, f"Cage {cage.name!r}: {len(cv)} vertices, {len(ct)} triangles")
        return {"FINISHED"}


class CAGERIG_OT_couple(bpy.types.Operator):
    """Couple the active skinned mesh, its armature and the selected cage: computes the binding
    (mean value coordinates Φ, MaxVol rows, joint coordinates Ψ) and starts the live sync"""

    bl_idname = "cagerig.couple"
    bl_label = "Couple"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context: bpy.types.Context) -> set[str]:

        skin = context.active_object
        found = _skin_with_armature(self, skin)
        if found is None:
            return {"CANCELLED"}
        arm, mod = found
        cages = [o for o in context.selected_objects if o.type == "MESH" and o != skin]
        if len(cages) > 1:
            self.report({"ERROR"}, f"Select one cage mesh besides the skin (found {len(cages)})")
            return {"CANCELLED"}
        cage = cages[0] if cages else skin.cagerig.cage
        if cage is None:
            self.report({"ERROR"}, "Select the cage mesh too (or press Generate Cage first)")
            return {"CANCELLED"}
        if cage.mode == "EDIT" or skin.mode == "EDIT" or arm.mode == "EDIT":
            self.report({"ERROR"}, "Leave Edit Mode before coupling")
            return {"CANCELLED"}
        linked = engine.linked_part(skin, arm, cage)
        if linked is not None:
            self.report({"ERROR"}, linked[0].upper() + linked[1:])
            return {"CANCELLED"}
        engine.remove_cor_key(skin)  # a CoR coupling's own key (coupling again): not the user's
        for obj, what in ((skin, "skin"), (cage, "cage")):
            if obj.data.shape_keys is not None:
                self.report({"ERROR"}, f"The {what} {obj.name!r} has shape keys: cagerig rewrites its mesh data; "
                            "apply or remove the shape keys first")
                return {"CANCELLED"}
            if obj.data.users > 1:
                self.report({"ERROR"}, f"The {what}'s mesh {obj.data.name!r} is shared by {obj.data.users} objects: "
                            "cagerig rewrites it; make it single-user first (Object ▸ Relations ▸ Make Single User)")
                return {"CANCELLED"}
        if not mod.use_vertex_groups or mod.use_bone_envelopes:
            self.report({"ERROR"}, f"The Armature modifier {mod.name!r} must deform with vertex groups only "
                        "(Bind To: Vertex Groups on, Bone Envelopes off)")
            return {"CANCELLED"}
        if skin.modifiers[0] != mod:
            self.report({"WARNING"}, f"The Armature modifier {mod.name!r} is not first in the stack: "
                        "the modifiers before it are not seen by cagerig")
        if arm.data.pose_position == "POSE" and _is_posed(arm, skin):
            self.report({"ERROR"}, f"{arm.name!r} is posed: couple in the rest pose (switch the armature to "
                        "Rest Position, or clear the pose); the cage is taken as the rest cage C")
            return {"CANCELLED"}
        names, heads, parents, deform = convert.rest_skeleton(arm)
        rows, cols, vals = convert.skin_weights_sparse(skin, names, deform)
        n = len(skin.data.vertices)
        unweighted = n - len(np.unique(rows))
        if unweighted:
            self.report({"ERROR"}, f"{unweighted} of {n} vertices of {skin.name!r} have no weight in a vertex "
                        "group of a deforming bone: weight them (cagerig needs every vertex skinned)")
            return {"CANCELLED"}
        points = convert.world_coords(skin)
        tris = convert.triangles(skin.data)
        cage_points = convert.world_coords(cage)
        cage_tris = convert.triangles(cage.data)
        parts = convert.connected_parts(len(cage_points), cage_tris)
        if parts > 1:
            self.report({"ERROR"}, f"The cage {cage.name!r} has {parts} separate parts: cagerig needs one closed "
                        "cage around the skin; delete the loose parts (in Edit Mode, L over a part selects it)")
            return {"CANCELLED"}
        options = engine.options_of(skin)
        bind_id = store.new_bind_id()
        binding = store.Binding(
            bind_id=bind_id, mesh=points, triangles=tris, weight_rows=rows, weight_cols=cols,
            weight_values=vals, joints=heads, parents=parents, names=names, cage=cage_points,
            cage_triangles=cage_tris, rest_cage=cage_points, options=options,
        )
        try:
            engine.build_rig(binding)
        except (ValueError, TypeError, IndexError) as e:
            msg = str(e)
            if "outside" in msg or "enclose" in msg:
                msg = f"the cage {cage.name!r} does not enclose {skin.name!r} in its rest pose: {msg}"
            elif "open boundary" in msg or "non-manifold" in msg:
                msg = (f"the cage {cage.name!r} must be closed, each edge shared by two faces: {msg}. Find the "
                       "edges with Select ▸ Select All by Trait ▸ Non Manifold in Edit Mode, and fill the holes (F)")
            self.report({"ERROR"}, f"cagerig refused the binding: {msg}")
            return {"CANCELLED"}
        store.save(skin, binding)
        skin.cagerig.cage = cage
        skin.cagerig.live = True
        engine.forget(skin.name)
        try:
            engine.sync(skin)
        except (engine.SyncError, ValueError) as e:
            self.report({"WARNING"}, f"Coupled, but the first sync failed: {e}")
            return {"FINISHED"}
        self.report({"INFO"}, f"Coupled {skin.name!r} ({n} vertices), {arm.name!r} ({len(names)} bones) "
                    f"and {cage.name!r} ({len(cage_points)} vertices): {options.describe()}")
        return {"FINISHED"}


class CAGERIG_OT_sync(bpy.types.Operator):
    """Synchronise the coupled skin, bones and cage now"""

    bl_idname = "cagerig.sync"
    bl_label = "Sync"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context: bpy.types.Context) -> set[str]:
        skin = _coupled_skin_or_report(self, context)
        if skin is None:
            return {"CANCELLED"}
        try:
            engine.sync(skin)
        except (engine.SyncError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}


class CAGERIG_OT_uncouple(bpy.types.Operator):
    """Remove the coupling (skin, bones and cage keep their current state)"""

    bl_idname = "cagerig.uncouple"
    bl_label = "Uncouple"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context: bpy.types.Context) -> set[str]:
        skin = _coupled_skin_or_report(self, context)
        if skin is None:
            return {"CANCELLED"}
        engine.remove_cor_key(skin)  # the skin keeps its rest state, shown by the modifier's LBS
        store.remove(skin)
        engine.forget(skin.name)
        return {"FINISHED"}


class CAGERIG_OT_bake(bpy.types.Operator):
    """Bake the cage's motion over the scene's frame range as shape-key animation on the cage
    (it then plays without the add-on); live sync of this coupling is switched off"""

    bl_idname = "cagerig.bake"
    bl_label = "Bake"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context: bpy.types.Context) -> set[str]:
        skin = _coupled_skin_or_report(self, context)
        if skin is None:
            return {"CANCELLED"}
        scene = context.scene
        try:
            cage = engine.cage_of(skin)
            arm, _ = engine.armature_of(skin)
        except engine.SyncError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if arm.data.pose_position != "POSE":
            self.report({"ERROR"}, "Switch the armature to Pose Position to bake")
            return {"CANCELLED"}
        if cage.data.shape_keys is not None:
            self.report({"ERROR"}, f"{cage.name!r} already has shape keys (an earlier bake?): remove them first")
            return {"CANCELLED"}
        frame0 = scene.frame_current
        frames = range(scene.frame_start, scene.frame_end + 1)
        shapes: list[np.ndarray] = []
        try:
            for f in frames:
                scene.frame_set(f)
                engine.sync(skin)
                shapes.append(convert.mesh_local_coords(cage.data))
        except (engine.SyncError, ValueError) as e:
            scene.frame_set(frame0)
            self.report({"ERROR"}, f"Bake stopped at frame {scene.frame_current}: {e}")
            return {"CANCELLED"}
        skin.cagerig.live = False
        basis = cage.shape_key_add(name="Basis", from_mix=False)
        basis.interpolation = "KEY_LINEAR"
        for f, co in zip(frames, shapes, strict=True):
            key = cage.shape_key_add(name=f"cagerig_{f:04d}", from_mix=False)
            key.data.foreach_set("co", co.astype(np.float32).ravel())
            for g, v in ((f - 1, 0.0), (f, 1.0), (f + 1, 0.0)):
                key.value = v
                key.keyframe_insert("value", frame=g)
        cage.data.shape_keys.use_relative = True
        scene.frame_set(frame0)
        self.report({"INFO"}, f"Baked {len(shapes)} frames on {cage.name!r}; live sync of {skin.name!r} is off")
        return {"FINISHED"}


CLASSES = (
    CAGERIG_OT_generate_cage,
    CAGERIG_OT_couple,
    CAGERIG_OT_sync,
    CAGERIG_OT_uncouple,
    CAGERIG_OT_bake,
)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
