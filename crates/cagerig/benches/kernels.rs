//! Criterion benches of the kernels, parameterised by mesh size #V, joint count #B and cage
//! size #C. `cargo bench -p cagerig`; the CLI's `cagerig bench` prints the Table-1 view.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::coords::mvc::compute_cage_coords;
use cagerig::demo;
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig::skin_weights::SkinWeights;
use cagerig::skinning::{
    CorScratch, CorSkinning, DqsScratch, DualQuaternionSkinning, LinearBlendSkinning,
};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DAffine3, DQuat, DVec3};

/// Synthetic Ω with `joints` bones along X: each vertex blends the nearest bones (≤ 4).
fn synthetic_weights(positions: &[DVec3], joints: usize) -> SkinWeights {
    let (lo, hi) = cagerig::mesh::bounding_box(positions);
    let len = (hi.x - lo.x).max(1e-9);
    let triplets = positions.iter().enumerate().flat_map(|(v, p)| {
        let u = (p.x - lo.x) / len * (joints as f64 - 1.0);
        let base = u.floor() as isize;
        (-1..3).filter_map(move |d| {
            let j = base + d;
            (0..joints as isize).contains(&j).then(|| {
                let w = 1.0 / (1.0 + (u - j as f64).powi(2));
                (v, j as usize, w)
            })
        })
    });
    SkinWeights::from_triplets(positions.len(), joints, triplets)
        .unwrap()
        .0
}

fn transforms(joints: usize) -> Vec<DAffine3> {
    (0..joints)
        .map(|j| {
            DAffine3::from_rotation_translation(
                DQuat::from_axis_angle(DVec3::new(1.0, 0.5, 0.2).normalize(), 0.1 * j as f64),
                DVec3::new(0.0, 0.05 * j as f64, 0.0),
            )
        })
        .collect()
}

fn skinning(c: &mut Criterion) {
    let mut group = c.benchmark_group("skinning");
    group.sample_size(30);
    for vertices in [10_000usize, 130_000] {
        let rig = demo::builtin("snake", Some(vertices)).unwrap();
        let rest = rig.mesh.positions;
        for joints in [16usize, 64] {
            let weights = synthetic_weights(&rest, joints);
            let t = transforms(joints);
            let mut out = vec![DVec3::ZERO; rest.len()];
            let id = format!("V{}_B{joints}", rest.len());
            group.throughput(Throughput::Elements(rest.len() as u64));
            let lbs = LinearBlendSkinning::new(&weights);
            group.bench_function(BenchmarkId::new("lbs", &id), |b| {
                b.iter(|| lbs.apply(&t, &rest, &mut out))
            });
            let dqs = DualQuaternionSkinning::new(&weights);
            let mut scratch = DqsScratch::new(joints);
            group.bench_function(BenchmarkId::new("dqs", &id), |b| {
                b.iter(|| dqs.apply(&t, &rest, &mut scratch, &mut out))
            });
            let cor = CorSkinning::new(&weights);
            let mut scratch = CorScratch::new(joints);
            let centres = rest.clone();
            group.bench_function(BenchmarkId::new("cor", &id), |b| {
                b.iter(|| cor.apply(&t, &rest, &centres, &mut scratch, &mut out))
            });
        }
    }
    group.finish();
}

fn cage_ops(c: &mut Criterion) {
    let mut group = c.benchmark_group("cage");
    group.sample_size(10);
    // #C varies with the rig: bar 20, bar_irregular 24, snake 70 cage vertices.
    for name in ["bar", "bar_irregular", "snake"] {
        let rig = demo::builtin(name, None).unwrap();
        let id = format!(
            "{name}_V{}_C{}",
            rig.mesh.num_vertices(),
            rig.cage.num_vertices()
        );
        group.bench_function(BenchmarkId::new("mvc", &id), |b| {
            b.iter(|| compute_cage_coords(&rig.cage, &rig.mesh.positions, None).unwrap())
        });
        let parts = RigParts::new(
            rig.mesh.clone(),
            rig.skeleton.clone(),
            rig.skin_weights.clone(),
            rig.cage.clone(),
        );
        let (mut s, _) = RigSession::new(parts, SessionOptions::default()).unwrap();
        s.rotate_joint(1, DVec3::Z, 0.5).unwrap();
        s.rotate_joint(2, DVec3::Y, 0.3).unwrap();
        group.bench_function(BenchmarkId::new("cagerev_refactor", &id), |b| {
            b.iter(|| s.refactor_reverser().unwrap())
        });
        let mut sign = 1.0;
        group.bench_function(BenchmarkId::new("rest_cage_drag_2v", &id), |b| {
            b.iter(|| {
                sign = -sign;
                s.move_rest_cage(&[0, 1], &[DVec3::new(0.01 * sign, 0.0, 0.0)])
                    .unwrap()
            })
        });
        group.bench_function(BenchmarkId::new("posed_cage_grab_1v", &id), |b| {
            b.iter(|| {
                sign = -sign;
                s.move_posed_cage(&[2], &[DVec3::new(0.0, 0.01 * sign, 0.0)])
                    .unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, skinning, cage_ops);
criterion_main!(benches);
