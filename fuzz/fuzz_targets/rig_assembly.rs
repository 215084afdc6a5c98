//! Rig assembly on arbitrary mesh and cage OBJ text (split at the first NUL byte): one joint,
//! every vertex fully bound to it. Exercises the cage validation (closed, manifold, oriented,
//! non-degenerate, enclosing), mean value coordinates, MaxVol, SkelUp and CageRev set-up: no
//! panic, and an assembled session is finite and survives a cage drag.
#![no_main]

use std::path::Path;

use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig::{Joint, Skeleton, SkinWeights};
use glam::{DAffine3, DVec3};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(split) = data.iter().position(|&b| b == 0) else {
        return;
    };
    let src = Path::new("fuzz");
    let (Ok(mesh), Ok(cage)) = (
        cagerig::io::parse_obj(&data[..split], src),
        cagerig::io::parse_obj(&data[split + 1..], src),
    ) else {
        return;
    };
    if mesh.num_vertices() > 64 || cage.num_vertices() > 32 || cage.num_triangles() > 64 {
        return;
    }
    let skeleton = Skeleton::new(vec![Joint {
        name: "root".into(),
        parent: None,
        rest_world_from_joint: DAffine3::IDENTITY,
    }])
    .unwrap();
    let Ok((weights, _)) =
        SkinWeights::from_triplets(mesh.num_vertices(), 1, (0..mesh.num_vertices()).map(|v| (v, 0, 1.0)))
    else {
        return;
    };
    let parts = RigParts::new(mesh, skeleton, weights, cage);
    let Ok((mut s, _)) = RigSession::new(parts, SessionOptions::default()) else {
        return;
    };
    let _ = s.move_rest_cage(&[0], &[DVec3::new(0.01, 0.0, 0.0)]);
    let _ = s.move_posed_cage(&[0], &[DVec3::new(0.0, 0.01, 0.0)]);
    assert!(s.rest_mesh().iter().chain(s.posed_mesh()).all(|p| p.is_finite()));
    assert!(s.rest_cage().iter().chain(s.posed_cage()).all(|p| p.is_finite()));
});
