"""The five workflow screenshots of docs/blender.md, taken from Blender's own window under Xvfb
(the live sync runs through the real depsgraph handler of the interactive session):

    blender -b --factory-startup --python blender/tests/screenshots.py -- setup ZIP ARM_GLB ARM_CAGE_OBJ OUT_DIR
    xvfb-run -a -s "-screen 0 1600x1000x24" blender --factory-startup --window-geometry 0 0 1600 1000 \
        OUT_DIR/setup.blend --python blender/tests/screenshots.py -- shoot OUT_DIR

    blender -b --factory-startup --python blender/tests/screenshots.py -- shrink OUT_DIR

(``BLENDER_USER_SCRIPTS`` the same for the first two, so the second run finds the installed
add-on; the second needs xdotool to switch the sidebar to the cagerig tab.)
"""

from __future__ import annotations

import math
import os
import sys

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:]
PHASE = argv[0]

if PHASE == "setup":
    ZIP, GLB, CAGE, OUT = argv[1:5]
    bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
    if "bool" not in np.__dict__:  # Debian's Blender 3.4 glTF importer + numpy >= 1.24
        np.bool = bool  # type: ignore[attr-defined]
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    bpy.ops.import_scene.gltf(filepath=GLB)
    skin = next(o for o in bpy.data.objects if o.type == "MESH" and o.modifiers)
    for o in list(bpy.data.objects):
        if o.type == "MESH" and o is not skin:
            bpy.data.objects.remove(o)
    bpy.ops.wm.obj_import(filepath=CAGE)
    cage = bpy.context.selected_objects[0]
    cage.display_type = "WIRE"
    cage.show_in_front = True
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    arm.show_in_front = True
    arm.data.display_type = "STICK"
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(OUT, "setup.blend"))
    sys.exit(0)

if PHASE == "shrink":
    # Smaller pictures for the docs: the window's top 800 rows, scaled to 70 %.
    import glob

    for path in sorted(glob.glob(os.path.join(argv[1], "blender-*.png"))):
        img = bpy.data.images.load(path)
        w, h = img.size
        px = np.empty(w * h * 4, dtype=np.float32)
        img.pixels.foreach_get(px)
        keep = min(h, 800)
        px = px.reshape(h, w, 4)[h - keep:]  # Blender's rows run bottom-up
        out = bpy.data.images.new("shrunk", w, keep, alpha=False)
        out.pixels.foreach_set(px.ravel())
        out.scale(int(w * 0.7), int(keep * 0.7))
        out.filepath_raw = path
        out.file_format = "PNG"
        out.save()
        print(f"shrunk {path}: {out.size[0]}x{out.size[1]}")
    sys.exit(0)

OUT = argv[1]
bpy.ops.preferences.addon_enable(module="cagerig_blender")
from cagerig_blender import convert  # noqa: E402
from mathutils import Quaternion, Vector  # noqa: E402

skin = next(o for o in bpy.data.objects if o.type == "MESH" and o.modifiers)
arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
cage = next(o for o in bpy.data.objects if o.type == "MESH" and o is not skin)


def view3d() -> tuple[bpy.types.Window, bpy.types.Area, bpy.types.Region]:
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return win, area, region


def setup_view() -> None:
    win, area, region = view3d()
    space = area.spaces.active
    space.show_region_ui = True
    space.shading.type = "SOLID"
    space.shading.color_type = "SINGLE"
    space.shading.single_color = (0.8, 0.62, 0.5)
    space.overlay.show_floor = False
    space.overlay.show_axis_x = False
    space.overlay.show_axis_y = False
    # Blender 3.4 cannot switch the sidebar's tab from Python: for the pictures, the sidebar
    # keeps only the cagerig tab (the other 3D-view sidebar panels are unregistered here).
    for cls in list(bpy.types.Panel.__subclasses__()):
        if (getattr(cls, "bl_space_type", "") == "VIEW_3D" and getattr(cls, "bl_region_type", "") == "UI"
                and getattr(cls, "bl_category", "") != "cagerig" and cls.__module__.startswith("bl_ui")):
            try:
                bpy.utils.unregister_class(cls)
            except RuntimeError:
                pass
    r3d = space.region_3d
    pts = convert.world_coords(skin)
    centre = (pts.max(0) + pts.min(0)) / 2
    r3d.view_location = Vector(centre.tolist())
    r3d.view_rotation = Quaternion((1.0, 0.0, 0.0), math.radians(90))  # front view
    r3d.view_distance = float(np.linalg.norm(pts.max(0) - pts.min(0))) * 1.2
    r3d.view_perspective = "PERSP"


def _xdotool(*args: str) -> None:
    import shutil
    import subprocess

    if shutil.which("xdotool"):
        subprocess.run(["xdotool", *args], check=False)


def hover_cagerig_tab() -> None:
    """Blender 3.4 cannot switch the sidebar's tab from Python: point at it, then click it
    (xdotool, under Xvfb; the tab strip is the sidebar region's right edge)."""
    win, area, _ = view3d()
    ui = next(r for r in area.regions if r.type == "UI")
    _xdotool("mousemove", str(ui.x + ui.width - 10), str(win.height - (ui.y + ui.height) + 90))


def click() -> None:
    _xdotool("click", "1")


def mouse_away() -> None:
    win, _, _ = view3d()
    _xdotool("mousemove", str(win.width // 3), str(win.height - 40))


def screenshot(name: str) -> None:
    win, area, region = view3d()
    with bpy.context.temp_override(window=win, area=area, region=region):
        bpy.ops.screen.screenshot_area(filepath=os.path.join(OUT, name))
    print(f"screenshot {name}", flush=True)


def select(objs: list[bpy.types.Object], active: bpy.types.Object) -> None:
    for o in bpy.context.view_layer.objects:
        o.select_set(o in objs)
    bpy.context.view_layer.objects.active = active


m_inv = np.linalg.inv(convert.matrix_np(cage.matrix_world))


def move_cage(indices: list[int], offset: np.ndarray) -> None:
    w = convert.world_coords(cage)
    for i in indices:
        p = w[i] + offset
        cage.data.vertices[i].co = (m_inv[:3, :3] @ p + m_inv[:3, 3]).tolist()
    cage.data.update()


def forearm(n: int) -> list[int]:
    w = convert.world_coords(cage)
    heads = convert.rest_skeleton(arm)[1]
    names = [b.name for b in arm.data.bones]
    a = heads[names.index("lowerarm02.R")]
    return np.argsort(np.linalg.norm(w - a, axis=1))[:n].tolist()


def step1() -> None:
    setup_view()
    select([skin, cage], skin)


def step1b() -> None:
    hover_cagerig_tab()


def step1c() -> None:
    click()


def step1d() -> None:
    mouse_away()
    select([skin, cage], skin)


def step2() -> None:
    screenshot("blender-1-import.png")
    bpy.ops.cagerig.couple()


def step3() -> None:
    screenshot("blender-2-couple.png")
    pb = arm.pose.bones["lowerarm01.R"]  # bend the elbow in the picture's plane (world Y axis)
    pb.rotation_mode = "QUATERNION"
    pose_rot = pb.matrix.to_3x3().normalized()
    r = Quaternion((0.0, 1.0, 0.0), math.radians(55)).to_matrix()
    basis = pb.matrix_basis.to_3x3().normalized()
    pb.rotation_quaternion = (basis @ pose_rot.inverted() @ r @ pose_rot).to_quaternion()


def step4() -> None:
    screenshot("blender-3-pose.png")
    # Grab the four posed-cage vertices nearest the posed wrist and pull them up, as a user would
    # with G in Edit Mode (written as data here, then shown selected in Edit Mode).
    diag = float(np.linalg.norm(convert.world_coords(skin).ptp(0)))
    wrist = convert.matrix_np(arm.matrix_world) @ np.array([*arm.pose.bones["wrist.R"].head, 1.0])
    w = convert.world_coords(cage)
    grab = np.argsort(np.linalg.norm(w - wrist[:3], axis=1))[:4].tolist()
    move_cage(grab, np.array([0.0, 0.0, 0.12]) * diag)
    select([cage], cage)
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="DESELECT")
    bpy.ops.object.mode_set(mode="OBJECT")
    for i in grab:
        cage.data.vertices[i].select = True
    bpy.ops.object.mode_set(mode="EDIT")


def step5() -> None:
    screenshot("blender-4-grab.png")
    bpy.ops.object.mode_set(mode="OBJECT")
    arm.data.pose_position = "REST"


def step6() -> None:
    w = convert.world_coords(cage)
    idx = forearm(10)
    c = w[idx].mean(0)
    for i in idx:  # inflate the forearm's rest cage
        move_cage([i], 0.35 * (w[i] - c))


def step7() -> None:
    screenshot("blender-5-rest.png")
    bpy.ops.wm.quit_blender()


STEPS = [step1, step1b, step1c, step1d, step2, step3, step4, step5, step6, step7]


def run_steps() -> float | None:
    if not STEPS:
        return None
    try:
        STEPS.pop(0)()
        for area in bpy.context.window_manager.windows[0].screen.areas:
            area.tag_redraw()
    except Exception:
        import traceback

        traceback.print_exc()
        bpy.ops.wm.quit_blender()
        return None
    return 1.0


bpy.app.timers.register(run_steps, first_interval=2.0)
