//! `cagerig export RIG [--script EDITS.json] --out FILE.glb`: the (edited) character as a
//! standard rigged glTF binary — the rest mesh and skeleton after cage edits as the bind shape,
//! Ω as JOINTS_n/WEIGHTS_n, the current pose as the joint nodes' transforms.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use cagerig::script::EditScript;
use cagerig::session::RigSession;
use clap::Args;

use crate::commands::SessionArgs;
use crate::rig_source::{RigArgs, load_rig};

#[derive(Debug, Clone, Args)]
pub struct ExportArgs {
    #[command(flatten)]
    pub rig: RigArgs,
    /// Edit script replayed before exporting (as for `edit`).
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Output `.glb` file (replaced atomically).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub session: SessionArgs,
}

pub fn run(args: &ExportArgs) -> anyhow::Result<()> {
    let ext = args.out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("glb") {
        bail!(
            "{}: export writes binary glTF: give an --out path ending in .glb",
            args.out.display()
        );
    }
    let script = match &args.script {
        Some(p) => {
            let text =
                std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
            Some(EditScript::parse(&text).with_context(|| format!("in {}", p.display()))?)
        }
        None => None,
    };
    let loaded = load_rig(&args.rig, true, true)?;
    let name = loaded
        .name
        .rsplit(['/', '\\'])
        .next()
        .and_then(|f| f.split('.').next())
        .unwrap_or("cagerig")
        .to_string();
    let mut options = args.session.options();
    if let Some(s) = script.as_ref().and_then(|s| s.skinning) {
        options.skinning = s;
    }
    let (mut session, warnings) =
        RigSession::new(loaded.parts, options).context("assembling the rig")?;
    for w in loaded.warnings.iter().chain(&warnings) {
        eprintln!("warning: {w}");
    }
    if let (Some(script), Some(path)) = (&script, &args.script) {
        script
            .validate(&session)
            .with_context(|| format!("in {}", path.display()))?;
        for k in 0..script.steps.len() {
            script
                .run_step(k, &mut session)
                .with_context(|| format!("in {}", path.display()))?;
        }
    }
    export(&session, &args.out, &name)
}

fn export(session: &RigSession, out: &Path, name: &str) -> anyhow::Result<()> {
    let t = std::time::Instant::now();
    cagerig_formats::gltf::export::export_glb(session, out, name)?;
    println!(
        "{} written ({} vertices, {} joints) in {:.1} ms",
        out.display(),
        session.rest_mesh().len(),
        session.skeleton().len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    Ok(())
}
