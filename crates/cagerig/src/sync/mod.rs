//! Sync operators of Section 4: CageUp (S'→C'), SkelUp (C→S), CageRev (C'→C).

pub mod cage_reverser;
pub mod cage_updater;
pub mod skeleton_updater;
