"""Installs and enables the add-on zip as a user would, on the Blender running this script:
as an extension on Blender >= 4.2 (what drag and drop or Get Extensions ▸ Install from Disk run:
the manifest, the bundled wheel), as a legacy add-on on older Blenders. Shared by the tests and
the benchmarks."""

from __future__ import annotations

import importlib
import sys
from types import ModuleType

import bpy


def install(zip_path: str) -> ModuleType:
    """Installs, enables and returns the add-on's package."""
    import numpy as np

    print(f"Blender {bpy.app.version_string}, Python {sys.version.split()[0]}, numpy {np.__version__}", flush=True)
    if bpy.app.version >= (4, 2, 0):
        bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default", enable_on_install=True)
        module = "bl_ext.user_default.cagerig_blender"
    else:
        bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
        bpy.ops.preferences.addon_enable(module="cagerig_blender")
        module = "cagerig_blender"
    if module not in bpy.context.preferences.addons:
        raise RuntimeError(f"the add-on {module} is not enabled after installing {zip_path}")
    if "bool" not in np.__dict__:  # Debian's Blender 3.4 glTF importer + numpy >= 1.24
        np.bool = bool  # type: ignore[attr-defined]
    return importlib.import_module(module)
