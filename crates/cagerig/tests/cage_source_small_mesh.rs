//! `--auto-cage` on a small mesh: the generated cage adapts to the mesh, so that a rig can be
//! built (a 24-vertex mesh with the default 100-vertex target would fail with "MaxVol needs at
//! least #C mesh vertices: expected 100 but got 24").

#![expect(clippy::unwrap_used)]

use std::path::Path;

use cagerig::cage_gen::CageOptions;
use cagerig::cage_source::{CageOrigin, CageRequest, choose_cage};
use cagerig::mesh::TriMesh;
use cagerig::session::{RigParts, RigSession, SessionOptions};
use cagerig::skeleton::{Joint, Skeleton};
use cagerig::skin_weights::SkinWeights;
use glam::{DAffine3, DVec3};

/// A closed octagonal prism of three rings (24 vertices) along +Y, caps triangulated as fans.
fn prism() -> TriMesh {
    let (rings, sides) = (3u32, 8u32);
    let mut positions = Vec::new();
    for r in 0..rings {
        for k in 0..sides {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(sides);
            positions.push(DVec3::new(0.3 * a.cos(), f64::from(r), 0.3 * a.sin()));
        }
    }
    let mut triangles = Vec::new();
    for r in 0..rings - 1 {
        for k in 0..sides {
            let (a, b) = (r * sides + k, r * sides + (k + 1) % sides);
            let (c, d) = (a + sides, b + sides);
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    let top = (rings - 1) * sides;
    for k in 1..sides - 1 {
        triangles.push([0, k, k + 1]);
        triangles.push([top, top + k + 1, top + k]);
    }
    TriMesh::new(positions, triangles).unwrap()
}

#[test]
fn a_generated_cage_on_a_24_vertex_mesh_builds_a_rig() {
    let mesh = prism();
    assert_eq!(mesh.num_vertices(), 24);
    let request = CageRequest {
        given: None,
        generate: Some(CageOptions::default()),
        generated: None,
    };
    let chosen = choose_cage(Path::new("prism.obj"), &mesh, None, None, &request).unwrap();
    assert!(matches!(chosen.origin, CageOrigin::Generated(_)));
    let nc = chosen.cage.num_vertices();
    assert!(
        (8..=12).contains(&nc),
        "{nc} cage vertices for 24 mesh vertices"
    );
    let joint = |name: &str, parent, y: f64| Joint {
        name: name.into(),
        parent,
        rest_world_from_joint: DAffine3::from_translation(DVec3::new(0.0, y, 0.0)),
    };
    let skeleton =
        Skeleton::new(vec![joint("base", None, 0.0), joint("tip", Some(0), 1.0)]).unwrap();
    let rows: Vec<Vec<f64>> = mesh
        .positions
        .iter()
        .map(|p| {
            let t = (p.y / 2.0).clamp(0.0, 1.0);
            vec![1.0 - t, t]
        })
        .collect();
    let weights = SkinWeights::from_dense(&rows).unwrap().0;
    let parts = RigParts::new(mesh, skeleton, weights, chosen.cage);
    let (mut session, _) = RigSession::new(parts, SessionOptions::default()).unwrap();
    session.rotate_joint(1, DVec3::Z, 0.5).unwrap();
    session
        .move_posed_cage(&[0], &[DVec3::new(0.01, 0.0, 0.0)])
        .unwrap();
}
