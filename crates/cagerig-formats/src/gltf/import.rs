//! glTF 2.0 → [`ImportedCharacter`]: the skinned primitives of one skin merged into the rest skin
//! M, the skin's joints as the rest skeleton S, Ω from every `JOINTS_n`/`WEIGHTS_n` set.
//!
//! Spaces. glTF skins a bind-shape vertex v as `Σ_j w_j G_j(t) IBM_j v` (G_j: world transform
//! of joint j's node at time t; the skinned mesh node's own transform is ignored, as the
//! specification requires). We place the bind shape in world space with X = the world transform
//! of the first node that uses the skin (where exporters put the bound mesh; Z-up roots written
//! as `matrix` are part of it), so that M = X v and the rest frames are `B_j = X · IBM_j⁻¹`: the
//! skinning transform `T_j = G_j(t) B_j⁻¹ = G_j(t) IBM_j X⁻¹` then gives exactly the viewer's
//! `Σ_j w_j G_j(t) IBM_j v`. When the file's nodes are in the bind pose (`G_j · IBM_j = X`) its
//! rest view is M; otherwise a warning says by how much they differ, and the nodes' transforms
//! are available as [`ImportedCharacter::node_pose`] (an exported cagerig pose, for instance).

use std::path::Path;

use cagerig::{Joint, Skeleton, SkinWeights, TriMesh, Warning};
use glam::{DAffine3, DVec3};

use super::animation::{AnimationTargets, import_animations};
use super::buffers::Buffers;
use super::cage::find_cage;
use super::morph_targets::{baked_targets, default_weights, drop_baked_targets, merge_targets};
use super::parse::parse_validated;
use super::primitive::{primitive_source, read_primitive};
use super::scene::NodeTree;
use super::shared_skins::{inverse_bind_matrices, skins_sharing_joints};
use crate::ImportOptions;
use crate::character::{
    ImportSummary, ImportedCharacter, MorphTargets, PrimitiveSummary, SkinSummary, max_abs_diff,
    snap_to_similarity,
};
use crate::error::{FormatError, invalid};

/// Relative difference between G_j(rest)·IBM_j over the joints above which the file's node rest
/// pose is reported as different from its bind pose.
const BIND_POSE_TOLERANCE: f64 = 1e-4;

/// Skins named in a warning or error that lists a file's skins (`info` lists every one).
const LISTED_SKINS: usize = 8;

/// Reads a `.gltf` or `.glb` file.
pub fn import_gltf(path: &Path, options: &ImportOptions) -> Result<ImportedCharacter, FormatError> {
    let bytes = std::fs::read(path).map_err(|e| FormatError::Io {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    import_gltf_bytes(&bytes, path, options)
}

/// Reads glTF/GLB bytes; `path` names the file in messages and locates external buffers.
pub fn import_gltf_bytes(
    bytes: &[u8],
    path: &Path,
    options: &ImportOptions,
) -> Result<ImportedCharacter, FormatError> {
    let (gltf, mut warnings) = parse_validated(bytes, path)?;
    let document = &gltf.document;
    let buffers = Buffers::load(document, gltf.blob.as_deref(), path)?;
    let tree = NodeTree::new(document, path)?;

    // ----- the skin ---------------------------------------------------------------------------
    let skins: Vec<SkinSummary> = document
        .skins()
        .map(|s| SkinSummary {
            index: s.index(),
            name: s.name().map(str::to_owned),
            joints: s.joints().count(),
        })
        .collect();
    // The first few skins (a file may have dozens: RecursiveSkeletons has 84); `info` lists all.
    let listing = || {
        let mut shown: Vec<String> = skins
            .iter()
            .take(LISTED_SKINS)
            .map(|s| {
                format!(
                    "{} {:?} ({} joints)",
                    s.index,
                    s.name.as_deref().unwrap_or(""),
                    s.joints
                )
            })
            .collect();
        if skins.len() > LISTED_SKINS {
            shown.push(format!(
                "and {} more (`cagerig info` lists every skin)",
                skins.len() - LISTED_SKINS
            ));
        }
        shown.join(", ")
    };
    let skin = match &options.skin {
        Some(sel) => document
            .skins()
            .find(|s| s.name() == Some(sel.as_str()))
            .or_else(|| {
                sel.parse::<usize>()
                    .ok()
                    .and_then(|i| document.skins().nth(i))
            })
            .ok_or_else(|| {
                invalid(
                    path,
                    "skins",
                    format!(
                        "no skin named or numbered {sel:?}; the file has: {}",
                        listing()
                    ),
                )
            })?,
        None => document.skins().next().ok_or_else(|| FormatError::NoSkin {
            path: path.to_path_buf(),
            format: "glTF",
        })?,
    };
    let skin_element = format!("skin {}", skin.index());
    let joint_nodes: Vec<usize> = skin.joints().map(|n| n.index()).collect();
    if joint_nodes.is_empty() {
        return Err(invalid(path, &skin_element, "has no joints"));
    }
    let nj = joint_nodes.len();
    let mut joint_of_node = vec![None; tree.parent.len()];
    for (j, &n) in joint_nodes.iter().enumerate() {
        if let Some(first) = joint_of_node[n] {
            return Err(invalid(
                path,
                &skin_element,
                format!("lists node {n} twice (joints {first} and {j})"),
            ));
        }
        joint_of_node[n] = Some(j);
    }
    let inverse_bind = inverse_bind_matrices(&skin, &buffers, path)?;

    // ----- skeleton -------------------------------------------------------------------------------
    let rest_locals = tree.rest_affines();
    let mut rest_globals = vec![DAffine3::IDENTITY; rest_locals.len()];
    tree.globals(&rest_locals, &mut rest_globals);
    let joint_parent: Vec<Option<usize>> = joint_nodes
        .iter()
        .map(|&n| {
            let mut k = tree.parent[n];
            while let Some(p) = k {
                if let Some(j) = joint_of_node[p] {
                    return Some(j);
                }
                k = tree.parent[p];
            }
            None
        })
        .collect();
    let j0 = (0..nj).find(|&j| joint_parent[j].is_none()).unwrap_or(0);
    let world_from_bind = document
        .nodes()
        .find(|n| n.mesh().is_some() && n.skin().map(|s| s.index()) == Some(skin.index()))
        .map_or(rest_globals[joint_nodes[j0]] * inverse_bind[j0], |n| {
            rest_globals[n.index()]
        });
    let scale = world_from_bind
        .matrix3
        .to_cols_array()
        .iter()
        .fold(1.0f64, |a, x| a.max(x.abs()));
    let mut worst = (0.0f64, 0);
    for j in 0..nj {
        let xj = rest_globals[joint_nodes[j]] * inverse_bind[j];
        let d = max_abs_diff(&xj, &world_from_bind)
            / scale.max(world_from_bind.translation.abs().max_element());
        if d > worst.0 {
            worst = (d, j);
        }
    }
    if worst.0 > BIND_POSE_TOLERANCE {
        warnings.push(Warning::Note {
            message: format!(
                "the file's node rest pose is not its bind pose (joint {} differs by {:.2e} relative); the rest skeleton is the bind pose; the nodes' transforms are kept as the file's pose",
                worst.1, worst.0
            ),
        });
    }
    let mut names = std::collections::HashSet::new();
    let mut joints = Vec::with_capacity(nj);
    for (j, &n) in joint_nodes.iter().enumerate() {
        let ibm = inverse_bind[j];
        let det = ibm.matrix3.determinant();
        if !det.is_finite() || det.abs() < 1e-12 {
            return Err(invalid(
                path,
                format!("{skin_element} inverse bind matrix {j}"),
                format!("is singular (det {det:e})"),
            ));
        }
        let base = document
            .nodes()
            .nth(n)
            .and_then(|node| node.name().map(str::to_owned))
            .unwrap_or_else(|| format!("joint{j}"));
        let mut name = base.clone();
        if !names.insert(name.clone()) {
            name = format!("{base}#node{n}");
            names.insert(name.clone());
        }
        joints.push(Joint {
            name,
            parent: joint_parent[j],
            rest_world_from_joint: snap_to_similarity(world_from_bind * ibm.inverse()),
        });
    }
    let skeleton = Skeleton::new(joints).map_err(|source| FormatError::Rig {
        path: path.to_path_buf(),
        element: skin_element.clone(),
        source,
    })?;

    // ----- other skins over the same skeleton: one rig -------------------------------------------
    let shared_skins = if options.skin.is_none() {
        skins_sharing_joints(
            document,
            &skin,
            &joint_of_node,
            &inverse_bind,
            &buffers,
            path,
        )
    } else {
        vec![(skin.index(), (0..nj).collect())]
    };
    if skins.len() > 1 && options.skin.is_none() {
        let merged: Vec<String> = shared_skins[1..]
            .iter()
            .map(|(k, _)| k.to_string())
            .collect();
        let message = if shared_skins.len() == skins.len() {
            format!(
                "the file's {} skins share one skeleton (same joints and bind pose): their meshes \
                 are imported as one rig",
                skins.len()
            )
        } else if merged.is_empty() {
            format!(
                "the file has {} skins; imported skin {} (choose with --skin NAME|INDEX, or skin= in Python): {}",
                skins.len(),
                skin.index(),
                listing()
            )
        } else {
            format!(
                "the file has {} skins; imported skin {} with skins {} (they share its skeleton) \
                 (choose another with --skin NAME|INDEX, or skin= in Python): {}",
                skins.len(),
                skin.index(),
                merged.join(", "),
                listing()
            )
        };
        warnings.push(Warning::Note { message });
    }

    // ----- morph targets animated by a weights channel ------------------------------------------
    // Kept when exactly one skinned node of this skin has targets and some animation animates
    // its weights (its default weights are applied to M either way).
    let has_targets = |node: &gltf::Node| {
        node.mesh()
            .is_some_and(|m| m.primitives().any(|p| p.morph_targets().next().is_some()))
    };
    let target_nodes: Vec<usize> = document
        .nodes()
        .filter(|n| n.skin().map(|s| s.index()) == Some(skin.index()) && has_targets(n))
        .map(|n| n.index())
        .collect();
    let morph_node = match target_nodes[..] {
        [node] => document
            .animations()
            .flat_map(|a| a.channels())
            .any(|c| {
                c.target().node().index() == node
                    && c.target().property() == gltf::animation::Property::MorphTargetWeights
            })
            .then_some(node),
        _ => None,
    };
    let mut morph_targets: Vec<Vec<DVec3>> = Vec::new();
    let mut default_morph_weights: Vec<f64> = Vec::new();
    let mut primitive_targets: Vec<Vec<DVec3>> = Vec::new();

    // ----- skinned primitives, merged ----------------------------------------------------------------
    let mut positions: Vec<DVec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut triplets: Vec<(usize, usize, f64)> = Vec::new();
    let mut primitives = Vec::new();
    for node in document.nodes() {
        let (Some(mesh), Some(node_skin)) = (node.mesh(), node.skin()) else {
            continue;
        };
        let Some((_, joint_map)) = shared_skins.iter().find(|(k, _)| *k == node_skin.index())
        else {
            continue;
        };
        for primitive in mesh.primitives() {
            let source = primitive_source(&node, &mesh, &primitive);
            let base = positions.len();
            let first_weight = triplets.len();
            let collect = morph_node == Some(node.index());
            let summary = read_primitive(
                &primitive,
                &node,
                &buffers,
                path,
                &source,
                joint_map.len(),
                &world_from_bind,
                &mut positions,
                &mut triangles,
                &mut triplets,
                collect.then_some(&mut primitive_targets),
                &mut warnings,
            )?;
            // The mesh's own skin's joint indices → the chosen skin's.
            for t in &mut triplets[first_weight..] {
                t.1 = joint_map[t.1];
            }
            if let Some((vertices, tris, indexed)) = summary {
                if collect {
                    merge_targets(&mut morph_targets, &primitive_targets, base, vertices).map_err(
                        |e| FormatError::Rig {
                            path: path.to_path_buf(),
                            element: source.clone(),
                            source: e,
                        },
                    )?;
                    default_morph_weights = default_weights(&node);
                }
                primitives.push(PrimitiveSummary {
                    source,
                    first_vertex: base,
                    vertices,
                    triangles: tris,
                    indexed,
                });
            }
        }
    }
    if positions.is_empty() {
        return Err(invalid(
            path,
            &skin_element,
            "no mesh node uses this skin with triangles",
        ));
    }
    let nv = positions.len();
    for target in &mut morph_targets {
        target.resize(nv, DVec3::ZERO);
    }
    default_morph_weights.resize(morph_targets.len(), 0.0);
    normalise_f32_rounded_rows(nv, &mut triplets);
    let (skin_weights, weight_warnings) =
        SkinWeights::from_triplets(nv, nj, triplets).map_err(|source| FormatError::Rig {
            path: path.to_path_buf(),
            element: "skinning weights (JOINTS_n/WEIGHTS_n)".into(),
            source,
        })?;
    warnings.extend(weight_warnings);
    let mesh = TriMesh::new(positions, triangles).map_err(|source| FormatError::Rig {
        path: path.to_path_buf(),
        element: "skinned mesh".into(),
        source,
    })?;
    let cage = find_cage(document, &buffers, &rest_globals, path)?;

    let (mut animations, node_pose, animation_warnings) = import_animations(
        document,
        &buffers,
        &tree,
        &AnimationTargets {
            joint_nodes: &joint_nodes,
            joint_parent: &joint_parent,
            morph: morph_node.map(|node| (node, morph_targets.len())),
        },
        options,
        path,
    )?;
    warnings.extend(animation_warnings);
    // Targets that `cagerig export --bake` wrote hold a skinning result, not a shape: left out
    // (cagerig skins with its own method).
    let baked = morph_node
        .and_then(|n| document.nodes().nth(n))
        .and_then(|n| n.mesh())
        .and_then(|m| baked_targets(&m));
    if let Some((first, method)) = baked {
        let total = morph_targets.len();
        drop_baked_targets(
            first,
            total,
            &mut morph_targets,
            &mut default_morph_weights,
            &mut animations,
        );
        warnings.push(Warning::Note {
            message: format!(
                "{} of the {total} morph targets hold a baked {method} result (cagerig export \
                 --bake): left out; cagerig skins with its own method (--skinning)",
                total.saturating_sub(first)
            ),
        });
    }

    let mut character = ImportedCharacter {
        mesh,
        skeleton,
        skin_weights,
        cage,
        animations,
        morph_targets: MorphTargets {
            displacements: morph_targets,
            default_weights: default_morph_weights,
        },
        node_pose,
        summary: ImportSummary {
            format: "glTF".into(),
            primitives,
            skins,
            chosen_skin: skin.index(),
            ..Default::default()
        },
        skinning: None,
        dq_blend_weights: None,
        warnings,
    };
    character.fill_influence_summary();
    Ok(character)
}

/// Weight rows whose sum is 1 up to the f32 rounding of the file (within
/// [`F32_ROW_SUM_TOLERANCE`]: eight f32 weights round by at most ≈ 5e-7 together) are normalised
/// here, silently; rows further from 1 are left for [`SkinWeights::from_triplets`] to
/// renormalise and report, so that the report counts rows that really do not sum to 1.
fn normalise_f32_rounded_rows(num_vertices: usize, triplets: &mut [(usize, usize, f64)]) {
    let mut sums = vec![0.0f64; num_vertices];
    for &(v, _, w) in triplets.iter() {
        sums[v] += w;
    }
    for (v, _, w) in triplets.iter_mut() {
        let sum = sums[*v];
        if sum != 1.0 && (sum - 1.0).abs() <= F32_ROW_SUM_TOLERANCE {
            *w /= sum;
        }
    }
}

/// See [`normalise_f32_rounded_rows`].
const F32_ROW_SUM_TOLERANCE: f64 = 1e-6;

pub(super) fn to_vec3(v: &[f64]) -> Vec<DVec3> {
    v.chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect()
}
