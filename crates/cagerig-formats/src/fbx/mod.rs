//! FBX → [`ImportedCharacter`] through `ufbx` (a fuzzed C loader built for untrusted files).
//!
//! - Mesh: every mesh node with a skin deformer, in scene order; vertices are the mesh's control
//!   points in file order (no welding, no splitting by polygon vertex), faces triangulated by
//!   ufbx. Positions in world space at bind time: `M = geometry_to_world · v` (of the mesh's
//!   first cluster).
//! - Skeleton: the clusters' bone nodes, in order of first use; parent = nearest ancestor that
//!   is also a bone. Rest frames `B_j = geometry_to_world · geometry_to_bone_j⁻¹` (the bone's
//!   world transform at bind time), so `T_j = node_to_world_j(t) · B_j⁻¹` skins exactly like
//!   ufbx (`Σ w node_to_world · geometry_to_bone · v`).
//! - Animation stacks: FBX curves are cubic, so each stack is sampled at the scene's frame rate
//!   (keys exact at frame times, slerp/lerp between; `exact = false`).
//! - Units and axes: converted to glTF's convention — right-handed, +Y up, +Z front, metres —
//!   by ufbx's load options (`target_axes`, `target_unit_meters`; the conversion is a transform
//!   of the scene root, `world_from_file`, composed into every world transform: mesh, bind
//!   frames, animation). A left-handed file is mirrored by it, and its triangle winding is
//!   reversed so that outward faces stay outward. `info` states the file's own axes and unit
//!   and the conversion applied; a cage must be given in the converted space.

use std::path::Path;

use cagerig::animation::SkeletonTrack;
use cagerig::{Joint, Skeleton, SkinWeights, TriMesh, Warning};
use glam::{DAffine3, DMat3, DVec3};

use crate::ImportOptions;
use crate::character::{
    ImportSummary, ImportedAnimation, ImportedCharacter, PrimitiveSummary, SkinSummary,
    SpaceSummary, max_abs_diff, snap_to_similarity,
};
use crate::error::{FormatError, invalid};

mod skinning_method;
mod static_mesh;

pub use static_mesh::{import_fbx_static, import_fbx_static_bytes};

/// Loads an FBX scene converted to glTF's convention (right-handed, +Y up, metres; see the
/// module doc), with the file's own axes and unit and the conversion applied.
fn load_scene(bytes: &[u8], path: &Path) -> Result<(ufbx::SceneRoot, SpaceSummary), FormatError> {
    let opts = ufbx::LoadOpts {
        load_external_files: false,
        target_axes: ufbx::CoordinateAxes::right_handed_y_up(),
        target_unit_meters: 1.0,
        space_conversion: ufbx::SpaceConversion::TransformRoot,
        ..Default::default()
    };
    let scene = ufbx::load_memory(bytes, opts).map_err(|e| fbx_error(path, &e))?;
    let space = space_summary(&scene);
    Ok((scene, space))
}

/// The triangles of `mesh` (faces triangulated by ufbx) as indices into its control points
/// `mesh.vertices`, in face order; `source` names the mesh node in messages.
fn mesh_triangles(
    mesh: &ufbx::Mesh,
    path: &Path,
    source: &str,
) -> Result<Vec<[u32; 3]>, FormatError> {
    let nv = mesh.vertices.len();
    let mut triangles = Vec::with_capacity(mesh.num_triangles);
    let mut tri = Vec::new();
    for face in mesh.faces.iter() {
        let n = ufbx::triangulate_face_vec(&mut tri, mesh, *face) as usize;
        for t in tri[..3 * n].chunks_exact(3) {
            let v = |i: u32| mesh.vertex_indices.get(i as usize).copied();
            match (v(t[0]), v(t[1]), v(t[2])) {
                (Some(a), Some(b), Some(c))
                    if (a as usize) < nv && (b as usize) < nv && (c as usize) < nv =>
                {
                    triangles.push([a, b, c]);
                }
                _ => {
                    return Err(invalid(
                        path,
                        source,
                        "a face refers to a vertex out of range",
                    ));
                }
            }
        }
    }
    Ok(triangles)
}

fn affine(m: &ufbx::Matrix) -> DAffine3 {
    DAffine3::from_mat3_translation(
        DMat3::from_cols(
            DVec3::new(m.m00, m.m10, m.m20),
            DVec3::new(m.m01, m.m11, m.m21),
            DVec3::new(m.m02, m.m12, m.m22),
        ),
        DVec3::new(m.m03, m.m13, m.m23),
    )
}

fn fbx_error(path: &Path, e: &ufbx::Error) -> FormatError {
    FormatError::Fbx {
        path: path.to_path_buf(),
        message: format!("{:?}: {} {}", e.type_, &*e.description, e.info()),
    }
}

/// Reads an FBX file (binary or ASCII).
pub fn import_fbx(path: &Path, options: &ImportOptions) -> Result<ImportedCharacter, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    import_fbx_bytes(&bytes, path, options)
}

/// [`import_fbx`] on the bytes of a file (`path` names it in messages; nothing else is read).
pub fn import_fbx_bytes(
    bytes: &[u8],
    path: &Path,
    options: &ImportOptions,
) -> Result<ImportedCharacter, FormatError> {
    // Every skinned mesh of an FBX file is one rig: a skin choice would be silently ignored.
    if let Some(skin) = &options.skin {
        return Err(invalid(
            path,
            "skins",
            format!(
                "--skin {skin:?} chooses among a glTF file's skins; an FBX character imports \
                 every skinned mesh as one rig (leave --skin out)"
            ),
        ));
    }
    let (scene, space) = load_scene(bytes, path)?;
    let mut warnings = Vec::new();

    // Skinned mesh nodes and their bones.
    let mut bone_ids: Vec<u32> = Vec::new();
    let mut bone_nodes: Vec<&ufbx::Node> = Vec::new();
    let mut rest_frames: Vec<DAffine3> = Vec::new();
    let mut positions = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut triplets = Vec::new();
    let mut primitives = Vec::new();
    let mut worst_bind = (0.0f64, 0usize);
    for node in scene.nodes.iter() {
        let Some(mesh) = node.mesh.as_ref() else {
            continue;
        };
        let Some(skin) = mesh.skin_deformers.first() else {
            continue;
        };
        let source = format!("mesh node {:?}", &*node.element.name);
        if mesh.skin_deformers.len() > 1 {
            warnings.push(Warning::Note {
                message: format!(
                    "{source}: {} skin deformers; only the first is used",
                    mesh.skin_deformers.len()
                ),
            });
        }
        let Some(first_cluster) = skin.clusters.first() else {
            return Err(invalid(path, &source, "its skin deformer has no clusters"));
        };
        let world_from_geometry = affine(&first_cluster.geometry_to_world);
        let mut joint_of_cluster = Vec::with_capacity(skin.clusters.len());
        for (c, cluster) in skin.clusters.iter().enumerate() {
            let Some(bone) = cluster.bone_node.as_deref() else {
                return Err(invalid(
                    path,
                    &source,
                    format!("skin cluster {c} has no bone node"),
                ));
            };
            let bone_from_geometry = affine(&cluster.geometry_to_bone);
            let det = bone_from_geometry.matrix3.determinant();
            if !det.is_finite() || det.abs() < 1e-12 {
                return Err(invalid(
                    path,
                    &source,
                    format!("skin cluster {c} has a singular geometry_to_bone (det {det:e})"),
                ));
            }
            let frame = world_from_geometry * bone_from_geometry.inverse();
            let j = match bone_ids
                .iter()
                .position(|&id| id == bone.element.element_id)
            {
                Some(j) => {
                    let d = max_abs_diff(&rest_frames[j], &frame)
                        / frame
                            .to_cols_array()
                            .iter()
                            .fold(1.0f64, |a, x| a.max(x.abs()));
                    if d > worst_bind.0 {
                        worst_bind = (d, j);
                    }
                    j
                }
                None => {
                    bone_ids.push(bone.element.element_id);
                    bone_nodes.push(bone);
                    rest_frames.push(frame);
                    bone_ids.len() - 1
                }
            };
            joint_of_cluster.push(j);
        }
        let base = positions.len();
        let nv = mesh.vertices.len();
        if skin.vertices.len() != nv {
            return Err(invalid(
                path,
                &source,
                format!(
                    "skin has {} vertices for {nv} control points",
                    skin.vertices.len()
                ),
            ));
        }
        positions.extend(
            mesh.vertices
                .iter()
                .map(|p| world_from_geometry.transform_point3(DVec3::new(p.x, p.y, p.z))),
        );
        let before = triangles.len();
        triangles.extend(
            mesh_triangles(mesh, path, &source)?
                .iter()
                .map(|t| t.map(|i| i + base as u32)),
        );
        for (v, sv) in skin.vertices.iter().enumerate() {
            let begin = sv.weight_begin as usize;
            let end = begin + sv.num_weights as usize;
            let Some(ws) = skin.weights.get(begin..end) else {
                return Err(invalid(
                    path,
                    &source,
                    format!("vertex {v}: weights out of range"),
                ));
            };
            for w in ws {
                let Some(&j) = joint_of_cluster.get(w.cluster_index as usize) else {
                    return Err(invalid(
                        path,
                        &source,
                        format!("vertex {v}: unknown cluster {}", w.cluster_index),
                    ));
                };
                if w.weight != 0.0 {
                    triplets.push((base + v, j, w.weight));
                }
            }
        }
        primitives.push(PrimitiveSummary {
            source,
            first_vertex: base,
            vertices: nv,
            triangles: triangles.len() - before,
            indexed: true,
        });
    }
    if bone_nodes.is_empty() {
        return Err(FormatError::NoSkin {
            path: path.to_path_buf(),
            format: "FBX",
        });
    }
    if worst_bind.0 > 1e-4 {
        warnings.push(Warning::Note {
            message: format!("meshes disagree on the bind pose of joint {} ({:.2e} relative); the first mesh's is used", worst_bind.1, worst_bind.0),
        });
    }
    let nj = bone_nodes.len();
    let parent_of = |node: &ufbx::Node| -> Option<usize> {
        let mut k = node.parent.as_deref();
        while let Some(p) = k {
            if let Some(j) = bone_ids.iter().position(|&id| id == p.element.element_id) {
                return Some(j);
            }
            k = p.parent.as_deref();
        }
        None
    };
    let joint_parent: Vec<Option<usize>> = bone_nodes.iter().map(|n| parent_of(n)).collect();
    let mut names = std::collections::HashSet::new();
    let joints: Vec<Joint> = (0..nj)
        .map(|j| {
            let base = bone_nodes[j].element.name.to_string();
            let base = if base.is_empty() {
                format!("joint{j}")
            } else {
                base
            };
            let name = if names.insert(base.clone()) {
                base
            } else {
                format!("{base}#{j}")
            };
            Joint {
                name,
                parent: joint_parent[j],
                rest_world_from_joint: snap_to_similarity(rest_frames[j]),
            }
        })
        .collect();
    let skeleton = Skeleton::new(joints).map_err(|source| FormatError::Rig {
        path: path.to_path_buf(),
        element: "skeleton".into(),
        source,
    })?;
    let nv = positions.len();
    let (skin_weights, w) =
        SkinWeights::from_triplets(nv, nj, triplets).map_err(|source| FormatError::Rig {
            path: path.to_path_buf(),
            element: "skin cluster weights".into(),
            source,
        })?;
    warnings.extend(w);
    // A left-handed file is mirrored by the conversion: reverse the winding so that outward
    // faces stay outward in the converted space.
    let mirrored = DAffine3::from_cols_array(&space.world_from_file)
        .matrix3
        .determinant()
        < 0.0;
    if mirrored {
        for t in &mut triangles {
            t.swap(1, 2);
        }
        warnings.push(Warning::Note {
            message:
                "left-handed FBX axes: mirrored into right-handed +Y up; triangle winding reversed"
                    .into(),
        });
    }
    let mesh = TriMesh::new(positions, triangles).map_err(|source| FormatError::Rig {
        path: path.to_path_buf(),
        element: "skinned mesh".into(),
        source,
    })?;

    let node_world: Vec<DAffine3> = bone_nodes
        .iter()
        .map(|n| affine(&n.node_to_world))
        .collect();
    let node_pose: Vec<DAffine3> = (0..nj)
        .map(|j| match joint_parent[j] {
            Some(p) => node_world[p].inverse() * node_world[j],
            None => node_world[j],
        })
        .collect();

    // Animation stacks, sampled at the scene frame rate.
    let fps = if scene.settings.frames_per_second > 0.0 {
        scene.settings.frames_per_second
    } else {
        30.0
    };
    let mut animations = Vec::new();
    for stack in scene.anim_stacks.iter() {
        let name = stack.element.name.to_string();
        let (t0, t1) = (stack.time_begin, stack.time_end.max(stack.time_begin));
        let frames = ((t1 - t0) * fps).round().clamp(0.0, 1e5) as usize;
        let mut times = Vec::with_capacity(frames + 1);
        let mut keys = Vec::with_capacity(frames + 1);
        for f in 0..=frames {
            let t = t0 + f as f64 / fps;
            let evaluated =
                ufbx::evaluate_scene(&scene, &stack.anim, t, ufbx::EvaluateOpts::default())
                    .map_err(|e| fbx_error(path, &e))?;
            let world: Vec<DAffine3> = bone_ids
                .iter()
                .map(|&id| {
                    evaluated
                        .nodes
                        .iter()
                        .find(|n| n.element.element_id == id)
                        .map(|n| affine(&n.node_to_world))
                        .unwrap_or(DAffine3::IDENTITY)
                })
                .collect();
            let key: Vec<DAffine3> = (0..nj)
                .map(|j| match joint_parent[j] {
                    Some(p) => world[p].inverse() * world[j],
                    None => world[j],
                })
                .collect();
            times.push(t);
            keys.push(key);
        }
        let track = SkeletonTrack::new(times, keys)
            .map_err(|e| invalid(path, format!("animation stack {name:?}"), e.to_string()))?;
        animations.push(ImportedAnimation {
            name,
            duration: t1,
            track,
            exact: false,
            morph_weights: None,
        });
    }
    if !scene.anim_stacks.is_empty() {
        warnings.push(Warning::Note {
            message: format!("FBX animation stacks sampled at {fps} frames/s"),
        });
    }
    let (file_method, dq_blend_weights) = skinning_method::file_skinning(&scene, path, nv)?;
    let mut character = ImportedCharacter {
        mesh,
        skeleton,
        skin_weights,
        cage: None,
        animations,
        morph_targets: Default::default(),
        node_pose,
        summary: ImportSummary {
            format: "FBX".into(),
            primitives,
            skins: vec![SkinSummary {
                index: 0,
                name: None,
                joints: nj,
            }],
            chosen_skin: 0,
            space,
            ..Default::default()
        },
        skinning: file_method,
        dq_blend_weights,
        warnings,
    };
    character.fill_influence_summary();
    Ok(character)
}

fn axis_name(axis: ufbx::CoordinateAxis) -> &'static str {
    match axis {
        ufbx::CoordinateAxis::PositiveX => "+X",
        ufbx::CoordinateAxis::NegativeX => "-X",
        ufbx::CoordinateAxis::PositiveY => "+Y",
        ufbx::CoordinateAxis::NegativeY => "-Y",
        ufbx::CoordinateAxis::PositiveZ => "+Z",
        ufbx::CoordinateAxis::NegativeZ => "-Z",
        ufbx::CoordinateAxis::Unknown => "unknown",
    }
}

/// The file's own axes and unit (ufbx keeps them in `settings` after conversion) and the
/// conversion ufbx applied at the scene root.
fn space_summary(scene: &ufbx::Scene) -> SpaceSummary {
    let axes = &scene.settings.axes;
    let world_from_file = affine(&scene.root_node.node_to_world);
    SpaceSummary {
        file_right: axis_name(axes.right).into(),
        file_up: axis_name(axes.up).into(),
        file_front: axis_name(axes.front).into(),
        file_unit_meters: scene.settings.unit_meters,
        converted: true,
        world_from_file: world_from_file.to_cols_array(),
    }
}
