//! Midpoint subdivision of the Arm rig: 2089 → 33 289 (2 levels) → 133 073 (3 levels) vertices,
//! the sizes of the reference tool's "sub1"/"sub2" benchmarks.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::collections::HashSet;

use cagerig::subdivide::subdivide_midpoint;
use cagerig::{SkinWeights, TriMesh};

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;
use support::ARM;

/// `<joint> <meshVertex> <weight>` lines.
fn read_skw(path: &str, num_vertices: usize) -> SkinWeights {
    let text = std::fs::read_to_string(path).unwrap();
    let triplets: Vec<(usize, usize, f64)> = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let p: Vec<&str> = l.split_whitespace().collect();
            (
                p[1].parse().unwrap(),
                p[0].parse().unwrap(),
                p[2].parse().unwrap(),
            )
        })
        .collect();
    let num_joints = triplets.iter().map(|t| t.1).max().unwrap() + 1;
    SkinWeights::from_triplets(num_vertices, num_joints, triplets)
        .unwrap()
        .0
}

fn euler_characteristic(mesh: &TriMesh) -> i64 {
    let mut edges = HashSet::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    mesh.num_vertices() as i64 - edges.len() as i64 + mesh.num_triangles() as i64
}

#[test]
fn arm_subdivision_counts_weights_and_topology() {
    let mesh = support::mesh("arm.obj");
    assert_eq!((mesh.num_vertices(), mesh.num_triangles()), (2089, 4156));
    let weights = read_skw(&format!("{ARM}/arm.skw"), mesh.num_vertices());
    assert_eq!(weights.num_joints(), 25);
    let chi = euler_characteristic(&mesh);

    for (levels, expected) in [(1, 8333), (2, 33_289), (3, 133_073)] {
        let start = std::time::Instant::now();
        let sub = subdivide_midpoint(&mesh, &weights, levels).unwrap();
        println!(
            "Arm, {levels} level(s): {} vertices in {:?}",
            sub.mesh.num_vertices(),
            start.elapsed()
        );
        assert_eq!(sub.mesh.num_vertices(), expected);
        assert_eq!(sub.mesh.num_triangles(), 4156 << (2 * levels));
        assert_eq!(sub.skin_weights.num_vertices(), expected);
        assert_eq!(sub.edge_parents.len(), expected - 2089);
        assert_eq!(euler_characteristic(&sub.mesh), chi);
        assert_eq!(&sub.mesh.positions[..2089], &mesh.positions[..]);
        assert!(
            (sub.mesh.signed_volume() - mesh.signed_volume()).abs()
                < 1e-9 * mesh.signed_volume().abs().max(1.0)
        );
        for v in 0..expected {
            let (_, w) = sub.skin_weights.row(v);
            let sum: f64 = w.iter().sum();
            assert!((sum - 1.0).abs() < 1e-12, "vertex {v}: {sum}");
        }
        for v in 0..2089 {
            assert_eq!(sub.skin_weights.row(v), weights.row(v));
        }
    }
}
