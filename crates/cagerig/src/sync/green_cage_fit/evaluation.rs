//! The buffers that one evaluation of [`super::GreenCageFit`]'s objective writes: scratch for
//! the face terms, and the residual and gradient at a point (allocated once per fit).

use glam::DVec3;

/// Scratch of [`super::GreenCageFit::evaluate`]: the face terms g(x) and ψ_Rᵀr (`#F` each),
/// and the prior's pulls W(x − P) (`#C`).
#[derive(Debug, Clone, Default)]
pub(super) struct FaceScratch {
    pub(super) g: Vec<DVec3>,
    pub(super) face_sums: Vec<DVec3>,
    pub(super) pulls: Vec<DVec3>,
}

impl FaceScratch {
    pub(super) fn new(num_cage: usize, num_faces: usize) -> Self {
        Self {
            g: vec![DVec3::ZERO; num_faces],
            face_sums: vec![DVec3::ZERO; num_faces],
            pulls: vec![DVec3::ZERO; num_cage],
        }
    }
}

/// What [`super::GreenCageFit::evaluate`] writes at a point: the residual rows r (`#R`) and the
/// gradient Jᵀr (+ W(x − P) with a prior; `#C`).
#[derive(Debug, Clone, Default)]
pub(super) struct Evaluation {
    pub(super) residual: Vec<DVec3>,
    pub(super) gradient: Vec<DVec3>,
}

impl Evaluation {
    pub(super) fn new(num_rows: usize, num_cage: usize) -> Self {
        Self {
            residual: vec![DVec3::ZERO; num_rows],
            gradient: vec![DVec3::ZERO; num_cage],
        }
    }
}
