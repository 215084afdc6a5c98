"""The add-on's per-object settings (saved with the skin object)."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, IntProperty, PointerProperty


def _is_mesh(_self: bpy.types.PropertyGroup, obj: bpy.types.Object) -> bool:
    return obj.type == "MESH"


# How CageUp fits the current cage (cagerig's CageFitKind, `--cage-fit` on the command line).
CAGE_FIT_ITEMS = [
    ("regularised", "Regularised",
     "The cage fits the skin and stays near the rest cage carried by the skeleton (default)"),
    ("paper", "Paper", "The paper's Eq. 8: the cage interpolates the skin at the MaxVol rows"),
]


def _cage_fit_changed(self: bpy.types.PropertyGroup, _context: bpy.types.Context) -> None:
    # A coupled skin keeps the fit in its stored binding; the rig is rebuilt with it and the
    # cage shows its new fit.
    from . import engine, store

    skin = self.id_data
    if store.is_coupled(skin) and store.cage_fit(skin) != self.cage_fit:
        store.save_cage_fit(skin, self.cage_fit)
        try:
            engine.refit_cage(skin)
        except (engine.SyncError, ValueError) as e:
            engine.forget(skin.name)
            print(f"cagerig: {e}")


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
    cage_fit: EnumProperty(  # type: ignore[valid-type]
        name="Current cage fit",
        description="How the current cage follows the pose",
        items=CAGE_FIT_ITEMS,
        default="regularised",
        update=_cage_fit_changed,
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
