//! Screen-space picking: projecting points of a view, mouse rays, the nearest visible point
//! under the mouse, box selection, and occlusion by the skin.
//!
//! Pixel coordinates are the view's own (origin at its top-left corner, y down, in egui
//! points); the projection is the renderer's (`OrbitCamera::project`), so what is picked is
//! what is drawn.

use cagerig_render::OrbitCamera;
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// A camera looking into a `width × height` view.
#[derive(Debug, Clone, Copy)]
pub struct ViewProjection {
    pub camera: OrbitCamera,
    pub width: f64,
    pub height: f64,
}

impl ViewProjection {
    pub fn new(camera: OrbitCamera, width: f64, height: f64) -> Self {
        Self {
            camera,
            width: width.max(1.0),
            height: height.max(1.0),
        }
    }

    /// Pixel position of a world point (`None` behind the eye).
    pub fn project(&self, point: DVec3) -> Option<DVec2> {
        self.camera
            .project(point, self.width, self.height, 1.0)
            .map(|(x, y, _)| DVec2::new(x, y))
    }

    /// The ray through pixel `pixel`: origin at the eye, unit direction.
    pub fn ray(&self, pixel: DVec2) -> (DVec3, DVec3) {
        let (right, up) = self.camera.right_up();
        let forward = -self.camera.backward();
        let tan = (0.5 * self.camera.fov_y).tan();
        let aspect = self.width / self.height;
        let x = (pixel.x / self.width * 2.0 - 1.0) * tan * aspect;
        let y = (1.0 - pixel.y / self.height * 2.0) * tan;
        (
            self.camera.eye(),
            (forward + x * right + y * up).normalize(),
        )
    }

    /// World length of one pixel at the depth of `point`.
    pub fn world_per_pixel(&self, point: DVec3) -> f64 {
        let depth = (point - self.camera.eye())
            .dot(-self.camera.backward())
            .max(1e-9);
        2.0 * depth * (0.5 * self.camera.fov_y).tan() / self.height
    }
}

/// Skin triangles that can hide points (`positions` `#V`, `triangles` `#F`).
#[derive(Debug, Clone, Copy)]
pub struct Occluder<'a> {
    pub positions: &'a [DVec3],
    pub triangles: &'a [[u32; 3]],
}

/// Whether the open segment `from → to` crosses a triangle (Möller–Trumbore), ignoring hits
/// within `end_tolerance` of `to` (a point on the surface does not hide itself).
pub fn segment_blocked(from: DVec3, to: DVec3, occluder: Occluder<'_>, end_tolerance: f64) -> bool {
    let d = to - from;
    let length = d.length();
    if length <= end_tolerance {
        return false;
    }
    let dir = d / length;
    let t_max = length - end_tolerance;
    occluder.triangles.par_iter().with_min_len(4096).any(|t| {
        let [a, b, c] = t.map(|i| occluder.positions[i as usize]);
        ray_triangle(from, dir, a, b, c).is_some_and(|t| t > 1e-12 * length && t < t_max)
    })
}

/// Distance along the ray to triangle `abc`, if it is hit.
pub fn ray_triangle(origin: DVec3, dir: DVec3, a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let e1 = b - a;
    let e2 = c - a;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}

/// Whether `point` is hidden by the occluder seen from the view's eye.
pub fn is_occluded(view: &ViewProjection, point: DVec3, occluder: Option<Occluder<'_>>) -> bool {
    let Some(occluder) = occluder else {
        return false;
    };
    let eye = view.camera.eye();
    let tolerance = 1e-6 * eye.distance(point).max(1e-12);
    segment_blocked(eye, point, occluder, tolerance)
}

/// The point nearest to `mouse` on screen within `radius` pixels, occluded points excluded
/// (ties: the nearer one in depth).
pub fn pick_nearest(
    view: &ViewProjection,
    points: &[DVec3],
    mouse: DVec2,
    radius: f64,
    occluder: Option<Occluder<'_>>,
) -> Option<usize> {
    let mut candidates: Vec<(usize, f64, f64)> = points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let s = view.project(*p)?;
            let d = s.distance(mouse);
            (d <= radius).then(|| (i, d, p.distance(view.camera.eye())))
        })
        .collect();
    candidates.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.2.total_cmp(&b.2)));
    candidates
        .into_iter()
        .find(|&(i, _, _)| !is_occluded(view, points[i], occluder))
        .map(|(i, _, _)| i)
}

/// Visible points whose projection lies in the pixel box `[lo, hi]`.
pub fn pick_box(
    view: &ViewProjection,
    points: &[DVec3],
    lo: DVec2,
    hi: DVec2,
    occluder: Option<Occluder<'_>>,
) -> Vec<usize> {
    let (lo, hi) = (lo.min(hi), lo.max(hi));
    let inside: Vec<usize> = points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| {
            let s = view.project(*p)?;
            (s.cmpge(lo).all() && s.cmple(hi).all()).then_some(i)
        })
        .collect();
    inside
        .into_par_iter()
        .filter(|&i| !is_occluded(view, points[i], occluder))
        .collect()
}

/// The test fixture of the picking and gizmo tests: an eye at z = 10 looking at the origin.
#[cfg(test)]
pub(crate) fn test_view(width: f64, height: f64) -> ViewProjection {
    ViewProjection::new(
        OrbitCamera::looking_at(DVec3::new(0.0, 0.0, 10.0), DVec3::ZERO),
        width,
        height,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> ViewProjection {
        crate::picking::test_view(400.0, 300.0)
    }

    #[test]
    fn the_target_projects_to_the_centre_and_its_ray_goes_back_through_it() {
        let v = view();
        let c = v.project(DVec3::ZERO).unwrap();
        assert!((c - DVec2::new(200.0, 150.0)).length() < 1e-9);
        let p = DVec3::new(1.0, 0.5, -2.0);
        let s = v.project(p).unwrap();
        let (o, d) = v.ray(s);
        let closest = o + d * (p - o).dot(d);
        assert!(closest.distance(p) < 1e-9, "{closest} vs {p}");
    }

    #[test]
    fn one_pixel_at_the_target_matches_the_projection() {
        let v = view();
        let w = v.world_per_pixel(DVec3::ZERO);
        let a = v.project(DVec3::ZERO).unwrap();
        let b = v.project(DVec3::new(100.0 * w, 0.0, 0.0)).unwrap();
        assert!(((b - a).length() - 100.0).abs() < 1e-6);
    }

    /// A unit square in the plane z = 0 (two triangles).
    fn wall() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        (
            vec![
                DVec3::new(-1.0, -1.0, 0.0),
                DVec3::new(1.0, -1.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(-1.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn a_point_behind_a_wall_is_occluded_and_one_in_front_is_not() {
        let v = view();
        let (p, t) = wall();
        let occ = Some(Occluder {
            positions: &p,
            triangles: &t,
        });
        assert!(is_occluded(&v, DVec3::new(0.2, 0.1, -1.0), occ));
        assert!(!is_occluded(&v, DVec3::new(0.2, 0.1, 1.0), occ));
        // On the wall itself: not hidden by itself.
        assert!(!is_occluded(&v, DVec3::new(0.2, 0.1, 0.0), occ));
        // Beside the wall.
        assert!(!is_occluded(&v, DVec3::new(3.0, 0.0, -1.0), occ));
    }

    #[test]
    fn picking_takes_the_nearest_visible_point() {
        let v = view();
        let (p, t) = wall();
        let occ = Some(Occluder {
            positions: &p,
            triangles: &t,
        });
        let points = [DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.05, 0.0, 1.0)];
        let behind = v.project(points[0]).unwrap();
        // The hidden point is closer to the mouse but excluded.
        assert_eq!(pick_nearest(&v, &points, behind, 20.0, occ), Some(1));
        assert_eq!(pick_nearest(&v, &points, behind, 20.0, None), Some(0));
        assert_eq!(
            pick_nearest(&v, &points, DVec2::new(0.0, 0.0), 5.0, None),
            None
        );
    }

    #[test]
    fn box_selection_keeps_visible_points_inside_the_box() {
        let v = view();
        let (p, t) = wall();
        let occ = Some(Occluder {
            positions: &p,
            triangles: &t,
        });
        let points = [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(3.0, 2.0, 1.0),
        ];
        let mut got = pick_box(
            &v,
            &points,
            DVec2::new(150.0, 100.0),
            DVec2::new(250.0, 200.0),
            occ,
        );
        got.sort();
        assert_eq!(got, [0]);
    }
}
