//! The FBX importer (ufbx, then cagerig's conversion to a character) on arbitrary bytes, seeded
//! with the repository's FBX sample: no panic; whatever it accepts is finite, within the input
//! bound, with consistent sizes.
#![no_main]

use std::path::Path;

use cagerig::error::is_input_value;
use cagerig_formats::ImportOptions;
use cagerig_formats::fbx::import_fbx_bytes;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(c) = import_fbx_bytes(data, Path::new("fuzz/input.fbx"), &ImportOptions::default())
    else {
        return;
    };
    let nv = c.mesh.num_vertices();
    assert!(
        c.mesh
            .positions
            .iter()
            .all(|p| p.to_array().iter().all(|&x| is_input_value(x)))
    );
    assert!(c.mesh.triangles.iter().flatten().all(|&v| (v as usize) < nv));
    assert_eq!(c.skin_weights.num_vertices(), nv);
    assert_eq!(c.skin_weights.num_joints(), c.skeleton.len());
    for v in 0..nv {
        assert!(c.skin_weights.row(v).1.iter().all(|w| w.is_finite()));
    }
    assert!(c.skeleton.joints().iter().all(|j| j.rest_world_from_joint.is_finite()));
    for a in &c.animations {
        assert!(a.track.keys().iter().flatten().all(|k| k.is_finite()));
    }
});
