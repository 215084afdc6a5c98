//! How well the current cage C' follows the posed skin M': the measures an artist sees when
//! grabbing the handle, reported by `animate --json`, `bench` and `info`.
//!
//! - **spread**: max over cage vertices of the distance of C'_k to the posed skin M', divided by
//!   the same maximum for the rest cage C and the rest skin M (1: the cage stays as close to the
//!   body as at rest; distances to the nearest skin vertex).
//! - **deviation**: max_k |C'_k − P_k| / the rest skin's bounding-box diagonal, with P_k the rest
//!   vertex C_k carried rigidly by the best-fit rotation and translation (Kabsch) of its
//!   [`SKIN_NEIGHBOURS`](crate::nearest_vertices::SKIN_NEIGHBOURS) nearest rest-skin vertices
//!   from M to M' (and any as near as the last, so the measure does not depend on round-off):
//!   the neighbourhoods of the regularised CageUp's prior, by the same rule
//!   ([`crate::nearest_vertices::skin_neighbourhoods`]).
//! - **flipped**: the share of C' triangles whose normal opposes that of the same triangle on P.
//!
//! [`CageQualityProbe::new`] picks the neighbours once (on the rest state given);
//! [`CageQualityProbe::measure`] evaluates a state in O(#C·#V) for the spread.

use faer::Mat;
use glam::{DMat3, DVec3};

use crate::error::RigError;
use crate::nearest_vertices::skin_neighbourhoods;

/// The three measures of one state (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CageQuality {
    /// Max distance of C' to M' over max distance of C to M.
    pub spread: f64,
    /// Max |C'_k − P_k| over the rest bounding-box diagonal.
    pub deviation: f64,
    /// Share of C' triangles flipped against P, in [0, 1].
    pub flipped: f64,
}

impl CageQuality {
    /// The worst of each measure over `self` and `other`.
    pub fn worst(self, other: Self) -> Self {
        Self {
            spread: self.spread.max(other.spread),
            deviation: self.deviation.max(other.deviation),
            flipped: self.flipped.max(other.flipped),
        }
    }
}

impl std::fmt::Display for CageQuality {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "spread {:.2}, deviation {:.3} of the diagonal, flipped {:.1} %",
            self.spread,
            self.deviation,
            100.0 * self.flipped
        )
    }
}

/// What [`CageQualityProbe::measure`] needs of the rest state.
#[derive(Debug, Clone)]
pub struct CageQualityProbe {
    /// Per cage vertex, its nearest rest-skin vertices
    /// ([`crate::nearest_vertices::skin_neighbourhoods`]).
    neighbours: Vec<Vec<usize>>,
    cage_triangles: Vec<[u32; 3]>,
    /// max_k dist(C_k, M).
    rest_reach: f64,
    /// The rest skin's bounding-box diagonal.
    diagonal: f64,
}

impl CageQualityProbe {
    /// Picks each rest cage vertex's neighbours in the rest skin `rest_mesh` (`#V`) and the rest
    /// reach. `rest_cage` is `#C`, `cage_triangles` its faces.
    pub fn new(
        rest_mesh: &[DVec3],
        rest_cage: &[DVec3],
        cage_triangles: &[[u32; 3]],
    ) -> Result<Self, RigError> {
        if rest_mesh.is_empty() || rest_cage.is_empty() {
            return Err(RigError::Invalid(format!(
                "cage quality needs a skin and a cage: got {} skin and {} cage vertices",
                rest_mesh.len(),
                rest_cage.len()
            )));
        }
        if let Some(bad) = cage_triangles
            .iter()
            .flatten()
            .find(|&&i| i as usize >= rest_cage.len())
        {
            return Err(RigError::IndexOutOfRange {
                what: "cage triangle corner",
                index: *bad as usize,
                len: rest_cage.len(),
            });
        }
        let neighbours = skin_neighbourhoods(rest_cage, rest_mesh);
        // The nearest skin vertex of each cage vertex is in its neighbourhood.
        let rest_reach = neighbours
            .iter()
            .zip(rest_cage)
            .map(|(near, c)| {
                near.iter()
                    .map(|&v| rest_mesh[v].distance_squared(*c))
                    .fold(f64::INFINITY, f64::min)
                    .sqrt()
            })
            .fold(0.0f64, f64::max);
        let (lo, hi) = crate::mesh::bounding_box(rest_mesh);
        Ok(Self {
            neighbours,
            cage_triangles: cage_triangles.to_vec(),
            rest_reach,
            diagonal: (hi - lo).length(),
        })
    }

    /// The measures of the state (`rest_mesh` M, `rest_cage` C, `posed_mesh` M', `posed_cage`
    /// C'; the same sizes as at [`Self::new`]).
    pub fn measure(
        &self,
        rest_mesh: &[DVec3],
        rest_cage: &[DVec3],
        posed_mesh: &[DVec3],
        posed_cage: &[DVec3],
    ) -> CageQuality {
        let reach = posed_cage
            .iter()
            .map(|c| {
                posed_mesh
                    .iter()
                    .map(|m| m.distance_squared(*c))
                    .fold(f64::INFINITY, f64::min)
                    .sqrt()
            })
            .fold(0.0f64, f64::max);
        let carried: Vec<DVec3> = self
            .neighbours
            .iter()
            .zip(rest_cage)
            .map(|(near, c)| carry_rigidly(near, rest_mesh, posed_mesh, *c))
            .collect();
        let deviation = carried
            .iter()
            .zip(posed_cage)
            .map(|(p, c)| p.distance(*c))
            .fold(0.0f64, f64::max);
        let flipped = self
            .cage_triangles
            .iter()
            .filter(|t| {
                let normal = |x: &[DVec3]| {
                    let [a, b, c] = t.map(|i| x[i as usize]);
                    (b - a).cross(c - a)
                };
                normal(posed_cage).dot(normal(&carried)) < 0.0
            })
            .count();
        CageQuality {
            spread: if self.rest_reach > 0.0 {
                reach / self.rest_reach
            } else {
                reach / self.diagonal
            },
            deviation: deviation / self.diagonal,
            flipped: flipped as f64 / self.cage_triangles.len().max(1) as f64,
        }
    }
}

/// The worst cage quality of one joint bent by the standard bend ([`joint_bends`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointBendQuality {
    /// The joint's index.
    pub joint: usize,
    /// The joint's name.
    pub name: String,
    /// The worst of each measure over the three bends (world x, y and z); `None` when the rig
    /// refused all three.
    pub quality: Option<CageQuality>,
    /// Bends refused by the rig (a Green rig whose CageUp finds no current cage), of three.
    pub refused: usize,
}

/// The standard bend of every joint: from the rest pose, the joint rotated by `angle` radians
/// about the world x, y and z axes in turn (one event each, back to rest after each), measured
/// with a probe of the session's rest state. The session ends in the rest pose.
pub fn joint_bends(
    session: &mut crate::session::RigSession,
    angle: f64,
) -> Result<Vec<JointBendQuality>, RigError> {
    let probe = CageQualityProbe::of_session(session)?;
    let mut out = Vec::with_capacity(session.skeleton().len());
    for joint in 0..session.skeleton().len() {
        let mut worst: Option<CageQuality> = None;
        let mut refused = 0;
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            match session.rotate_joint(joint, axis, angle) {
                Ok(()) => {
                    let q = probe.measure_session(session);
                    worst = Some(worst.map_or(q, |w| w.worst(q)));
                }
                Err(RigError::GreenFitFailed(_)) => refused += 1,
                Err(e) => return Err(e),
            }
            session.reset_pose();
        }
        out.push(JointBendQuality {
            joint,
            name: session.skeleton().joint(joint).name.clone(),
            quality: worst,
            refused,
        });
    }
    Ok(out)
}

impl CageQualityProbe {
    /// [`Self::new`] on `session`'s rest state (M, C and the cage's faces).
    pub fn of_session(session: &crate::session::RigSession) -> Result<Self, RigError> {
        Self::new(
            session.rest_mesh(),
            session.rest_cage(),
            session.cage_triangles(),
        )
    }

    /// [`Self::measure`] of `session`'s state (M, C, M', C').
    pub fn measure_session(&self, session: &crate::session::RigSession) -> CageQuality {
        self.measure(
            session.rest_mesh(),
            session.rest_cage(),
            session.posed_mesh(),
            session.posed_cage(),
        )
    }
}

/// `point` moved by the best-fit rigid motion (Kabsch) of `near` from `from` to `to`.
fn carry_rigidly(near: &[usize], from: &[DVec3], to: &[DVec3], point: DVec3) -> DVec3 {
    let n = near.len() as f64;
    let from_centre = near.iter().map(|&i| from[i]).sum::<DVec3>() / n;
    let to_centre = near.iter().map(|&i| to[i]).sum::<DVec3>() / n;
    // H = Σ (x − x̄)(y − ȳ)ᵀ.
    let mut h = [[0.0f64; 3]; 3];
    for &i in near {
        let (x, y) = (from[i] - from_centre, to[i] - to_centre);
        for (a, row) in h.iter_mut().enumerate() {
            for (b, e) in row.iter_mut().enumerate() {
                *e += x[a] * y[b];
            }
        }
    }
    let rotation = Mat::<f64>::from_fn(3, 3, |a, b| h[a][b])
        .svd()
        .ok()
        .map(|svd| {
            let (u, v) = (svd.U(), svd.V());
            let m = |x: faer::MatRef<'_, f64>| {
                DMat3::from_cols_array(&[
                    x[(0, 0)],
                    x[(1, 0)],
                    x[(2, 0)],
                    x[(0, 1)],
                    x[(1, 1)],
                    x[(2, 1)],
                    x[(0, 2)],
                    x[(1, 2)],
                    x[(2, 2)],
                ])
            };
            let (u, v) = (m(u), m(v));
            // R = V diag(1, 1, det(V Uᵀ)) Uᵀ.
            let d = (v * u.transpose()).determinant().signum();
            v * DMat3::from_diagonal(DVec3::new(1.0, 1.0, d)) * u.transpose()
        })
        .filter(|r| r.is_finite())
        .unwrap_or(DMat3::IDENTITY);
    to_centre + rotation * (point - from_centre)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::TriMesh;

    fn sphere_points() -> Vec<DVec3> {
        (0..200)
            .map(|i| {
                let t = i as f64 * 2.399_963;
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / 200.0;
                let r = (1.0 - z * z).sqrt();
                DVec3::new(r * t.cos(), r * t.sin(), z)
            })
            .collect()
    }

    #[test]
    fn a_rigid_motion_of_skin_and_cage_is_perfect_and_a_wild_vertex_is_seen() {
        let skin = sphere_points();
        let cage = TriMesh::cuboid(DVec3::splat(-1.2), DVec3::splat(1.2)).unwrap();
        let probe = CageQualityProbe::new(&skin, &cage.positions, &cage.triangles).unwrap();
        let rotation = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.9);
        let shift = DVec3::new(3.0, -1.0, 2.0);
        let moved = |x: &[DVec3]| x.iter().map(|p| rotation * *p + shift).collect::<Vec<_>>();
        let (posed_skin, mut posed_cage) = (moved(&skin), moved(&cage.positions));
        let q = probe.measure(&skin, &cage.positions, &posed_skin, &posed_cage);
        assert!((q.spread - 1.0).abs() < 1e-9, "{q}");
        assert!(q.deviation < 1e-9 && q.flipped == 0.0, "{q}");
        // One vertex thrown far out: spread and deviation grow.
        posed_cage[0] += DVec3::new(0.0, 0.0, 5.0);
        let q = probe.measure(&skin, &cage.positions, &posed_skin, &posed_cage);
        assert!(q.spread > 2.0 && q.deviation > 1.0, "{q}");
        // The current cage mirrored in z about its centre while the skin is not: the normals
        // of the four x and y faces (8 of 12 triangles) turn inside out, the z faces' do not.
        let centre = shift;
        let mirror = rotation * DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
        let mirrored: Vec<DVec3> = cage
            .positions
            .iter()
            .map(|p| centre + mirror * *p)
            .collect();
        let q = probe.measure(&skin, &cage.positions, &posed_skin, &mirrored);
        assert_eq!(q.flipped, 8.0 / 12.0, "{q}");
    }
}
