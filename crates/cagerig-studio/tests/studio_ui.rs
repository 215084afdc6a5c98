//! The editor driven through its real UI with egui_kittest on a wgpu device (a software one —
//! lavapipe — on machines without a GPU): selecting by clicking projected positions, dragging,
//! G/R/S keys with typed values, numeric entry, undo / redo, keys and playback, session files
//! and the skinning switch. `CAGERIG_SKIP_GPU_TESTS=1` skips them where no wgpu adapter exists.

// tests, benches and examples may panic on a broken fixture

use std::path::{Path, PathBuf};

use cagerig_studio::StudioApp;
use cagerig_studio::gizmo;
use cagerig_studio::keys::Track;
use cagerig_studio::opening::{AfterConfirm, OpenRequest};
use cagerig_studio::view_state::{CURRENT, REST};
use egui::{Event, Modifiers, Pos2};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use glam::{DQuat, DVec2, DVec3};

mod support;
use support::*;

#[test]
fn opens_the_demo_and_draws_both_views() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("draw");
    let app = h.state();
    assert!(app.project.doc.is_some(), "log: {:?}", app.diagnostics.log);
    assert!(
        app.view.render_error.is_none(),
        "{:?}",
        app.view.render_error
    );
    let image = h.render().unwrap();
    // The skin (clay) is drawn where its centre projects in each view.
    for view in [CURRENT, REST] {
        let s = &h.state().project.doc.as_ref().unwrap().session;
        let mesh = if view == CURRENT {
            s.posed_mesh()
        } else {
            s.rest_mesh()
        };
        let centre = mesh.iter().copied().sum::<DVec3>() / mesh.len() as f64;
        let nearest = mesh
            .iter()
            .min_by(|a, b| a.distance(centre).total_cmp(&b.distance(centre)))
            .unwrap();
        let p = screen_of(&h, view, *nearest);
        let ppp = 1.0;
        let px = image.get_pixel((p.x * ppp) as u32, (p.y * ppp) as u32);
        let [r, _, b, _] = px.0;
        // Not the white/blue backdrop: a warm grey with r ≥ b.
        assert!(
            r < 250 && r >= b.saturating_sub(10),
            "view {view}: pixel {:?} at {p:?}",
            px.0
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn click_selects_a_cage_vertex_and_drag_lands_it_under_the_mouse_then_undo_restores() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("drag");
    let before = snapshot(&h);
    let (k, _, at) = click_front_cage_vertex(&mut h);
    assert_eq!(
        h.state()
            .tools
            .selection
            .cage
            .iter()
            .copied()
            .collect::<Vec<_>>(),
        [k]
    );
    let to = at + egui::vec2(40.0, -25.0);
    drag(&mut h, at, to);
    let doc = h.state().project.doc.as_ref().unwrap();
    assert_eq!(doc.history().undo_len(), 1, "one drag = one undo step");
    let landed = screen_of(&h, CURRENT, doc.session.posed_cage()[k]);
    // Pointer positions reach egui rounded to the pixel grid: within a pixel.
    assert!(
        landed.distance(to) < 1.0,
        "C'[{k}] landed at {landed:?}, mouse at {to:?}"
    );
    assert_ne!(snapshot(&h), before);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(2);
    assert_eq!(snapshot(&h), before, "undo restores the exact state");
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, egui::Key::Z);
    h.run_steps(2);
    assert_ne!(snapshot(&h), before, "redo");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn the_gizmo_plane_handle_moves_the_selection_in_its_plane_only() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("plane");
    let (k, p, _) = click_front_cage_vertex(&mut h);
    // A three-quarter view so that the plane normal to Y faces the camera.
    h.state_mut().view.views[CURRENT].camera.yaw = 0.6;
    h.state_mut().view.views[CURRENT].camera.pitch = 0.5;
    h.run_steps(2);
    let (pivot, arrows, _) = h.state().gizmo_pivot(CURRENT).unwrap();
    assert!(arrows, "the move tool shows arrows and plane handles");
    let projection = h.state().view.views[CURRENT].projection();
    let square = gizmo::plane_square(&projection, pivot, gizmo::Axis::Y).unwrap();
    let centre = square.iter().copied().sum::<DVec2>() / 4.0;
    let rect = h.state().tools.interaction.view_rects[CURRENT];
    let from = Pos2::new(rect.left() + centre.x as f32, rect.top() + centre.y as f32);
    drag(&mut h, from, from + egui::vec2(30.0, 12.0));
    let doc = h.state().project.doc.as_ref().unwrap();
    assert_eq!(doc.history().undo_len(), 1, "one drag = one undo step");
    let moved = doc.session.posed_cage()[k] - p;
    assert!(moved.length() > 1e-3, "C'[{k}] moved by {moved}");
    assert!(moved.y.abs() < 1e-9, "C'[{k}] left the XZ plane: {moved}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn typing_a_joint_rotation_in_the_inspector_sets_it_in_one_undo_step() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("euler");
    let (j, _) = click_middle_joint(&mut h);
    // The three Euler fields (X, Y, Z; unlabelled, shown as 0.0 at rest, never -0.0); type 40
    // into Z.
    let fields: Vec<_> = h
        .get_all_by_role(egui::accesskit::Role::SpinButton)
        .filter(|n| n.value().as_deref() == Some("0.0"))
        .collect();
    assert_eq!(fields.len(), 3, "the joint's Euler X, Y, Z fields");
    fields[2].click();
    h.run_steps(2);
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::A);
    h.event(Event::Text("40".into()));
    h.step();
    h.key_press(egui::Key::Enter);
    h.run_steps(3);
    let s = &h.state().project.doc.as_ref().unwrap().session;
    let expected = DQuat::from_rotation_z(40f64.to_radians());
    assert!(
        s.posed_local_rotations()[j].abs_diff_eq(expected, 1e-9)
            || s.posed_local_rotations()[j].abs_diff_eq(-expected, 1e-9),
        "{:?}",
        s.posed_local_rotations()[j]
    );
    assert_eq!(
        h.state().project.doc.as_ref().unwrap().history().undo_len(),
        1
    );
    std::fs::remove_dir_all(dir).ok();
}

/// A file dropped on the window, as the windowing integration hands it to egui.
#[derive(Debug)]
struct DroppedPath(PathBuf);

impl egui::DroppedFile for DroppedPath {
    fn path(&self) -> &Path {
        &self.0
    }
    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

#[test]
fn a_dropped_character_file_is_opened() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("drop");
    let arm = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm/arm.obj");
    // With unsaved edits, dropping a file asks first; Cancel keeps the bar and its edits.
    let (_, _, at) = click_front_cage_vertex(&mut h);
    drag(&mut h, at, at + egui::vec2(20.0, 0.0));
    assert!(h.state().unsaved());
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(DroppedPath(arm.clone())));
    h.run_steps(2);
    assert!(matches!(
        h.state().dialogs.confirm,
        Some(AfterConfirm::Open(OpenRequest::Rig(_)))
    ));
    h.get_by_label("Cancel").click();
    h.run_steps(2);
    assert!(h.state().dialogs.confirm.is_none() && !h.state().is_opening());
    assert!(h.state().unsaved(), "the bar and its edit stay");
    // Drop again and discard the edits: the Arm loads in the background, then replaces the bar.
    h.input_mut()
        .dropped_files
        .push(std::sync::Arc::new(DroppedPath(arm)));
    h.run_steps(2);
    h.get_by_label("Don't save").click();
    h.step();
    assert!(h.state().is_opening(), "loading in the background");
    wait_for_open(&mut h);
    let s = &h.state().project.doc.as_ref().unwrap().session;
    assert_eq!(
        (s.num_vertices(), s.skeleton().len(), s.rest_cage().len()),
        (2089, 25, 58),
        "the Arm replaced the bar"
    );
    assert!(!h.state().unsaved());
    std::fs::remove_dir_all(dir).ok();
}

/// Asks the window to close, as the window manager's close button does.
fn request_close(h: &mut Harness<'_, StudioApp>) {
    h.input_mut()
        .viewports
        .entry(egui::ViewportId::ROOT)
        .or_default()
        .events
        .push(egui::ViewportEvent::Close);
    h.step();
}

fn root_commands(h: &Harness<'_, StudioApp>) -> Vec<egui::ViewportCommand> {
    h.output()
        .viewport_output
        .get(&egui::ViewportId::ROOT)
        .map(|v| v.commands.clone())
        .unwrap_or_default()
}

#[test]
fn closing_with_unsaved_edits_asks_and_saves_or_discards() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("close");
    // Nothing edited: the window closes without asking.
    request_close(&mut h);
    assert!(h.state().dialogs.confirm.is_none());
    assert!(!root_commands(&h).contains(&egui::ViewportCommand::CancelClose));
    // An edit, then a close request: held back and asked about; Cancel keeps working.
    let (k, _, at) = click_front_cage_vertex(&mut h);
    drag(&mut h, at, at + egui::vec2(20.0, 0.0));
    assert!(h.state().unsaved());
    request_close(&mut h);
    assert!(root_commands(&h).contains(&egui::ViewportCommand::CancelClose));
    assert_eq!(h.state().dialogs.confirm, Some(AfterConfirm::Close));
    h.run_steps(2);
    h.get_by_label("Cancel").click();
    h.run_steps(2);
    assert!(h.state().dialogs.confirm.is_none() && !h.state().dialogs.close_approved);
    // Save: with a session path the edits are written there, then the window may close.
    let path = dir.join("closing.cagerig");
    h.state_mut().project.session_path = Some(path.clone());
    request_close(&mut h);
    h.run_steps(2);
    h.get_by_label("Save").click();
    h.step();
    assert!(path.exists(), "saved before closing");
    assert!(!h.state().unsaved() && h.state().dialogs.close_approved);
    assert!(root_commands(&h).contains(&egui::ViewportCommand::Close));
    // Don't save: another edit is discarded on request.
    h.state_mut().dialogs.close_approved = false;
    let at = screen_of(
        &h,
        CURRENT,
        h.state().project.doc.as_ref().unwrap().session.posed_cage()[k],
    );
    drag(&mut h, at, at + egui::vec2(0.0, 15.0));
    assert!(h.state().unsaved());
    request_close(&mut h);
    h.run_steps(2);
    h.get_by_label("Don't save").click();
    h.step();
    assert!(h.state().dialogs.close_approved && h.state().unsaved());
    assert!(root_commands(&h).contains(&egui::ViewportCommand::Close));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn rest_view_drag_moves_the_rest_cage_and_the_bones_follow() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("rest");
    let joints0: Vec<DVec3> = h
        .state()
        .project
        .doc
        .as_ref()
        .unwrap()
        .session
        .rest_joints()
        .collect();
    h.state_mut().select_all();
    h.step();
    let (_, p) = front_cage_vertex(&h, REST);
    let at = screen_of(&h, REST, p);
    drag(&mut h, at, at + egui::vec2(0.0, -30.0));
    let s = &h.state().project.doc.as_ref().unwrap().session;
    let joints1: Vec<DVec3> = s.rest_joints().collect();
    // The whole cage moved (up on screen, in the view plane): SkelUp moves every joint by the
    // same translation.
    let d = joints1[0] - joints0[0];
    assert!(d.y > 0.0, "{d}");
    for (a, b) in joints1.iter().zip(&joints0) {
        assert!((*a - *b - d).length() < 1e-9);
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn keys_select_a_joint_and_rotate_it_by_a_typed_angle() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("rotate");
    let (j, at) = click_middle_joint(&mut h);
    // R, Z, 3, 0, Enter: 30° about world Z.
    h.hover_at(at + egui::vec2(50.0, 0.0));
    h.step();
    h.key_press(egui::Key::R);
    h.step();
    h.key_press(egui::Key::Z);
    h.event(Event::Text("30".into()));
    h.step();
    h.key_press(egui::Key::Enter);
    h.run_steps(2);
    let mut reference = cagerig_studio::rig_open::open_rig(&bar()).unwrap().session;
    reference
        .rotate_joint(j, DVec3::Z, 30f64.to_radians())
        .unwrap();
    let s = &h.state().project.doc.as_ref().unwrap().session;
    for (a, b) in s.posed_mesh().iter().zip(reference.posed_mesh()) {
        assert!(a.distance(*b) < 1e-9, "{a} vs {b}");
    }
    assert_eq!(
        h.state().project.doc.as_ref().unwrap().history().undo_len(),
        1
    );
    // Esc cancels a transform: R then a value then Esc leaves the state as it was.
    let before = snapshot(&h);
    h.key_press(egui::Key::R);
    h.event(Event::Text("45".into()));
    h.step();
    h.key_press(egui::Key::Escape);
    h.run_steps(2);
    assert_eq!(snapshot(&h), before);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn numeric_offset_buttons_and_the_skinning_switch_are_undoable() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("numeric");
    let before = snapshot(&h);
    h.state_mut().tools.selection.cage.insert(0);
    h.state_mut().tools.numeric.offset = [0.0, 0.25, 0.0];
    h.run_steps(2);
    h.get_by_label("Move rest cage C").click();
    h.run_steps(2);
    let c = h.state().project.doc.as_ref().unwrap().session.rest_cage()[0];
    assert!((c.y - before.rig.rest_cage[0].y - 0.25).abs() < 1e-12);
    h.get_by_label("DQS").click();
    h.run_steps(2);
    assert_eq!(
        h.state().project.doc.as_ref().unwrap().session.skinning(),
        cagerig::skinning::SkinningMethod::Dqs
    );
    h.state_mut().undo();
    h.state_mut().undo();
    h.run_steps(1);
    assert_eq!(snapshot(&h), before);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn keys_are_set_deleted_and_played_from_the_timeline() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("keys");
    h.get_by_label("Key skeleton").click();
    h.run_steps(1);
    h.state_mut().scrub_to(1.0);
    let j = h
        .state()
        .project
        .doc
        .as_ref()
        .unwrap()
        .session
        .skeleton()
        .len()
        / 2;
    h.state_mut()
        .run_command(&cagerig_studio::document::Command::RotateJoint {
            joint: j,
            axis: DVec3::Z,
            angle: 0.8,
        });
    h.get_by_label("Key skeleton").click();
    h.get_by_label("Key cage").click();
    h.run_steps(1);
    let keys = &h.state().project.doc.as_ref().unwrap().keys;
    assert_eq!((keys.len(Track::Skeleton), keys.len(Track::Cage)), (2, 1));
    h.get_by_label("Delete key").click();
    h.run_steps(1);
    assert_eq!(
        h.state()
            .project
            .doc
            .as_ref()
            .unwrap()
            .keys
            .len(Track::Cage),
        0
    );
    h.state_mut().scrub_to(0.0);
    let posed0 = h
        .state()
        .project
        .doc
        .as_ref()
        .unwrap()
        .session
        .posed_mesh()
        .to_vec();
    h.get_by_label("Play").click();
    h.run_steps(20);
    assert!(h.state().timeline.time > 0.0);
    assert_ne!(
        h.state().project.doc.as_ref().unwrap().session.posed_mesh(),
        &posed0[..]
    );
    std::fs::remove_dir_all(dir).ok();
}

/// The first `BrainStem.glb` under the folders of `CAGERIG_GLTF_SWEEP` (searched recursively):
/// the repository does not ship it (© Smith Micro Software, Poser EULA).
fn brainstem_from_sweep() -> Option<PathBuf> {
    fn find(dir: &Path) -> Option<PathBuf> {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .ok()?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        paths.sort();
        if let Some(p) = paths
            .iter()
            .find(|p| p.is_file() && p.file_name().is_some_and(|f| f == "BrainStem.glb"))
        {
            return Some(p.clone());
        }
        paths.iter().filter(|p| p.is_dir()).find_map(|p| find(p))
    }
    let dirs = std::env::var_os("CAGERIG_GLTF_SWEEP")?;
    std::env::split_paths(&dirs).find_map(|d| find(&d))
}

/// File > Open takes the skin of a file with several (BrainStem's 59 skins share one skeleton
/// and open as one rig by default): the dialog's skin field, by index, opens that skin alone.
/// Runs only when `CAGERIG_GLTF_SWEEP` names a folder holding `BrainStem.glb`.
#[test]
fn the_open_dialog_chooses_a_skin_of_a_file_with_several() {
    if skip() {
        return;
    }
    let Some(brainstem) = brainstem_from_sweep() else {
        println!(
            "skipped: no BrainStem.glb under CAGERIG_GLTF_SWEEP (the repository does not ship it; \
             set CAGERIG_GLTF_SWEEP to a folder holding it to run this test)"
        );
        return;
    };
    let (mut h, dir) = open_bar("skin");
    let app = h.state_mut();
    app.dialogs.skin = " 3 ".into();
    app.dialogs.generate_cage = true;
    app.dialogs.cage_vertices = 40;
    app.open_path(&brainstem);
    wait_for_open(&mut h);
    let app = h.state();
    let doc = app.project.doc.as_ref().unwrap();
    assert_eq!(
        doc.session.num_vertices(),
        1064,
        "log: {:?}",
        app.diagnostics.log
    );
    assert_eq!(doc.session.skeleton().len(), 18);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_cage_fit_and_the_reach_map_are_chosen_in_the_inspector() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("cage-fit");
    let regularised = || cagerig::CageFitKind::Regularised;
    assert_eq!(
        h.state().project.doc.as_ref().unwrap().session.cage_fit(),
        regularised()
    );
    h.get_by_label("paper").click();
    h.run_steps(2);
    assert_eq!(
        h.state().project.doc.as_ref().unwrap().session.cage_fit(),
        cagerig::CageFitKind::Paper
    );
    h.state_mut().undo();
    h.run_steps(1);
    assert_eq!(
        h.state().project.doc.as_ref().unwrap().session.cage_fit(),
        regularised()
    );
    h.get_by_label("Cage handles far from the body").click();
    h.run_steps(2);
    assert_eq!(
        h.state().view.color_mode,
        cagerig_studio::view_state::ColorMode::CageReach
    );
    assert!(h.state().view.render_error.is_none());
    std::fs::remove_dir_all(dir).ok();
}
