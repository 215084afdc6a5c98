//! Green coordinates (φ, ψ) against mean value coordinates Φ of the Arm subdivided N times, timed
//! alternately in one process (the ratio is what `cagerig bench --coords green` reports as
//! "binding / MVC"). `cargo run --release -p cagerig --example green_bind_bench -- [N] [--reps R]`
//! (`RAYON_NUM_THREADS=1` for one thread).

// tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Instant;

use cagerig::coords::green::compute_green_coords;
use cagerig::coords::mvc::compute_cage_coords;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let levels: usize = args
        .iter()
        .find(|a| a.parse::<usize>().is_ok())
        .map_or(Ok(0), |a| a.parse())?;
    let reps: usize = args
        .iter()
        .position(|a| a == "--reps")
        .and_then(|i| args.get(i + 1))
        .map_or(Ok(if levels >= 3 { 5 } else { 31 }), |a| a.parse())?;
    let arm_obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm/arm.obj");
    let arm = cagerig::rig_files::load_rig_files(&arm_obj, None)?.parts;
    let (mesh, weights, cage) = (arm.mesh, arm.skin_weights, arm.cage);
    let mesh = cagerig::subdivide::subdivide_midpoint(&mesh, &weights, levels)?.mesh;
    let points = &mesh.positions;
    println!(
        "Arm N={levels}: {} points, cage {} vertices / {} triangles, {} threads, {reps} runs each",
        points.len(),
        cage.num_vertices(),
        cage.triangles.len(),
        rayon::current_num_threads()
    );
    let (mut green, mut mvc) = (Vec::new(), Vec::new());
    for _ in 0..reps + 1 {
        let start = Instant::now();
        drop(compute_green_coords(&cage, points, None)?);
        green.push(start.elapsed().as_secs_f64() * 1e3);
        let start = Instant::now();
        drop(compute_cage_coords(&cage, points, None)?);
        mvc.push(start.elapsed().as_secs_f64() * 1e3);
    }
    // The first run of each warms up.
    let median = |mut v: Vec<f64>| {
        v.remove(0);
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2], v[0])
    };
    let ((green_median, green_min), (mvc_median, mvc_min)) = (median(green), median(mvc));
    println!("  Green (φ, ψ)   median {green_median:9.3} ms, min {green_min:9.3} ms");
    println!("  MVC Φ          median {mvc_median:9.3} ms, min {mvc_min:9.3} ms");
    println!(
        "  ratio          median {:.2}, min {:.2}",
        green_median / mvc_median,
        green_min / mvc_min
    );
    Ok(())
}
