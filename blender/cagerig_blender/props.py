"""The add-on's per-object settings (saved with the skin object, restored by undo).

The rig options are the CLI's (``--coords``, ``--cage-fit``, ``--skinning``,
``--unfitted-cage``); their names come from the cagerig package (cagerig.COORDS_KINDS, …), the
add-on adds only labels. On a coupled skin, changing one rebinds (engine.apply_options): the rig
is rebuilt with it and the skin, cage and bones show what it computes.
"""

from __future__ import annotations

import bpy
import cagerig  # importable: register() puts the bundled package on sys.path first
from bpy.props import BoolProperty, EnumProperty, IntProperty, PointerProperty

from . import convert


def _is_mesh(_self: bpy.types.PropertyGroup, obj: bpy.types.Object) -> bool:
    return obj.type == "MESH"


# Labels and tooltips by cagerig's option names; a name the package adds and this table lacks
# is listed under its own name.
LABELS: dict[str, dict[str, tuple[str, str]]] = {
    "coords": {
        "mvc": ("Mean value", "Mean value coordinates: the paper's linear M = Φ·C (default)"),
        "green": ("Green", "Green coordinates: shape-preserving cage edits (the current cage fitted by Gauss–Newton)"),
    },
    "cage_fit": {
        "regularised": ("Regularised",
                        "The cage fits the skin and stays near the rest cage carried by the skeleton (default)"),
        "paper": ("Paper", "The paper's Eq. 8: the cage interpolates the skin at the MaxVol rows"),
    },
    "green_face_term": {
        "fold-safe": ("Fold-safe",
                      "Green rigs: a face term smooth through folds, so every pose finds a current cage (default)"),
        "lipman": ("Lipman", "Green rigs: Lipman's stretched normal, which jumps where a cage triangle folds"),
    },
    "skinning": {
        "lbs": ("Linear (LBS)", "Linear blend skinning: the Armature modifier without Preserve Volume"),
        "dqs": ("Preserve Volume (DQS)", "Dual quaternion skinning: the Armature modifier's Preserve Volume"),
        "cor": ("Centres of rotation (CoR)",
                "Optimised centres of rotation: the Armature modifier's LBS plus a corrective shape key the "
                "add-on rewrites at every sync"),
    },
    "unfitted_cage": {
        "refuse": ("Refuse", "Green rigs: a pose whose current cage cannot be fitted is refused (default)"),
        "keep": ("Keep",
                 "Green rigs: such a pose is kept, the skin and bones exact, the cage the fit's closest; "
                 "cage grabs are refused until a pose fits again"),
    },
}


def _items(option: str, names: list[str]) -> list[tuple[str, str, str]]:
    return [(n, *LABELS[option].get(n, (n, n))) for n in names]


def _option_changed(self: bpy.types.PropertyGroup, _context: bpy.types.Context) -> None:
    from . import engine

    engine.apply_options(self.id_data)


def _armature_modifier(skin: bpy.types.Object) -> bpy.types.ArmatureModifier | None:
    return next((m for m in skin.modifiers if m.type == "ARMATURE"), None)


def _skinning_items() -> list[tuple[str, str, str]]:
    return _items("skinning", [n for n in cagerig.SKINNING_METHODS if n in convert.BLENDER_SKINNING])


_SKINNING_ITEMS: list[tuple[str, str, str]] = []


def _get_skinning(self: bpy.types.PropertyGroup) -> int:
    mod = _armature_modifier(self.id_data)
    name = convert.skinning_of(mod, self.use_cor) if mod is not None else "lbs"
    return [i[0] for i in _SKINNING_ITEMS].index(name)


def _set_skinning(self: bpy.types.PropertyGroup, value: int) -> None:
    # LBS and DQS are the Armature modifier's Preserve Volume: one setting, shown in both places.
    mod = _armature_modifier(self.id_data)
    if mod is None:
        print(f"cagerig: {self.id_data.name!r} has no Armature modifier: the skinning is its setting")
        return
    preserve_volume, corrective = convert.skinning_settings(_SKINNING_ITEMS[value][0])
    self.use_cor = corrective
    mod.use_deform_preserve_volume = preserve_volume


def _settings_class() -> type:
    _SKINNING_ITEMS[:] = _skinning_items()

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
        coords: EnumProperty(  # type: ignore[valid-type]
            name="Coordinates",
            description="The cage coordinates binding the skin to the cage",
            items=_items("coords", cagerig.COORDS_KINDS),
            default="mvc",
            update=_option_changed,
        )
        cage_fit: EnumProperty(  # type: ignore[valid-type]
            name="Current cage fit",
            description="How the current cage follows the pose",
            items=_items("cage_fit", cagerig.CAGE_FITS),
            default="regularised",
            update=_option_changed,
        )
        green_face_term: EnumProperty(  # type: ignore[valid-type]
            name="Green face term",
            description="Green coordinates: the stretched normals' face term",
            items=_items("green_face_term", cagerig.GREEN_FACE_TERMS),
            default="fold-safe",
            update=_option_changed,
        )
        use_cor: BoolProperty(  # type: ignore[valid-type]
            name="CoR skinning",
            description="Skinning by centres of rotation (set through Skinning)",
            default=False,
            options={"HIDDEN"},
        )
        skinning: EnumProperty(  # type: ignore[valid-type]
            name="Skinning",
            description="How the bones deform the skin (LBS and DQS: the Armature modifier's Preserve Volume)",
            items=_SKINNING_ITEMS,
            get=_get_skinning,
            set=_set_skinning,
            update=_option_changed,
        )
        unfitted_cage: EnumProperty(  # type: ignore[valid-type]
            name="Unfitted cage",
            description="Green coordinates: what a pose whose current cage cannot be fitted does",
            items=_items("unfitted_cage", cagerig.UNFITTED_CAGE_POLICIES),
            default="refuse",
            update=_option_changed,
        )
        cage_vertices: IntProperty(  # type: ignore[valid-type]
            name="Cage vertices",
            description="Target vertex count of a generated cage",
            default=100,
            min=8,
            max=5000,
        )

    return CagerigObjectSettings


CLASSES: list[type] = []


def register() -> None:
    CLASSES[:] = [_settings_class()]
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Object.cagerig = PointerProperty(type=CLASSES[0])


def unregister() -> None:
    del bpy.types.Object.cagerig
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
    CLASSES.clear()
