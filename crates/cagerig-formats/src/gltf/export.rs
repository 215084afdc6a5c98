//! A rig session → a standard rigged glTF 2.0 binary (`.glb`) that any viewer opens.
//!
//! What is written: the rest mesh M *after* cage edits as the bind shape (the skinned mesh node
//! sits at the scene root with no transform, so bind space = world space), the rest skeleton S
//! after SkelUp as the inverse bind matrices `IBM_j = B_j⁻¹`, Ω as `JOINTS_n`/`WEIGHTS_n` (four
//! influences per set, as many sets as needed), and the session's current pose S' as the joint
//! nodes' TRS. Under LBS a viewer then shows cagerig's M' up to the f32 rounding of the file
//! (positions, matrices and weights are f32 in glTF). Importing the file back
//! ([`super::import_gltf`]) gives the same M, S and Ω, and [`crate::ImportedCharacter::node_pose`]
//! gives back the pose. The rest cage C is written too, as a mesh node `<name>_cage` outside the
//! scene (marked `extras.cagerig_cage`), so that the file reopens in cagerig with its cage.

use std::io::Write;
use std::path::Path;

use cagerig::session::RigSession;
use glam::{DAffine3, DVec3};
use serde_json::{Value, json};

use crate::error::FormatError;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;

/// Binary chunk and the JSON arrays that describe it.
#[derive(Default)]
pub(crate) struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// Continues a document written by [`session_to_gltf`] (its accessors and views).
    pub(crate) fn from_document(document: &Value, bin: Vec<u8>) -> Self {
        let list = |key: &str| document[key].as_array().cloned().unwrap_or_default();
        Self {
            bin,
            views: list("bufferViews"),
            accessors: list("accessors"),
        }
    }

    /// Puts the accessors, views and buffer length into `document`; returns it with the chunk.
    pub(crate) fn finish(self, mut document: Value) -> (Value, Vec<u8>) {
        document["accessors"] = Value::Array(self.accessors);
        document["bufferViews"] = Value::Array(self.views);
        document["buffers"] = json!([{"byteLength": self.bin.len()}]);
        (document, self.bin)
    }

    /// Appends bytes as a new buffer view (4-byte aligned) and an accessor over it.
    pub(crate) fn accessor(&mut self, bytes: &[u8], target: Option<u32>, accessor: Value) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view =
            json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            view["target"] = t.into();
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(view);
        let mut accessor = accessor;
        accessor["bufferView"] = (self.views.len() - 1).into();
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }
}

pub(crate) fn f32_bytes(values: impl IntoIterator<Item = f64>) -> Vec<u8> {
    values
        .into_iter()
        .flat_map(|v| (v as f32).to_le_bytes())
        .collect()
}

/// A VEC3 float accessor of `points` with the min/max the specification requires for POSITION
/// (bounds of the f32 values written).
pub(crate) fn position_accessor(b: &mut Builder, points: &[DVec3], vertex_target: bool) -> usize {
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for p in points {
        for (c, x) in [p.x as f32, p.y as f32, p.z as f32].into_iter().enumerate() {
            min[c] = min[c].min(x);
            max[c] = max[c].max(x);
        }
    }
    if points.is_empty() {
        (min, max) = ([0.0; 3], [0.0; 3]);
    }
    b.accessor(
        &f32_bytes(points.iter().flat_map(|p| [p.x, p.y, p.z])),
        vertex_target.then_some(ARRAY_BUFFER),
        json!({"componentType": FLOAT, "count": points.len(), "type": "VEC3", "min": min, "max": max}),
    )
}

/// A u32 SCALAR index accessor of `triangles` (an element-array buffer view).
fn index_accessor(b: &mut Builder, triangles: &[[u32; 3]]) -> usize {
    let bytes: Vec<u8> = triangles
        .iter()
        .flatten()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    b.accessor(
        &bytes,
        Some(ELEMENT_ARRAY_BUFFER),
        json!({"componentType": UNSIGNED_INT, "count": 3 * triangles.len(), "type": "SCALAR"}),
    )
}

/// TRS of an affine transform as glTF node fields (rotation normalised).
fn trs(local: &DAffine3) -> Value {
    let (s, r, t) = local.to_scale_rotation_translation();
    let r = r.normalize();
    json!({
        "translation": [t.x as f32, t.y as f32, t.z as f32],
        "rotation": [r.x as f32, r.y as f32, r.z as f32, r.w as f32],
        "scale": [s.x as f32, s.y as f32, s.z as f32],
    })
}

/// Joint weights of one vertex as f32 that sum to 1 in f32 (the largest absorbs the rounding).
fn f32_row(weights: &[f64]) -> Vec<f32> {
    let sum: f64 = weights.iter().sum();
    let mut row: Vec<f32> = weights.iter().map(|w| (w / sum) as f32).collect();
    if let Some(k) = (0..row.len()).max_by(|&a, &b| row[a].total_cmp(&row[b])) {
        let others: f32 = row
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != k)
            .map(|(_, w)| *w)
            .sum();
        row[k] = 1.0 - others;
    }
    row
}

/// The glTF document (JSON) and its binary chunk for the session's current state.
pub fn session_to_gltf(session: &RigSession, name: &str) -> Result<(Value, Vec<u8>), String> {
    let skeleton = session.skeleton();
    let nj = skeleton.len();
    if nj > u16::MAX as usize {
        return Err(format!("{nj} joints: glTF JOINTS_n hold at most 65535"));
    }
    let rest = session.rest_mesh();
    let nv = rest.len();
    let weights = session.skin_weights();
    let mut b = Builder::default();
    let positions = position_accessor(&mut b, rest, true);
    let indices = index_accessor(&mut b, session.mesh_triangles());
    // JOINTS_n / WEIGHTS_n: heaviest influences first, four per set.
    let sets = weights.max_influences().div_ceil(4).max(1);
    let mut joint_sets = vec![Vec::with_capacity(8 * nv); sets];
    let mut weight_sets = vec![Vec::with_capacity(16 * nv); sets];
    for v in 0..nv {
        let (joints, ws) = weights.row(v);
        let mut order: Vec<usize> = (0..joints.len()).collect();
        order.sort_by(|&a, &c| ws[c].total_cmp(&ws[a]));
        let sorted: Vec<f64> = order.iter().map(|&k| ws[k]).collect();
        let row = if sorted.is_empty() {
            Vec::new()
        } else {
            f32_row(&sorted)
        };
        for s in 0..sets {
            for slot in 0..4 {
                let k = 4 * s + slot;
                let (j, w) = match order.get(k) {
                    Some(&i) if row[k] != 0.0 => (joints[i] as u16, row[k]),
                    _ => (0u16, 0.0f32),
                };
                joint_sets[s].extend_from_slice(&j.to_le_bytes());
                weight_sets[s].extend_from_slice(&w.to_le_bytes());
            }
        }
    }
    let mut attributes = json!({"POSITION": positions});
    for s in 0..sets {
        let j = b.accessor(
            &joint_sets[s],
            Some(ARRAY_BUFFER),
            json!({"componentType": UNSIGNED_SHORT, "count": nv, "type": "VEC4"}),
        );
        let w = b.accessor(
            &weight_sets[s],
            Some(ARRAY_BUFFER),
            json!({"componentType": FLOAT, "count": nv, "type": "VEC4"}),
        );
        attributes[format!("JOINTS_{s}")] = j.into();
        attributes[format!("WEIGHTS_{s}")] = w.into();
    }
    // Inverse bind matrices B_j⁻¹ (column-major, affine bottom row).
    let ibm_values: Vec<f64> = session
        .rest_world_from_joint()
        .iter()
        .flat_map(|frame| {
            let m = glam::DMat4::from(frame.inverse());
            let mut cols = m.to_cols_array();
            cols[3] = 0.0;
            cols[7] = 0.0;
            cols[11] = 0.0;
            cols[15] = 1.0;
            cols
        })
        .collect();
    let ibm = b.accessor(
        &f32_bytes(ibm_values),
        None,
        json!({"componentType": FLOAT, "count": nj, "type": "MAT4"}),
    );
    // Joint nodes with the current pose as TRS.
    let posed = session.posed_world_from_joint();
    let mut nodes: Vec<Value> = (0..nj)
        .map(|j| {
            let local = match skeleton.parent(j) {
                Some(p) => posed[p].inverse() * posed[j],
                None => posed[j],
            };
            let mut node = trs(&local);
            node["name"] = skeleton.joint(j).name.clone().into();
            node
        })
        .collect();
    for j in 0..nj {
        if let Some(p) = skeleton.parent(j) {
            let children = nodes[p]
                .as_object_mut()
                .map(|o| o.entry("children").or_insert_with(|| json!([])));
            if let Some(Value::Array(c)) = children {
                c.push(j.into());
            }
        }
    }
    nodes.push(json!({"name": name, "mesh": 0, "skin": 0}));
    // The rest cage C, for cagerig to read back: a mesh node outside the scene (viewers do not
    // draw it), named `<name>_cage` and marked in `extras`.
    let cage_positions = position_accessor(&mut b, session.rest_cage(), true);
    let cage_indices = index_accessor(&mut b, session.cage_triangles());
    let cage_name = format!("{name}_cage");
    nodes.push(json!({"name": cage_name, "mesh": 1, "extras": {"cagerig_cage": true}}));
    let mut roots: Vec<usize> = (0..nj).filter(|&j| skeleton.parent(j).is_none()).collect();
    roots.push(nj);
    let document = json!({
        "asset": {"version": "2.0", "generator": "cagerig"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [
            {"name": name, "primitives": [{"attributes": attributes, "indices": indices, "mode": 4}]},
            {"name": cage_name, "primitives": [{"attributes": {"POSITION": cage_positions}, "indices": cage_indices, "mode": 4}]},
        ],
        "skins": [{"joints": (0..nj).collect::<Vec<_>>(), "inverseBindMatrices": ibm}],
    });
    Ok(b.finish(document))
}

/// Writes a GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded).
pub fn write_glb(out: &mut dyn Write, document: &Value, bin: &[u8]) -> std::io::Result<()> {
    let mut json_bytes = serde_json::to_vec(document).map_err(std::io::Error::other)?;
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let bin_len = bin.len().div_ceil(4) * 4;
    let total = 12 + 8 + json_bytes.len() + 8 + bin_len;
    let total = u32::try_from(total).map_err(|_| std::io::Error::other("the GLB exceeds 4 GiB"))?;
    out.write_all(b"glTF")?;
    out.write_all(&2u32.to_le_bytes())?;
    out.write_all(&total.to_le_bytes())?;
    out.write_all(&(json_bytes.len() as u32).to_le_bytes())?;
    out.write_all(b"JSON")?;
    out.write_all(&json_bytes)?;
    out.write_all(&(bin_len as u32).to_le_bytes())?;
    out.write_all(b"BIN\0")?;
    out.write_all(bin)?;
    out.write_all(&vec![0u8; bin_len - bin.len()])?;
    Ok(())
}

/// Writes `document` as `path` (`.gltf`, JSON) with its buffer in `<stem>-<hash>.bin` beside it
/// (`<hash>`: 16 hex digits of the buffer's FNV-1a hash), so that replacing an earlier export is
/// atomic: the new `.bin` is written first under its own name, then the `.gltf` that refers to
/// it replaces the old one in one rename (the commit point), then the earlier exports' `.bin`
/// files of this stem are removed. A kill at any moment leaves a `.gltf` whose buffer is
/// complete, old or new.
pub fn write_gltf_files(path: &Path, document: &Value, bin: &[u8]) -> Result<(), FormatError> {
    let io = |p: &Path, message: String| FormatError::Io {
        path: p.to_path_buf(),
        message,
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .ok_or_else(|| io(path, "expected a file name ending in .gltf".into()))?;
    let bin_name = format!("{stem}-{:016x}.bin", fnv1a(bin));
    let bin_path = path.with_file_name(&bin_name);
    let mut document = document.clone();
    let buffer = document
        .get_mut("buffers")
        .and_then(|b| b.get_mut(0))
        .ok_or_else(|| io(path, "the document has no buffer".into()))?;
    buffer["uri"] = Value::String(bin_name.clone());
    let text = serde_json::to_vec_pretty(&document).map_err(|e| io(path, e.to_string()))?;
    cagerig::io::atomic::write_atomically(&bin_path, |w| w.write_all(bin))
        .map_err(|e| io(&bin_path, e.reason()))?;
    cagerig::io::atomic::write_atomically(path, |w| w.write_all(&text))
        .map_err(|e| io(path, e.reason()))?;
    remove_earlier_buffers(path, &stem, &bin_name);
    Ok(())
}

/// 64-bit FNV-1a of `bytes` (names an export's buffer file by its content).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Removes `<stem>-<16 hex digits>.bin` files beside `path` other than `keep`: buffers of
/// earlier exports to the same `.gltf`, no longer referred to. Other files are never touched.
fn remove_earlier_buffers(path: &Path, stem: &str, keep: &str) {
    let Some(dir) = path.parent().map(|d| {
        if d.as_os_str().is_empty() {
            Path::new(".")
        } else {
            d
        }
    }) else {
        return;
    };
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        let ours = name
            .strip_prefix(stem)
            .and_then(|rest| rest.strip_prefix('-'))
            .and_then(|rest| rest.strip_suffix(".bin"))
            .is_some_and(|hash| hash.len() == 16 && hash.bytes().all(|b| b.is_ascii_hexdigit()));
        if ours && name != keep {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Writes `document` + `bin` as `.glb` or as `.gltf` + `.bin`, by the extension of `path`.
pub fn write_gltf_or_glb(path: &Path, document: &Value, bin: &[u8]) -> Result<(), FormatError> {
    let text = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf"));
    if text {
        return write_gltf_files(path, document, bin);
    }
    cagerig::io::atomic::write_atomically(path, |w| write_glb(w, document, bin)).map_err(|e| {
        FormatError::Io {
            path: path.to_path_buf(),
            message: e.reason(),
        }
    })
}

/// Exports the session's current state to `path` (`.glb`, or `.gltf` + `.bin`), replacing the
/// files atomically.
pub fn export_glb(session: &RigSession, path: &Path, name: &str) -> Result<(), FormatError> {
    let (document, bin) = session_to_gltf(session, name).map_err(|message| FormatError::Io {
        path: path.to_path_buf(),
        message,
    })?;
    write_gltf_or_glb(path, &document, &bin)
}
