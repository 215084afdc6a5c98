//! Building blocks shared by the straight-tube demo rigs: a closed tube mesh from a stack of
//! rings, a joint chain along +X, and smooth two-bone skinning weights along the chain.

use std::f64::consts::TAU;

use glam::{DAffine3, DVec3};

use crate::error::RigError;
use crate::mesh::TriMesh;
use crate::skeleton::{Joint, Skeleton};
use crate::skin_weights::SkinWeights;

/// How an end of a tube is closed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Cap {
    /// A fan of triangles around an extra vertex at this position (on the tube axis).
    Centre(DVec3),
    /// A fan from the ring's first vertex (no extra vertex; the ring must be convex and planar).
    Polygon,
}

/// A ring of `around` points at axial coordinate `x`: `(x, r cos θ_k, r sin θ_k)` with
/// `θ_k = phase + 2πk / around` (counter-clockwise seen from +X).
pub(crate) fn circle_ring(x: f64, radius: f64, around: usize, phase: f64) -> Vec<DVec3> {
    (0..around)
        .map(|k| {
            let theta = phase + TAU * k as f64 / around as f64;
            DVec3::new(x, radius * theta.cos(), radius * theta.sin())
        })
        .collect()
}

/// Closed, outward-oriented tube along +X through `rings` (each of the same length ≥ 3, ordered
/// counter-clockwise seen from +X, rings ordered by increasing x).
///
/// Vertex layout: ring `i`, point `k` is vertex `i·around + k`; the cap centres (if any) follow,
/// start cap first. Each quad between two rings is split along the diagonal (i,k+1)–(i+1,k).
pub(crate) fn tube_from_rings(rings: &[Vec<DVec3>], start: Cap, end: Cap) -> TriMesh {
    let around = rings[0].len();
    debug_assert!(around >= 3 && rings.len() >= 2);
    debug_assert!(rings.iter().all(|r| r.len() == around));
    let index = |ring: usize, k: usize| (ring * around + k % around) as u32;
    let mut positions: Vec<DVec3> = rings.iter().flatten().copied().collect();
    let mut triangles = Vec::with_capacity(2 * around * rings.len());
    for i in 0..rings.len() - 1 {
        for k in 0..around {
            let (a, b) = (index(i, k), index(i, k + 1));
            let (c, d) = (index(i + 1, k), index(i + 1, k + 1));
            // e_θ × e_x points radially outwards.
            triangles.push([a, b, c]);
            triangles.push([b, d, c]);
        }
    }
    let last = rings.len() - 1;
    for (ring, cap, outward_is_minus_x) in [(0, start, true), (last, end, false)] {
        match cap {
            Cap::Centre(centre) => {
                let c = positions.len() as u32;
                positions.push(centre);
                for k in 0..around {
                    let (p, q) = (index(ring, k), index(ring, k + 1));
                    triangles.push(if outward_is_minus_x {
                        [c, q, p]
                    } else {
                        [c, p, q]
                    });
                }
            }
            Cap::Polygon => {
                let first = index(ring, 0);
                for k in 1..around - 1 {
                    let (p, q) = (index(ring, k), index(ring, k + 1));
                    triangles.push(if outward_is_minus_x {
                        [first, q, p]
                    } else {
                        [first, p, q]
                    });
                }
            }
        }
    }
    TriMesh {
        positions,
        triangles,
    }
}

/// A chain of joints along +X named `{prefix}{j}`: joint `j` at `(joint_x[j], 0, 0)` with identity
/// rest rotation and parent `j − 1` (joint 0 is the root).
pub(crate) fn chain_skeleton(prefix: &str, joint_x: &[f64]) -> Result<Skeleton, RigError> {
    Skeleton::new(
        joint_x
            .iter()
            .enumerate()
            .map(|(j, &x)| Joint {
                name: format!("{prefix}{j}"),
                parent: j.checked_sub(1),
                rest_world_from_joint: DAffine3::from_translation(DVec3::new(x, 0.0, 0.0)),
            })
            .collect(),
    )
}

/// Cubic smoothstep `3t² − 2t³` of `t` clamped to [0, 1].
pub(crate) fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Skinning weights Ω (`#V × #J`) of a straight chain, a function of the axial coordinate `x` only.
///
/// Joint `j` owns bone `j` (from `joint_x[j]` to `joint_x[j+1]`; the last joint owns everything
/// beyond it, the root everything before it). Around every non-root joint `j` the weight blends
/// from joint `j − 1` to joint `j` with a smoothstep over `[x_j − h, x_j + h]` (`h = half_width`,
/// which must be below half the shortest bone), so each vertex has at most two influences and the
/// two weights are ½ exactly at the joint.
pub(crate) fn chain_weights(
    positions: &[DVec3],
    joint_x: &[f64],
    half_width: f64,
) -> Result<SkinWeights, RigError> {
    let mut triplets = Vec::with_capacity(2 * positions.len());
    for (v, p) in positions.iter().enumerate() {
        let x = p.x;
        // Owner: the last joint at or before x (the root for x before it).
        let owner = joint_x.iter().rposition(|&jx| jx <= x).unwrap_or(0);
        // The blend region of a joint can reach back into the previous bone.
        let blend = (1..joint_x.len()).find(|&j| (x - joint_x[j]).abs() < half_width);
        match blend {
            Some(j) => {
                let t = smoothstep((x - joint_x[j] + half_width) / (2.0 * half_width));
                if t < 1.0 {
                    triplets.push((v, j - 1, 1.0 - t));
                }
                if t > 0.0 {
                    triplets.push((v, j, t));
                }
            }
            None => triplets.push((v, owner, 1.0)),
        }
    }
    let (weights, _warnings) =
        SkinWeights::from_triplets(positions.len(), joint_x.len(), triplets)?;
    Ok(weights)
}

/// Deterministic pseudo-random number in [−1, 1] from an integer seed (SplitMix64).
pub(crate) fn hash_unit(seed: u64) -> f64 {
    let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothstep_endpoints_and_symmetry() {
        assert_eq!(smoothstep(-1.0), 0.0);
        assert_eq!(smoothstep(0.0), 0.0);
        assert_eq!(smoothstep(1.0), 1.0);
        assert_eq!(smoothstep(2.0), 1.0);
        assert!((smoothstep(0.5) - 0.5).abs() < 1e-15);
        for t in [0.1, 0.3, 0.45] {
            assert!((smoothstep(t) + smoothstep(1.0 - t) - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn chain_weights_blend_half_half_at_joints() {
        let joints = [0.0, 2.0, 4.0];
        let pts: Vec<DVec3> = [-1.0, 0.5, 2.0, 2.25, 3.5, 5.0]
            .iter()
            .map(|&x| DVec3::new(x, 0.3, 0.0))
            .collect();
        let w = chain_weights(&pts, &joints, 0.5).unwrap();
        assert_eq!(w.row(0).0, &[0]);
        assert_eq!(w.row(1).0, &[0]);
        assert!((w.get(2, 0) - 0.5).abs() < 1e-15 && (w.get(2, 1) - 0.5).abs() < 1e-15);
        // x = 2.25: t = 0.75 → smoothstep = 0.84375 on joint 1.
        assert!((w.get(3, 1) - 0.84375).abs() < 1e-15);
        assert!((w.get(4, 1) - 1.0).abs() < 1e-15);
        assert_eq!(w.row(5).0, &[2]);
        assert!(w.max_influences() <= 2);
    }

    #[test]
    fn hash_unit_is_in_range_and_deterministic() {
        let values: Vec<f64> = (0..1000).map(hash_unit).collect();
        assert!(values.iter().all(|v| (-1.0..1.0).contains(v)));
        assert_eq!(values[17], hash_unit(17));
        let mean = values.iter().sum::<f64>() / 1000.0;
        assert!(mean.abs() < 0.1);
        assert!(values.iter().any(|&v| v > 0.9) && values.iter().any(|&v| v < -0.9));
    }
}
