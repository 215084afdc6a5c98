//! Import speed: `cargo run --release -p cagerig-formats --example import_bench -- FILE [RUNS]`
//! prints the median, min and max wall time of `import_character` (a 100k-vertex file:
//! `cagerig export --builtin snake --resolution 100000 --out snake100k.glb`).

// tests, benches and examples may panic on a broken fixture

use std::time::Instant;

use cagerig_formats::{ImportOptions, import_character};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().ok_or("usage: import_bench FILE [RUNS]")?;
    let runs: usize = args.next().map_or(Ok(7), |r| r.parse())?;
    let mut times = Vec::with_capacity(runs);
    let mut vertices = 0;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let c = import_character(path.as_ref(), &ImportOptions::default())?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
        vertices = c.mesh.num_vertices();
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{path}: {vertices} vertices, import median {:.1} ms (min {:.1}, max {:.1}, {} runs)",
        times[times.len() / 2],
        times[0],
        times[times.len() - 1],
        times.len()
    );
    Ok(())
}
