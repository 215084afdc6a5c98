//! `cagerig info`: counts, discovered files, validation warnings and the cage's checks of a rig.

use anyhow::Context;
use serde::Serialize;

use crate::rig_source::{
    AutoCageArgs, CageCheck, FileUse, LoadedRig, RigArgs, load_rig_or_generate_cage,
};

#[derive(Serialize)]
struct InfoReport {
    rig: String,
    vertices: usize,
    triangles: usize,
    joints: usize,
    cage_vertices: usize,
    cage_triangles: usize,
    /// Whether the cage was generated (`--auto-cage`) because the rig had none.
    cage_generated: bool,
    max_influences: usize,
    files: Vec<FileUse>,
    /// Things to look at: weights that were far from summing to 1, a flipped cage, ….
    warnings: Vec<String>,
    /// Harmless facts about the input (e.g. weight rows rounded when written, renormalised).
    notes: Vec<String>,
    /// The cage validator's checks and figures for this mesh (margin required: none).
    cage_checks: Option<cagerig::cage_gen::CageReport>,
    /// With `--coords green`: the Green binding of this mesh.
    #[serde(skip_serializing_if = "Option::is_none")]
    green: Option<GreenReport>,
    /// With `--bend-joints`: each joint's standard bend and the current cage's quality.
    #[serde(skip_serializing_if = "Option::is_none")]
    joint_bends: Option<BendReport>,
}

/// What a Green binding of the rig gives (`--coords green`).
#[derive(Serialize)]
struct GreenReport {
    /// Face coordinates per vertex (#F, the cage triangles).
    face_coordinates: usize,
    /// max |M − (φC + ψN)| over the vertices inside the cage, as a fraction of the cage's
    /// bounding-box diagonal.
    reproduction_error: f64,
    /// Mesh vertices outside the cage (Σφ ≠ 1), which a Green rig moves by mean value
    /// coordinates.
    outside_cage: usize,
    /// Seconds the binding took.
    binding_seconds: f64,
}

/// Binds the mesh with Green coordinates and measures the reproduction.
fn green_report(p: &cagerig::session::RigParts) -> anyhow::Result<GreenReport> {
    use cagerig::coords::green::{compute_green_coords, face_normals};
    use glam::DVec3;
    let start = std::time::Instant::now();
    let coords = compute_green_coords(&p.cage, &p.mesh.positions, None)?;
    let binding_seconds = start.elapsed().as_secs_f64();
    let mut normals = vec![DVec3::ZERO; coords.triangles.len()];
    face_normals(&p.cage.positions, &coords.triangles, &mut normals);
    let mut reproduced = vec![DVec3::ZERO; p.mesh.num_vertices()];
    coords.vertex.apply(&p.cage.positions, &mut reproduced);
    let faces: Vec<usize> = (0..normals.len()).collect();
    coords.face.apply_delta(&faces, &normals, &mut reproduced);
    let nc = p.cage.num_vertices();
    let (mut worst, mut outside) = (0.0f64, 0);
    for (i, (r, m)) in reproduced.iter().zip(&p.mesh.positions).enumerate() {
        let sum: f64 = (0..nc).map(|k| coords.vertex.get(i, k)).sum();
        if (sum - 1.0).abs() > 1e-6 {
            outside += 1;
        } else {
            worst = worst.max(r.distance(*m));
        }
    }
    let (lo, hi) = p.cage.bounding_box();
    Ok(GreenReport {
        face_coordinates: coords.triangles.len(),
        reproduction_error: worst / (hi - lo).length().max(f64::MIN_POSITIVE),
        outside_cage: outside,
        binding_seconds,
    })
}

/// `cagerig info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub rig: RigArgs,
    #[command(flatten)]
    pub auto_cage: AutoCageArgs,
    /// Machine-readable output (errors too).
    #[arg(long)]
    pub json: bool,
    /// Also bind with these cage coordinates and report it (`green`: face coordinates,
    /// reproduction error, vertices outside the cage, binding time).
    #[arg(long, value_parser = crate::session_args::kind_parser::<cagerig::CoordsKind>(), default_value = "mvc")]
    pub coords: cagerig::CoordsKind,
    /// Also bind the rig (with --coords and --cage-fit) and report how well the current cage
    /// follows the body when each joint is bent by this many degrees about the world x, y and z
    /// axes in turn, from the rest pose: spread, deviation and flipped (see docs/method.md).
    #[arg(long, value_name = "DEGREES")]
    pub bend_joints: Option<f64>,
    /// The CageUp fit for --bend-joints.
    #[arg(long, value_parser = crate::session_args::kind_parser::<cagerig::CageFitKind>(), default_value = cagerig::CageFitKind::default().name())]
    pub cage_fit: cagerig::CageFitKind,
}

/// `info --bend-joints`: the bend and each joint's worst cage quality.
#[derive(serde::Serialize)]
struct BendReport {
    degrees: f64,
    cage_fit: cagerig::CageFitKind,
    joints: Vec<cagerig::cage_quality::JointBendQuality>,
    /// The worst of each measure over every joint.
    worst: Option<cagerig::cage_quality::CageQuality>,
}

/// Binds `loaded` with `coords` and `cage_fit` and bends each joint by `degrees`.
fn bend_report(
    loaded: &crate::rig_source::LoadedRig,
    coords: cagerig::CoordsKind,
    cage_fit: cagerig::CageFitKind,
    degrees: f64,
) -> anyhow::Result<BendReport> {
    if !(degrees.is_finite() && degrees.abs() <= 360.0) {
        anyhow::bail!("--bend-joints {degrees}: expected an angle in degrees between -360 and 360");
    }
    let options = cagerig::session::SessionOptions {
        coords,
        cage_fit,
        ..Default::default()
    };
    let (mut session, _) = cagerig::session::RigSession::new(loaded.parts.clone(), options)?;
    let joints = cagerig::cage_quality::joint_bends(&mut session, degrees.to_radians())?;
    let worst = joints
        .iter()
        .filter_map(|j| j.quality)
        .reduce(cagerig::cage_quality::CageQuality::worst);
    Ok(BendReport {
        degrees,
        cage_fit: session.cage_fit(),
        joints,
        worst,
    })
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (rig, json) = (&args.rig, args.json);
    let load = || {
        load_rig_or_generate_cage(
            rig,
            !json,
            false,
            args.auto_cage.options(),
            CageCheck::Loader,
        )
    };
    if let Some(m) = rig.mesh.as_deref()
        && crate::interchange::is_interchange(m)?
    {
        // The file's own facts; then, when a cage is given or generated, or anything of the rig
        // built from the file is asked for, that rig, as for a rig of OBJ files (a rig with no
        // cage is then an error that says how to give one).
        let binds = rig.cage.is_some()
            || args.auto_cage.auto_cage
            || args.bend_joints.is_some()
            || args.coords != cagerig::CoordsKind::Mvc
            || rig.weights.is_some()
            || rig.auto_weights
            || rig.allow_outside_cage;
        if !binds {
            return crate::interchange::info(m, rig.skin.as_deref(), json);
        }
        let loaded = load()?;
        let summary = loaded.import_summary.as_ref().with_context(|| {
            format!(
                "{}: loaded as a glTF/FBX file without its importer's summary",
                m.display()
            )
        })?;
        let report = rig_report(&loaded, args)?;
        let cage = match &loaded.generated_cage {
            Some(_) => "a cage generated by --auto-cage".to_owned(),
            None => loaded.cage_name(),
        };
        let bound = crate::interchange::BoundRig {
            report: &report,
            cage,
        };
        crate::interchange::info_with_rig(m, summary, bound, json)?;
        if !json {
            print_report(&report);
        }
        return Ok(());
    }
    let report = rig_report(&load()?, args)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report);
    }
    Ok(())
}

/// The report of the rig `loaded`: counts, files, warnings, the cage's checks, and what `args`
/// asks beyond them (a Green binding, the joints' bends).
fn rig_report(loaded: &LoadedRig, args: &Args) -> anyhow::Result<InfoReport> {
    let p = &loaded.parts;
    let cage_check = cagerig::cage::validate_cage(p.cage.clone());
    let (mut warnings, mut notes) = (Vec::new(), Vec::new());
    let cage_warnings = cage_check
        .as_ref()
        .map(|(_, w)| w.as_slice())
        .unwrap_or(&[]);
    for w in loaded.warnings.iter().chain(cage_warnings) {
        match w.severity() {
            cagerig::Severity::Note => notes.push(w.to_string()),
            cagerig::Severity::Warning => warnings.push(w.to_string()),
        }
    }
    if let Err(e) = &cage_check {
        warnings.push(format!("the cage is unusable: {e}"));
    }
    Ok(InfoReport {
        rig: loaded.name.clone(),
        vertices: p.mesh.num_vertices(),
        triangles: p.mesh.num_triangles(),
        joints: p.skeleton.len(),
        cage_vertices: p.cage.num_vertices(),
        cage_triangles: p.cage.num_triangles(),
        cage_generated: loaded.generated_cage.is_some(),
        max_influences: p.skin_weights.max_influences(),
        files: loaded.files.clone(),
        warnings,
        notes,
        cage_checks: cage_check
            .is_ok()
            .then(|| crate::commands::cage::validate_rig_cage(&p.cage, &p.mesh)),
        green: match args.coords {
            cagerig::CoordsKind::Mvc => None,
            cagerig::CoordsKind::Green => Some(green_report(p)?),
        },
        joint_bends: args
            .bend_joints
            .map(|degrees| bend_report(loaded, args.coords, args.cage_fit, degrees))
            .transpose()?,
    })
}

/// The text form of a rig's report.
fn print_report(report: &InfoReport) {
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
        "cage           {} vertices, {} triangles{}",
        report.cage_vertices,
        report.cage_triangles,
        if report.cage_generated {
            " (generated by --auto-cage)"
        } else {
            ""
        }
    );
    for f in &report.files {
        println!("file           {:<14} {}", f.role, f.path.display());
    }
    if let Some(checks) = &report.cage_checks {
        println!(
            "cage distance  min {:.3} %, mean {:.3} % of the diagonal; smallest triangle \
             angle {:.2}°",
            100.0 * checks.min_distance_fraction,
            100.0 * checks.mean_distance_fraction,
            checks.min_triangle_angle.to_degrees()
        );
        crate::commands::cage::print_checks(checks);
    }
    if let Some(green) = &report.green {
        println!(
            "green coords   {} face coordinates, reproduction {:.2e} of the diagonal, {} \
             vertices outside the cage, bound in {:.3} s",
            green.face_coordinates,
            green.reproduction_error,
            green.outside_cage,
            green.binding_seconds
        );
    }
    if let Some(bends) = &report.joint_bends {
        println!(
            "joint bends    {}° about x, y and z from rest, {} cage fit:",
            bends.degrees, bends.cage_fit
        );
        for j in &bends.joints {
            match j.quality {
                Some(q) => println!("  {:>3} {:<24} {q}", j.joint, j.name),
                None => println!("  {:>3} {:<24} every bend refused", j.joint, j.name),
            }
            if j.refused > 0 && j.quality.is_some() {
                println!("      {} of 3 bends refused", j.refused);
            }
        }
        if let Some(w) = bends.worst {
            println!("  worst                            {w}");
        }
    }
    for n in &report.notes {
        println!("note           {n}");
    }
    if report.warnings.is_empty() {
        println!("warnings       none");
    }
    for w in &report.warnings {
        println!("warning        {w}");
    }
}
