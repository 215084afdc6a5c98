"""cagerig — real-time deformation with coupled cages and skeletons (Corda et al. 2020).

A rig couples a skinning skeleton and a deformation cage on one character: pose with bones,
sculpt volume with the cage, in the rest pose or the current pose, in any order, and every
structure stays in sync. Arrays in and out are numpy: float64 ``(n, 3)`` points, int ``(m, 3)``
triangles.

>>> import cagerig
>>> rig = cagerig.Rig.load("arm.obj")                     # companions found beside the mesh
>>> rig.rotate_joint("lowerarm01.R", [1, 0, 0], 60)        # bend the elbow (S' edit)
>>> rig.move_rest_cage([0, 2, 4, 5, 6], [2, -1, 1.5])      # sculpt the rest cage (C edit)
>>> rig.posed_mesh                                         # M', (#V, 3) float64
"""

from ._cagerig import (
    CAGE_FITS as CAGE_FITS,
    CAGE_LAYOUTS as CAGE_LAYOUTS,
    COORDS_KINDS as COORDS_KINDS,
    COORDS_PRECISIONS as COORDS_PRECISIONS,
    FIT_ROWS as FIT_ROWS,
    FIT_SOURCES as FIT_SOURCES,
    GREEN_FACE_TERMS as GREEN_FACE_TERMS,
    LOCALISATIONS as LOCALISATIONS,
    SKINNING_METHODS as SKINNING_METHODS,
    UNFITTED_CAGE_POLICIES as UNFITTED_CAGE_POLICIES,
    EditScript as EditScript,
    OutputFolder as OutputFolder,
    Rig as Rig,
    RigError as RigError,
    RigFileError as RigFileError,
    RigWarning as RigWarning,
    ScriptError as ScriptError,
    __version__ as __version__,
    cor as cor,
    cor_centres as cor_centres,
    dqs as dqs,
    lbs as lbs,
    max_entropy_coordinates as max_entropy_coordinates,
    maxvol_rows as maxvol_rows,
    mvc as mvc,
    green_coordinates as green_coordinates,
    read_obj as read_obj,
    skin_weights as skin_weights,
    subdivide as subdivide,
    validate_cage as validate_cage,
    generate_cage as generate_cage,
    write_obj as write_obj,
)
from .states import replay_script as replay_script, save_state as save_state

__all__ = [
    "CAGE_FITS",
    "CAGE_LAYOUTS",
    "COORDS_KINDS",
    "COORDS_PRECISIONS",
    "FIT_ROWS",
    "FIT_SOURCES",
    "GREEN_FACE_TERMS",
    "LOCALISATIONS",
    "SKINNING_METHODS",
    "UNFITTED_CAGE_POLICIES",
    "EditScript",
    "OutputFolder",
    "Rig",
    "RigError",
    "RigFileError",
    "RigWarning",
    "ScriptError",
    "cor",
    "cor_centres",
    "dqs",
    "lbs",
    "max_entropy_coordinates",
    "maxvol_rows",
    "mvc",
    "green_coordinates",
    "read_obj",
    "replay_script",
    "save_state",
    "skin_weights",
    "subdivide",
    "validate_cage",
    "generate_cage",
    "write_obj",
]
