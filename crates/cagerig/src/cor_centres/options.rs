//! Options of the CoR-centre precomputation ([`super::exact::compute_cor_centres`]): the
//! similarity kernel's width, the pruning tolerance, and exact or clustered rows.

/// How the rows of S are evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CorCentresMethod {
    /// One evaluation per vertex (O(#V × triangles sharing two joints), parallel).
    Exact,
    /// One evaluation per cluster of vertices with equal quantised weight rows.
    Clustered {
        /// Measured (Arm and its midpoint subdivision): `vertex_step` 0.01, `patch_step` 0.05,
        /// `weight_floor` 0 give max centre error ≈ 7e-4 × bbox diagonal.
        ///
        /// Quantisation step of vertex weight rows: weights are binned by
        /// `round(ln(ω + weight_floor) / vertex_step)`, i.e. relative bins of about this size for
        /// weights above `weight_floor` (a small weight on a third joint steers the centre
        /// between joint-pair regions, so absolute bins are too coarse there) and absolute
        /// bins of about `vertex_step × weight_floor` below it.
        vertex_step: f64,
        /// The same for triangle patches (ω_t).
        patch_step: f64,
        /// See `vertex_step`.
        weight_floor: f64,
    },
}

/// Options of [`compute_cor_centres`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorCentresOptions {
    /// Width σ of the similarity kernel (Le & Hodgins: 0.1).
    pub sigma: f64,
    /// Relative similarity mass that may be dropped per vertex (error ≤ this × bbox diagonal).
    pub mass_tolerance: f64,
    /// How the rows of S are evaluated.
    pub method: CorCentresMethod,
}

impl Default for CorCentresOptions {
    fn default() -> Self {
        Self {
            sigma: 0.1,
            mass_tolerance: 1e-5,
            method: CorCentresMethod::Exact,
        }
    }
}
