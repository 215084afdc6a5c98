"""The binding, kept with the skin object as ID properties (saved in the .blend, restored by undo).

``skin["cagerig_binding"]`` holds what the rig was built from (bind-time rest skin, triangles, skinning
weights, rest joints, cage; world space, float64), the current rest cage C and the rig options
(coordinates, CageUp fit, skinning, unfitted-cage policy) that what Blender shows was computed
with. Φ, MaxVol and Ψ are recomputed from the bind-time arrays when the file is opened
(deterministic: the same arrays give the same rig), then the stored rest cage is applied as one
rest-cage edit, which reproduces M = Φ·C and S = Ψ·C exactly as they were.

The options the user wants live in the skin's settings (props.py) and, for the skinning, in its
Armature modifier (Preserve Volume); when they differ from the applied ones the add-on rebinds
(engine.coupling). Undo restores both together.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass
from typing import Any

import bpy
import numpy as np

KEY = "cagerig_binding"  # not "cagerig": that name holds the settings (props.py)
FORMAT = 1


@dataclass
class Binding:
    bind_id: str
    mesh: np.ndarray  # (n, 3) bind-time rest skin, world space
    triangles: np.ndarray  # (m, 3)
    weight_rows: np.ndarray
    weight_cols: np.ndarray
    weight_values: np.ndarray
    joints: np.ndarray  # (J, 3) bind-time rest heads, world space
    parents: np.ndarray  # (J,)
    names: list[str]
    cage: np.ndarray  # (c, 3) bind-time rest cage, world space
    cage_triangles: np.ndarray
    rest_cage: np.ndarray  # (c, 3) current rest cage C, world space
    options: RigOptions  # the options what Blender shows was computed with


@dataclass(frozen=True)
class RigOptions:
    """The rig choices of the CLI (``--coords``, ``--cage-fit``, ``--skinning``,
    ``--unfitted-cage``), by the names the cagerig package lists (cagerig.COORDS_KINDS, …)."""

    coords: str = "mvc"
    cage_fit: str = "regularised"
    skinning: str = "lbs"
    unfitted_cage: str = "refuse"
    green_face_term: str = "fold-safe"

    def rig_key(self) -> str:
        """What the rig's precomputation depends on (the unfitted-cage policy is set after)."""
        return f"{self.coords}:{self.cage_fit}:{self.skinning}:{self.green_face_term}"

    def describe(self) -> str:
        green = f", {self.green_face_term} face term" if self.coords == "green" else ""
        return (f"{self.coords}{green}, {self.cage_fit} fit, {self.skinning.upper()}, "
                f"unfitted cage: {self.unfitted_cage}")


_OPTION_KEYS = ("coords", "cage_fit", "skinning", "unfitted_cage", "green_face_term")


def _floats(a: np.ndarray) -> list[float]:
    return np.asarray(a, dtype=np.float64).ravel().tolist()


def _ints(a: np.ndarray) -> list[int]:
    return np.asarray(a, dtype=np.int64).ravel().tolist()


def _array(group: Any, name: str, dtype: Any, cols: int | None = None) -> np.ndarray:
    value = group[name]
    a = np.array(value.to_list() if hasattr(value, "to_list") else list(value), dtype=dtype)
    return a.reshape(-1, cols) if cols else a


def save(skin: bpy.types.Object, b: Binding) -> None:
    skin[KEY] = {
        "format": FORMAT,
        "bind_id": b.bind_id,
        "mesh": _floats(b.mesh),
        "triangles": _ints(b.triangles),
        "weight_rows": _ints(b.weight_rows),
        "weight_cols": _ints(b.weight_cols),
        "weight_values": _floats(b.weight_values),
        "joints": _floats(b.joints),
        "parents": _ints(b.parents),
        "names": "\n".join(b.names),
        "cage": _floats(b.cage),
        "cage_triangles": _ints(b.cage_triangles),
        "rest_cage": _floats(b.rest_cage),
        **{k: getattr(b.options, k) for k in _OPTION_KEYS},
    }


def new_bind_id() -> str:
    return uuid.uuid4().hex


def save_rest_cage(skin: bpy.types.Object, rest_cage: np.ndarray) -> None:
    skin[KEY]["rest_cage"] = _floats(rest_cage)


def applied_options(skin: bpy.types.Object) -> RigOptions:
    """The options the shown state was computed with (cheap: reads no array). Files from before
    an option existed hold none for it: its default, which is what they were computed with."""
    g = skin[KEY]
    default = RigOptions()
    return RigOptions(**{k: str(g.get(k, getattr(default, k))) for k in _OPTION_KEYS})


def save_applied_options(skin: bpy.types.Object, options: RigOptions) -> None:
    g = skin[KEY]
    for k in _OPTION_KEYS:
        g[k] = getattr(options, k)


def is_coupled(obj: bpy.types.Object) -> bool:
    return obj.type == "MESH" and KEY in obj.keys()


def bind_id(skin: bpy.types.Object) -> str:
    """The stored binding's id (cheap: reads no array)."""
    if not is_coupled(skin):
        raise ValueError(f"{skin.name!r} is not coupled (no cagerig binding stored with it)")
    return str(skin[KEY].get("bind_id", ""))


def load(skin: bpy.types.Object) -> Binding:
    """The stored binding; raises ValueError naming what is missing or damaged."""
    if not is_coupled(skin):
        raise ValueError(f"{skin.name!r} is not coupled (no cagerig binding stored with it)")
    g = skin[KEY]
    try:
        fmt = int(g["format"])
        if fmt != FORMAT:
            raise ValueError(f"binding format {fmt}, this add-on reads format {FORMAT}")
        return Binding(
            bind_id=str(g["bind_id"]),
            mesh=_array(g, "mesh", np.float64, 3),
            triangles=_array(g, "triangles", np.int64, 3),
            weight_rows=_array(g, "weight_rows", np.int64),
            weight_cols=_array(g, "weight_cols", np.int64),
            weight_values=_array(g, "weight_values", np.float64),
            joints=_array(g, "joints", np.float64, 3),
            parents=_array(g, "parents", np.int64),
            names=str(g["names"]).split("\n"),
            cage=_array(g, "cage", np.float64, 3),
            cage_triangles=_array(g, "cage_triangles", np.int64, 3),
            rest_cage=_array(g, "rest_cage", np.float64, 3),
            options=applied_options(skin),
        )
    except KeyError as e:
        raise ValueError(f"the cagerig binding of {skin.name!r} lacks {e}: couple again") from None


def remove(skin: bpy.types.Object) -> None:
    if KEY in skin.keys():
        del skin[KEY]
