//! Linear cage coordinates from outside the library, bound as `docs/architecture.md` ("A
//! coordinates kind", linear kinds) says: any Φ with a partition of unity that reproduces the rest
//! mesh (M = ΦC) is given in `RigParts::cage_coords`, and the session builds MaxVol, CageUp,
//! CageRev and SkelUp on it unchanged.
//!
//! The toy kind is *fan coordinates*: the cage is split into tetrahedra (c, a, b, d) joining its
//! centroid c = ΣC_k/#C to each triangle (a, b, d); a point p of the cone of (a, b, d) is
//! p − c = α(a − c) + β(b − c) + γ(d − c), so its row of Φ is α at a, β at b, γ at d, plus
//! (1 − α − β − γ)/#C at every cage vertex (the centroid's share). Exact on linear functions,
//! piecewise linear inside a cage star-shaped about its centroid (the built-in bar's box).

#![expect(clippy::unwrap_used)]

use cagerig::cage_coords::CageCoords;
use cagerig::demo;
use cagerig::mesh::TriMesh;
use cagerig::session::{RigParts, RigSession, SessionOptions};
use glam::{DMat3, DVec3};

/// Fan coordinates of `points` in `cage` (`#points × #C`).
fn fan_coordinates(cage: &TriMesh, points: &[DVec3]) -> CageCoords {
    let nc = cage.num_vertices();
    let centroid = cage.positions.iter().sum::<DVec3>() / nc as f64;
    let rows: Vec<Vec<f64>> = points
        .iter()
        .map(|&p| {
            // The triangle whose cone holds p best: the largest least coefficient.
            let (triangle, coefficients) = cage
                .triangles
                .iter()
                .filter_map(|&[a, b, d]| {
                    let [pa, pb, pd] = [a, b, d].map(|k| cage.positions[k as usize] - centroid);
                    let frame = DMat3::from_cols(pa, pb, pd);
                    (frame.determinant().abs() > 1e-12)
                        .then(|| ([a, b, d], frame.inverse() * (p - centroid)))
                })
                .max_by(|x, y| x.1.min_element().total_cmp(&y.1.min_element()))
                .unwrap();
            let centre_share = (1.0 - coefficients.element_sum()) / nc as f64;
            let mut row = vec![centre_share; nc];
            for (k, w) in triangle.iter().zip(coefficients.to_array()) {
                row[*k as usize] += w;
            }
            row
        })
        .collect();
    CageCoords::from_rows(&rows, nc).unwrap()
}

#[test]
fn fan_coordinates_bind_a_rig_and_keep_the_couplings_exact() {
    let rig = demo::builtin("bar", None).unwrap();
    let phi = fan_coordinates(&rig.cage, &rig.mesh.positions);
    let mut parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
    parts.cage_coords = Some(phi.clone());
    let (mut session, warnings) = RigSession::new(parts, SessionOptions::default()).unwrap();
    assert!(
        warnings
            .iter()
            .all(|w| !w.to_string().contains("recomputed")),
        "the toy's Φ reproduces M, so it is kept: {warnings:?}"
    );
    assert_eq!(session.cage_coords(), &phi, "the session binds the toy's Φ");
    let diagonal = {
        let points = session.rest_mesh();
        let lo = points.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
        let hi = points.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
        (hi - lo).length()
    };
    // Pose, then grab the current cage: the grabbed vertex lands, the others stay.
    session
        .rotate_joint(1, DVec3::Z, 40f64.to_radians())
        .unwrap();
    let before = session.posed_cage().to_vec();
    let offset = DVec3::new(0.0, 0.05, 0.02) * diagonal;
    session.move_posed_cage(&[3], &[offset]).unwrap();
    for (k, (now, was)) in session.posed_cage().iter().zip(&before).enumerate() {
        let expected = if k == 3 { *was + offset } else { *was };
        assert!(
            now.distance(expected) <= 1e-9 * diagonal,
            "C'[{k}] {now} against {expected}"
        );
    }
    // CageRev moved the rest cage, and the rest skin is the toy's map of it.
    let mut phi_c = vec![DVec3::ZERO; session.rest_mesh().len()];
    phi.apply(session.rest_cage(), &mut phi_c);
    let worst = phi_c
        .iter()
        .zip(session.rest_mesh())
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    assert!(worst <= 1e-9 * diagonal, "M = ΦC to {worst:e}");
}
