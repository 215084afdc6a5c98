"""Type stubs of the native module (crates/cagerig-py/src). Arrays: float64 ``(n, 3)`` points,
int64 ``(m, 3)`` triangles; inputs accept anything ``numpy.asarray`` takes with a real (points) or
integer (indices) dtype."""

import os
import pathlib
from typing import Any, Callable, Literal, Optional, Sequence, Union, final, overload

import numpy as np
import numpy.typing as npt

__version__: str
# The accepted names of each rig option, in the order front ends list them.
SKINNING_METHODS: list[str]
COORDS_KINDS: list[str]
CAGE_FITS: list[str]
CAGE_LAYOUTS: list[str]
UNFITTED_CAGE_POLICIES: list[str]
FIT_ROWS: list[str]
LOCALISATIONS: list[str]
FIT_SOURCES: list[str]
COORDS_PRECISIONS: list[str]
GREEN_FACE_TERMS: list[str]
__all__ = ['RigError', 'RigFileError', 'ScriptError', 'RigWarning', 'Rig', 'EditScript', 'mvc', 'maxvol_rows',
           'max_entropy_coordinates', 'lbs', 'dqs', 'cor', 'cor_centres', 'validate_cage', 'generate_cage', 'subdivide',
           'read_obj', 'write_obj', '__version__', 'SKINNING_METHODS', 'COORDS_KINDS', 'FIT_ROWS', 'LOCALISATIONS', 'FIT_SOURCES', 'COORDS_PRECISIONS', 'GREEN_FACE_TERMS',
           'CAGE_FITS', 'CAGE_LAYOUTS', 'UNFITTED_CAGE_POLICIES']

_F64Array = npt.NDArray[np.float64]
_I64Array = npt.NDArray[np.int64]
_ArrayLike = npt.ArrayLike
_PathLike = Union[str, os.PathLike[str]]
_Skinning = Literal["lbs", "dqs", "cor", "blended"]
_Coords = Literal["mvc", "green"]
_CageFit = Literal["regularised", "paper"]
_CageLayout = Literal["skeleton", "offset"]
_UnfittedCage = Literal["refuse", "keep"]
_GreenFaceTerm = Literal["fold-safe", "lipman"]
_FitRows = Literal["maxvol", "all"]
_Localisation = Literal["articulation", "reference-tool"]
_FitSource = Literal["ghost", "displayed"]
_Precision = Literal["f64", "f32"]
_Structure = Literal["posed_mesh", "rest_mesh", "posed_cage", "rest_cage"]

class RigError(ValueError): ...
class RigFileError(RigError): ...
class ScriptError(RigError): ...
class RigWarning(UserWarning): ...

def mvc(points: _ArrayLike, cage_vertices: _ArrayLike, cage_triangles: _ArrayLike) -> _F64Array:
    """Mean value coordinates Φ, (n, #C), of ``points`` w.r.t. the cage."""

def green_coordinates(
    points: _ArrayLike, cage_vertices: _ArrayLike, cage_triangles: _ArrayLike
) -> tuple[_F64Array, _F64Array]:
    """Green coordinates (φ (n, #C), ψ (n, #F)) of ``points`` w.r.t. the closed cage."""

def skin_weights(
    vertices: _ArrayLike,
    triangles: _ArrayLike,
    joint_positions: _ArrayLike,
    parents: _ArrayLike,
    max_influences: int = 4,
    cage: Optional[tuple[_ArrayLike, _ArrayLike]] = None,
    *,
    joint_names: Optional[Sequence[str]] = None,
    tips: Union[Literal["auto", "all", "none"], Sequence[int], None] = None,
    resolution: int = 128,
    exponent: float = 8.0,
) -> _F64Array:
    """Automatic skinning weights Ω, (n, #J), by geodesic voxel binding: rows sum to 1, at
    most ``max_influences`` non-zeros; ``cage`` = (vertices, triangles) of a closed cage."""

def maxvol_rows(phi: _ArrayLike) -> tuple[_I64Array, float]:
    """MaxVol rows of Φ and ``log|det Φ[rows]|``."""

@overload
def max_entropy_coordinates(
    points: _ArrayLike, prior: _ArrayLike, targets: Sequence[float], signed: bool = False
) -> _F64Array: ...
@overload
def max_entropy_coordinates(
    points: _ArrayLike, prior: _ArrayLike, targets: _ArrayLike, signed: bool = False
) -> _F64Array: ...
def lbs(vertices: _ArrayLike, weights: Any, transforms: _ArrayLike) -> _F64Array:
    """Linear blend skinning; ``weights`` dense (n, J) or scipy.sparse; ``transforms`` (J, 4, 4)."""

def dqs(vertices: _ArrayLike, weights: Any, transforms: _ArrayLike) -> _F64Array:
    """Dual quaternion skinning (rigid transforms)."""

def cor(vertices: _ArrayLike, weights: Any, transforms: _ArrayLike, centres: _ArrayLike) -> _F64Array:
    """_Skinning with optimised centres of rotation (rigid transforms, (n, 3) centres)."""

def cor_centres(
    vertices: _ArrayLike, triangles: _ArrayLike, weights: Any, sigma: float = 0.1
) -> _F64Array:
    """Centres of rotation (Le & Hodgins 2016), (n, 3)."""

def validate_cage(vertices: _ArrayLike, triangles: _ArrayLike) -> _I64Array:
    """Checks a cage (closed, manifold, oriented); returns its (possibly flipped) triangles."""

def generate_cage(
    vertices: _ArrayLike, triangles: _ArrayLike, target_vertices: int = 100, margin: Optional[float] = None
) -> tuple[_F64Array, _I64Array]:
    """A closed, validated cage around a triangle mesh (cagerig cage's method)."""

@overload
def subdivide(
    vertices: _ArrayLike, triangles: _ArrayLike, levels: int = 1, weights: None = None
) -> tuple[_F64Array, _I64Array]: ...
@overload
def subdivide(
    vertices: _ArrayLike, triangles: _ArrayLike, levels: int, weights: Any
) -> tuple[_F64Array, _I64Array, _F64Array]: ...
def read_obj(path: _PathLike) -> tuple[_F64Array, _I64Array]:
    """Reads an OBJ triangle mesh."""

def write_obj(path: _PathLike, vertices: _ArrayLike, triangles: _ArrayLike) -> None:
    """Writes an OBJ triangle mesh (round-trip floats, atomic replace)."""

@final
class EditScript:
    """An edit script in the ``cagerig edit`` JSON format."""

    def __new__(cls, script: Union[str, dict[str, Any], _PathLike]) -> EditScript: ...
    def __len__(self) -> int: ...
    @property
    def skinning(self) -> Optional[_Skinning]: ...
    @property
    def steps(self) -> list[dict[str, Any]]: ...
    @property
    def text(self) -> str: ...
    def validate(self, rig: Rig) -> None: ...
    def run_step(self, rig: Rig, index: int) -> None: ...
    def run(self, rig: Rig) -> None: ...

@final
class OutputFolder:
    """Files that appear together in ``directory`` or not at all: they are staged beside it
    and put in place by :meth:`finish` (or at the end of a ``with`` block that raised nothing).
    ``directory`` must be new or empty, or, with ``overwrite=True``, an earlier cagerig output
    (replaced as a whole); a folder holding other files raises ``FileExistsError``."""

    def __new__(cls, directory: _PathLike, overwrite: bool = False) -> OutputFolder: ...
    def write_obj(self, name: str, vertices: _ArrayLike, triangles: _ArrayLike) -> None: ...
    def write_text(self, name: str, text: str) -> None: ...
    def finish(self) -> list[pathlib.Path]: ...
    def discard(self) -> None: ...
    def __enter__(self) -> OutputFolder: ...
    def __exit__(self, exc_type: Any, exc_value: Any, traceback: Any) -> bool: ...

@final
class Rig:
    """A coupled cage + skeleton rig. Properties return copies except ``cage_coords``/``phi``
    (a read-only view of Φ)."""

    @staticmethod
    def load(
        path: _PathLike,
        cage: Optional[_PathLike] = None,
        *,
        skinning: Optional[_Skinning] = None,
        fit_rows: _FitRows = "maxvol",
        localisation: _Localisation = "articulation",
        fit_source: _FitSource = "ghost",
        coords_precision: _Precision = "f64",
        keep_file_coords: bool = False,
        auto_cage: Optional[int] = None,
        cage_layout: _CageLayout = "skeleton",
        auto_weights: bool = False,
        coords: _Coords = "mvc",
        cage_fit: _CageFit = "regularised",
        green_face_term: _GreenFaceTerm = "fold-safe",
        progress: Optional[Callable[[str, int, int], None]] = None,
        skin: Optional[str] = None,
    ) -> Rig: ...
    @staticmethod
    def builtin(
        name: Literal["bar", "bar_irregular", "snake"],
        resolution: Optional[int] = None,
        *,
        skinning: _Skinning = "lbs",
        fit_rows: _FitRows = "maxvol",
        localisation: _Localisation = "articulation",
        fit_source: _FitSource = "ghost",
        coords_precision: _Precision = "f64",
        coords: _Coords = "mvc",
        cage_fit: _CageFit = "regularised",
        green_face_term: _GreenFaceTerm = "fold-safe",
        progress: Optional[Callable[[str, int, int], None]] = None,
    ) -> Rig: ...
    @staticmethod
    def from_arrays(
        vertices: _ArrayLike,
        triangles: _ArrayLike,
        skin_weights: Any,
        joint_positions: _ArrayLike,
        joint_parents: _ArrayLike,
        cage_vertices: _ArrayLike,
        cage_triangles: _ArrayLike,
        joint_names: Optional[Sequence[str]] = None,
        *,
        skinning: _Skinning = "lbs",
        fit_rows: _FitRows = "maxvol",
        localisation: _Localisation = "articulation",
        fit_source: _FitSource = "ghost",
        coords_precision: _Precision = "f64",
        coords: _Coords = "mvc",
        cage_fit: _CageFit = "regularised",
        green_face_term: _GreenFaceTerm = "fold-safe",
        progress: Optional[Callable[[str, int, int], None]] = None,
        dq_blend_weights: Optional[_ArrayLike] = None,
    ) -> Rig: ...
    def copy(self) -> Rig: ...
    @property
    def coords(self) -> _Coords: ...
    @property
    def cage_fit(self) -> _CageFit: ...
    @property
    def green_face_term(self) -> _GreenFaceTerm: ...
    def __copy__(self) -> Rig: ...
    def __deepcopy__(self, memo: Any) -> Rig: ...
    # Edits.
    def rotate_joint(self, joint: Union[str, int], axis: _ArrayLike, degrees: float) -> None: ...
    def move_rest_cage(self, indices: Union[int, _ArrayLike], offsets: _ArrayLike) -> None: ...
    def move_posed_cage(self, indices: Union[int, _ArrayLike], offsets: _ArrayLike) -> None: ...
    def set_skinning(self, method: _Skinning) -> None: ...
    def set_unfitted_cage(self, policy: _UnfittedCage) -> None: ...
    @property
    def unfitted_cage(self) -> _UnfittedCage: ...
    @property
    def posed_cage_unfitted(self) -> Optional[str]: ...
    def set_fit_source(self, source: _FitSource) -> None: ...
    def set_pose(self, local_rotations: _ArrayLike, root_motion: Optional[_ArrayLike] = None) -> None: ...
    @property
    def pose(self) -> tuple[_F64Array, _F64Array]: ...
    def reset_pose(self) -> None: ...
    # Animation and scripts.
    def set_animation(self, skeleton: Any = None, cage: Any = None) -> None: ...
    @property
    def animation_duration(self) -> float: ...
    def sample_animation(self, t: float) -> None: ...
    def run_script(self, script: Union[EditScript, str, dict[str, Any], _PathLike]) -> None: ...
    # Output.
    def save(self, directory: _PathLike, name: str = "rig", overwrite: bool = False) -> None: ...
    def export_obj(self, path: _PathLike, what: _Structure = "posed_mesh") -> None: ...
    def export_gltf(self, path: _PathLike, name: str = "cagerig", bake: bool = False) -> None: ...
    # Structures.
    @property
    def rest_mesh(self) -> _F64Array: ...
    @property
    def posed_mesh(self) -> _F64Array: ...
    def lbs_rest_preimage(self) -> _F64Array: ...
    @property
    def rest_cage(self) -> _F64Array: ...
    @property
    def posed_cage(self) -> _F64Array: ...
    @property
    def original_rest_cage(self) -> _F64Array: ...
    @property
    def rest_joints(self) -> _F64Array: ...
    @property
    def posed_joints(self) -> _F64Array: ...
    @property
    def rest_joint_frames(self) -> _F64Array: ...
    @property
    def posed_joint_frames(self) -> _F64Array: ...
    @property
    def skinning_transforms(self) -> _F64Array: ...
    @property
    def triangles(self) -> _I64Array: ...
    @property
    def cage_triangles(self) -> _I64Array: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def joint_parents(self) -> _I64Array: ...
    @property
    def cage_coords(self) -> _F64Array:
        """Φ (#V, #C): read-only view, no copy."""
    @property
    def phi(self) -> _F64Array: ...
    @property
    def joint_coords(self) -> _F64Array: ...
    @property
    def psi(self) -> _F64Array: ...
    @property
    def joint_face_coords(self) -> _F64Array:
        """Ψ_ψ (#J, #F) of a Green rig: rest joints = Ψ_φ C + Ψ_ψ g(C); (#J, 0) for MVC."""
    @property
    def rest_cage_terms(self) -> _F64Array:
        """g(C) (#F, 3), the rest cage's stretched face normals (Green); (0, 3) for MVC."""
    @property
    def skin_weights(self) -> _F64Array: ...
    @property
    def omega(self) -> _F64Array: ...
    @property
    def cor_centres(self) -> Optional[_F64Array]: ...
    @property
    def fit_rows(self) -> _I64Array: ...
    @property
    def skinning(self) -> _Skinning: ...
    @property
    def dq_blend_weights(self) -> Optional[_F64Array]: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_joints(self) -> int: ...
    @property
    def num_cage_vertices(self) -> int: ...
