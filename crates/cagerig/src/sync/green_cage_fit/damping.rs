//! The Levenberg–Marquardt damping schedule of the Green CageUp: μ scales with the Hessian's
//! mean diagonal, rises by a factor on a rejected step and falls to 0 (pure Newton) as the
//! iterate converges.

use faer::Mat;

/// The mean |diagonal| of the Hessian: the scale of the damping.
pub(super) fn damping_scale(hessian: &Mat<f64>) -> f64 {
    let n = hessian.nrows().max(1);
    let mean = (0..hessian.nrows())
        .map(|i| hessian[(i, i)].abs())
        .sum::<f64>()
        / n as f64;
    mean.max(f64::MIN_POSITIVE)
}

/// μ × `factor` (from 1e-9 of the Hessian's scale when μ = 0); infinite past 1e9 of the scale.
pub(super) fn raise_damping(damping: f64, hessian: &Mat<f64>, factor: f64) -> f64 {
    let scale = damping_scale(hessian);
    let raised = if damping == 0.0 {
        1e-9 * scale
    } else {
        damping * factor
    };
    if raised > 1e9 * scale {
        f64::INFINITY
    } else {
        raised
    }
}

/// μ / 4, and 0 (Newton) below 1e-12 of the Hessian's scale.
pub(super) fn lower_damping(damping: f64, hessian: &Mat<f64>) -> f64 {
    let lowered = damping / 4.0;
    if lowered < 1e-12 * damping_scale(hessian) {
        0.0
    } else {
        lowered
    }
}
