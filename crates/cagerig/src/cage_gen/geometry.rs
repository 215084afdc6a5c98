//! Exact-arithmetic-free geometric predicates of cage generation: point/segment/triangle
//! distances (Ericson, *Real-Time Collision Detection*, 5.1.5 and 5.1.9), triangle–triangle
//! distance, the adjacency-aware self-intersection test of two cage triangles, solid angles.

use glam::DVec3;

/// Three corner positions of a triangle.
pub type Triangle = [DVec3; 3];

/// Closest point of triangle `abc` to `p` (Ericson 5.1.5, Voronoi regions of the corners/edges).
pub fn closest_point_on_triangle(p: DVec3, [a, b, c]: Triangle) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + v * ab;
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + w * ac;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + w * (c - b);
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE {
        // Degenerate (zero-area) triangle: closest of its three edges.
        let candidates = [
            closest_point_on_segment(p, a, b),
            closest_point_on_segment(p, b, c),
            closest_point_on_segment(p, a, c),
        ];
        return candidates
            .into_iter()
            .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
            .unwrap_or(a);
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

/// Distance from `p` to triangle `t`.
pub fn point_triangle_distance(p: DVec3, t: Triangle) -> f64 {
    p.distance(closest_point_on_triangle(p, t))
}

/// Closest point of segment `ab` to `p`.
pub fn closest_point_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= 0.0 {
        return a;
    }
    a + ab * ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
}

/// Squared distance between segments `p1q1` and `p2q2` (Ericson 5.1.9).
pub fn segment_segment_distance_squared(p1: DVec3, q1: DVec3, p2: DVec3, q2: DVec3) -> f64 {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let tiny = f64::MIN_POSITIVE;
    let (s, t);
    if a <= tiny && e <= tiny {
        return r.length_squared();
    }
    if a <= tiny {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(r);
        if e <= tiny {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > 0.0 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = s0;
            t = t0;
        }
    }
    (p1 + d1 * s).distance_squared(p2 + d2 * t)
}

/// Whether segment `pq` crosses the interior or boundary of triangle `t` (non-parallel case;
/// a segment lying in the triangle's plane is handled by the distance terms of
/// [`triangle_triangle_distance`]).
pub fn segment_crosses_triangle(p: DVec3, q: DVec3, [a, b, c]: Triangle) -> bool {
    let dir = q - p;
    let (e1, e2) = (b - a, c - a);
    let h = dir.cross(e2);
    let det = e1.dot(h);
    let scale = e1.length() * e2.length() * dir.length();
    if det.abs() <= 1e-14 * scale || scale == 0.0 {
        return false;
    }
    let inv = 1.0 / det;
    let s = p - a;
    let u = inv * s.dot(h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = s.cross(e1);
    let v = inv * dir.dot(qv);
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = inv * e2.dot(qv);
    (0.0..=1.0).contains(&t)
}

/// Distance between two triangles: 0 when they intersect, else the least of the 6 corner–triangle
/// and 9 edge–edge distances (the closest pair of two disjoint triangles always involves a corner
/// or two edges).
pub fn triangle_triangle_distance(t1: Triangle, t2: Triangle) -> f64 {
    for k in 0..3 {
        let (p, q) = (t1[k], t1[(k + 1) % 3]);
        if segment_crosses_triangle(p, q, t2) {
            return 0.0;
        }
        let (p, q) = (t2[k], t2[(k + 1) % 3]);
        if segment_crosses_triangle(p, q, t1) {
            return 0.0;
        }
    }
    let mut best2 = f64::INFINITY;
    for k in 0..3 {
        best2 = best2.min(closest_point_on_triangle(t1[k], t2).distance_squared(t1[k]));
        best2 = best2.min(closest_point_on_triangle(t2[k], t1).distance_squared(t2[k]));
        for l in 0..3 {
            best2 = best2.min(segment_segment_distance_squared(
                t1[k],
                t1[(k + 1) % 3],
                t2[l],
                t2[(l + 1) % 3],
            ));
        }
    }
    best2.sqrt()
}

/// Cheap sufficient test that two triangles are farther apart than `r`: all corners of one lie
/// more than `r` to one side of the other's plane.
pub fn separated_by_a_plane(t1: Triangle, t2: Triangle, r: f64) -> bool {
    let beyond = |plane: Triangle, other: Triangle| {
        let n = area_normal(plane);
        let len = n.length();
        if len <= 0.0 {
            return false;
        }
        let d = other.map(|p| (p - plane[0]).dot(n));
        let reach = r * len;
        (d[0] > reach && d[1] > reach && d[2] > reach)
            || (d[0] < -reach && d[1] < -reach && d[2] < -reach)
    };
    beyond(t1, t2) || beyond(t2, t1)
}

/// Distance from segment `pq` to triangle `t` (0 when it crosses it).
pub fn segment_triangle_distance(p: DVec3, q: DVec3, t: Triangle) -> f64 {
    if segment_crosses_triangle(p, q, t) {
        return 0.0;
    }
    let mut best2 = closest_point_on_triangle(p, t)
        .distance_squared(p)
        .min(closest_point_on_triangle(q, t).distance_squared(q));
    for k in 0..3 {
        best2 = best2.min(segment_segment_distance_squared(p, q, t[k], t[(k + 1) % 3]));
    }
    best2.sqrt()
}

/// Smallest angle (radians) between two triangles sharing the edge `ab`, whose third corners are
/// `c` and `d`: the angle between the components of `c − a` and `d − a` orthogonal to the edge.
/// 0 means the triangles fold onto each other.
pub fn fold_angle(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let axis = (b - a).normalize_or_zero();
    let pc = (c - a) - axis * (c - a).dot(axis);
    let pd = (d - a) - axis * (d - a).dot(axis);
    let cross = pc.cross(pd).length();
    cross.atan2(pc.dot(pd))
}

/// Sine of the angle below which two triangles sharing an edge or a corner count as touching
/// along it (folded onto each other).
pub const FOLD_SINE: f64 = 1e-4;

/// Whether two cage triangles (corner positions and vertex ids) intersect or come closer than
/// `separation` anywhere except along the corners or edge they legitimately share.
///
/// * no shared vertex: triangle–triangle distance < `separation`;
/// * one shared corner v: two such triangles can only meet along a segment from v, which leaves
///   one of them through its opposite edge (so that edge comes within `separation` of the other
///   triangle) or runs along an edge through v lying in the other's plane inside its wedge;
/// * a shared edge: their planes meet in the edge's line, so they overlap only when folded
///   ([`fold_angle`] ≈ 0);
/// * three shared vertices: the same triangle twice.
pub fn cage_triangles_conflict(
    t1: Triangle,
    ids1: [u32; 3],
    t2: Triangle,
    ids2: [u32; 3],
    separation: f64,
) -> bool {
    let mut shared = [(0usize, 0usize); 3];
    let mut count = 0;
    for (i, id1) in ids1.iter().enumerate() {
        for (j, id2) in ids2.iter().enumerate() {
            if id1 == id2 {
                shared[count] = (i, j);
                count += 1;
            }
        }
    }
    match count {
        0 => {
            !separated_by_a_plane(t1, t2, separation)
                && triangle_triangle_distance(t1, t2) < separation
        }
        1 => {
            let (i, j) = shared[0];
            let v = t1[i];
            let (p1, q1) = (t1[(i + 1) % 3], t1[(i + 2) % 3]);
            let (p2, q2) = (t2[(j + 1) % 3], t2[(j + 2) % 3]);
            if one_side_of_plane(v, area_normal(t1), p2, q2, separation)
                || one_side_of_plane(v, area_normal(t2), p1, q1, separation)
            {
                // One triangle meets the other's plane only at v.
                return false;
            }
            segment_triangle_distance(p1, q1, t2) < separation
                || segment_triangle_distance(p2, q2, t1) < separation
                || edge_in_wedge(v, p1, v, p2, q2)
                || edge_in_wedge(v, q1, v, p2, q2)
                || edge_in_wedge(v, p2, v, p1, q1)
                || edge_in_wedge(v, q2, v, p1, q1)
        }
        2 => {
            let (i0, _) = shared[0];
            let (i1, _) = shared[1];
            let c = t1[3 - i0 - i1];
            let d = (0..3)
                .find(|&j| ids2[j] != ids1[i0] && ids2[j] != ids1[i1])
                .map_or(t2[0], |j| t2[j]);
            fold_angle(t1[i0], t1[i1], c, d) < FOLD_SINE
        }
        _ => true,
    }
}

/// Whether `p` and `q` lie strictly on one side of the plane through `v` with normal `normal`:
/// farther than `separation` and at an angle above [`FOLD_SINE`] seen from `v`.
fn one_side_of_plane(v: DVec3, normal: DVec3, p: DVec3, q: DVec3, separation: f64) -> bool {
    let len = normal.length();
    if len <= 0.0 {
        return false;
    }
    let n = normal / len;
    let (dp, dq) = ((p - v).dot(n), (q - v).dot(n));
    let (mp, mq) = (
        FOLD_SINE * p.distance(v) + separation,
        FOLD_SINE * q.distance(v) + separation,
    );
    (dp > mp && dq > mq) || (dp < -mp && dq < -mq)
}

/// Whether the edge from `v` to `e` lies (within [`FOLD_SINE`]) in the plane of the wedge at `w`
/// spanned by `w→p` and `w→q`, pointing inside it (`v == w` is the shared corner).
fn edge_in_wedge(v: DVec3, e: DVec3, w: DVec3, p: DVec3, q: DVec3) -> bool {
    let dir = (e - v).normalize_or_zero();
    let (u1, u2) = ((p - w).normalize_or_zero(), (q - w).normalize_or_zero());
    let normal = u1.cross(u2);
    let normal_len = normal.length();
    if normal_len <= 0.0 || dir == DVec3::ZERO {
        return false;
    }
    let n = normal / normal_len;
    if dir.dot(n).abs() >= FOLD_SINE {
        return false;
    }
    // Inside the wedge: on the u2 side of u1 and the u1 side of u2, and not opposite.
    let s1 = u1.cross(dir).dot(n);
    let s2 = dir.cross(u2).dot(n);
    s1 >= -FOLD_SINE && s2 >= -FOLD_SINE && dir.dot(u1 + u2) > 0.0
}

/// Signed solid angle subtended by triangle `t` at `p` (Van Oosterom–Strackee), in steradians;
/// the winding number of a closed surface is the sum over its triangles divided by 4π.
pub fn solid_angle(p: DVec3, [a, b, c]: Triangle) -> f64 {
    let (va, vb, vc) = (a - p, b - p, c - p);
    let (la, lb, lc) = (va.length(), vb.length(), vc.length());
    let numerator = va.dot(vb.cross(vc));
    let denominator = la * lb * lc + va.dot(vb) * lc + va.dot(vc) * lb + vb.dot(vc) * la;
    2.0 * numerator.atan2(denominator)
}

/// Unnormalised normal (twice the area vector) of a triangle.
pub fn area_normal([a, b, c]: Triangle) -> DVec3 {
    (b - a).cross(c - a)
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: Triangle = [DVec3::ZERO, DVec3::X, DVec3::Y];

    #[test]
    fn point_distances_by_region() {
        assert!((point_triangle_distance(DVec3::new(0.2, 0.2, 2.0), T) - 2.0).abs() < 1e-15);
        assert!((point_triangle_distance(DVec3::new(-3.0, -4.0, 0.0), T) - 5.0).abs() < 1e-15);
        let d = point_triangle_distance(DVec3::new(1.0, 1.0, 0.0), T);
        assert!((d - 0.5f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn triangle_distances() {
        let lifted = T.map(|p| p + DVec3::new(0.0, 0.0, 0.5));
        assert!((triangle_triangle_distance(T, lifted) - 0.5).abs() < 1e-15);
        // A vertical triangle piercing T.
        let piercing = [
            DVec3::new(0.2, 0.2, -1.0),
            DVec3::new(0.2, 0.2, 1.0),
            DVec3::new(0.3, 0.25, 1.0),
        ];
        assert_eq!(triangle_triangle_distance(T, piercing), 0.0);
        // Edge–edge closest pair.
        let across = [
            DVec3::new(0.5, 0.5 + 0.3, -1.0),
            DVec3::new(0.5 + 0.3, 0.5, 1.0),
            DVec3::new(3.0, 3.0, 0.0),
        ];
        let d = triangle_triangle_distance(T, across);
        assert!((0.0..0.3).contains(&d), "{d}");
    }

    #[test]
    fn adjacent_conflicts() {
        // Shared edge, folded flat onto each other vs opened.
        let ids = [0, 1, 2];
        let folded = [DVec3::X, DVec3::ZERO, DVec3::new(0.3, 0.4, 0.0)];
        assert!(cage_triangles_conflict(T, ids, folded, [1, 0, 3], 1e-9));
        let open = [DVec3::X, DVec3::ZERO, DVec3::new(0.3, -0.4, 0.0)];
        assert!(!cage_triangles_conflict(T, ids, open, [1, 0, 3], 1e-9));
        // Shared corner, second triangle pierces the first from the corner.
        let pierce = [
            DVec3::ZERO,
            DVec3::new(0.5, 0.3, 0.2),
            DVec3::new(0.3, 0.5, -0.2),
        ];
        assert!(cage_triangles_conflict(T, ids, pierce, [0, 4, 5], 1e-9));
        let away = [
            DVec3::ZERO,
            DVec3::new(-0.5, 0.3, 0.2),
            DVec3::new(-0.3, -0.5, -0.2),
        ];
        assert!(!cage_triangles_conflict(T, ids, away, [0, 4, 5], 1e-9));
        // Shared corner, coplanar, second wedge inside the first.
        let inside = [
            DVec3::ZERO,
            DVec3::new(0.3, 0.1, 0.0),
            DVec3::new(0.1, 0.3, 0.0),
        ];
        assert!(cage_triangles_conflict(T, ids, inside, [0, 4, 5], 1e-9));
    }

    #[test]
    fn solid_angles_sum_to_winding() {
        // Unit tetrahedron, outward.
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let inside = DVec3::splat(0.1);
        let w: f64 = faces
            .iter()
            .map(|f: &[usize; 3]| solid_angle(inside, f.map(|i| p[i])))
            .sum::<f64>()
            / (4.0 * std::f64::consts::PI);
        assert!((w - 1.0).abs() < 1e-12);
    }
}
