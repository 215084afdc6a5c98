//! The CPU part of an editor frame during a drag, without drawing: one session event through
//! the editor's gesture path (sync) plus the scene upload of the views it changes (normals,
//! packing, in-place vertex-buffer writes), on the built-in snake at about 133k vertices. The
//! GPU stays idle, so a software rasteriser does not compete for the CPU (in the real editor on
//! lavapipe it does: see `--frame-stats`).
//!
//! `cargo run --release -p cagerig-studio --example edit_frame_bench -- [RESOLUTION] [EVENTS]`

// tests, benches and examples may panic on a broken fixture

use std::time::Instant;

use cagerig_render::rig_scene::{ColorBy, Layers, Pose, RigSceneData};
use cagerig_render::{GpuContext, Renderer, SceneBuffers, Style};
use cagerig_studio::document::{Command, Document};
use cagerig_studio::rig_open::{RigSource, open_rig};
use glam::DVec3;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let resolution: usize = args.get(1).map_or(Ok(133_000), |s| s.parse())?;
    let events: usize = args.get(2).map_or(Ok(60), |s| s.parse())?;
    let source = RigSource::Builtin {
        name: "snake".into(),
        resolution: Some(resolution),
    };
    let mut doc = Document::new(source.clone(), open_rig(&source)?.session);
    let gpu = GpuContext::new_headless()?;
    let renderer = Renderer::new(&gpu.device);
    let mut buffers = [
        SceneBuffers::new(&gpu.device, renderer.pipelines()),
        SceneBuffers::new(&gpu.device, renderer.pipelines()),
    ];
    let mut data = [RigSceneData::new(), RigSceneData::new()];
    println!(
        "snake: {} vertices, {} joints, {} cage vertices; {} on {}",
        doc.session.rest_mesh().len(),
        doc.session.skeleton().len(),
        doc.session.rest_cage().len(),
        events,
        gpu.adapter_name
    );
    let n = doc.session.skeleton().len();
    for (name, rest_changes) in [
        ("cage drag (C')", true),
        ("rest-cage drag (C)", true),
        ("joint rotation (S')", false),
    ] {
        let mut sync = Vec::new();
        let mut upload = Vec::new();
        doc.begin_gesture(name);
        for i in 0..events {
            let phase = i as f64 * 0.2;
            let step = 0.01 * DVec3::new(phase.cos(), phase.sin(), 0.0);
            let command = match name.chars().next() {
                Some('c') => Command::MovePosedCage {
                    vertices: vec![0, 1, 2],
                    offsets: vec![step],
                },
                Some('r') => Command::MoveRestCage {
                    vertices: vec![0, 1, 2],
                    offsets: vec![step],
                },
                _ => Command::RotateJoint {
                    joint: n / 2,
                    axis: DVec3::Z,
                    angle: 0.01 * phase.cos(),
                },
            };
            let t = Instant::now();
            doc.gesture_event(&command)?;
            sync.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            let poses: &[Pose] = if rest_changes {
                &[Pose::Current, Pose::Rest]
            } else {
                &[Pose::Current]
            };
            for (k, pose) in poses.iter().enumerate() {
                let scene = data[k].scene(&doc.session, *pose, Layers::default(), ColorBy::None);
                buffers[k].update(&gpu.device, &gpu.queue, &scene, &Style::default())?;
            }
            upload.push(t.elapsed().as_secs_f64() * 1e3);
        }
        doc.end_gesture();
        let total: Vec<f64> = sync.iter().zip(&upload).map(|(a, b)| a + b).collect();
        println!(
            "{name:22} sync {:6.2} ms + normals/upload {:6.2} ms = {:6.2} ms (medians)",
            median(sync),
            median(upload),
            median(total)
        );
    }
    Ok(())
}
