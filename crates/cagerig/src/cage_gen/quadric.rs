//! Quadric error metric (Garland & Heckbert 1997): the sum of squared distances to a set of
//! planes, Q(x) = xᵀAx − 2bᵀx + c, accumulated area-weighted over the faces around a vertex.

use glam::{DMat3, DVec3};

/// A symmetric quadric: A (3×3), b (3), c.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quadric {
    a: DMat3,
    b: DVec3,
    c: f64,
}

/// The zero quadric (not derived: glam's default matrix is the identity, which would add
/// |x|² to every vertex's error).
impl Default for Quadric {
    fn default() -> Self {
        Self {
            a: DMat3::ZERO,
            b: DVec3::ZERO,
            c: 0.0,
        }
    }
}

impl Quadric {
    /// `weight` × squared distance to the plane through `point` with unit `normal`.
    pub fn from_plane(normal: DVec3, point: DVec3, weight: f64) -> Self {
        let d = normal.dot(point);
        let a = DMat3::from_cols(normal * normal.x, normal * normal.y, normal * normal.z);
        Self {
            a: a * weight,
            b: normal * (d * weight),
            c: d * d * weight,
        }
    }

    /// Q(x).
    pub fn evaluate(&self, x: DVec3) -> f64 {
        (x.dot(self.a * x) - 2.0 * self.b.dot(x) + self.c).max(0.0)
    }

    /// The minimiser A⁻¹b when A is well conditioned (its determinant is not tiny relative to
    /// its scale cubed), else `None`.
    pub fn minimiser(&self) -> Option<DVec3> {
        let det = self.a.determinant();
        let scale = self.a.x_axis.x + self.a.y_axis.y + self.a.z_axis.z;
        if scale <= 0.0 || det.abs() <= 1e-6 * scale * scale * scale {
            return None;
        }
        let x = self.a.inverse() * self.b;
        x.is_finite().then_some(x)
    }
}

impl std::ops::Add for Quadric {
    type Output = Self;
    fn add(self, other: Self) -> Self {
        Self {
            a: self.a + other.a,
            b: self.b + other.b,
            c: self.c + other.c,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: the derived default had A = identity, so every vertex's collapse cost
    /// carried |x|² (the distance to the origin) and the minimiser was pulled towards it.
    #[test]
    fn default_is_zero_everywhere() {
        let zero = Quadric::default();
        assert_eq!(zero.evaluate(DVec3::new(3.0, -4.0, 12.0)), 0.0);
        let plane = Quadric::from_plane(DVec3::Z, DVec3::Z * 2.0, 1.0);
        let x = DVec3::new(5.0, 6.0, 3.0);
        assert!(((zero + plane).evaluate(x) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn three_planes_meet_at_their_corner() {
        let corner = DVec3::new(1.0, 2.0, 3.0);
        let q = Quadric::from_plane(DVec3::X, corner, 1.0)
            + Quadric::from_plane(DVec3::Y, corner, 2.0)
            + Quadric::from_plane(DVec3::Z, corner, 0.5);
        let x = q.minimiser().unwrap();
        assert!(x.distance(corner) < 1e-12);
        assert!(q.evaluate(corner) < 1e-12);
        assert!((q.evaluate(corner + DVec3::Y) - 2.0).abs() < 1e-12);
        // One plane: singular.
        assert!(
            Quadric::from_plane(DVec3::Z, corner, 1.0)
                .minimiser()
                .is_none()
        );
    }
}
