//! Timings of the cage coordinates Φ (MVC) and the MaxVol row selection on the Arm subdivided
//! three times (133 073 vertices, 58-vertex cage). Run with
//! `cargo run --release -p cagerig --example coords_bench`.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::path::Path;

use cagerig::coords::maxvol::select_maxvol_rows;
use cagerig::coords::mvc::compute_cage_coords;
use cagerig::io::{read_obj, read_skt, read_skw};
use cagerig::subdivide::subdivide_midpoint;

mod timing;

const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm");
const REPETITIONS: usize = 7;

/// CPU time (user + system) of this process in milliseconds (Linux; 0 elsewhere).
fn cpu_ms() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 =
        fields[11].parse::<f64>().unwrap_or(0.0) + fields[12].parse::<f64>().unwrap_or(0.0);
    ticks * 10.0
}

/// (median, min) wall-clock milliseconds over [`REPETITIONS`] runs; also prints the mean CPU
/// time per run (less sensitive to other processes on the machine).
fn timings<T>(f: impl FnMut() -> T) -> ((f64, f64), T) {
    let cpu_start = cpu_ms();
    let timings = timing::timed(REPETITIONS, f);
    println!(
        "  CPU time per run {:.1} ms",
        (cpu_ms() - cpu_start) / REPETITIONS as f64
    );
    timings
}

fn main() {
    let dir = Path::new(ARM);
    let mesh = read_obj(&dir.join("arm.obj")).unwrap();
    let cage = read_obj(&dir.join("arm_cage.obj")).unwrap();
    let skeleton = read_skt(&dir.join("arm.skt")).unwrap();
    let (weights, _) = read_skw(&dir.join("arm.skw"), mesh.num_vertices(), skeleton.len()).unwrap();
    let subdivided = subdivide_midpoint(&mesh, &weights, 3).unwrap().mesh;
    let points = &subdivided.positions;
    println!(
        "{} points, cage {} vertices / {} triangles, {} threads",
        points.len(),
        cage.num_vertices(),
        cage.triangles.len(),
        rayon::current_num_threads()
    );
    let ((median, min), phi) = timings(|| compute_cage_coords(&cage, points, None).unwrap());
    println!("MVC Φ: median {median:.1} ms, min {min:.1} ms");
    println!("  max partition error {:e}", phi.max_partition_error());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let ((median, min), _) =
        pool.install(|| timings(|| compute_cage_coords(&cage, points, None).unwrap()));
    println!("MVC Φ single thread: median {median:.1} ms, min {min:.1} ms");
    let ((median, min), selection) = timings(|| select_maxvol_rows(&phi).unwrap());
    println!(
        "MaxVol: median {median:.1} ms, min {min:.1} ms (ln|det| {:.6}, {} swaps)",
        selection.log_abs_det, selection.swaps
    );
}
