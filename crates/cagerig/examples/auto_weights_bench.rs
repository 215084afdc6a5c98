//! Times the automatic weights (`cagerig::auto_weights`, default options) on the Arm and on the
//! Arm subdivided 1–3 times (3 levels: 133,105 vertices).
//! `cargo run --release -p cagerig --example auto_weights_bench -- [--levels N] [--reps R]`
//! (targets on a 2-core machine: ≤ 0.5 s on the Arm, ≤ 3 s at 133k vertices).

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Instant;

use cagerig::auto_weights::{AutoWeights, AutoWeightsOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let flag = |name: &str, default: usize| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .map_or(default, |v| v.parse().unwrap())
    };
    let levels = flag("--levels", 3);
    let reps = flag("--reps", 3);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm");
    let mesh = cagerig::io::obj::read_obj(&root.join("arm.obj")).unwrap();
    let skeleton = cagerig::io::skt::read_skt(&root.join("arm.skt")).unwrap();
    let (artist, _) =
        cagerig::io::skw::read_skw(&root.join("arm.skw"), mesh.num_vertices(), skeleton.len())
            .unwrap();
    let aw = AutoWeights::new(AutoWeightsOptions::default()).unwrap();
    println!(
        "threads {}; options {:?}",
        rayon::current_num_threads(),
        aw.options()
    );
    for level in 0..=levels {
        let sub = cagerig::subdivide::subdivide_midpoint(&mesh, &artist, level).unwrap();
        let mut times: Vec<f64> = (0..reps.max(1))
            .map(|_| {
                let start = Instant::now();
                let r = aw.compute(&sub.mesh, &skeleton, None).unwrap();
                std::hint::black_box(r);
                start.elapsed().as_secs_f64()
            })
            .collect();
        times.sort_by(f64::total_cmp);
        println!(
            "Arm ×{level} levels: {:>7} vertices, {:>7} triangles: median {:.3} s, best {:.3} s",
            sub.mesh.num_vertices(),
            sub.mesh.num_triangles(),
            times[times.len() / 2],
            times[0]
        );
    }
}
