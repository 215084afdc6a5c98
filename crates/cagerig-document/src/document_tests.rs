//! Tests of the document: undo / redo, gestures, keys, scripts, and skeleton building.

use super::*;
use crate::rig_open::open_rig;

fn doc() -> Document {
    let source = RigSource::Builtin {
        name: "bar".into(),
        resolution: Some(6),
    };
    let opened = open_rig(&source).unwrap();
    Document::new(source, opened.session)
}

#[test]
fn undo_and_redo_restore_the_exact_state() {
    let mut d = doc();
    let s0 = d.snapshot();
    d.execute(&Command::RotateJoint {
        joint: 1,
        axis: DVec3::Z,
        angle: 0.5,
    })
    .unwrap();
    let s1 = d.snapshot();
    d.execute(&Command::MovePosedCage {
        vertices: vec![2, 3],
        offsets: vec![DVec3::new(0.0, 0.1, 0.0)],
    })
    .unwrap();
    let s2 = d.snapshot();
    assert!(d.undo().unwrap());
    assert_eq!(d.snapshot(), s1);
    assert!(d.undo().unwrap());
    assert_eq!(d.snapshot(), s0);
    assert!(!d.undo().unwrap());
    assert!(d.redo().unwrap());
    assert!(d.redo().unwrap());
    assert_eq!(d.snapshot(), s2);
}

#[test]
fn the_cage_fit_is_one_undo_step_that_refits_the_handle() {
    let mut d = doc();
    d.execute(&Command::RotateJoint {
        joint: 1,
        axis: DVec3::Z,
        angle: 0.8,
    })
    .unwrap();
    assert_eq!(d.session.cage_fit(), cagerig::CageFitKind::Regularised);
    let regularised = d.session.posed_cage().to_vec();
    let posed = d.session.posed_mesh().to_vec();
    d.execute(&Command::SetCageFit(cagerig::CageFitKind::Paper))
        .unwrap();
    assert_eq!(d.session.cage_fit(), cagerig::CageFitKind::Paper);
    assert_ne!(d.session.posed_cage(), &regularised[..]);
    assert_eq!(d.session.posed_mesh(), &posed[..]);
    assert!(d.undo().unwrap());
    assert_eq!(d.session.cage_fit(), cagerig::CageFitKind::Regularised);
    let tol = 1e-12;
    assert!(cagerig::mesh::max_distance(d.session.posed_cage(), &regularised) < tol);
}

#[test]
fn a_drag_is_one_undo_step_and_cancel_restores() {
    let mut d = doc();
    let s0 = d.snapshot();
    d.begin_gesture("drag");
    for _ in 0..5 {
        d.gesture_event(&Command::MoveRestCage {
            vertices: vec![0],
            offsets: vec![DVec3::new(0.01, 0.0, 0.0)],
        })
        .unwrap();
    }
    d.end_gesture();
    assert_eq!(d.history().undo_len(), 1);
    d.begin_gesture("drag 2");
    d.gesture_event(&Command::MoveRestCage {
        vertices: vec![1],
        offsets: vec![DVec3::new(0.0, 0.05, 0.0)],
    })
    .unwrap();
    let before_cancel = d.gesture_start().unwrap().clone();
    d.cancel_gesture().unwrap();
    assert_eq!(d.snapshot(), before_cancel);
    assert_eq!(d.history().undo_len(), 1);
    d.undo().unwrap();
    assert_eq!(d.snapshot(), s0);
}

#[test]
fn a_failed_command_changes_nothing_and_records_nothing() {
    let mut d = doc();
    let s0 = d.snapshot();
    let err = d
        .execute(&Command::MoveRestCage {
            vertices: vec![10_000],
            offsets: vec![DVec3::X],
        })
        .unwrap_err();
    assert!(err.to_string().contains("10000"), "{err}");
    assert_eq!(d.snapshot(), s0);
    assert_eq!(d.history().undo_len(), 0);
}

#[test]
fn keys_are_undoable() {
    let mut d = doc();
    d.execute(&Command::SetKey {
        track: Track::Cage,
        time: 0.5,
    })
    .unwrap();
    assert_eq!(d.keys.len(Track::Cage), 1);
    d.undo().unwrap();
    assert_eq!(d.keys.len(Track::Cage), 0);
    d.redo().unwrap();
    assert_eq!(d.keys.len(Track::Cage), 1);
}

#[test]
fn a_script_matches_the_library_run_of_the_same_script() {
    let text = r#"{"skinning":"dqs","steps":[
        {"op":"rotate_joint","joint":1,"axis":[0,0,1],"degrees":40},
        {"op":"move_rest_cage","vertices":[0,1],"offset":[0,0.2,0]},
        {"op":"move_posed_cage","vertices":[5],"offset":[0.1,0,0]}]}"#;
    let script = EditScript::parse(text).unwrap();
    let mut d = doc();
    d.run_script(&script).unwrap();
    assert_eq!(d.history().undo_len(), 4);
    let mut reference = doc();
    reference.session.set_skinning(SkinningMethod::Dqs).unwrap();
    for k in 0..script.steps.len() {
        script.run_step(k, &mut reference.session).unwrap();
    }
    for (a, b) in d
        .session
        .posed_mesh()
        .iter()
        .zip(reference.session.posed_mesh())
    {
        assert!(a.distance(*b) < 1e-12);
    }
    assert_eq!(d.session.rest_cage(), reference.session.rest_cage());
}

mod skeleton_building {
    use super::*;
    use crate::binding::BindWeights;
    use crate::document::SkeletonEdit;
    use cagerig::auto_weights::AutoWeightsOptions;

    fn automatic() -> BindWeights {
        BindWeights::Automatic(AutoWeightsOptions {
            resolution: 48,
            ..Default::default()
        })
    }

    fn add(d: &mut Document, position: DVec3, parent: Option<usize>) {
        d.execute(&Command::EditSkeleton(SkeletonEdit::Add {
            position,
            parent,
            mirror: None,
        }))
        .unwrap();
    }

    /// The bar rig's rest mesh box.
    fn bar_box(d: &Document) -> (DVec3, DVec3) {
        cagerig::mesh::bounding_box(d.session.rest_mesh())
    }

    /// A stand-in for the web page's worker: answers when told, through the JSON encoding.
    #[derive(Debug, Default)]
    struct LaterWorker {
        waiting:
            std::cell::RefCell<Vec<(crate::offload::WeightsInput, crate::offload::WeightsReply)>>,
    }

    impl crate::offload::WeightsOffload for LaterWorker {
        fn start(&self, input: crate::offload::WeightsInput, reply: crate::offload::WeightsReply) {
            self.waiting.borrow_mut().push((input, reply));
        }
    }

    impl LaterWorker {
        fn answer(&self) {
            use crate::offload::{WeightsInput, WeightsOutput};
            for (input, reply) in self.waiting.borrow_mut().drain(..) {
                let json = input.to_json().unwrap();
                let output = WeightsInput::from_json(&json)
                    .unwrap()
                    .compute(&|p| reply.report(p))
                    .unwrap()
                    .to_json()
                    .unwrap();
                reply.finish(Ok(WeightsOutput::from_json(&output).unwrap()));
            }
        }
    }

    #[test]
    fn offloaded_weights_bind_as_the_bind_computes_them() {
        let mut reference = doc();
        reference.bind_blocking(automatic()).unwrap();
        let mut d = doc();
        let worker = LaterWorker::default();
        d.start_bind(automatic(), Some(&worker)).unwrap();
        assert!(d.poll_bind().is_none(), "waiting for the worker");
        assert!(d.bind_job().unwrap().progress().1.contains("in the worker"));
        worker.answer();
        let line = loop {
            if let Some(result) = d.poll_bind() {
                break result.unwrap();
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        assert!(line.starts_with("bound "), "{line}");
        let (a, b) = (d.session.skin_weights(), reference.session.skin_weights());
        for v in 0..a.num_vertices() {
            assert_eq!(a.row(v).0, b.row(v).0);
            for (x, y) in a.row(v).1.iter().zip(b.row(v).1) {
                assert!((x - y).abs() <= 1e-15);
            }
        }
        // A failed computation fails the bind with its message; the rig stays.
        let mut d = doc();
        let worker = LaterWorker::default();
        d.start_bind(automatic(), Some(&worker)).unwrap();
        for (_, reply) in worker.waiting.borrow_mut().drain(..) {
            reply.finish(Err("the worker failed".into()));
        }
        let failed = d.poll_bind().unwrap();
        assert!(
            failed
                .unwrap_err()
                .to_string()
                .contains("the worker failed")
        );
        assert!(d.bind_job().is_none());
    }

    #[test]
    fn a_new_skeleton_binds_in_one_undo_step_and_undo_brings_the_old_rig_back() {
        let mut d = doc();
        let old_joints = d.session.skeleton().len();
        d.execute(&Command::RotateJoint {
            joint: 1,
            axis: DVec3::Z,
            angle: 0.3,
        })
        .unwrap();
        let posed = d.snapshot();
        // A new joint below joint 1, in the middle of the bar.
        let (lo, hi) = bar_box(&d);
        add(&mut d, 0.5 * (lo + hi), Some(1));
        assert_eq!(d.draft.as_ref().unwrap().len(), old_joints + 1);
        // Posing waits for the Bind.
        let refused = d.execute(&Command::RotateJoint {
            joint: 1,
            axis: DVec3::Z,
            angle: 0.1,
        });
        assert!(
            matches!(refused, Err(DocError::SkeletonPending)),
            "{refused:?}"
        );
        let steps = d.history().undo_len();
        d.bind_blocking(automatic()).unwrap();
        assert_eq!(d.history().undo_len(), steps + 1, "a bind is one undo step");
        assert!(d.draft.is_none());
        assert_eq!(d.session.skeleton().len(), old_joints + 1);
        // The pose is carried by joint; the new joint is at rest.
        let rotations = d.session.posed_local_rotations();
        assert_eq!(rotations[1], posed.rig.rotations[1]);
        assert_eq!(rotations[old_joints], DQuat::IDENTITY);
        // Every vertex is weighted, rows sum to 1.
        let w = d.session.skin_weights();
        for v in 0..w.num_vertices() {
            let (_, row) = w.row(v);
            assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        }
        d.undo().unwrap();
        assert_eq!(d.session.skeleton().len(), old_joints);
        assert!(
            d.draft.is_some(),
            "undo goes back to the skeleton not bound yet"
        );
        d.undo().unwrap();
        assert_eq!(d.snapshot(), posed);
        d.redo().unwrap();
        d.redo().unwrap();
        assert_eq!(d.session.skeleton().len(), old_joints + 1);
        assert!(d.draft.is_none());
    }

    #[test]
    fn a_mesh_with_no_skeleton_builds_one_binds_and_poses() {
        let dir = std::env::temp_dir().join(format!("cagerig-unrigged-doc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bar = crate::rig_open::open_rig(&RigSource::Builtin {
            name: "bar".into(),
            resolution: Some(6),
        })
        .unwrap()
        .session;
        let mesh = dir.join("bar.obj");
        cagerig::io::write_obj(&mesh, bar.rest_mesh(), bar.mesh_triangles()).unwrap();
        let source = RigSource::File {
            path: mesh.clone(),
            cage: None,
            skin: None,
            auto_cage: Some(40),
        };
        let opened = crate::rig_open::open_rig(&source).unwrap();
        assert!(!opened.rigged);
        let mut d = Document::new(source, opened.session).with_rigged(false);
        assert!(d.shown_skeleton(true).positions.is_empty());
        assert!(matches!(
            d.execute(&Command::RotateJoint {
                joint: 0,
                axis: DVec3::Z,
                angle: 0.3
            }),
            Err(DocError::NotRigged)
        ));
        assert!(d.bind_blocking(automatic()).is_err(), "nothing to bind yet");
        // A chain of three joints along the bar's long axis.
        let (lo, hi) = bar_box(&d);
        let axis = (hi - lo).max_position();
        for k in 0..3usize {
            let mut p = 0.5 * (lo + hi);
            p[axis] = lo[axis] + (0.15 + 0.35 * k as f64) * (hi[axis] - lo[axis]);
            add(&mut d, p, k.checked_sub(1));
        }
        d.bind_blocking(automatic()).unwrap();
        assert!(d.rigged());
        assert_eq!(d.session.skeleton().len(), 3);
        let rest = d.session.posed_mesh().to_vec();
        d.execute(&Command::RotateJoint {
            joint: 1,
            axis: DVec3::Z,
            angle: 0.5,
        })
        .unwrap();
        let moved = cagerig::mesh::max_distance(&rest, d.session.posed_mesh());
        assert!(moved > 1e-3 * (hi - lo).length(), "the mesh did not deform");
        // The session file keeps the binding and reopens it exactly.
        let file = d.session_file(0.0);
        assert_eq!(file.version, 2, "a studio binding needs version 2");
        let binding = file.binding.clone().unwrap();
        let reopened = crate::rig_open::open_rig(&file.source).unwrap();
        let rebuilt = binding.bind(&reopened.session).unwrap();
        let (a, b) = (rebuilt.skin_weights(), d.session.skin_weights());
        for v in 0..a.num_vertices() {
            for j in 0..3 {
                assert!((a.get(v, j) - b.get(v, j)).abs() < 1e-12, "Ω[{v}, {j}]");
            }
        }
        assert_eq!(rebuilt.skeleton().len(), 3);
        let mut again = Document::new(file.source.clone(), reopened.session).with_rigged(false);
        again.adopt_binding(rebuilt);
        let mut state = file.state.clone();
        state.binding = again.binding;
        again.restore(&state).unwrap();
        let off = cagerig::mesh::max_distance(again.session.posed_mesh(), d.session.posed_mesh());
        assert!(off < 1e-9 * (hi - lo).length(), "{off}");
        std::fs::remove_dir_all(dir).ok();
    }
}
