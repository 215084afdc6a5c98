//! The skeleton being built or changed in the rest view, before it is bound: joints with a
//! name, a parent and a rest position, edited by clicks, the gizmo and the Skeleton panel
//! (add, add a child, move, re-parent, rename, delete), with an optional X mirror that names
//! and places symmetric joints `.L` / `.R`. "Bind" turns it into the rig's skeleton S.

use cagerig::session::RigSession;
use cagerig::{Joint, RigError, Skeleton};
use glam::{DAffine3, DVec3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// One joint of a draft.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DraftJoint {
    /// Unique, non-empty name.
    pub name: String,
    /// Parent joint (an index into the draft), `None` for a root.
    pub parent: Option<usize>,
    /// Rest position a_j, world space (the rest view).
    pub position: DVec3,
    /// The bound joint this one stands for (its index in the session's skeleton), `None` for
    /// a joint added since binding: a rebind keeps that joint's pose and keys.
    pub bound: Option<usize>,
}

/// A skeleton under construction (`#J` joints, any order).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SkeletonDraft {
    pub joints: Vec<DraftJoint>,
}

/// The X mirror: the plane x = `centre_x` (the character's middle) and how close to it a joint
/// counts as on it (snapped, no side suffix).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mirror {
    pub centre_x: f64,
    pub tolerance: f64,
}

/// Why a skeleton edit is refused.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DraftError {
    #[error("joint {index} does not exist: the skeleton has {count} joints")]
    NoJoint { index: usize, count: usize },
    #[error("joint {joint:?} cannot be parented to {parent:?}: {parent:?} is itself below it")]
    Cycle { joint: String, parent: String },
    #[error("a joint is already named {0:?}: names must be unique")]
    NameTaken(String),
    #[error("a joint name cannot be empty")]
    EmptyName,
    #[error("joint position {0:?} is not finite")]
    NotFinite(DVec3),
    #[error("the skeleton has no joint: add joints in the rest view (click on the mesh) first")]
    Empty,
    #[error(
        "joint {joint} ({name:?}): expected a parent below {count} (the joint count), found {parent}"
    )]
    ParentOutOfRange {
        joint: usize,
        name: String,
        parent: usize,
        count: usize,
    },
}

/// `.L` / `.R` of a side-suffixed name, and the name without it.
fn split_side(name: &str) -> Option<(&str, char)> {
    let (stem, side) = name.rsplit_once('.')?;
    match side {
        "L" => Some((stem, 'L')),
        "R" => Some((stem, 'R')),
        _ => None,
    }
}

/// The name of the mirror of `name`: `.L` ↔ `.R`; `None` for a name with no side.
pub fn mirrored_name(name: &str) -> Option<String> {
    split_side(name).map(|(stem, side)| match side {
        'L' => format!("{stem}.R"),
        _ => format!("{stem}.L"),
    })
}

impl SkeletonDraft {
    /// The rest skeleton of `session` (joint positions at the current rest pose), each joint
    /// standing for itself.
    pub fn from_session(session: &RigSession) -> Self {
        let skeleton = session.skeleton();
        Self {
            joints: skeleton
                .joints()
                .iter()
                .zip(session.rest_joints())
                .enumerate()
                .map(|(j, (joint, position))| DraftJoint {
                    name: joint.name.clone(),
                    parent: joint.parent,
                    position,
                    bound: Some(j),
                })
                .collect(),
        }
    }

    pub fn len(&self) -> usize {
        self.joints.len()
    }

    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    pub fn positions(&self) -> Vec<DVec3> {
        self.joints.iter().map(|j| j.position).collect()
    }

    pub fn parents(&self) -> Vec<Option<usize>> {
        self.joints.iter().map(|j| j.parent).collect()
    }

    fn check(&self, index: usize) -> Result<(), DraftError> {
        if index < self.joints.len() {
            Ok(())
        } else {
            Err(DraftError::NoJoint {
                index,
                count: self.joints.len(),
            })
        }
    }

    /// The joint named `name`.
    pub fn find(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// The mirror of joint `j` (by its `.L` / `.R` name), if it exists.
    pub fn mirror_of(&self, j: usize) -> Option<usize> {
        self.joints
            .get(j)
            .and_then(|joint| mirrored_name(&joint.name))
            .and_then(|name| self.find(&name))
    }

    /// `base` if no joint has that name, else `base.001`, `base.002`, … (Blender's rule).
    fn unique_name(&self, base: &str) -> String {
        if self.find(base).is_none() {
            return base.to_string();
        }
        (1..)
            .map(|k| format!("{base}.{k:03}"))
            .find(|n| self.find(n).is_none())
            .unwrap_or_else(|| base.to_string())
    }

    /// A fresh `joint<N>` stem that is free with and without side suffixes.
    fn fresh_stem(&self) -> String {
        (self.joints.len() + 1..)
            .map(|k| format!("joint{k}"))
            .find(|s| {
                [s.clone(), format!("{s}.L"), format!("{s}.R")]
                    .iter()
                    .all(|n| self.find(n).is_none())
            })
            .unwrap_or_else(|| "joint".into())
    }

    /// Adds a joint at `position` below `parent` (a root when `None`); returns its index.
    /// With `mirror`, a joint off the mirror plane gets a side suffix (`.L` at +x) and a mirror
    /// twin below the mirror of `parent`; a joint near the plane is snapped onto it.
    pub fn add_joint(
        &mut self,
        position: DVec3,
        parent: Option<usize>,
        mirror: Option<Mirror>,
    ) -> Result<usize, DraftError> {
        if !position.is_finite() {
            return Err(DraftError::NotFinite(position));
        }
        if let Some(p) = parent {
            self.check(p)?;
        }
        let stem = self.fresh_stem();
        let Some(m) = mirror else {
            return Ok(self.push(stem, parent, position));
        };
        let offset = position.x - m.centre_x;
        if offset.abs() <= m.tolerance {
            let on_plane = DVec3::new(m.centre_x, position.y, position.z);
            return Ok(self.push(stem, parent, on_plane));
        }
        let (side, other) = if offset > 0.0 { ("L", "R") } else { ("R", "L") };
        let added = self.push(format!("{stem}.{side}"), parent, position);
        let twin_parent = parent.map(|p| self.mirror_of(p).unwrap_or(p));
        let twin_position = DVec3::new(2.0 * m.centre_x - position.x, position.y, position.z);
        self.push(format!("{stem}.{other}"), twin_parent, twin_position);
        Ok(added)
    }

    fn push(&mut self, name: String, parent: Option<usize>, position: DVec3) -> usize {
        let name = self.unique_name(&name);
        self.joints.push(DraftJoint {
            name,
            parent,
            position,
            bound: None,
        });
        self.joints.len() - 1
    }

    /// Moves joint `j` to `position`; with `mirror`, its `.L` / `.R` twin follows mirrored.
    pub fn move_joint(
        &mut self,
        j: usize,
        position: DVec3,
        mirror: Option<Mirror>,
    ) -> Result<(), DraftError> {
        self.check(j)?;
        if !position.is_finite() {
            return Err(DraftError::NotFinite(position));
        }
        self.joints[j].position = position;
        if let Some(m) = mirror
            && let Some(twin) = self.mirror_of(j)
            && twin != j
        {
            self.joints[twin].position =
                DVec3::new(2.0 * m.centre_x - position.x, position.y, position.z);
        }
        Ok(())
    }

    /// Whether `ancestor` is `j` or above it.
    fn is_above(&self, ancestor: usize, mut j: usize) -> bool {
        for _ in 0..=self.joints.len() {
            if j == ancestor {
                return true;
            }
            match self.joints[j].parent {
                Some(p) => j = p,
                None => return false,
            }
        }
        false
    }

    /// Parents joint `j` to `parent` (a root when `None`); refuses a cycle.
    pub fn set_parent(&mut self, j: usize, parent: Option<usize>) -> Result<(), DraftError> {
        self.check(j)?;
        if let Some(p) = parent {
            self.check(p)?;
            if self.is_above(j, p) {
                return Err(DraftError::Cycle {
                    joint: self.joints[j].name.clone(),
                    parent: self.joints[p].name.clone(),
                });
            }
        }
        self.joints[j].parent = parent;
        Ok(())
    }

    /// Renames joint `j` (trimmed; unique and non-empty).
    pub fn rename(&mut self, j: usize, name: &str) -> Result<(), DraftError> {
        self.check(j)?;
        let name = name.trim();
        if name.is_empty() {
            return Err(DraftError::EmptyName);
        }
        if let Some(other) = self.find(name)
            && other != j
        {
            return Err(DraftError::NameTaken(name.to_string()));
        }
        self.joints[j].name = name.to_string();
        Ok(())
    }

    /// Deletes joint `j` (and, with `mirror`, its twin): its children move up to its parent;
    /// the joints after it shift down by one.
    pub fn delete_joint(&mut self, j: usize, mirror: bool) -> Result<(), DraftError> {
        self.check(j)?;
        let twin = if mirror { self.mirror_of(j) } else { None };
        self.remove(j);
        if let Some(t) = twin {
            let t = if t > j { t - 1 } else { t };
            self.remove(t);
        }
        Ok(())
    }

    fn remove(&mut self, j: usize) {
        let parent = self.joints[j].parent;
        self.joints.remove(j);
        for joint in &mut self.joints {
            joint.parent = match joint.parent {
                Some(p) if p == j => parent.map(|q| if q > j { q - 1 } else { q }),
                Some(p) if p > j => Some(p - 1),
                other => other,
            };
        }
    }

    /// Checks what the edits keep true, for a draft read from a file: every parent names a
    /// joint of the draft, no joint is its own ancestor, positions are finite, names are
    /// non-empty and unique. O(#J²) at worst (ancestor walks bounded by `#J`).
    pub fn validate(&self) -> Result<(), DraftError> {
        let count = self.joints.len();
        let mut names = std::collections::HashSet::with_capacity(count);
        for (j, joint) in self.joints.iter().enumerate() {
            if let Some(parent) = joint.parent
                && parent >= count
            {
                return Err(DraftError::ParentOutOfRange {
                    joint: j,
                    name: joint.name.clone(),
                    parent,
                    count,
                });
            }
            if !joint.position.is_finite() {
                return Err(DraftError::NotFinite(joint.position));
            }
            if joint.name.trim().is_empty() {
                return Err(DraftError::EmptyName);
            }
            if !names.insert(joint.name.as_str()) {
                return Err(DraftError::NameTaken(joint.name.clone()));
            }
        }
        for (j, joint) in self.joints.iter().enumerate() {
            if let Some(parent) = joint.parent
                && self.is_above(j, parent)
            {
                return Err(DraftError::Cycle {
                    joint: joint.name.clone(),
                    parent: self.joints[parent].name.clone(),
                });
            }
        }
        Ok(())
    }

    /// The rig skeleton S of this draft: a joint that stands for a bound joint keeps that
    /// joint's rest orientation and scale (`rest_frames`, `#J` of the session), a new joint is
    /// axis-aligned; positions are the draft's.
    pub fn to_skeleton(&self, rest_frames: &[DAffine3]) -> Result<Skeleton, RigError> {
        if self.joints.is_empty() {
            return Err(RigError::Invalid(DraftError::Empty.to_string()));
        }
        let joints = self
            .joints
            .iter()
            .map(|j| {
                let frame =
                    j.bound
                        .and_then(|b| rest_frames.get(b))
                        .map_or(DAffine3::IDENTITY, |f| DAffine3 {
                            matrix3: f.matrix3,
                            translation: DVec3::ZERO,
                        });
                Joint {
                    name: j.name.clone(),
                    parent: j.parent,
                    rest_world_from_joint: DAffine3 {
                        translation: j.position,
                        ..frame
                    },
                }
            })
            .collect();
        Skeleton::new(joints)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(name: &str, parent: Option<usize>, position: DVec3) -> DraftJoint {
        DraftJoint {
            name: name.into(),
            parent,
            position,
            bound: None,
        }
    }

    #[test]
    fn validate_accepts_what_edits_make_and_refuses_each_broken_rule() {
        let good = SkeletonDraft {
            joints: vec![
                joint("a", None, DVec3::ZERO),
                joint("b", Some(0), DVec3::X),
                joint("c", Some(1), DVec3::Y),
            ],
        };
        assert_eq!(good.validate(), Ok(()));
        let broken = |f: &dyn Fn(&mut SkeletonDraft)| {
            let mut d = good.clone();
            f(&mut d);
            d.validate().unwrap_err()
        };
        assert!(matches!(
            broken(&|d| d.joints[1].parent = Some(3)),
            DraftError::ParentOutOfRange {
                joint: 1,
                parent: 3,
                count: 3,
                ..
            }
        ));
        assert!(matches!(
            broken(&|d| d.joints[0].parent = Some(2)),
            DraftError::Cycle { .. }
        ));
        assert!(matches!(
            broken(&|d| d.joints[2].parent = Some(2)),
            DraftError::Cycle { .. }
        ));
        assert!(matches!(
            broken(&|d| d.joints[2].position.x = f64::NAN),
            DraftError::NotFinite(_)
        ));
        assert_eq!(
            broken(&|d| d.joints[2].name = " ".into()),
            DraftError::EmptyName
        );
        assert_eq!(
            broken(&|d| d.joints[2].name = "a".into()),
            DraftError::NameTaken("a".into())
        );
    }

    const MIRROR: Mirror = Mirror {
        centre_x: 0.0,
        tolerance: 0.01,
    };

    #[test]
    fn a_chain_of_clicks_builds_a_chain() {
        let mut d = SkeletonDraft::default();
        let a = d.add_joint(DVec3::ZERO, None, None).unwrap();
        let b = d.add_joint(DVec3::Y, Some(a), None).unwrap();
        let c = d.add_joint(2.0 * DVec3::Y, Some(b), None).unwrap();
        assert_eq!(d.parents(), vec![None, Some(0), Some(1)]);
        assert_eq!(c, 2);
        let names: Vec<_> = d.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, ["joint1", "joint2", "joint3"]);
        let s = d.to_skeleton(&[]).unwrap();
        assert_eq!(
            s.rest_positions(),
            vec![DVec3::ZERO, DVec3::Y, 2.0 * DVec3::Y]
        );
    }

    #[test]
    fn the_mirror_names_and_places_twins_and_moves_them_together() {
        let mut d = SkeletonDraft::default();
        let spine = d
            .add_joint(DVec3::new(0.005, 1.0, 0.0), None, Some(MIRROR))
            .unwrap();
        assert_eq!(d.joints[spine].position.x, 0.0, "snapped onto the plane");
        assert_eq!(d.joints[spine].name, "joint1");
        let arm = d
            .add_joint(DVec3::new(0.5, 1.0, 0.0), Some(spine), Some(MIRROR))
            .unwrap();
        assert_eq!(d.joints[arm].name, "joint2.L");
        let twin = d.mirror_of(arm).unwrap();
        assert_eq!(d.joints[twin].name, "joint2.R");
        assert_eq!(d.joints[twin].position, DVec3::new(-0.5, 1.0, 0.0));
        let hand = d
            .add_joint(DVec3::new(-1.0, 1.0, 0.0), Some(twin), Some(MIRROR))
            .unwrap();
        assert_eq!(d.joints[hand].name, "joint4.R");
        let hand_twin = d.mirror_of(hand).unwrap();
        assert_eq!(
            d.joints[hand_twin].parent,
            Some(arm),
            "below the twin's parent"
        );
        d.move_joint(arm, DVec3::new(0.6, 1.2, 0.1), Some(MIRROR))
            .unwrap();
        assert_eq!(d.joints[twin].position, DVec3::new(-0.6, 1.2, 0.1));
        d.delete_joint(hand, true).unwrap();
        assert_eq!(d.len(), 3);
        assert!(d.to_skeleton(&[]).is_ok());
    }

    #[test]
    fn deleting_reparents_children_and_shifts_indices() {
        let mut d = SkeletonDraft::default();
        let a = d.add_joint(DVec3::ZERO, None, None).unwrap();
        let b = d.add_joint(DVec3::Y, Some(a), None).unwrap();
        let c = d.add_joint(2.0 * DVec3::Y, Some(b), None).unwrap();
        d.add_joint(3.0 * DVec3::Y, Some(c), None).unwrap();
        d.delete_joint(b, false).unwrap();
        assert_eq!(d.parents(), vec![None, Some(0), Some(1)]);
        assert_eq!(d.joints[1].name, "joint3");
    }

    #[test]
    fn cycles_bad_names_and_bad_indices_are_refused() {
        let mut d = SkeletonDraft::default();
        let a = d.add_joint(DVec3::ZERO, None, None).unwrap();
        let b = d.add_joint(DVec3::Y, Some(a), None).unwrap();
        assert!(matches!(
            d.set_parent(a, Some(b)),
            Err(DraftError::Cycle { .. })
        ));
        assert!(matches!(
            d.set_parent(a, Some(a)),
            Err(DraftError::Cycle { .. })
        ));
        assert_eq!(
            d.rename(b, "joint1"),
            Err(DraftError::NameTaken("joint1".into()))
        );
        assert_eq!(d.rename(b, "  "), Err(DraftError::EmptyName));
        d.rename(b, " forearm ").unwrap();
        assert_eq!(d.joints[b].name, "forearm");
        assert_eq!(
            d.move_joint(7, DVec3::ZERO, None),
            Err(DraftError::NoJoint { index: 7, count: 2 })
        );
        assert!(d.add_joint(DVec3::NAN, None, None).is_err());
        d.set_parent(b, None).unwrap();
        assert_eq!(d.parents(), vec![None, None]);
        assert!(SkeletonDraft::default().to_skeleton(&[]).is_err());
    }
}
