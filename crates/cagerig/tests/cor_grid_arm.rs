//! CoR centres in cage coordinates from the similarity tables (`cor_grid`) against the exact
//! Eq. 5 centres on the Arm: every vertex at N = 0, a sample at N = 2 midpoint subdivisions.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::collections::BTreeMap;
use std::path::Path;

use cagerig::SkinWeights;
use cagerig::coords::mvc::compute_cage_coords;
use cagerig::cor_centres::weight_similarity;
use cagerig::io::{read_obj, read_skt, read_skw};
use cagerig::mesh::bounding_box;
use cagerig::skinning::{CorGridOptions, compute_cor_cage_coords_grid};
use cagerig::subdivide::subdivide_midpoint;
use glam::DVec3;

const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm");

/// Per triangle of positive area: (α_t, v_t, ω_t joints, ω_t weights).
type TriangleData = (f64, DVec3, Vec<u32>, Vec<f64>);

fn triangle_data(rest: &[DVec3], tris: &[[u32; 3]], weights: &SkinWeights) -> Vec<TriangleData> {
    tris.iter()
        .filter_map(|&[a, b, c]| {
            let (pa, pb, pc) = (rest[a as usize], rest[b as usize], rest[c as usize]);
            let area = 0.5 * (pb - pa).cross(pc - pa).length();
            if area <= 0.0 {
                return None;
            }
            let mut row = BTreeMap::new();
            for v in [a, b, c] {
                let (js, ws) = weights.row(v as usize);
                for (&j, &w) in js.iter().zip(ws) {
                    *row.entry(j).or_insert(0.0) += w / 3.0;
                }
            }
            Some((
                area,
                (pa + pb + pc) / 3.0,
                row.keys().copied().collect(),
                row.values().copied().collect(),
            ))
        })
        .collect()
}

/// Exact Eq. 5 centre of vertex i (σ = 0.1), the rest position where it has none.
fn exact_centre(i: usize, rest: &[DVec3], weights: &SkinWeights, tris: &[TriangleData]) -> DVec3 {
    let (js, ws) = weights.row(i);
    let (mut num, mut den) = (DVec3::ZERO, 0.0);
    for (area, centroid, tj, tw) in tris {
        let s = weight_similarity(js, ws, tj, tw, 100.0) * area;
        num += s * *centroid;
        den += s;
    }
    if den > 0.0 { num / den } else { rest[i] }
}

/// (max, mean) centre error / bbox diagonal over `checked`, and max |Σ_c Λ_ic − 1| over all rows.
fn check(levels: usize, checked: impl Fn(usize) -> Vec<usize>) -> (f64, f64, f64) {
    let arm = Path::new(ARM);
    let mesh = read_obj(&arm.join("arm.obj")).unwrap();
    let cage = read_obj(&arm.join("arm_cage.obj")).unwrap();
    let skeleton = read_skt(&arm.join("arm.skt")).unwrap();
    let (weights, _) = read_skw(&arm.join("arm.skw"), mesh.num_vertices(), skeleton.len()).unwrap();
    let sub = subdivide_midpoint(&mesh, &weights, levels).unwrap();
    let (rest, tris, weights) = (sub.mesh.positions, sub.mesh.triangles, sub.skin_weights);
    let phi = compute_cage_coords(&cage, &rest, None).unwrap();
    let lambda = compute_cor_cage_coords_grid(
        &rest,
        &tris,
        &weights,
        &phi,
        &CorGridOptions::default(),
        &|_, _| {},
    )
    .unwrap();
    let mut centres = vec![DVec3::ZERO; rest.len()];
    lambda.apply(&cage.positions, &mut centres);
    let (lo, hi) = bounding_box(&rest);
    let diag = (hi - lo).length();
    let data = triangle_data(&rest, &tris, &weights);
    let errors: Vec<f64> = checked(rest.len())
        .into_iter()
        .map(|i| exact_centre(i, &rest, &weights, &data).distance(centres[i]) / diag)
        .collect();
    let unity = (0..rest.len())
        .map(|i| {
            let sum: f64 = (0..lambda.num_cage_vertices())
                .map(|k| lambda.get(i, k))
                .sum();
            (sum - 1.0).abs()
        })
        .fold(0.0, f64::max);
    (
        errors.iter().copied().fold(0.0, f64::max),
        errors.iter().sum::<f64>() / errors.len() as f64,
        unity,
    )
}

#[test]
fn grid_centres_match_exact_on_every_vertex_of_the_arm() {
    let (max, mean, unity) = check(0, |n| (0..n).collect());
    println!("Arm N=0, all vertices: max {max:.3e}, mean {mean:.3e} of bbox diagonal");
    assert!(max <= 1e-3, "max centre error {max:e} of bbox diagonal");
    assert!(unity <= 1e-9, "row sums off by {unity:e}");
}

#[test]
fn grid_centres_match_exact_on_sampled_vertices_of_the_subdivided_arm() {
    let (max, mean, unity) = check(2, |n| (0..300).map(|s| (s * 7919 * 13 + 17) % n).collect());
    println!("Arm N=2, 300 sampled vertices: max {max:.3e}, mean {mean:.3e} of bbox diagonal");
    assert!(max <= 1e-3, "max centre error {max:e} of bbox diagonal");
    assert!(unity <= 1e-9, "row sums off by {unity:e}");
}
