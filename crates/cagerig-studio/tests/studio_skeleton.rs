//! Rigging a mesh with no skeleton in the studio, through its real UI (egui_kittest on a wgpu
//! device — lavapipe where there is no GPU): open an OBJ with no rig, add a chain of three
//! joints by clicking on the mesh in the rest view, move one with G, Bind (automatic weights on a background
//! thread), rotate a joint in the current view, and the mesh deforms. The test saves a
//! screenshot (`$CAGERIG_STUDIO_TEST_IMAGES/skeleton_built.png`, else in the temporary folder).
//! `CAGERIG_SKIP_GPU_TESTS=1` skips it where no wgpu adapter exists.

// tests, benches and examples may panic on a broken fixture

use std::time::{Duration, Instant};

use cagerig_studio::rig_open::RigSource;
use cagerig_studio::view_state::{CURRENT, REST};
use cagerig_studio::{StartupOptions, StudioApp};
use egui::{Event, Modifiers};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;
use support::{click, screen_of};

#[test]
fn a_mesh_with_no_rig_gets_a_clicked_skeleton_binds_and_poses() {
    if std::env::var_os("CAGERIG_SKIP_GPU_TESTS").is_some_and(|v| v == "1") {
        return;
    }
    let dir = std::env::temp_dir().join(format!("cagerig-studio-skeleton-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A bar along y with no skeleton beside it.
    let bar = cagerig_studio::rig_open::open_rig(&RigSource::Builtin {
        name: "bar".into(),
        resolution: Some(24),
    })
    .unwrap()
    .session;
    let mesh = dir.join("bar.obj");
    cagerig::io::write_obj(&mesh, bar.rest_mesh(), bar.mesh_triangles()).unwrap();
    let options = StartupOptions {
        source: Some(RigSource::File {
            path: mesh,
            cage: None,
            skin: None,
            auto_cage: Some(40),
        }),
        state_dir: Some(dir.clone()),
        ..Default::default()
    };
    let mut h = Harness::builder()
        .with_size(egui::vec2(1280.0, 800.0))
        .wgpu()
        .build_eframe(move |cc| StudioApp::new(cc, options));
    h.run_steps(3);
    let doc = h.state().project.doc.as_ref().unwrap();
    assert!(!doc.rigged(), "{:?}", h.state().diagnostics.log);
    assert!(doc.shown_skeleton(true).positions.is_empty());
    let (lo, hi) = cagerig::mesh::bounding_box(doc.session.rest_mesh());
    let diagonal = (hi - lo).length();
    let axis = (hi - lo).max_position();

    // Three clicks on the mesh in the rest view, along the bar: a chain.
    h.get_by_label("Add joints by clicking").click();
    h.run_steps(2);
    for k in 0..3 {
        let mut p = 0.5 * (lo + hi);
        p[axis] = lo[axis] + (0.15 + 0.35 * k as f64) * (hi[axis] - lo[axis]);
        let at = screen_of(&h, REST, p);
        click(&mut h, at, Modifiers::NONE);
    }
    let doc = h.state().project.doc.as_ref().unwrap();
    let draft = doc.draft.as_ref().expect("a skeleton being built");
    assert_eq!(draft.len(), 3, "{:?}", h.state().diagnostics.log);
    assert_eq!(draft.parents(), vec![None, Some(0), Some(1)]);
    let centre = 0.5 * (lo + hi);
    for j in &draft.joints {
        // In the middle of the body, not on its surface.
        let mut off = j.position - centre;
        off[axis] = 0.0;
        assert!(
            off.length() < 0.05 * diagonal,
            "{} at {}",
            j.name,
            j.position
        );
    }
    assert_eq!(doc.history().undo_len(), 3, "one undo step per joint");

    // G, the axis key, a typed distance, Enter: the selected joint moves along the bar.
    let before = draft.joints[2].position;
    let step = -0.05 * (hi[axis] - lo[axis]);
    let at = screen_of(&h, REST, before);
    h.hover_at(at + egui::vec2(30.0, 30.0));
    h.step();
    h.key_press(egui::Key::G);
    h.step();
    h.key_press([egui::Key::X, egui::Key::Y, egui::Key::Z][axis]);
    // Minus toggles the sign (Blender's way), the digits are typed.
    h.key_press(egui::Key::Minus);
    h.event(Event::Text(format!("{}", -step)));
    h.step();
    h.key_press(egui::Key::Enter);
    h.run_steps(2);
    let doc = h.state().project.doc.as_ref().unwrap();
    let moved = doc.draft.as_ref().unwrap().joints[2].position;
    let mut expected = before;
    expected[axis] += step;
    assert!(
        moved.distance(expected) < 1e-9 * diagonal,
        "{moved} vs {expected}"
    );
    assert_eq!(doc.history().undo_len(), 4, "a move is one undo step");

    // Bind: automatic weights in the background, then one undo step.
    h.get_by_label("Add joints by clicking").click();
    if let Ok(out) = std::env::var("CAGERIG_STUDIO_TEST_IMAGES") {
        h.render()
            .unwrap()
            .save(format!("{out}/skeleton_clicked.png"))
            .unwrap();
    }
    h.get_by_label("Bind").click();
    h.run_steps(2);
    let start = Instant::now();
    while h.state().project.doc.as_ref().unwrap().bind_job().is_some() {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "bind did not end"
        );
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    h.run_steps(2);
    let doc = h.state().project.doc.as_ref().unwrap();
    assert!(doc.rigged(), "{:?}", h.state().diagnostics.log);
    assert_eq!(doc.session.skeleton().len(), 3);
    assert_eq!(doc.history().undo_len(), 5, "a bind is one undo step");

    // Rotate the middle joint in the current view: R, Z, 40, Enter.
    let middle = doc.session.posed_world_from_joint()[1].translation;
    let rest_pose = doc.session.posed_mesh().to_vec();
    let at = screen_of(&h, CURRENT, middle);
    click(&mut h, at, Modifiers::NONE);
    assert_eq!(h.state().tools.selection.joint, Some(1));
    h.hover_at(at + egui::vec2(40.0, 0.0));
    h.step();
    h.key_press(egui::Key::R);
    h.step();
    h.key_press(egui::Key::Z);
    h.event(Event::Text("40".into()));
    h.step();
    h.key_press(egui::Key::Enter);
    h.run_steps(3);
    let doc = h.state().project.doc.as_ref().unwrap();
    let moved = cagerig::mesh::max_distance(&rest_pose, doc.session.posed_mesh());
    assert!(
        moved > 0.05 * diagonal,
        "the mesh moved by {moved} ({:?})",
        h.state().diagnostics.log
    );
    // The first third of the bar stays; the far end turns with the joint.
    let near = doc
        .session
        .posed_mesh()
        .iter()
        .zip(&rest_pose)
        .filter(|(_, r)| r[axis] < lo[axis] + 0.1 * (hi[axis] - lo[axis]))
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    assert!(near < 1e-3 * diagonal, "the root end moved by {near}");
    let image = h.render().unwrap();
    let out = std::env::var("CAGERIG_STUDIO_TEST_IMAGES")
        .map_or_else(|_| std::env::temp_dir(), Into::into);
    let path = out.join("skeleton_built.png");
    image.save(&path).unwrap();
    println!("screenshot: {}", path.display());
    std::fs::remove_dir_all(dir).ok();
}
