//! cagerig — real-time deformation with coupled cages and skeletons (Corda et al., CGF 2020).
//!
//! Six structures: rest skin M, rest skeleton S, rest cage C and their current counterparts
//! M', S', C'. Skinning weights Ω (`#V × #J`, [`SkinWeights`]) drive S→S'→M' ([`skinning`]); cage
//! coordinates Φ (`#V × #C`, [`CageCoords`]) give M = ΦC ([`coords`]); the sync operators of
//! Section 4 ([`sync`]) keep all six in consensus.

pub mod animation;
pub mod cage;
pub mod cage_coords;
pub mod coords;
pub mod error;
pub mod io;
pub mod mesh;
pub mod skeleton;
pub mod skin_weights;
pub mod skinning;
pub mod sparse_rows;

pub use cage_coords::CageCoords;
pub use error::{RigError, Warning};
pub use mesh::TriMesh;
pub use skeleton::{Joint, Skeleton};
pub use skin_weights::SkinWeights;
pub use sparse_rows::SparseRows;
