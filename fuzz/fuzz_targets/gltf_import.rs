//! The glTF importer (`.glb` / `.gltf` bytes from anywhere) on arbitrary bytes, seeded with the
//! shared samples and cagerig exports (a hybrid one with morph targets and a cage node): no
//! panic, no allocation beyond what the bytes back; whatever it accepts is finite and within the
//! input bound, with consistent sizes (morph weights: one row of #targets per key).
#![no_main]

use std::path::Path;

use cagerig::error::is_input_value;
use cagerig_formats::ImportOptions;
use cagerig_formats::gltf::import_gltf_bytes;
use glam::DVec3;
use libfuzzer_sys::fuzz_target;

fn finite(p: DVec3) -> bool {
    p.to_array().iter().all(|&x| is_input_value(x))
}

fuzz_target!(|data: &[u8]| {
    let Ok(c) = import_gltf_bytes(data, Path::new("fuzz/input.glb"), &ImportOptions::default())
    else {
        return;
    };
    let nv = c.mesh.num_vertices();
    assert!(c.mesh.positions.iter().all(|p| finite(*p)));
    assert_eq!(c.skin_weights.num_vertices(), nv);
    for v in 0..nv {
        assert!(c.skin_weights.row(v).1.iter().all(|w| w.is_finite()));
    }
    assert!(c.skeleton.joints().iter().all(|j| j.rest_world_from_joint.is_finite()));
    if let Some(cage) = &c.cage {
        assert!(cage.positions.iter().all(|p| finite(*p)));
    }
    let targets = c.morph_targets.displacements.len();
    assert_eq!(c.morph_targets.default_weights.len(), targets);
    for d in &c.morph_targets.displacements {
        assert_eq!(d.len(), nv);
        assert!(d.iter().all(|p| p.is_finite()));
    }
    for a in &c.animations {
        let keys = a.track.num_keyframes();
        assert!(a.track.keys().iter().flatten().all(|k| k.is_finite()));
        if let Some(w) = &a.morph_weights {
            assert_eq!(w.len(), keys * targets);
            assert!(w.iter().all(|x| x.is_finite()));
        }
    }
});
