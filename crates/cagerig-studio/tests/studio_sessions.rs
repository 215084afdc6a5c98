//! The editor's files driven through its real UI with egui_kittest (lavapipe where there is no
//! GPU): a saved session reopens to the same state and picture, a corrupt one changes nothing,
//! box selection, the autosave offered at the next start, and a hybrid export that reopens with
//! its cage keys. `CAGERIG_SKIP_GPU_TESTS=1` skips them where no wgpu adapter exists.

// tests, benches and examples may panic on a broken fixture

use std::path::Path;

use cagerig_studio::StartupOptions;
use cagerig_studio::keys::Track;
use cagerig_studio::rig_open::RigSource;
use cagerig_studio::session_file::SessionFile;
use cagerig_studio::view_state::{CURRENT, REST};
use egui_kittest::kittest::Queryable;
use glam::{DVec2, DVec3};

#[expect(
    dead_code,
    reason = "each test binary uses a part of the shared helpers"
)]
mod support;
use support::*;

#[test]
fn a_saved_session_reopens_to_the_same_state_and_picture() {
    if skip() {
        return;
    }
    let dir = temp_dir("session");
    let script = dir.join("edits.json");
    std::fs::write(
        &script,
        r#"{"steps":[{"op":"rotate_joint","joint":3,"axis":[0,0,1],"degrees":35},
                      {"op":"move_posed_cage","vertices":[1,2],"offset":[0,0.1,0]}]}"#,
    )
    .unwrap();
    let path = dir.join("a.cagerig");
    // As `cagerig-studio --builtin bar --script edits.json --save-session a.cagerig`.
    let mut h = harness(
        StartupOptions {
            source: Some(bar()),
            script: Some(script.clone()),
            save_session: Some(path.clone()),
            ..Default::default()
        },
        &dir,
    );
    assert!(path.is_file(), "{:?}", h.state().diagnostics.log);
    assert_eq!(
        h.state().project.doc.as_ref().unwrap().history().undo_len(),
        2
    );
    h.run_steps(2);
    let first = h.render().unwrap();
    let state = snapshot(&h);
    let mut again = harness(
        StartupOptions {
            session: Some(path.clone()),
            ..Default::default()
        },
        &dir,
    );
    assert_eq!(snapshot(&again), state);
    let second = again.render().unwrap();
    if let Ok(out) = std::env::var("CAGERIG_STUDIO_TEST_IMAGES") {
        first.save(format!("{out}/session_first.png")).unwrap();
        second.save(format!("{out}/session_second.png")).unwrap();
    }
    // The 3D views (the log and the status bar say different things) match.
    let mut differing = 0;
    let mut total = 0;
    for view in [CURRENT, REST] {
        let r = h.state().tools.interaction.view_rects[view];
        assert_eq!(r, again.state().tools.interaction.view_rects[view]);
        for y in r.top() as u32..r.bottom() as u32 {
            for x in r.left() as u32..r.right() as u32 {
                let (a, b) = (first.get_pixel(x, y).0, second.get_pixel(x, y).0);
                total += 1;
                if a.iter().zip(b).any(|(p, q)| p.abs_diff(q) > 8) {
                    differing += 1;
                }
            }
        }
    }
    assert!(
        differing < total / 1000,
        "{differing} of {total} view pixels differ"
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_corrupt_session_is_reported_and_changes_nothing() {
    if skip() {
        return;
    }
    let dir = temp_dir("corrupt");
    let path = dir.join("bad.cagerig");
    std::fs::write(
        &path,
        "{\"format\": \"cagerig-studio-session\", \"version\": 1, \"sour",
    )
    .unwrap();
    let h = harness(
        StartupOptions {
            session: Some(path.clone()),
            ..Default::default()
        },
        &dir,
    );
    let app = h.state();
    assert!(
        app.diagnostics
            .log
            .iter()
            .any(|l| l.text.contains("bad.cagerig")),
        "{:?}",
        app.diagnostics.log
    );
    assert!(app.project.doc.is_some(), "falls back to the demo");
    assert!(std::fs::read_to_string(&path).unwrap().ends_with("sour"));
    let mut value = serde_json::to_value(SessionFile::new(bar(), snapshot(&h), 0.0)).unwrap();
    value["version"] = 99.into();
    std::fs::write(&path, value.to_string()).unwrap();
    let h = harness(
        StartupOptions {
            session: Some(path.clone()),
            ..Default::default()
        },
        &dir,
    );
    assert!(
        h.state()
            .diagnostics
            .log
            .iter()
            .any(|l| l.text.contains("newer"))
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn box_selection_picks_only_visible_cage_vertices() {
    if skip() {
        return;
    }
    let (mut h, dir) = open_bar("box");
    // Looking along the bar, its far cage ring is hidden behind the skin.
    h.state_mut()
        .frame_views(Some(cagerig_render::CameraPreset::Side));
    h.run_steps(2);
    let rect = h.state().tools.interaction.view_rects[CURRENT];
    drag(
        &mut h,
        rect.left_top() + egui::vec2(5.0, 30.0),
        rect.right_bottom() - egui::vec2(5.0, 5.0),
    );
    let selected = h.state().tools.selection.cage.len();
    let total = h
        .state()
        .project
        .doc
        .as_ref()
        .unwrap()
        .session
        .rest_cage()
        .len();
    assert!(selected > 0 && selected < total, "{selected} of {total}");
    let _ = DVec2::ZERO;
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn an_autosave_is_offered_at_the_next_start_and_recovers_the_work() {
    if skip() {
        return;
    }
    let dir = temp_dir("recovery");
    let mut h = harness(
        StartupOptions {
            source: Some(bar()),
            ..Default::default()
        },
        &dir,
    );
    h.state_mut()
        .run_command(&cagerig_studio::document::Command::MoveRestCage {
            vertices: vec![0, 1],
            offsets: vec![DVec3::new(0.0, 0.2, 0.0)],
        });
    let edited = snapshot(&h);
    assert!(h.state_mut().autosave_now());
    // The editor "crashes": no clean exit. The next start offers the recovery.
    drop(h);
    let mut again = harness(
        StartupOptions {
            source: Some(bar()),
            ..Default::default()
        },
        &dir,
    );
    assert!(again.state().dialogs.recovery.is_some());
    again.get_by_label("Recover").click();
    again.run_steps(2);
    wait_for_open(&mut again);
    assert_eq!(snapshot(&again), edited);
    assert!(again.state().dialogs.recovery.is_none());
    assert!(
        again.state().project.session_path.is_none(),
        "a recovered session is not saved back over the autosave"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// A cagerig glTF export of the Arm's hybrid animation (skeleton + cage track) opened in the
/// editor with the cage it carries: File > Load animation puts its joint keys on the skeleton
/// track and its morph weights on the cage track as cage keys, and playback (SkelUp held: the
/// joint keys already carry the rest joints' motion) shows cagerig's own result to 1e-5 of the
/// diagonal.
#[test]
fn a_hybrid_export_reopens_with_its_cage_keys_and_plays_as_exported() {
    use cagerig::playback::{AnimationPlayer, PoseChannels};
    use cagerig::session::{RigSession, SessionOptions};
    if skip() {
        return;
    }
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm");
    let files = cagerig::rig_files::load_rig_files(&data.join("arm.obj"), None).unwrap();
    let mut original = RigSession::new(files.parts, SessionOptions::default())
        .unwrap()
        .0;
    let skeleton_track = cagerig::io::skeleton_animation::read_skeleton_animation(
        &data.join("arm_skelAnim.txt"),
        original.skeleton(),
    )
    .unwrap()
    .0;
    let cage_track = cagerig::io::read_cage_animation(
        &data.join("arm_cageAnim.txt"),
        original.rest_cage().len(),
    )
    .unwrap();
    let mut player = AnimationPlayer::with_channels(
        &original,
        Some(skeleton_track.clone()),
        Some(cage_track.clone()),
        PoseChannels::RotationsAndRootMotion,
    )
    .unwrap();
    let keys: Vec<f64> = skeleton_track
        .times()
        .iter()
        .chain(cage_track.times())
        .copied()
        .collect();
    let times =
        cagerig_formats::gltf::export_animation::sample_times(player.duration(), 30.0, &keys);
    let (document, bin, _) = cagerig_formats::gltf::export_animation::animation_to_gltf(
        &mut original,
        &mut player,
        Some(&cage_track),
        &times,
        "arm",
        "arm",
        false,
    )
    .unwrap();
    let dir = temp_dir("hybrid");
    let path = dir.join("arm_anim.glb");
    cagerig_formats::gltf::export::write_gltf_or_glb(&path, &document, &bin).unwrap();

    let mut h = harness(
        StartupOptions {
            source: Some(RigSource::file(&path)),
            ..Default::default()
        },
        &dir.join("state"),
    );
    assert_eq!(h.state().project.animations.len(), 1);
    h.state_mut().load_character_animation(0);
    h.run_steps(1);
    let doc_keys = &h.state().project.doc.as_ref().unwrap().keys;
    assert_eq!(
        doc_keys.len(Track::Cage),
        times.len(),
        "a cage key per sample"
    );
    assert!(doc_keys.hold_rest_skeleton);
    let (lo, hi) = cagerig::mesh::bounding_box(original.rest_mesh());
    let diagonal = (hi - lo).length();
    for t in [0.37, 2.5, 6.1] {
        player.apply(t, &mut original).unwrap();
        h.state_mut().scrub_to(t);
        let shown = &h.state().project.doc.as_ref().unwrap().session;
        let off = cagerig::mesh::max_distance(shown.posed_mesh(), original.posed_mesh());
        assert!(
            off <= 1e-5 * diagonal,
            "t = {t}: {:e} of the diagonal",
            off / diagonal
        );
    }
    std::fs::remove_dir_all(dir).ok();
}
