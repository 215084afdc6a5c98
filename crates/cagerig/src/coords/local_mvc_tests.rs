//! Tests of [`super`] (`local_mvc.rs`), kept beside it to hold that file under ~600 lines.

use super::*;
use crate::coords::mvc::mean_value_coordinates;
use crate::coords::mvc::tests::icosphere;
use proptest::prelude::*;

/// Unnormalised weights of all vertices, summed and normalised, reproduce the MVC.
fn check_against_full(pos: &[DVec3], tris: &[[u32; 3]], x: DVec3) {
    let local = LocalMvc::new(pos, tris);
    let mut scratch = local.scratch();
    let all: Vec<usize> = (0..pos.len()).collect();
    let mut w = vec![0.0; pos.len()];
    let sign = local
        .weights_at(x, &all, &mut scratch, &mut w)
        .expect("regular point");
    let total: f64 = w.iter().sum();
    assert_eq!(sign, total.signum());
    let mut full = vec![0.0; pos.len()];
    mean_value_coordinates(pos, tris, x, &mut full);
    for (a, b) in w.iter().zip(&full) {
        assert!((a / total - b).abs() < 1e-12 * (1.0 + b.abs()), "{a} {b}");
    }
    // A subset gives bitwise the same weights and the same sign.
    let subset: Vec<usize> = (0..pos.len()).step_by(5).collect();
    let mut ws = vec![0.0; subset.len()];
    assert_eq!(
        local.weights_at(x, &subset, &mut scratch, &mut ws),
        Some(sign)
    );
    for (k, &v) in subset.iter().enumerate() {
        assert_eq!(ws[k], w[v]);
    }
    // The scratch is clean again.
    assert!(scratch.weight.iter().all(|v| *v == 0.0));
    assert!(scratch.evaluated.iter().all(|e| *e == 0));
}

#[test]
fn reproduces_full_mvc_inside_and_outside() {
    let radii: Vec<f64> = (0..42).map(|i| 1.0 + 0.1 * (i % 5) as f64).collect();
    let (pos, tris) = icosphere(&radii);
    for x in [
        DVec3::new(0.1, -0.2, 0.3),
        DVec3::new(0.0, 0.0, 0.95),
        DVec3::new(3.0, 1.0, -2.0),
        DVec3::new(0.0, 1.2, 0.1),
    ] {
        check_against_full(&pos, &tris, x);
    }
}

#[test]
fn sign_is_positive_inside_negative_outside() {
    // A long tube of many small triangles: most clusters are bounded, not evaluated.
    let (pos, tris) = tube(200, 24, 0.5, 0.05);
    let local = LocalMvc::new(&pos, &tris);
    let mut scratch = local.scratch();
    let vertices = vec![100 * 24 + 3, 100 * 24 + 4];
    let mut w = vec![0.0; 2];
    let inside = DVec3::new(0.1, 0.0, 5.0);
    assert_eq!(
        local.weights_at(inside, &vertices, &mut scratch, &mut w),
        Some(1.0)
    );
    assert!(w.iter().all(|v| *v > 0.0));
    let evaluated_inside = count_work(&local, inside, &vertices);
    assert!(
        evaluated_inside < tris.len() / 2,
        "{evaluated_inside} of {}",
        tris.len()
    );
    let outside = DVec3::new(1.5, 0.0, 5.0);
    assert_eq!(
        local.weights_at(outside, &vertices, &mut scratch, &mut w),
        Some(-1.0)
    );
    // Outside, W < 0: the full (normalised) coordinates are w / W.
    let mut full = vec![0.0; pos.len()];
    mean_value_coordinates(&pos, &tris, outside, &mut full);
    let ratio = w[0] / full[vertices[0]];
    assert!(ratio < 0.0);
    assert!((w[1] / full[vertices[1]] - ratio).abs() < 1e-9 * ratio.abs());
}

#[test]
fn degenerate_points_need_the_full_function() {
    let (pos, tris) = icosphere(&[1.0]);
    let local = LocalMvc::new(&pos, &tris);
    let mut scratch = local.scratch();
    let mut w = vec![0.0; 1];
    let face = tris[7].map(|i| pos[i as usize]);
    for x in [
        pos[3],
        0.5 * (face[0] + face[1]),
        (face[0] + face[1] + face[2]) / 3.0,
    ] {
        // Far from the requested vertex too: found through the near clusters.
        assert_eq!(local.weights_at(x, &[41], &mut scratch, &mut w), None);
    }
}

#[test]
fn open_mesh_seen_from_its_hole_is_uncertain_or_right() {
    // A hemisphere-like open cap: W changes sign across the hole; wherever a sign is
    // returned it must be that of the full sum.
    let (pos, tris) = icosphere(&[1.0]);
    let open: Vec<[u32; 3]> = tris
        .iter()
        .copied()
        .filter(|t| t.iter().any(|&i| pos[i as usize].z > 0.0))
        .collect();
    let local = LocalMvc::new(&pos, &open);
    let mut scratch = local.scratch();
    let all: Vec<usize> = (0..pos.len()).collect();
    let mut w = vec![0.0; pos.len()];
    for k in 0..40 {
        let x = DVec3::new(0.1, 0.05, -1.5 + 0.05 * k as f64);
        if let Some(sign) = local.weights_at(x, &all, &mut scratch, &mut w) {
            let total: f64 = w.iter().sum();
            assert_eq!(sign, total.signum(), "x = {x}");
        }
    }
}

#[test]
fn triangle_contribution_is_bounded_by_area_over_distance_cubed() {
    let mut worst: f64 = 0.0;
    for i in 0..2000 {
        let f = i as f64;
        let p = [
            DVec3::new((f * 0.37).sin(), (f * 0.73).cos(), (f * 0.11).sin()),
            DVec3::new((f * 0.19).cos(), (f * 0.53).sin(), (f * 0.97).cos()),
            DVec3::new((f * 0.61).sin(), (f * 0.29).sin(), (f * 0.43).cos()),
        ];
        let x = DVec3::new((f * 1.3).sin(), (f * 2.1).cos(), (f * 0.7).sin()) * 2.0;
        let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        let dist = distance_to_triangle(x, p);
        if let TriangleWeights::Add(w) = mvc::triangle_weights(&p, [0, 1, 2], x) {
            let c = (w[0] + w[1] + w[2]).abs();
            worst = worst.max(c * dist.powi(3) / area);
        }
    }
    assert!(worst <= 1.0, "{worst}");
    assert!(worst > 0.1, "the bound should be reasonably tight: {worst}");
}

proptest! {
    #[test]
    fn subset_weights_match_full_mvc(
        radii in proptest::collection::vec(0.5f64..2.0, 42),
        dir in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        t in 0.0f64..3.0,
    ) {
        let (pos, tris) = icosphere(&radii);
        let d = DVec3::new(dir.0, dir.1, dir.2);
        prop_assume!(d.length() > 1e-3);
        let x = d.normalize() * t;
        let local = LocalMvc::new(&pos, &tris);
        let mut scratch = local.scratch();
        let subset: Vec<usize> = (0..pos.len()).step_by(3).collect();
        let mut w = vec![0.0; subset.len()];
        let mut full = vec![0.0; pos.len()];
        mean_value_coordinates(&pos, &tris, x, &mut full);
        if let Some(sign) = local.weights_at(x, &subset, &mut scratch, &mut w) {
            // Same direction as the normalised coordinates: w · sign = |W| · mvc.
            let scale = subset.iter().zip(&w).map(|(&v, wk)| wk * sign * full[v]).sum::<f64>();
            prop_assert!(scale > 0.0);
            let norm = w.iter().map(|v| v * v).sum::<f64>();
            let factor = norm / scale; // |W|
            for (k, &v) in subset.iter().enumerate() {
                prop_assert!((w[k] * sign - factor * full[v]).abs() <= 1e-9 * norm.sqrt());
            }
        }
    }
}

fn count_work(local: &LocalMvc, x: DVec3, vertices: &[usize]) -> usize {
    let mut scratch = local.scratch();
    let mut w = vec![0.0; vertices.len()];
    assert!(!local.snapped(x, &mut scratch));
    local.certified_weights(x, vertices, &mut scratch, &mut w);
    scratch
        .evaluated
        .iter()
        .map(|w| w.count_ones() as usize)
        .sum()
}

/// Closed tube along z: `rings × segments` vertices of radius `radius`, ring spacing `step`,
/// capped by two fans.
fn tube(rings: usize, segments: usize, radius: f64, step: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut pos = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let a = std::f64::consts::TAU * s as f64 / segments as f64;
            pos.push(DVec3::new(
                radius * a.cos(),
                radius * a.sin(),
                step * r as f64,
            ));
        }
    }
    let bottom = pos.len() as u32;
    pos.push(DVec3::ZERO);
    let top = pos.len() as u32;
    pos.push(DVec3::new(0.0, 0.0, step * (rings - 1) as f64));
    let id = |r: usize, s: usize| (r * segments + s % segments) as u32;
    let mut tris = Vec::new();
    for r in 0..rings - 1 {
        for s in 0..segments {
            tris.push([id(r, s), id(r, s + 1), id(r + 1, s + 1)]);
            tris.push([id(r, s), id(r + 1, s + 1), id(r + 1, s)]);
        }
    }
    for s in 0..segments {
        tris.push([bottom, id(0, s + 1), id(0, s)]);
        tris.push([top, id(rings - 1, s), id(rings - 1, s + 1)]);
    }
    (pos, tris)
}

/// Euclidean distance from x to a triangle (closest point by regions, Ericson's method).
fn distance_to_triangle(x: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, x - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return x.distance(a);
    }
    let bp = x - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return x.distance(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return x.distance(a + ab * (d1 / (d1 - d3)));
    }
    let cp = x - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return x.distance(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return x.distance(a + ac * (d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return x.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denom = 1.0 / (va + vb + vc);
    x.distance(a + ab * (vb * denom) + ac * (vc * denom))
}
