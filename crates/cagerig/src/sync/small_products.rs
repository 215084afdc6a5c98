//! The small dense products of the cage fits: a `#C × n` map (column-major, faer) times `n`
//! points, accumulated into `#C` points, column by column. No allocation.

use faer::Mat;
use glam::DVec3;

/// `out += map · points` (`map` is `out.len() × points.len()`), column by column.
pub(crate) fn accumulate_product(map: &Mat<f64>, points: &[DVec3], out: &mut [DVec3]) {
    for (r, p) in points.iter().enumerate() {
        accumulate_column(map, r, *p, out);
    }
}

/// `out += map[:, r] · p`.
#[inline]
pub(crate) fn accumulate_column(map: &Mat<f64>, r: usize, p: DVec3, out: &mut [DVec3]) {
    let col = map.col(r);
    for (k, o) in out.iter_mut().enumerate() {
        *o += col[k] * p;
    }
}
