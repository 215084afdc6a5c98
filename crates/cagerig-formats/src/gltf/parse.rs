//! glTF/GLB bytes to a validated document: the checks the `gltf` crate's own validation
//! misses, and the required extensions cagerig reads.

use std::path::Path;

use cagerig::Warning;

use crate::error::FormatError;

/// Why GLB `bytes` (magic `glTF`) are shorter than their header or a chunk header says: the
/// file looks truncated (a download or copy that stopped early). `None` for complete files and
/// for anything that is not GLB.
fn glb_truncation(bytes: &[u8]) -> Option<String> {
    const HEADER: usize = 12;
    const CHUNK_HEADER: usize = 8;
    if !bytes.starts_with(b"glTF") {
        return None;
    }
    let found = bytes.len();
    let word = |at: usize| -> Option<usize> {
        let b = bytes.get(at..at + 4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let truncated = |expected: usize, what: &str| {
        format!(
            "the file looks truncated: {what} says {expected} bytes, found {found} (the download \
             or copy stopped early: get the file again)"
        )
    };
    let Some(total) = word(8) else {
        return Some(truncated(HEADER, "a GLB header"));
    };
    if total > found {
        return Some(truncated(total, "its GLB header"));
    }
    // The chunks (JSON, then the optional binary chunk) within the declared length.
    let mut at = HEADER;
    while at < total {
        let Some(length) = word(at) else {
            return Some(truncated(at + CHUNK_HEADER, "its chunk list"));
        };
        let end = at.saturating_add(CHUNK_HEADER).saturating_add(length);
        if end > found {
            return Some(truncated(end, "its chunk list"));
        }
        at = end;
    }
    None
}

/// Parses and validates glTF/GLB bytes. The `gltf` crate's validation (1.4) indexes the
/// accessors with each primitive's POSITION index before checking it, and panics on an index
/// out of range, and it does not check animation channel targets: both are checked here.
///
/// Required extensions that change only lighting, materials, textures or metadata
/// ([`changes_appearance_only`]) are accepted and returned as one warning naming them; any
/// other required extension but `KHR_mesh_quantization` is refused by name.
pub(super) fn parse_validated(
    bytes: &[u8],
    path: &Path,
) -> Result<(gltf::Gltf, Vec<Warning>), FormatError> {
    let gltf_error = |message: String| FormatError::Gltf {
        path: path.to_path_buf(),
        message,
    };
    if let Some(message) = glb_truncation(bytes) {
        return Err(gltf_error(message));
    }
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| gltf_error(e.to_string()))?;
    let mut root = document.into_json();
    // KHR_mesh_quantization only widens the component types of vertex attributes (normalised or
    // not, 8/16-bit), which the accessor reader decodes: a file that requires it is read. The
    // `gltf` crate's validation would refuse it as unsupported.
    root.extensions_required
        .retain(|e| e != "KHR_mesh_quantization");
    let (ignored, required): (Vec<String>, Vec<String>) =
        std::mem::take(&mut root.extensions_required)
            .into_iter()
            .partition(|e| changes_appearance_only(e));
    root.extensions_required = required;
    let mut warnings = Vec::new();
    if !ignored.is_empty() {
        warnings.push(Warning::Note {
            message: format!(
                "required extension{} {} ignored: {} only lighting, materials, textures or \
                 metadata, not the skinned geometry or its animation",
                if ignored.len() == 1 { "" } else { "s" },
                ignored.join(", "),
                if ignored.len() == 1 {
                    "it changes"
                } else {
                    "they change"
                },
            ),
        });
    }
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&gltf::json::validation::Checked::Valid(
                    gltf::json::mesh::Semantic::Positions,
                ))
                .map(|index| index.value());
            if let Some(index) = position.filter(|&i| i >= accessors) {
                return Err(gltf_error(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION names accessor {index}, \
                     but the file has {accessors} accessors"
                )));
            }
        }
    }
    // Nor does it check animation channel targets (node index, path), which the accessors of
    // the `gltf` crate unwrap.
    let nodes = root.nodes.len();
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let node = channel.target.node.value();
            if node >= nodes {
                return Err(gltf_error(format!(
                    "animations[{a}].channels[{c}].target.node is {node}, but the file has \
                     {nodes} nodes"
                )));
            }
            if !matches!(
                channel.target.path,
                gltf::json::validation::Checked::Valid(_)
            ) {
                return Err(gltf_error(format!(
                    "animations[{a}].channels[{c}].target.path is not one of translation, \
                     rotation, scale, weights"
                )));
            }
        }
    }
    let document = gltf::Document::from_json(root).map_err(|e| gltf_error(e.to_string()))?;
    Ok((gltf::Gltf { document, blob }, warnings))
}

/// Whether a glTF extension changes only how a file looks (lights, materials, textures) or
/// what it says about itself (metadata), never its vertices, skin or animation: cagerig can
/// read a file that requires it by ignoring it. Geometry extensions (Draco, meshopt, GPU
/// instancing) and animation ones (`KHR_animation_pointer`) are not in this list.
fn changes_appearance_only(extension: &str) -> bool {
    extension.starts_with("KHR_materials_")
        || matches!(
            extension,
            "KHR_lights_punctual"
                | "KHR_texture_transform"
                | "KHR_texture_basisu"
                | "EXT_texture_webp"
                | "EXT_texture_avif"
                | "EXT_lights_image_based"
                | "KHR_xmp_json_ld"
        )
}
