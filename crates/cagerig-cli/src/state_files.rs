//! The files written for one rig state: `{prefix}_mesh_rest.obj`, `_mesh_posed.obj`,
//! `_cage_rest.obj`, `_cage_posed.obj` (round-trip floats) and `_joints.json`. Every writer
//! refuses non-finite numbers, so no command writes one. They go into a [`StagedDir`].

use std::io::Write;

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
        Ok(self.write(name, write)?)
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
    crate::session_args::warn_if_unfitted(&format!("{prefix}_cage_posed.obj"), s);
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
