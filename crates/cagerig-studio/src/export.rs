//! File ▸ Export: the rest and current skin and cage as OBJ, the joints as JSON, the keys as the
//! paper tool's animation files, the rig as the paper tool's file set (`rig.obj`, `rig.skt`,
//! `rig.skw`, `rig_cage.obj`: `cagerig edit rig.obj` opens it) and as glTF 2.0 (`.glb`, with
//! its skin). Every file is replaced atomically; nothing non-finite is written. A mesh with no
//! skeleton bound yet exports no skeleton, weights or glTF.

use std::path::{Path, PathBuf};

use cagerig::io::text::FloatFormat;
use serde::Serialize;
use thiserror::Error;

use crate::document::Document;

#[derive(Debug, Error)]
pub enum ExportError {
    #[error("{path}: cannot create the folder: {message}", path = path.display())]
    Folder { path: PathBuf, message: String },
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

/// Writes every export of `doc` into `dir`; returns the files written.
pub fn export_all(doc: &Document, dir: &Path) -> Result<Vec<PathBuf>, ExportError> {
    std::fs::create_dir_all(dir).map_err(|e| ExportError::Folder {
        path: dir.to_path_buf(),
        message: e.to_string(),
    })?;
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
    cagerig::io::skw::write_skw(&skw, s.skin_weights(), FloatFormat::RoundTrip)?;
    let rig_cage = dir.join("rig_cage.obj");
    cagerig::io::write_obj(&rig_cage, s.rest_cage(), s.cage_triangles())?;
    written.extend([rig_mesh, skt, skw, rig_cage]);
    let glb = dir.join("rig.glb");
    cagerig_formats::export_character(s, &glb, "cagerig")?;
    written.push(glb);
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig_open::{RigSource, open_rig};

    #[test]
    fn export_writes_every_file_and_the_objs_read_back() {
        let source = RigSource::Builtin {
            name: "bar".into(),
            resolution: Some(6),
        };
        let mut doc = Document::new(source.clone(), open_rig(&source).unwrap().session);
        doc.execute(&crate::document::Command::SetKey {
            track: crate::keys::Track::Cage,
            time: 0.0,
        })
        .unwrap();
        let dir =
            std::env::temp_dir().join(format!("cagerig-studio-export-{}", std::process::id()));
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
}
