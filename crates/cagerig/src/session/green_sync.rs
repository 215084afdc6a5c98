//! The session's Green CageUp and CageRev: the warm-started Gauss–Newton fit, the Newton
//! CageRev's system for the pose, and the Green accessors (the state is [`super::green`]'s).

use super::RigSession;
use super::green::GREEN_FIT_LIMIT;
use super::rest_map::CageMap;
use super::unfitted_cage::UnfittedCagePolicy;
use crate::cage_coords::CageCoords;
use crate::error::{RigError, UnfittedCage};
use crate::sync::green_cage_fit::FitBudget;
use crate::sync::green_cage_fit::reverser::GrabState;
use crate::sync::newton::NewtonReport;
use faer::Mat;
use glam::{DMat3, DVec3};

impl RigSession {
    /// CageUp under Green coordinates: C' fitted to the rows M'_R (in `green.target_rows`) by
    /// Gauss–Newton, warm-started from the current C'. Records a failure to converge for
    /// `finish_event`.
    pub(super) fn fit_green_cage(&mut self) {
        let CageMap::Green(green) = self.rest_map.cage_map_mut() else {
            return;
        };
        let limit = GREEN_FIT_LIMIT * green.size;
        green
            .fit
            .carry_prior(&self.posed_from_rest, &self.rest_cage);
        let predict = !green.start_from_posed_cage;
        green.start_from_posed_cage = false;
        if predict {
            // Two warm starts, the one the fit likes better: the previous C' moved by the change
            // of the skinning transforms and the skinned change of the rest cage, and the rest
            // cage skinned outright — both blended with the cage vertices' weights P·Ω̃ (the
            // normals turn with the bones; at the rest pose the second is C, the exact answer).
            let nj = green.last_transforms.len();
            let continuing =
                green.has_last_transforms && self.posed_cage.iter().all(|p| p.is_finite());
            for (k, (p, s)) in self
                .posed_cage
                .iter_mut()
                .zip(green.skinned_cage.iter_mut())
                .enumerate()
            {
                let weights = &green.cage_weights[k * nj..(k + 1) * nj];
                let rest_change = self.rest_cage[k] - green.last_rest_cage[k];
                let (mut moved, mut skinned) = (DVec3::ZERO, DVec3::ZERO);
                for (j, &w) in weights.iter().enumerate() {
                    if w != 0.0 {
                        let transform = &self.posed_from_rest[j];
                        skinned += w * transform.transform_point3(self.rest_cage[k]);
                        if continuing {
                            let back = green.last_transforms[j].inverse().transform_point3(*p);
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
            let skinned_energy = green.fit.energy(&green.target_rows, &green.skinned_cage);
            if !continuing
                || skinned_energy < green.fit.energy(&green.target_rows, &self.posed_cage)
            {
                self.posed_cage.copy_from_slice(&green.skinned_cage);
            }
        }
        green.last_transforms.copy_from_slice(&self.posed_from_rest);
        green.last_rest_cage.copy_from_slice(&self.rest_cage);
        green.has_last_transforms = true;
        // A run of kept events past the fold tries a few steps each (`FitBudget`).
        let budget = match (self.options.unfitted_cage, green.unfitted) {
            (UnfittedCagePolicy::KeepEvent, Some(_)) => FitBudget::UNFITTED_STREAK,
            (UnfittedCagePolicy::KeepEvent | UnfittedCagePolicy::Refuse, _) => FitBudget::FULL,
        };
        let result = green
            .fit
            .apply_within(&green.target_rows, &mut self.posed_cage, budget);
        let residual = match result {
            Ok(report) if report.residual <= limit => {
                green.failure_unreported = false;
                green.unfitted = None;
                return;
            }
            Ok(report) => report.residual,
            Err(_) => f64::INFINITY,
        };
        let (face, area_ratio) = green
            .fit
            .normals()
            .triangles()
            .iter()
            .enumerate()
            .map(|(f, t)| {
                // Signed: negative when the triangle turned over against its binding normal.
                let [a, b, c] = t.map(|v| self.posed_cage[v as usize]);
                let [a0, b0, c0] = t.map(|v| self.original_rest_cage[v as usize]);
                let rest = (b0 - a0).cross(c0 - a0);
                let now = (b - a).cross(c - a);
                let signed = now.length() * now.dot(rest).signum();
                (f, signed / rest.length().max(f64::MIN_POSITIVE))
            })
            .fold(
                (0, f64::INFINITY),
                |best, x| if x.1 < best.1 { x } else { best },
            );
        green.unfitted = Some(UnfittedCage {
            residual,
            limit,
            face,
            area_ratio,
        });
        green.failure_unreported = true;
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
                .prepare_prior(&green.fit, &joint_linear, &translation_jacobian);
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
            posed_rows: &green.target_rows,
            posed_cage: &self.posed_cage,
        };
        let report = green
            .reverser
            .solve(&green.fit, at, posed_delta, rest_delta)?;
        green.last_reverse = report;
        if report.residual > GREEN_FIT_LIMIT * green.size {
            return Err(RigError::GreenGrabFailed {
                residual: report.residual,
                limit: GREEN_FIT_LIMIT * green.size,
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
            CageMap::Green(green) => Some(green.fit.normals().triangles()),
        }
    }

    /// Green rigs: the Newton reports of the last CageUp and the last CageRev.
    pub fn green_newton_reports(&self) -> Option<(NewtonReport, NewtonReport)> {
        match self.rest_map.cage_map() {
            CageMap::Mvc(_) => None,
            CageMap::Green(green) => Some((green.fit.last_report(), green.last_reverse)),
        }
    }
}
