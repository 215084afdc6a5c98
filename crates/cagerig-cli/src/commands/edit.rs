//! `cagerig edit`: replays a JSON edit script and writes every structure after each step.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use cagerig::script::EditScript;
use cagerig::skinning::SkinningMethod;

use crate::output_dir::{StagedDir, StateOutputArgs};
use crate::pictures::PictureMaker;
use crate::rig_source::{
    GENERATED_CAGE_FILE, RigInputArgs, report_generated_cage, write_generated_cage,
};
use crate::session_args::{SessionArgs, kind_parser, start_session};
use crate::state_files::write_state;

/// The script operations, for `edit --help`.
pub const SCRIPT_HELP: &str = "\
Script: {\"skinning\": \"lbs\"|\"dqs\"|\"cor\" (optional), \"steps\": [step, ...]}, one step = one event:
  {\"op\":\"rotate_joint\", \"joint\": NAME or INDEX, \"axis\": [x,y,z], \"degrees\": A}
      rotate a joint of the current skeleton S' about a world axis through the joint
  {\"op\":\"move_rest_cage\", \"vertices\": [i,...], \"offset\": [x,y,z]}
      move rest-cage (C) vertices; each index at most once
  {\"op\":\"move_posed_cage\", \"vertices\": [i,...], \"offset\": [x,y,z]}
      move current-cage (C') vertices (CageRev); each index at most once
  {\"op\":\"set_skinning\", \"method\": \"lbs\"|\"dqs\"|\"cor\"}
  {\"op\":\"reset_pose\"}
The whole script is checked against the rig before the first step runs. Files stepK_mesh_rest.obj,
stepK_mesh_posed.obj, stepK_cage_rest.obj, stepK_cage_posed.obj and stepK_joints.json (K = 0 as
loaded, then after each step) appear in --out only when every step succeeded; with --render also
stepK.png (rest pose left, current pose right).";

/// Reads and parses an edit script; errors name the file once.
pub fn read_script(path: &Path) -> anyhow::Result<EditScript> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading the script {}", path.display()))?;
    EditScript::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// `cagerig edit`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub input: RigInputArgs,
    /// The script: {"skinning":..., "steps":[{"op":...}, ...]} (operations: see --help).
    #[arg(long)]
    pub script: PathBuf,
    #[command(flatten)]
    pub output: StateOutputArgs,
    /// Skinning method (overrides the script's).
    #[arg(long, value_parser = kind_parser::<SkinningMethod>())]
    pub skinning: Option<SkinningMethod>,
    #[command(flatten)]
    pub session: SessionArgs,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (script_path, out) = (args.script.as_path(), args.output.out.as_path());
    let (force, render, skinning, session_args) = (
        args.output.force,
        args.output.render,
        args.skinning,
        &args.session,
    );
    let script = read_script(script_path)?;
    let mut pictures = PictureMaker::for_steps(render)?;
    let mut staged = StagedDir::create(out, force, crate::output_dir::OUT)?;
    let loaded = args.input.load_for_session()?;
    if let Some(g) = &loaded.generated_cage {
        report_generated_cage(&loaded.name, g, &out.join(GENERATED_CAGE_FILE));
        write_generated_cage(&mut staged, &g.cage)?;
    }
    let mut options = session_args.options();
    options.skinning = crate::session_args::choose_skinning(skinning, script.skinning, &loaded);
    let (mut session, warnings) = start_session(loaded, options)?;
    for w in &warnings {
        crate::errors::report_warning(w);
    }
    script
        .validate(&session)
        .map_err(|e| anyhow::anyhow!("{}: {e}", script_path.display()))?;
    write_state(&mut staged, "step0", &session)?;
    if let Some(p) = &mut pictures {
        p.caption = Some("step 0: as loaded".into());
        p.write_staged(&session, &mut staged, "step0.png")?;
    }
    for k in 0..script.steps.len() {
        let t = Instant::now();
        script
            .run_step(k, &mut session)
            .map_err(|e| crate::session_args::event_error(script_path.display(), e))?;
        eprintln!(
            "step {}: {} ({:.3} ms)",
            k + 1,
            script.steps[k],
            t.elapsed().as_secs_f64() * 1e3
        );
        write_state(&mut staged, &format!("step{}", k + 1), &session)?;
        if let Some(p) = &mut pictures {
            p.caption = Some(format!("step {}: {}", k + 1, script.steps[k].summary()));
            p.marked = crate::pictures::MarkedHandles::of_steps(&script.steps[k..=k]);
            p.write_staged(&session, &mut staged, &format!("step{}.png", k + 1))?;
        }
    }
    let n = staged.finish()?;
    println!("{n} files written to {}", out.display());
    Ok(())
}
