//! `cagerig coords`: mean value coordinates Φ of the mesh w.r.t. the cage, in the paper tool's
//! cage-weights format.

use std::path::PathBuf;
use std::time::Instant;

use crate::rig_source::{RigArgs, load_rig};

/// `cagerig coords`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub rig: RigArgs,
    /// Output file (`<cageVertex> <meshVertex> <weight>` lines).
    #[arg(long)]
    pub out: PathBuf,
    /// Write 6 fixed decimals like the paper tool instead of round-trip floats.
    #[arg(long)]
    pub fixed6: bool,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (rig, out, fixed6) = (&args.rig, args.out.as_path(), args.fixed6);
    let mut loaded = load_rig(rig, true, false)?;
    for w in &loaded.warnings {
        crate::errors::report_warning(w);
    }
    let t = Instant::now();
    let phi = crate::rig_source::compute_coords_with_progress(&loaded.parts, true)?;
    let elapsed = t.elapsed();
    let format = if fixed6 {
        cagerig::io::text::FloatFormat::TOOL
    } else {
        cagerig::io::text::FloatFormat::RoundTrip
    };
    cagerig::io::cage_weights::write_cage_weights(out, &phi, format)?;
    loaded.parts.cage_coords = Some(phi);
    println!(
        "mean value coordinates: {} vertices × {} cage vertices in {:.1} ms, written to {}",
        loaded.parts.mesh.num_vertices(),
        loaded.parts.cage.num_vertices(),
        elapsed.as_secs_f64() * 1e3,
        out.display()
    );
    Ok(())
}
