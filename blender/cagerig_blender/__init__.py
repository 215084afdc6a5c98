"""cagerig for Blender: couples an armature and a cage on a skinned mesh, live, both ways
(Corda et al., Real-Time Deformation with Coupled Cages and Skeletons, CGF 2020).

The cagerig Python package (with its compiled abi3 module) ships inside the add-on, under
``vendor/`` (and as a wheel under ``wheels/`` for Blender >= 4.2's extension installer); enabling
the add-on puts ``vendor/`` on ``sys.path`` when ``cagerig`` is not importable otherwise, so that
``import cagerig`` works in Blender's Python (3.10 or newer; it needs numpy, which Blender ships — on Debian's
Blender: ``apt-get install python3-numpy``).
"""

from __future__ import annotations

import os
import sys

bl_info = {
    "name": "cagerig",
    "author": "cagerig authors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > cagerig",
    "description": "Coupled cage + skeleton deformation (Corda et al. 2020): cage edits move the bones",
    "category": "Rigging",
}

_VENDOR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "vendor")


def _vendor_path() -> None:
    """Blender >= 4.2 installs the bundled wheel (blender_manifest.toml); older Blenders import
    the package from vendor/."""
    try:
        import cagerig  # noqa: F401
    except ImportError:
        if os.path.isdir(_VENDOR) and _VENDOR not in sys.path:
            sys.path.insert(0, _VENDOR)


def register() -> None:
    _vendor_path()
    from . import handlers, operators, panel, props, weights

    props.register()
    operators.register()
    weights.register()
    panel.register()
    handlers.register()


def unregister() -> None:
    from . import handlers, operators, panel, props, weights

    handlers.unregister()
    panel.unregister()
    weights.unregister()
    operators.unregister()
    props.unregister()
