//! Times a current-cage grab right after a skeleton edit on the Arm subdivided N times, with Φ
//! in f64 and in f32, next to its two big parts (M(C), ΦC or ΦC + ψ·g(C), and LBS), and on the f32 display path
//! (what the editor runs) next to its product M̃ = Φ̃C:
//! `cargo run --release -p cagerig --example grab_bench -- [N] [display|exact] [green]` (`display`:
//! only the display path, `exact`: only the f64 path, each 400 grabs, e.g. under a profiler;
//! `green`: a Green-coordinates rig, bent in 10° steps; `paper`: the paper's cage fit instead of
//! the default regularised one).

// tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Instant;

use cagerig::cage_coords::CoordsPrecision;
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig::skinning::LinearBlendSkinning;
use cagerig::subdivide::subdivide_midpoint;
use glam::DVec3;

fn stats(mut samples: Vec<f64>) -> String {
    samples.sort_by(f64::total_cmp);
    format!(
        "min {:.3} ms, median {:.3} ms",
        samples[0],
        samples[samples.len() / 2]
    )
}

/// A small rotation of `joint` (alternating with `i`), then the timed grab of cage vertex 7 (ms).
fn grab_after_skeleton_edit(
    session: &mut RigSession,
    joint: usize,
    i: usize,
) -> Result<f64, cagerig::RigError> {
    let sign = if i.is_multiple_of(2) { 1.0 } else { -1.0 };
    session.rotate_joint(joint, DVec3::Y, 0.01 * sign)?;
    let t = Instant::now();
    session.move_posed_cage(&[7], &[DVec3::new(0.0, 0.01 * sign, 0.0)])?;
    Ok(t.elapsed().as_secs_f64() * 1e3)
}

/// The elbow bent by 60° about +X, in 10° steps (a Green CageUp follows a large bend better in
/// steps).
fn bend(session: &mut RigSession, joint: usize) -> Result<(), cagerig::RigError> {
    for _ in 0..6 {
        session.rotate_joint(joint, DVec3::X, 10f64.to_radians())?;
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let levels: usize = std::env::args().nth(1).map_or(Ok(3), |a| a.parse())?;
    let display_only = std::env::args().any(|a| a == "display");
    let exact_only = std::env::args().any(|a| a == "exact");
    let coords = if std::env::args().any(|a| a == "green") {
        cagerig::CoordsKind::Green
    } else {
        cagerig::CoordsKind::Mvc
    };
    let cage_fit = if std::env::args().any(|a| a == "paper") {
        cagerig::sync::CageFitKind::Paper
    } else {
        cagerig::sync::CageFitKind::Regularised
    };
    let arm_obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm/arm.obj");
    let arm = cagerig::rig_files::load_rig_files(&arm_obj, None)?.parts;
    let (mesh, skeleton, weights, cage) = (arm.mesh, arm.skeleton, arm.skin_weights, arm.cage);
    let sub = subdivide_midpoint(&mesh, &weights, levels)?;
    let nv = sub.mesh.num_vertices();
    println!("Arm N={levels}: {nv} vertices");
    let precisions: &[CoordsPrecision] = if display_only {
        &[]
    } else if exact_only {
        &[CoordsPrecision::F64]
    } else {
        &[CoordsPrecision::F64, CoordsPrecision::F32]
    };
    for &precision in precisions {
        let parts = RigParts::new(
            sub.mesh.clone(),
            skeleton.clone(),
            sub.skin_weights.clone(),
            cage.clone(),
        );
        let options = SessionOptions {
            cage_coords_precision: precision,
            coords,
            cage_fit,
            ..SessionOptions::default()
        };
        let (mut session, _) = RigSession::new(parts, options)?;
        let joint = session.skeleton().find("lowerarm01.R").unwrap_or(3);
        bend(&mut session, joint)?;
        let (mut grab, mut product, mut skin) = (Vec::new(), Vec::new(), Vec::new());
        let mut m = vec![DVec3::ZERO; nv];
        let mut out = vec![DVec3::ZERO; nv];
        let lbs = LinearBlendSkinning::new(session.skin_weights());
        for i in 0..if exact_only { 400 } else { 60 } {
            grab.push(grab_after_skeleton_edit(&mut session, joint, i)?);
            let t = Instant::now();
            session.rest_mesh_for_cage(session.rest_cage(), &mut m)?;
            product.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            lbs.apply(session.posed_from_rest(), &m, &mut out);
            skin.push(t.elapsed().as_secs_f64() * 1e3);
        }
        println!("Φ {precision:?}:");
        println!("  grab after skeleton edit: {}", stats(grab));
        println!("  M(C) alone:               {}", stats(product));
        println!("  LBS alone:                {}", stats(skin));
    }
    if exact_only {
        return Ok(());
    }
    // The display path: M̃ = Φ̃C and the f32 M' for display, exact MaxVol rows.
    let parts = RigParts::new(sub.mesh, skeleton, sub.skin_weights, cage);
    let options = SessionOptions {
        coords,
        cage_fit,
        ..SessionOptions::default()
    };
    let (mut session, _) = RigSession::new(parts, options)?;
    session.set_display_precision(cagerig::session::DisplayPrecision::F32)?;
    let joint = session.skeleton().find("lowerarm01.R").unwrap_or(3);
    bend(&mut session, joint)?;
    let display_coords = cagerig::cage_coords::DisplayCageCoords::try_new(session.cage_coords())
        .ok_or("Φ̃ does not fit")?;
    let mut m = vec![glam::Vec3::ZERO; nv];
    let (mut grab, mut product) = (Vec::new(), Vec::new());
    let reps = if display_only { 400 } else { 60 };
    for i in 0..reps {
        grab.push(grab_after_skeleton_edit(&mut session, joint, i)?);
        let t = Instant::now();
        display_coords.apply(session.rest_cage(), &mut m);
        product.push(t.elapsed().as_secs_f64() * 1e3);
    }
    println!("display path (f32 Φ̃ and M' drawn, exact rows):");
    println!("  grab after skeleton edit: {}", stats(grab));
    println!("  M̃ = Φ̃C alone:             {}", stats(product));
    Ok(())
}
