//! A long tapered tube with a bulging radius and 16 joints: the scalable benchmark rig.
//!
//! Geometry (world units):
//! - skin M: a tube along +X, x ∈ [0, 32], radius `r(x) = (1 + 0.3 sin(2πx/8))·(1 − ½(x/32)²)`
//!   (1 at the head, ≈0.39 at the last joint, 0.5·(1 + 0.3 sin 8π) = 0.5 at the tail), flat end
//!   caps fanned around a centre vertex;
//! - resolution = the requested vertex count `n` (default 8192): `around = max(8,
//!   round(√(n·2π·0.85/32)))` points per ring (square-ish quads for the mean radius 0.85) and
//!   `rings = max(2, round((n − 2)/around))`, so `#V = rings·around + 2 ≈ n` (within half a ring);
//! - skeleton S: 16 joints `snake0`…`snake15` at x = 0.2, 2, 4, …, 30, chained from the head;
//! - skinning weights Ω: joint j owns the bone starting at it, smoothstep blends over x_j ± 0.6;
//! - cage C: a coarse square tube (a diamond in cross-section: corners on ±Y and ±Z) with a
//!   ring at every joint but the root, x = −0.5, 2, 4, …, 30, 32.5, and centre-fanned end caps:
//!   70 vertices, 136 triangles. Each ring's inscribed radius is 1.15 × the largest skin radius
//!   over the two intervals next to it; since the cross-section of the cage between two aligned
//!   regular rings is a square with linearly interpolated radius, the cage clears the skin by at
//!   least 15 % of the local radius everywhere. A ring at each joint lets every bend happen at a
//!   ring, and four sides keep Green CageUp well conditioned: the snake's Green rig bends each
//!   joint to 60° about any axis (the octagonal cage with rings at every second joint of earlier
//!   versions folded at 10–18°; `docs/green-coordinates.md`).

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::DemoRig;
use super::tube::{Cap, chain_skeleton, chain_weights, circle_ring, tube_from_rings};
use crate::error::RigError;

/// Length of the snake along +X.
pub const SNAKE_LENGTH: f64 = 32.0;
/// Number of joints.
pub const SNAKE_JOINTS: usize = 16;
/// Default requested vertex count.
pub const SNAKE_DEFAULT_VERTICES: usize = 8192;
/// Largest accepted vertex count (keeps indices well inside u32 and memory reasonable).
pub const SNAKE_MAX_VERTICES: usize = 50_000_000;
/// Half-width of the smoothstep blend around each non-root joint.
pub const SNAKE_BLEND_HALF_WIDTH: f64 = 0.6;
/// Points per cage ring.
pub const SNAKE_CAGE_AROUND: usize = 4;
/// Cage inscribed radius / largest nearby skin radius.
pub const SNAKE_CAGE_RADIUS_FACTOR: f64 = 1.15;
/// How far the cage extends beyond each end of the snake.
pub const SNAKE_CAGE_END_MARGIN: f64 = 0.5;

/// Skin radius at axial coordinate `x` ∈ [0, 32].
pub fn snake_radius(x: f64) -> f64 {
    let s = x / SNAKE_LENGTH;
    (1.0 + 0.3 * (TAU * x / 8.0).sin()) * (1.0 - 0.5 * s * s)
}

/// Rest x of joint `j`: `2j`, except the root at 0.2 (just inside the head cap).
pub fn snake_joint_x() -> Vec<f64> {
    let spacing = SNAKE_LENGTH / SNAKE_JOINTS as f64;
    (0..SNAKE_JOINTS)
        .map(|j| spacing * j as f64 + if j == 0 { 0.1 * spacing } else { 0.0 })
        .collect()
}

/// `(rings, around)` of the skin for a requested vertex count.
pub fn snake_grid(vertices: usize) -> (usize, usize) {
    let mean_circumference = TAU * 0.85;
    let around = ((vertices as f64 * mean_circumference / SNAKE_LENGTH)
        .sqrt()
        .round() as usize)
        .max(8);
    let rings = ((vertices.saturating_sub(2) as f64 / around as f64).round() as usize).max(2);
    (rings, around)
}

/// Largest skin radius over `[a, b]` ∩ [0, 32] (dense sampling; r is smooth with |r'| < 0.3).
fn max_radius(a: f64, b: f64) -> f64 {
    let (a, b) = (a.max(0.0), b.min(SNAKE_LENGTH));
    const SAMPLES: usize = 256;
    (0..=SAMPLES)
        .map(|i| snake_radius(a + (b - a) * i as f64 / SAMPLES as f64))
        .fold(0.0, f64::max)
}

/// The snake with about `vertices` skin vertices (default 8192; see the module doc).
pub fn snake(vertices: Option<usize>) -> Result<DemoRig, RigError> {
    let requested = vertices.unwrap_or(SNAKE_DEFAULT_VERTICES);
    if requested == 0 || requested > SNAKE_MAX_VERTICES {
        return Err(RigError::Invalid(format!(
            "demo rig \"snake\": resolution (vertex count) must be in 1..={SNAKE_MAX_VERTICES}, got {requested}"
        )));
    }
    let (num_rings, around) = snake_grid(requested);
    let rings: Vec<Vec<DVec3>> = (0..num_rings)
        .map(|i| {
            let x = SNAKE_LENGTH * i as f64 / (num_rings - 1) as f64;
            circle_ring(x, snake_radius(x), around, 0.0)
        })
        .collect();
    let mesh = tube_from_rings(
        &rings,
        Cap::Centre(DVec3::ZERO),
        Cap::Centre(DVec3::new(SNAKE_LENGTH, 0.0, 0.0)),
    );
    let joint_x = snake_joint_x();
    let skeleton = chain_skeleton("snake", &joint_x)?;
    let skin_weights = chain_weights(&mesh.positions, &joint_x, SNAKE_BLEND_HALF_WIDTH)?;

    // Cage rings at every joint but the root, plus one beyond each end.
    let ring_step = SNAKE_LENGTH / SNAKE_JOINTS as f64;
    let inner = (SNAKE_LENGTH / ring_step).round() as usize;
    let mut cage_x = vec![-SNAKE_CAGE_END_MARGIN];
    cage_x.extend((1..inner).map(|i| ring_step * i as f64));
    cage_x.push(SNAKE_LENGTH + SNAKE_CAGE_END_MARGIN);
    let cage_rings: Vec<Vec<DVec3>> = (0..cage_x.len())
        .map(|i| {
            let before = cage_x[i.saturating_sub(1)];
            let after = cage_x[(i + 1).min(cage_x.len() - 1)];
            let inscribed = SNAKE_CAGE_RADIUS_FACTOR * max_radius(before, after);
            let circumradius = inscribed / (PI / SNAKE_CAGE_AROUND as f64).cos();
            circle_ring(cage_x[i], circumradius, SNAKE_CAGE_AROUND, 0.0)
        })
        .collect();
    let cage = tube_from_rings(
        &cage_rings,
        Cap::Centre(DVec3::new(cage_x[0], 0.0, 0.0)),
        Cap::Centre(DVec3::new(cage_x[cage_x.len() - 1], 0.0, 0.0)),
    );
    Ok(DemoRig {
        name: "snake".to_string(),
        mesh,
        skeleton,
        skin_weights,
        cage,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snake_counts_follow_the_requested_vertex_count() {
        for n in [100, 8192, 33_000, 130_000] {
            let (rings, around) = snake_grid(n);
            let v = rings * around + 2;
            assert!(
                (v as f64 - n as f64).abs() <= around as f64 / 2.0 + 1.0,
                "n = {n}: {v}"
            );
        }
        let rig = snake(Some(2000)).unwrap();
        let (rings, around) = snake_grid(2000);
        assert_eq!(rig.mesh.num_vertices(), rings * around + 2);
        assert_eq!(rig.cage.num_vertices(), 70);
        assert_eq!(rig.cage.num_triangles(), 136);
        assert_eq!(rig.skeleton.len(), 16);
        assert!(snake(Some(0)).is_err());
        assert!(snake(Some(SNAKE_MAX_VERTICES + 1)).is_err());
    }

    #[test]
    fn snake_radius_profile() {
        assert!((snake_radius(0.0) - 1.0).abs() < 1e-15);
        assert!((snake_radius(2.0) - 1.3 * (1.0 - 0.5 / 256.0)).abs() < 1e-12);
        assert!((snake_radius(32.0) - 0.5).abs() < 1e-12);
        let min = (0..=3200)
            .map(|i| snake_radius(i as f64 / 100.0))
            .fold(f64::INFINITY, f64::min);
        assert!(min > 0.3, "{min}");
    }
}
