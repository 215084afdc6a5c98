//! Times the SkelUp precomputation (Ψ) on the Arm subdivided N times:
//! `cargo run --release -p cagerig --example skelup_bench -- [N]`.

use std::path::Path;
use std::time::Instant;

use cagerig::coords::mvc::compute_cage_coords;
use cagerig::subdivide::subdivide_midpoint;
use cagerig::sync::skeleton_updater::{JointLocalisation, SkeletonUpdater};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let levels: usize = std::env::args().nth(1).map_or(Ok(2), |a| a.parse())?;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/arm");
    let mesh = cagerig::io::read_obj(&dir.join("arm.obj"))?;
    let skeleton = cagerig::io::read_skt(&dir.join("arm.skt"))?;
    let (weights, _) = cagerig::io::read_skw(&dir.join("arm.skw"), mesh.num_vertices(), 25)?;
    let cage = cagerig::io::read_obj(&dir.join("arm_cage.obj"))?;
    let sub = subdivide_midpoint(&mesh, &weights, levels)?;
    let phi = compute_cage_coords(&cage, &sub.mesh.positions, None)?;
    for localisation in [
        JointLocalisation::default(),
        JointLocalisation::reference_tool(),
    ] {
        let t = Instant::now();
        let (up, _) = SkeletonUpdater::new(
            &sub.mesh,
            &skeleton,
            &sub.skin_weights,
            &phi,
            &cage.positions,
            localisation,
        )?;
        println!(
            "{} vertices, {localisation:?}: SkelUp preprocess {:.1} ms ({} joints)",
            sub.mesh.num_vertices(),
            t.elapsed().as_secs_f64() * 1e3,
            up.num_joints()
        );
    }
    Ok(())
}
