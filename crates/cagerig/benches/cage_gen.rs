//! Criterion bench of automatic cage generation (`generate_cage`, default options: 100
//! vertices, margin 0.5 % of the diagonal) on the Arm (2 089 vertices) and on the Arm
//! subdivided three times (133 073 vertices). Targets: ≤ 0.3 s and ≤ 2 s on the
//! project's 2-core machine. `cargo bench -p cagerig --bench cage_gen`; the example
//! `cage_gen_timing` prints the same runs with their stage times and quality figures.

#![expect(clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

use std::path::Path;
use std::time::Duration;

use cagerig::cage_gen::{CageOptions, generate_cage};
use cagerig::rig_files::load_rig_files;
use cagerig::subdivide::subdivide_midpoint;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm/arm.obj");

fn cage_generation(c: &mut Criterion) {
    let parts = load_rig_files(Path::new(ARM), None)
        .expect("the Arm rig in data/arm in the repository")
        .parts;
    let arm3 = subdivide_midpoint(&parts.mesh, &parts.skin_weights, 3)
        .expect("subdividing the Arm")
        .mesh;
    let options = CageOptions::default();
    let mut group = c.benchmark_group("cage_gen");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(15));
    for (name, mesh) in [("arm", &parts.mesh), ("arm_x3", &arm3)] {
        group.bench_function(BenchmarkId::new(name, mesh.num_vertices()), |b| {
            b.iter(|| generate_cage(mesh, &options).expect("a validated cage"))
        });
    }
    group.finish();
}

criterion_group!(benches, cage_generation);
criterion_main!(benches);
