//! Offscreen image checks on whatever adapter the machine has (lavapipe / llvmpipe in CI):
//! silhouettes of known shapes, colour-map colours at known places, in-place uploads.
//!
//! These tests need a Vulkan or GL adapter (software ones are fine); `.ci/run` installs
//! `mesa-vulkan-drivers`. Set `CAGERIG_SKIP_GPU_TESTS=1` to skip them on a machine without one.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use cagerig_render::palette::ColorMap;
use cagerig_render::{
    CageLayer, CameraPreset, MeshLayer, MeshPositions, OffscreenRenderer, OrbitCamera, RenderError,
    Scene, SkeletonLayer, Style,
};
use glam::DVec3;

fn renderer() -> Option<OffscreenRenderer> {
    if std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_some() {
        return None;
    }
    match OffscreenRenderer::new() {
        Ok(r) => Some(r),
        Err(e) => panic!("{e} (set CAGERIG_SKIP_GPU_TESTS=1 to skip the GPU tests)"),
    }
}

/// An axis-aligned box `[lo, hi]` as 8 vertices and 12 outward triangles.
fn cuboid(lo: DVec3, hi: DVec3) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mesh = cagerig::TriMesh::cuboid(lo, hi).unwrap();
    (mesh.positions, mesh.triangles)
}

fn mesh_scene<'a>(
    positions: impl Into<MeshPositions<'a>>,
    triangles: &'a [[u32; 3]],
    colors: Option<&'a [[u8; 4]]>,
) -> Scene<'a> {
    Scene {
        mesh: Some(MeshLayer {
            positions: positions.into(),
            triangles,
            colors,
            flat: false,
            wireframe: false,
            topology_id: None,
        }),
        ..Scene::default()
    }
}

fn is_background(c: [u8; 4]) -> bool {
    // The backdrop is a light grey-blue gradient (blue above red everywhere); the neutral clay
    // material is warm (red above blue).
    let [r, g, b, _] = c;
    r > 170 && g > 170 && b > r && (b as i32 - r as i32) < 30
}

#[test]
fn a_box_covers_the_centre_and_leaves_the_corners_to_the_backdrop() {
    let Some(mut r) = renderer() else { return };
    let (positions, triangles) = cuboid(DVec3::splat(-1.0), DVec3::splat(1.0));
    let scene = mesh_scene(&positions[..], &triangles, None);
    let (lo, hi) = scene.bounds().unwrap();
    let camera = OrbitCamera::framing(CameraPreset::Front, lo, hi, 320.0 / 240.0);
    let image = r
        .render(&scene, &Style::default(), &camera, 320, 240)
        .unwrap();
    assert_eq!((image.width(), image.height()), (320, 240));
    let centre = image.pixel(160, 120);
    assert!(
        !is_background(centre),
        "centre {centre:?} should be the box"
    );
    for (x, y) in [(2, 2), (317, 2), (2, 237), (317, 237)] {
        let c = image.pixel(x, y);
        assert!(
            is_background(c),
            "corner ({x},{y}) {c:?} should be the backdrop"
        );
    }
    // The front face spans a known part of the picture: project its corners.
    let radius = 0.5 * (hi - lo).length();
    let (x0, y0, _) = camera
        .project(DVec3::new(-1.0, 1.0, 1.0), 320.0, 240.0, radius)
        .unwrap();
    let (x1, y1, _) = camera
        .project(DVec3::new(1.0, -1.0, 1.0), 320.0, 240.0, radius)
        .unwrap();
    let inside = image.pixel(
        ((x0 + x1) / 2.0 + 0.4 * (x1 - x0)) as u32,
        ((y0 + y1) / 2.0) as u32,
    );
    assert!(
        !is_background(inside),
        "{inside:?} inside the projected face"
    );
    let outside = image.pixel((x1 + 6.0) as u32, ((y0 + y1) / 2.0) as u32);
    assert!(
        is_background(outside),
        "{outside:?} just right of the projected face"
    );
}

#[test]
fn f32_display_positions_draw_the_same_picture_as_f64() {
    let Some(mut r) = renderer() else { return };
    let (positions, triangles) = cuboid(DVec3::new(-1.0, -0.5, -2.0), DVec3::new(1.5, 1.0, 0.5));
    let positions32: Vec<glam::Vec3> = positions.iter().map(|p| p.as_vec3()).collect();
    let scene64 = mesh_scene(&positions[..], &triangles, None);
    let scene32 = mesh_scene(&positions32[..], &triangles, None);
    assert_eq!(scene64.bounds(), scene32.bounds());
    let (lo, hi) = scene64.bounds().unwrap();
    let camera = OrbitCamera::framing(CameraPreset::ThreeQuarter, lo, hi, 1.0);
    let a = r
        .render(&scene64, &Style::default(), &camera, 160, 160)
        .unwrap();
    let b = r
        .render(&scene32, &Style::default(), &camera, 160, 160)
        .unwrap();
    let worst = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0);
    assert!(worst <= 1, "largest channel difference {worst}");
}

#[test]
fn colour_maps_show_their_colours_at_known_vertices() {
    let Some(mut r) = renderer() else { return };
    // Two boxes side by side: the left coloured with the diverging map's negative end
    // (blue), the right with its positive end (red).
    let (mut positions, mut triangles) =
        cuboid(DVec3::new(-3.0, -1.0, -1.0), DVec3::new(-0.5, 1.0, 1.0));
    let (right, right_tris) = cuboid(DVec3::new(0.5, -1.0, -1.0), DVec3::new(3.0, 1.0, 1.0));
    triangles.extend(right_tris.iter().map(|t| t.map(|i| i + 8)));
    positions.extend(right);
    let map = ColorMap::Diverging { limit: 1.0 };
    let colors: Vec<[u8; 4]> = (0..16)
        .map(|i| map.color_u8(if i < 8 { -1.0 } else { 1.0 }))
        .collect();
    let scene = mesh_scene(&positions[..], &triangles, Some(&colors));
    let (lo, hi) = scene.bounds().unwrap();
    let camera = OrbitCamera::framing(CameraPreset::Front, lo, hi, 2.0);
    let image = r
        .render(&scene, &Style::default(), &camera, 400, 200)
        .unwrap();
    let radius = 0.5 * (hi - lo).length();
    let at = |p: DVec3| {
        let (x, y, _) = camera.project(p, 400.0, 200.0, radius).unwrap();
        image.pixel(x as u32, y as u32)
    };
    let blue = at(DVec3::new(-1.75, 0.0, 1.0));
    let red = at(DVec3::new(1.75, 0.0, 1.0));
    assert!(
        blue[2] as i32 > blue[0] as i32 + 40,
        "left box {blue:?} should be blue"
    );
    assert!(
        red[0] as i32 > red[2] as i32 + 40,
        "right box {red:?} should be red"
    );
}

#[test]
fn skeleton_is_drawn_on_top_of_the_skin_and_hidden_cage_parts_are_faint() {
    let Some(mut r) = renderer() else { return };
    let (positions, triangles) = cuboid(DVec3::splat(-1.0), DVec3::splat(1.0));
    let (cage, cage_tris) = cuboid(DVec3::splat(-1.5), DVec3::splat(1.5));
    // A bone through the middle of the box, hidden by the skin but drawn on top.
    let joints = [DVec3::new(-0.8, 0.0, 0.0), DVec3::new(0.8, 0.0, 0.0)];
    let parents = [None, Some(0)];
    let scene = Scene {
        cage: Some(CageLayer {
            positions: &cage,
            triangles: &cage_tris,
            handle_colors: None,
        }),
        skeleton: Some(SkeletonLayer {
            joints: &joints,
            parents: &parents,
            joint_colors: None,
        }),
        ..mesh_scene(&positions[..], &triangles, None)
    };
    let (lo, hi) = scene.bounds().unwrap();
    let camera = OrbitCamera::framing(CameraPreset::Front, lo, hi, 1.0);
    let style = Style::default();
    let image = r.render(&scene, &style, &camera, 256, 256).unwrap();
    let radius = 0.5 * (hi - lo).length();
    let (x, y, _) = camera
        .project(DVec3::new(0.4, 0.0, 0.0), 256.0, 256.0, radius)
        .unwrap();
    let bone = image.pixel(x as u32, y as u32);
    assert!(
        bone[2] as i32 > bone[0] as i32 + 60,
        "bone pixel {bone:?} should be the bone colour"
    );
    // A front cage handle is drawn in the handle colour (orange).
    let (x, y, _) = camera
        .project(DVec3::new(1.5, 1.5, 1.5), 256.0, 256.0, radius)
        .unwrap();
    let handle = image.pixel(x as u32, y as u32);
    assert!(
        handle[0] as i32 > handle[2] as i32 + 60,
        "handle pixel {handle:?} should be orange"
    );
}

#[test]
fn frames_of_the_same_size_update_buffers_in_place() {
    let Some(mut r) = renderer() else { return };
    let (mut positions, triangles) = cuboid(DVec3::splat(-1.0), DVec3::splat(1.0));
    let style = Style::default();
    r.upload(&mesh_scene(&positions[..], &triangles, None), &style)
        .unwrap();
    let created = r.buffers_created();
    for step in 0..5 {
        positions.iter_mut().for_each(|p| p.x += 0.01 * step as f64);
        r.upload(&mesh_scene(&positions[..], &triangles, None), &style)
            .unwrap();
    }
    assert_eq!(
        r.buffers_created(),
        created,
        "no buffer re-created for same-sized frames"
    );
    // Bad indices are refused before anything is uploaded.
    let bad = [[0, 1, 8]];
    let err = r
        .upload(&mesh_scene(&positions[..], &bad, None), &style)
        .unwrap_err();
    assert!(matches!(err, RenderError::Geometry(_)));
    assert!(err.to_string().contains("mesh triangle 0"), "{err}");
}

#[test]
fn impossible_sizes_are_refused_with_the_limit() {
    let Some(mut r) = renderer() else { return };
    let (positions, triangles) = cuboid(DVec3::splat(-1.0), DVec3::splat(1.0));
    let scene = mesh_scene(&positions[..], &triangles, None);
    let camera = OrbitCamera::default();
    let err = r
        .render(&scene, &Style::default(), &camera, 0, 10)
        .unwrap_err();
    assert!(err.to_string().contains("0×10"), "{err}");
}
