//! The wgpu rest map on a bound rig: the Arm on the f32 display path with
//! `DisplayRestMap::External(GpuRestMap)`, under mean value and Green coordinates, through a
//! current-cage edit, a rest-cage edit and another current-cage edit. The drawn rest skin is
//! within 2e-6 of the bounding-box diagonal of the exact M, and the rig's exact state (C, C', S,
//! S', M, M') is bit-identical to a session on the CPU backend. A backend that refuses the
//! coordinates leaves the session on the exact product.
//!
//! These tests need a Vulkan or GL adapter with compute shaders (lavapipe is fine, from Debian's
//! `mesa-vulkan-drivers`). Set `CAGERIG_SKIP_GPU_TESTS=1` to skip them on a machine without one.

#![expect(clippy::unwrap_used, clippy::expect_used)] // tests may panic on a broken fixture

use std::path::Path;
use std::sync::Arc;

use cagerig::CoordsKind;
use cagerig::session::{DisplayPrecision, DisplayRestMap, RigSession, SessionOptions};
use cagerig_render::GpuRestMap;
use glam::{DVec3, Vec3};

/// The backend on a headless device, or `None` where `CAGERIG_SKIP_GPU_TESTS` is set. With no
/// adapter and no such variable the test fails, as the renderer's tests do: a GPU test does not
/// pass by not running.
fn backend() -> Option<GpuRestMap> {
    if std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_some() {
        eprintln!("skipped: CAGERIG_SKIP_GPU_TESTS is set");
        return None;
    }
    match GpuRestMap::new_headless() {
        Ok(backend) => Some(backend),
        Err(e) => panic!("{e} (set CAGERIG_SKIP_GPU_TESTS=1 to skip the GPU tests)"),
    }
}

fn arm(coords: CoordsKind, display_rest_map: DisplayRestMap) -> RigSession {
    let arm_obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm/arm.obj");
    let parts = cagerig::rig_files::load_rig_files(&arm_obj, None)
        .unwrap()
        .parts;
    let options = SessionOptions {
        coords,
        display_rest_map,
        ..SessionOptions::default()
    };
    let mut session = RigSession::new(parts, options).unwrap().0;
    session
        .set_display_precision(DisplayPrecision::F32)
        .unwrap();
    session
}

fn diagonal(points: &[DVec3]) -> f64 {
    let lo = points.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = points.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    (hi - lo).length()
}

/// Largest distance of the drawn points from the exact ones, as a fraction of the diagonal.
fn relative_error(shown: &[Vec3], exact: &[DVec3]) -> f64 {
    let worst = shown
        .iter()
        .zip(exact)
        .map(|(a, b)| a.as_dvec3().distance(*b))
        .fold(0.0, f64::max);
    worst / diagonal(exact)
}

/// Both sessions' exact state is the same bits; the GPU session's drawn M is within 2e-6 of the
/// diagonal of the exact M.
fn check(gpu: &RigSession, cpu: &RigSession, what: &str) {
    assert_eq!(gpu.posed_cage(), cpu.posed_cage(), "C' after {what}");
    assert_eq!(gpu.rest_cage(), cpu.rest_cage(), "C after {what}");
    assert_eq!(
        gpu.rest_world_from_joint(),
        cpu.rest_world_from_joint(),
        "S after {what}"
    );
    assert_eq!(
        gpu.posed_world_from_joint(),
        cpu.posed_world_from_joint(),
        "S' after {what}"
    );
    assert_eq!(gpu.posed_mesh(), cpu.posed_mesh(), "M' after {what}");
    assert_eq!(gpu.rest_mesh(), cpu.rest_mesh(), "M after {what}");
    let exact = gpu.rest_mesh();
    let on_gpu = relative_error(gpu.display_rest_mesh().expect("display path"), exact);
    let on_cpu = relative_error(cpu.display_rest_mesh().expect("display path"), exact);
    eprintln!("{what}: drawn M within {on_gpu:.2e} (wgpu) / {on_cpu:.2e} (cpu) of the diagonal");
    assert!(
        on_gpu <= 2e-6,
        "drawn M after {what}: {on_gpu:e} of the diagonal"
    );
}

/// Runs `event` on both sessions and checks that both apply it (or refuse it alike).
fn both(
    gpu: &mut RigSession,
    cpu: &mut RigSession,
    event: impl Fn(&mut RigSession) -> Result<(), cagerig::RigError>,
) -> bool {
    match (event(gpu), event(cpu)) {
        (Ok(()), Ok(())) => true,
        (Err(a), Err(b)) => {
            assert_eq!(a.to_string(), b.to_string());
            false
        }
        (a, b) => panic!("wgpu session: {a:?}, cpu session: {b:?}"),
    }
}

fn check_arm(coords: CoordsKind) {
    let Some(backend) = backend() else { return };
    eprintln!("{coords:?} on {}", backend.adapter_name());
    let backend = Arc::new(backend);
    let mut gpu = arm(coords, DisplayRestMap::External(Arc::clone(&backend) as _));
    let mut cpu = arm(coords, DisplayRestMap::Cpu);
    let joint = gpu.skeleton().find("lowerarm01.R").unwrap_or(3);
    let step = 0.01 * diagonal(gpu.rest_cage());
    assert!(both(&mut gpu, &mut cpu, |s| {
        s.rotate_joint(joint, DVec3::X, 10f64.to_radians())
    }));
    let mut grabs = 0;
    let grab =
        |s: &mut RigSession| s.move_posed_cage(&[7, 8], &[DVec3::new(0.0, step, 0.5 * step)]);
    if both(&mut gpu, &mut cpu, grab) {
        grabs += 1;
    }
    check(&gpu, &cpu, &format!("{coords:?} current-cage edit"));
    assert!(both(&mut gpu, &mut cpu, |s| {
        s.move_rest_cage(&[3], &[DVec3::new(step, 0.0, -step)])
    }));
    check(&gpu, &cpu, &format!("{coords:?} rest-cage edit"));
    let grab = |s: &mut RigSession| s.move_posed_cage(&[12], &[DVec3::new(-step, 0.0, step)]);
    if both(&mut gpu, &mut cpu, grab) {
        grabs += 1;
    }
    check(&gpu, &cpu, &format!("{coords:?} second current-cage edit"));
    assert!(grabs > 0, "{coords:?}: every current-cage edit was refused");
    let counts = backend.counts();
    assert_eq!(counts.bound, 1, "{coords:?}: {counts:?}");
    assert_eq!(counts.gpu_applies, grabs, "{coords:?}: {counts:?}");
    assert_eq!(counts.cpu_applies, 0, "{:?}", backend.first_failure());
}

#[test]
fn the_arm_draws_its_rest_skin_on_the_gpu_under_mean_value_coordinates() {
    check_arm(CoordsKind::Mvc);
}

#[test]
fn the_arm_draws_its_rest_skin_on_the_gpu_under_green_coordinates() {
    check_arm(CoordsKind::Green);
}

#[test]
fn a_gpu_that_cannot_hold_the_coordinates_leaves_the_exact_product() {
    let Some(backend) = backend() else { return };
    let backend = Arc::new(backend.with_max_bytes(1024));
    let mut session = arm(
        CoordsKind::Mvc,
        DisplayRestMap::External(Arc::clone(&backend) as _),
    );
    session
        .move_posed_cage(&[7], &[DVec3::new(0.0, 0.3, 0.0)])
        .unwrap();
    let counts = backend.counts();
    assert_eq!(
        (counts.bound, counts.refused, counts.gpu_applies),
        (0, 1, 0)
    );
    assert!(backend.last_refusal().unwrap().contains("1024"));
    let exact = session.rest_mesh().to_vec();
    let shown = session.display_rest_mesh().expect("display path");
    for (a, b) in shown.iter().zip(&exact) {
        assert_eq!(*a, b.as_vec3());
    }
}
