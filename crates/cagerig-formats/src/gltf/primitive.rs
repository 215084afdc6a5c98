//! One skinned primitive of a glTF mesh into the merged rest skin: its triangles (any mode,
//! indexed or not), positions placed in world space, JOINTS_n/WEIGHTS_n as weight triplets and its
//! morph targets.

use std::path::Path;

use cagerig::Warning;
use glam::{DAffine3, DVec3};
use gltf::accessor::Dimensions;
use gltf::mesh::Mode;

use super::buffers::Buffers;
use super::import::to_vec3;
use super::morph_targets::{baked_targets, default_weights};
use crate::error::{FormatError, invalid};

/// Triangles of a primitive (local vertex indices) from its mode and optional indices.
pub(super) fn primitive_triangles(
    mode: Mode,
    indices: Option<Vec<u32>>,
    num_vertices: usize,
    path: &Path,
    source: &str,
    warnings: &mut Vec<Warning>,
) -> Result<Option<Vec<[u32; 3]>>, FormatError> {
    let idx: Vec<u32> = match indices {
        Some(i) => i,
        None => (0..num_vertices as u32).collect(),
    };
    if let Some(&bad) = idx.iter().find(|&&i| i as usize >= num_vertices) {
        return Err(invalid(
            path,
            source,
            format!("index {bad} is out of range (the primitive has {num_vertices} vertices)"),
        ));
    }
    let tris: Vec<[u32; 3]> = match mode {
        Mode::Triangles => {
            if !idx.len().is_multiple_of(3) {
                warnings.push(Warning::Note {
                    message: format!(
                        "{source}: {} indices is not a multiple of 3; the last {} were ignored",
                        idx.len(),
                        idx.len() % 3
                    ),
                });
            }
            idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
        }
        Mode::TriangleStrip => (2..idx.len())
            .map(|k| {
                if k % 2 == 0 {
                    [idx[k - 2], idx[k - 1], idx[k]]
                } else {
                    [idx[k - 1], idx[k - 2], idx[k]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..idx.len())
            .map(|k| [idx[0], idx[k - 1], idx[k]])
            .collect(),
        other => {
            warnings.push(Warning::Note {
                message: format!(
                    "{source}: mode {other:?} is not triangles; the primitive was skipped"
                ),
            });
            return Ok(None);
        }
    };
    Ok(Some(tris))
}

/// The geometry of one primitive: local positions (bind shape, the node's default morph weights
/// applied) and triangles (local vertex indices).
pub(super) struct PrimitiveGeometry {
    /// Local positions, one per vertex of the primitive's accessors.
    pub local: Vec<DVec3>,
    /// Triangles in the file's winding, indices into `local`.
    pub triangles: Vec<[u32; 3]>,
    /// Whether the triangles come from an index buffer.
    pub indexed: bool,
}

/// How messages name a primitive: its node (index and name), mesh and primitive index.
pub(super) fn primitive_source(
    node: &gltf::Node<'_>,
    mesh: &gltf::Mesh<'_>,
    primitive: &gltf::Primitive<'_>,
) -> String {
    format!(
        "node {} {:?}, mesh {} primitive {}",
        node.index(),
        node.name().unwrap_or(""),
        mesh.index(),
        primitive.index()
    )
}

/// Reads a primitive's positions and triangles (any triangle mode; None with a note for points
/// and lines), with its morph targets at the node's default weights. When `targets_out` asks,
/// every target's displacements are kept, mapped by `world_from_bind` (a linear map of
/// displacements).
#[expect(clippy::too_many_arguments)]
pub(super) fn read_geometry(
    primitive: &gltf::Primitive,
    node: &gltf::Node,
    buffers: &Buffers,
    path: &Path,
    source: &str,
    world_from_bind: &DAffine3,
    mut targets_out: Option<&mut Vec<Vec<DVec3>>>,
    warnings: &mut Vec<Warning>,
) -> Result<Option<PrimitiveGeometry>, FormatError> {
    if let Some(out) = targets_out.as_deref_mut() {
        out.clear();
    }
    let position_accessor = primitive
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| invalid(path, source, "has no POSITION attribute"))?;
    let mut local = to_vec3(&buffers.read(&position_accessor, "POSITION", &[Dimensions::Vec3])?);
    let nv = local.len();
    let indices = match primitive.indices() {
        Some(acc) => Some(buffers.read_indices(&acc, "indices", &[Dimensions::Scalar])?),
        None => None,
    };
    let indexed = indices.is_some();
    let Some(tris) = primitive_triangles(primitive.mode(), indices, nv, path, source, warnings)?
    else {
        return Ok(None);
    };
    // Morph targets at their default weights (node weights override mesh weights), before
    // skinning; all of them kept (world-space displacements) when `targets_out` asks.
    let targets: Vec<_> = primitive.morph_targets().collect();
    if !targets.is_empty() {
        let weights = default_weights(node);
        // Targets cagerig's export baked hold a skinning result, not a shape: never part of the
        // bind shape (a one-state bake gives them default weight 1).
        let baked_from = node
            .mesh()
            .and_then(|m| baked_targets(&m))
            .map_or(usize::MAX, |(first, _)| first);
        let mut applied = 0;
        for (k, target) in targets.iter().enumerate() {
            let w = if k < baked_from {
                weights.get(k).copied().unwrap_or(0.0)
            } else {
                0.0
            };
            if w == 0.0 && targets_out.is_none() {
                continue;
            }
            if let Some(out) = targets_out.as_deref_mut() {
                out.resize(k + 1, Vec::new());
            }
            if let Some(acc) = target.positions() {
                let d =
                    to_vec3(&buffers.read(&acc, "morph target POSITION", &[Dimensions::Vec3])?);
                if d.len() != nv {
                    return Err(invalid(
                        path,
                        source,
                        format!(
                            "morph target {k} has {} positions for {nv} vertices",
                            d.len()
                        ),
                    ));
                }
                if w != 0.0 {
                    for (p, dp) in local.iter_mut().zip(&d) {
                        *p += *dp * w;
                    }
                    applied += 1;
                }
                if let Some(out) = targets_out.as_deref_mut() {
                    out[k] = d
                        .iter()
                        .map(|dp| world_from_bind.transform_vector3(*dp))
                        .collect();
                }
            }
        }
        if targets_out.is_some() {
            if applied > 0 {
                warnings.push(Warning::Note {
                    message: format!(
                        "{source}: {applied} of {} morph targets applied at their non-zero default weight to the bind shape; the animations' morph weights are played relative to it",
                        targets.len()
                    ),
                });
            }
        } else {
            warnings.push(Warning::Note {
                message: format!(
                    "{source}: {} morph targets; {applied} with non-zero default weight applied to the bind shape before skinning (morph animation is not imported)",
                    targets.len()
                ),
            });
        }
    }
    Ok(Some(PrimitiveGeometry {
        local,
        triangles: tris,
        indexed,
    }))
}

/// Appends one skinned primitive to the merged mesh. Returns (vertices, triangles, indexed),
/// or None when the primitive was skipped (with a warning).
#[expect(clippy::too_many_arguments)]
pub(super) fn read_primitive(
    primitive: &gltf::Primitive,
    node: &gltf::Node,
    buffers: &Buffers,
    path: &Path,
    source: &str,
    num_joints: usize,
    world_from_bind: &DAffine3,
    positions: &mut Vec<DVec3>,
    triangles: &mut Vec<[u32; 3]>,
    triplets: &mut Vec<(usize, usize, f64)>,
    targets_out: Option<&mut Vec<Vec<DVec3>>>,
    warnings: &mut Vec<Warning>,
) -> Result<Option<(usize, usize, bool)>, FormatError> {
    let Some(PrimitiveGeometry {
        local,
        triangles: tris,
        indexed,
    }) = read_geometry(
        primitive,
        node,
        buffers,
        path,
        source,
        world_from_bind,
        targets_out,
        warnings,
    )?
    else {
        return Ok(None);
    };
    let nv = local.len();
    // Every JOINTS_n / WEIGHTS_n set.
    let base = positions.len();
    let mut set = 0;
    loop {
        let joints = primitive.get(&gltf::Semantic::Joints(set));
        let weights = primitive.get(&gltf::Semantic::Weights(set));
        let (joints, weights) = match (joints, weights) {
            (None, None) => break,
            (Some(j), Some(w)) => (j, w),
            _ => {
                return Err(invalid(
                    path,
                    source,
                    format!("has only one of JOINTS_{set} and WEIGHTS_{set}"),
                ));
            }
        };
        let j = buffers.read_indices(&joints, &format!("JOINTS_{set}"), &[Dimensions::Vec4])?;
        let w = buffers.read(&weights, &format!("WEIGHTS_{set}"), &[Dimensions::Vec4])?;
        if j.len() != 4 * nv || w.len() != 4 * nv {
            return Err(invalid(
                path,
                source,
                format!(
                    "JOINTS_{set}/WEIGHTS_{set} have {}/{} elements for {nv} vertices",
                    j.len() / 4,
                    w.len() / 4
                ),
            ));
        }
        for (k, (&joint, &weight)) in j.iter().zip(&w).enumerate() {
            if weight == 0.0 {
                continue;
            }
            if joint as usize >= num_joints {
                return Err(invalid(
                    path,
                    source,
                    format!(
                        "JOINTS_{set} of vertex {} names joint {joint} with weight {weight}, but the skin has {num_joints} joints",
                        k / 4
                    ),
                ));
            }
            triplets.push((base + k / 4, joint as usize, weight));
        }
        set += 1;
    }
    if set == 0 {
        return Err(invalid(
            path,
            source,
            "is used with a skin but has no JOINTS_0/WEIGHTS_0",
        ));
    }
    positions.extend(local.iter().map(|p| world_from_bind.transform_point3(*p)));
    let ntri = tris.len();
    triangles.extend(tris.iter().map(|t| t.map(|i| i + base as u32)));
    Ok(Some((nv, ntri, indexed)))
}
