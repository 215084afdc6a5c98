//! glTF export → import round trip: a built-in rig edited by fuzzer-chosen events (joint
//! rotations, rest- and current-cage moves), exported as `.glb` and read back. Whatever the
//! session accepts must export, and the import must give the exported rest mesh (to 1e-5 of the
//! diagonal: glTF stores float32), the same joint count and the same triangles.
#![no_main]

use std::path::Path;

use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig_formats::ImportOptions;
use cagerig_formats::gltf::export::{session_to_gltf, write_glb};
use cagerig_formats::gltf::import_gltf_bytes;
use glam::DVec3;
use libfuzzer_sys::fuzz_target;

fn value(bytes: &[u8], k: usize) -> f64 {
    let b = bytes.get(k).copied().unwrap_or(0);
    (f64::from(b) - 127.5) / 127.5
}

fuzz_target!(|data: &[u8]| {
    let Ok(rig) = cagerig::demo::builtin("bar", None) else {
        return;
    };
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
    let Ok((mut s, _)) = RigSession::new(parts, SessionOptions::default()) else {
        return;
    };
    let (nj, nc) = (s.skeleton().len(), s.rest_cage().len());
    for event in data.chunks(5).take(12) {
        let v = DVec3::new(value(event, 2), value(event, 3), value(event, 4)) * 0.3;
        let pick = event.get(1).copied().unwrap_or(0) as usize;
        let _ = match event[0] % 3 {
            0 => s.rotate_joint(pick % nj, v.try_normalize().unwrap_or(DVec3::Z), 2.0 * v.x),
            1 => s.move_rest_cage(&[pick % nc], &[v]),
            _ => s.move_posed_cage(&[pick % nc], &[v]),
        };
    }
    let (document, bin) = session_to_gltf(&s, "fuzz").expect("a valid session exports");
    let mut glb = Vec::new();
    write_glb(&mut glb, &document, &bin).expect("writing to memory");
    let back = import_gltf_bytes(&glb, Path::new("fuzz/roundtrip.glb"), &ImportOptions::default())
        .expect("cagerig's own export imports");
    let rest = s.rest_mesh();
    assert_eq!(back.mesh.num_vertices(), rest.len());
    assert_eq!(back.skeleton.len(), nj);
    let (lo, hi) = cagerig::mesh::bounding_box(rest);
    let tolerance = 1e-5 * (hi - lo).length().max(1e-9);
    for (a, b) in back.mesh.positions.iter().zip(rest) {
        assert!(a.distance(*b) <= tolerance, "{a} vs {b}");
    }
});
