//! Static bounding-volume hierarchy over a triangle soup (axis-aligned boxes, median split on the
//! longest centroid axis, ≤ [`LEAF_SIZE`] triangles per leaf): nearest distance from a point,
//! "is any triangle within r of this triangle", and box-overlap enumeration.

use glam::DVec3;

use super::geometry::{
    Triangle, closest_point_on_triangle, separated_by_a_plane, triangle_triangle_distance,
};

/// Triangles per leaf.
const LEAF_SIZE: usize = 4;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Least corner (componentwise minimum).
    pub min: DVec3,
    /// Greatest corner (componentwise maximum).
    pub max: DVec3,
}

impl Aabb {
    /// The empty box (min = +∞, max = −∞): the identity of [`Aabb::union`].
    pub const EMPTY: Self = Self {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// The bounding box of triangle `t`.
    pub fn of_triangle(t: &Triangle) -> Self {
        Self {
            min: t[0].min(t[1]).min(t[2]),
            max: t[0].max(t[1]).max(t[2]),
        }
    }

    /// The smallest box containing both boxes.
    pub fn union(self, other: Self) -> Self {
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The box grown by `r` on every side.
    pub fn expanded(self, r: f64) -> Self {
        Self {
            min: self.min - DVec3::splat(r),
            max: self.max + DVec3::splat(r),
        }
    }

    /// Whether the two boxes intersect (touching counts).
    pub fn overlaps(&self, other: &Self) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    /// Whether `p` lies in the box (boundary included).
    pub fn contains(&self, p: DVec3) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    /// Squared distance from `p` to the box (0 inside).
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        let d = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        d.length_squared()
    }
}

/// An upper bound of the distance from any point of `t` to its nearest corner: the
/// circumradius, or 2/3 of the longest edge (a point Σλᵢpᵢ with λₖ ≥ 1/3 lies within
/// (1 − λₖ)·longest edge of pₖ), whichever is smaller.
pub fn covering_radius([a, b, c]: Triangle) -> f64 {
    let (ab, bc, ca) = (a.distance(b), b.distance(c), c.distance(a));
    let twice_area = (b - a).cross(c - a).length();
    let longest = ab.max(bc).max(ca);
    let circumradius = if twice_area > 0.0 {
        ab * bc * ca / (2.0 * twice_area)
    } else {
        f64::INFINITY
    };
    circumradius.min(2.0 / 3.0 * longest)
}

/// Separating axes of a triangle for box queries: its unit normal and the in-plane normals of
/// its edges, with the triangle's extent along each. Projections onto a unit axis never
/// lengthen distances, so a gap along any axis (or between bounding boxes) bounds the
/// box–triangle distance from below.
#[derive(Debug, Clone, Copy)]
struct SeparatingAxes {
    bounds: Aabb,
    axes: [DVec3; 4],
    /// Extent [min, max] of the triangle along each axis.
    extents: [(f64, f64); 4],
    /// Number of valid axes (0 for a degenerate triangle).
    count: usize,
}

impl SeparatingAxes {
    fn of_triangle(t: Triangle) -> Self {
        let mut out = Self {
            bounds: Aabb::of_triangle(&t),
            axes: [DVec3::ZERO; 4],
            extents: [(0.0, 0.0); 4],
            count: 0,
        };
        let Some(normal) = super::geometry::area_normal(t).try_normalize() else {
            return out;
        };
        out.axes[0] = normal;
        for k in 0..3 {
            if let Some(m) = normal.cross(t[(k + 1) % 3] - t[k]).try_normalize() {
                out.axes[1 + k] = m;
            }
        }
        for (axis, extent) in out.axes.iter().zip(&mut out.extents) {
            let d = t.map(|p| p.dot(*axis));
            *extent = (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]));
        }
        out.count = 4;
        out
    }

    /// Whether box `b` is certainly farther than `r` from the triangle.
    fn box_farther_than(&self, b: &Aabb, r: f64) -> bool {
        if !b.overlaps(&self.bounds.expanded(r)) {
            return true;
        }
        let centre = 0.5 * (b.min + b.max);
        let half = 0.5 * (b.max - b.min);
        self.axes[..self.count]
            .iter()
            .zip(&self.extents)
            .any(|(axis, &(lo, hi))| {
                let c = centre.dot(*axis);
                let radius = half.dot(axis.abs());
                c - radius > hi + r || c + radius < lo - r
            })
    }
}

#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Aabb,
    /// Leaf: first triangle in `order`; inner: index of the left child (right = left + 1).
    start: u32,
    /// Leaf: number of triangles (> 0); inner: 0.
    count: u32,
}

/// BVH over triangles given by corner positions (`#T`).
#[derive(Debug, Clone)]
pub struct TriangleBvh {
    nodes: Vec<Node>,
    /// Triangle corners in leaf order.
    triangles: Vec<Triangle>,
    /// Original index of each triangle in leaf order.
    order: Vec<u32>,
}

impl TriangleBvh {
    /// Builds the tree over `triangles` (any count, degenerate ones included).
    pub fn new(triangles: Vec<Triangle>) -> Self {
        let n = triangles.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let centroids: Vec<DVec3> = triangles
            .iter()
            .map(|t| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        let boxes: Vec<Aabb> = triangles.iter().map(Aabb::of_triangle).collect();
        let mut nodes = Vec::with_capacity(2 * n / LEAF_SIZE + 1);
        if n > 0 {
            nodes.push(Node {
                bounds: Aabb::EMPTY,
                start: 0,
                count: 0,
            });
            let mut stack = vec![(0usize, 0usize, n)];
            while let Some((node, start, end)) = stack.pop() {
                let bounds = order[start..end]
                    .iter()
                    .fold(Aabb::EMPTY, |b, &t| b.union(boxes[t as usize]));
                nodes[node].bounds = bounds;
                if end - start <= LEAF_SIZE {
                    nodes[node].start = start as u32;
                    nodes[node].count = (end - start) as u32;
                    continue;
                }
                let (lo, hi) = order[start..end].iter().fold(
                    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                    |(lo, hi), &t| (lo.min(centroids[t as usize]), hi.max(centroids[t as usize])),
                );
                let extent = hi - lo;
                let axis = if extent.x >= extent.y && extent.x >= extent.z {
                    0
                } else if extent.y >= extent.z {
                    1
                } else {
                    2
                };
                let mid = (start + end) / 2;
                order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
                    centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
                });
                let left = nodes.len();
                nodes[node].start = left as u32;
                nodes[node].count = 0;
                for _ in 0..2 {
                    nodes.push(Node {
                        bounds: Aabb::EMPTY,
                        start: 0,
                        count: 0,
                    });
                }
                stack.push((left, start, mid));
                stack.push((left + 1, mid, end));
            }
        }
        let triangles = order.iter().map(|&t| triangles[t as usize]).collect();
        Self {
            nodes,
            triangles,
            order,
        }
    }

    /// Whether the hierarchy holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Distance from `p` to the nearest triangle, or `cap` if none is closer than `cap`.
    pub fn nearest_distance(&self, p: DVec3, cap: f64) -> f64 {
        self.nearest(p, cap).map_or(cap, |(d, _)| d)
    }

    /// Nearest triangle (original index) to `p` and its distance, if one is closer than `cap`.
    pub fn nearest(&self, p: DVec3, cap: f64) -> Option<(f64, usize)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best2 = cap * cap;
        let mut best = None;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if node.bounds.distance_squared(p) >= best2 {
                continue;
            }
            if node.count > 0 {
                let range = node.start as usize..(node.start + node.count) as usize;
                for i in range {
                    let d2 = closest_point_on_triangle(p, self.triangles[i]).distance_squared(p);
                    if d2 < best2 {
                        best2 = d2;
                        best = Some(self.order[i] as usize);
                    }
                }
            } else {
                let (l, r) = (node.start as usize, node.start as usize + 1);
                let (dl, dr) = (
                    self.nodes[l].bounds.distance_squared(p),
                    self.nodes[r].bounds.distance_squared(p),
                );
                // Visit the nearer child first (pushed last).
                let (first, second) = if dl <= dr { (l, r) } else { (r, l) };
                if top + 2 <= stack.len() {
                    stack[top] = second as u32;
                    stack[top + 1] = first as u32;
                    top += 2;
                }
            }
        }
        best.map(|t| (best2.sqrt(), t))
    }

    /// Least distance from triangle `t` to the tree's triangles, or `cap` when none is closer
    /// than `cap`.
    pub fn triangle_distance(&self, t: Triangle, cap: f64) -> f64 {
        let mut best = cap;
        self.visit_near_triangle(t, cap, |other| {
            best = best.min(triangle_triangle_distance(t, other));
            best <= 0.0
        });
        best
    }

    /// Whether some triangle of the tree comes closer than `r` to triangle `t`.
    pub fn any_within(&self, t: Triangle, r: f64) -> bool {
        let mut found = false;
        let axes = SeparatingAxes::of_triangle(t);
        self.visit_near_triangle(t, r, |other| {
            found = !axes.box_farther_than(&Aabb::of_triangle(&other), r)
                && !separated_by_a_plane(t, other, r)
                && triangle_triangle_distance(t, other) < r;
            found
        });
        found
    }

    /// Whether triangle `t` stays at least `r` from every tree triangle, given its corners'
    /// distances to the tree (exact below `r`; above it any lower bound will do, e.g. the
    /// result of a [`Self::nearest_distance`] capped at ≥ `r`). Exact:
    /// * a corner closer than `r` proves it is not clear;
    /// * every point of the triangle lies within its [`covering_radius`] ρ of a corner, and the
    ///   distance is 1-Lipschitz, so it is clear when every corner is ≥ `r` + ρ away;
    /// * otherwise [`Self::any_within`] decides.
    pub fn clear_of(&self, t: Triangle, corner_distances: [f64; 3], r: f64) -> bool {
        let nearest_corner = corner_distances.into_iter().fold(f64::INFINITY, f64::min);
        if nearest_corner < r {
            return false;
        }
        if nearest_corner >= r + covering_radius(t) {
            return true;
        }
        !self.any_within(t, r)
    }

    /// Calls `visit` with every tree triangle whose box may come within `r` of `t` (by the
    /// separating axes of [`SeparatingAxes`]), until it returns `true`.
    fn visit_near_triangle(&self, t: Triangle, r: f64, mut visit: impl FnMut(Triangle) -> bool) {
        if self.nodes.is_empty() {
            return;
        }
        let axes = SeparatingAxes::of_triangle(t);
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if axes.box_farther_than(&node.bounds, r) {
                continue;
            }
            if node.count > 0 {
                for i in node.start as usize..(node.start + node.count) as usize {
                    if visit(self.triangles[i]) {
                        return;
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = node.start;
                stack[top + 1] = node.start + 1;
                top += 2;
            }
        }
    }

    /// Calls `visit(original index)` for every triangle whose box overlaps `query`.
    pub fn for_each_overlapping(&self, query: &Aabb, mut visit: impl FnMut(usize)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if !node.bounds.overlaps(query) {
                continue;
            }
            if node.count > 0 {
                for i in node.start as usize..(node.start + node.count) as usize {
                    if Aabb::of_triangle(&self.triangles[i]).overlaps(query) {
                        visit(self.order[i] as usize);
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = node.start;
                stack[top + 1] = node.start + 1;
                top += 2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cage_gen::geometry::point_triangle_distance;

    fn grid_triangles(n: usize) -> Vec<Triangle> {
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let p = DVec3::new(i as f64, j as f64, ((i * 7 + j * 3) % 5) as f64 * 0.1);
                out.push([p, p + DVec3::X, p + DVec3::Y]);
            }
        }
        out
    }

    #[test]
    fn nearest_matches_brute_force() {
        let tris = grid_triangles(12);
        let bvh = TriangleBvh::new(tris.clone());
        for k in 0..50 {
            let p = DVec3::new(
                (k * 37 % 130) as f64 * 0.1 - 0.5,
                (k * 53 % 127) as f64 * 0.1,
                (k % 7) as f64 * 0.3 - 1.0,
            );
            let brute = tris
                .iter()
                .map(|t| point_triangle_distance(p, *t))
                .fold(f64::INFINITY, f64::min);
            let (d, idx) = bvh.nearest(p, f64::INFINITY).unwrap();
            assert!((d - brute).abs() < 1e-12);
            assert!((point_triangle_distance(p, tris[idx]) - brute).abs() < 1e-12);
            assert_eq!(bvh.nearest_distance(p, brute * 0.5), brute * 0.5);
        }
    }

    #[test]
    fn covering_radius_bounds_the_distance_to_the_nearest_corner() {
        let triangles = [
            [DVec3::ZERO, DVec3::X, DVec3::Y],
            [DVec3::ZERO, DVec3::X * 4.0, DVec3::new(2.0, 0.1, 0.0)],
            [
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(0.5, 3f64.sqrt() / 2.0, 0.0),
            ],
            [DVec3::ZERO, DVec3::X, DVec3::X * 2.0],
        ];
        for t in triangles {
            let rho = covering_radius(t);
            for i in 0..=20 {
                for j in 0..=20 - i {
                    let (u, v) = (i as f64 / 20.0, j as f64 / 20.0);
                    let x = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
                    let nearest = t
                        .iter()
                        .map(|c| c.distance(x))
                        .fold(f64::INFINITY, f64::min);
                    assert!(nearest <= rho + 1e-12, "{t:?}: {nearest} > {rho}");
                }
            }
        }
        // Equilateral: the circumradius, reached at the centre.
        let rho = covering_radius(triangles[2]);
        assert!((rho - 1.0 / 3f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn triangle_queries_match_brute_force() {
        let tris = grid_triangles(8);
        let bvh = TriangleBvh::new(tris.clone());
        let probe = [
            DVec3::new(2.2, 3.1, 0.9),
            DVec3::new(5.0, 1.0, 1.4),
            DVec3::new(3.0, 6.0, 0.7),
        ];
        let brute = tris
            .iter()
            .map(|t| triangle_triangle_distance(probe, *t))
            .fold(f64::INFINITY, f64::min);
        assert!((bvh.triangle_distance(probe, 10.0) - brute).abs() < 1e-12);
        assert!(bvh.any_within(probe, brute * 1.01));
        assert!(!bvh.any_within(probe, brute * 0.99));
        let corners = probe.map(|p| bvh.nearest_distance(p, f64::INFINITY));
        assert!(!bvh.clear_of(probe, corners, brute * 1.01));
        assert!(bvh.clear_of(probe, corners, brute * 0.99));
        // Lower bounds above r are sound too.
        let capped = corners.map(|d| d.min(brute * 0.995));
        assert!(bvh.clear_of(probe, capped, brute * 0.99));
        let mut hits = Vec::new();
        let query = Aabb {
            min: DVec3::new(0.5, 0.5, -1.0),
            max: DVec3::new(1.5, 1.2, 1.0),
        };
        bvh.for_each_overlapping(&query, |i| hits.push(i));
        hits.sort();
        let expected: Vec<usize> = (0..tris.len())
            .filter(|&i| Aabb::of_triangle(&tris[i]).overlaps(&query))
            .collect();
        assert_eq!(hits, expected);
    }
}
