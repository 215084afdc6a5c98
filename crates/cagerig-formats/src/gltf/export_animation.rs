//! The hybrid animation (skeleton track + cage track) as standard glTF that plays without
//! cagerig.
//!
//! - The bind shape is the session's rest mesh M₀ when the export starts; each cage key k
//!   becomes a morph target `ΦC_k − M₀`, and the morph weights are animated LINEAR with
//!   `w_lo = 1 − a, w_hi = a` at the cage keys' bracket, which is exactly cagerig's linear
//!   interpolation of cage keys (M(t) = Σ_k w_k ΦC_k) at every time, as long as every cage key
//!   time is a sample time (it always is).
//! - The inverse bind matrices are `B_j(0)⁻¹` (rest frames at the start). SkelUp moves the rest
//!   joints with the cage; that motion is folded into the joint nodes: the node world transform
//!   written at time t is `G_j(t) = T_j(t) · B_j(0)` with `T_j(t)` cagerig's skinning transform,
//!   so a viewer's `G_j(t) · IBM_j · M(t) = T_j(t) · M(t)` — cagerig's LBS result.
//! - Read back by cagerig ([`crate::morph_cage_track`]), the morph weights become a cage track
//!   again (each target solved for its cage displacement on CageUp's rows) and the joint keys
//!   are played with SkelUp held, since they already carry the rest joints' motion.
//! - Exactness: under LBS, exact (to the f32 rounding of glTF) at every sample time; samples are
//!   the union of the skeleton keys, the cage keys and a grid at `fps`. Between samples a viewer
//!   slerps/lerps the node TRS, which differs from cagerig's interpolation by the resampling.
//!   Under DQS/CoR the file still carries the LBS rig (glTF skins with LBS only), unless it is
//!   baked ([`animation_to_gltf`] with `bake`): then each sample also gets a morph target that turns the
//!   viewer's LBS into cagerig's DQS/CoR M' at that sample ([`super::export_bake`]), with LINEAR
//!   weights that are 1 at its sample and 0 at every other, so that between two samples a viewer
//!   blends the two corrections linearly.

use cagerig::animation::{CageTrack, bracket};
use cagerig::playback::AnimationPlayer;
use cagerig::session::RigSession;
use glam::{DAffine3, DQuat, DVec3};
use serde_json::{Value, json};

use super::export::{Builder, f32_bytes, position_accessor, session_to_gltf};
use super::export_animation_error::ExportAnimationError;
use super::export_bake::{BakeReport, bake_target, f32_rounded};

/// Sample times: a grid at `fps` over `[0, duration]` plus every key time, sorted, unique as f32.
pub fn sample_times(duration: f64, fps: f64, key_times: &[f64]) -> Vec<f64> {
    let steps = (duration * fps).ceil().clamp(0.0, 1e6) as usize;
    let mut times: Vec<f64> = (0..=steps)
        .map(|i| (i as f64 / fps).min(duration))
        .chain(
            key_times
                .iter()
                .copied()
                .filter(|t| *t >= 0.0 && *t <= duration),
        )
        .collect();
    times.sort_by(f64::total_cmp);
    // glTF stores times as f32: keep one time per f32 value (key times before grid times).
    let is_key = |t: f64| key_times.contains(&t);
    let mut out: Vec<f64> = Vec::with_capacity(times.len());
    for t in times {
        match out.last_mut() {
            Some(last) if *last as f32 == t as f32 => {
                if is_key(t) && !is_key(*last) {
                    *last = t;
                }
            }
            _ => out.push(t),
        }
    }
    out
}

/// The local (translation, rotation, scale) of every joint node (`#J`) for the session's current
/// state: node world `G_j = T_j · B_j(0)` with `bind` = `B_j(0)` (`#J`); `world` is scratch
/// (`#J`).
pub(crate) fn node_trs(
    session: &RigSession,
    bind: &[DAffine3],
    world: &mut [DAffine3],
    out: &mut Vec<(DVec3, DQuat, DVec3)>,
) {
    for (j, w) in world.iter_mut().enumerate() {
        *w = session.posed_from_rest()[j] * bind[j];
    }
    out.clear();
    for j in 0..world.len() {
        let local = match session.skeleton().parent(j) {
            Some(p) => world[p].inverse() * world[j],
            None => world[j],
        };
        let (s, r, tr) = local.to_scale_rotation_translation();
        out.push((tr, r.normalize(), s));
    }
}

/// Bytes the baked targets add: 12 per vertex and sample (f32 VEC3), plus the weights of every
/// target (`cage_keys + samples`) at every sample (f32).
pub fn baked_bytes(vertices: usize, cage_keys: usize, samples: usize) -> u64 {
    let (v, c, s) = (vertices as u64, cage_keys as u64, samples as u64);
    12u64
        .saturating_mul(v)
        .saturating_mul(s)
        .saturating_add(4u64.saturating_mul(s).saturating_mul(c.saturating_add(s)))
}

/// Plays `player` at every time of `times` on `session` and writes the glTF document (JSON and
/// binary chunk) of the animation. `cage_track` must be the player's cage track (its keys
/// become the morph targets). `name` names the mesh and the skin, `animation` the animation.
/// The session is left at the last sample.
///
/// With `bake`, the session's skinning result is baked: after the cage-key targets, one morph
/// target per sample (`#V` bind-space corrections, see [`super::export_bake`]) whose weight is 1
/// at its sample and 0 at the others (LINEAR), so that at every sample time a viewer shows the
/// session's M' (DQS or CoR) instead of the LBS of the rig. The mesh's `extras` name the targets
/// (`targetNames`, which Blender uses for shape keys) and mark the baked ones
/// (`cagerig_baked_skinning`: `method`, `first_target`) so that cagerig's importer leaves them
/// out. Under LBS nothing needs baking and no target is added. Refused when the file would pass
/// the GLB limit of 4 GiB (12 bytes × `#V` per sample, plus `#samples × #targets` weights).
/// Without `bake` the report is empty.
pub fn animation_to_gltf(
    session: &mut RigSession,
    player: &mut AnimationPlayer,
    cage_track: Option<&CageTrack>,
    times: &[f64],
    name: &str,
    animation: &str,
    bake: bool,
) -> Result<(Value, Vec<u8>, BakeReport), ExportAnimationError> {
    let bake = bake && !session.skinning().is_linear();
    if bake {
        let cage_keys = cage_track.map_or(0, |c| c.times().len());
        let bytes = baked_bytes(session.num_vertices(), cage_keys, times.len());
        if bytes > u64::from(u32::MAX) {
            return Err(ExportAnimationError::TooLarge {
                samples: times.len(),
                vertices: session.num_vertices(),
                gib: bytes as f64 / f64::from(1u32 << 30),
            });
        }
    }
    if times.is_empty() {
        return Err(ExportAnimationError::NoSamples);
    }
    let base: Vec<DVec3> = session.rest_mesh().to_vec();
    let bind: Vec<DAffine3> = session.rest_world_from_joint().to_vec();
    let (mut document, bin) =
        session_to_gltf(session, name).map_err(ExportAnimationError::Document)?;
    let mut b = Builder::from_document(&document, bin);
    let nj = session.skeleton().len();
    // Morph targets: the rest mesh at each cage key.
    let mut targets = Vec::new();
    let mut target_names = Vec::new();
    // The cage-key targets as the file holds them (f32), for the baked targets' bind shape.
    let mut cage_deltas: Vec<Vec<DVec3>> = Vec::new();
    if let Some(track) = cage_track {
        for (k, &t) in track.times().iter().enumerate() {
            player
                .apply(t, session)
                .map_err(|source| ExportAnimationError::Sample { time: t, source })?;
            let delta: Vec<DVec3> = session
                .rest_mesh()
                .iter()
                .zip(&base)
                .map(|(m, m0)| *m - *m0)
                .collect();
            targets.push(json!({"POSITION": position_accessor(&mut b, &delta, true)}));
            target_names.push(format!("cage key {k} (t = {t} s)"));
            if bake {
                cage_deltas.push(delta.into_iter().map(f32_rounded).collect());
            }
        }
    }
    let cage_targets = targets.len();
    let mut report = BakeReport::default();
    let bind_base: Vec<DVec3> = base.iter().copied().map(f32_rounded).collect();
    let mut bind_shape = Vec::with_capacity(if bake { base.len() } else { 0 });
    let mut correction = Vec::new();
    // Node TRS and morph weights at each sample.
    let mut translations = Vec::with_capacity(nj * times.len());
    let mut rotations = Vec::with_capacity(nj * times.len());
    let mut scales = Vec::with_capacity(nj * times.len());
    let mut weights = Vec::with_capacity(targets.len() * times.len());
    let mut world = vec![DAffine3::IDENTITY; nj];
    let mut trs = Vec::with_capacity(nj);
    for &t in times {
        player
            .apply(t, session)
            .map_err(|source| ExportAnimationError::Sample { time: t, source })?;
        node_trs(session, &bind, &mut world, &mut trs);
        for &(tr, r, s) in &trs {
            translations.push(tr);
            rotations.push(r);
            scales.push(s);
        }
        let first_weight = weights.len();
        if let Some(track) = cage_track {
            let br = bracket(track.times(), t);
            weights.extend((0..cage_targets).map(|k| {
                if br.lo == br.hi {
                    f64::from(u8::from(k == br.lo))
                } else if k == br.lo {
                    1.0 - br.a
                } else if k == br.hi {
                    br.a
                } else {
                    0.0
                }
            }));
        }
        if bake {
            // The viewer's bind shape at t: M₀ plus the cage targets at their weights (f32).
            bind_shape.clone_from(&bind_base);
            for (delta, &w) in cage_deltas.iter().zip(&weights[first_weight..]) {
                if w != 0.0 {
                    for (x, d) in bind_shape.iter_mut().zip(delta) {
                        *x += w * *d;
                    }
                }
            }
            bake_target(session, &bind_shape, &mut correction, &mut report);
            targets.push(json!({"POSITION": position_accessor(&mut b, &correction, true)}));
            target_names.push(format!("{} t = {t} s", session.skinning().label()));
        }
    }
    if bake {
        // One-hot: baked target k has weight 1 at sample k (rows of `#samples` after the cage
        // weights of each sample).
        let ns = times.len();
        let cage_weights = std::mem::replace(&mut weights, Vec::with_capacity(ns * targets.len()));
        for k in 0..ns {
            weights.extend_from_slice(&cage_weights[k * cage_targets..(k + 1) * cage_targets]);
            weights.extend((0..ns).map(|i| f64::from(u8::from(i == k))));
        }
    }
    // Keep consecutive quaternions in one hemisphere (viewers slerp without flipping).
    for j in 0..nj {
        for k in 1..times.len() {
            let (prev, cur) = (rotations[(k - 1) * nj + j], rotations[k * nj + j]);
            if prev.dot(cur) < 0.0 {
                rotations[k * nj + j] = -cur;
            }
        }
    }
    let (t_min, t_max) = (times[0], times[times.len() - 1]);
    let input = b.accessor(
        &f32_bytes(times.iter().copied()),
        None,
        json!({"componentType": 5126, "count": times.len(), "type": "SCALAR",
               "min": [t_min as f32], "max": [t_max as f32]}),
    );
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    for j in 0..nj {
        let column = |k: usize| k * nj + j;
        let tr = f32_bytes((0..times.len()).flat_map(|k| translations[column(k)].to_array()));
        let ro = f32_bytes((0..times.len()).flat_map(|k| rotations[column(k)].to_array()));
        let sc = f32_bytes((0..times.len()).flat_map(|k| scales[column(k)].to_array()));
        for (bytes, kind, path) in [
            (tr, "VEC3", "translation"),
            (ro, "VEC4", "rotation"),
            (sc, "VEC3", "scale"),
        ] {
            let output = b.accessor(
                &bytes,
                None,
                json!({"componentType": 5126, "count": times.len(), "type": kind}),
            );
            channels.push(json!({"sampler": samplers.len(), "target": {"node": j, "path": path}}));
            samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
        }
    }
    if !targets.is_empty() {
        let output = b.accessor(
            &f32_bytes(weights.iter().copied()),
            None,
            json!({"componentType": 5126, "count": weights.len(), "type": "SCALAR"}),
        );
        channels
            .push(json!({"sampler": samplers.len(), "target": {"node": nj, "path": "weights"}}));
        samplers.push(json!({"input": input, "output": output, "interpolation": "LINEAR"}));
        // Default weights 0: without the animation the file shows M₀, the bind shape.
        let count = targets.len();
        document["meshes"][0]["primitives"][0]["targets"] = Value::Array(targets);
        document["meshes"][0]["weights"] = json!(vec![0.0; count]);
        document["meshes"][0]["extras"] = json!({"targetNames": target_names});
        if bake {
            document["meshes"][0]["extras"]["cagerig_baked_skinning"] = json!({
                "method": session.skinning().name(),
                "first_target": cage_targets,
            });
        }
    }
    document["animations"] =
        json!([{"name": animation, "channels": channels, "samplers": samplers}]);
    let (document, bin) = b.finish(document);
    Ok((document, bin, report))
}
