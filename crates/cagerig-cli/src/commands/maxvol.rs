//! `cagerig maxvol`: the MaxVol rows of Φ (the rows CageUp and CageRev fit) and log|det|.

use std::path::PathBuf;
use std::time::Instant;

use cagerig::coords::maxvol;
use serde::Serialize;

use crate::rig_source::{RigArgs, load_rig};

#[derive(Serialize)]
struct MaxvolReport {
    rows: Vec<usize>,
    log_abs_det: f64,
    milliseconds: f64,
    shipped: Option<ShippedMaxvol>,
}

#[derive(Serialize)]
struct ShippedMaxvol {
    path: PathBuf,
    log_abs_det: f64,
}

/// `cagerig maxvol`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub rig: RigArgs,
    /// Output `.maxvol` file.
    #[arg(long)]
    pub out: PathBuf,
    /// Machine-readable output (errors too).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (rig, out, json) = (&args.rig, args.out.as_path(), args.json);
    let loaded = load_rig(rig, !json, true)?;
    for w in &loaded.warnings {
        crate::errors::report_warning(w);
    }
    let phi = match &loaded.parts.cage_coords {
        Some(phi) => phi.clone(),
        None => crate::rig_source::compute_coords_with_progress(&loaded.parts, !json)?,
    };
    let t = Instant::now();
    let selection = maxvol::select_maxvol_rows(&phi)?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    cagerig::io::maxvol::write_maxvol(out, &selection.rows)?;
    let shipped = match (&loaded.parts.maxvol_rows, &loaded.maxvol_path) {
        (Some(rows), Some(path)) => Some(ShippedMaxvol {
            path: path.clone(),
            log_abs_det: maxvol::log_abs_det_of_rows(&phi, rows)?,
        }),
        _ => None,
    };
    let report = MaxvolReport {
        rows: selection.rows,
        log_abs_det: selection.log_abs_det,
        milliseconds: ms,
        shipped,
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "MaxVol: {} rows, log|det| = {:.6} ({ms:.1} ms), written to {}",
            report.rows.len(),
            report.log_abs_det,
            out.display()
        );
        if let Some(s) = &report.shipped {
            println!(
                "shipped selection {}: log|det| = {:.6}",
                s.path.display(),
                s.log_abs_det
            );
        }
    }
    Ok(())
}
