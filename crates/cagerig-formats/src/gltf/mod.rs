//! glTF 2.0 import (and export).

pub mod animation;
pub mod buffers;
mod cage;
pub mod composed_keys;
pub mod import;
mod morph_targets;
mod parse;
mod primitive;
pub mod scene;
mod shared_skins;
pub mod static_mesh;

pub use import::{import_gltf, import_gltf_bytes};
pub use static_mesh::{import_gltf_static, import_gltf_static_bytes};
pub mod export;
pub mod export_animation;
pub mod export_animation_error;
pub mod export_bake;
pub mod export_resampling;
