//! Which joints deform, and the bone segments that carry their weight.
//!
//! A joint's transform moves the part of the body between it and its children, so joint `j`'s
//! bones are the segments `a_j → a_c` for each child `c` (world space, rest pose). A segment
//! shorter than [`MIN_BONE_FRACTION`] of the skeleton's extent is no bone: a joint whose only
//! children sit on it (the Arm's `Skeleton` and `upperarm01.R`, the Fox's `_rootJoint`) is a
//! control joint and gets no weight. A tip joint (no child) has no segment of its own; when it
//! is set to deform ([`TipJoints`]) it gets one, continuing its parent's direction for
//! `tip_length` × the parent's bone length (the head, a hand, the last phalanx).

use glam::DVec3;

use crate::Skeleton;

/// Segments shorter than this fraction of the joints' bounding-box diagonal are not bones.
pub const MIN_BONE_FRACTION: f64 = 1e-6;

/// Which tip joints (joints with no child) deform.
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TipJoints {
    /// Every tip except end markers: joints whose name ends with `end`, `nub`, `tip` or
    /// `null` (any case; Blender's and 3ds Max's leaf markers, e.g. `head_end`, `Bip01 R Finger0Nub`).
    #[default]
    AllButEndMarkers,
    /// Every tip joint.
    All,
    /// No tip joint.
    None,
    /// Only the listed tip joints (indices; other joints listed are an error).
    Only(Vec<usize>),
}

/// True when a joint name marks the end of a chain rather than a deforming joint.
pub fn is_end_marker(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    ["end", "nub", "tip", "null"]
        .iter()
        .any(|suffix| lower.ends_with(suffix))
}

/// A straight bone segment `start → end` (world space) of one joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoneSegment {
    /// The joint whose transform moves this segment.
    pub joint: usize,
    /// The joint position a_j.
    pub start: DVec3,
    /// The child position, or the end of a tip's extension.
    pub end: DVec3,
}

/// The bone segments of every deforming joint (`joint` ascending), and the number of children
/// of each joint (`#J`).
///
/// `tips` selects the deforming tips; a tip index in [`TipJoints::Only`] that has children is
/// returned as `Err(joint)`.
pub fn bone_segments(
    skeleton: &Skeleton,
    tips: &TipJoints,
    tip_length: f64,
) -> Result<Vec<BoneSegment>, usize> {
    let n = skeleton.len();
    let positions = skeleton.rest_positions();
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    for j in 0..n {
        if let Some(p) = skeleton.parent(j) {
            children[p].push(j);
        }
    }
    if let TipJoints::Only(list) = tips
        && let Some(&bad) = list.iter().find(|&&j| j >= n || !children[j].is_empty())
    {
        return Err(bad);
    }
    let (lo, hi) = crate::mesh::bounding_box(&positions);
    let min_length = (hi - lo).length() * MIN_BONE_FRACTION;
    let mut segments = Vec::new();
    for j in 0..n {
        let start = positions[j];
        if !children[j].is_empty() {
            for &c in &children[j] {
                if positions[c].distance(start) > min_length {
                    segments.push(BoneSegment {
                        joint: j,
                        start,
                        end: positions[c],
                    });
                }
            }
            continue;
        }
        let deforms = match tips {
            TipJoints::AllButEndMarkers => !is_end_marker(&skeleton.joint(j).name),
            TipJoints::All => true,
            TipJoints::None => false,
            TipJoints::Only(list) => list.contains(&j),
        };
        if !deforms {
            continue;
        }
        // The direction of the nearest ancestor at a distinct position.
        let mut ancestor = skeleton.parent(j);
        while let Some(a) = ancestor {
            if positions[a].distance(start) > min_length {
                break;
            }
            ancestor = skeleton.parent(a);
        }
        let end = match ancestor {
            Some(a) => start + (start - positions[a]) * tip_length,
            // A lone joint: a point bone.
            None => start,
        };
        segments.push(BoneSegment {
            joint: j,
            start,
            end,
        });
    }
    Ok(segments)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Joint;
    use glam::DAffine3;

    fn chain(points: &[(&str, Option<usize>, DVec3)]) -> Skeleton {
        Skeleton::new(
            points
                .iter()
                .map(|(name, parent, p)| Joint {
                    name: name.to_string(),
                    parent: *parent,
                    rest_world_from_joint: DAffine3::from_translation(*p),
                })
                .collect(),
        )
        .unwrap()
    }

    #[test]
    fn joints_own_the_segments_to_their_children_and_tips_extend() {
        let s = chain(&[
            ("root", None, DVec3::ZERO),
            ("hip", Some(0), DVec3::ZERO),
            ("knee", Some(1), DVec3::X),
            ("ankle", Some(2), DVec3::new(2.0, 0.0, 0.0)),
            ("ankle_end", Some(3), DVec3::new(2.5, 0.0, 0.0)),
        ]);
        let segs = bone_segments(&s, &TipJoints::AllButEndMarkers, 0.5).unwrap();
        let joints: Vec<usize> = segs.iter().map(|s| s.joint).collect();
        // root → hip has zero length: the root is a control joint; the end marker is static.
        assert_eq!(joints, vec![1, 2, 3]);
        let all = bone_segments(&s, &TipJoints::All, 0.5).unwrap();
        let tip = all.last().unwrap();
        assert_eq!(tip.joint, 4);
        assert!((tip.end - DVec3::new(2.75, 0.0, 0.0)).length() < 1e-12);
        assert_eq!(bone_segments(&s, &TipJoints::None, 0.5).unwrap().len(), 3);
        assert_eq!(bone_segments(&s, &TipJoints::Only(vec![2]), 0.5), Err(2));
    }

    #[test]
    fn end_markers_are_recognised() {
        assert!(is_end_marker("head_end"));
        assert!(is_end_marker("Bip01 R Finger0Nub"));
        assert!(!is_end_marker("b_Head_05"));
        assert!(!is_end_marker("finger1-3.R"));
    }
}
