//! Orbit camera: a target point, a distance and two angles, with view presets and frame-all.
//!
//! World space is the rig's own space with +Y up. The camera looks at `target` from
//! `eye = target + distance · (cos(pitch) sin(yaw), sin(pitch), cos(pitch) cos(yaw))`, so
//! `yaw = 0, pitch = 0` looks along −Z (the front view). Angles are radians.

use glam::{DMat4, DVec3, Mat4};

/// Named viewpoints (the front view looks along −Z with +Y up).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraPreset {
    /// Eye on +Z, looking along −Z.
    Front,
    /// Eye on +X, looking along −X.
    Side,
    /// Eye on +Y, looking down (−Y), +Z towards the bottom of the picture.
    Top,
    /// Eye up and to the right of the front view (yaw 35°, pitch 25°).
    ThreeQuarter,
}

impl CameraPreset {
    /// All presets with their command-line names.
    pub const ALL: [(&'static str, CameraPreset); 4] = [
        ("front", CameraPreset::Front),
        ("side", CameraPreset::Side),
        ("top", CameraPreset::Top),
        ("three-quarter", CameraPreset::ThreeQuarter),
    ];

    /// Parses a command-line name (`front`, `side`, `top`, `three-quarter`).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().find(|(n, _)| *n == name).map(|(_, p)| *p)
    }

    /// `(yaw, pitch)` in radians.
    pub fn angles(self) -> (f64, f64) {
        match self {
            CameraPreset::Front => (0.0, 0.0),
            CameraPreset::Side => (std::f64::consts::FRAC_PI_2, 0.0),
            CameraPreset::Top => (0.0, MAX_PITCH),
            CameraPreset::ThreeQuarter => (35f64.to_radians(), 25f64.to_radians()),
        }
    }
}

/// Pitch is kept strictly inside ±90° so that the up vector stays defined.
pub const MAX_PITCH: f64 = 89.9 * std::f64::consts::PI / 180.0;

/// An orbiting perspective camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitCamera {
    /// Point looked at (world space).
    pub target: DVec3,
    /// Distance from the eye to `target` (world units, > 0).
    pub distance: f64,
    /// Rotation about +Y (radians); 0 = eye on +Z.
    pub yaw: f64,
    /// Elevation (radians), clamped to ±[`MAX_PITCH`].
    pub pitch: f64,
    /// Vertical field of view (radians).
    pub fov_y: f64,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        Self {
            target: DVec3::ZERO,
            distance: 5.0,
            yaw: 0.0,
            pitch: 0.0,
            fov_y: 30f64.to_radians(),
        }
    }
}

impl OrbitCamera {
    /// A camera at `preset` framing the axis-aligned box `[lo, hi]` for the aspect ratio
    /// `width / height`.
    pub fn framing(preset: CameraPreset, lo: DVec3, hi: DVec3, aspect: f64) -> Self {
        let (yaw, pitch) = preset.angles();
        let mut camera = Self {
            yaw,
            pitch,
            ..Self::default()
        };
        camera.frame_box(lo, hi, aspect);
        camera
    }

    /// A camera with its eye at `eye` looking at `target`.
    pub fn looking_at(eye: DVec3, target: DVec3) -> Self {
        let d = eye - target;
        let distance = d.length().max(1e-9);
        let pitch = (d.y / distance)
            .clamp(-1.0, 1.0)
            .asin()
            .clamp(-MAX_PITCH, MAX_PITCH);
        let yaw = d.x.atan2(d.z);
        Self {
            target,
            distance,
            yaw,
            pitch,
            ..Self::default()
        }
    }

    /// Moves the target to the centre of `[lo, hi]` and sets the distance so that the box's
    /// bounding sphere fits the view with a small margin, keeping the angles.
    pub fn frame_box(&mut self, lo: DVec3, hi: DVec3, aspect: f64) {
        let radius = (0.5 * (hi - lo).length()).max(1e-9);
        self.target = 0.5 * (lo + hi);
        let half_y = 0.5 * self.fov_y;
        let half_x = (half_y.tan() * aspect.max(1e-3)).atan();
        let half = half_y.min(half_x);
        // The bounding sphere always fits at this distance; then move in (bisection) while the
        // box's eight corners stay within 90 % of the view, so long thin shapes fill it.
        let sphere_distance = 1.05 * radius / half.sin();
        let fits = |camera: &Self| {
            let view_from_world = camera.view_from_world();
            (0..8).all(|i| {
                let corner = DVec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                let p = view_from_world.transform_point3(corner);
                let depth = -p.z;
                depth > 0.05 * radius
                    && p.x.abs() <= 0.9 * depth * half_x.tan()
                    && p.y.abs() <= 0.9 * depth * half_y.tan()
            })
        };
        let (mut near, mut far) = (0.0, sphere_distance);
        for _ in 0..30 {
            self.distance = 0.5 * (near + far);
            if fits(self) {
                far = self.distance;
            } else {
                near = self.distance;
            }
        }
        self.distance = far;
    }

    /// Unit vector from the target towards the eye.
    pub fn backward(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        DVec3::new(cp * sy, sp, cp * cy)
    }

    /// Eye position (world space).
    pub fn eye(&self) -> DVec3 {
        self.target + self.distance * self.backward()
    }

    /// Camera right and up vectors (world space, unit, orthogonal to the view direction).
    pub fn right_up(&self) -> (DVec3, DVec3) {
        let back = self.backward();
        let right = DVec3::Y.cross(back).try_normalize().unwrap_or(DVec3::X);
        (right, back.cross(right))
    }

    /// Rotates about the target by screen-space angles (radians), clamping the pitch.
    pub fn orbit(&mut self, delta_yaw: f64, delta_pitch: f64) {
        self.yaw += delta_yaw;
        self.pitch = (self.pitch + delta_pitch).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target in the view plane by `(dx, dy)` fractions of the view height.
    pub fn pan(&mut self, dx: f64, dy: f64) {
        let (right, up) = self.right_up();
        let height = 2.0 * self.distance * (0.5 * self.fov_y).tan();
        self.target += (-dx * right + dy * up) * height;
    }

    /// Multiplies the distance by `factor` (> 0).
    pub fn zoom(&mut self, factor: f64) {
        if factor.is_finite() && factor > 0.0 {
            self.distance = (self.distance * factor).max(1e-6);
        }
    }

    /// View matrix (camera from world), right-handed, camera looking along its −Z.
    pub fn view_from_world(&self) -> DMat4 {
        let (_, up) = self.right_up();
        glam::dcamera::rh::view::look_at_mat4(self.eye(), self.target, up)
    }

    /// Near and far clip distances that contain a sphere of `scene_radius` around the target.
    pub fn clip_range(&self, scene_radius: f64) -> (f64, f64) {
        let far = self.distance + 2.0 * scene_radius.max(1e-9);
        let near = (self.distance - 2.0 * scene_radius).max(far * 1e-4);
        (near, far)
    }

    /// Projection matrix (clip from camera) for wgpu's [0, 1] depth range.
    pub fn clip_from_view(&self, aspect: f64, scene_radius: f64) -> DMat4 {
        let (near, far) = self.clip_range(scene_radius);
        glam::dcamera::rh::proj::directx::perspective(self.fov_y, aspect.max(1e-6), near, far)
    }

    /// `clip_from_world` in f32, ready for a uniform buffer.
    pub fn clip_from_world(&self, aspect: f64, scene_radius: f64) -> Mat4 {
        (self.clip_from_view(aspect, scene_radius) * self.view_from_world()).as_mat4()
    }

    /// Projects a world point to pixel coordinates (origin top-left) of a `width × height`
    /// viewport; `None` behind the eye.
    pub fn project(
        &self,
        point: DVec3,
        width: f64,
        height: f64,
        scene_radius: f64,
    ) -> Option<(f64, f64, f64)> {
        let clip = self.clip_from_view(width / height, scene_radius)
            * self.view_from_world()
            * point.extend(1.0);
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some((
            (ndc.x * 0.5 + 0.5) * width,
            (0.5 - ndc.y * 0.5) * height,
            ndc.z,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_put_the_eye_on_the_expected_axis() {
        let lo = DVec3::splat(-1.0);
        let hi = DVec3::splat(1.0);
        let front = OrbitCamera::framing(CameraPreset::Front, lo, hi, 1.0);
        let e = front.eye().normalize();
        assert!((e - DVec3::Z).length() < 1e-12);
        let side = OrbitCamera::framing(CameraPreset::Side, lo, hi, 1.0);
        assert!((side.eye().normalize() - DVec3::X).length() < 1e-12);
        let top = OrbitCamera::framing(CameraPreset::Top, lo, hi, 1.0);
        assert!(top.eye().normalize().y > 0.9999);
        assert_eq!(
            CameraPreset::from_name("three-quarter"),
            Some(CameraPreset::ThreeQuarter)
        );
        assert_eq!(CameraPreset::from_name("bogus"), None);
    }

    #[test]
    fn framed_box_corners_project_inside_the_viewport() {
        let lo = DVec3::new(-3.0, 0.5, -1.0);
        let hi = DVec3::new(5.0, 2.0, 4.0);
        for (_, preset) in CameraPreset::ALL {
            for (w, h) in [(800.0, 600.0), (300.0, 900.0)] {
                let cam = OrbitCamera::framing(preset, lo, hi, w / h);
                let radius = 0.5 * (hi - lo).length();
                for i in 0..8 {
                    let p = DVec3::new(
                        if i & 1 == 0 { lo.x } else { hi.x },
                        if i & 2 == 0 { lo.y } else { hi.y },
                        if i & 4 == 0 { lo.z } else { hi.z },
                    );
                    let (x, y, z) = cam.project(p, w, h, radius).unwrap();
                    assert!(
                        (0.0..=w).contains(&x) && (0.0..=h).contains(&y),
                        "{preset:?} {x} {y}"
                    );
                    assert!((0.0..=1.0).contains(&z));
                }
            }
        }
    }

    #[test]
    fn target_projects_to_the_viewport_centre_and_looking_at_round_trips() {
        let cam = OrbitCamera::looking_at(DVec3::new(3.0, 4.0, 5.0), DVec3::new(1.0, 1.0, 1.0));
        assert!((cam.eye() - DVec3::new(3.0, 4.0, 5.0)).length() < 1e-12);
        let (x, y, _) = cam.project(cam.target, 640.0, 480.0, 1.0).unwrap();
        assert!((x - 320.0).abs() < 1e-9 && (y - 240.0).abs() < 1e-9);
    }

    #[test]
    fn orbit_clamps_pitch_and_pan_moves_in_the_view_plane() {
        let mut cam = OrbitCamera::default();
        cam.orbit(0.3, 10.0);
        assert!((cam.pitch - MAX_PITCH).abs() < 1e-15);
        let before = cam.target;
        cam.pan(0.25, 0.0);
        let (right, _) = cam.right_up();
        let moved = cam.target - before;
        assert!(moved.dot(cam.backward()).abs() < 1e-12);
        assert!(moved.dot(right) < 0.0);
        cam.zoom(0.5);
        assert!((cam.distance - 2.5).abs() < 1e-12);
        cam.zoom(f64::NAN);
        assert!((cam.distance - 2.5).abs() < 1e-12);
    }
}
