//! Shared test helpers: data paths, a box cage, an independent glTF skinning evaluator.
#![allow(dead_code)]

use std::path::PathBuf;

use cagerig::TriMesh;
use glam::{DAffine3, DMat4, DQuat, DVec3};

pub fn data(rel: &str) -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/"
    ))
    .join(rel)
}

/// An outward-oriented box around `points`, padded by `pad` × its diagonal.
pub fn box_cage(points: &[DVec3], pad: f64) -> TriMesh {
    let (mut lo, mut hi) = cagerig::mesh::bounding_box(points);
    let d = (hi - lo).length() * pad;
    lo -= DVec3::splat(d);
    hi += DVec3::splat(d);
    TriMesh::cuboid(lo, hi).unwrap()
}

/// Straightforward glTF skinning written from the specification, on the `gltf` crate's own
/// loader and readers (an evaluation independent of cagerig-formats): node TRS at time t
/// (LINEAR channels only), morph targets at the (animated) weights, world transforms by
/// recursion, `v' = Σ w_j G_j(t) IBM_j v / Σ w`, skinned primitives of skin 0 in node order.
pub fn reference_skinning(path: &std::path::Path, animation: Option<usize>, t: f64) -> Vec<DVec3> {
    let (doc, buffers, _) = gltf::import(path).unwrap();
    let get = |b: gltf::Buffer| Some(&*buffers[b.index()]);
    let mut trs: Vec<(DVec3, DQuat, DVec3, Option<DAffine3>)> = doc
        .nodes()
        .map(|n| match n.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                let m = DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)));
                (
                    DVec3::ZERO,
                    DQuat::IDENTITY,
                    DVec3::ONE,
                    Some(DAffine3::from_mat4(m)),
                )
            }
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => (
                DVec3::from(translation.map(f64::from)),
                DQuat::from_array(rotation.map(f64::from)),
                DVec3::from(scale.map(f64::from)),
                None,
            ),
        })
        .collect();
    let mut morph: Vec<Option<Vec<f64>>> = doc
        .nodes()
        .map(|n| {
            n.mesh()
                .and_then(|m| m.weights())
                .map(|w| w.iter().map(|&x| x as f64).collect())
        })
        .collect();
    if let Some(a) = animation.and_then(|a| doc.animations().nth(a)) {
        for ch in a.channels() {
            let r = ch.reader(get);
            let times: Vec<f64> = r.read_inputs().unwrap().map(f64::from).collect();
            let k = times.partition_point(|&x| x <= t);
            let (lo, hi, s) = if k == 0 {
                (0, 0, 0.0)
            } else if k >= times.len() {
                (times.len() - 1, times.len() - 1, 0.0)
            } else {
                (k - 1, k, (t - times[k - 1]) / (times[k] - times[k - 1]))
            };
            assert_eq!(
                ch.sampler().interpolation(),
                gltf::animation::Interpolation::Linear
            );
            let node = &mut trs[ch.target().node().index()];
            match r.read_outputs().unwrap() {
                gltf::animation::util::ReadOutputs::Translations(it) => {
                    let v: Vec<DVec3> = it.map(|x| DVec3::from(x.map(f64::from))).collect();
                    node.0 = v[lo].lerp(v[hi], s);
                }
                gltf::animation::util::ReadOutputs::Scales(it) => {
                    let v: Vec<DVec3> = it.map(|x| DVec3::from(x.map(f64::from))).collect();
                    node.2 = v[lo].lerp(v[hi], s);
                }
                gltf::animation::util::ReadOutputs::Rotations(it) => {
                    let v: Vec<DQuat> = it
                        .into_f32()
                        .map(|x| DQuat::from_array(x.map(f64::from)).normalize())
                        .collect();
                    node.1 = v[lo].slerp(v[hi], s);
                }
                gltf::animation::util::ReadOutputs::MorphTargetWeights(it) => {
                    let v: Vec<f64> = it.into_f32().map(f64::from).collect();
                    let n = v.len() / times.len();
                    morph[ch.target().node().index()] = Some(
                        (0..n)
                            .map(|k| v[lo * n + k] + (v[hi * n + k] - v[lo * n + k]) * s)
                            .collect(),
                    );
                }
            }
        }
    }
    let mut parent = vec![None; trs.len()];
    for n in doc.nodes() {
        for c in n.children() {
            parent[c.index()] = Some(n.index());
        }
    }
    fn global(
        i: usize,
        parent: &[Option<usize>],
        trs: &[(DVec3, DQuat, DVec3, Option<DAffine3>)],
    ) -> DAffine3 {
        let (t, r, s, m) = trs[i];
        let local = m.unwrap_or_else(|| DAffine3::from_scale_rotation_translation(s, r, t));
        match parent[i] {
            Some(p) => global(p, parent, trs) * local,
            None => local,
        }
    }
    let skin = doc.skins().next().unwrap();
    let sr = skin.reader(get);
    let ibm: Vec<DAffine3> = sr
        .read_inverse_bind_matrices()
        .unwrap()
        .map(|m| DAffine3::from_mat4(DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)))))
        .collect();
    let joint_mats: Vec<DAffine3> = skin
        .joints()
        .zip(&ibm)
        .map(|(n, ibm)| global(n.index(), &parent, &trs) * *ibm)
        .collect();
    let mut out = Vec::new();
    for node in doc.nodes() {
        if node.skin().map(|s| s.index()) != Some(skin.index()) {
            continue;
        }
        for prim in node.mesh().unwrap().primitives() {
            let r = prim.reader(get);
            let mut pos: Vec<DVec3> = r
                .read_positions()
                .unwrap()
                .map(|p| DVec3::from(p.map(f64::from)))
                .collect();
            if let Some(w) = &morph[node.index()] {
                for (k, target) in r.read_morph_targets().enumerate() {
                    if let Some(d) = target.0 {
                        for (p, d) in pos.iter_mut().zip(d) {
                            *p += DVec3::from(d.map(f64::from)) * w[k];
                        }
                    }
                }
            }
            let joints: Vec<[u16; 4]> = r.read_joints(0).unwrap().into_u16().collect();
            let weights: Vec<[f32; 4]> = r.read_weights(0).unwrap().into_f32().collect();
            for ((p, j), w) in pos.iter().zip(&joints).zip(&weights) {
                let sum: f64 = w.iter().map(|&x| x as f64).sum();
                let mut v = DVec3::ZERO;
                for k in 0..4 {
                    if w[k] != 0.0 {
                        v += joint_mats[j[k] as usize].transform_point3(*p) * (w[k] as f64 / sum);
                    }
                }
                out.push(v);
            }
        }
    }
    out
}
