# Blender's own glTF importer on a baked export (crates/cagerig-cli/tests/bake_export.rs):
#   blender -b --python blender_read_baked.py -- FILE.glb POSED.obj TIME
# imports FILE.glb, evaluates the skinned mesh (armature + shape keys) at TIME seconds and prints
# one line `BLENDER {json}`: shape keys, vertices, and the largest distance to POSED.obj (cagerig's
# posed skin in glTF's Y-up space; Blender's importer turns it Z-up: (x, y, z) -> (x, -z, y)).
import json
import sys

import bpy
import numpy as np

if "bool" not in np.__dict__:  # Debian's Blender 3.4 glTF importer + numpy >= 1.24
    np.bool = bool  # type: ignore[attr-defined]

path, posed_path, time = sys.argv[sys.argv.index("--") + 1 :][:3]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
skinned = [o for o in bpy.data.objects if o.type == "MESH" and o.find_armature()]
obj = skinned[0]
scene = bpy.context.scene
frame = float(time) * scene.render.fps / scene.render.fps_base
scene.frame_set(int(frame), subframe=frame - int(frame))
evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
mesh = evaluated.to_mesh()
points = [evaluated.matrix_world @ v.co for v in mesh.vertices]
reference = [tuple(map(float, line.split()[1:4])) for line in open(posed_path) if line.startswith("v ")]
worst = None
if len(points) == len(reference):
    worst = max(
        ((p.x - r[0]) ** 2 + (p.y + r[2]) ** 2 + (p.z - r[1]) ** 2) ** 0.5
        for p, r in zip(points, reference)
    )
keys = obj.data.shape_keys.key_blocks if obj.data.shape_keys else []
print("BLENDER " + json.dumps({"shape_keys": len(keys), "vertices": len(points), "worst": worst}))
