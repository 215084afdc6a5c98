//! The Rig panel's coordinates switch: clicking "Green" rebinds the open rig with Green
//! coordinates in one undo step, keeping the edits; undo goes back to mean value coordinates.
//! `CAGERIG_SKIP_GPU_TESTS=1` skips it where no wgpu adapter exists.

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests, benches and examples may panic on a broken fixture

use cagerig::CoordsKind;
use egui::Modifiers;
use egui_kittest::kittest::Queryable;

mod support;

#[test]
fn the_coordinates_switch_rebinds_in_one_undo_step() {
    if support::skip() {
        return;
    }
    let (mut h, state) = support::open_bar("coordinates-switch");
    let doc = h.state().project.doc.as_ref().unwrap();
    assert_eq!(doc.session.coords_kind(), CoordsKind::Mvc);
    let before = doc.session.editable_state();
    let rest = doc.session.rest_mesh().to_vec();
    h.get_by_label("Green").click();
    h.run_steps(3);
    let doc = h.state().project.doc.as_ref().unwrap();
    assert_eq!(doc.session.coords_kind(), CoordsKind::Green);
    assert_eq!(doc.history().undo_len(), 1, "one switch = one undo step");
    let (lo, hi) = cagerig::mesh::bounding_box(doc.session.rest_cage());
    let moved = cagerig::mesh::max_distance(&rest, doc.session.rest_mesh());
    assert!(
        moved < 1e-9 * (hi - lo).length(),
        "the rest mesh moved by {moved}"
    );
    h.key_press_modifiers(Modifiers::COMMAND, egui::Key::Z);
    h.run_steps(3);
    let doc = h.state().project.doc.as_ref().unwrap();
    assert_eq!(doc.session.coords_kind(), CoordsKind::Mvc);
    assert_eq!(doc.session.editable_state(), before);
    std::fs::remove_dir_all(state).ok();
}
