//! File ▸ Export: the rest and current skin and cage as OBJ, the joints as JSON, the keys as the
//! paper tool's animation files, the rig as the paper tool's file set (`rig.obj`, `rig.skt`,
//! `rig.skw`, `rig_cage.obj`: `cagerig edit rig.obj` opens it) and as glTF 2.0 (`.glb`, with
//! its skin; under DQS, CoR or the blended method with the skin baked in, so that a viewer
//! shows what the editor shows). Nothing non-finite is written. A mesh with no skeleton bound yet exports no
//! skeleton, weights or glTF.
//!
//! The folder the user picks is the export: it appears complete or not at all (the library's
//! [`StagedDir`]: the files are written into a staging folder beside it, which is swapped in at
//! the end). A new or empty folder is filled; an earlier export (its `.cagerig-output` manifest
//! lists every file in it) is replaced as a whole, so no file of an older export lingers; a
//! folder holding anything else — the user's own files — is refused and left untouched.

use std::path::{Path, PathBuf};

use cagerig::io::staged_dir::{FolderNaming, StagedDir, StagedDirError};
use cagerig::io::text::FloatFormat;
use serde::Serialize;
use thiserror::Error;

use crate::document::Document;

/// How export messages name the folder: the editor always replaces an earlier export.
const EXPORT_FOLDER: FolderNaming = FolderNaming {
    folder: "export folder",
    replace_option: None,
};

#[derive(Debug, Error)]
pub enum ExportError {
    #[error("{0}")]
    Folder(#[from] StagedDirError),
    #[error("{0}")]
    File(#[from] cagerig::io::ParseError),
    #[error("{0}")]
    Keys(#[from] crate::keys::KeyError),
    #[error("{0}")]
    Gltf(#[from] cagerig_formats::FormatError),
    #[error("{path}: joint {index} is not finite; nothing written for it", path = path.display())]
    NonFinite { path: PathBuf, index: usize },
}

#[derive(Serialize)]
struct JointOut<'a> {
    name: &'a str,
    parent: Option<usize>,
    rest: [f64; 3],
    posed: [f64; 3],
}

/// Writes every export of `doc` as the folder `dir` (see the module documentation); returns
/// the files written.
pub fn export_all(doc: &Document, dir: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let mut staged = StagedDir::create(dir, true, EXPORT_FOLDER)?;
    let mut written = Vec::new();
    staged.write_into(|staging| {
        written = write_exports(doc, staging)?;
        Ok::<(), ExportError>(())
    })?;
    staged.finish()?;
    Ok(written
        .iter()
        .filter_map(|path| path.file_name())
        .map(|name| dir.join(name))
        .collect())
}

/// Writes every export of `doc` into the folder `dir`; returns the files written.
fn write_exports(doc: &Document, dir: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let s = &doc.session;
    let mut written = Vec::new();
    for (name, positions, triangles) in [
        ("mesh_rest.obj", s.rest_mesh(), s.mesh_triangles()),
        ("mesh_posed.obj", s.posed_mesh(), s.mesh_triangles()),
        ("cage_rest.obj", s.rest_cage(), s.cage_triangles()),
        ("cage_posed.obj", s.posed_cage(), s.cage_triangles()),
    ] {
        let path = dir.join(name);
        cagerig::io::write_obj(&path, positions, triangles)?;
        written.push(path);
    }
    let joints_path = dir.join("joints.json");
    let joints: Vec<JointOut<'_>> = s
        .skeleton()
        .joints()
        .iter()
        .zip(s.rest_joints().zip(s.posed_joints()))
        .map(|(j, (rest, posed))| JointOut {
            name: &j.name,
            parent: j.parent,
            rest: rest.to_array(),
            posed: posed.to_array(),
        })
        .collect();
    if let Some(index) = joints
        .iter()
        .position(|j| !j.rest.iter().chain(&j.posed).all(|x| x.is_finite()))
    {
        return Err(ExportError::NonFinite {
            path: joints_path,
            index,
        });
    }
    let text = serde_json::to_string_pretty(&joints).unwrap_or_default();
    cagerig::io::write_atomically(&joints_path, |w| w.write_all(text.as_bytes()))?;
    written.push(joints_path);
    let skel = dir.join("skeleton_animation.txt");
    if doc.keys.export_skeleton_animation(&skel, s)? {
        written.push(skel);
    }
    let cage = dir.join("cage_animation.txt");
    if doc.keys.export_cage_animation(&cage, s)? {
        written.push(cage);
    }
    if !doc.rigged() {
        return Ok(written);
    }
    // The rig at its current rest pose: the skeleton where SkelUp put the joints.
    let rest_joints: Vec<glam::DVec3> = s.rest_joints().collect();
    let skeleton = s.skeleton().with_rest_positions(&rest_joints);
    let rig_mesh = dir.join("rig.obj");
    cagerig::io::write_obj(&rig_mesh, s.rest_mesh(), s.mesh_triangles())?;
    let skt = dir.join("rig.skt");
    cagerig::io::skt::write_skt(&skt, &skeleton)?;
    let skw = dir.join("rig.skw");
    cagerig::io::skw::write_skw(&skw, s.skin_weights(), &skeleton, FloatFormat::RoundTrip)?;
    let rig_cage = dir.join("rig_cage.obj");
    cagerig::io::write_obj(&rig_cage, s.rest_cage(), s.cage_triangles())?;
    written.extend([rig_mesh, skt, skw, rig_cage]);
    // Under DQS, CoR or the blended method the skin a viewer shows is baked in (one morph
    // target at default weight 1), so the file looks as the editor does; cagerig reads it back
    // without it.
    let glb = dir.join("rig.glb");
    cagerig_formats::export_character_baked(s, &glb, "cagerig")?;
    written.push(glb);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig_open::{RigSource, open_rig};

    fn bar_document() -> Document {
        let source = RigSource::Builtin {
            name: "bar".into(),
            resolution: Some(6),
        };
        Document::new(source.clone(), open_rig(&source).unwrap().session)
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn export_writes_every_file_and_the_objs_read_back() {
        let mut doc = bar_document();
        doc.execute(&crate::document::Command::SetKey {
            track: crate::keys::Track::Cage,
            time: 0.0,
        })
        .unwrap();
        let dir =
            std::env::temp_dir().join(format!("cagerig-studio-export-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let files = export_all(&doc, &dir).unwrap();
        assert_eq!(files.len(), 11, "{files:?}");
        let back = cagerig::io::read_obj(&dir.join("mesh_posed.obj")).unwrap();
        assert_eq!(back.positions, doc.session.posed_mesh());
        // The file set opens as a rig with the same skeleton and weights.
        let rig = cagerig::rig_files::load_rig_files(&dir.join("rig.obj"), None).unwrap();
        assert_eq!(rig.parts.skeleton.len(), doc.session.skeleton().len());
        assert_eq!(rig.parts.skin_weights, *doc.session.skin_weights());
        std::fs::remove_dir_all(dir).ok();
    }

    /// Under DQS the exported `rig.glb` carries the baked skin of the current pose (one morph
    /// target at default weight 1, marked as cagerig's), and reads back with the same rest skin.
    #[test]
    fn export_bakes_the_dqs_skin_into_the_gltf() {
        let mut doc = bar_document();
        doc.execute(&crate::document::Command::SetSkinning(
            cagerig::skinning::SkinningMethod::Dqs,
        ))
        .unwrap();
        doc.execute(&crate::document::Command::RotateJoint {
            joint: 1,
            axis: glam::DVec3::X,
            angle: 0.8,
        })
        .unwrap();
        let dir = std::env::temp_dir().join(format!(
            "cagerig-studio-export-baked-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        export_all(&doc, &dir).unwrap();
        let glb = dir.join("rig.glb");
        // The GLB's JSON chunk: 12-byte header, chunk length, chunk type, JSON.
        let bytes = std::fs::read(&glb).unwrap();
        let length = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + length]).unwrap();
        let mesh = &json["meshes"][0];
        assert_eq!(
            mesh["primitives"][0]["targets"].as_array().unwrap().len(),
            1
        );
        assert_eq!(mesh["weights"], serde_json::json!([1.0]));
        assert_eq!(mesh["extras"]["cagerig_baked_skinning"]["method"], "dqs");
        let back = cagerig_formats::import_character(&glb, &Default::default()).unwrap();
        let (lo, hi) = cagerig::mesh::bounding_box(doc.session.rest_mesh());
        let off = cagerig::mesh::max_distance(&back.mesh.positions, doc.session.rest_mesh());
        assert!(off <= 1e-6 * (hi - lo).length(), "{off:e}");
        std::fs::remove_dir_all(dir).ok();
    }

    /// The export folder is complete or absent: the user's own folder is refused untouched, an
    /// earlier export is replaced as a whole, and what a killed export left is cleaned up.
    #[test]
    fn export_replaces_only_an_earlier_export_and_leaves_no_staging() {
        let doc = bar_document();
        let root = std::env::temp_dir().join(format!(
            "cagerig-studio-export-staged-{}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&root);
        let mine = root.join("mine");
        std::fs::create_dir_all(&mine).unwrap();
        std::fs::write(mine.join("notes.txt"), b"mine").unwrap();
        let e = export_all(&doc, &mine).unwrap_err().to_string();
        assert!(
            e.contains("export folder") && e.contains("notes.txt") && e.contains("new folder"),
            "{e}"
        );
        assert_eq!(entries(&mine), ["notes.txt"]);

        let out = root.join("export");
        let first = export_all(&doc, &out).unwrap();
        assert!(
            first
                .iter()
                .all(|p| p.parent() == Some(out.as_path()) && p.is_file())
        );
        // An earlier export that listed a file this one does not write: replaced wholly.
        std::fs::write(out.join("old_pose.obj"), b"v 0 0 0\n").unwrap();
        let manifest = out.join(cagerig::io::staged_dir::MANIFEST_FILE);
        let mut listed = std::fs::read_to_string(&manifest).unwrap();
        listed.push_str("old_pose.obj\n");
        std::fs::write(&manifest, listed).unwrap();
        // A staging folder of an export killed in a process that no longer runs.
        let abandoned = root.join(".export.partial-4294967");
        std::fs::create_dir_all(&abandoned).unwrap();
        std::fs::write(abandoned.join("mesh_rest.obj"), b"half").unwrap();
        let second = export_all(&doc, &out).unwrap();
        assert_eq!(second, first);
        assert!(!out.join("old_pose.obj").exists());
        assert!(!abandoned.exists() || !Path::new("/proc/self").exists());
        assert_eq!(
            entries(&root)
                .into_iter()
                .filter(|n| n.contains(".partial-") && !n.ends_with("4294967"))
                .count(),
            0
        );
        // A file the user added after the export makes the folder theirs.
        std::fs::write(out.join("notes.txt"), b"mine").unwrap();
        assert!(export_all(&doc, &out).is_err());
        assert!(out.join("notes.txt").is_file() && out.join("rig.glb").is_file());
        std::fs::remove_dir_all(&root).ok();
    }

    /// A skeleton built and bound in the studio on a mesh that had none is what the export
    /// writes: the file set and the glTF carry its joints and weights.
    #[test]
    fn a_skeleton_bound_in_the_studio_is_exported() {
        use crate::binding::BindWeights;
        use crate::document::{Command, SkeletonEdit};
        let dir = std::env::temp_dir().join(format!(
            "cagerig-studio-export-bound-{}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let bar = bar_document().session;
        let mesh = dir.join("bar.obj");
        cagerig::io::write_obj(&mesh, bar.rest_mesh(), bar.mesh_triangles()).unwrap();
        let source = RigSource::File {
            path: mesh,
            cage: None,
            skin: None,
            auto_cage: Some(40),
        };
        let opened = open_rig(&source).unwrap();
        let mut doc = Document::new(source, opened.session).with_rigged(opened.rigged);
        let (lo, hi) = cagerig::mesh::bounding_box(doc.session.rest_mesh());
        let axis = (hi - lo).max_position();
        for k in 0..3usize {
            let mut position = 0.5 * (lo + hi);
            position[axis] = lo[axis] + (0.15 + 0.35 * k as f64) * (hi[axis] - lo[axis]);
            doc.execute(&Command::EditSkeleton(SkeletonEdit::Add {
                position,
                parent: k.checked_sub(1),
                mirror: None,
            }))
            .unwrap();
        }
        doc.bind_blocking(BindWeights::Automatic(
            cagerig::auto_weights::AutoWeightsOptions {
                resolution: 48,
                ..Default::default()
            },
        ))
        .unwrap();
        let out = dir.join("export");
        export_all(&doc, &out).unwrap();
        let rig = cagerig::rig_files::load_rig_files(&out.join("rig.obj"), None).unwrap();
        assert_eq!(rig.parts.skeleton.len(), 3);
        let glb =
            cagerig_formats::import_character(&out.join("rig.glb"), &Default::default()).unwrap();
        assert_eq!(glb.skeleton.len(), 3);
        assert_eq!(glb.skin_weights.num_vertices(), doc.session.num_vertices());
        std::fs::remove_dir_all(dir).ok();
    }
}
