//! Timings of automatic cage generation ([`cagerig::cage_gen::generate_cage`], default options)
//! on the Arm (2 089 vertices) and on the Arm subdivided three times (133 073 vertices), with
//! the generation figures of the last run. Run with
//! `cargo run --release -p cagerig --example cage_gen_timing [-- REPETITIONS]`.

#![expect(clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Instant;

use cagerig::cage_gen::{CageOptions, generate_cage};
use cagerig::rig_files::load_rig_files;
use cagerig::subdivide::subdivide_midpoint;

const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm");

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repetitions: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(5);
    let dir = Path::new(ARM);
    let parts = load_rig_files(&dir.join("arm.obj"), None)?.parts;
    let arm = parts.mesh.clone();
    let arm3 = subdivide_midpoint(&parts.mesh, &parts.skin_weights, 3)?.mesh;
    let options = CageOptions::default();
    for (name, mesh) in [("arm", &arm), ("arm ×3", &arm3)] {
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..repetitions {
            let start = Instant::now();
            last = Some(generate_cage(mesh, &options)?);
            times.push(start.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        let g = last.expect("at least one repetition");
        println!(
            "{name:8} {} vertices: median {:.3} s, min {:.3} s over {repetitions} runs; cage {} vertices, {} surface vertices, {} collapses, {} rejected",
            mesh.num_vertices(),
            times[times.len() / 2],
            times[0],
            g.cage.num_vertices(),
            g.stats.surface_vertices,
            g.stats.collapses,
            g.stats.rejected_positions,
        );
        println!("         stages {:?}", g.stats.stage_seconds);
        println!(
            "         offset {:.3} %, spacing {:.3} %, distance min {:.3} % mean {:.3} %, volume ratio {:.3}, attempts {:?}",
            100.0 * g.stats.offset_fraction,
            100.0 * g.stats.spacing_fraction,
            100.0 * g.report.min_distance_fraction,
            100.0 * g.report.mean_distance_fraction,
            g.report.volume_ratio,
            g.stats.attempts
        );
    }
    Ok(())
}
