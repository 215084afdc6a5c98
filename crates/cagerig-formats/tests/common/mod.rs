//! Shared test helpers: data paths, a box cage, an independent glTF skinning evaluator.

use std::path::PathBuf;

use cagerig::TriMesh;
use glam::{DAffine3, DMat4, DQuat, DVec3};

pub fn data(rel: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/")).join(rel)
}

/// The first file named `name` under the folders of `CAGERIG_GLTF_SWEEP` (a path list, searched
/// recursively in sorted order), for tests of characters the repository cannot ship; `None`
/// when the variable is unset or no folder holds one.
pub fn sweep_file(name: &str) -> Option<PathBuf> {
    fn find(dir: &std::path::Path, name: &str) -> Option<PathBuf> {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
            .ok()?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        paths.sort();
        for p in &paths {
            if p.is_file() && p.file_name().is_some_and(|f| f == name) {
                return Some(p.clone());
            }
        }
        paths
            .iter()
            .filter(|p| p.is_dir())
            .find_map(|p| find(p, name))
    }
    let dirs = std::env::var_os("CAGERIG_GLTF_SWEEP")?;
    std::env::split_paths(&dirs).find_map(|d| find(&d, name))
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
/// recursion, `v' = Σ w_j G_j(t) IBM_j v / Σ w` over every JOINTS_n/WEIGHTS_n set, skinned
/// primitives of skin 0 in node order.
pub fn reference_skinning(path: &std::path::Path, animation: Option<usize>, t: f64) -> Vec<DVec3> {
    ReferenceGltf::load(path).skin(animation, t)
}

/// A glTF file loaded once by the `gltf` crate, for [`reference_skinning`] at many times.
pub struct ReferenceGltf {
    doc: gltf::Document,
    buffers: Vec<gltf::buffer::Data>,
    /// The skin evaluated (0 unless [`ReferenceGltf::with_skin`]).
    skin: usize,
}

impl ReferenceGltf {
    pub fn load(path: &std::path::Path) -> Self {
        // Unvalidated: the reference reads files whose required extensions do not change the
        // geometry (lights, materials), which the `gltf` crate's validation refuses.
        let gltf::Gltf { document, blob } =
            gltf::Gltf::from_slice_without_validation(&std::fs::read(path).unwrap()).unwrap();
        let buffers = gltf::import_buffers(&document, path.parent(), blob).unwrap();
        let doc = document;
        Self {
            doc,
            buffers,
            skin: 0,
        }
    }

    /// Evaluates skin `skin` (its skinned nodes) instead of skin 0.
    pub fn with_skin(mut self, skin: usize) -> Self {
        self.skin = skin;
        self
    }

    /// The skinned vertices at time `t` of `animation` (see [`reference_skinning`]).
    pub fn skin(&self, animation: Option<usize>, t: f64) -> Vec<DVec3> {
        skin_at(&self.doc, &self.buffers, self.skin, animation, t)
    }
}

fn skin_at(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    skin_index: usize,
    animation: Option<usize>,
    t: f64,
) -> Vec<DVec3> {
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
            let interpolation = ch.sampler().interpolation();
            let node = ch.target().node().index();
            use gltf::animation::util::ReadOutputs;
            let (values, rotation): (Vec<Vec<f64>>, bool) = match r.read_outputs().unwrap() {
                ReadOutputs::Translations(it) | ReadOutputs::Scales(it) => {
                    (it.map(|x| x.map(f64::from).to_vec()).collect(), false)
                }
                ReadOutputs::Rotations(it) => (
                    it.into_f32().map(|x| x.map(f64::from).to_vec()).collect(),
                    true,
                ),
                ReadOutputs::MorphTargetWeights(it) => {
                    let w: Vec<f64> = it.into_f32().map(f64::from).collect();
                    let per_key = if interpolation == gltf::animation::Interpolation::CubicSpline {
                        3
                    } else {
                        1
                    };
                    let n = w.len() / times.len() / per_key;
                    (w.chunks(n).map(<[f64]>::to_vec).collect(), false)
                }
            };
            let v = sample_channel(&times, &values, interpolation, rotation, t);
            match ch.target().property() {
                gltf::animation::Property::Translation => {
                    trs[node].0 = DVec3::new(v[0], v[1], v[2])
                }
                gltf::animation::Property::Rotation => {
                    trs[node].1 = DQuat::from_xyzw(v[0], v[1], v[2], v[3]).normalize()
                }
                gltf::animation::Property::Scale => trs[node].2 = DVec3::new(v[0], v[1], v[2]),
                gltf::animation::Property::MorphTargetWeights => morph[node] = Some(v),
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
    let skin = doc.skins().nth(skin_index).unwrap();
    let sr = skin.reader(get);
    // Absent inverse bind matrices are identities (specification).
    let ibm: Vec<DAffine3> = match sr.read_inverse_bind_matrices() {
        Some(it) => it
            .map(|m| DAffine3::from_mat4(DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)))))
            .collect(),
        None => vec![DAffine3::IDENTITY; skin.joints().count()],
    };
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
            // Every JOINTS_n / WEIGHTS_n set: influences (joint, weight) per vertex.
            let mut influences: Vec<Vec<(usize, f64)>> = vec![Vec::new(); pos.len()];
            let mut set = 0;
            while let (Some(joints), Some(weights)) = (r.read_joints(set), r.read_weights(set)) {
                for ((row, j), w) in influences
                    .iter_mut()
                    .zip(joints.into_u16())
                    .zip(weights.into_f32())
                {
                    row.extend((0..4).map(|k| (j[k] as usize, w[k] as f64)));
                }
                set += 1;
            }
            for (p, row) in pos.iter().zip(&influences) {
                let sum: f64 = row.iter().map(|&(_, w)| w).sum();
                let mut v = DVec3::ZERO;
                for &(j, w) in row {
                    if w != 0.0 {
                        v += joint_mats[j].transform_point3(*p) * (w / sum);
                    }
                }
                out.push(v);
            }
        }
    }
    out
}

/// A channel's value at `t` by the specification: LINEAR (slerp for rotations), STEP (the value
/// of the last key at or before t), CUBICSPLINE (Hermite with the file's tangents; elements
/// per key: in-tangent, value, out-tangent). `values` holds one element per output element.
pub fn sample_channel(
    times: &[f64],
    values: &[Vec<f64>],
    interpolation: gltf::animation::Interpolation,
    rotation: bool,
    t: f64,
) -> Vec<f64> {
    use gltf::animation::Interpolation;
    let cubic = interpolation == Interpolation::CubicSpline;
    let value = |k: usize| -> &Vec<f64> {
        if cubic {
            &values[3 * k + 1]
        } else {
            &values[k]
        }
    };
    let k = times.partition_point(|&x| x <= t);
    if k == 0 {
        return value(0).clone();
    }
    if k >= times.len() {
        return value(times.len() - 1).clone();
    }
    let (lo, hi) = (k - 1, k);
    let dt = times[hi] - times[lo];
    let s = (t - times[lo]) / dt;
    let mut out: Vec<f64> = match interpolation {
        Interpolation::Step => value(lo).clone(),
        Interpolation::Linear if rotation => {
            let q = |v: &Vec<f64>| DQuat::from_xyzw(v[0], v[1], v[2], v[3]).normalize();
            q(value(lo)).slerp(q(value(hi)), s).to_array().to_vec()
        }
        Interpolation::Linear => value(lo)
            .iter()
            .zip(value(hi))
            .map(|(a, b)| a + (b - a) * s)
            .collect(),
        Interpolation::CubicSpline => {
            let (s2, s3) = (s * s, s * s * s);
            let (p0, m0) = (&values[3 * lo + 1], &values[3 * lo + 2]);
            let (p1, m1) = (&values[3 * hi + 1], &values[3 * hi]);
            (0..p0.len())
                .map(|c| {
                    (2.0 * s3 - 3.0 * s2 + 1.0) * p0[c]
                        + (s3 - 2.0 * s2 + s) * dt * m0[c]
                        + (-2.0 * s3 + 3.0 * s2) * p1[c]
                        + (s3 - s2) * dt * m1[c]
                })
                .collect()
        }
    };
    if rotation {
        let n = out.iter().map(|x| x * x).sum::<f64>().sqrt();
        out.iter_mut().for_each(|x| *x /= n);
    }
    out
}
