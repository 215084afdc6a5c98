//! glTF animations → skeleton tracks of local transforms `parent_from_joint`.
//!
//! Each channel is evaluated exactly as the specification says (LINEAR: lerp, and slerp for
//! rotations along the shorter arc; STEP; CUBICSPLINE: Hermite with the file's tangents, then
//! normalised for rotations). The track's keys are the union of the key times of every channel
//! that moves the skeleton (joint nodes, nodes between joints, ancestors of the skeleton). Joint
//! j's local is the product of the node locals from its parent joint (excluded) down to its own
//! node; for a root, every ancestor is composed in.
//!
//! Exactness: between two union keys the track lerps translation and scale and slerps rotation,
//! which is exactly what LINEAR channels do (a sub-interval of a lerp/slerp is a lerp/slerp) when
//! one node of a joint's composed chain moves, or the nodes below a turning one are still and
//! at its origin. Where a turning node carries another animated node or a translation (a
//! skeleton hanging from the joints of another, an animated armature above an offset root), the
//! composed origin moves on an arc: keys are added until the track is within
//! [`COMPOSED_TOLERANCE`] of the skeleton's size of the file ([`super::composed_keys`]), and
//! the animation is marked `exact = false` with a note. STEP channels get an extra key 1e-6 s
//! (or less on tight keys) before each step; CUBICSPLINE channels are resampled at the
//! `resample_fps` of [`ImportOptions`]; such animations are marked `exact = false` and reported.

use std::path::Path;

use cagerig::Warning;
use cagerig::animation::SkeletonTrack;
use glam::{DAffine3, DQuat, DVec3};
use gltf::accessor::Dimensions;
use gltf::animation::{Interpolation, Property};

use super::buffers::Buffers;
use super::composed_keys::{NodeMotion, composes_several_motions, refine_composed_keys};
use super::scene::{NodeLocal, NodeTree};
use crate::ImportOptions;
use crate::character::ImportedAnimation;
use crate::error::{FormatError, invalid};

/// Keys are added where a joint's composed local leaves the track's interpolation by more than
/// this fraction of the skeleton's size (`composed_keys.rs`).
pub const COMPOSED_TOLERANCE: f64 = 1e-6;

/// Seconds before a STEP key at which the previous value is held (the track ramps in between).
const STEP_RAMP: f64 = 1e-6;

/// One channel's sampler data.
struct Channel {
    node: usize,
    property: Property,
    interpolation: Interpolation,
    times: Vec<f64>,
    /// Output values: 3 or 4 components per element; CUBICSPLINE has 3 elements per key.
    values: Vec<f64>,
    width: usize,
}

impl Channel {
    fn element(&self, k: usize) -> &[f64] {
        &self.values[k * self.width..(k + 1) * self.width]
    }

    /// Value at time t (clamped to the keys).
    fn sample(&self, t: f64) -> Vec<f64> {
        let n = self.times.len();
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| {
            if cubic {
                self.element(3 * k + 1)
            } else {
                self.element(k)
            }
        };
        let hi = self.times.partition_point(|&x| x <= t);
        if hi == 0 {
            return value(0).to_vec();
        }
        if hi >= n {
            return value(n - 1).to_vec();
        }
        let lo = hi - 1;
        let dt = self.times[hi] - self.times[lo];
        let s = (t - self.times[lo]) / dt;
        let rotation = self.property == Property::Rotation;
        let out = match self.interpolation {
            Interpolation::Step => value(lo).to_vec(),
            Interpolation::Linear if rotation => {
                let q = |e: &[f64]| DQuat::from_xyzw(e[0], e[1], e[2], e[3]).normalize();
                let r = q(value(lo)).slerp(q(value(hi)), s);
                vec![r.x, r.y, r.z, r.w]
            }
            Interpolation::Linear => value(lo)
                .iter()
                .zip(value(hi))
                .map(|(a, b)| a + (b - a) * s)
                .collect(),
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let (h00, h10, h01, h11) = (
                    2.0 * s3 - 3.0 * s2 + 1.0,
                    s3 - 2.0 * s2 + s,
                    -2.0 * s3 + 3.0 * s2,
                    s3 - s2,
                );
                let (v0, b0) = (self.element(3 * lo + 1), self.element(3 * lo + 2));
                let (v1, a1) = (self.element(3 * hi + 1), self.element(3 * hi));
                (0..self.width)
                    .map(|c| h00 * v0[c] + h10 * dt * b0[c] + h01 * v1[c] + h11 * dt * a1[c])
                    .collect()
            }
        };
        if rotation {
            let q = DQuat::from_xyzw(out[0], out[1], out[2], out[3]).normalize();
            vec![q.x, q.y, q.z, q.w]
        } else {
            out
        }
    }
}

/// Animations, the nodes' own pose (joint locals) and warnings.
pub type AnimationImport = (Vec<ImportedAnimation>, Vec<DAffine3>, Vec<Warning>);

/// What the animations are read for: the skin's joints and the skinned node with morph targets.
#[derive(Debug, Clone, Copy)]
pub struct AnimationTargets<'a> {
    /// Node of each joint (`#J`).
    pub joint_nodes: &'a [usize],
    /// Parent joint of each joint (`#J`).
    pub joint_parent: &'a [Option<usize>],
    /// (node, number of targets) of the skinned node whose morph weights are imported.
    pub morph: Option<(usize, usize)>,
}

/// Every animation of the document as a skeleton track for the skin's joints (with the morph
/// weights of `targets.morph` at the track's keys), and the joint locals of the nodes' own
/// (unanimated) transforms.
pub fn import_animations(
    document: &gltf::Document,
    buffers: &Buffers,
    tree: &NodeTree,
    targets: &AnimationTargets,
    options: &ImportOptions,
    path: &Path,
) -> Result<AnimationImport, FormatError> {
    let AnimationTargets {
        joint_nodes,
        joint_parent,
        morph,
    } = *targets;
    let nn = tree.parent.len();
    // Nodes whose transform moves the skeleton: joints and all their ancestors.
    let mut relevant = vec![false; nn];
    for &n in joint_nodes {
        relevant[n] = true;
        let mut k = tree.parent[n];
        while let Some(p) = k {
            relevant[p] = true;
            k = tree.parent[p];
        }
    }
    // Per joint: the chain of nodes whose locals compose its `parent_from_joint`, top first.
    let chains: Vec<Vec<usize>> = joint_nodes
        .iter()
        .enumerate()
        .map(|(j, &n)| {
            let stop = joint_parent[j].map(|p| joint_nodes[p]);
            let mut chain = vec![n];
            let mut k = tree.parent[n];
            while let Some(p) = k {
                if Some(p) == stop {
                    break;
                }
                chain.push(p);
                k = tree.parent[p];
            }
            chain.reverse();
            chain
        })
        .collect();
    let rest_locals = tree.rest_affines();
    let node_pose: Vec<DAffine3> = chains
        .iter()
        .map(|chain| {
            chain
                .iter()
                .fold(DAffine3::IDENTITY, |acc, &n| acc * rest_locals[n])
        })
        .collect();
    let length_scale = skeleton_size(tree, &rest_locals, joint_nodes, &node_pose);
    let mut warnings = Vec::new();
    let mut animations = Vec::new();
    for animation in document.animations() {
        let name = animation
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("animation{}", animation.index()));
        let element = format!("animation {} {name:?}", animation.index());
        let mut channels = Vec::new();
        let mut weight_channel = None;
        let mut ignored = 0usize;
        for channel in animation.channels() {
            let node = channel.target().node().index();
            let property = channel.target().property();
            let morph_targets = match morph {
                Some((n, count)) if n == node && property == Property::MorphTargetWeights => {
                    Some(count)
                }
                _ => None,
            };
            if property == Property::MorphTargetWeights && morph_targets.is_none() {
                warnings.push(Warning::Note {
                    message: format!(
                        "{element}: morph-weight channel on node {node} is not imported (only the weights of the one skinned node with morph targets are)"
                    ),
                });
                continue;
            }
            if morph_targets.is_none() && !relevant[node] {
                ignored += 1;
                continue;
            }
            if matches!(tree.rest_local[node], NodeLocal::Matrix(_)) {
                return Err(invalid(
                    path,
                    &element,
                    format!(
                        "animates node {node}, which has a `matrix` (the specification forbids it)"
                    ),
                ));
            }
            let sampler = channel.sampler();
            let times = buffers.read(&sampler.input(), "animation input", &[Dimensions::Scalar])?;
            if times.is_empty() {
                return Err(invalid(path, &element, "a sampler has no keys"));
            }
            if let Some(k) = (1..times.len()).find(|&k| times[k] <= times[k - 1]) {
                return Err(invalid(
                    path,
                    &element,
                    format!(
                        "sampler input time {} at key {k} does not increase after {}",
                        times[k],
                        times[k - 1]
                    ),
                ));
            }
            let (width, dims) = match (property, morph_targets) {
                (Property::Rotation, _) => (4, Dimensions::Vec4),
                (_, Some(count)) => (count, Dimensions::Scalar),
                _ => (3, Dimensions::Vec3),
            };
            if width == 0 {
                continue;
            }
            let values = buffers.read(&sampler.output(), "animation output", &[dims])?;
            let interpolation = sampler.interpolation();
            let per_key = if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
            if values.len() != times.len() * per_key * width {
                return Err(invalid(
                    path,
                    &element,
                    format!(
                        "sampler has {} keys but {} output elements (expected {})",
                        times.len(),
                        values.len() / width,
                        times.len() * per_key
                    ),
                ));
            }
            let channel = Channel {
                node,
                property,
                interpolation,
                times,
                values,
                width,
            };
            if morph_targets.is_some() {
                weight_channel = Some(channel);
            } else {
                channels.push(channel);
            }
        }
        if ignored > 0 {
            warnings.push(Warning::Note {
                message: format!("{element}: {ignored} channels on nodes that do not move the skeleton were ignored"),
            });
        }
        // Key times: union of channel keys, plus STEP ramps and CUBICSPLINE resampling.
        let mut times: Vec<f64> = Vec::new();
        let mut exact = true;
        for c in channels.iter().chain(&weight_channel) {
            times.extend(&c.times);
            match c.interpolation {
                Interpolation::Step => {
                    exact = false;
                    for k in 1..c.times.len() {
                        let gap = c.times[k] - c.times[k - 1];
                        times.push(c.times[k] - STEP_RAMP.min(gap / 4.0));
                    }
                }
                Interpolation::CubicSpline => {
                    exact = false;
                    let (t0, t1) = (c.times[0], c.times[c.times.len() - 1]);
                    let steps = ((t1 - t0) * options.resample_fps).ceil().clamp(1.0, 1e6) as usize;
                    times.extend((0..=steps).map(|i| t0 + (t1 - t0) * i as f64 / steps as f64));
                }
                Interpolation::Linear => {}
            }
        }
        times.sort_by(f64::total_cmp);
        times.dedup();
        if times.is_empty() {
            times.push(0.0);
        }
        if !exact {
            warnings.push(Warning::Note {
                message: format!(
                    "{element}: STEP/CUBICSPLINE channels were resampled (STEP: a {STEP_RAMP:e} s ramp before each step; CUBICSPLINE: {} samples/s); the track matches the file at its keys",
                    options.resample_fps
                ),
            });
        }
        // The composed locals of every joint at time t.
        let mut node_locals = vec![DAffine3::IDENTITY; nn];
        let mut trs: Vec<Option<(DVec3, DQuat, DVec3)>> = vec![None; nn];
        let mut composed_at = |t: f64| -> Vec<DAffine3> {
            for (i, local) in node_locals.iter_mut().enumerate() {
                *local = tree.rest_local[i].affine();
            }
            trs.iter_mut().for_each(|x| *x = None);
            for c in &channels {
                let (mut tr, mut r, mut s) = match (trs[c.node], tree.rest_local[c.node]) {
                    (Some(x), _) => x,
                    (
                        None,
                        NodeLocal::Trs {
                            translation,
                            rotation,
                            scale,
                        },
                    ) => (translation, rotation, scale),
                    // Channels on `matrix` nodes were refused above.
                    (None, NodeLocal::Matrix(_)) => continue,
                };
                let v = c.sample(t);
                match c.property {
                    Property::Translation => tr = DVec3::new(v[0], v[1], v[2]),
                    Property::Scale => s = DVec3::new(v[0], v[1], v[2]),
                    Property::Rotation => r = DQuat::from_xyzw(v[0], v[1], v[2], v[3]),
                    Property::MorphTargetWeights => {}
                }
                trs[c.node] = Some((tr, r, s));
            }
            for (i, x) in trs.iter().enumerate() {
                if let Some((tr, r, s)) = x {
                    node_locals[i] = DAffine3::from_scale_rotation_translation(*s, *r, *tr);
                }
            }
            chains
                .iter()
                .map(|chain| {
                    chain
                        .iter()
                        .fold(DAffine3::IDENTITY, |acc, &n| acc * node_locals[n])
                })
                .collect()
        };
        // Joints whose composed local the track's interpolation may not follow between keys.
        let motion = node_motion(tree, &channels);
        let suspects: Vec<usize> = chains
            .iter()
            .enumerate()
            .filter(|(_, chain)| {
                let chain: Vec<NodeMotion> = chain.iter().map(|&n| motion[n]).collect();
                composes_several_motions(&chain)
            })
            .map(|(j, _)| j)
            .collect();
        let (times, keys) = if suspects.is_empty() {
            let keys = times.iter().map(|&t| composed_at(t)).collect();
            (times, keys)
        } else {
            let tolerance = COMPOSED_TOLERANCE * length_scale;
            let refined = refine_composed_keys(
                &times,
                &suspects,
                length_scale,
                tolerance,
                2.0 * STEP_RAMP,
                composed_at,
            );
            if refined.added > 0 || refined.capped {
                exact = false;
                let j = suspects[0];
                let within = if refined.capped {
                    format!(
                        "the keys were capped, so between them it is up to {:.1e} of the skeleton's size off the file (target {COMPOSED_TOLERANCE:e})",
                        refined.largest_checked / length_scale
                    )
                } else {
                    format!("within {COMPOSED_TOLERANCE:e} of the skeleton's size of the file")
                };
                let which = match suspects.len() {
                    1 => format!("joint {j} (node {}) moves", joint_nodes[j]),
                    n => format!(
                        "{n} joints (first: joint {j}, node {}) move",
                        joint_nodes[j]
                    ),
                };
                warnings.push(Warning::Note {
                    message: format!(
                        "{element}: {which} with several animated nodes above (a turning node carries another motion or a translation on an arc), which the track's interpolation between the file's keys does not follow; {} keys were added, {within}",
                        refined.added
                    ),
                });
            }
            (refined.times, refined.keys)
        };
        let morph_weights = weight_channel.as_ref().map(|c| {
            times
                .iter()
                .flat_map(|&t| c.sample(t))
                .collect::<Vec<f64>>()
        });
        let duration = *times.last().unwrap_or(&0.0);
        let track =
            SkeletonTrack::new(times, keys).map_err(|e| invalid(path, &element, e.to_string()))?;
        animations.push(ImportedAnimation {
            name,
            duration,
            track,
            exact,
            morph_weights,
        });
    }
    Ok((animations, node_pose, warnings))
}

/// How each node is animated by `channels`, and whether its rest translation is not zero.
fn node_motion(tree: &NodeTree, channels: &[Channel]) -> Vec<NodeMotion> {
    let mut motion: Vec<NodeMotion> = tree
        .rest_local
        .iter()
        .map(|local| NodeMotion {
            turns: false,
            animated: false,
            offset: local.affine().translation != DVec3::ZERO,
        })
        .collect();
    for c in channels {
        let m = &mut motion[c.node];
        m.animated = true;
        m.turns |= matches!(c.property, Property::Rotation | Property::Scale);
    }
    motion
}

/// The length that rotation and scale differences count by: the extent of the joints' rest
/// positions (or of the composed rest translations for a skeleton of one point; 1 if nothing
/// has a size).
fn skeleton_size(
    tree: &NodeTree,
    rest_locals: &[DAffine3],
    joint_nodes: &[usize],
    node_pose: &[DAffine3],
) -> f64 {
    let mut world = vec![DAffine3::IDENTITY; rest_locals.len()];
    tree.globals(rest_locals, &mut world);
    let (lo, hi) = joint_nodes
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &n| {
            (lo.min(world[n].translation), hi.max(world[n].translation))
        });
    let extent = (hi - lo).length();
    let reach = node_pose
        .iter()
        .map(|p| p.translation.length())
        .fold(0.0, f64::max);
    let size = if extent.is_finite() {
        extent.max(reach)
    } else {
        reach
    };
    if size.is_finite() && size > 0.0 {
        size
    } else {
        1.0
    }
}
