"""The add-on's per-object settings (saved with the skin object)."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, IntProperty, PointerProperty


def _is_mesh(_self: bpy.types.PropertyGroup, obj: bpy.types.Object) -> bool:
    return obj.type == "MESH"


class CagerigObjectSettings(bpy.types.PropertyGroup):
    cage: PointerProperty(  # type: ignore[valid-type]
        name="Cage",
        description="The cage object coupled with this skin",
        type=bpy.types.Object,
        poll=_is_mesh,
    )
    live: BoolProperty(  # type: ignore[valid-type]
        name="Live sync",
        description="Synchronise skin, bones and cage on every change (CageUp, CageRev, SkelUp)",
        default=True,
    )
    cage_vertices: IntProperty(  # type: ignore[valid-type]
        name="Cage vertices",
        description="Target vertex count of a generated cage",
        default=100,
        min=8,
        max=5000,
    )


CLASSES = (CagerigObjectSettings,)


def register() -> None:
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.cagerig = PointerProperty(type=CagerigObjectSettings)


def unregister() -> None:
    del bpy.types.Object.cagerig
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
