//! Adaptive sample times for the hybrid animation export: between two samples a viewer
//! interpolates the joint nodes' TRS (LINEAR: lerp / slerp), which differs from cagerig's own
//! interpolation; intervals where the difference is too large get more samples.
//!
//! An interval `[t0, t1]` is checked at its midpoint: cagerig's LBS M'(t) against the LBS a
//! viewer computes there from the TRS interpolated between the samples at `t0` and `t1` (on the
//! same rest mesh M(t): the morph weights are exact at every time). When the largest vertex
//! distance exceeds the bound, the midpoint becomes a sample and both halves are checked again.

use std::collections::HashMap;

use cagerig::playback::AnimationPlayer;
use cagerig::session::RigSession;
use cagerig::skinning::LinearBlendSkinning;
use glam::{DAffine3, DQuat, DVec3};

use super::export_animation::node_trs;
use super::export_animation_error::ExportAnimationError;
use super::export_bake::{BakeReport, bake_target};

/// Node (translation, rotation, scale) per joint at one sample.
type NodeTrs = Vec<(DVec3, DQuat, DVec3)>;

/// The outcome of [`refine_sample_times`].
#[derive(Debug, Clone, PartialEq)]
pub struct RefinedTimes {
    /// The sample times (sorted, every input time kept).
    pub times: Vec<f64>,
    /// Samples added to the input times.
    pub added: usize,
    /// The largest distance measured at the midpoint of an interval of `times` that was not
    /// split (world units): what a viewer shows there is that far from cagerig's M' at most
    /// among the checked midpoints.
    pub largest_checked: f64,
    /// True when `max_samples` stopped the refinement before every interval met the bound.
    pub capped: bool,
}

/// Refines `times` (sorted, e.g. from [`super::export_animation::sample_times`]) until at the
/// midpoint of every interval a viewer's interpolation of the exported nodes is within
/// `max_distance` (world units) of cagerig's LBS M' — or, `baked` (a `--bake` export under
/// DQS/CoR/blended), a viewer's LBS of the bind shape plus the two bracketing samples' baked
/// targets at their interpolated weights is within it of cagerig's M' under the session's
/// method — adding at most `max_samples − times.len()`
/// samples (intervals shorter than 1e-4 s, or whose midpoint rounds to an end in f32 as glTF
/// stores times, are not split). The session is put back in the state it was given in: its rest frames are the
/// bind frames [`super::export_animation::animation_to_gltf`] then writes, which the check
/// assumes.
pub fn refine_sample_times(
    session: &mut RigSession,
    player: &mut AnimationPlayer,
    times: &[f64],
    max_distance: f64,
    max_samples: usize,
    baked: bool,
) -> Result<RefinedTimes, ExportAnimationError> {
    if !(max_distance.is_finite() && max_distance > 0.0) {
        return Err(ExportAnimationError::InvalidBound {
            bound: max_distance,
        });
    }
    // The bind frames of the export are the rest frames when it starts.
    let bind: Vec<DAffine3> = session.rest_world_from_joint().to_vec();
    let start = session.editable_state();
    let mut checker = Checker {
        lbs: LinearBlendSkinning::new(session.skin_weights()),
        bind,
        trs: HashMap::new(),
        baked: baked.then(HashMap::new),
        world: Vec::new(),
        viewer_from_rest: Vec::new(),
        exact: Vec::new(),
        viewer: Vec::new(),
    };
    let mut out: Vec<f64> = times.to_vec();
    let mut pending: Vec<(f64, f64)> = times.windows(2).map(|w| (w[0], w[1])).collect();
    pending.reverse();
    let (mut largest, mut capped) = (0.0f64, false);
    while let Some((t0, t1)) = pending.pop() {
        // Intervals come in increasing t0: the baked targets of earlier samples are done with.
        if let Some(targets) = &mut checker.baked {
            targets.retain(|&bits, _| f64::from_bits(bits) >= t0);
        }
        let mid = 0.5 * (t0 + t1);
        let distance = checker.distance_at(session, player, t0, t1, mid)?;
        // glTF stores times as f32, strictly increasing: a midpoint that rounds onto an end
        // cannot be a sample.
        let representable = mid as f32 != t0 as f32 && mid as f32 != t1 as f32;
        if distance <= max_distance || t1 - t0 < 1e-4 || !representable {
            largest = largest.max(distance);
        } else if out.len() >= max_samples {
            largest = largest.max(distance);
            capped = true;
        } else {
            out.push(mid);
            // Left half first (a stack: pushed last).
            pending.push((mid, t1));
            pending.push((t0, mid));
        }
    }
    out.sort_by(f64::total_cmp);
    session
        .restore_editable_state(&start)
        .map_err(|source| ExportAnimationError::Restore { source })?;
    Ok(RefinedTimes {
        added: out.len() - times.len(),
        times: out,
        largest_checked: largest,
        capped,
    })
}

/// Scratch and cache of the midpoint checks.
struct Checker {
    lbs: LinearBlendSkinning,
    bind: Vec<DAffine3>,
    /// Node TRS at the sample times evaluated so far (by the bits of the time).
    trs: HashMap<u64, NodeTrs>,
    /// For a baked export: the baked targets (`#V`, bind space) of the samples still needed,
    /// by the bits of the time.
    baked: Option<HashMap<u64, Vec<DVec3>>>,
    world: Vec<DAffine3>,
    viewer_from_rest: Vec<DAffine3>,
    exact: Vec<DVec3>,
    viewer: Vec<DVec3>,
}

impl Checker {
    /// Evaluates the export at sample time `t` once (one playback of `t`): the node TRS and,
    /// for a baked export, the baked target ([`bake_target`] with the session's rest mesh at
    /// `t` as the bind shape, which the file holds to its f32 rounding), into the caches.
    fn sample_at(
        &mut self,
        session: &mut RigSession,
        player: &mut AnimationPlayer,
        t: f64,
    ) -> Result<(), ExportAnimationError> {
        let key = t.to_bits();
        let baked_cached = self.baked.as_ref().is_none_or(|b| b.contains_key(&key));
        if self.trs.contains_key(&key) && baked_cached {
            return Ok(());
        }
        player
            .apply(t, session)
            .map_err(|source| ExportAnimationError::Sample { time: t, source })?;
        self.world.resize(self.bind.len(), DAffine3::IDENTITY);
        let mut trs = Vec::with_capacity(self.bind.len());
        node_trs(session, &self.bind, &mut self.world, &mut trs);
        self.trs.insert(key, trs);
        if let Some(baked) = &mut self.baked {
            let mut target = Vec::new();
            bake_target(
                session,
                session.rest_mesh(),
                &mut target,
                &mut BakeReport::default(),
            );
            baked.insert(key, target);
        }
        Ok(())
    }

    /// Largest vertex distance at `mid` between cagerig's M' and a viewer's, whose nodes (and
    /// baked target weights) interpolate the samples at `t0` and `t1`.
    fn distance_at(
        &mut self,
        session: &mut RigSession,
        player: &mut AnimationPlayer,
        t0: f64,
        t1: f64,
        mid: f64,
    ) -> Result<f64, ExportAnimationError> {
        self.sample_at(session, player, t0)?;
        self.sample_at(session, player, t1)?;
        let (a, b) = (&self.trs[&t0.to_bits()], &self.trs[&t1.to_bits()]);
        let s = (mid - t0) / (t1 - t0);
        player
            .apply(mid, session)
            .map_err(|source| ExportAnimationError::Sample { time: mid, source })?;
        // The viewer's node worlds from the interpolated locals, parents before children.
        let nj = self.bind.len();
        self.world.resize(nj, DAffine3::IDENTITY);
        for &j in session.skeleton().topological_order() {
            let ((ta, ra, sa), (tb, rb, sb)) = (a[j], b[j]);
            // The exporter keeps consecutive quaternions in one hemisphere; so does this.
            let rb = if ra.dot(rb) < 0.0 { -rb } else { rb };
            let local = DAffine3::from_scale_rotation_translation(
                sa.lerp(sb, s),
                ra.slerp(rb, s),
                ta.lerp(tb, s),
            );
            self.world[j] = match session.skeleton().parent(j) {
                Some(p) => self.world[p] * local,
                None => local,
            };
        }
        self.viewer_from_rest.clear();
        self.viewer_from_rest.extend(
            self.world
                .iter()
                .zip(&self.bind)
                .map(|(w, b)| *w * b.inverse()),
        );
        let rest = session.rest_mesh();
        self.viewer.resize(rest.len(), DVec3::ZERO);
        let targets = self
            .baked
            .as_ref()
            .map(|baked| (&baked[&t0.to_bits()], &baked[&t1.to_bits()]));
        match targets {
            None => {
                self.exact.resize(rest.len(), DVec3::ZERO);
                self.lbs
                    .apply(session.posed_from_rest(), rest, &mut self.exact);
                self.lbs
                    .apply(&self.viewer_from_rest, rest, &mut self.viewer);
                Ok(cagerig::mesh::max_distance(&self.exact, &self.viewer))
            }
            Some((a, b)) => {
                // The viewer's bind shape: the rest mesh plus the baked targets at weights
                // 1 − s and s; cagerig's M' is the session's method.
                self.exact.clear();
                self.exact.extend(
                    rest.iter()
                        .zip(a.iter().zip(b))
                        .map(|(x, (ba, bb))| *x + ba.lerp(*bb, s)),
                );
                self.lbs
                    .apply(&self.viewer_from_rest, &self.exact, &mut self.viewer);
                Ok(cagerig::mesh::max_distance(
                    session.posed_mesh(),
                    &self.viewer,
                ))
            }
        }
    }
}
