//! Skeleton guide of cage generation (part of the skeleton layout, [`super::CageLayout`]): keep
//! rings of cage vertices around the articulations.
//!
//! At every joint with a parent and a child (an articulation) the guide places a plane through
//! the joint, orthogonal to the bisector of the incoming and outgoing bone directions. Starting-
//! surface vertices within the joint's reach (half its shorter bone) and within a band of the
//! plane get that plane's quadric with a large weight: collapses that keep them in the plane
//! stay cheap, collapses that pull them off it become expensive, so the quadric order leaves a
//! ring of vertices around the joint — the cage vertices SkelUp and CageUp move with the bend.

use glam::DVec3;

use super::quadric::Quadric;
use crate::skeleton::Skeleton;

/// Quadric weight of a guide plane, × the mean triangle area of the starting surface: large
/// against the surface's own planes (one triangle's area each). Of 500, 1000 and 2000, 2000 gave
/// the generated cages whose current cage strays least from the body (docs/characters.md).
pub const GUIDE_WEIGHT: f64 = 2000.0;

/// A plane around one articulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GuidePlane {
    /// The joint's rest position.
    pub centre: DVec3,
    /// Unit normal: the bisector of the bone directions at the joint.
    pub normal: DVec3,
    /// Vertices farther than this from the centre are not guided.
    pub reach: f64,
}

/// The planes of a skeleton's articulations.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CageGuide {
    /// One plane per articulation (empty: no guidance).
    pub planes: Vec<GuidePlane>,
}

impl CageGuide {
    /// One plane per joint that has a parent and at least one child (rest pose).
    pub fn from_skeleton(skeleton: &Skeleton) -> Self {
        let positions = skeleton.rest_positions();
        let mut planes = Vec::new();
        for j in 0..skeleton.len() {
            let Some(parent) = skeleton.parent(j) else {
                continue;
            };
            let children: Vec<usize> = (0..skeleton.len())
                .filter(|&c| skeleton.parent(c) == Some(j))
                .collect();
            if children.is_empty() {
                continue;
            }
            let incoming = positions[j] - positions[parent];
            let outgoing: DVec3 = children
                .iter()
                .map(|&c| (positions[c] - positions[j]).normalize_or_zero())
                .sum::<DVec3>()
                / children.len() as f64;
            let shortest = children
                .iter()
                .map(|&c| positions[c].distance(positions[j]))
                .fold(incoming.length(), f64::min);
            let Some(normal) = (incoming.normalize_or_zero() + outgoing).try_normalize() else {
                continue;
            };
            if shortest > 0.0 {
                planes.push(GuidePlane {
                    centre: positions[j],
                    normal,
                    reach: 0.5 * shortest,
                });
            }
        }
        Self { planes }
    }

    /// The guide's quadric at a surface vertex `p`: `weight` × the squared distance to every
    /// plane whose band (`band` either side) and reach hold `p`.
    pub fn quadric_at(&self, p: DVec3, band: f64, weight: f64) -> Quadric {
        self.planes
            .iter()
            .filter(|g| g.normal.dot(p - g.centre).abs() <= band && p.distance(g.centre) <= g.reach)
            .fold(Quadric::default(), |q, g| {
                q + Quadric::from_plane(g.normal, g.centre, weight)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::Joint;

    #[test]
    fn planes_bisect_the_bones_at_articulations_only() {
        // Shoulder → elbow (bent 90°) → wrist: one articulation, the elbow.
        let skeleton = Skeleton::new(vec![
            Joint::at("shoulder", None, DVec3::ZERO),
            Joint::at("elbow", Some(0), DVec3::X * 4.0),
            Joint::at("wrist", Some(1), DVec3::new(4.0, 2.0, 0.0)),
        ])
        .unwrap();
        let guide = CageGuide::from_skeleton(&skeleton);
        assert_eq!(guide.planes.len(), 1);
        let plane = guide.planes[0];
        assert_eq!(plane.centre, DVec3::X * 4.0);
        let bisector = DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!((plane.normal - bisector).length() < 1e-12);
        assert!((plane.reach - 1.0).abs() < 1e-12);
        // In the band and reach: the plane's quadric; elsewhere nothing.
        let near = DVec3::new(4.0, 0.0, 0.5);
        let q = guide.quadric_at(near, 0.1, 2.0);
        let off_plane = near + plane.normal * 0.3;
        let value = q.evaluate(off_plane);
        assert!((value - 2.0 * 0.09).abs() < 1e-12, "{value}");
        assert_eq!(
            guide.quadric_at(DVec3::new(4.0, 0.0, 3.0), 0.1, 2.0),
            Quadric::default()
        );
        assert_eq!(
            guide.quadric_at(near + plane.normal, 0.1, 2.0),
            Quadric::default()
        );
    }
}
