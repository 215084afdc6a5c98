//! The selection (cage vertices and a joint, the same indices in both poses), what a click
//! selects, and the active tool of the gizmo.

use std::collections::BTreeSet;

/// Selected cage vertices and joint (the same indices in both poses).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Selection {
    pub cage: BTreeSet<usize>,
    pub joint: Option<usize>,
    /// Whether the gizmo and the keys act on the joint (last clicked) rather than the cage.
    pub joint_is_active: bool,
}

/// What a click in a view hits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Picked {
    CageVertex(usize),
    Joint(usize),
}

/// The active transform tool of the gizmo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tool {
    Move,
    Rotate,
    Scale,
}

impl Selection {
    pub fn is_empty(&self) -> bool {
        self.cage.is_empty() && self.joint.is_none()
    }

    /// Whether transforms act on the selected joint.
    pub fn joint_active(&self) -> bool {
        self.joint.is_some() && (self.joint_is_active || self.cage.is_empty())
    }

    /// Selects every cage vertex of a cage of `cage_len` vertices.
    pub fn select_all_cage(&mut self, cage_len: usize) {
        self.cage = (0..cage_len).collect();
        self.joint_is_active = false;
    }

    /// Applies a click on `picked` (shift adds / toggles, ctrl removes, else replaces).
    pub fn click(&mut self, picked: Option<Picked>, modifiers: egui::Modifiers) {
        match picked {
            Some(Picked::CageVertex(k)) => {
                if modifiers.command {
                    self.cage.remove(&k);
                } else if modifiers.shift {
                    if !self.cage.remove(&k) {
                        self.cage.insert(k);
                    }
                } else {
                    self.cage.clear();
                    self.cage.insert(k);
                }
                self.joint_is_active = false;
            }
            Some(Picked::Joint(j)) => {
                if modifiers.command {
                    if self.joint == Some(j) {
                        self.joint = None;
                    }
                } else {
                    self.joint = Some(j);
                    self.joint_is_active = true;
                    if !modifiers.shift {
                        self.cage.clear();
                    }
                }
            }
            None => {
                if !modifiers.shift && !modifiers.command {
                    self.cage.clear();
                    self.joint = None;
                }
            }
        }
    }

    /// Applies a box selection of the cage vertices `inside` (shift adds, ctrl removes, else
    /// replaces).
    pub fn box_select(&mut self, inside: Vec<usize>, modifiers: egui::Modifiers) {
        if modifiers.command {
            for k in inside {
                self.cage.remove(&k);
            }
        } else {
            if !modifiers.shift {
                self.cage.clear();
            }
            self.cage.extend(inside);
        }
        self.joint_is_active = false;
    }
}
