//! `cagerig subdivide`: N levels of midpoint subdivision of a rig, written as the paper tool's
//! file set (mesh, `.skt`, `.skw`, cage, Φ, MaxVol rows, CoR weights when present) and cagerig's
//! DQ blend weights when the rig has them (`<name>_dqBlendWeights.txt`). The files
//! appear in `--out` all at once, or not at all.

use std::path::PathBuf;

use anyhow::bail;
use cagerig::session::RigParts;

use crate::output_dir::StagedDir;
use crate::rig_source::{RigInputArgs, compute_coords_with_progress, load_rig_or_generate_cage};

/// `cagerig subdivide`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub input: RigInputArgs,
    /// Rounds of midpoint subdivision (each multiplies the triangles by 4).
    #[arg(long, default_value_t = 1)]
    pub levels: usize,
    /// Output folder; it appears complete, only after every file was written.
    #[arg(long)]
    pub out: PathBuf,
    /// Replace a non-empty --out that holds an earlier run's output.
    #[arg(long)]
    pub force: bool,
    /// Base name of the written files (no path separator).
    #[arg(long, default_value = "rig")]
    pub name: String,
}

pub fn run(cli: &Args) -> anyhow::Result<()> {
    let (args, levels, out, name, force) = (
        &cli.input.rig,
        cli.levels,
        cli.out.as_path(),
        cli.name.as_str(),
        cli.force,
    );
    if name.is_empty()
        || name.contains(['/', '\\'])
        || name == "."
        || name == ".."
        || name.starts_with('.')
    {
        bail!(
            "--name {name:?}: expected a plain base name for the files written into --out (no \
             path separator, not starting with a dot)"
        );
    }
    let mut staged = StagedDir::create(out, force, crate::output_dir::OUT)?;
    let loaded = load_rig_or_generate_cage(
        args,
        true,
        false,
        cli.input.auto_cage.options(),
        crate::rig_source::CageCheck::Loader,
    )?;
    for w in &loaded.warnings {
        crate::errors::report_warning(w);
    }
    let p = &loaded.parts;
    let levels_u32 = u32::try_from(levels).unwrap_or(u32::MAX);
    cagerig::memory_estimate::check_fits(
        &format!("subdivide --levels {levels}"),
        cagerig::memory_estimate::subdivided_vertices(
            p.mesh.num_vertices() as u64,
            p.mesh.num_triangles() as u64,
            levels_u32,
        ),
        p.cage.num_vertices() as u64,
    )?;
    let t = std::time::Instant::now();
    let sub = cagerig::subdivide::subdivide_rig(
        &p.mesh,
        &p.skin_weights,
        p.cor_rows.as_ref(),
        p.dq_blend_weights.as_ref(),
        levels,
    )?;
    println!(
        "subdivided {} → {} vertices, {} triangles in {:.1} ms",
        p.mesh.num_vertices(),
        sub.mesh.num_vertices(),
        sub.mesh.num_triangles(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let sub_parts = RigParts {
        cor_rows: sub.cor_rows,
        dq_blend_weights: sub.dq_blend_weights,
        ..RigParts::new(
            sub.mesh,
            p.skeleton.clone(),
            sub.skin_weights,
            p.cage.clone(),
        )
    };
    let phi = compute_coords_with_progress(&sub_parts, true)?;
    let rows = cagerig::coords::maxvol::select_maxvol_rows(&phi)?.rows;
    staged.write_into(|dir| -> anyhow::Result<()> {
        Ok(cagerig::rig_files::write_rig_files(
            dir, name, &sub_parts, &phi, &rows,
        )?)
    })?;
    let n = staged.finish()?;
    println!("{n} rig files written to {} as {name}.*", out.display());
    Ok(())
}
