//! A Green-coordinates animation frame on the Arm subdivided N times, split into its parts:
//! skeleton keys alone (skinning + CageUp), cage keys alone (the rest skin M = φC + ψg(C) and
//! CageUp) and both (what `cagerig bench --coords green` reports as "animation frame"), with
//! CageUp's Newton steps and Hessian factorisations per frame:
//! `cargo run --release -p cagerig --example green_frame_bench -- [N] [display] [all-rows] [mvc]`
//! (`display`: the f32 display path; `all-rows`: CageUp fits every row; `mvc`: mean value
//! coordinates instead, for comparison; `GREEN_FRAME_ERRORS=1` prints the first refusals).

// tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Instant;

use cagerig::CoordsKind;
use cagerig::playback::AnimationPlayer;
use cagerig::session::{DisplayPrecision, RigParts, RigSession, SessionOptions};
use cagerig::subdivide::subdivide_midpoint;
use glam::DVec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let levels: usize = std::env::args().nth(1).map_or(Ok(3), |a| a.parse())?;
    let display = std::env::args().any(|a| a == "display");
    let arm_obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm/arm.obj");
    let arm = cagerig::rig_files::load_rig_files(&arm_obj, None)?.parts;
    let (mesh, skeleton, weights, cage) = (arm.mesh, arm.skeleton, arm.skin_weights, arm.cage);
    let sub = subdivide_midpoint(&mesh, &weights, levels)?;
    println!("Arm N={levels}: {} vertices", sub.mesh.num_vertices());
    let parts = RigParts::new(sub.mesh, skeleton, sub.skin_weights, cage);
    let options = SessionOptions {
        coords: if std::env::args().any(|a| a == "mvc") {
            CoordsKind::Mvc
        } else {
            CoordsKind::Green
        },
        fit_rows: if std::env::args().any(|a| a == "all-rows") {
            cagerig::session::FitRows::AllRows
        } else {
            cagerig::session::FitRows::MaxVol
        },
        ..SessionOptions::default()
    };
    let (mut session, _) = RigSession::new(parts, options)?;
    if std::env::args().any(|a| a == "edits-first") {
        // What `cagerig bench` does before its display pass: a bend, drags and grabs.
        let joint = session.skeleton().find("lowerarm01.R").unwrap_or(3);
        for _ in 0..6 {
            session.rotate_joint(joint, DVec3::X, 10f64.to_radians())?;
        }
        for i in 0..20 {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            session.move_rest_cage(&[7, 8], &[DVec3::new(sign * 0.05, 0.0, 0.0)])?;
        }
        for i in 0..20 {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            session.rotate_joint(joint, DVec3::Y, 0.01 * sign)?;
            let _ = session.move_posed_cage(&[7], &[DVec3::new(0.0, sign * 0.05, 0.0)]);
        }
    }
    if display {
        session.set_display_precision(DisplayPrecision::F32)?;
    }
    if std::env::args().any(|a| a == "grab-first") {
        session.move_posed_cage(&[7], &[DVec3::new(0.0, 0.01, 0.0)])?;
        session.move_rest_cage(&[7], &[DVec3::new(0.0, 0.01, 0.0)])?;
    }
    let sections: &[(&str, bool, bool)] = if std::env::args().any(|a| a == "grab-only") {
        &[]
    } else {
        &[
            ("skeleton keys", true, false),
            ("cage keys", false, true),
            ("both", true, true),
        ]
    };
    for &(name, use_skeleton, use_cage) in sections {
        session.reset_pose();
        let (skeleton_track, cage_track) =
            cagerig::demo::bench_tracks::synthetic_tracks(session.skeleton(), session.rest_cage())?;
        let mut player = AnimationPlayer::new(
            &session,
            use_skeleton.then_some(skeleton_track),
            use_cage.then_some(cage_track),
        )?;
        let duration = player.duration();
        let (mut times, mut steps, mut factors, mut refused) =
            (Vec::new(), Vec::new(), Vec::new(), 0);
        for i in 0..103 {
            let t = Instant::now();
            let result = player.apply((i as f64 * 0.037) % duration, &mut session);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            if let Err(e) = result {
                if refused < 3 && std::env::var_os("GREEN_FRAME_ERRORS").is_some() {
                    println!("  t = {:.3}: {e}", (i as f64 * 0.037) % duration);
                }
                refused += 1;
                continue;
            }
            if i >= 3 {
                times.push(ms);
                if let Some((fit, _)) = session.green_newton_reports() {
                    steps.push(fit.iterations);
                    factors.push(fit.factorisations);
                }
            }
        }
        times.sort_by(f64::total_cmp);
        steps.sort_unstable();
        factors.sort_unstable();
        let median = |v: &[usize]| v.get(v.len() / 2).copied().unwrap_or(0);
        println!(
            "{name:<14} median {:.2} ms (min {:.2}); CageUp steps median {} max {}, Hessians median {} max {}; {refused} refused",
            times.get(times.len() / 2).copied().unwrap_or(0.0),
            times.first().copied().unwrap_or(0.0),
            median(&steps),
            steps.last().copied().unwrap_or(0),
            median(&factors),
            factors.last().copied().unwrap_or(0),
        );
    }
    // A grab right after a small skeleton edit (the edit untimed), as `cagerig bench` times it.
    session.reset_pose();
    let joint = session.skeleton().find("lowerarm01.R").unwrap_or(3);
    for _ in 0..6 {
        session.rotate_joint(joint, DVec3::X, 10f64.to_radians())?;
    }
    let step = 1e-3 * {
        let (lo, hi) = cagerig::mesh::bounding_box(session.rest_cage());
        (hi - lo).length()
    };
    let (mut times, mut steps) = (Vec::new(), Vec::new());
    let grabs = if std::env::args().any(|a| a == "grab-only") {
        400
    } else {
        60
    };
    for i in 0..grabs {
        let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
        session.rotate_joint(joint, DVec3::Y, 0.01 * sign)?;
        let t = Instant::now();
        let result = session.move_posed_cage(&[7], &[DVec3::new(0.0, sign * step, 0.0)]);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if result.is_ok() && i >= 3 {
            times.push(ms);
            steps.push(
                session
                    .green_newton_reports()
                    .map_or(0, |(_, r)| r.iterations),
            );
        }
    }
    times.sort_by(f64::total_cmp);
    steps.sort_unstable();
    println!(
        "grab after a skeleton edit: median {:.2} ms (min {:.2}), CageRev steps median {}",
        times.get(times.len() / 2).copied().unwrap_or(0.0),
        times.first().copied().unwrap_or(0.0),
        steps.get(steps.len() / 2).copied().unwrap_or(0),
    );
    Ok(())
}
