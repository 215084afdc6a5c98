//! `cagerig info`: counts, discovered files, validation warnings and the cage's checks of a rig.

use serde::Serialize;

use crate::rig_source::{FileUse, RigArgs, load_rig};

#[derive(Serialize)]
struct InfoReport {
    rig: String,
    vertices: usize,
    triangles: usize,
    joints: usize,
    cage_vertices: usize,
    cage_triangles: usize,
    max_influences: usize,
    files: Vec<FileUse>,
    warnings: Vec<String>,
    /// The cage validator's checks and figures for this mesh (margin required: none).
    cage_checks: Option<cagerig::cage_gen::CageReport>,
}

/// `cagerig info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub rig: RigArgs,
    /// Machine-readable output (errors too).
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (rig, json) = (&args.rig, args.json);
    if let Some(m) = rig
        .mesh
        .as_deref()
        .filter(|m| crate::interchange::is_interchange(m))
    {
        return crate::interchange::info(m, rig.skin.as_deref(), json);
    }
    let loaded = load_rig(rig, !json, false)?;
    let p = &loaded.parts;
    let mut warnings: Vec<String> = loaded.warnings.iter().map(|w| w.to_string()).collect();
    let cage_check = cagerig::cage::validate_cage(p.cage.clone());
    match &cage_check {
        Ok((_, w)) => warnings.extend(w.iter().map(|w| w.to_string())),
        Err(e) => warnings.push(format!("the cage is unusable: {e}")),
    }
    let report = InfoReport {
        rig: loaded.name.clone(),
        vertices: p.mesh.num_vertices(),
        triangles: p.mesh.num_triangles(),
        joints: p.skeleton.len(),
        cage_vertices: p.cage.num_vertices(),
        cage_triangles: p.cage.num_triangles(),
        max_influences: p.skin_weights.max_influences(),
        files: loaded.files.clone(),
        warnings,
        cage_checks: cage_check
            .is_ok()
            .then(|| crate::commands::cage::validate_rig_cage(&p.cage, &p.mesh)),
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!("rig            {}", report.rig);
        println!(
            "mesh           {} vertices, {} triangles",
            report.vertices, report.triangles
        );
        println!(
            "skeleton       {} joints (at most {} influences per vertex)",
            report.joints, report.max_influences
        );
        println!(
            "cage           {} vertices, {} triangles",
            report.cage_vertices, report.cage_triangles
        );
        for f in &report.files {
            println!("file           {:<14} {}", f.role, f.path.display());
        }
        if let Some(checks) = &report.cage_checks {
            println!(
                "cage distance  min {:.3} %, mean {:.3} % of the diagonal",
                100.0 * checks.min_distance_fraction,
                100.0 * checks.mean_distance_fraction
            );
            crate::commands::cage::print_checks(checks);
        }
        if report.warnings.is_empty() {
            println!("warnings       none");
        }
        for w in &report.warnings {
            println!("warning        {w}");
        }
    }
    Ok(())
}
