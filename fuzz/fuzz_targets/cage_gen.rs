//! Cage generation on random meshes: a fuzzer-chosen cloud of boxes (positions, sizes, a
//! rotation, some triangles dropped to make holes) and target size. Whatever the generator
//! returns passes the validator: closed, manifold, outward, every mesh vertex inside, with the
//! margin; and it never panics on degenerate input.
#![no_main]

use cagerig::cage_gen::{CageOptions, CageTarget, generate_cage};
use cagerig::mesh::TriMesh;
use glam::{DQuat, DVec3};
use libfuzzer_sys::fuzz_target;

fn value(bytes: &[u8], k: usize) -> f64 {
    f64::from(bytes.get(k).copied().unwrap_or(0)) / 255.0
}

const CORNERS: [[f64; 3]; 8] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [0.0, 1.0, 1.0],
];
const FACES: [[u32; 3]; 12] = [
    [0, 2, 1],
    [0, 3, 2],
    [4, 5, 6],
    [4, 6, 7],
    [0, 1, 5],
    [0, 5, 4],
    [1, 2, 6],
    [1, 6, 5],
    [2, 3, 7],
    [2, 7, 6],
    [3, 0, 4],
    [3, 4, 7],
];

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 {
        return;
    }
    let target = 8 + usize::from(data[0]) % 120;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (b, block) in data[1..].chunks(9).take(6).enumerate() {
        let origin = DVec3::new(value(block, 0), value(block, 1), value(block, 2)) * 3.0;
        let size = DVec3::new(value(block, 3), value(block, 4), value(block, 5)) + DVec3::splat(0.05);
        let rotation = DQuat::from_rotation_y(6.3 * value(block, 6));
        let base = positions.len() as u32;
        positions.extend(
            CORNERS
                .iter()
                .map(|c| origin + rotation * (DVec3::from_array(*c) * size)),
        );
        let holes = block.get(7).copied().unwrap_or(0);
        for (f, face) in FACES.iter().enumerate() {
            if b > 0 && f < 8 && holes & (1 << f) != 0 {
                continue;
            }
            triangles.push(face.map(|v| base + v));
        }
    }
    let Ok(mesh) = TriMesh::new(positions, triangles) else {
        return;
    };
    let options = CageOptions {
        target: CageTarget::Vertices(target),
        ..CageOptions::default()
    };
    let Ok(generated) = generate_cage(&mesh, &options) else {
        return;
    };
    let (cage, _) = cagerig::cage::validate_cage(generated.cage.clone())
        .expect("a generated cage is closed, manifold and outward");
    assert!(cage.positions.iter().all(|p| p.is_finite()));
    assert_eq!(generated.report.cage_vertices, cage.num_vertices());
    assert!(
        cagerig::cage_enclosure::validate_cage_for_mesh(cage, &mesh.positions, false).is_ok(),
        "every mesh vertex is inside the generated cage"
    );
});
