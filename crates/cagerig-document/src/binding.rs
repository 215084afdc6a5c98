//! Binding the skeleton: the rig's skeleton S becomes the draft built in the rest view (or
//! stays, for a re-weighting), with automatic skinning weights Ω (geodesic voxel binding, the
//! `cagerig weights` method) or the bound weights carried over. The heavy part — the weights
//! and the new session — runs on a background thread with progress; the document takes the
//! result as one undo step ([`crate::document::Document::finish_bind`]). The automatic weights
//! may instead be handed to a [`WeightsOffload`] (the web page's worker); the new session is
//! then built once they are back (on the web target, which has no threads, on the page's
//! thread after a frame of progress).

use std::sync::mpsc::{Receiver, TryRecvError, channel};
use std::sync::{Arc, Mutex};
use web_time::Instant;

use cagerig::auto_weights::{AutoWeightsOptions, Stage};
use cagerig::session::{DisplayPrecision, RigParts, RigSession, SessionOptions};
use cagerig::{Skeleton, SkinWeights, Warning};
use glam::{DQuat, DVec3};

pub use crate::bind_progress::BindStep;
use crate::offload::{WeightsInput, WeightsOffload, WeightsOutput, WeightsReply, compute_weights};
use crate::skeleton_draft::SkeletonDraft;

/// Where the new Ω comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum BindWeights {
    /// Computed from the mesh, the new skeleton and the cage's interior.
    Automatic(AutoWeightsOptions),
    /// The bound weights, each joint's column carried to the joint that stands for it; the
    /// weight of a deleted joint goes to its nearest kept ancestor; new joints get none.
    KeepBound,
}

/// Everything a bind needs, taken from the document (cheap: carried weights are made here)
/// so the rest can run elsewhere.
pub struct BindRequest {
    /// The parts of the new rig; Ω is final unless `automatic` computes it.
    parts: RigParts,
    options: SessionOptions,
    precision: DisplayPrecision,
    /// The automatic weights' options, when Ω is to be computed.
    automatic: Option<AutoWeightsOptions>,
    /// For each new joint, the bound joint it stands for (`#J` new).
    pub origins: Vec<Option<usize>>,
    /// Warnings of weights computed elsewhere, reported with the bind's.
    warnings: Vec<Warning>,
}

/// A finished bind.
pub struct BoundRig {
    pub session: RigSession,
    pub warnings: Vec<Warning>,
    /// For each joint of the new skeleton, the old joint it stands for.
    pub origins: Vec<Option<usize>>,
    pub seconds: f64,
}

impl BindRequest {
    /// A bind of `session` to `draft` (`None`: the session's own skeleton, re-weighted).
    /// `rigged` is false for the placeholder rig of a mesh opened without a skeleton, whose
    /// weights cannot be kept.
    pub fn new(
        session: &RigSession,
        draft: Option<&SkeletonDraft>,
        rigged: bool,
        weights: BindWeights,
    ) -> Result<Self, String> {
        let own;
        let draft = match draft {
            Some(d) => d,
            None if rigged => {
                own = SkeletonDraft::from_session(session);
                &own
            }
            None => return Err(crate::skeleton_draft::DraftError::Empty.to_string()),
        };
        if !rigged && weights == BindWeights::KeepBound {
            return Err(
                "the rig has no bound weights to keep: bind with automatic weights".to_string(),
            );
        }
        let skeleton = draft
            .to_skeleton(session.rest_frames())
            .map_err(|e| e.to_string())?;
        let origins: Vec<Option<usize>> = if rigged {
            draft.joints.iter().map(|j| j.bound).collect()
        } else {
            vec![None; draft.len()]
        };
        let (weights, automatic) = match weights {
            BindWeights::Automatic(options) => (
                SkinWeights::from_triplets(session.num_vertices(), skeleton.len(), [])
                    .map_err(|e| e.to_string())?
                    .0,
                Some(options),
            ),
            BindWeights::KeepBound => {
                let old_parents: Vec<Option<usize>> = session
                    .skeleton()
                    .joints()
                    .iter()
                    .map(|j| j.parent)
                    .collect();
                let carried =
                    carry_weights(session.skin_weights(), &old_parents, &origins, &skeleton)?;
                (carried, None)
            }
        };
        Ok(Self {
            parts: session.parts_with_skeleton(skeleton, weights),
            options: session.rebinding_options(),
            precision: session.display_precision(),
            automatic,
            origins,
            warnings: Vec::new(),
        })
    }

    /// The input of the automatic weights, when Ω is to be computed.
    fn weights_input(&self) -> Option<WeightsInput> {
        let options = self.automatic.as_ref()?;
        let p = &self.parts;
        Some(WeightsInput::new(options, &p.mesh, &p.skeleton, &p.cage))
    }

    /// Takes Ω computed elsewhere: the request then only builds the session.
    fn with_weights(mut self, output: WeightsOutput) -> Result<Self, String> {
        let (weights, warnings) = output
            .into_weights(self.parts.mesh.num_vertices(), self.parts.skeleton.len())
            .map_err(|e| e.to_string())?;
        self.parts.skin_weights = weights;
        self.warnings.extend(warnings);
        self.automatic = None;
        Ok(self)
    }

    /// Computes Ω and builds the new session; `progress` follows the automatic weights, then
    /// the rig's binding.
    pub fn run(mut self, progress: &(dyn Fn(BindStep) + Sync)) -> Result<BoundRig, String> {
        let t = Instant::now();
        let mut warnings = std::mem::take(&mut self.warnings);
        if let Some(options) = &self.automatic {
            let (weights, more) = compute_weights(
                options,
                &self.parts.mesh,
                &self.parts.skeleton,
                &self.parts.cage,
                &|p| progress(BindStep::Weights(p)),
            )
            .map_err(|e| e.to_string())?;
            warnings.extend(more);
            self.parts.skin_weights = weights;
        }
        let report = |stage, done, total| progress(BindStep::Rig { stage, done, total });
        let (mut session, more) = RigSession::with_progress(self.parts, self.options, &report)
            .map_err(|e| e.to_string())?;
        warnings.extend(more);
        session
            .set_display_precision(self.precision)
            .map_err(|e| e.to_string())?;
        Ok(BoundRig {
            session,
            warnings,
            origins: self.origins,
            seconds: t.elapsed().as_secs_f64(),
        })
    }
}

/// Ω of the old rig (`#V × #J old`, parents `old_parents`) carried to `skeleton`
/// (`#V × #J new`) by `origins` (new joint → old joint): a deleted joint's weight goes to its
/// nearest ancestor that was kept, or to new joint 0 when none was.
pub fn carry_weights(
    old: &SkinWeights,
    old_parents: &[Option<usize>],
    origins: &[Option<usize>],
    skeleton: &Skeleton,
) -> Result<SkinWeights, String> {
    let mut new_of_old = vec![None; old.num_joints()];
    for (new, origin) in origins.iter().enumerate() {
        if let Some(o) = origin
            && let Some(slot) = new_of_old.get_mut(*o)
        {
            *slot = Some(new);
        }
    }
    let target = |mut j: usize| -> usize {
        for _ in 0..=old_parents.len() {
            if let Some(Some(n)) = new_of_old.get(j) {
                return *n;
            }
            match old_parents.get(j).copied().flatten() {
                Some(p) => j = p,
                None => break,
            }
        }
        0
    };
    let mut triplets = Vec::with_capacity(old.num_entries());
    for v in 0..old.num_vertices() {
        let (joints, weights) = old.row(v);
        for (&j, &w) in joints.iter().zip(weights) {
            triplets.push((v, target(j as usize), w));
        }
    }
    SkinWeights::from_triplets(old.num_vertices(), skeleton.len(), triplets)
        .map(|(w, _)| w)
        .map_err(|e| e.to_string())
}

/// The pose of the old rig (`rotations`, `scales`, `offsets`, `#J old`) on the new skeleton
/// (`#J new`): a joint that stands for an old one keeps its pose, a new joint is at rest.
pub fn carry_pose(
    origins: &[Option<usize>],
    rotations: &[DQuat],
    scales: &[DVec3],
    offsets: &[DVec3],
) -> (Vec<DQuat>, Vec<DVec3>, Vec<DVec3>) {
    let pick = |o: &Option<usize>| o.filter(|&o| o < rotations.len());
    (
        origins
            .iter()
            .map(|o| pick(o).map_or(DQuat::IDENTITY, |o| rotations[o]))
            .collect(),
        origins
            .iter()
            .map(|o| {
                pick(o)
                    .and_then(|o| scales.get(o).copied())
                    .unwrap_or(DVec3::ONE)
            })
            .collect(),
        origins
            .iter()
            .map(|o| {
                pick(o)
                    .and_then(|o| offsets.get(o).copied())
                    .unwrap_or(DVec3::ZERO)
            })
            .collect(),
    )
}

/// Where a running bind is.
enum JobState {
    /// Running on a background thread (never on the web target).
    #[cfg_attr(
        target_arch = "wasm32",
        expect(dead_code, reason = "the web target has no threads")
    )]
    Running(Receiver<Result<BoundRig, String>>),
    /// Waiting for its automatic weights from a [`WeightsOffload`].
    Offloaded {
        weights: Receiver<Result<WeightsOutput, String>>,
        request: Box<BindRequest>,
    },
    /// To run on this thread (the web target has no threads; or none could be started) at its
    /// second poll, so that a frame shows the progress first; whether it was polled once.
    Deferred(Box<BindRequest>, bool),
    /// Its result was taken, or it failed to continue.
    Done,
}

/// A bind running in the background: on a thread, or with its automatic weights offloaded.
pub struct BindJob {
    state: JobState,
    progress: Arc<Mutex<Option<BindStep>>>,
    started: Instant,
    /// Whether the automatic weights are computed by a [`WeightsOffload`].
    offloaded: bool,
}

impl BindJob {
    /// Starts `request`: on a new thread; with its automatic weights handed to `offload`
    /// when given (the rest once they are back). On the web target, which has no threads,
    /// what is not offloaded runs on this thread at the second [`Self::poll`] after it is due.
    pub fn spawn(request: BindRequest, offload: Option<&dyn WeightsOffload>) -> Self {
        let progress = Arc::new(Mutex::new(None));
        let started = Instant::now();
        if let Some(offload) = offload
            && let Some(input) = request.weights_input()
        {
            let (sender, weights) = channel();
            offload.start(
                input,
                WeightsReply {
                    sender,
                    progress: Arc::clone(&progress),
                },
            );
            return Self {
                state: JobState::Offloaded {
                    weights,
                    request: Box::new(request),
                },
                progress,
                started,
                offloaded: true,
            };
        }
        Self {
            state: Self::start(request, &progress),
            progress,
            started,
            offloaded: false,
        }
    }

    /// Runs `request` on a new thread; on the web target, or when no thread can be started,
    /// on this thread at the second poll.
    fn start(request: BindRequest, progress: &Arc<Mutex<Option<BindStep>>>) -> JobState {
        #[cfg(target_arch = "wasm32")]
        {
            let _ = progress;
            JobState::Deferred(Box::new(request), false)
        }
        #[cfg(not(target_arch = "wasm32"))]
        {
            let (sender, receiver) = channel();
            let shared = Arc::clone(progress);
            // The thread takes the request; it stays here when no thread can be started.
            let slot = Arc::new(Mutex::new(Some(request)));
            let job = Arc::clone(&slot);
            let spawned = std::thread::Builder::new()
                .name("cagerig-bind".into())
                .spawn(move || {
                    let Some(request) = job.lock().ok().and_then(|mut r| r.take()) else {
                        return;
                    };
                    let result = request.run(&|p| report_to(&shared, p));
                    // The studio may have closed the document meanwhile: nobody to tell.
                    let _ = sender.send(result);
                });
            let left = match spawned {
                Ok(_) => None,
                Err(_) => slot.lock().ok().and_then(|mut r| r.take()),
            };
            match left {
                Some(request) => JobState::Deferred(Box::new(request), false),
                None => JobState::Running(receiver),
            }
        }
    }

    /// The result once the bind is done (`None` while it runs; a deferred bind runs here).
    pub fn poll(&mut self) -> Option<Result<BoundRig, String>> {
        match std::mem::replace(&mut self.state, JobState::Done) {
            JobState::Running(receiver) => match receiver.try_recv() {
                Ok(result) => Some(result.map(|bound| self.total_time(bound))),
                Err(TryRecvError::Empty) => {
                    self.state = JobState::Running(receiver);
                    None
                }
                Err(TryRecvError::Disconnected) => Some(Err(
                    "the bind stopped unexpectedly (its thread ended)".into(),
                )),
            },
            JobState::Offloaded { weights, request } => match weights.try_recv() {
                Ok(Ok(output)) => match request.with_weights(output) {
                    Ok(request) => {
                        self.state = Self::start(request, &self.progress);
                        None
                    }
                    Err(e) => Some(Err(e)),
                },
                Ok(Err(message)) => Some(Err(message)),
                Err(TryRecvError::Empty) => {
                    self.state = JobState::Offloaded { weights, request };
                    None
                }
                Err(TryRecvError::Disconnected) => Some(Err(
                    "the automatic weights stopped unexpectedly (nothing computes them)".into(),
                )),
            },
            JobState::Deferred(request, false) => {
                self.state = JobState::Deferred(request, true);
                None
            }
            JobState::Deferred(request, true) => {
                let progress = &self.progress;
                let result = request.run(&|p| report_to(progress, p));
                Some(result.map(|bound| self.total_time(bound)))
            }
            JobState::Done => None,
        }
    }

    /// `bound` with the time since the bind started (its weights included, wherever they ran).
    /// (A bind that ran whole on its thread keeps its own time.)
    fn total_time(&self, mut bound: BoundRig) -> BoundRig {
        if self.offloaded {
            bound.seconds = self.started.elapsed().as_secs_f64();
        }
        bound
    }

    /// Fraction done (0…1) and a line for the progress bar.
    pub fn progress(&self) -> (f32, String) {
        let seconds = self.started.elapsed().as_secs_f64();
        if matches!(self.state, JobState::Deferred(..)) {
            return (
                0.75,
                format!("binding: the rig's operators… {seconds:.1} s"),
            );
        }
        let p = self.progress.lock().ok().and_then(|p| *p);
        let Some(p) = p else {
            let what = if self.offloaded {
                "computing the weights in the worker"
            } else {
                "binding"
            };
            return (0.0, format!("{what}… {seconds:.1} s"));
        };
        let fraction = |done: usize, total: usize| {
            if total == 0 {
                0.0
            } else {
                done as f32 / total as f32
            }
        };
        let (start, span, what, done, total) = match p {
            BindStep::Weights(w) => match w.stage {
                Stage::Voxelising => (0.0, 0.15, "voxelising the body", w.done, w.total),
                Stage::Distances => (0.15, 0.5, "geodesic distances", w.done, w.total),
                Stage::Weights => (0.65, 0.1, "weights", w.done, w.total),
            },
            BindStep::Rig { stage, done, total } => (0.75, 0.25, stage.label(), done, total),
        };
        let place = match p {
            BindStep::Weights(_) if self.offloaded => " in the worker",
            _ => "",
        };
        (
            start + span * fraction(done, total),
            format!("binding: {what}{place} ({done}/{total}) {seconds:.1} s"),
        )
    }
}

/// Records `step` as the bind's progress.
fn report_to(progress: &Mutex<Option<BindStep>>, step: BindStep) {
    if let Ok(mut slot) = progress.lock() {
        *slot = Some(step);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cagerig::Joint;
    use glam::DAffine3;

    fn chain(names: &[&str]) -> Skeleton {
        Skeleton::new(
            names
                .iter()
                .enumerate()
                .map(|(j, n)| Joint {
                    name: (*n).into(),
                    parent: j.checked_sub(1),
                    rest_world_from_joint: DAffine3::from_translation(DVec3::Y * j as f64),
                })
                .collect(),
        )
        .unwrap()
    }

    #[test]
    fn weights_of_a_deleted_joint_go_to_its_kept_ancestor() {
        // Old chain a-b-c; b deleted, a joint d added: new = [a, c, d].
        let old =
            SkinWeights::from_triplets(3, 3, [(0, 0, 1.0), (1, 1, 1.0), (2, 1, 0.5), (2, 2, 0.5)])
                .unwrap()
                .0;
        let new = chain(&["a", "c", "d"]);
        let w = carry_weights(
            &old,
            &[None, Some(0), Some(1)],
            &[Some(0), Some(2), None],
            &new,
        )
        .unwrap();
        assert_eq!(w.get(1, 0), 1.0, "b's vertex goes to a");
        assert_eq!(w.get(2, 0), 0.5);
        assert_eq!(w.get(2, 1), 0.5);
        assert_eq!(w.get(0, 2), 0.0, "a new joint gets no weight");
    }

    #[test]
    fn the_pose_follows_the_joints_and_new_joints_rest() {
        let q = DQuat::from_rotation_z(0.5);
        let (r, s, o) = carry_pose(
            &[Some(1), None],
            &[DQuat::IDENTITY, q],
            &[DVec3::ONE, DVec3::splat(2.0)],
            &[DVec3::ZERO, DVec3::X],
        );
        assert_eq!(r, vec![q, DQuat::IDENTITY]);
        assert_eq!(s, vec![DVec3::splat(2.0), DVec3::ONE]);
        assert_eq!(o, vec![DVec3::X, DVec3::ZERO]);
    }
}
