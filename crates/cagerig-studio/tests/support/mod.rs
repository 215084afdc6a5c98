//! Set-up shared by the studio's kittests: the harness on a wgpu device, the built-in bar, fresh
//! temporary folders, and pointer input at projected world positions. Each test file uses its
//! part.

#![expect(clippy::unwrap_used)]

use std::path::{Path, PathBuf};

use cagerig_studio::document::Snapshot;
use cagerig_studio::rig_open::RigSource;
use cagerig_studio::view_state::CURRENT;
use cagerig_studio::{StartupOptions, StudioApp};
use egui::{Event, Modifiers, PointerButton, Pos2};
use egui_kittest::Harness;
use glam::DVec3;

/// Whether `CAGERIG_SKIP_GPU_TESTS=1` asks to skip the tests that need a wgpu adapter.
pub fn skip() -> bool {
    std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_some_and(|v| v == "1")
}

pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "cagerig-studio-{}-{name}-{}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn bar() -> RigSource {
    RigSource::Builtin {
        name: "bar".into(),
        resolution: Some(10),
    }
}

pub fn harness(options: StartupOptions, state: &Path) -> Harness<'static, StudioApp> {
    let options = StartupOptions {
        state_dir: Some(state.to_path_buf()),
        ..options
    };
    let mut h = Harness::builder()
        .with_size(egui::vec2(1280.0, 800.0))
        .wgpu()
        .build_eframe(move |cc| StudioApp::new(cc, options));
    h.run_steps(3);
    h
}

pub fn open_bar(name: &str) -> (Harness<'static, StudioApp>, PathBuf) {
    let dir = temp_dir(name);
    let h = harness(
        StartupOptions {
            source: Some(bar()),
            ..Default::default()
        },
        &dir,
    );
    (h, dir)
}

/// Screen position of a world point in a view.
pub fn screen_of(h: &Harness<'_, StudioApp>, view: usize, p: DVec3) -> Pos2 {
    let app = h.state();
    let s = app.view.views[view].projection().project(p).unwrap();
    let rect = app.tools.interaction.view_rects[view];
    Pos2::new(rect.left() + s.x as f32, rect.top() + s.y as f32)
}

pub fn press(h: &Harness<'_, StudioApp>, pos: Pos2, pressed: bool, modifiers: Modifiers) {
    h.event(Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed,
        modifiers,
    });
}

pub fn click(h: &mut Harness<'_, StudioApp>, pos: Pos2, modifiers: Modifiers) {
    h.hover_at(pos);
    h.step();
    press(h, pos, true, modifiers);
    h.step();
    press(h, pos, false, modifiers);
    h.run_steps(2);
}

pub fn drag(h: &mut Harness<'_, StudioApp>, from: Pos2, to: Pos2) {
    h.hover_at(from);
    h.step();
    press(h, from, true, Modifiers::NONE);
    h.step();
    for i in 1..=8 {
        let t = i as f32 / 8.0;
        h.hover_at(from + (to - from) * t);
        h.step();
    }
    press(h, to, false, Modifiers::NONE);
    h.run_steps(2);
}

/// A cage vertex facing the camera in `view` (front view: largest z), and its position.
pub fn front_cage_vertex(h: &Harness<'_, StudioApp>, view: usize) -> (usize, DVec3) {
    let s = &h.state().project.doc.as_ref().unwrap().session;
    let cage = if view == CURRENT {
        s.posed_cage()
    } else {
        s.rest_cage()
    };
    let eye = h.state().view.views[view].camera.eye();
    let (k, p) = cage
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.distance(eye).total_cmp(&b.1.distance(eye)))
        .unwrap();
    (k, *p)
}

/// Clicks the middle joint in the current view: its index and screen position.
pub fn click_middle_joint(h: &mut Harness<'_, StudioApp>) -> (usize, Pos2) {
    let s = &h.state().project.doc.as_ref().unwrap().session;
    let j = s.skeleton().len() / 2;
    let at = screen_of(h, CURRENT, s.posed_world_from_joint()[j].translation);
    click(h, at, Modifiers::NONE);
    assert_eq!(h.state().tools.selection.joint, Some(j));
    (j, at)
}

/// Clicks the current cage vertex nearest the camera: its index, position and screen position.
pub fn click_front_cage_vertex(h: &mut Harness<'_, StudioApp>) -> (usize, DVec3, Pos2) {
    let (k, p) = front_cage_vertex(h, CURRENT);
    let at = screen_of(h, CURRENT, p);
    click(h, at, Modifiers::NONE);
    (k, p, at)
}

pub fn snapshot(h: &Harness<'_, StudioApp>) -> Snapshot {
    h.state().project.doc.as_ref().unwrap().snapshot()
}

/// Steps the UI until a background load has finished (at most 60 s).
pub fn wait_for_open(h: &mut Harness<'_, StudioApp>) {
    let start = std::time::Instant::now();
    while h.state().is_opening() {
        assert!(
            start.elapsed().as_secs() < 60,
            "the rig did not load within 60 s"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
        h.step();
    }
    h.run_steps(2);
}
