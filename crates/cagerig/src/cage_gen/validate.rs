//! Public validator of a cage C for a mesh M: every guarantee of cage generation, checked
//! independently of how the cage was made (generated or hand-made; `cagerig info` runs it too).
//!
//! | check | how |
//! |---|---|
//! | `closed_manifold` | every edge in exactly two triangles, traversed once each way (so consistently oriented); one fan per vertex; no unused vertex, repeated-vertex or zero-area triangle |
//! | `outward` | positive enclosed volume |
//! | `one_piece` | triangles connected through edges |
//! | `no_self_intersection` | no two triangles intersect except along their shared corner or edge (cage BVH; [`cage_triangles_conflict`]) |
//! | `mesh_inside` | no mesh triangle meets the cage, and the winding number of each mesh piece is 1 (a piece that never meets the cage is wholly on one side); with crossings, every vertex's winding number is counted |
//! | `margin` | least mesh-vertex-to-cage distance ≥ the margin |
//! | `vertex_count` | within ±10 % of the target (when there is one) |
//! | `coordinates` | mean value coordinates Φ of all mesh vertices finite, ‖ΦC − M‖∞ ≤ 1e-9 · diagonal ([`check_coordinates`]) |

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Deserializer, Serialize};

use super::bvh::{Aabb, TriangleBvh};
use super::geometry::{Triangle, cage_triangles_conflict};
use super::weld::{piece_representatives, weld_by_position};
use crate::coords::maxvol::select_maxvol_rows;
use crate::coords::mvc::compute_cage_coords;
use crate::mesh::{TriMesh, winding_number};

/// Relative tolerance of `vertex_count`.
pub const VERTEX_COUNT_TOLERANCE: f64 = 0.1;
/// Largest ‖ΦC − M‖∞ accepted, × bbox diagonal of M.
pub const REPRODUCTION_TOLERANCE: f64 = 1e-9;
/// Triangles of the cage closer than this (× diagonal of M) count as intersecting.
pub const VALIDATION_SEPARATION: f64 = 1e-12;

/// What a cage must satisfy beyond the structural checks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CageRequirements {
    /// Least distance from every mesh vertex to the cage (absolute units).
    pub margin: f64,
    /// Target vertex count (±10 %), if any.
    pub target_vertices: Option<usize>,
    /// Target triangle count (±10 %), if any.
    pub target_faces: Option<usize>,
}

/// Name of the check of what a rig needs of a cage (`cage_source::rig_check`, which adds it to
/// the validator's report).
pub const RIG_CHECK: &str = "rig";

/// The name of every check a [`CageReport`] can hold: the validator's, and the rig's
/// ([`RIG_CHECK`]).
pub const CHECK_NAMES: [&str; 10] = [
    "closed_manifold",
    "no_degenerate_triangle",
    "outward",
    "one_piece",
    "no_self_intersection",
    "mesh_inside",
    "margin",
    "vertex_count",
    "coordinates",
    RIG_CHECK,
];

/// A check's name, one of [`CHECK_NAMES`] (an alias, so that serde does not borrow it from the
/// input it reads).
pub type CheckName = &'static str;

/// A check's name read back: the [`CHECK_NAMES`] entry it spells.
fn check_name<'de, D: Deserializer<'de>>(deserializer: D) -> Result<&'static str, D::Error> {
    let name = String::deserialize(deserializer)?;
    CHECK_NAMES
        .iter()
        .find(|known| **known == name)
        .copied()
        .ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown cage check {name:?} (expected one of {})",
                CHECK_NAMES.join(", ")
            ))
        })
}

/// One named check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    /// Name of the check (e.g. `closed_manifold`, see the module docs): one of [`CHECK_NAMES`].
    #[serde(deserialize_with = "check_name")]
    pub name: CheckName,
    /// Whether the cage passed it.
    pub passed: bool,
    /// What was measured or found (the first offender when it failed).
    pub detail: String,
}

/// Results of [`validate_cage_geometry`] (and [`check_coordinates`] when run).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CageReport {
    /// Every check run, in order.
    pub checks: Vec<Check>,
    /// Vertices `#C` of the cage.
    pub cage_vertices: usize,
    /// Triangles of the cage.
    pub cage_faces: usize,
    /// Bounding-box diagonal of the mesh (the unit of the fractions below).
    pub mesh_diagonal: f64,
    /// Least / mean distance of the mesh vertices to the cage, × 1/diagonal.
    pub min_distance_fraction: f64,
    /// Mean distance of the mesh vertices to the cage, × 1/diagonal.
    pub mean_distance_fraction: f64,
    /// Least distance between a mesh triangle and a cage triangle, × 1/diagonal.
    pub min_triangle_distance_fraction: f64,
    /// Cage volume / |mesh signed volume| (the latter is approximate for an open mesh).
    pub volume_ratio: f64,
    /// Smallest interior angle of any cage triangle, radians: needles (a few hundredths of a
    /// degree) make Green coordinates' stretched normals turn fast and CageUp ill-conditioned.
    pub min_triangle_angle: f64,
    /// ‖ΦC − M‖∞ × 1/diagonal, when coordinates were checked.
    pub reproduction_error_fraction: Option<f64>,
    /// 2-norm condition number of the MaxVol block Φ̃ (`#C × #C`), when computed.
    pub maxvol_condition: Option<f64>,
}

impl CageReport {
    /// Whether every check passed.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(|c| c.passed)
    }

    /// The failed checks as "name: detail" lines.
    pub fn failures(&self) -> Vec<String> {
        self.checks
            .iter()
            .filter(|c| !c.passed)
            .map(|c| format!("{}: {}", c.name, c.detail))
            .collect()
    }
}

/// Checks that `triangles` over `num_vertices` vertices form a closed, consistently oriented
/// 2-manifold with one fan per vertex and no unused vertex; `Err` names the first offender.
pub fn check_closed_manifold(triangles: &[[u32; 3]], num_vertices: usize) -> Result<(), String> {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * triangles.len());
    for (t, tri) in triangles.iter().enumerate() {
        if tri.iter().any(|&v| v as usize >= num_vertices) {
            return Err(format!("triangle {t} indexes a missing vertex"));
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return Err(format!("triangle {t} repeats a vertex"));
        }
        for k in 0..3 {
            let edge = (tri[k], tri[(k + 1) % 3]);
            if let Some(first) = directed.insert(edge, t) {
                return Err(format!(
                    "edge ({}, {}) is traversed in the same direction by triangles {first} and {t} (non-manifold or inconsistently oriented)",
                    edge.0, edge.1
                ));
            }
        }
    }
    for (&(a, b), &t) in &directed {
        if !directed.contains_key(&(b, a)) {
            return Err(format!(
                "edge ({a}, {b}) of triangle {t} has no opposite triangle (open boundary or inconsistent orientation)"
            ));
        }
    }
    // One fan per vertex: the link edges (next → previous corner) form a single cycle.
    let mut link: Vec<Vec<(u32, u32)>> = vec![Vec::new(); num_vertices];
    for tri in triangles {
        for k in 0..3 {
            link[tri[k] as usize].push((tri[(k + 1) % 3], tri[(k + 2) % 3]));
        }
    }
    for (v, edges) in link.iter().enumerate() {
        if edges.is_empty() {
            return Err(format!("vertex {v} belongs to no triangle"));
        }
        let next: HashMap<u32, u32> = edges.iter().copied().collect();
        let start = edges[0].0;
        let mut current = start;
        let mut steps = 0;
        loop {
            let Some(&n) = next.get(&current) else {
                return Err(format!("the triangles around vertex {v} do not close"));
            };
            current = n;
            steps += 1;
            if current == start || steps > edges.len() {
                break;
            }
        }
        if steps != edges.len() {
            return Err(format!(
                "vertex {v} is pinched: its {} triangles form more than one fan",
                edges.len()
            ));
        }
    }
    Ok(())
}

/// Number of edge-connected pieces of a triangle set.
pub fn count_pieces(triangles: &[[u32; 3]], num_vertices: usize) -> usize {
    let mut parent: Vec<u32> = (0..num_vertices as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for tri in triangles {
        for k in 1..3 {
            let (a, b) = (find(&mut parent, tri[0]), find(&mut parent, tri[k]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut used = vec![false; num_vertices];
    triangles
        .iter()
        .flatten()
        .for_each(|&v| used[v as usize] = true);
    (0..num_vertices)
        .filter(|&v| used[v] && find(&mut parent, v as u32) == v as u32)
        .count()
}

/// First pair of cage triangles that intersect or come closer than `separation` away from
/// their shared corners/edges.
pub fn find_self_intersection(cage: &TriMesh, separation: f64) -> Option<(usize, usize)> {
    let corners: Vec<Triangle> = (0..cage.num_triangles()).map(|t| cage.corners(t)).collect();
    let bvh = TriangleBvh::new(corners.clone());
    (0..corners.len()).into_par_iter().find_map_first(|i| {
        let query = Aabb::of_triangle(&corners[i]).expanded(separation);
        let mut hit = None;
        bvh.for_each_overlapping(&query, |j| {
            if hit.is_none()
                && j > i
                && cage_triangles_conflict(
                    corners[i],
                    cage.triangles[i],
                    corners[j],
                    cage.triangles[j],
                    separation,
                )
            {
                hit = Some(j);
            }
        });
        hit.map(|j| (i, j))
    })
}

fn diagonal(mesh: &TriMesh) -> f64 {
    let (lo, hi) = mesh.bounding_box();
    (hi - lo).length()
}

/// The mesh as BVH primitives: its triangles, plus isolated vertices as point triangles.
pub fn mesh_primitives(mesh: &TriMesh) -> Vec<Triangle> {
    let mut used = vec![false; mesh.num_vertices()];
    let mut prims: Vec<Triangle> = (0..mesh.num_triangles())
        .map(|t| {
            mesh.triangles[t]
                .iter()
                .for_each(|&v| used[v as usize] = true);
            mesh.corners(t)
        })
        .collect();
    for (v, u) in used.iter().enumerate() {
        if !u {
            let p = mesh.positions[v];
            prims.push([p, p, p]);
        }
    }
    prims
}

/// Runs every check except the coordinates (see module docs). `mesh` must have vertices.
pub fn validate_cage_geometry(
    cage: &TriMesh,
    mesh: &TriMesh,
    requirements: &CageRequirements,
) -> CageReport {
    let diag = diagonal(mesh).max(f64::MIN_POSITIVE);
    let mut checks = Vec::new();
    let manifold = check_closed_manifold(&cage.triangles, cage.num_vertices());
    let is_manifold = manifold.is_ok();
    checks.push(Check {
        name: "closed_manifold",
        passed: is_manifold,
        detail: manifold.err().unwrap_or_else(|| {
            "every edge in two triangles, consistently oriented, one fan per vertex".into()
        }),
    });
    let scale2 = diag * diag;
    if let Some(t) = (0..cage.num_triangles()).find(|&t| {
        let [a, b, c] = cage.corners(t);
        0.5 * (b - a).cross(c - a).length() <= 1e-14 * scale2
    }) {
        checks.push(Check {
            name: "no_degenerate_triangle",
            passed: false,
            detail: format!("cage triangle {t} has (almost) zero area"),
        });
    }
    let volume = cage.signed_volume();
    checks.push(Check {
        name: "outward",
        passed: volume > 0.0,
        detail: format!("enclosed volume {volume:.6e}"),
    });
    let pieces = count_pieces(&cage.triangles, cage.num_vertices());
    checks.push(Check {
        name: "one_piece",
        passed: pieces == 1,
        detail: format!("{pieces} piece(s)"),
    });
    let intersection = find_self_intersection(cage, VALIDATION_SEPARATION * diag);
    checks.push(Check {
        name: "no_self_intersection",
        passed: intersection.is_none(),
        detail: match intersection {
            Some((i, j)) => format!("cage triangles {i} and {j} intersect"),
            None => "no two cage triangles meet outside shared corners/edges".into(),
        },
    });
    // Distances of the mesh vertices and triangles to the cage.
    let cage_bvh = TriangleBvh::new((0..cage.num_triangles()).map(|t| cage.corners(t)).collect());
    let distances: Vec<f64> = mesh
        .positions
        .par_iter()
        .map(|&p| cage_bvh.nearest_distance(p, f64::INFINITY))
        .collect();
    let min_distance = distances.iter().copied().fold(f64::INFINITY, f64::min);
    let mean_distance = distances.iter().sum::<f64>() / distances.len().max(1) as f64;
    let prims = mesh_primitives(mesh);
    // Corner distances bound a triangle's: every point is within its longest edge of a corner,
    // so triangles whose corners are all farther than min_distance + longest edge need no test.
    let triangle_distances: Vec<f64> = (0..prims.len())
        .into_par_iter()
        .map(|i| {
            let t = prims[i];
            let near = if i < mesh.num_triangles() {
                mesh.triangles[i]
                    .iter()
                    .map(|&v| distances[v as usize])
                    .fold(f64::INFINITY, f64::min)
            } else {
                cage_bvh.nearest_distance(t[0], f64::INFINITY)
            };
            let longest = t[0]
                .distance(t[1])
                .max(t[1].distance(t[2]))
                .max(t[2].distance(t[0]));
            if near - longest > min_distance {
                near - longest
            } else {
                cage_bvh.triangle_distance(t, min_distance)
            }
        })
        .collect();
    let min_triangle_distance = triangle_distances
        .iter()
        .copied()
        .fold(min_distance, f64::min);
    let crossing = triangle_distances.iter().filter(|&&d| d <= 0.0).count();
    let winding = |p: DVec3| winding_number(&cage.positions, &cage.triangles, p);
    let outside_vertices = if crossing == 0 && is_manifold {
        let welded = weld_by_position(&mesh.positions, 0.0);
        let reps = piece_representatives(mesh.num_vertices(), &mesh.triangles, &welded);
        let bad: Vec<usize> = reps
            .par_iter()
            .copied()
            .filter(|&v| (winding(mesh.positions[v]) - 1.0).abs() > 1e-6)
            .collect();
        if bad.is_empty() {
            Ok(reps.len())
        } else {
            Err(format!(
                "{} of {} mesh pieces are not inside (winding number ≠ 1), e.g. the piece of vertex {}",
                bad.len(),
                reps.len(),
                bad[0]
            ))
        }
    } else {
        let bad = mesh
            .positions
            .par_iter()
            .filter(|&&p| (winding(p) - 1.0).abs() > 0.5)
            .count();
        Err(format!(
            "{crossing} mesh triangle(s) meet the cage; {bad} of {} vertices have winding number far from 1",
            mesh.num_vertices()
        ))
    };
    checks.push(Check {
        name: "mesh_inside",
        passed: outside_vertices.is_ok(),
        detail: match outside_vertices {
            Ok(pieces) => format!(
                "no mesh triangle meets the cage; all {pieces} mesh piece(s) have winding number 1"
            ),
            Err(e) => e,
        },
    });
    checks.push(Check {
        name: "margin",
        passed: min_distance >= requirements.margin,
        detail: format!(
            "least vertex distance {:.4} % of the diagonal (required ≥ {:.4} %)",
            100.0 * min_distance / diag,
            100.0 * requirements.margin / diag
        ),
    });
    for (target, found, what) in [
        (
            requirements.target_vertices,
            cage.num_vertices(),
            "vertices",
        ),
        (requirements.target_faces, cage.num_triangles(), "triangles"),
    ] {
        if let Some(target) = target {
            let off = (found as f64 - target as f64).abs() / target.max(1) as f64;
            checks.push(Check {
                name: "vertex_count",
                passed: off <= VERTEX_COUNT_TOLERANCE,
                detail: format!("{found} {what} for a target of {target} (±10 %)"),
            });
        }
    }
    let mesh_volume = mesh.signed_volume().abs();
    CageReport {
        checks,
        cage_vertices: cage.num_vertices(),
        cage_faces: cage.num_triangles(),
        mesh_diagonal: diag,
        min_distance_fraction: min_distance / diag,
        mean_distance_fraction: mean_distance / diag,
        min_triangle_distance_fraction: min_triangle_distance / diag,
        volume_ratio: if mesh_volume > 0.0 {
            volume / mesh_volume
        } else {
            f64::INFINITY
        },
        min_triangle_angle: min_triangle_angle(cage),
        reproduction_error_fraction: None,
        maxvol_condition: None,
    }
}

/// Smallest interior angle of the triangles of `cage`, radians (π for no triangle).
fn min_triangle_angle(cage: &TriMesh) -> f64 {
    (0..cage.num_triangles())
        .flat_map(|t| {
            let c = cage.corners(t);
            (0..3).map(move |k| {
                let (u, v) = (c[(k + 1) % 3] - c[k], c[(k + 2) % 3] - c[k]);
                u.cross(v).length().atan2(u.dot(v))
            })
        })
        .fold(std::f64::consts::PI, f64::min)
}

/// Adds the `coordinates` check to `report`: Φ = MVC of the mesh vertices w.r.t. the cage,
/// finite, with ‖ΦC − M‖∞ ≤ [`REPRODUCTION_TOLERANCE`] · diagonal; and the condition number of
/// the MaxVol block Φ̃ as a quality measure (`None` if MaxVol fails).
pub fn check_coordinates(cage: &TriMesh, mesh: &TriMesh, report: &mut CageReport) {
    let diag = report.mesh_diagonal;
    let phi = match compute_cage_coords(cage, &mesh.positions, None) {
        Ok(phi) => phi,
        Err(e) => {
            report.checks.push(Check {
                name: "coordinates",
                passed: false,
                detail: format!("mean value coordinates failed: {e}"),
            });
            return;
        }
    };
    let mut reproduced = vec![DVec3::ZERO; mesh.num_vertices()];
    phi.apply(&cage.positions, &mut reproduced);
    let error = reproduced
        .iter()
        .zip(&mesh.positions)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0, f64::max);
    let finite = reproduced.iter().all(|p| p.is_finite());
    report.reproduction_error_fraction = Some(error / diag);
    report.checks.push(Check {
        name: "coordinates",
        passed: finite && error <= REPRODUCTION_TOLERANCE * diag,
        detail: format!("Φ finite, ‖ΦC − M‖∞ = {:.2e} of the diagonal", error / diag),
    });
    if mesh.num_vertices() >= cage.num_vertices()
        && let Ok(selection) = select_maxvol_rows(&phi)
        && let Ok(sv) = phi.select_rows(&selection.rows).singular_values()
    {
        let (max, min) = sv.iter().fold((0.0f64, f64::INFINITY), |(hi, lo), &s| {
            (hi.max(s), lo.min(s))
        });
        report.maxvol_condition = Some(if min > 0.0 { max / min } else { f64::INFINITY });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(half: f64) -> TriMesh {
        TriMesh::cuboid(DVec3::splat(-half), DVec3::splat(half)).unwrap()
    }

    #[test]
    fn cube_in_cube_passes_and_defects_are_named() {
        let mesh = cube(1.0);
        let cage = cube(1.5);
        let req = CageRequirements {
            margin: 0.4,
            target_vertices: Some(8),
            target_faces: None,
        };
        let mut report = validate_cage_geometry(&cage, &mesh, &req);
        check_coordinates(&cage, &mesh, &mut report);
        assert!(report.passed(), "{:?}", report.failures());
        assert!((report.min_distance_fraction * report.mesh_diagonal - 0.5).abs() < 1e-12);
        assert!((report.volume_ratio - 3.375).abs() < 1e-12);
        // A cube's triangles are right isosceles: 45° at the acute corners.
        assert!((report.min_triangle_angle - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
        assert!(report.maxvol_condition.unwrap() >= 1.0);
        // Too small: the mesh crosses it.
        let small = validate_cage_geometry(&cube(0.9), &mesh, &req);
        let failed: Vec<_> = small
            .checks
            .iter()
            .filter(|c| !c.passed)
            .map(|c| c.name)
            .collect();
        assert!(
            failed.contains(&"mesh_inside") && failed.contains(&"margin"),
            "{failed:?}"
        );
        // Flipped.
        let mut flipped = cage.clone();
        flipped.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        let r = validate_cage_geometry(&flipped, &mesh, &req);
        assert!(r.checks.iter().any(|c| c.name == "outward" && !c.passed));
        // Two cubes: two pieces; one dented into the other: self-intersection.
        let mut two = cage.clone();
        let other = cube(0.3);
        two.positions
            .extend(other.positions.iter().map(|p| *p + DVec3::X * 1.4));
        two.triangles
            .extend(other.triangles.iter().map(|t| t.map(|v| v + 8)));
        let r = validate_cage_geometry(&two, &mesh, &req);
        let failed: Vec<_> = r
            .checks
            .iter()
            .filter(|c| !c.passed)
            .map(|c| c.name)
            .collect();
        assert!(failed.contains(&"one_piece"), "{failed:?}");
        assert!(failed.contains(&"no_self_intersection"), "{failed:?}");
        assert!(failed.contains(&"vertex_count"), "{failed:?}");
    }

    #[test]
    fn open_and_pinched_surfaces_are_not_manifold() {
        let cube = cube(1.0);
        let mut open = cube.triangles.clone();
        open.pop();
        assert!(
            check_closed_manifold(&open, 8)
                .unwrap_err()
                .contains("no opposite")
        );
        assert!(
            check_closed_manifold(&cube.triangles, 9)
                .unwrap_err()
                .contains("vertex 8")
        );
        // Two tetrahedra sharing one vertex: a pinched vertex.
        let tet = [[0u32, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let mut pinched: Vec<[u32; 3]> = tet.to_vec();
        pinched.extend(
            tet.iter()
                .map(|t| t.map(|v| if v == 0 { 0 } else { v + 3 })),
        );
        assert!(
            check_closed_manifold(&pinched, 7)
                .unwrap_err()
                .contains("pinched")
        );
    }
}
