//! Who computes the display path's rest skin M̃ = Φ̃·[C; g] — the per-event product a GPU can
//! take over — as a type a front end passes in [`super::SessionOptions::display_rest_map`].
//!
//! On the f32 display path ([`super::DisplayPrecision::F32`]) a current-cage edit changes C
//! everywhere, and the drawn rest skin is the product of the whole `#V × #K` coordinate matrix
//! with the cage (`#K` = `#C` for mean value rigs; `#C + #F` for Green rigs, whose face terms g
//! are extra columns). That product is the largest per-event read (79 MB at 133k vertices × 74
//! cage vertices in f64), and the one a GPU backend holds in its own memory. The sync
//! operators never read it: CageUp, CageRev and SkelUp take the exact f64 rows, so a backend can
//! change what is drawn, never the rig's state.
//!
//! [`DisplayRestMap::Cpu`] is [`DisplayCageCoords`] (Φ rounded to f32 on the CPU). A backend
//! from another crate implements [`DisplayRestMapBackend`] (upload once per binding) and
//! [`DisplayRestMapProduct`] (apply per event into the caller's buffer), and is passed as
//! [`DisplayRestMap::External`]; `crates/cagerig/tests/display_rest_map.rs` is a complete one,
//! and `cagerig-render`'s `GpuRestMap` a wgpu one.

use std::fmt;
use std::sync::Arc;

use glam::{DVec3, Vec3};

use crate::cage_coords::{CageCoords, DisplayCageCoords};

/// The product M̃ = K̃·[`head`; `tail`] of a bound backend: `#V × #K` coordinates held by the
/// backend, `head` the rest cage C (`#C`) and `tail` the kind's extra terms (Green's g, `#F`;
/// empty for mean value rigs).
pub trait DisplayRestMapProduct: Send + Sync + fmt::Debug {
    /// M̃ into `out` (`#V`, f32), without allocating. The drawn mesh is within the display
    /// path's stated error of the exact M (2e-6 of the bounding-box diagonal) when the backend
    /// sums in f32 or better over coordinates rounded at most to f32.
    fn apply(&self, head: &[DVec3], tail: &[DVec3], out: &mut [Vec3]);
}

/// A backend of the display path's rest skin: it takes the coordinates once per binding.
pub trait DisplayRestMapBackend: Send + Sync {
    /// A short name for reports ("cpu", "wgpu").
    fn name(&self) -> &str;

    /// The product of the columns of `parts` side by side (the vertex part Φ or φ, then the
    /// kind's extra columns ψ; each `#V` rows), or `None` when the backend cannot hold them —
    /// the session then computes the exact M in full, as without a display path.
    fn upload(&self, parts: &[&CageCoords]) -> Option<Arc<dyn DisplayRestMapProduct>>;
}

/// Which backend computes the drawn rest skin M̃ on the f32 display path.
#[derive(Clone, Default)]
pub enum DisplayRestMap {
    /// Φ rounded to f32 and summed in f64 on the CPU ([`DisplayCageCoords`]).
    #[default]
    Cpu,
    /// A backend from outside the library, e.g. one on the GPU.
    External(Arc<dyn DisplayRestMapBackend>),
}

impl fmt::Debug for DisplayRestMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Cpu => f.write_str("Cpu"),
            Self::External(backend) => f.debug_tuple("External").field(&backend.name()).finish(),
        }
    }
}

impl DisplayRestMap {
    /// The backend's name: "cpu" or the external backend's own.
    pub fn name(&self) -> &str {
        match self {
            Self::Cpu => "cpu",
            Self::External(backend) => backend.name(),
        }
    }

    /// The bound product of `parts` (see [`DisplayRestMapBackend::upload`]).
    pub fn upload(&self, parts: &[&CageCoords]) -> Option<Arc<dyn DisplayRestMapProduct>> {
        match self {
            Self::Cpu => DisplayCageCoords::try_new_concatenated(parts)
                .map(|coords| Arc::new(coords) as Arc<dyn DisplayRestMapProduct>),
            Self::External(backend) => backend.upload(parts),
        }
    }
}

impl DisplayRestMapProduct for DisplayCageCoords {
    fn apply(&self, head: &[DVec3], tail: &[DVec3], out: &mut [Vec3]) {
        self.apply_concatenated(head, tail, out);
    }
}

/// A product every backend must compute without rounding, for the tests of a backend (the CPU
/// one's here, the wgpu one's in `cagerig-render`): three vertices on two cage points, rows
/// (1, 0), (0.5, 0.5), (0.25, 0.75) ([`Self::coords`]), uploaded as both the vertex part and
/// the extra columns and applied to [`Self::HEAD`] and [`Self::TAIL`]. Every coefficient, moved
/// point and partial sum is a short dyadic number, so M̃ is [`Self::EXPECTED`] exactly.
#[derive(Debug, Clone, Copy)]
pub struct DyadicProductCheck;

impl DyadicProductCheck {
    /// The rest cage C (`#C` = 2).
    pub const HEAD: [DVec3; 2] = [DVec3::new(1.0, 2.0, 3.0), DVec3::new(-3.0, 0.0, 1.0)];
    /// The extra terms (2).
    pub const TAIL: [DVec3; 2] = [DVec3::X, DVec3::Y];
    /// M̃ of the three vertices.
    pub const EXPECTED: [Vec3; 3] = [
        Vec3::new(2.0, 2.0, 3.0),
        Vec3::new(-0.5, 1.5, 2.0),
        Vec3::new(-1.75, 1.25, 1.5),
    ];

    /// The coordinates: rows (1, 0), (0.5, 0.5), (0.25, 0.75).
    #[expect(clippy::expect_used, reason = "three finite constant rows")]
    pub fn coords() -> CageCoords {
        CageCoords::from_rows(&[vec![1.0, 0.0], vec![0.5, 0.5], vec![0.25, 0.75]], 2)
            .expect("finite rows")
    }

    /// `product`'s M̃ at [`Self::HEAD`] and [`Self::TAIL`] (the product of two uploaded copies
    /// of [`Self::coords`]).
    pub fn apply(product: &dyn DisplayRestMapProduct) -> [Vec3; 3] {
        let mut out = [Vec3::ZERO; 3];
        product.apply(&Self::HEAD, &Self::TAIL, &mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cpu_backend_is_the_f32_product_of_the_concatenated_columns() {
        let coords = DyadicProductCheck::coords();
        let product = DisplayRestMap::Cpu
            .upload(&[&coords, &coords])
            .expect("a few bytes");
        let out = DyadicProductCheck::apply(&*product);
        let expected = DyadicProductCheck::EXPECTED;
        for (o, e) in out.iter().zip(expected) {
            assert!(o.abs_diff_eq(e, 1e-6), "{out:?}");
        }
        assert_eq!(DisplayRestMap::Cpu.name(), "cpu");
        assert_eq!(format!("{:?}", DisplayRestMap::Cpu), "Cpu");
    }
}
