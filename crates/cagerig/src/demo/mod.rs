//! Built-in demo rigs generated procedurally: skin M, skeleton S, skinning weights Ω and cage C.
//!
//! | name            | what                                               | resolution                        |
//! |-----------------|----------------------------------------------------|-----------------------------------|
//! | `bar`           | Figure 5 bar, 4 joints, regular box cage (20 v)    | ring intervals along the bar (40) |
//! | `bar_irregular` | same bar, jittered non-uniform box cage (24 v)     | ring intervals along the bar (40) |
//! | `snake`         | tapered bulging tube, 16 joints, square-tube cage (70 v) | ≈ skin vertex count (8192)  |
//!
//! Every rig's skin is closed, watertight and outward oriented; its cage passes
//! [`validate_cage`](crate::cage::validate_cage) and encloses the skin strictly (margin ≥ 0.1);
//! every joint lies inside the skin; every row of Ω sums to 1 with at most two influences.
//! All rigs lie along +X with joint rest frames that have identity rotation.

pub mod bar;
pub mod bench_tracks;
pub mod snake;
mod tube;

use crate::cage::validate_cage;
use crate::error::RigError;
use crate::mesh::TriMesh;
use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;

/// A complete rest-pose rig: skin M (`#V`), skeleton S (`#J`), skinning weights Ω (`#V × #J`) and
/// cage C (`#C` vertices). Mean value coordinates Φ are not included (compute them from M and C).
#[derive(Debug, Clone, PartialEq)]
pub struct DemoRig {
    /// Name of the demo rig (one of [`builtin_names`]).
    pub name: String,
    /// Rest skin M.
    pub mesh: TriMesh,
    /// Rest skeleton S.
    pub skeleton: Skeleton,
    /// Skinning weights Ω, `#V × #J`.
    pub skin_weights: SkinWeights,
    /// Rest cage C (validated: closed, consistently and outward oriented).
    pub cage: TriMesh,
}

/// Names accepted by [`builtin`].
pub fn builtin_names() -> &'static [&'static str] {
    &["bar", "bar_irregular", "snake"]
}

/// Builds the demo rig `name` (see the module table for what `resolution` means; `None` = default).
pub fn builtin(name: &str, resolution: Option<usize>) -> Result<DemoRig, RigError> {
    // The one memory check of every front end (CLI, studio, Python) before a built-in rig at a
    // user-given resolution is built: a request the machine cannot hold is refused up front,
    // with what it would need.
    if builtin_names().contains(&name) {
        let (vertices, cage_vertices) = crate::memory_estimate::builtin_size(name, resolution);
        let what = match resolution {
            Some(r) => format!("the built-in rig {name:?} at resolution {r}"),
            None => format!("the built-in rig {name:?}"),
        };
        crate::memory_estimate::check_fits(&what, vertices, cage_vertices)?;
    }
    let mut rig = match name {
        "bar" => bar::bar(resolution)?,
        "bar_irregular" => bar::bar_irregular(resolution)?,
        "snake" => snake::snake(resolution)?,
        _ => {
            return Err(RigError::Invalid(format!(
                "unknown demo rig {name:?} (available: {})",
                builtin_names().join(", ")
            )));
        }
    };
    let (cage, _warnings) = validate_cage(std::mem::take(&mut rig.cage))?;
    rig.cage = cage;
    Ok(rig)
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use glam::DVec3;
    use rayon::prelude::*;

    use super::*;
    use crate::mesh::winding_number;

    /// Closest distance from `p` to triangle `abc` (Ericson, Real-Time Collision Detection 5.1.5).
    fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
        let (ab, ac, ap) = (b - a, c - a, p - a);
        let (d1, d2) = (ab.dot(ap), ac.dot(ap));
        if d1 <= 0.0 && d2 <= 0.0 {
            return p.distance(a);
        }
        let bp = p - b;
        let (d3, d4) = (ab.dot(bp), ac.dot(bp));
        if d3 >= 0.0 && d4 <= d3 {
            return p.distance(b);
        }
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return p.distance(a + ab * (d1 / (d1 - d3)));
        }
        let cp = p - c;
        let (d5, d6) = (ab.dot(cp), ac.dot(cp));
        if d6 >= 0.0 && d5 <= d6 {
            return p.distance(c);
        }
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return p.distance(a + ac * (d2 / (d2 - d6)));
        }
        let va = d3 * d6 - d5 * d4;
        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            return p.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
        }
        let denom = 1.0 / (va + vb + vc);
        p.distance(a + ab * (vb * denom) + ac * (vc * denom))
    }

    fn distance_to_mesh(mesh: &TriMesh, p: DVec3) -> f64 {
        (0..mesh.num_triangles())
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                point_triangle_distance(p, a, b, c)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Every undirected edge in exactly two triangles, traversed once in each direction.
    fn assert_closed_and_consistent(mesh: &TriMesh, what: &str) {
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for tri in &mesh.triangles {
            assert!(tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2]);
            for k in 0..3 {
                *directed.entry((tri[k], tri[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &directed {
            assert_eq!(
                count, 1,
                "{what}: directed edge ({a},{b}) used {count} times"
            );
            assert_eq!(
                directed.get(&(b, a)),
                Some(&1),
                "{what}: edge ({a},{b}) has no opposite half-edge"
            );
        }
        // Euler characteristic of a sphere.
        let edges = directed.len() / 2;
        let chi = mesh.num_vertices() as i64 - edges as i64 + mesh.num_triangles() as i64;
        assert_eq!(chi, 2, "{what}: Euler characteristic");
        // No unreferenced vertex.
        let mut used = vec![false; mesh.num_vertices()];
        mesh.triangles
            .iter()
            .flatten()
            .for_each(|&i| used[i as usize] = true);
        assert!(used.iter().all(|&u| u), "{what}: unreferenced vertex");
        assert!(mesh.signed_volume() > 0.0, "{what}: faces inwards");
    }

    fn check_rig(rig: &DemoRig, min_margin: f64, every_joint_weighted: bool) {
        let name = rig.name.as_str();
        assert_closed_and_consistent(&rig.mesh, name);
        assert_closed_and_consistent(&rig.cage, name);
        let (validated, warnings) = validate_cage(rig.cage.clone()).unwrap();
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        assert_eq!(validated, rig.cage);

        // Every skin vertex strictly inside the cage, away from its surface.
        let (cage_p, cage_t) = (&rig.cage.positions, &rig.cage.triangles);
        let worst = rig
            .mesh
            .positions
            .par_iter()
            .map(|&p| {
                let w = winding_number(cage_p, cage_t, p);
                assert!(
                    (w - 1.0).abs() < 1e-6,
                    "{name}: skin vertex {p} winding {w}"
                );
                distance_to_mesh(&rig.cage, p)
            })
            .reduce(|| f64::INFINITY, f64::min);
        assert!(worst >= min_margin, "{name}: skin-cage clearance {worst}");
        println!(
            "{name}: {} skin vertices, clearance {worst:.4}",
            rig.mesh.num_vertices()
        );
        // Every cage vertex outside the skin (so the surfaces do not cross at cage corners).
        for &c in cage_p {
            let w = winding_number(&rig.mesh.positions, &rig.mesh.triangles, c);
            assert!(
                w.abs() < 1e-6,
                "{name}: cage vertex {c} inside the skin ({w})"
            );
        }
        // Joints inside the skin.
        for (j, a) in rig.skeleton.rest_positions().into_iter().enumerate() {
            let w = winding_number(&rig.mesh.positions, &rig.mesh.triangles, a);
            assert!(
                (w - 1.0).abs() < 1e-6,
                "{name}: joint {j} at {a} winding {w}"
            );
        }
        // Ω: #V × #J, rows sum to 1, at most two influences, every joint used.
        let weights = &rig.skin_weights;
        assert_eq!(weights.num_vertices(), rig.mesh.num_vertices());
        assert_eq!(weights.num_joints(), rig.skeleton.len());
        assert!(weights.max_influences() <= 2);
        let mut used = vec![false; rig.skeleton.len()];
        for v in 0..weights.num_vertices() {
            let (joints, w) = weights.row(v);
            assert!(
                (w.iter().sum::<f64>() - 1.0).abs() < 1e-12,
                "{name}: row {v}"
            );
            assert!(w.iter().all(|&x| x > 0.0));
            if joints.len() == 2 {
                assert_eq!(joints[1], joints[0] + 1, "{name}: non-adjacent bones");
            }
            joints.iter().for_each(|&j| used[j as usize] = true);
        }
        if every_joint_weighted {
            assert!(used.iter().all(|&u| u), "{name}: a joint has no weights");
        }
        assert!(rig.mesh.positions.iter().all(|p| p.is_finite()));
    }

    #[test]
    fn all_builtins_validate_and_enclose() {
        for &name in builtin_names() {
            let rig = builtin(name, None).unwrap();
            assert_eq!(rig.name, name);
            check_rig(&rig, 0.1, true);
        }
        // Coarse and odd resolutions too (too coarse to sample every bone).
        check_rig(&builtin("bar", Some(1)).unwrap(), 0.1, false);
        check_rig(&builtin("bar_irregular", Some(7)).unwrap(), 0.1, false);
        check_rig(&builtin("snake", Some(50)).unwrap(), 0.1, false);
    }

    #[test]
    fn enclosure_check_detects_a_shrunken_cage() {
        let rig = builtin("snake", Some(2000)).unwrap();
        // Squeeze the cage towards the axis: 0.7 × 1.3 < 1, so it cuts through the bulges.
        let squeezed: Vec<DVec3> = rig
            .cage
            .positions
            .iter()
            .map(|p| DVec3::new(p.x, 0.7 * p.y, 0.7 * p.z))
            .collect();
        let outside = rig
            .mesh
            .positions
            .iter()
            .filter(|&&p| winding_number(&squeezed, &rig.cage.triangles, p) < 0.5)
            .count();
        assert!(outside > 100, "{outside}");
    }

    #[test]
    fn unknown_name_and_zero_resolution_are_errors() {
        let err = builtin("dragon", None).unwrap_err();
        assert!(err.to_string().contains("bar_irregular"), "{err}");
        for &name in builtin_names() {
            assert!(builtin(name, Some(0)).is_err());
        }
    }

    #[test]
    fn irregular_cage_differs_from_regular() {
        let regular = builtin("bar", None).unwrap().cage;
        let irregular = builtin("bar_irregular", None).unwrap().cage;
        assert_ne!(regular.num_vertices(), irregular.num_vertices());
        // Not a box: the side faces are not all axis-aligned.
        let tilted = irregular
            .triangles
            .iter()
            .enumerate()
            .filter(|(t, _)| {
                let [a, b, c] = irregular.corners(*t);
                let n = (b - a).cross(c - a).normalize();
                n.abs().max_element() < 0.999
            })
            .count();
        assert!(tilted > 20, "{tilted}");
    }

    #[test]
    fn snake_scales_to_130k_vertices() {
        let start = web_time::Instant::now();
        let rig = builtin("snake", Some(130_000)).unwrap();
        let elapsed = start.elapsed();
        let n = rig.mesh.num_vertices();
        assert!((n as f64 - 130_000.0).abs() < 200.0, "{n}");
        assert_eq!(rig.skin_weights.num_vertices(), n);
        println!(
            "snake 130k: {n} vertices, {} triangles in {elapsed:?}",
            rig.mesh.num_triangles()
        );
        check_rig(&rig, 0.1, true);
    }
}
