"""Type stubs of the native module (crates/cagerig-py/src). Arrays: float64 ``(n, 3)`` points,
int64 ``(m, 3)`` triangles; inputs accept anything ``numpy.asarray`` takes with a real (points) or
integer (indices) dtype."""

import os
from typing import Any, Literal, Optional, Sequence, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

F64Array = npt.NDArray[np.float64]
I64Array = npt.NDArray[np.int64]
ArrayLike = npt.ArrayLike
PathLike = Union[str, os.PathLike[str]]
Skinning = Literal["lbs", "dqs", "cor"]
FitRows = Literal["maxvol", "all"]
Localisation = Literal["articulation", "reference_tool"]
FitSource = Literal["ghost", "displayed"]
Precision = Literal["f64", "f32"]
Structure = Literal["posed_mesh", "rest_mesh", "posed_cage", "rest_cage"]

class RigError(ValueError): ...
class RigFileError(RigError): ...
class ScriptError(RigError): ...
class RigWarning(UserWarning): ...

def mvc(points: ArrayLike, cage_vertices: ArrayLike, cage_triangles: ArrayLike) -> F64Array:
    """Mean value coordinates Φ, (n, #C), of ``points`` w.r.t. the cage."""

def maxvol_rows(phi: ArrayLike) -> tuple[I64Array, float]:
    """MaxVol rows of Φ and ``log|det Φ[rows]|``."""

@overload
def max_entropy_coordinates(
    points: ArrayLike, prior: ArrayLike, targets: Sequence[float], signed: bool = False
) -> F64Array: ...
@overload
def max_entropy_coordinates(
    points: ArrayLike, prior: ArrayLike, targets: ArrayLike, signed: bool = False
) -> F64Array: ...
def lbs(vertices: ArrayLike, weights: Any, transforms: ArrayLike) -> F64Array:
    """Linear blend skinning; ``weights`` dense (n, J) or scipy.sparse; ``transforms`` (J, 4, 4)."""

def dqs(vertices: ArrayLike, weights: Any, transforms: ArrayLike) -> F64Array:
    """Dual quaternion skinning (rigid transforms)."""

def cor(vertices: ArrayLike, weights: Any, transforms: ArrayLike, centres: ArrayLike) -> F64Array:
    """Skinning with optimised centres of rotation (rigid transforms, (n, 3) centres)."""

def cor_centres(
    vertices: ArrayLike, triangles: ArrayLike, weights: Any, sigma: float = 0.1
) -> F64Array:
    """Centres of rotation (Le & Hodgins 2016), (n, 3)."""

def validate_cage(vertices: ArrayLike, triangles: ArrayLike) -> I64Array:
    """Checks a cage (closed, manifold, oriented); returns its (possibly flipped) triangles."""

@overload
def subdivide(
    vertices: ArrayLike, triangles: ArrayLike, levels: int = 1, weights: None = None
) -> tuple[F64Array, I64Array]: ...
@overload
def subdivide(
    vertices: ArrayLike, triangles: ArrayLike, levels: int, weights: Any
) -> tuple[F64Array, I64Array, F64Array]: ...
def read_obj(path: PathLike) -> tuple[F64Array, I64Array]:
    """Reads an OBJ triangle mesh."""

def write_obj(path: PathLike, vertices: ArrayLike, triangles: ArrayLike) -> None:
    """Writes an OBJ triangle mesh (round-trip floats, atomic replace)."""

class EditScript:
    """An edit script in the ``cagerig edit`` JSON format."""

    def __init__(self, script: Union[str, dict[str, Any], PathLike]) -> None: ...
    def __len__(self) -> int: ...
    @property
    def skinning(self) -> Optional[Skinning]: ...
    @property
    def steps(self) -> list[dict[str, Any]]: ...
    @property
    def text(self) -> str: ...
    def validate(self, rig: Rig) -> None: ...
    def run_step(self, rig: Rig, index: int) -> None: ...
    def run(self, rig: Rig) -> None: ...

class Rig:
    """A coupled cage + skeleton rig. Properties return copies except ``cage_coords``/``phi``
    (a read-only view of Φ)."""

    @staticmethod
    def load(
        path: PathLike,
        cage: Optional[PathLike] = None,
        *,
        skinning: Skinning = "lbs",
        fit_rows: FitRows = "maxvol",
        localisation: Localisation = "articulation",
        fit_source: FitSource = "ghost",
        coords_precision: Precision = "f64",
    ) -> Rig: ...
    @staticmethod
    def builtin(
        name: Literal["bar", "bar_irregular", "snake"],
        resolution: Optional[int] = None,
        *,
        skinning: Skinning = "lbs",
        fit_rows: FitRows = "maxvol",
        localisation: Localisation = "articulation",
        fit_source: FitSource = "ghost",
        coords_precision: Precision = "f64",
    ) -> Rig: ...
    @staticmethod
    def from_arrays(
        vertices: ArrayLike,
        triangles: ArrayLike,
        skin_weights: Any,
        joint_positions: ArrayLike,
        joint_parents: ArrayLike,
        cage_vertices: ArrayLike,
        cage_triangles: ArrayLike,
        joint_names: Optional[Sequence[str]] = None,
        *,
        skinning: Skinning = "lbs",
        fit_rows: FitRows = "maxvol",
        localisation: Localisation = "articulation",
        fit_source: FitSource = "ghost",
        coords_precision: Precision = "f64",
    ) -> Rig: ...
    def copy(self) -> Rig: ...
    def __copy__(self) -> Rig: ...
    def __deepcopy__(self, memo: Any) -> Rig: ...
    # Edits.
    def rotate_joint(self, joint: Union[str, int], axis: ArrayLike, degrees: float) -> None: ...
    def move_rest_cage(self, indices: Union[int, ArrayLike], offsets: ArrayLike) -> None: ...
    def move_posed_cage(self, indices: Union[int, ArrayLike], offsets: ArrayLike) -> None: ...
    def set_skinning(self, method: Skinning) -> None: ...
    def set_fit_source(self, source: FitSource) -> None: ...
    def set_pose(self, local_rotations: ArrayLike, root_motion: Optional[ArrayLike] = None) -> None: ...
    @property
    def pose(self) -> tuple[F64Array, F64Array]: ...
    def reset_pose(self) -> None: ...
    # Animation and scripts.
    def set_animation(self, skeleton: Any = None, cage: Any = None) -> None: ...
    @property
    def animation_duration(self) -> float: ...
    def sample_animation(self, t: float) -> None: ...
    def run_script(self, script: Union[EditScript, str, dict[str, Any], PathLike]) -> None: ...
    # Output.
    def save(self, directory: PathLike, name: str = "rig") -> None: ...
    def export_obj(self, path: PathLike, what: Structure = "posed_mesh") -> None: ...
    # Structures.
    @property
    def rest_mesh(self) -> F64Array: ...
    @property
    def posed_mesh(self) -> F64Array: ...
    @property
    def rest_cage(self) -> F64Array: ...
    @property
    def posed_cage(self) -> F64Array: ...
    @property
    def original_rest_cage(self) -> F64Array: ...
    @property
    def rest_joints(self) -> F64Array: ...
    @property
    def posed_joints(self) -> F64Array: ...
    @property
    def rest_joint_frames(self) -> F64Array: ...
    @property
    def posed_joint_frames(self) -> F64Array: ...
    @property
    def skinning_transforms(self) -> F64Array: ...
    @property
    def triangles(self) -> I64Array: ...
    @property
    def cage_triangles(self) -> I64Array: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def joint_parents(self) -> I64Array: ...
    @property
    def cage_coords(self) -> F64Array:
        """Φ (#V, #C): read-only view, no copy."""
    @property
    def phi(self) -> F64Array: ...
    @property
    def joint_coords(self) -> F64Array: ...
    @property
    def psi(self) -> F64Array: ...
    @property
    def skin_weights(self) -> F64Array: ...
    @property
    def omega(self) -> F64Array: ...
    @property
    def cor_centres(self) -> Optional[F64Array]: ...
    @property
    def fit_rows(self) -> I64Array: ...
    @property
    def skinning(self) -> Skinning: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_joints(self) -> int: ...
    @property
    def num_cage_vertices(self) -> int: ...
