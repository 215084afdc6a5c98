//! cagerig — real-time deformation with coupled cages and skeletons (Corda et al., CGF 2020).
//!
//! Six structures: rest skin M, rest skeleton S, rest cage C and their current counterparts
//! M', S', C'. Skinning weights Ω (`#V × #J`, [`SkinWeights`]) drive S→S'→M' ([`skinning`]); cage
//! coordinates Φ (`#V × #C`, [`CageCoords`]) give M = ΦC ([`coords`]); the sync operators of
//! Section 4 ([`sync`]) keep all six in consensus inside a [`session::RigSession`].
//!
//! The numerical modules depend on no file format; [`io`] reads and writes OBJ and the paper
//! tool's formats, [`script`] replays JSON edit scripts.

#![warn(missing_docs)]

pub mod animation;
pub mod auto_weights;
pub mod cage;
pub mod cage_coords;
pub mod cage_enclosure;
pub mod cage_gen;
pub mod cage_quality;
pub mod cage_source;
pub mod coords;
pub mod coords_kind;
pub mod cor_centres;
pub mod demo;
pub mod error;
pub mod io;
pub mod memory_estimate;
pub mod mesh;
pub mod named_kind;
pub mod nearest_vertices;
pub mod playback;
pub mod pose;
pub mod rig_files;
mod row_blocks;
pub mod script;
pub mod session;
mod simd_dispatch;
pub mod skeleton;
pub mod skin_weights;
pub mod skinning;
pub mod sparse_rows;
pub mod subdivide;
pub mod sync;
#[cfg(test)]
mod test_random;
mod vector_registers;
pub mod weights_source;

pub use cage_coords::CageCoords;
pub use coords_kind::CoordsKind;
pub use error::{RigError, Severity, UnfittedCage, Warning};
pub use mesh::TriMesh;
pub use named_kind::NamedKind;
pub use skeleton::{Joint, Skeleton};
pub use skin_weights::SkinWeights;
pub use sparse_rows::SparseRows;
pub use sync::CageFitKind;
