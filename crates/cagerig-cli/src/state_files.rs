//! The files written for one rig state: `{prefix}_mesh_rest.obj`, `_mesh_posed.obj`,
//! `_cage_rest.obj`, `_cage_posed.obj` (round-trip floats) and `_joints.json`. Every writer
//! refuses non-finite numbers, so no command writes one.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use cagerig::io::obj::write_obj_to;
use cagerig::io::text::FloatFormat;
use cagerig::session::RigSession;
use glam::DVec3;
use serde::Serialize;

use crate::output_dir::StagedDir;

/// Where the files of a state go.
pub trait StateSink {
    fn put(
        &mut self,
        name: &str,
        write: &dyn Fn(&mut dyn Write) -> std::io::Result<()>,
    ) -> anyhow::Result<()>;
}

impl StateSink for StagedDir {
    fn put(
        &mut self,
        name: &str,
        write: &dyn Fn(&mut dyn Write) -> std::io::Result<()>,
    ) -> anyhow::Result<()> {
        self.write(name, write)
    }
}

#[derive(Serialize)]
struct JointState {
    name: String,
    parent: Option<usize>,
    rest: [f64; 3],
    posed: [f64; 3],
}

/// Writes the five files of the session's current state into `sink`.
pub fn write_state(sink: &mut dyn StateSink, prefix: &str, s: &RigSession) -> anyhow::Result<()> {
    type Obj<'a> = (&'a str, &'a [DVec3], &'a [[u32; 3]]);
    let objs: [Obj<'_>; 4] = [
        ("mesh_rest", s.rest_mesh(), s.mesh_triangles()),
        ("mesh_posed", s.posed_mesh(), s.mesh_triangles()),
        ("cage_rest", s.rest_cage(), s.cage_triangles()),
        ("cage_posed", s.posed_cage(), s.cage_triangles()),
    ];
    for (what, positions, triangles) in objs {
        sink.put(&format!("{prefix}_{what}.obj"), &|w| {
            write_obj_to(w, positions, triangles, FloatFormat::RoundTrip)
        })?;
    }
    let joints: Vec<JointState> = s
        .skeleton()
        .joints()
        .iter()
        .zip(s.rest_joints().zip(s.posed_joints()))
        .map(|(j, (rest, posed))| JointState {
            name: j.name.clone(),
            parent: j.parent,
            rest: rest.to_array(),
            posed: posed.to_array(),
        })
        .collect();
    if let Some((k, _)) = joints
        .iter()
        .enumerate()
        .find(|(_, j)| !j.rest.iter().chain(&j.posed).all(|x| x.is_finite()))
    {
        anyhow::bail!("refusing to write {prefix}_joints.json: joint {k} is not finite");
    }
    let bytes = serde_json::to_vec_pretty(&joints)?;
    sink.put(&format!("{prefix}_joints.json"), &|w| w.write_all(&bytes))
}

/// Files of a few states kept in memory and written at the end (`demo`).
pub struct StateFiles {
    files: Vec<(PathBuf, Vec<u8>)>,
}

impl StateSink for StateFiles {
    fn put(
        &mut self,
        name: &str,
        write: &dyn Fn(&mut dyn Write) -> std::io::Result<()>,
    ) -> anyhow::Result<()> {
        let mut bytes = Vec::new();
        write(&mut bytes).with_context(|| format!("writing {name}"))?;
        self.files.push((PathBuf::from(name), bytes));
        Ok(())
    }
}

impl StateFiles {
    pub fn new() -> Self {
        Self { files: Vec::new() }
    }

    /// Adds the files of the session's current state (see [`write_state`]).
    pub fn add_state(&mut self, prefix: &str, s: &RigSession) -> anyhow::Result<()> {
        write_state(self, prefix, s)
    }

    /// Writes every file into `dir` (created if needed), each through a temporary file.
    pub fn write_all(&self, dir: &Path) -> anyhow::Result<usize> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("creating output directory {}", dir.display()))?;
        for (name, bytes) in &self.files {
            let path = dir.join(name);
            cagerig::io::atomic::write_atomically(&path, |w| w.write_all(bytes))
                .with_context(|| format!("writing {}", path.display()))?;
        }
        Ok(self.files.len())
    }
}
