//! Offscreen rendering speed on the Arm subdivided N times (default 3: 133,073 vertices):
//! the per-frame upload alone (normals + packing + in-place buffer writes, GPU idle after) and
//! a whole frame (upload, draw, MSAA resolve, readback), at 1280×720.
//!
//! `cargo run --release -p cagerig-render --example render_bench -- [LEVELS] [FRAMES] [PNG]`
//!
//! The first frame is written to PNG (default: `render_bench.png` in the system's temporary
//! folder), and its path printed.

// tests, benches and examples may panic on a broken fixture

use std::time::Instant;

use cagerig_render::{
    CageLayer, CameraPreset, MeshLayer, OffscreenRenderer, OrbitCamera, Scene, SkeletonLayer, Style,
};
use glam::DVec3;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let levels: usize = args.get(1).map_or(Ok(3), |s| s.parse())?;
    let frames: usize = args.get(2).map_or(Ok(20), |s| s.parse())?;
    let png = args.get(3).map_or_else(
        || std::env::temp_dir().join("render_bench.png"),
        std::path::PathBuf::from,
    );
    let arm = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm/arm.obj");
    let rig = cagerig::rig_files::load_rig_files(std::path::Path::new(arm), None)?;
    let p = &rig.parts;
    let sub = cagerig::subdivide::subdivide_midpoint(&p.mesh, &p.skin_weights, levels)?;
    let mut positions = sub.mesh.positions.clone();
    let triangles = &sub.mesh.triangles;
    let joints = p.skeleton.rest_positions();
    let parents: Vec<Option<usize>> = p.skeleton.joints().iter().map(|j| j.parent).collect();
    let mut renderer = OffscreenRenderer::new()?;
    println!(
        "Arm N={levels}: {} vertices, {} triangles, {}×{} on {}",
        positions.len(),
        triangles.len(),
        1280,
        720,
        renderer.adapter_name()
    );
    let style = Style::default();
    let (w, h) = (1280, 720);
    let mut upload = Vec::new();
    let mut frame = Vec::new();
    let mut camera = None;
    for k in 0..frames + 2 {
        // A small change per frame, as during a drag.
        let shift = DVec3::new(1e-3 * k as f64, 0.0, 0.0);
        positions.iter_mut().for_each(|q| *q += shift);
        let scene = Scene {
            mesh: Some(MeshLayer {
                positions: cagerig_render::MeshPositions::F64(&positions),
                triangles,
                colors: None,
                flat: false,
                wireframe: false,
                topology_id: None,
            }),
            cage: Some(CageLayer {
                positions: &p.cage.positions,
                triangles: &p.cage.triangles,
                handle_colors: None,
            }),
            skeleton: Some(SkeletonLayer {
                joints: &joints,
                parents: &parents,
                joint_colors: None,
            }),
            ground: true,
        };
        let cam = *camera.get_or_insert_with(|| {
            let (lo, hi) = scene.bounds().unwrap_or((DVec3::ZERO, DVec3::ONE));
            OrbitCamera::framing(CameraPreset::ThreeQuarter, lo, hi, w as f64 / h as f64)
        });
        let t = Instant::now();
        renderer.upload(&scene, &style)?;
        renderer.wait_idle()?;
        let t_upload = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let image = renderer.draw(&cam, w, h)?;
        let t_draw = t.elapsed().as_secs_f64() * 1e3;
        if k == 0 {
            image.write_png(&png)?;
            println!("first frame: {}", png.display());
        }
        if k >= 2 {
            upload.push(t_upload);
            frame.push(t_upload + t_draw);
        }
    }
    let created = renderer.buffers_created();
    println!(
        "upload (normals + pack + write, GPU idle): median {:.2} ms; whole frame incl. draw + readback: median {:.1} ms; buffers created in all: {created}",
        median(upload),
        median(frame)
    );
    Ok(())
}
