//! Sync operators of Section 4: CageUp (S'→C'), SkelUp (C→S), CageRev (C'→C); for
//! Green coordinates, their Newton forms (`green_cage_fit`, with its reverser).

pub mod cage_fit_kind;
pub mod cage_prior;
pub mod cage_reverser;
pub mod cage_updater;
pub(crate) mod dense_lu;
pub mod green_cage_fit;
pub mod newton;
pub mod reach_limit;
pub mod skeleton_updater;
pub(crate) mod small_products;

pub use cage_fit_kind::CageFitKind;
