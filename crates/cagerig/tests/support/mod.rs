//! Set-up shared by the library's integration tests: the Arm's files (read by small independent
//! readers, so that a bug in `cagerig::io` cannot hide itself), the paper tool's reference
//! transforms, and the proptest strategies of the skinning properties. Each test crate uses the
//! part it needs (`mod support;`).

use cagerig::SkinWeights;
use cagerig::mesh::TriMesh;
use glam::{DAffine3, DMat3, DQuat, DVec3};
use proptest::prelude::*;

/// The Arm rig's folder (`data/arm` in the repository).
pub const ARM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/arm");

/// The text of `name` in the Arm's folder.
pub fn read(name: &str) -> String {
    std::fs::read_to_string(format!("{ARM}/{name}")).unwrap_or_else(|e| panic!("{ARM}/{name}: {e}"))
}

/// The numbers of a whitespace-separated line.
pub fn numbers(line: &str) -> Vec<f64> {
    line.split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect()
}

/// Minimal OBJ reader of `text`: `v x y z` and `f a b c` lines (1-based, `a/b/c` forms
/// allowed, triangles only).
pub fn parse_obj(text: &str) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let v: Vec<f64> = it.take(3).map(|x| x.parse().unwrap()).collect();
                positions.push(DVec3::new(v[0], v[1], v[2]));
            }
            Some("f") => {
                let f: Vec<u32> = it
                    .map(|x| x.split('/').next().unwrap().parse::<u32>().unwrap() - 1)
                    .collect();
                assert_eq!(f.len(), 3, "non-triangle face");
                triangles.push([f[0], f[1], f[2]]);
            }
            _ => {}
        }
    }
    (positions, triangles)
}

/// [`parse_obj`] of `name` in the Arm's folder.
pub fn obj(name: &str) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    parse_obj(&read(name))
}

/// [`obj`] as a validated mesh.
pub fn mesh(name: &str) -> TriMesh {
    let (positions, triangles) = obj(name);
    TriMesh::new(positions, triangles).unwrap()
}

/// Skinning transforms T_j of the reference tool's step ii (the third 3×4 row-major matrix per
/// joint of `reference/s2_transforms.txt`), `#J`.
pub fn step2_transforms() -> Vec<DAffine3> {
    read("reference/s2_transforms.txt")
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let n = &numbers(l)[25..37];
            DAffine3 {
                matrix3: DMat3::from_cols(
                    DVec3::new(n[0], n[4], n[8]),
                    DVec3::new(n[1], n[5], n[9]),
                    DVec3::new(n[2], n[6], n[10]),
                ),
                translation: DVec3::new(n[3], n[7], n[11]),
            }
        })
        .collect()
}

/// A point in the cube [−10, 10]³.
pub fn point() -> impl Strategy<Value = DVec3> {
    (-10.0..10.0f64, -10.0..10.0f64, -10.0..10.0f64).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

/// A rigid transform: a unit quaternion (from a non-degenerate random one) and a [`point`].
pub fn rigid() -> impl Strategy<Value = DAffine3> {
    (
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
        point(),
    )
        .prop_filter_map("degenerate quaternion", |((x, y, z, w), t)| {
            let q = DQuat::from_xyzw(x, y, z, w);
            (q.length() > 0.1).then(|| DAffine3::from_rotation_translation(q.normalize(), t))
        })
}

/// Rows of 1..=`num_joints` influences (joint, weight) for `n` vertices.
pub fn weight_rows(n: usize, num_joints: usize) -> impl Strategy<Value = Vec<Vec<(usize, f64)>>> {
    proptest::collection::vec(
        proptest::collection::btree_map(0..num_joints, 0.01..1.0f64, 1..=num_joints)
            .prop_map(|m| m.into_iter().collect::<Vec<_>>()),
        n,
    )
}

/// Ω (`#rows × num_joints`) of [`weight_rows`].
pub fn skin_weights(rows: &[Vec<(usize, f64)>], num_joints: usize) -> SkinWeights {
    let triplets = rows
        .iter()
        .enumerate()
        .flat_map(|(v, r)| r.iter().map(move |&(j, w)| (v, j, w)));
    SkinWeights::from_triplets(rows.len(), num_joints, triplets.collect::<Vec<_>>())
        .unwrap()
        .0
}

/// Deterministic DQ blend weights for `num_vertices` vertices (blended skinning): spread over
/// [0, 1] by the golden ratio, with every tenth vertex at exactly 0 and every tenth (offset 5)
/// at exactly 1, so both pure rules and the blend run.
pub fn spread_blend_weights(num_vertices: usize) -> cagerig::skinning::DqBlendWeights {
    let values = (0..num_vertices)
        .map(|v| match v % 10 {
            0 => 0.0,
            5 => 1.0,
            _ => (v as f64 * 0.618_033_988_749_895).fract(),
        })
        .collect();
    cagerig::skinning::DqBlendWeights::new(values).unwrap()
}
