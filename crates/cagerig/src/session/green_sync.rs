//! The session's Green CageUp and CageRev: the warm-started Gauss–Newton fit, the Newton
//! CageRev's system for the pose, and the Green accessors (the state is [`super::green`]'s).

use super::RigSession;
use super::green_cage_up::CageUpInputs;
use super::rest_map::CageMap;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::sync::green_cage_fit::reverser::GrabState;
use crate::sync::newton::NewtonReport;
use faer::Mat;
use glam::{DMat3, DVec3};

impl RigSession {
    /// CageUp under Green coordinates: C' fitted to the rows M'_R (in the CageUp's
    /// `target_rows`) by Gauss–Newton ([`GreenCageUp::fit_cage`]).
    pub(super) fn fit_green_cage(&mut self) {
        let CageMap::Green(green) = self.rest_map.cage_map_mut() else {
            return;
        };
        let inputs = CageUpInputs {
            posed_from_rest: &self.posed_from_rest,
            rest_cage: &self.rest_cage,
            original_rest_cage: &self.original_rest_cage,
            unfitted_policy: self.options.unfitted_cage,
            limit: green.fit_limit(),
        };
        green.cage_up.fit_cage(inputs, &mut self.posed_cage);
    }

    /// Builds R̃ and K_A = Ω̃ ∂T/∂A of the Green CageRev for the current pose and SkelUp lock,
    /// unless they are already built for them. K_A in closed form: the translations are affine
    /// in the rest joints for fixed rotations (0.27 ms by differences, 3#J forward kinematics,
    /// at 133k on the Arm). Zero while SkelUp is locked (a grab then moves no joint).
    pub(super) fn prepare_green_reverser(&mut self) -> Result<(), RigError> {
        let CageMap::Green(green) = self.rest_map.cage_map() else {
            return Ok(());
        };
        let pose = || self.posed_from_rest.iter().map(|t| t.matrix3);
        let locked = self.locks.skel_up;
        if green.reverser.is_ready_for(pose(), locked) {
            return Ok(());
        }
        // Owned: `green` is updated below while the closure reads them.
        let rows = green.linear.rows().to_vec();
        let rows = &rows[..];
        let nj = self.skeleton.len();
        let row_linear: Vec<DMat3> = rows
            .iter()
            .map(|&row| {
                let (joints, weights) = self.skin_weights.row(row);
                joints
                    .iter()
                    .zip(weights)
                    .fold(DMat3::ZERO, |acc, (&j, &w)| {
                        acc + self.posed_from_rest[j as usize].matrix3 * w
                    })
            })
            .collect();
        // ∂t_j/∂A_k in closed form (`Skeleton::skinning_translation_jacobian`), then
        // K_A = Ω̃ ∂t/∂A row by row.
        let mut translation_jacobian = vec![DMat3::ZERO; nj * nj];
        self.skeleton
            .skinning_translation_jacobian(&self.posed_from_rest, &mut translation_jacobian);
        let skin_weights = &self.skin_weights;
        let fill_skeleton_rows = |out: &mut Mat<f64>| {
            for (i, &row) in rows.iter().enumerate() {
                let (joints, weights) = skin_weights.row(row);
                for k in 0..nj {
                    let block = joints
                        .iter()
                        .zip(weights)
                        .fold(DMat3::ZERO, |acc, (&j, &w)| {
                            acc + translation_jacobian[j as usize * nj + k] * w
                        });
                    for c in 0..3 {
                        let column = block.col(c);
                        for a in 0..3 {
                            out[(3 * i + a, 3 * k + c)] = column[a];
                        }
                    }
                }
            }
        };
        let pose_linear = self.posed_from_rest.iter().map(|t| t.matrix3);
        if let CageMap::Green(green) = self.rest_map.cage_map_mut() {
            green.reverser.prepare(
                row_linear.into_iter(),
                pose_linear,
                locked,
                fill_skeleton_rows,
            );
            let joint_linear: Vec<DMat3> = self.posed_from_rest.iter().map(|t| t.matrix3).collect();
            green
                .reverser
                .prepare_prior(&green.cage_up.fit, &joint_linear, &translation_jacobian);
        }
        Ok(())
    }

    /// CageRev under Green coordinates: the rest-cage change `rest_delta` (`#C`) for the
    /// current-cage change `posed_delta` (`#C`).
    pub(super) fn reverse_green(
        &mut self,
        posed_delta: &[DVec3],
        rest_delta: &mut [DVec3],
    ) -> Result<(), RigError> {
        self.prepare_green_reverser()?;
        let CageMap::Green(green) = self.rest_map.cage_map_mut() else {
            return Err(RigError::Invalid(
                "the Green CageRev was asked of a rig bound with another coordinates kind".into(),
            ));
        };
        for (r, &row) in self.scratch_rows_rest.iter_mut().zip(green.linear.rows()) {
            *r = self.rest_mesh[row];
        }
        let at = GrabState {
            rest_cage: &self.rest_cage,
            rest_rows: &self.scratch_rows_rest,
            posed_rows: &green.cage_up.target_rows,
            posed_cage: &self.posed_cage,
        };
        let report = green
            .reverser
            .solve(&green.cage_up.fit, at, posed_delta, rest_delta)?;
        green.last_reverse = report;
        if report.residual > green.fit_limit() {
            return Err(RigError::GreenGrabFailed {
                residual: report.residual,
                limit: green.fit_limit(),
                iterations: report.iterations,
            });
        }
        Ok(())
    }

    /// Green rigs: ψ (`#V × #F`, one column per cage triangle of
    /// [`RigSession::green_triangles`]); `None` for MVC rigs.
    pub fn green_face_coords(&self) -> Option<&CageCoords> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => Some(&green.face_coords),
        }
    }

    /// Green rigs: the outward-oriented cage triangles the face coordinates refer to.
    pub fn green_triangles(&self) -> Option<&[[u32; 3]]> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => Some(green.cage_up.fit.normals().triangles()),
        }
    }

    /// Green rigs with a regularised CageUp: the reach weights β_k (`#C`, 0 where the fit stays
    /// within reach of the body) and which cage vertices are anchored on the cage vertex
    /// skinned with its nearest skin vertex's weights (`#C`), in the current pose
    /// ([`crate::sync::green_cage_fit::prior`]); `None` for MVC rigs and the paper's fit.
    pub fn green_reach(&self) -> Option<(&[f64], &[bool])> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => green
                .cage_up
                .fit
                .prior()
                .map(|p| (p.reach_weights(), p.anchored())),
        }
    }

    /// Green rigs with a regularised CageUp: how far the prior's hat fit turns each cage
    /// triangle in the current pose, in [0, 1] (`#F`; the weights of the fit's fold terms,
    /// [`crate::sync::green_cage_fit::prior`]); `None` for MVC rigs and the paper's fit.
    pub fn green_fold_turns(&self) -> Option<&[f64]> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => green.cage_up.fit.prior().map(|p| p.turns()),
        }
    }

    /// Green rigs: the Newton reports of the last CageUp and the last CageRev.
    pub fn green_newton_reports(&self) -> Option<(NewtonReport, NewtonReport)> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => Some((green.cage_up.fit.last_report(), green.last_reverse)),
        }
    }
}
