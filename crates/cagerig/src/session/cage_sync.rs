//! CageUp and CageRev of the session, through its rest map ([`super::rest_map`]): each kind's
//! own fit and reverser, and M(C) of a cage that is not the session's.

use super::RigSession;
use super::parts::CageFitSource;
use super::rest_map::{CageMap, MvcMap};
use super::skinning::CorState;
use crate::coords_kind::CoordsKind;
use crate::error::RigError;
use glam::DVec3;

impl RigSession {
    /// The coordinates kind the rig is bound with.
    pub fn coords_kind(&self) -> CoordsKind {
        self.rest_map.kind()
    }

    /// CageUp: C' from the fitting rows of M' (or their ghost LBS, Sec. 4.3 for DQS/CoR): the
    /// linear map P for MVC rigs, the Gauss–Newton fit for Green rigs.
    pub(super) fn fit_cage(&mut self) {
        let ghost = !self.skinning.method().is_linear()
            && self.options_fit_source == CageFitSource::GhostLbs;
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => self.fit_linear_cage(ghost),
            CageMap::Green(_) => self.fit_green_cage_rows(ghost),
        }
    }

    /// CageRev: the rest-cage change `rest_delta` (`#C`) for the current-cage change
    /// `posed_delta` (`#C`): Eq. 19 (factorised for the pose first if needed) for MVC rigs, the
    /// Newton solve for Green rigs.
    pub(super) fn reverse_cage(
        &mut self,
        posed_delta: &[DVec3],
        rest_delta: &mut [DVec3],
    ) -> Result<(), RigError> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(mvc) => {
                if !mvc.reverser.is_factorised() {
                    self.refactor_reverser()?;
                }
                self.rest_map.solve_linear_reverse(posed_delta, rest_delta)
            }
            CageMap::Green(_) => self.reverse_green(posed_delta, rest_delta),
        }
    }

    /// After a grab's CageRev moved C: a non-linear map's CageUp starts from the grabbed C'
    /// (C' + `posed_delta`, `#C`), which CageRev made the answer. A linear map re-fits C' in
    /// one product and needs nothing.
    pub(super) fn start_fit_from_grab(&mut self, posed_delta: &[DVec3]) {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => {}
            CageMap::Green(_) => {
                for (p, d) in self.posed_cage.iter_mut().zip(posed_delta) {
                    *p += *d;
                }
                self.rest_map.start_next_fit_from_posed_cage();
            }
        }
    }

    /// Factorises the reverse cage deformer (Eq. 19) for the current pose now (again, if it
    /// already was). A caller can run it before a grab, so that the grab's first event does not
    /// pay for it; [`RigSession::move_posed_cage`] does it lazily otherwise, once per pose.
    pub fn refactor_reverser(&mut self) -> Result<(), RigError> {
        for (r, t) in self.scratch_rotations.iter_mut().zip(&self.posed_from_rest) {
            *r = t.matrix3;
        }
        let skel_up = !self.locks.skel_up;
        match self.rest_map.cage_map_mut() {
            CageMap::Mvc(mvc) => {
                let MvcMap { fit, reverser } = &mut **mvc;
                let rotations = &self.scratch_rotations;
                reverser.refactor(rotations, skel_up, fit.reach_factors_in_pose(rotations))
            }
            CageMap::Green(_) => self.prepare_green_reverser(),
        }
    }

    /// M = ΦC (+ the kind's terms) for the rest cage `cage` (`#C`) into `out` (`#V`).
    pub(super) fn rest_mesh_of_cage(&self, cage: &[DVec3], out: &mut [DVec3]) {
        self.rest_map.rest_mesh_of(cage, out);
    }

    /// The rest skin M(C) of the rest cage `cage` (`#C`) into `out` (`#V`): ΦC, plus ψ·g(C) for
    /// Green coordinates. The session is not changed.
    pub fn rest_mesh_for_cage(&self, cage: &[DVec3], out: &mut [DVec3]) -> Result<(), RigError> {
        if cage.len() != self.rest_cage.len() || out.len() != self.rest_mesh.len() {
            return Err(RigError::SizeMismatch {
                what: "rest cage (#C) and rest skin (#V) for M(C)",
                expected: self.rest_cage.len(),
                actual: cage.len(),
            });
        }
        self.rest_mesh_of_cage(cage, out);
        Ok(())
    }

    /// The rest cage C (`out`, `#C`; on entry the start of a non-linear fit) whose rest skin
    /// fits `rows`, the skin at CageUp's fitting rows ([`CageUpdater::rows`], `#R`): for mean
    /// value coordinates C = P·rows (exact on MaxVol rows); for Green coordinates the
    /// Gauss–Newton fit of φ_R C + ψ_R g(C) to `rows` (CageUp's solver, to a stationary point
    /// to round-off), which recovers C exactly when the rows are a Green deformation of the
    /// binding. Errors when the Green fit does not converge. The session is not changed.
    pub fn rest_cage_from_rows(&self, rows: &[DVec3], out: &mut [DVec3]) -> Result<(), RigError> {
        if rows.len() != self.rest_map.rows().len() || out.len() != self.rest_cage.len() {
            return Err(RigError::SizeMismatch {
                what: "fitting rows (#R) for a rest cage",
                expected: self.rest_map.rows().len(),
                actual: rows.len(),
            });
        }
        match self.rest_map.cage_map() {
            CageMap::Mvc(mvc) => {
                mvc.fit.apply_rows(rows, out);
                Ok(())
            }
            CageMap::Green(green) => {
                let mut fit = green.cage_up.fit.clone();
                // The rows alone: no regulariser towards a carried cage.
                fit.set_regularised(false);
                // Start from the better of the given cage and the linear map's cage P·rows (the
                // vertex part's fit, which ignores ψ·g but follows large deformations).
                let mut linear = vec![DVec3::ZERO; out.len()];
                green.linear.apply_rows(rows, &mut linear);
                if fit.energy(rows, &linear) < fit.energy(rows, out) {
                    out.copy_from_slice(&linear);
                }
                // A stalled solve continues from the start to `rows` in pieces.
                fit.restart_from(out);
                let report = fit.apply(rows, out)?;
                if report.residual <= green.fit_limit() {
                    Ok(())
                } else {
                    Err(RigError::Invalid(format!(
                        "no rest cage reproduces the given skin rows through Green coordinates: \
                         the fit stopped with a gradient of {:.3e}, expected at most {:.3e}",
                        report.residual,
                        green.fit_limit()
                    )))
                }
            }
        }
    }

    /// The CoR centres Λ·C (+ the kind's terms) into `out` (`#V`) for the rest cage `cage`.
    pub(super) fn centres_of_cage(&self, cor: &CorState, cage: &[DVec3], out: &mut [DVec3]) {
        cor.centre_coords.apply(cage, out);
        self.rest_map.add_centre_terms_of(cage, out);
    }
}

#[cfg(test)]
mod tests {
    use super::super::rest_map::{CageMap, MvcMap};
    use super::super::{RigSession, SessionOptions};
    use crate::rig_files::load_rig_files;
    use glam::{DMat3, DVec3};
    use std::path::Path;

    /// CageRev's rows take the reach factors CageUp applied in the pose: the Arm with its
    /// first metacarpal turned 90°, where the limit holds six cage vertices (s_k < 1),
    /// factorises to the same bits with them as when it computes its own, and a stale pose
    /// gives none.
    #[test]
    fn cage_rev_takes_cage_ups_reach_factors_to_the_bit() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm");
        let files = load_rig_files(&dir.join("arm.obj"), None).unwrap();
        let mut s = RigSession::new(files.parts, SessionOptions::default())
            .unwrap()
            .0;
        let metacarpal = s.skeleton().find("metacarpal1.R").unwrap();
        s.rotate_joint(metacarpal, DVec3::X, 90f64.to_radians())
            .unwrap();
        let rotations: Vec<DMat3> = s.posed_from_rest.iter().map(|t| t.matrix3).collect();
        let skel_up = !s.locks.skel_up;
        let CageMap::Mvc(mvc) = s.rest_map.cage_map_mut() else {
            panic!("a mean value rig");
        };
        let MvcMap { fit, reverser } = &mut **mvc;
        let shared = fit.reach_factors_in_pose(&rotations).unwrap().to_vec();
        assert!(shared.iter().any(|&f| f < 1.0), "{shared:?}");
        let offset = vec![DVec3::new(0.01, -0.02, 0.03); shared.len()];
        let solve = |reverser: &mut crate::sync::cage_reverser::CageReverser,
                     factors: Option<&[f64]>| {
            reverser.refactor(&rotations, skel_up, factors).unwrap();
            let mut delta = vec![DVec3::ZERO; offset.len()];
            reverser.solve(&offset, &mut delta).unwrap();
            delta
        };
        assert_eq!(solve(reverser, Some(&shared)), solve(reverser, None));
        let mut other = rotations.clone();
        other[metacarpal] = DMat3::IDENTITY;
        assert!(fit.reach_factors_in_pose(&other).is_none());
    }

    /// The Green twin: what CageRev takes of the fit's last carry in its pose is what it would
    /// compute. The Arm's elbow bent 135° under Green coordinates, where the hat turns
    /// triangles, gives the same β, anchors and W (fold terms included) both ways.
    #[test]
    fn green_cage_rev_takes_the_fits_reach_weights_to_the_bit() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/arm");
        let files = load_rig_files(&dir.join("arm.obj"), None).unwrap();
        let options = SessionOptions {
            coords: crate::CoordsKind::Green,
            ..SessionOptions::default()
        };
        let mut s = RigSession::new(files.parts, options).unwrap().0;
        let elbow = s.skeleton().find("lowerarm01.R").unwrap();
        for _ in 0..9 {
            s.rotate_joint(elbow, DVec3::X, 15f64.to_radians()).unwrap();
        }
        assert!(s.green_fold_turns().unwrap().iter().any(|&t| t > 0.0));
        let linear: Vec<DMat3> = s.posed_from_rest.iter().map(|t| t.matrix3).collect();
        let CageMap::Green(green) = s.rest_map.cage_map() else {
            panic!("a Green rig");
        };
        let prior = green.cage_up.fit.prior().unwrap();
        assert!(prior.carried().reach_factors_in_pose(&linear).is_some());
        let nc = prior.reach_weights().len();
        let run = |shared: bool| {
            let (mut weights, mut anchored) = (vec![0.0; nc], vec![false; nc]);
            let mut weight = faer::Mat::zeros(nc, nc);
            if shared {
                prior.reach_weights_in(&linear, &mut weights, &mut anchored, &mut weight);
            } else {
                prior.compute_reach_weights_in(&linear, &mut weights, &mut anchored, &mut weight);
            }
            (weights, anchored, weight)
        };
        assert_eq!(run(true), run(false));
    }
}
