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
def on_undo_redo(scene: bpy.types.Scene, *_args: object) -> None:
    # Undo restored the stored rest cage and whatever Blender shows; rebuild the rigs from the
    # binding and sync, so that what is shown and what is stored agree again.
    engine.forget()
    engine.sync_all(scene)


@persistent
def on_load(*_args: object) -> None:
    engine.forget()
    engine.forget_bases()


_HANDLERS = (
    (bpy.app.handlers.depsgraph_update_post, on_depsgraph_update),
    (bpy.app.handlers.frame_change_post, on_frame_change),
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
