//! The straight bar of the paper's Figure 5, with a regular and an irregular box cage.
//!
//! Geometry (world units):
//! - skin M: a round bar along +X, x ∈ [0, 10], radius 1, 24 points per ring, `segments` ring
//!   intervals along the length, flat end caps fanned around a centre vertex
//!   (`#V = 24·(segments + 1) + 2`);
//! - skeleton S: a chain of 4 joints `bar0`…`bar3` at x = 0.25, 2.5, 5, 7.5 (root `bar0` just
//!   inside the left cap so that every joint lies strictly inside M; the leaf `bar3` owns the last
//!   quarter of the bar);
//! - skinning weights Ω: joint j owns the bone that starts at it; around `bar1`…`bar3` the weight
//!   blends to the next joint with a smoothstep over x_j ± 0.75 (at most two influences per vertex);
//! - regular cage C: a box of half-width 1.3 around the bar, x ∈ [−0.5, 10.5], 4 equal segments
//!   (5 square rings: 20 vertices, 36 triangles);
//! - irregular cage: 5 unequal segments, every vertex jittered deterministically (angle, distance
//!   from the axis, and x for the inner rings): 24 vertices, 44 triangles. Both enclose M with a
//!   margin of at least 0.1.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, SQRT_2};

use glam::DVec3;

use super::DemoRig;
use super::tube::{Cap, chain_skeleton, chain_weights, circle_ring, hash_unit, tube_from_rings};
use crate::error::RigError;
use crate::mesh::TriMesh;

/// Length of the bar along +X.
pub const BAR_LENGTH: f64 = 10.0;
/// Radius of the bar's round cross-section.
pub const BAR_RADIUS: f64 = 1.0;
/// Points per ring of the skin.
pub const BAR_AROUND: usize = 24;
/// Default number of ring intervals along the bar.
pub const BAR_DEFAULT_SEGMENTS: usize = 40;
/// Rest positions (x) of the joints `bar0`…`bar3`.
pub const BAR_JOINT_X: [f64; 4] = [0.25, 2.5, 5.0, 7.5];
/// Half-width of the smoothstep blend around each non-root joint.
pub const BAR_BLEND_HALF_WIDTH: f64 = 0.75;
/// Half-width of the regular box cage's square cross-section.
pub const BAR_CAGE_HALF_WIDTH: f64 = 1.3;
/// How far the cage extends beyond each end of the bar.
pub const BAR_CAGE_END_MARGIN: f64 = 0.5;

/// The bar skin, skeleton and weights with `segments` ring intervals along the length.
fn bar_without_cage(name: &str, segments: usize) -> Result<DemoRig, RigError> {
    if segments == 0 {
        return Err(RigError::Invalid(format!(
            "demo rig {name:?}: resolution (segments along the bar) must be at least 1"
        )));
    }
    let rings: Vec<Vec<DVec3>> = (0..=segments)
        .map(|i| {
            let x = BAR_LENGTH * i as f64 / segments as f64;
            circle_ring(x, BAR_RADIUS, BAR_AROUND, 0.0)
        })
        .collect();
    let mesh = tube_from_rings(
        &rings,
        Cap::Centre(DVec3::ZERO),
        Cap::Centre(DVec3::new(BAR_LENGTH, 0.0, 0.0)),
    );
    let skeleton = chain_skeleton("bar", &BAR_JOINT_X)?;
    let skin_weights = chain_weights(&mesh.positions, &BAR_JOINT_X, BAR_BLEND_HALF_WIDTH)?;
    Ok(DemoRig {
        name: name.to_string(),
        mesh,
        skeleton,
        skin_weights,
        cage: TriMesh::default(),
    })
}

/// A square ring (corners at 45°, 135°, …) of half-width `half_width` at `x`.
fn square_ring(x: f64, half_width: f64) -> Vec<DVec3> {
    circle_ring(x, half_width * SQRT_2, 4, FRAC_PI_4)
}

/// The regular box cage: 4 equal segments, 20 vertices, 36 triangles.
pub fn regular_bar_cage() -> TriMesh {
    let (x0, x1) = (-BAR_CAGE_END_MARGIN, BAR_LENGTH + BAR_CAGE_END_MARGIN);
    let rings: Vec<Vec<DVec3>> = (0..=4)
        .map(|i| square_ring(x0 + (x1 - x0) * i as f64 / 4.0, BAR_CAGE_HALF_WIDTH))
        .collect();
    tube_from_rings(&rings, Cap::Polygon, Cap::Polygon)
}

/// The irregular box cage: 5 unequal segments, each vertex jittered deterministically.
pub fn irregular_bar_cage() -> TriMesh {
    const RING_X: [f64; 6] = [-0.6, 1.7, 4.6, 6.2, 8.9, 10.55];
    let last = RING_X.len() - 1;
    let rings: Vec<Vec<DVec3>> = RING_X
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            (0..4)
                .map(|k| {
                    let seed = 4 * i as u64 + k as u64;
                    let angle = FRAC_PI_4 + FRAC_PI_2 * k as f64 + 0.12 * hash_unit(3 * seed);
                    // Corner distance of a square of half-width 1.3 … 1.6.
                    let radius = SQRT_2 * (1.45 + 0.15 * hash_unit(3 * seed + 1));
                    // The end rings stay planar (flat caps); the inner ones wobble in x.
                    let dx = if i == 0 || i == last {
                        0.0
                    } else {
                        0.25 * hash_unit(3 * seed + 2)
                    };
                    DVec3::new(x + dx, radius * angle.cos(), radius * angle.sin())
                })
                .collect()
        })
        .collect();
    tube_from_rings(&rings, Cap::Polygon, Cap::Polygon)
}

/// The bar with its regular box cage; `segments` ring intervals along the length (default 40).
pub fn bar(segments: Option<usize>) -> Result<DemoRig, RigError> {
    let mut rig = bar_without_cage("bar", segments.unwrap_or(BAR_DEFAULT_SEGMENTS))?;
    rig.cage = regular_bar_cage();
    Ok(rig)
}

/// The bar with its irregular cage; `segments` ring intervals along the length (default 40).
pub fn bar_irregular(segments: Option<usize>) -> Result<DemoRig, RigError> {
    let mut rig = bar_without_cage("bar_irregular", segments.unwrap_or(BAR_DEFAULT_SEGMENTS))?;
    rig.cage = irregular_bar_cage();
    Ok(rig)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bar_counts() {
        let rig = bar(Some(8)).unwrap();
        assert_eq!(rig.mesh.num_vertices(), 24 * 9 + 2);
        assert_eq!(rig.mesh.num_triangles(), 2 * 24 * 8 + 2 * 24);
        assert_eq!(rig.cage.num_vertices(), 20);
        assert_eq!(rig.cage.num_triangles(), 36);
        let irregular = bar_irregular(None).unwrap();
        assert_eq!(irregular.cage.num_vertices(), 24);
        assert_eq!(irregular.cage.num_triangles(), 44);
        assert_eq!(irregular.mesh, bar(None).unwrap().mesh);
        assert!(bar(Some(0)).is_err());
    }

    #[test]
    fn bar_volume_close_to_cylinder() {
        // A 24-gon prism: area = ½·24·sin(2π/24)·r².
        let rig = bar(Some(4)).unwrap();
        let area = 0.5 * 24.0 * (std::f64::consts::TAU / 24.0).sin();
        assert!((rig.mesh.signed_volume() - area * BAR_LENGTH).abs() < 1e-9);
        let cage_volume = (2.0 * BAR_CAGE_HALF_WIDTH).powi(2) * (BAR_LENGTH + 1.0);
        assert!((rig.cage.signed_volume() - cage_volume).abs() < 1e-9);
    }

    #[test]
    fn bar_weights_follow_the_joints() {
        let rig = bar(Some(40)).unwrap();
        // Ring i is at x = i/4: ring 10 (x = 2.5) sits on bar1, ring 20 on bar2, ring 30 on bar3.
        for (ring, joint) in [(10, 1), (20, 2), (30, 3)] {
            let v = ring * BAR_AROUND;
            assert!((rig.skin_weights.get(v, joint - 1) - 0.5).abs() < 1e-12);
            assert!((rig.skin_weights.get(v, joint) - 0.5).abs() < 1e-12);
        }
        // x = 1.25 and x = 8.75 are rigid.
        assert_eq!(rig.skin_weights.row(5 * BAR_AROUND).1, &[1.0]);
        assert_eq!(rig.skin_weights.row(35 * BAR_AROUND).0, &[3]);
    }
}
