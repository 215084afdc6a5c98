//! Green CageUp's state in a session: the Gauss–Newton fit of C' to the skinned rows M'_R, its
//! warm start (the previous C' moved with the bones, or the rest cage skinned outright) and the
//! report of a fit that found no current cage. Kept apart from the face terms ψ·g(C) that the
//! rest skin's pass reads, so that the fit and the pass over the skin can run side by side.

use super::unfitted_cage::UnfittedCagePolicy;
use crate::error::UnfittedCage;
use crate::sync::green_cage_fit::{FitBudget, GreenCageFit};
use glam::{DAffine3, DVec3};

/// Green CageUp's state (see the module docs).
#[derive(Debug, Clone)]
pub(super) struct GreenCageUp {
    pub(super) fit: GreenCageFit,
    /// The skinned fitting rows M'_R CageUp fits (`#R`), written before [`Self::fit_cage`].
    pub(super) target_rows: Vec<DVec3>,
    /// Skinning weights of the cage vertices, P·Ω̃ (`#C × #J`, row-major): the predictor of
    /// CageUp's warm start.
    pub(super) cage_weights: Vec<f64>,
    /// The skinning transforms (`#J`) and the rest cage (`#C`) of the last CageUp, for the
    /// predictor.
    pub(super) last_transforms: Vec<DAffine3>,
    pub(super) last_rest_cage: Vec<DVec3>,
    pub(super) has_last_transforms: bool,
    /// Scratch: the rest cage skinned with the cage weights, `#C`.
    pub(super) skinned_cage: Vec<DVec3>,
    /// Set by a grab: the next CageUp starts from the grabbed C' (CageRev made it the answer).
    pub(super) start_from_posed_cage: bool,
    /// Whether the failure in `unfitted` is yet to be reported to `finish_event` (a fit
    /// outside an event, e.g. a rollback's, is not that event's).
    pub(super) failure_unreported: bool,
    /// Where the last CageUp stopped when it found no current cage (`None`: C' is its fit).
    pub(super) unfitted: Option<UnfittedCage>,
}

/// What one Green CageUp reads besides its own state.
pub(super) struct CageUpInputs<'a> {
    /// The skinning transforms S'·S⁻¹ (`#J`).
    pub(super) posed_from_rest: &'a [DAffine3],
    /// C (`#C`).
    pub(super) rest_cage: &'a [DVec3],
    /// The binding's rest cage (`#C`): a folded triangle is reported against it.
    pub(super) original_rest_cage: &'a [DVec3],
    pub(super) unfitted_policy: UnfittedCagePolicy,
    /// The largest gradient the fit may end with, in scene units.
    pub(super) limit: f64,
}

impl GreenCageUp {
    /// A fresh state for `fit` with `num_rows` fitting rows, the cage vertices' weights
    /// (`#C × #J`, row-major), `num_joints` joints and the rest cage (`#C`).
    pub(super) fn new(
        fit: GreenCageFit,
        num_rows: usize,
        cage_weights: Vec<f64>,
        num_joints: usize,
        rest_cage: &[DVec3],
    ) -> Self {
        Self {
            fit,
            target_rows: vec![DVec3::ZERO; num_rows],
            cage_weights,
            last_transforms: vec![DAffine3::IDENTITY; num_joints],
            last_rest_cage: rest_cage.to_vec(),
            has_last_transforms: false,
            skinned_cage: rest_cage.to_vec(),
            start_from_posed_cage: false,
            failure_unreported: false,
            unfitted: None,
        }
    }

    /// CageUp under Green coordinates: C' (`posed_cage`, `#C`) fitted to the rows
    /// [`Self::target_rows`] by Gauss–Newton, warm-started from the current C'. Records a
    /// failure to converge for `finish_event`. No allocation.
    pub(super) fn fit_cage(&mut self, inputs: CageUpInputs<'_>, posed_cage: &mut [DVec3]) {
        let CageUpInputs {
            posed_from_rest,
            rest_cage,
            original_rest_cage,
            unfitted_policy,
            limit,
        } = inputs;
        self.fit.carry_prior(posed_from_rest, rest_cage);
        let predict = !self.start_from_posed_cage;
        self.start_from_posed_cage = false;
        if predict {
            // Two warm starts, the one the fit likes better: the previous C' moved by the change
            // of the skinning transforms and the skinned change of the rest cage, and the rest
            // cage skinned outright — both blended with the cage vertices' weights P·Ω̃ (the
            // normals turn with the bones; at the rest pose the second is C, the exact answer).
            let nj = self.last_transforms.len();
            let continuing = self.has_last_transforms && posed_cage.iter().all(|p| p.is_finite());
            for (k, (p, s)) in posed_cage
                .iter_mut()
                .zip(self.skinned_cage.iter_mut())
                .enumerate()
            {
                let weights = &self.cage_weights[k * nj..(k + 1) * nj];
                let rest_change = rest_cage[k] - self.last_rest_cage[k];
                let (mut moved, mut skinned) = (DVec3::ZERO, DVec3::ZERO);
                for (j, &w) in weights.iter().enumerate() {
                    if w != 0.0 {
                        let transform = &posed_from_rest[j];
                        skinned += w * transform.transform_point3(rest_cage[k]);
                        if continuing {
                            let back = self.last_transforms[j].inverse().transform_point3(*p);
                            moved += w
                                * (transform.transform_point3(back)
                                    + transform.transform_vector3(rest_change));
                        }
                    }
                }
                *s = skinned;
                if continuing {
                    *p = moved;
                }
            }
            let skinned_energy = self.fit.energy(&self.target_rows, &self.skinned_cage);
            if !continuing || skinned_energy < self.fit.energy(&self.target_rows, posed_cage) {
                posed_cage.copy_from_slice(&self.skinned_cage);
            }
        }
        self.last_transforms.copy_from_slice(posed_from_rest);
        self.last_rest_cage.copy_from_slice(rest_cage);
        self.has_last_transforms = true;
        // A run of kept events past the fold tries a few steps each (`FitBudget`).
        let budget = match (unfitted_policy, self.unfitted) {
            (UnfittedCagePolicy::KeepEvent, Some(_)) => FitBudget::UNFITTED_STREAK,
            (UnfittedCagePolicy::KeepEvent | UnfittedCagePolicy::Refuse, _) => FitBudget::FULL,
        };
        let result = self.fit.apply_within(&self.target_rows, posed_cage, budget);
        let residual = match result {
            Ok(report) if report.residual <= limit => {
                self.failure_unreported = false;
                self.unfitted = None;
                return;
            }
            Ok(report) => report.residual,
            Err(_) => f64::INFINITY,
        };
        let (face, area_ratio) = self
            .fit
            .normals()
            .triangles()
            .iter()
            .enumerate()
            .map(|(f, t)| {
                // Signed: negative when the triangle turned over against its binding normal.
                let [a, b, c] = t.map(|v| posed_cage[v as usize]);
                let [a0, b0, c0] = t.map(|v| original_rest_cage[v as usize]);
                let rest = (b0 - a0).cross(c0 - a0);
                let now = (b - a).cross(c - a);
                let signed = now.length() * now.dot(rest).signum();
                (f, signed / rest.length().max(f64::MIN_POSITIVE))
            })
            .fold(
                (0, f64::INFINITY),
                |best, x| if x.1 < best.1 { x } else { best },
            );
        self.unfitted = Some(UnfittedCage {
            residual,
            limit,
            face,
            area_ratio,
        });
        self.failure_unreported = true;
    }
}
