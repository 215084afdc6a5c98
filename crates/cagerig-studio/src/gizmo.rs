//! The transform gizmo, drawn by us (no gizmo crate supports egui 0.37): the maths of dragging
//! along an axis, in a plane or freely in the view plane, of turning a ring or a trackball,
//! and of scaling; plus the handles' screen geometry for hit testing and drawing.

use glam::{DQuat, DVec2, DVec3};

use crate::picking::ViewProjection;

/// Length of the axis arrows, in pixels.
pub const ARROW_PIXELS: f64 = 90.0;
/// Radius of the rotation rings, in pixels.
pub const RING_PIXELS: f64 = 70.0;
/// How close (pixels) the mouse must be to grab a handle.
pub const GRAB_PIXELS: f64 = 7.0;

/// A world axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    pub fn vector(self) -> DVec3 {
        match self {
            Axis::X => DVec3::X,
            Axis::Y => DVec3::Y,
            Axis::Z => DVec3::Z,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "X",
            Axis::Y => "Y",
            Axis::Z => "Z",
        }
    }
}

/// How a drag is constrained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Constraint {
    /// Free: in the view plane (grab), about the view axis (rotate), uniform (scale).
    #[default]
    Free,
    /// Along / about / scaling one axis.
    Axis(Axis),
    /// In the plane normal to an axis (grab), or scaling the other two axes.
    Plane(Axis),
}

/// A gizmo handle under the mouse.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Handle {
    Arrow(Axis),
    Ring(Axis),
    /// The square between the two other arrows: moves (scales) in the plane normal to the axis.
    Plane(Axis),
}

/// Intersection of a ray with the plane through `point` with normal `normal`.
fn ray_plane(origin: DVec3, dir: DVec3, point: DVec3, normal: DVec3) -> Option<DVec3> {
    let denom = dir.dot(normal);
    if denom.abs() < 1e-12 {
        return None;
    }
    let t = (point - origin).dot(normal) / denom;
    Some(origin + t * dir)
}

/// Parameter along the line `point + s·axis` of its closest point to the ray.
fn closest_on_line(origin: DVec3, dir: DVec3, point: DVec3, axis: DVec3) -> Option<f64> {
    // Minimise |point + s·axis − (origin + t·dir)|.
    let w = point - origin;
    let a = axis.dot(axis);
    let b = axis.dot(dir);
    let c = dir.dot(dir);
    let d = axis.dot(w);
    let e = dir.dot(w);
    let denom = a * c - b * b;
    if denom.abs() < 1e-12 {
        return None;
    }
    Some((b * e - c * d) / denom)
}

/// World translation of a drag from pixel `start` to `now` of something at `pivot`.
pub fn drag_translation(
    view: &ViewProjection,
    pivot: DVec3,
    constraint: Constraint,
    start: DVec2,
    now: DVec2,
) -> DVec3 {
    let (o0, d0) = view.ray(start);
    let (o1, d1) = view.ray(now);
    match constraint {
        Constraint::Axis(axis) => {
            let a = axis.vector();
            // Project the mouse onto the axis as drawn on screen first, so that moving across
            // the axis does nothing (as in Blender); then the rays meet the axis exactly.
            let on_axis = |m: DVec2| -> DVec2 {
                match (
                    view.project(pivot),
                    view.project(pivot + a * view.world_per_pixel(pivot)),
                ) {
                    (Some(s0), Some(s1)) if s0.distance(s1) > 1e-9 => {
                        let u = (s1 - s0).normalize();
                        s0 + (m - s0).dot(u) * u
                    }
                    _ => m,
                }
            };
            let (o0, d0) = view.ray(on_axis(start));
            let (o1, d1) = view.ray(on_axis(now));
            match (
                closest_on_line(o0, d0, pivot, a),
                closest_on_line(o1, d1, pivot, a),
            ) {
                (Some(s0), Some(s1)) => (s1 - s0) * a,
                _ => DVec3::ZERO,
            }
        }
        Constraint::Plane(axis) => plane_delta(o0, d0, o1, d1, pivot, axis.vector()),
        Constraint::Free => plane_delta(o0, d0, o1, d1, pivot, view.camera.backward()),
    }
}

fn plane_delta(o0: DVec3, d0: DVec3, o1: DVec3, d1: DVec3, pivot: DVec3, n: DVec3) -> DVec3 {
    match (ray_plane(o0, d0, pivot, n), ray_plane(o1, d1, pivot, n)) {
        (Some(a), Some(b)) => b - a,
        _ => DVec3::ZERO,
    }
}

/// Angle (radians, right-handed about `axis`) of a drag from `start` to `now` turning around
/// the projected pivot: a counter-clockwise turn on screen is positive about an axis that
/// points at the viewer.
pub fn drag_rotation_angle(
    view: &ViewProjection,
    pivot: DVec3,
    axis: DVec3,
    start: DVec2,
    now: DVec2,
) -> f64 {
    let Some(c) = view.project(pivot) else {
        return 0.0;
    };
    let (u, v) = (start - c, now - c);
    if u.length() < 1e-9 || v.length() < 1e-9 {
        return 0.0;
    }
    // Screen y points down: flip it for a counter-clockwise-positive angle.
    let angle = |p: DVec2| (-p.y).atan2(p.x);
    let mut delta = angle(v) - angle(u);
    delta = (delta + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    let facing = axis.dot(view.camera.backward());
    if facing < 0.0 { -delta } else { delta }
}

/// Rotation of a free trackball drag: about the axis perpendicular to the drag in the view
/// plane, by `radians_per_pixel` per pixel.
pub fn trackball(view: &ViewProjection, start: DVec2, now: DVec2, radians_per_pixel: f64) -> DQuat {
    let d = now - start;
    let length = d.length();
    if length < 1e-9 {
        return DQuat::IDENTITY;
    }
    let (right, up) = view.camera.right_up();
    // Screen y is down: a drag to the right turns about +up, a drag down about +right.
    let drag = (d.x * right - d.y * up) / length;
    let axis = view.camera.backward().cross(drag).normalize();
    DQuat::from_axis_angle(axis, length * radians_per_pixel)
}

/// Scale factor of a drag: the ratio of the mouse's distances to the projected pivot.
pub fn drag_scale(view: &ViewProjection, pivot: DVec3, start: DVec2, now: DVec2) -> f64 {
    let Some(c) = view.project(pivot) else {
        return 1.0;
    };
    let d0 = (start - c).length();
    if d0 < 1e-6 {
        return 1.0;
    }
    (now - c).length() / d0
}

/// Per-axis scale of a factor under a constraint.
pub fn scale_vector(factor: f64, constraint: Constraint) -> DVec3 {
    match constraint {
        Constraint::Free => DVec3::splat(factor),
        Constraint::Axis(a) => DVec3::ONE + (factor - 1.0) * a.vector(),
        Constraint::Plane(a) => DVec3::splat(factor) + (1.0 - factor) * a.vector(),
    }
}

/// Screen end points of the arrow of `axis` at `pivot`.
pub fn arrow_segment(view: &ViewProjection, pivot: DVec3, axis: Axis) -> Option<(DVec2, DVec2)> {
    let length = ARROW_PIXELS * view.world_per_pixel(pivot);
    Some((
        view.project(pivot)?,
        view.project(pivot + length * axis.vector())?,
    ))
}

/// The two axes spanning the plane normal to `axis`, in cyclic order.
fn plane_axes(axis: Axis) -> (Axis, Axis) {
    match axis {
        Axis::X => (Axis::Y, Axis::Z),
        Axis::Y => (Axis::Z, Axis::X),
        Axis::Z => (Axis::X, Axis::Y),
    }
}

/// Screen corners of the plane handle normal to `axis` at `pivot`: a square spanning 25–45 %
/// of the arrows along the two other axes. `None` when it is behind the camera or seen so
/// edge-on that it cannot be grabbed (under 40 px²).
pub fn plane_square(view: &ViewProjection, pivot: DVec3, axis: Axis) -> Option<[DVec2; 4]> {
    let length = ARROW_PIXELS * view.world_per_pixel(pivot);
    let (u, v) = plane_axes(axis);
    let (u, v) = (u.vector() * length, v.vector() * length);
    let corner = |a: f64, b: f64| view.project(pivot + a * u + b * v);
    let square = [
        corner(0.25, 0.25)?,
        corner(0.45, 0.25)?,
        corner(0.45, 0.45)?,
        corner(0.25, 0.45)?,
    ];
    let area = 0.5
        * (0..4)
            .map(|i| square[i].perp_dot(square[(i + 1) % 4]))
            .sum::<f64>()
            .abs();
    (area >= 40.0).then_some(square)
}

/// Whether `p` lies inside the convex quadrilateral `quad` (either winding).
fn inside_convex(quad: &[DVec2; 4], p: DVec2) -> bool {
    let sides: Vec<f64> = (0..4)
        .map(|i| (quad[(i + 1) % 4] - quad[i]).perp_dot(p - quad[i]))
        .collect();
    sides.iter().all(|&s| s >= 0.0) || sides.iter().all(|&s| s <= 0.0)
}

/// Screen polyline of the ring about `axis` at `pivot` (closed, `n` points).
pub fn ring_polyline(view: &ViewProjection, pivot: DVec3, axis: Axis, n: usize) -> Vec<DVec2> {
    let radius = RING_PIXELS * view.world_per_pixel(pivot);
    let a = axis.vector();
    let u = a.any_orthonormal_vector();
    let v = a.cross(u);
    (0..n)
        .filter_map(|i| {
            let t = i as f64 / n as f64 * std::f64::consts::TAU;
            view.project(pivot + radius * (t.cos() * u + t.sin() * v))
        })
        .collect()
}

fn point_segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + t * ab)
}

/// The handle under `mouse`: arrows when `arrows`, rings when `rings` (arrows win ties).
pub fn hit_handle(
    view: &ViewProjection,
    pivot: DVec3,
    mouse: DVec2,
    arrows: bool,
    rings: bool,
) -> Option<Handle> {
    // The centre of the gizmo is free (a drag there moves the selection freely).
    if view
        .project(pivot)
        .is_some_and(|c| c.distance(mouse) < GRAB_PIXELS + 3.0)
    {
        return None;
    }
    let mut best: Option<(f64, Handle)> = None;
    let mut consider = |d: f64, h: Handle| {
        if d <= GRAB_PIXELS && best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, h));
        }
    };
    if arrows {
        for axis in Axis::ALL {
            if plane_square(view, pivot, axis).is_some_and(|q| inside_convex(&q, mouse)) {
                consider(0.0, Handle::Plane(axis));
            }
        }
        for axis in Axis::ALL {
            // An arrow pointing at the viewer is too short on screen to grab reliably.
            if let Some((a, b)) = arrow_segment(view, pivot, axis)
                .filter(|(a, b)| a.distance(*b) > 0.3 * ARROW_PIXELS)
            {
                // The first fifth of an arrow is too close to the pivot to tell axes apart.
                consider(
                    point_segment_distance(mouse, a + 0.2 * (b - a), b),
                    Handle::Arrow(axis),
                );
            }
        }
    }
    if rings {
        for axis in Axis::ALL {
            let poly = ring_polyline(view, pivot, axis, 64);
            let d = (0..poly.len())
                .map(|i| point_segment_distance(mouse, poly[i], poly[(i + 1) % poly.len()]))
                .fold(f64::INFINITY, f64::min);
            // Rings seen edge-on are lines through the pivot: prefer the ones facing us.
            let facing = axis.vector().dot(view.camera.backward()).abs();
            consider(d + 2.0 * (1.0 - facing), Handle::Ring(axis));
        }
    }
    best.map(|(_, h)| h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cagerig_render::OrbitCamera;

    fn view() -> ViewProjection {
        crate::picking::test_view(400.0, 400.0)
    }

    #[test]
    fn plane_handles_are_hit_inside_their_square_and_drag_in_their_plane() {
        // A three-quarter view: all three squares face the camera at an angle.
        let v = ViewProjection::new(
            OrbitCamera::looking_at(DVec3::new(6.0, 5.0, 8.0), DVec3::ZERO),
            400.0,
            400.0,
        );
        let pivot = DVec3::new(0.2, -0.1, 0.3);
        let mut hits = 0;
        for axis in Axis::ALL {
            let Some(square) = plane_square(&v, pivot, axis) else {
                continue;
            };
            hits += 1;
            let centre = square.iter().copied().sum::<DVec2>() / 4.0;
            assert_eq!(
                hit_handle(&v, pivot, centre, true, false),
                Some(Handle::Plane(axis))
            );
            // Without arrows (the rotate tool) there are no plane handles.
            assert_ne!(
                hit_handle(&v, pivot, centre, false, false),
                Some(Handle::Plane(axis))
            );
            let d = drag_translation(
                &v,
                pivot,
                Constraint::Plane(axis),
                centre,
                centre + DVec2::new(25.0, -10.0),
            );
            assert!(d.length() > 1e-6, "{axis:?}: {d}");
            assert!(d.dot(axis.vector()).abs() < 1e-9, "{axis:?}: {d}");
        }
        assert_eq!(
            hits, 3,
            "the three-quarter view shows the three plane handles"
        );
        // A point outside every square hits no plane.
        let far = v.project(pivot).unwrap() + DVec2::new(-200.0, 170.0);
        assert_eq!(hit_handle(&v, pivot, far, true, false), None);
    }

    #[test]
    fn an_axis_drag_follows_the_mouse_along_the_axis_only() {
        let v = view();
        let start = v.project(DVec3::ZERO).unwrap();
        let target = v.project(DVec3::new(1.5, 0.0, 0.0)).unwrap();
        let now = target + DVec2::new(0.0, 30.0);
        let d = drag_translation(&v, DVec3::ZERO, Constraint::Axis(Axis::X), start, now);
        assert!((d - DVec3::new(1.5, 0.0, 0.0)).length() < 1e-9, "{d}");
    }

    #[test]
    fn a_free_drag_lands_under_the_mouse_in_the_view_plane() {
        let v = view();
        let pivot = DVec3::new(0.5, -0.3, 1.0);
        let start = v.project(pivot).unwrap();
        let now = start + DVec2::new(40.0, -25.0);
        let d = drag_translation(&v, pivot, Constraint::Free, start, now);
        let landed = v.project(pivot + d).unwrap();
        assert!((landed - now).length() < 1e-6, "{landed} vs {now}");
        assert!(d.z.abs() < 1e-12);
    }

    #[test]
    fn a_plane_drag_stays_in_the_plane() {
        let v = ViewProjection::new(
            OrbitCamera::looking_at(DVec3::new(4.0, 6.0, 8.0), DVec3::ZERO),
            400.0,
            400.0,
        );
        let start = v.project(DVec3::ZERO).unwrap();
        let d = drag_translation(
            &v,
            DVec3::ZERO,
            Constraint::Plane(Axis::Y),
            start,
            start + DVec2::new(30.0, 10.0),
        );
        assert!(d.y.abs() < 1e-12 && d.length() > 0.01);
        let landed = v.project(d).unwrap();
        assert!((landed - (start + DVec2::new(30.0, 10.0))).length() < 1e-6);
    }

    #[test]
    fn a_quarter_turn_counter_clockwise_is_plus_ninety_degrees_about_the_view_axis() {
        let v = view();
        let c = v.project(DVec3::ZERO).unwrap();
        let start = c + DVec2::new(50.0, 0.0);
        let now = c + DVec2::new(0.0, -50.0); // up on screen
        let a = drag_rotation_angle(&v, DVec3::ZERO, DVec3::Z, start, now);
        assert!((a - std::f64::consts::FRAC_PI_2).abs() < 1e-9, "{a}");
        let b = drag_rotation_angle(&v, DVec3::ZERO, -DVec3::Z, start, now);
        assert!((b + std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        // The rotated point is where the mouse went.
        let p = DQuat::from_axis_angle(DVec3::Z, a) * DVec3::new(1.0, 0.0, 0.0);
        let s = v.project(p).unwrap();
        assert!((s - c).normalize().distance(DVec2::new(0.0, -1.0)) < 1e-9);
    }

    #[test]
    fn scaling_doubles_with_the_distance_and_constraints_pick_axes() {
        let v = view();
        let c = v.project(DVec3::ZERO).unwrap();
        let f = drag_scale(
            &v,
            DVec3::ZERO,
            c + DVec2::new(20.0, 0.0),
            c + DVec2::new(0.0, 40.0),
        );
        assert!((f - 2.0).abs() < 1e-12);
        assert_eq!(
            scale_vector(2.0, Constraint::Axis(Axis::Y)),
            DVec3::new(1.0, 2.0, 1.0)
        );
        assert_eq!(
            scale_vector(2.0, Constraint::Plane(Axis::Y)),
            DVec3::new(2.0, 1.0, 2.0)
        );
        assert_eq!(scale_vector(2.0, Constraint::Free), DVec3::splat(2.0));
    }

    #[test]
    fn handles_are_hit_at_their_drawn_positions() {
        let v = view();
        let (_, tip) = arrow_segment(&v, DVec3::ZERO, Axis::X).unwrap();
        assert_eq!(
            hit_handle(&v, DVec3::ZERO, tip, true, true),
            Some(Handle::Arrow(Axis::X))
        );
        // Looking down Z, the Z ring is a circle around the pivot.
        let c = v.project(DVec3::ZERO).unwrap();
        let on_ring = c + DVec2::new(-RING_PIXELS, 0.0);
        assert_eq!(
            hit_handle(&v, DVec3::ZERO, on_ring, false, true),
            Some(Handle::Ring(Axis::Z))
        );
        assert_eq!(
            hit_handle(&v, DVec3::ZERO, c + DVec2::new(200.0, 200.0), true, true),
            None
        );
    }

    #[test]
    fn a_trackball_drag_to_the_right_turns_about_the_up_axis() {
        let v = view();
        let q = trackball(&v, DVec2::new(100.0, 100.0), DVec2::new(150.0, 100.0), 0.01);
        let (axis, angle) = q.to_axis_angle();
        assert!((angle - 0.5).abs() < 1e-9);
        assert!(axis.distance(DVec3::Y) < 1e-9, "{axis}");
    }
}
