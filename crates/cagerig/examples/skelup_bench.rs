//! Times the SkelUp precomputation (Ψ) on the Arm subdivided N times, for both localisations,
//! then again after MaxVol has run on the same threads (the order of a binding): the two
//! default-localisation figures should match. They did not while faer's kernels left the vector
//! registers' upper halves in use (36 against 70–75 ms at N = 3; see `vector_registers.rs`).
//! `cargo run --release -p cagerig --example skelup_bench -- [N]`.

// tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Instant;

use cagerig::coords::maxvol::select_maxvol_rows;
use cagerig::coords::mvc::compute_cage_coords;
use cagerig::subdivide::subdivide_midpoint;
use cagerig::sync::skeleton_updater::{JointLocalisation, SkeletonUpdater};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let levels: usize = std::env::args().nth(1).map_or(Ok(2), |a| a.parse())?;
    let arm_obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm/arm.obj");
    let arm = cagerig::rig_files::load_rig_files(&arm_obj, None)?.parts;
    let (mesh, skeleton, weights, cage) = (arm.mesh, arm.skeleton, arm.skin_weights, arm.cage);
    let sub = subdivide_midpoint(&mesh, &weights, levels)?;
    let phi = compute_cage_coords(&cage, &sub.mesh.positions, None)?;
    // Best of three runs, in ms.
    let skelup = |localisation| -> Result<f64, cagerig::RigError> {
        let mut best = f64::INFINITY;
        for _ in 0..3 {
            let t = Instant::now();
            SkeletonUpdater::new(
                &sub.mesh,
                &skeleton,
                &sub.skin_weights,
                &phi,
                None,
                &cage.positions,
                localisation,
            )?;
            best = best.min(t.elapsed().as_secs_f64() * 1e3);
        }
        Ok(best)
    };
    println!("Arm N={levels}: {} vertices", sub.mesh.num_vertices());
    for localisation in [
        JointLocalisation::default(),
        JointLocalisation::reference_tool(),
    ] {
        println!(
            "  SkelUp preprocess, {localisation:?}: {:.1} ms",
            skelup(localisation)?
        );
    }
    select_maxvol_rows(&phi)?;
    println!(
        "  SkelUp preprocess after MaxVol, default: {:.1} ms",
        skelup(JointLocalisation::default())?
    );
    Ok(())
}
