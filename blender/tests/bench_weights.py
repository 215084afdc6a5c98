"""Time of automatic weights inside Blender: cagerig's (the add-on's operator, as Object ▸ Parent ▸
With cagerig Automatic Weights runs it) and Blender's bone heat (With Automatic Weights), on one
character, each on its own copy of the skin with no vertex groups:

    blender -b --factory-startup --python blender/tests/bench_weights.py -- ZIP CHARACTER_GLB [heat]
    python blender/tests/bench_weights.py -- ZIP CHARACTER_GLB [heat]     # PyPI's bpy module

The glTF is imported with the "Temperance" bone heuristic (bones pointing at their children),
which bone heat needs; cagerig's weights use the joints only. Bone heat runs only when ``heat``
is given. Prints the seconds of each, compute and vertex-group writing together.
"""

from __future__ import annotations

import os
import sys
import time

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
ZIP, GLB = argv[:2]
HEAT = "heat" in argv[2:]

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from install_addon import install  # noqa: E402

install(ZIP)

for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
bpy.ops.import_scene.gltf(filepath=GLB, bone_heuristic="TEMPERANCE")
skin = next(o for o in bpy.data.objects if o.type == "MESH" and any(m.type == "ARMATURE" for m in o.modifiers))
arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
for o in list(bpy.data.objects):
    if o.type == "MESH" and o is not skin:
        bpy.data.objects.remove(o)


def timed(how: str) -> float:
    obj = skin.copy()
    obj.data = skin.data.copy()
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
    return time.perf_counter() - t0


print(f"\nbench weights: {len(skin.data.vertices)} vertices, {len(arm.data.bones)} bones")
for how in ("cagerig", "heat") if HEAT else ("cagerig",):
    print(f"bench weights: {how}: {timed(how):.2f} s", flush=True)
