//! glTF buffers and accessors, read defensively (files come from anywhere).
//!
//! - Buffer URIs resolve only inside the glTF file's own folder: `data:` base64 URIs are decoded,
//!   relative paths are percent-decoded and joined to the folder; absolute paths, `..`
//!   components, other schemes and symbolic links leading outside are refused.
//! - Every accessor's declared count, offset and stride are checked against the bytes actually
//!   present before anything is allocated, with overflow-checked arithmetic.

use std::path::{Component, Path, PathBuf};

use base64::Engine;
use gltf::accessor::{DataType, Dimensions};

use crate::error::{FormatError, invalid};

/// The bytes of every buffer of a document, in buffer order.
pub struct Buffers {
    data: Vec<Vec<u8>>,
    path: PathBuf,
}

/// Resolves a relative URI inside `folder`, refusing anything that could leave it.
pub fn resolve_uri(
    folder: &Path,
    uri: &str,
    file: &Path,
    element: &str,
) -> Result<PathBuf, FormatError> {
    let refuse = |why: &str| invalid(file, element, format!("URI {uri:?} refused: {why}"));
    if let Some(colon) = uri.find(':') {
        let scheme_end = uri.find('/').unwrap_or(uri.len());
        if colon < scheme_end {
            return Err(refuse(
                "only relative file paths inside the file's folder are read (no URI scheme)",
            ));
        }
    }
    let decoded = cagerig::io::text::percent_decode(uri)
        .ok_or_else(|| refuse("malformed percent-encoding"))?;
    if decoded.starts_with('/') || decoded.starts_with('\\') || decoded.contains('\0') {
        return Err(refuse("absolute paths are not allowed"));
    }
    let relative = Path::new(&decoded);
    for c in relative.components() {
        match c {
            Component::Normal(_) | Component::CurDir => {}
            _ => return Err(refuse("'..' and absolute components are not allowed")),
        }
    }
    let joined = folder.join(relative);
    let canon_folder = folder
        .canonicalize()
        .map_err(|e| refuse(&format!("the file's folder cannot be resolved: {e}")))?;
    let canon = joined.canonicalize().map_err(|e| FormatError::Io {
        path: joined.clone(),
        message: format!("{element} (URI {uri:?}) cannot be opened: {e}"),
    })?;
    if !canon.starts_with(&canon_folder) {
        return Err(refuse("it leads outside the file's folder (symbolic link)"));
    }
    Ok(canon)
}

impl Buffers {
    /// Loads every buffer of `document` (`blob`: the GLB binary chunk), checking each has at
    /// least its declared `byteLength`.
    pub fn load(
        document: &gltf::Document,
        blob: Option<&[u8]>,
        path: &Path,
    ) -> Result<Self, FormatError> {
        let folder = path.parent().unwrap_or(Path::new("."));
        let folder = if folder.as_os_str().is_empty() {
            Path::new(".")
        } else {
            folder
        };
        let mut data = Vec::with_capacity(document.buffers().len());
        for buffer in document.buffers() {
            let element = format!("buffer {}", buffer.index());
            let bytes = match buffer.source() {
                gltf::buffer::Source::Bin => blob
                    .ok_or_else(|| {
                        invalid(
                            path,
                            &element,
                            "refers to the GLB binary chunk, which is missing",
                        )
                    })?
                    .to_vec(),
                gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    let (_, payload) = uri.split_once(";base64,").ok_or_else(|| {
                        invalid(
                            path,
                            &element,
                            "data URI is not base64 (expected 'data:<type>;base64,')",
                        )
                    })?;
                    // Decoded size ≤ 3/4 of the text: bounded by what the file holds.
                    base64::engine::general_purpose::STANDARD
                        .decode(payload)
                        .map_err(|e| invalid(path, &element, format!("bad base64 data URI: {e}")))?
                }
                gltf::buffer::Source::Uri(uri) => {
                    let file = resolve_uri(folder, uri, path, &element)?;
                    let len = std::fs::metadata(&file)
                        .map_err(|e| FormatError::Io {
                            path: file.clone(),
                            message: format!("{element}: {e}"),
                        })?
                        .len();
                    if len < buffer.length() as u64 {
                        return Err(invalid(
                            path,
                            &element,
                            format!(
                                "declares {} bytes but {} holds {len}",
                                buffer.length(),
                                file.display()
                            ),
                        ));
                    }
                    std::fs::read(&file).map_err(|e| FormatError::Io {
                        path: file.clone(),
                        message: format!("{element}: {e}"),
                    })?
                }
            };
            if bytes.len() < buffer.length() {
                return Err(invalid(
                    path,
                    &element,
                    format!(
                        "declares {} bytes but only {} are present",
                        buffer.length(),
                        bytes.len()
                    ),
                ));
            }
            data.push(bytes);
        }
        Ok(Self {
            data,
            path: path.to_path_buf(),
        })
    }

    /// The accessor's elements as f64, `count × components` row-major, with normalised integer
    /// types mapped to [0, 1] (or [−1, 1]) as the glTF specification says. `allowed` lists the
    /// dimensions the caller accepts.
    pub fn read(
        &self,
        accessor: &gltf::Accessor,
        what: &str,
        allowed: &[Dimensions],
    ) -> Result<Vec<f64>, FormatError> {
        let element = format!("accessor {} ({what})", accessor.index());
        let err = |m: String| invalid(&self.path, &element, m);
        let dims = accessor.dimensions();
        if !allowed.contains(&dims) {
            return Err(err(format!(
                "has type {dims:?}, expected one of {allowed:?}"
            )));
        }
        let ncomp = dims.multiplicity();
        let size = component_size(accessor.data_type());
        if matches!(dims, Dimensions::Mat2 | Dimensions::Mat3) && size < 4 {
            return Err(err(
                "small-integer matrices (column padding) are not supported".into(),
            ));
        }
        let count = accessor.count();
        let Some(view) = accessor.view() else {
            // No buffer view: all zeros (specification), then the sparse substitutions. Bounded
            // by the file: a document this small cannot claim more than 2^24 zero elements.
            if count > 1 << 24 {
                return Err(err(format!(
                    "claims {count} zero elements without any data"
                )));
            }
            let mut out = vec![0.0; count * ncomp];
            self.apply_sparse(accessor, &element, &mut out)?;
            return self.finite(&element, out, ncomp);
        };
        let buffer = &self.data[view.buffer().index()];
        let elem = size * ncomp;
        let stride = view.stride().unwrap_or(elem);
        if stride < elem {
            return Err(err(format!(
                "stride {stride} is smaller than its element ({elem} bytes)"
            )));
        }
        let view_end = view
            .offset()
            .checked_add(view.length())
            .filter(|&e| e <= buffer.len())
            .ok_or_else(|| {
                err(format!(
                    "buffer view {} (offset {}, length {}) exceeds buffer {} ({} bytes)",
                    view.index(),
                    view.offset(),
                    view.length(),
                    view.buffer().index(),
                    buffer.len()
                ))
            })?;
        let start = view.offset().checked_add(accessor.offset());
        let needed = count.checked_sub(1).map_or(Some(0), |c| {
            c.checked_mul(stride).and_then(|x| x.checked_add(elem))
        });
        let end = start.zip(needed).and_then(|(s, n)| s.checked_add(n));
        match end {
            Some(e) if e <= view_end => {}
            _ => {
                return Err(err(format!(
                    "declares {count} elements of {elem} bytes (stride {stride}) at offset {} but its buffer view {} holds {} bytes",
                    accessor.offset(),
                    view.index(),
                    view.length()
                )));
            }
        }
        let start = start.unwrap_or(0);
        let mut out = Vec::with_capacity(count * ncomp);
        for i in 0..count {
            let base = start + i * stride;
            for c in 0..ncomp {
                let o = base + c * size;
                out.push(decode(accessor, &buffer[o..o + size]));
            }
        }
        self.apply_sparse(accessor, &element, &mut out)?;
        self.finite(&element, out, ncomp)
    }

    /// `out` when every value is finite; else an error naming the first element that is not.
    fn finite(&self, element: &str, out: Vec<f64>, ncomp: usize) -> Result<Vec<f64>, FormatError> {
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            return Err(invalid(
                &self.path,
                element,
                format!(
                    "element {} component {} is not finite ({})",
                    i / ncomp,
                    i % ncomp,
                    out[i]
                ),
            ));
        }
        Ok(out)
    }

    /// Applies the accessor's sparse substitutions (glTF 2.0 §3.6.2.3), if any, to its dense
    /// elements `out` (`count × components`): `sparse.count` element indices (unsigned 8/16/32
    /// bit, strictly increasing) and as many tightly packed elements of the accessor's type.
    fn apply_sparse(
        &self,
        accessor: &gltf::Accessor,
        element: &str,
        out: &mut [f64],
    ) -> Result<(), FormatError> {
        let Some(sparse) = accessor.sparse() else {
            return Ok(());
        };
        let err = |m: String| invalid(&self.path, element, m);
        let ncomp = accessor.dimensions().multiplicity();
        let size = component_size(accessor.data_type());
        let elem = size * ncomp;
        let n = sparse.count();
        let count = accessor.count();
        if n > count {
            return Err(err(format!(
                "has {n} sparse substitutions for {count} elements"
            )));
        }
        use gltf::accessor::sparse::IndexType;
        let index_type = sparse.indices().index_type();
        let index_size = match index_type {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        };
        let indices = self.view_bytes(
            &sparse.indices().view(),
            sparse.indices().offset(),
            n * index_size,
            element,
            "sparse indices",
        )?;
        let values = self.view_bytes(
            &sparse.values().view(),
            sparse.values().offset(),
            n * elem,
            element,
            "sparse values",
        )?;
        let mut previous: Option<usize> = None;
        for k in 0..n {
            let b = &indices[k * index_size..(k + 1) * index_size];
            let index = match index_type {
                IndexType::U8 => b[0] as usize,
                IndexType::U16 => u16::from_le_bytes([b[0], b[1]]) as usize,
                IndexType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if index >= count || previous.is_some_and(|p| index <= p) {
                return Err(err(format!(
                    "sparse index {k} is {index}: expected strictly increasing element indices \
                     below {count}"
                )));
            }
            previous = Some(index);
            for c in 0..ncomp {
                let o = k * elem + c * size;
                out[index * ncomp + c] = decode(accessor, &values[o..o + size]);
            }
        }
        Ok(())
    }

    /// `length` bytes of buffer view `view` from `offset`, bounds-checked against the view and
    /// its buffer.
    fn view_bytes(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        length: usize,
        element: &str,
        what: &str,
    ) -> Result<&[u8], FormatError> {
        let buffer = &self.data[view.buffer().index()];
        let fits_view = offset
            .checked_add(length)
            .is_some_and(|e| e <= view.length());
        let start = view.offset().checked_add(offset);
        let end = start.and_then(|s| s.checked_add(length));
        match (fits_view, start, end) {
            (true, Some(s), Some(e)) if e <= buffer.len() => Ok(&buffer[s..e]),
            _ => Err(invalid(
                &self.path,
                element,
                format!(
                    "its {what} ({length} bytes at offset {offset} of buffer view {}) exceed \
                     the view ({} bytes) or its buffer ({} bytes)",
                    view.index(),
                    view.length(),
                    buffer.len()
                ),
            )),
        }
    }

    /// Integer accessor (indices, joints): unsigned 8/16/32-bit, not normalised.
    pub fn read_indices(
        &self,
        accessor: &gltf::Accessor,
        what: &str,
        allowed: &[Dimensions],
    ) -> Result<Vec<u32>, FormatError> {
        if !matches!(
            accessor.data_type(),
            DataType::U8 | DataType::U16 | DataType::U32
        ) || accessor.normalized()
        {
            return Err(invalid(
                &self.path,
                format!("accessor {} ({what})", accessor.index()),
                format!(
                    "has component type {:?}{}, expected unsigned 8/16/32-bit integers",
                    accessor.data_type(),
                    if accessor.normalized() {
                        " (normalized)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        Ok(self
            .read(accessor, what, allowed)?
            .into_iter()
            .map(|v| v as u32)
            .collect())
    }
}

/// Bytes per component of `data_type`.
fn component_size(data_type: DataType) -> usize {
    match data_type {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// One component (`b`: its little-endian bytes) of `accessor` as f64, normalised integers
/// mapped to [0, 1] or [−1, 1] as the specification says (KHR_mesh_quantization's types too).
fn decode(accessor: &gltf::Accessor, b: &[u8]) -> f64 {
    let normalized = accessor.normalized();
    match accessor.data_type() {
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        DataType::U16 => {
            let x = u16::from_le_bytes([b[0], b[1]]) as f64;
            if normalized { x / 65535.0 } else { x }
        }
        DataType::I16 => {
            let x = i16::from_le_bytes([b[0], b[1]]) as f64;
            if normalized {
                (x / 32767.0).max(-1.0)
            } else {
                x
            }
        }
        DataType::U8 => {
            let x = b[0] as f64;
            if normalized { x / 255.0 } else { x }
        }
        DataType::I8 => {
            let x = b[0] as i8 as f64;
            if normalized { (x / 127.0).max(-1.0) } else { x }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_stay_inside_the_folder() {
        let dir = std::env::temp_dir().join(format!("cagerig-uri-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(dir.join("sub/a b.bin"), b"xy").unwrap();
        let file = dir.join("x.gltf");
        let ok = resolve_uri(&dir, "sub/a%20b.bin", &file, "buffer 0").unwrap();
        assert!(ok.ends_with("sub/a b.bin"));
        for bad in [
            "../x.bin",
            "/etc/passwd",
            "http://example.com/a.bin",
            "file:///etc/passwd",
            "sub/../../x",
        ] {
            let e = resolve_uri(&dir, bad, &file, "buffer 0")
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("refused") && e.contains("buffer 0"),
                "{bad}: {e}"
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
