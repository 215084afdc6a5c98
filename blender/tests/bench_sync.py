"""Sync time of one interaction inside Blender (the add-on's speed check):

    blender -b --factory-startup --python blender/tests/bench_sync.py -- ZIP CHARACTER_GLB CAGE_OBJ [REPEATS [profile]]
    python blender/tests/bench_sync.py -- ZIP CHARACTER_GLB CAGE_OBJ [REPEATS [profile]]   # PyPI's bpy module

Installs and enables the add-on, imports the character and cage, couples, then times, for each
interaction, the add-on's sync (what the depsgraph handler runs: cagerig + reading and writing
Blender's data, the bones' Edit Mode round trip included) and the whole update (Blender's own
evaluation of the armature and the Armature modifier + the sync). Prints medians and minima.
"""

from __future__ import annotations

import math
import os
import statistics
import sys
import time

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:]
ZIP, GLB, CAGE = argv[:3]
REPEATS = int(argv[3]) if len(argv) > 3 else 15

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from install_addon import install  # noqa: E402

_addon = install(ZIP)
convert, engine = _addon.convert, _addon.engine
from mathutils import Quaternion  # noqa: E402

for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
bpy.ops.import_scene.gltf(filepath=GLB)
skin = next(o for o in bpy.data.objects if o.type == "MESH" and any(m.type == "ARMATURE" for m in o.modifiers))
arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
for o in list(bpy.data.objects):
    if o.type == "MESH" and o is not skin:
        bpy.data.objects.remove(o)
bpy.ops.wm.obj_import(filepath=CAGE)
cage = bpy.context.selected_objects[0]
bpy.ops.object.select_all(action="DESELECT")
skin.select_set(True)
cage.select_set(True)
bpy.context.view_layer.objects.active = skin
# CAGERIG_BENCH_SKINNING=dqs|cor times that skinning (default: the modifier's, LBS for the Arm).
if os.environ.get("CAGERIG_BENCH_SKINNING"):
    skin.cagerig.skinning = os.environ["CAGERIG_BENCH_SKINNING"]
t0 = time.perf_counter()
bpy.ops.cagerig.couple()
couple_s = time.perf_counter() - t0
skin.cagerig.live = False  # the bench calls the sync itself, to time it alone
diag = float(np.linalg.norm(convert.world_coords(skin).max(0) - convert.world_coords(skin).min(0)))
m_inv = np.linalg.inv(convert.matrix_np(cage.matrix_world))

bone_ms: list[float] = []
_write = engine.write_rest_bones


def timed_write(*args: object) -> None:
    t = time.perf_counter()
    _write(*args)  # type: ignore[arg-type]
    bone_ms.append(1000 * (time.perf_counter() - t))


engine.write_rest_bones = timed_write


def timed(edit) -> tuple[list[float], list[float]]:  # type: ignore[no-untyped-def]
    sync_ms, total_ms = [], []
    for k in range(REPEATS):
        t_total = time.perf_counter()
        edit(k)
        bpy.context.view_layer.update()  # Blender evaluates the edit (the pose's matrices)
        t = time.perf_counter()
        engine.sync(skin)
        sync_ms.append(1000 * (time.perf_counter() - t))
        bpy.context.view_layer.update()  # Blender re-evaluates skin and cage
        total_ms.append(1000 * (time.perf_counter() - t_total))
    return sync_ms, total_ms


pb = arm.pose.bones["lowerarm01.R"]
pb.rotation_mode = "QUATERNION"


def pose(k: int) -> None:
    pb.rotation_quaternion = Quaternion((1.0, 0.0, 0.0), math.radians(10 + 3 * k))


def grab(k: int) -> None:
    w = convert.world_coords(cage)
    for i in (10, 13, 15):
        p = w[i] + np.array([0.0, 0.0, 0.002 * diag * (1 if k % 2 else -1)])
        cage.data.vertices[i].co = (m_inv[:3, :3] @ p + m_inv[:3, 3]).tolist()
    cage.data.update()


def rest_edit(k: int) -> None:
    w = convert.world_coords(cage)
    for i in (0, 2, 4, 5, 6):
        p = w[i] + np.array([0.002 * diag * (1 if k % 2 else -1), 0.0, 0.0])
        cage.data.vertices[i].co = (m_inv[:3, :3] @ p + m_inv[:3, 3]).tolist()
    cage.data.update()


print(f"\nbench: {len(skin.data.vertices)} vertices, {len(arm.data.bones)} bones, cage {len(cage.data.vertices)}; "
      f"couple {couple_s * 1000:.0f} ms; {REPEATS} repeats")
for name, edit, rest in (("pose (set_pose, CageUp)", pose, False),
                         ("posed-cage grab, 3 vertices (CageRev, SkelUp)", grab, False),
                         ("rest-cage edit, 5 vertices (M += Φ·ΔC, SkelUp)", rest_edit, True)):
    arm.data.pose_position = "REST" if rest else "POSE"
    bpy.context.view_layer.update()
    engine.sync(skin)
    bone_ms.clear()
    s, t = timed(edit)
    bones = f", bone write {statistics.median(bone_ms):.2f} ms" if bone_ms else ""
    print(f"bench: {name}: sync median {statistics.median(s):.2f} ms (min {min(s):.2f}){bones}; "
          f"with Blender's evaluation median {statistics.median(t):.2f} ms (min {min(t):.2f})")

if len(argv) > 4 and argv[4] == "profile":
    import cProfile
    import pstats

    arm.data.pose_position = "POSE"
    bpy.context.view_layer.update()
    engine.sync(skin)
    grab(0)
    bpy.context.view_layer.update()
    cProfile.run("engine.sync(skin)", "/tmp/cagerig-sync.prof")
    pstats.Stats("/tmp/cagerig-sync.prof").sort_stats("cumulative").print_stats(18)
    pose(3)
    bpy.context.view_layer.update()
    cProfile.run("engine.sync(skin)", "/tmp/cagerig-sync.prof")
    pstats.Stats("/tmp/cagerig-sync.prof").sort_stats("tottime").print_stats(12)
