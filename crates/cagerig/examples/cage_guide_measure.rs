//! Does the skeleton guide ([`cagerig::cage_gen::skeleton_guide`]) make better cages? Compares
//! unguided and guided cages on the Arm (58 and 100 vertices): the condition number of the
//! MaxVol block Φ̃, the locality of Φ (mean effective support (Σₖ|φᵢₖ|)² / Σₖ φᵢₖ² of the mesh
//! rows: the number of cage vertices a mesh vertex effectively depends on) and the distances.
//! `cargo run --release -p cagerig --example cage_guide_measure`.

// tests, benches and examples may panic on a broken fixture

use std::path::Path;

use cagerig::cage_gen::{
    CageGuide, CageOptions, CageTarget, check_coordinates, generate_guided_cage,
};
use cagerig::coords::mvc::compute_cage_coords;
use cagerig::rig_files::load_rig_files;

const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm/arm.obj");

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let parts = load_rig_files(Path::new(ARM), None)?.parts;
    let guide = CageGuide::from_skeleton(&parts.skeleton);
    println!("{} guide planes", guide.planes.len());
    for vertices in [58, 100] {
        let options = CageOptions {
            target: CageTarget::Vertices(vertices),
            ..CageOptions::default()
        };
        for (name, g) in [
            ("unguided", CageGuide::default()),
            ("guided", guide.clone()),
        ] {
            let mut generated = generate_guided_cage(&parts.mesh, &options, &g)?;
            check_coordinates(&generated.cage, &parts.mesh, &mut generated.report);
            let phi = compute_cage_coords(&generated.cage, &parts.mesh.positions, None)?;
            let (nv, nc) = (phi.num_vertices(), phi.num_cage_vertices());
            let mut support = 0.0;
            for i in 0..nv {
                let (mut l1, mut l2) = (0.0, 0.0);
                for k in 0..nc {
                    let x = phi.get(i, k);
                    l1 += x.abs();
                    l2 += x * x;
                }
                support += l1 * l1 / l2;
            }
            let r = &generated.report;
            println!(
                "{vertices:4} {name:9} passed {} MaxVol cond {:.3e} support {:.2} min/mean distance {:.3}/{:.3} % {:.2} s",
                r.passed(),
                r.maxvol_condition.unwrap_or(f64::NAN),
                support / nv as f64,
                100.0 * r.min_distance_fraction,
                100.0 * r.mean_distance_fraction,
                generated.stats.seconds
            );
        }
    }
    Ok(())
}
