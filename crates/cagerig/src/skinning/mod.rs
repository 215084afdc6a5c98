//! Skinning S→S'→M': LBS, DQS and CoR (Eq. 1–6), and the per-vertex LBS/DQS blend of Maya's
//! "weight blended" skin clusters.
//!
//! Every kernel takes the skinning transforms `T_j = posed_from_rest[j]` (`#J`, see
//! [`crate::Skeleton::skinning_transforms`]), the rest mesh M (`#V`, it changes when the rest cage
//! is edited) and writes M' into a caller-owned `#V` buffer without allocating.
//! Vertices with an empty weight row stay at their rest position under every method.

pub(crate) mod antipodal_signs;
pub mod blended;
pub mod blended_f32;
pub(crate) mod compact_weights;
pub mod cor;
pub mod cor_f32;
mod dq_blend_weights;
pub mod dqs;
pub mod dqs_f32;
pub mod lbs;
pub mod lbs_f32;
mod method;
pub mod precision;
pub mod rigid_rotation;
mod stored_rest_kernel;
#[cfg(test)]
mod test_fixtures;
pub use stored_rest_kernel::{RestOnlyMethod, StoredRestKernel};

pub use blended::BlendedSkinning;
pub use blended_f32::{BlendedF32, BlendedF32Method, BlendedF32Scratch};
pub use cor::{CorScratch, CorSkinning};
// The CoR-centre precomputation lives beside this module, in `crate::cor_centres`; its
// types are re-exported here for the callers of the skinning kernels.
pub use crate::cor_centres::{
    CorCentresFactored, CorCentresMethod, CorCentresOptions, CorGridOptions, GridInterpolation,
    compute_cor_cage_coords, compute_cor_cage_coords_grid, compute_cor_centres,
    compute_cor_centres_factored,
};
pub use cor_f32::{CorF32, CorF32Scratch};
pub use dq_blend_weights::DqBlendWeights;
pub use dqs::{DqsScratch, DualQuat, DualQuaternionSkinning};
pub use dqs_f32::{DqsF32, DqsF32Method, DqsF32Scratch};
pub use lbs::LinearBlendSkinning;
pub use lbs_f32::{LbsF32, LbsF32Method, LbsF32Scratch};
pub use method::{SkinningMethod, UnknownSkinningMethod};
pub use precision::{RestPoint, SkinReal};
