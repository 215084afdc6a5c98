//! The rigging skeleton S (rest) and its forward kinematics towards S' (current pose).
//!
//! Joint `j` carries a rest transform `rest_world_from_joint[j]` (its frame in world space at rest).
//! A pose is a set of local transforms `parent_from_joint[j]` (for roots: `world_from_joint`);
//! forward kinematics composes them root-first. The skinning transform of Eq. 1–3 is
//! `T_j = posed_from_rest[j] = posed_world_from_joint[j] · rest_world_from_joint[j]⁻¹`.

mod translation_jacobian;

use glam::{DAffine3, DVec3};

use crate::error::RigError;

/// One joint of the skeleton (serialised with serde; [`Skeleton::new`] checks joints).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Joint {
    /// Unique name.
    pub name: String,
    /// Parent joint index, `None` for a root (several roots are allowed).
    pub parent: Option<usize>,
    /// Rest frame of the joint in world space (its translation is the joint position a_j).
    pub rest_world_from_joint: DAffine3,
}

impl Joint {
    /// A joint named `name` under `parent` whose rest frame is a translation to `position`
    /// (the joint position a_j, axes aligned with the world's).
    pub fn at(name: impl Into<String>, parent: Option<usize>, position: DVec3) -> Self {
        Self {
            name: name.into(),
            parent,
            rest_world_from_joint: DAffine3::from_translation(position),
        }
    }
}

/// A validated joint hierarchy: parents exist, no cycles, unique names.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    joints: Vec<Joint>,
    /// Joint indices with every parent before its children (roots first).
    order: Vec<usize>,
}

impl Skeleton {
    /// Validates the hierarchy. Joints may be listed in any order.
    pub fn new(joints: Vec<Joint>) -> Result<Self, RigError> {
        let n = joints.len();
        let mut by_name = std::collections::HashMap::with_capacity(n);
        for (j, joint) in joints.iter().enumerate() {
            if let Some(first) = by_name.insert(joint.name.as_str(), j) {
                return Err(RigError::DuplicateJointName {
                    name: joint.name.clone(),
                    first,
                    second: j,
                });
            }
            if let Some(p) = joint.parent
                && p >= n
            {
                return Err(RigError::UnknownParent {
                    joint: j,
                    name: joint.name.clone(),
                    parent: p,
                });
            }
            if !joint.rest_world_from_joint.is_finite() {
                return Err(RigError::NonFinite {
                    what: "joint rest transform",
                    index: j,
                });
            }
            if let Some(value) =
                crate::error::first_bad_component(joint.rest_world_from_joint.translation)
            {
                return Err(RigError::ValueOutOfBounds {
                    what: "joint position",
                    index: j,
                    value,
                });
            }
        }
        // Depth of each joint by walking up; a walk longer than n means a cycle.
        let mut depth = vec![0usize; n];
        for (j, d) in depth.iter_mut().enumerate() {
            let mut k = j;
            let mut steps = 0;
            while let Some(p) = joints[k].parent {
                steps += 1;
                if steps > n {
                    return Err(RigError::Cycle {
                        joint: j,
                        name: joints[j].name.clone(),
                    });
                }
                k = p;
            }
            *d = steps;
        }
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by_key(|&j| (depth[j], j));
        Ok(Self { joints, order })
    }

    /// Number of joints `#J`.
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Whether the skeleton has no joint.
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// The joints, by index (`#J`).
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Joint `j`. Panics if `j` is out of range.
    pub fn joint(&self, j: usize) -> &Joint {
        &self.joints[j]
    }

    /// Parent index of joint `j`, `None` for a root. Panics if `j` is out of range.
    pub fn parent(&self, j: usize) -> Option<usize> {
        self.joints[j].parent
    }

    /// Index of the joint called `name`.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Joint indices with parents before children.
    pub fn topological_order(&self) -> &[usize] {
        &self.order
    }

    /// Rest joint positions (the translations of the rest frames), `#J`.
    pub fn rest_positions(&self) -> Vec<DVec3> {
        self.joints
            .iter()
            .map(|j| j.rest_world_from_joint.translation)
            .collect()
    }

    /// Rest frames `world_from_joint`, `#J`.
    pub fn rest_world_from_joint(&self) -> Vec<DAffine3> {
        self.joints
            .iter()
            .map(|j| j.rest_world_from_joint)
            .collect()
    }

    /// Local transforms `parent_from_joint` (roots: `world_from_joint`) of the given world frames.
    pub fn locals_from_worlds(&self, world_from_joint: &[DAffine3], out: &mut [DAffine3]) {
        for (j, joint) in self.joints.iter().enumerate() {
            out[j] = match joint.parent {
                Some(p) => world_from_joint[p].inverse() * world_from_joint[j],
                None => world_from_joint[j],
            };
        }
    }

    /// Forward kinematics: world frames from local transforms (roots first).
    pub fn forward_kinematics(&self, parent_from_joint: &[DAffine3], out: &mut [DAffine3]) {
        for &j in &self.order {
            out[j] = match self.joints[j].parent {
                Some(p) => out[p] * parent_from_joint[j],
                None => parent_from_joint[j],
            };
        }
    }

    /// Skinning transforms `posed_from_rest[j] = posed_world_from_joint[j] · rest_world_from_joint[j]⁻¹`
    /// (the T_j of Eq. 1–3) for world frames of a pose and of the rest skeleton.
    pub fn skinning_transforms(
        rest_world_from_joint: &[DAffine3],
        posed_world_from_joint: &[DAffine3],
        out: &mut [DAffine3],
    ) {
        for ((o, rest), posed) in out
            .iter_mut()
            .zip(rest_world_from_joint)
            .zip(posed_world_from_joint)
        {
            *o = *posed * rest.inverse();
        }
    }

    /// Returns a copy with new rest joint positions (rest rotations kept).
    pub fn with_rest_positions(&self, positions: &[DVec3]) -> Self {
        let mut s = self.clone();
        for (j, p) in s.joints.iter_mut().zip(positions) {
            j.rest_world_from_joint.translation = *p;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_cycles_unknown_parents_and_duplicates() {
        let cyc = vec![
            Joint::at("a", Some(1), DVec3::ZERO),
            Joint::at("b", Some(0), DVec3::X),
        ];
        assert!(matches!(Skeleton::new(cyc), Err(RigError::Cycle { .. })));
        let unk = vec![Joint::at("a", Some(5), DVec3::ZERO)];
        assert!(matches!(
            Skeleton::new(unk),
            Err(RigError::UnknownParent { parent: 5, .. })
        ));
        let dup = vec![
            Joint::at("a", None, DVec3::ZERO),
            Joint::at("a", Some(0), DVec3::X),
        ];
        assert!(matches!(
            Skeleton::new(dup),
            Err(RigError::DuplicateJointName {
                first: 0,
                second: 1,
                ..
            })
        ));
    }

    #[test]
    fn fk_of_rest_locals_gives_rest_frames_with_children_listed_first() {
        // Child listed before its parent, two roots.
        let joints = vec![
            Joint::at("child", Some(1), DVec3::new(1.0, 2.0, 0.0)),
            Joint {
                name: "root".into(),
                parent: None,
                rest_world_from_joint: DAffine3::from_rotation_z(0.3)
                    * DAffine3::from_translation(DVec3::new(1.0, 0.0, 0.0)),
            },
            Joint::at("other_root", None, DVec3::Z),
        ];
        let s = Skeleton::new(joints).unwrap();
        assert_eq!(s.topological_order()[2], 0);
        let rest = s.rest_world_from_joint();
        let mut locals = vec![DAffine3::IDENTITY; 3];
        s.locals_from_worlds(&rest, &mut locals);
        let mut world = vec![DAffine3::IDENTITY; 3];
        s.forward_kinematics(&locals, &mut world);
        for (a, b) in world.iter().zip(&rest) {
            assert!(a.abs_diff_eq(*b, 1e-14));
        }
    }
}
