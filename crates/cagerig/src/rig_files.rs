//! A whole rig on disk: the mesh and its companions, discovered beside it the way the paper
//! tool does (see [`crate::io::discovery`]), read and validated into [`RigParts`]; and the reverse,
//! writing a rig as such a file set.

use std::path::{Path, PathBuf};

use crate::cage_coords::CageCoords;
use crate::cage_gen::{CageOptions, GeneratedCage};
use crate::cage_source::{CageOrigin, CageRequest, CageSourceError, choose_cage};
use crate::error::Warning;
use crate::io::discovery::discover;
use crate::io::error::ParseError;
use crate::io::text::FloatFormat;
use crate::session::RigParts;
use crate::skin_weights::SkinWeights;
use crate::weights_source::{WeightsSource, WeightsSourceError, apply_weights_source};

/// A rig read from files.
#[derive(Debug, Clone)]
pub struct RigFiles {
    /// The validated rest structures (M, S, Ω, C) and the precomputed data read.
    pub parts: RigParts,
    /// `(role, path)` of every file that was read.
    pub files: Vec<(&'static str, PathBuf)>,
    /// Validation warnings (weights renormalised, …).
    pub warnings: Vec<Warning>,
    /// The shipped MaxVol selection file, if one was found.
    pub maxvol_path: Option<PathBuf>,
    /// The cage generated because none was found ([`MissingCage::Generate`]), with its
    /// validation report and figures; `parts.cage` is this cage.
    pub generated_cage: Option<GeneratedCage>,
}

/// What [`load_rig_files_or_generate`] does when no cage is found beside the mesh (and none is
/// given).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MissingCage {
    /// Fail, naming the files looked for.
    Fail,
    /// Generate one ([`generate_cage`]); files that belong to a cage (Φ, MaxVol rows) are then
    /// not read, since they would describe another cage.
    Generate(CageOptions),
}

/// Reads `mesh` (OBJ) and its companions. The skeleton (`.skt`), the skinning weights (`.skw`)
/// and the cage are required; Φ, MaxVol rows and CoR weights are optional (computed later), and
/// so are the DQ blend weights (`<stem>_dqBlendWeights.txt`, for the blended method).
pub fn load_rig_files(mesh: &Path, cage: Option<&Path>) -> Result<RigFiles, ParseError> {
    load_rig_files_or_generate(mesh, cage, MissingCage::Fail)
}

/// [`load_rig_files`], with a choice of what happens when the rig has no cage.
pub fn load_rig_files_or_generate(
    mesh: &Path,
    cage: Option<&Path>,
    missing_cage: MissingCage,
) -> Result<RigFiles, ParseError> {
    load_rig_files_with_weights(mesh, cage, missing_cage, &WeightsSource::Character, &|_| {})
        .map_err(|e| match e {
            WeightsSourceError::Read(e) => e,
            e @ WeightsSourceError::Automatic { .. } => ParseError::Rig {
                path: mesh.to_path_buf(),
                source: crate::error::RigError::Invalid(e.to_string()),
            },
        })
}

/// [`load_rig_files_or_generate`] with the weights of `weights` ([`crate::weights_source`]):
/// unless they are the character's own, the `.skw` beside the mesh is not needed, and the
/// CoR weights beside it (derived from that `.skw`) are not read. `progress` follows the
/// automatic weights.
pub fn load_rig_files_with_weights(
    mesh: &Path,
    cage: Option<&Path>,
    missing_cage: MissingCage,
    weights: &WeightsSource,
    progress: &(dyn Fn(crate::auto_weights::Progress) + Sync),
) -> Result<RigFiles, WeightsSourceError> {
    let mut found = discover(mesh, cage);
    let missing = |what: &str, expected: String| ParseError::Io {
        path: mesh.to_path_buf(),
        kind: std::io::ErrorKind::NotFound,
        message: format!("no {what} found beside the mesh (looked for {expected})"),
    };
    let stem = mesh
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut files = Vec::new();
    let mesh_data = crate::io::obj::read_obj(mesh)?;
    let mut mesh_warnings = check_character_mesh(mesh, &mesh_data)?;
    files.push(("mesh", mesh.to_path_buf()));
    // A skeleton paired with the weights replaces the one beside the mesh (read once, here).
    let skeleton_path = match weights.paired_skeleton() {
        Some(p) => p.to_path_buf(),
        None => found
            .skeleton
            .clone()
            .ok_or_else(|| missing("skeleton", format!("{stem}.skt")))?,
    };
    let skeleton = crate::io::skt::read_skt(&skeleton_path)?;
    let skeleton_source = skeleton_path.display().to_string();
    files.push(("skeleton", skeleton_path));
    let (skin_weights, mut warnings) = if weights.replaces_character_weights() {
        // Replaced below, once the cage is known; the CoR rows beside the mesh belong to the
        // `.skw` beside it.
        found.cor_weights = None;
        let (empty, _) = SkinWeights::from_triplets(mesh_data.num_vertices(), skeleton.len(), [])
            .map_err(|source| ParseError::Rig {
            path: mesh.to_path_buf(),
            source,
        })?;
        (empty, Vec::new())
    } else {
        let weights_path = found
            .skin_weights
            .clone()
            .ok_or_else(|| missing("skinning weights", format!("{stem}.skw")))?;
        let read = crate::io::skw::read_skw_for_skeleton(
            &weights_path,
            mesh_data.num_vertices(),
            &skeleton,
            &skeleton_source,
        )?;
        files.push(("skin_weights", weights_path));
        read
    };
    warnings.append(&mut mesh_warnings);
    let request = CageRequest {
        given: found.cage.as_deref(),
        generate: match missing_cage {
            MissingCage::Fail => None,
            MissingCage::Generate(options) => Some(options),
        },
        generated: None,
    };
    let rig = crate::cage_gen::CageRig {
        skeleton: &skeleton,
        weights: Some(&skin_weights),
    };
    let chosen = choose_cage(mesh, &mesh_data, Some(rig), None, &request).map_err(|e| match e {
        CageSourceError::Read(e) => e,
        CageSourceError::Missing { .. } => missing("cage", format!("{stem}_cage.obj or --cage")),
        CageSourceError::Generate { source, .. } => ParseError::Rig {
            path: mesh.to_path_buf(),
            source: crate::error::RigError::Invalid(format!(
                "no cage found beside the mesh, and none could be generated: {source}"
            )),
        },
        CageSourceError::Unusable { reason, .. } => ParseError::Rig {
            path: mesh.to_path_buf(),
            source: crate::error::RigError::Invalid(format!(
                "no cage found beside the mesh, and no usable cage could be generated: {reason}"
            )),
        },
    })?;
    let cage_data = chosen.cage;
    let generated_cage = match chosen.origin {
        CageOrigin::Given(cage_path) => {
            files.push(("cage", cage_path));
            None
        }
        CageOrigin::Found => None,
        CageOrigin::Generated(generated) => {
            // Φ and MaxVol rows found beside the mesh belong to another cage.
            found.cage_coords = None;
            found.maxvol = None;
            Some(*generated)
        }
    };
    let nv = mesh_data.num_vertices();
    let nc = cage_data.num_vertices();
    let cage_coords = match &found.cage_coords {
        Some(p) => {
            let phi = crate::io::cage_weights::read_cage_weights(p, nv, nc)?;
            files.push(("cage_coords", p.clone()));
            Some(phi)
        }
        None => None,
    };
    let maxvol_rows = match &found.maxvol {
        Some(p) => {
            let rows = crate::io::maxvol::read_maxvol(p, nv)?;
            files.push(("maxvol", p.clone()));
            if rows.len() < nc {
                return Err(ParseError::Rig {
                    path: p.clone(),
                    source: crate::error::RigError::Invalid(format!(
                        "expected at least {nc} mesh rows (one per cage vertex), found {}: the \
                         cage could not be fitted; delete the file to have the rows computed",
                        rows.len()
                    )),
                }
                .into());
            }
            if rows.len() != nc {
                warnings.push(Warning::Note {
                    message: format!(
                        "{} selects {} rows for a {nc}-vertex cage: least-squares fit",
                        p.display(),
                        rows.len()
                    ),
                });
            }
            Some(rows)
        }
        None => None,
    };
    let cor_rows = match &found.cor_weights {
        Some(p) => {
            let rows = crate::io::cor_weights::read_cor_weights(p, nv)?;
            files.push(("cor_weights", p.clone()));
            Some(rows)
        }
        None => None,
    };
    let dq_blend_weights = match &found.dq_blend_weights {
        Some(p) => {
            let weights = crate::io::dq_blend_weights::read_dq_blend_weights(p, nv)?;
            files.push(("dq_blend_weights", p.clone()));
            Some(weights)
        }
        None => None,
    };
    let mut parts = RigParts {
        mesh: mesh_data,
        skeleton,
        skin_weights,
        cage: cage_data,
        cage_coords,
        maxvol_rows,
        cor_rows,
        joint_coords: None,
        cor_centre_coords: None,
        dq_blend_weights,
    };
    let name = mesh.display().to_string();
    // The paired skeleton is `parts.skeleton` already.
    let unpaired = match weights {
        WeightsSource::File { weights, .. } => WeightsSource::File {
            weights: weights.clone(),
            skeleton: None,
        },
        other => other.clone(),
    };
    let mut applied =
        apply_weights_source(&unpaired, &mut parts, &name, &skeleton_source, progress)?;
    warnings.append(&mut applied.warnings);
    files.append(&mut applied.files);
    Ok(RigFiles {
        parts,
        files,
        warnings,
        maxvol_path: found.maxvol,
        generated_cage,
    })
}

/// Checks the character mesh as read: it must have vertices and faces (SkelUp and CoR need the
/// faces); vertices used by no face are reported, since that is what a file cut short in its
/// face list looks like.
pub fn check_character_mesh(
    path: &Path,
    mesh: &crate::mesh::TriMesh,
) -> Result<Vec<Warning>, ParseError> {
    let invalid = |message: String| ParseError::Rig {
        path: path.to_path_buf(),
        source: crate::error::RigError::Invalid(message),
    };
    if mesh.num_vertices() == 0 {
        return Err(invalid(
            "expected a mesh, found no vertex (`v`) line".to_string(),
        ));
    }
    if mesh.num_triangles() == 0 {
        return Err(invalid(format!(
            "expected faces (`f` lines), found {} vertices and no face: skinning-based \
             skeleton updates and CoR need the surface",
            mesh.num_vertices()
        )));
    }
    let mut used = vec![false; mesh.num_vertices()];
    for t in &mesh.triangles {
        for &i in t {
            used[i as usize] = true;
        }
    }
    let unused = used.iter().filter(|u| !**u).count();
    let mut warnings = Vec::new();
    if let Some(first) = used.iter().position(|u| !*u) {
        warnings.push(Warning::Note {
            message: format!(
                "{}: {unused} of {} vertices are used by no face (first: vertex {first}); \
                 if the file was cut short, faces are missing",
                path.display(),
                mesh.num_vertices()
            ),
        });
    }
    Ok(warnings)
}

/// Writes a rig as `<name>.obj`, `.skt`, `.skw`, `<name>_cage.obj`,
/// `<name>_cage_cageWeights.txt`, `<name>_cage.maxvol` and, when present,
/// `<name>_corWeights.txt` and `<name>_dqBlendWeights.txt` into `dir` (each file replaced
/// atomically). Round-trip floats.
pub fn write_rig_files(
    dir: &Path,
    name: &str,
    parts: &RigParts,
    cage_coords: &CageCoords,
    maxvol_rows: &[usize],
) -> Result<(), ParseError> {
    let fmt = FloatFormat::RoundTrip;
    let p = |suffix: &str| dir.join(format!("{name}{suffix}"));
    crate::io::obj::write_obj(&p(".obj"), &parts.mesh.positions, &parts.mesh.triangles)?;
    crate::io::skt::write_skt(&p(".skt"), &parts.skeleton)?;
    crate::io::skw::write_skw(&p(".skw"), &parts.skin_weights, &parts.skeleton, fmt)?;
    crate::io::obj::write_obj(
        &p("_cage.obj"),
        &parts.cage.positions,
        &parts.cage.triangles,
    )?;
    crate::io::cage_weights::write_cage_weights(&p("_cage_cageWeights.txt"), cage_coords, fmt)?;
    crate::io::maxvol::write_maxvol(&p("_cage.maxvol"), maxvol_rows)?;
    if let Some(rows) = &parts.cor_rows {
        crate::io::cor_weights::write_cor_weights(&p("_corWeights.txt"), rows, fmt)?;
    }
    if let Some(weights) = &parts.dq_blend_weights {
        crate::io::dq_blend_weights::write_dq_blend_weights(
            &p("_dqBlendWeights.txt"),
            weights,
            fmt,
        )?;
    }
    Ok(())
}
