"""Blender data <-> numpy arrays, all in world space (float64).

The rig lives in world space: the skin, the cage and the bones are brought there with their
objects' ``matrix_world``; what is written back is brought into each object's own space.
Blender stores coordinates as float32, so a round trip rounds to float32.
"""

from __future__ import annotations


import bpy
import numpy as np
from mathutils import Matrix

F64 = np.float64


def matrix_np(m: Matrix) -> np.ndarray:
    """A mathutils 4x4 matrix as a float64 (4, 4) array."""
    return np.array([list(row) for row in m], dtype=F64)


_IDENTITY = np.eye(4)


def _apply(m: np.ndarray, pts: np.ndarray) -> np.ndarray:
    if np.array_equal(m, _IDENTITY):  # an object at the origin, unrotated, unscaled: no pass over the points
        return pts
    return pts @ m[:3, :3].T + m[:3, 3]


def _positions(mesh: bpy.types.Mesh) -> tuple[bpy.types.bpy_prop_collection, str]:
    """The collection and field that hold the vertex positions. Blender >= 3.5 stores them as the
    "position" attribute, whose foreach_get/set copies the array at once; ``vertices``' "co"
    goes element by element there (29 ms against 0.1 ms for 133k vertices on Blender 4.5)."""
    attributes = getattr(mesh, "attributes", None)
    a = attributes.get("position") if attributes is not None else None
    if a is not None and a.domain == "POINT" and a.data_type == "FLOAT_VECTOR":
        return a.data, "vector"
    return mesh.vertices, "co"


def mesh_local_coords(mesh: bpy.types.Mesh) -> np.ndarray:
    """Vertex coordinates of mesh data (object space), (n, 3) float64."""
    n = len(mesh.vertices)
    co = np.empty(n * 3, dtype=np.float32)
    collection, field = _positions(mesh)
    collection.foreach_get(field, co)
    return co.reshape(n, 3).astype(F64)


def world_coords(obj: bpy.types.Object, mesh: bpy.types.Mesh | None = None) -> np.ndarray:
    """The object's mesh vertices (its own data unless ``mesh`` is given) in world space."""
    return _apply(matrix_np(obj.matrix_world), mesh_local_coords(mesh or obj.data))


def edit_mode_world_coords(obj: bpy.types.Object) -> np.ndarray | None:
    """While ``obj`` is in Edit Mode: its edit-mesh coordinates in world space (else None)."""
    if obj.mode != "EDIT" or obj.type != "MESH":
        return None
    import bmesh

    bm = bmesh.from_edit_mesh(obj.data)
    co = np.array([v.co[:] for v in bm.verts], dtype=F64)
    return _apply(matrix_np(obj.matrix_world), co)


def write_world_coords(obj: bpy.types.Object, world: np.ndarray) -> None:
    """Writes world-space points into the object's mesh data (object space) and tags it."""
    inv = np.linalg.inv(matrix_np(obj.matrix_world))
    local = _apply(inv, np.asarray(world, dtype=F64)).astype(np.float32)
    mesh = obj.data
    collection, field = _positions(mesh)
    collection.foreach_set(field, local.ravel())
    mesh.update()


def write_key_world_coords(obj: bpy.types.Object, key: bpy.types.ShapeKey, world: np.ndarray) -> None:
    """Writes world-space points into a shape key of the object's mesh (object space)."""
    inv = np.linalg.inv(matrix_np(obj.matrix_world))
    # Blender >= 4.1's ``points`` copies the array at once; ``data`` goes point by point (15 ms at
    # 133k vertices on 3.4, 34 ms on 4.5).
    points = key.points if "points" in key.bl_rna.properties else key.data
    points.foreach_set("co", _apply(inv, np.asarray(world, dtype=F64)).astype(np.float32).ravel())
    key.id_data.update_tag()
    obj.data.update()


def as_displayed(obj: bpy.types.Object, world: np.ndarray) -> np.ndarray:
    """World points as ``write_world_coords`` then ``world_coords`` would give them back
    (float32 in the object's space)."""
    m = matrix_np(obj.matrix_world)
    local = _apply(np.linalg.inv(m), np.asarray(world, dtype=F64)).astype(np.float32)
    return _apply(m, local.astype(F64))


def triangles(mesh: bpy.types.Mesh) -> np.ndarray:
    """Triangles of the mesh (its polygons triangulated by Blender), (m, 3) int64."""
    mesh.calc_loop_triangles()
    n = len(mesh.loop_triangles)
    t = np.empty(n * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", t)
    return t.reshape(n, 3).astype(np.int64)


def connected_parts(num_vertices: int, tris: np.ndarray) -> int:
    """How many separate parts the triangles ``tris`` (m, 3) form over ``num_vertices`` vertices
    (vertices in no triangle count as parts of their own)."""
    parent = np.arange(num_vertices)

    def root(v: int) -> int:
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = int(parent[v])
        return v

    for a, b, c in tris.tolist():
        for u, w in ((a, b), (b, c)):
            ru, rw = root(u), root(w)
            if ru != rw:
                parent[ru] = rw
    return len({root(v) for v in range(num_vertices)})


def skin_weights_sparse(
    obj: bpy.types.Object, bone_names: list[str], deform: list[bool]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertex groups named after deforming bones as sparse (rows, cols, values), rows
    normalised as Blender's Armature modifier does (it divides by the weight sum)."""
    col_of_group: dict[int, int] = {}
    for j, name in enumerate(bone_names):
        g = obj.vertex_groups.get(name)
        if g is not None and deform[j]:
            col_of_group[g.index] = j
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    for v in obj.data.vertices:
        for ge in v.groups:
            j = col_of_group.get(ge.group)
            if j is not None and ge.weight > 0.0:
                rows.append(v.index)
                cols.append(j)
                vals.append(ge.weight)
    r = np.array(rows, dtype=np.int64)
    c = np.array(cols, dtype=np.int64)
    w = np.array(vals, dtype=F64)
    sums = np.bincount(r, weights=w, minlength=len(obj.data.vertices))
    if len(r):
        w = w / sums[r]
    return r, c, w


class SparseWeights:
    """The duck-typed sparse matrix cagerig accepts (``tocoo()`` → shape, row, col, data)."""

    def __init__(self, shape: tuple[int, int], row: np.ndarray, col: np.ndarray, data: np.ndarray):
        self.shape = shape
        self.row = row
        self.col = col
        self.data = data

    def tocoo(self) -> SparseWeights:
        return self


# How Blender shows each of cagerig's skinning methods, by cagerig's names: the Armature
# modifier's Preserve Volume setting, and whether the add-on adds a corrective shape key. LBS and
# DQS are the modifier's own (cagerig's DQS is Blender's Preserve Volume); CoR is the modifier's
# LBS of the rest skin plus a per-pose corrective key (engine.py). Blended (per-vertex LBS/DQS
# weights) Blender cannot show: the add-on does not offer it.
BLENDER_SKINNING = {"lbs": (False, False), "dqs": (True, False), "cor": (False, True)}


def skinning_of(mod: bpy.types.ArmatureModifier, corrective: bool) -> str:
    """The skinning method shown: the modifier's Preserve Volume (DQS) wins over the corrective
    flag (a user who ticks Preserve Volume in the modifier gets DQS)."""
    shown = (bool(mod.use_deform_preserve_volume), bool(corrective) and not mod.use_deform_preserve_volume)
    return next(k for k, v in BLENDER_SKINNING.items() if v == shown)


def skinning_settings(method: str) -> tuple[bool, bool]:
    """(Preserve Volume, corrective key) for a method; ValueError naming what Blender shows."""
    if method not in BLENDER_SKINNING:
        raise ValueError(f"Blender shows {', '.join(BLENDER_SKINNING)} skinning, not {method!r}")
    return BLENDER_SKINNING[method]


def rest_skeleton(arm: bpy.types.Object) -> tuple[list[str], np.ndarray, np.ndarray, list[bool]]:
    """Bone names, rest heads in world space (J, 3), parent indices (-1 = root), deform flags.

    Joint j of the rig is bone j of ``arm.data.bones`` (Blender lists parents before children)."""
    bones = arm.data.bones
    names = [b.name for b in bones]
    index = {n: j for j, n in enumerate(names)}
    heads = np.array([b.head_local[:] for b in bones], dtype=F64).reshape(-1, 3)
    heads = _apply(matrix_np(arm.matrix_world), heads)
    parents = np.array([index[b.parent.name] if b.parent else -1 for b in bones], dtype=np.int64)
    deform = [bool(b.use_deform) for b in bones]
    return names, heads, parents, deform


def _matrices(collection: bpy.types.bpy_prop_collection, field: str, n: int) -> np.ndarray:
    """A 4x4 matrix property of every item at once, (n, 4, 4) float64 (Blender keeps them
    column-major)."""
    buf = np.empty(n * 16, dtype=np.float32)
    collection.foreach_get(field, buf)
    return buf.reshape(n, 4, 4).transpose(0, 2, 1).astype(F64)


def skinning_transforms(arm: bpy.types.Object) -> np.ndarray:
    """World-space skinning transforms of the bones, K_j = A·P_j·B_j⁻¹·A⁻¹ (J, 4, 4), where A is
    the armature's matrix_world, P_j the pose matrix and B_j the rest matrix (what the Armature
    modifier applies). Only meaningful while the armature shows its pose (in Rest Position Blender
    evaluates the pose bones at rest)."""
    bones, pose_bones = arm.data.bones, arm.pose.bones
    nj = len(bones)
    rest = _matrices(bones, "matrix_local", nj)
    pose = _matrices(pose_bones, "matrix", nj)
    names = [b.name for b in bones]
    pose_names = [b.name for b in pose_bones]
    if pose_names != names:  # joint j is bone j of arm.data.bones
        at = {n: i for i, n in enumerate(pose_names)}
        pose = pose[[at[n] for n in names]]
    a = matrix_np(arm.matrix_world)
    return a @ pose @ np.linalg.inv(rest) @ np.linalg.inv(a)


def _proper_rotations(m: np.ndarray) -> np.ndarray:
    """The nearest rotation to each of (n, 3, 3) matrices (polar decomposition); a mirroring
    part is dropped (its last axis flipped)."""
    u, _, vt = np.linalg.svd(m)
    flip = np.linalg.det(u @ vt) < 0
    u[flip, :, -1] *= -1
    return u @ vt


def quaternions_xyzw(r: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) as unit quaternions x, y, z, w (w ≥ 0), each from its largest
    component (Shepperd's method: no division by a small number)."""
    n = len(r)
    q = np.empty((n, 4), dtype=F64)
    tr = r[:, 0, 0] + r[:, 1, 1] + r[:, 2, 2]
    case = np.argmax(np.stack([tr, r[:, 0, 0], r[:, 1, 1], r[:, 2, 2]], axis=1), axis=1)
    i = case == 0
    s = 2.0 * np.sqrt(1.0 + tr[i])
    q[i] = np.stack([(r[i, 2, 1] - r[i, 1, 2]) / s, (r[i, 0, 2] - r[i, 2, 0]) / s,
                     (r[i, 1, 0] - r[i, 0, 1]) / s, 0.25 * s], axis=1)
    i = case == 1
    s = 2.0 * np.sqrt(1.0 + r[i, 0, 0] - r[i, 1, 1] - r[i, 2, 2])
    q[i] = np.stack([0.25 * s, (r[i, 0, 1] + r[i, 1, 0]) / s, (r[i, 0, 2] + r[i, 2, 0]) / s,
                     (r[i, 2, 1] - r[i, 1, 2]) / s], axis=1)
    i = case == 2
    s = 2.0 * np.sqrt(1.0 + r[i, 1, 1] - r[i, 0, 0] - r[i, 2, 2])
    q[i] = np.stack([(r[i, 0, 1] + r[i, 1, 0]) / s, 0.25 * s, (r[i, 1, 2] + r[i, 2, 1]) / s,
                     (r[i, 0, 2] - r[i, 2, 0]) / s], axis=1)
    i = case == 3
    s = 2.0 * np.sqrt(1.0 + r[i, 2, 2] - r[i, 0, 0] - r[i, 1, 1])
    q[i] = np.stack([(r[i, 0, 2] + r[i, 2, 0]) / s, (r[i, 1, 2] + r[i, 2, 1]) / s, 0.25 * s,
                     (r[i, 1, 0] - r[i, 0, 1]) / s], axis=1)
    q[q[:, 3] < 0] *= -1.0
    return q / np.linalg.norm(q, axis=1, keepdims=True)


class PoseMismatch(Exception):
    """The Blender pose holds something the rig's pose model (rotations about the joints plus
    root motion) cannot represent."""


def cagerig_pose(
    transforms: np.ndarray, rest_heads: np.ndarray, parents: np.ndarray, tolerance: float
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Blender's skinning transforms as cagerig's pose: local rotations (J, 4) xyzw in world
    axes (G_j = G_parent·L_j) and root motion (J, 3). Returns also what does not fit the model
    (scale, a non-root bone moved off its parent), as messages."""
    nj = len(transforms)
    lin = transforms[:, :3, :3]
    u, s, vt = np.linalg.svd(lin)
    g = u @ vt  # each joint's world rotation (polar part)
    problems = [
        f"joint {j} is scaled in the pose (×{s[j].min():.4g}…{s[j].max():.4g})"
        for j in np.flatnonzero(np.abs(s - 1.0).max(axis=1) > 1e-4)
    ]
    parents = np.asarray(parents)
    child = np.flatnonzero(parents >= 0)
    root = np.flatnonzero(parents < 0)
    rel = g.copy()
    rel[child] = np.swapaxes(g[parents[child]], 1, 2) @ g[child]
    locals_q = quaternions_xyzw(_proper_rotations(rel))
    heads = np.asarray(rest_heads, dtype=F64)
    own = np.einsum("jab,jb->ja", lin, heads) + transforms[:, :3, 3]
    motion = np.zeros((nj, 3), dtype=F64)
    motion[root] = own[root] - heads[root]
    via_parent = np.einsum("jab,jb->ja", lin[parents[child]], heads[child]) + transforms[parents[child], :3, 3]
    off = child[np.linalg.norm(own[child] - via_parent, axis=1) > tolerance]
    problems += [f"joint {j} is moved off its parent in the pose" for j in off]
    return locals_q, motion, problems
