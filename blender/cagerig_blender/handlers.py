"""Application handlers: the live sync (depsgraph updates, frame changes) and the rebuild of
the run-time state after undo/redo and when a file is opened."""

from __future__ import annotations

import bpy
from bpy.app.handlers import persistent

from . import engine


@persistent
def on_depsgraph_update(scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph) -> None:
    updated = {u.id.original.as_pointer() for u in depsgraph.updates}
    engine.sync_all(scene, updated)


@persistent
def on_frame_change(scene: bpy.types.Scene, _depsgraph: bpy.types.Depsgraph) -> None:
    engine.sync_all(scene)


@persistent
def on_undo_redo_pre(_scene: bpy.types.Scene, *_args: object) -> None:
    # While Blender restores a step, what it shows is not an edit of the user's: no sync reads it.
    engine.suspend(True)
    engine.forget()


@persistent
def on_undo_redo(_scene: bpy.types.Scene, *_args: object) -> None:
    # Undo restored the stored binding (rest cage C) together with the skin, bones and cage of
    # the same step. The rigs are rebuilt from the binding at the next sync, after Blender has
    # evaluated the restored scene: until then the pose bones' matrices are not those of the
    # restored pose (Blender >= 4.2 leaves them unevaluated here), and a rig posed with them
    # would read the restored cage as a grab.
    engine.forget()
    engine.suspend(False)


@persistent
def on_load(*_args: object) -> None:
    engine.suspend(False)
    engine.forget()
    engine.forget_bases()


_HANDLERS = (
    (bpy.app.handlers.depsgraph_update_post, on_depsgraph_update),
    (bpy.app.handlers.frame_change_post, on_frame_change),
    (bpy.app.handlers.undo_pre, on_undo_redo_pre),
    (bpy.app.handlers.redo_pre, on_undo_redo_pre),
    (bpy.app.handlers.undo_post, on_undo_redo),
    (bpy.app.handlers.redo_post, on_undo_redo),
    (bpy.app.handlers.load_post, on_load),
)


def register() -> None:
    for handlers, fn in _HANDLERS:
        if fn not in handlers:
            handlers.append(fn)


def unregister() -> None:
    for handlers, fn in _HANDLERS:
        if fn in handlers:
            handlers.remove(fn)
    engine.forget()
    engine.forget_bases()
