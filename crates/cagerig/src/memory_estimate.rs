//! Refusing requests too large for this machine up front (`subdivide --levels`, `bench
//! --subdivide`, `demo --resolution`, the editor's built-in rigs), with the memory they would
//! need, instead of an abort ("memory allocation failed") seconds later.

use crate::error::{MemoryNeed, RigError};

/// Bytes a session of `vertices` skin vertices and `cage_vertices` cage vertices needs, about:
/// Φ and the CoR coordinates Λ (`#V × #C` f64 each) plus the transient MaxVol and CoR tables
/// (≈ one more Φ), and ≈ 400 bytes per vertex of meshes, weights and scratch.
pub fn session_bytes(vertices: u64, cage_vertices: u64) -> u64 {
    vertices
        .saturating_mul(cage_vertices)
        .saturating_mul(8 * 3)
        .saturating_add(vertices.saturating_mul(400))
}

/// `MemAvailable` of /proc/meminfo, when known.
fn available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn gib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 30) as f64
}

/// Fails when `bytes` exceed the memory available now (`what` names the request).
pub fn check_fits(what: &str, vertices: u64, cage_vertices: u64) -> Result<(), RigError> {
    let bytes = session_bytes(vertices, cage_vertices);
    check_bytes_fit(what, vertices, cage_vertices, bytes, available_bytes())
}

fn check_bytes_fit(
    what: &str,
    vertices: u64,
    cage_vertices: u64,
    bytes: u64,
    available: Option<u64>,
) -> Result<(), RigError> {
    // Without /proc/meminfo, still refuse what no machine of today holds (1 TiB).
    let limit = available.unwrap_or(1 << 40);
    if bytes > limit {
        return Err(RigError::TooLarge(Box::new(MemoryNeed {
            what: what.to_string(),
            vertices,
            cage_vertices,
            needed_gib: gib(bytes),
            phi_gib: gib(vertices.saturating_mul(cage_vertices).saturating_mul(8)),
            limit_gib: gib(limit),
            limit: if available.is_some() {
                "are available"
            } else {
                "is the limit"
            },
        })));
    }
    Ok(())
}

/// About how many skin and cage vertices the built-in rig `name` has at `resolution` (see
/// [`crate::demo::builtin`]).
pub fn builtin_size(name: &str, resolution: Option<usize>) -> (u64, u64) {
    match name {
        "snake" => (resolution.unwrap_or(8192) as u64, 96),
        _ => ((resolution.unwrap_or(40) as u64).saturating_mul(24), 24),
    }
}

/// Vertices after `levels` rounds of midpoint subdivision of a mesh with `vertices` vertices and
/// `triangles` triangles: each round adds one vertex per edge (≈ 1.5 per triangle) and
/// multiplies the triangles by 4.
pub fn subdivided_vertices(vertices: u64, triangles: u64, levels: u32) -> u64 {
    let (mut v, mut t) = (vertices, triangles);
    for _ in 0..levels {
        v = v.saturating_add(t.saturating_mul(3).div_ceil(2));
        t = t.saturating_mul(4);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arm_levels() {
        // The Arm: 2,089 v, 4,156 t → 133,073 v at N = 3 (README), 34 M at N = 7.
        let v3 = subdivided_vertices(2089, 4156, 3);
        assert!((130_000..136_000).contains(&v3), "{v3}");
        let v8 = subdivided_vertices(2089, 4156, 8);
        assert!(v8 > 100_000_000);
        let e = check_bytes_fit(
            "subdivide --levels 8",
            v8,
            58,
            session_bytes(v8, 58),
            Some(24 << 30),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("GiB") && e.contains("subdivide --levels 8"),
            "{e}"
        );
        assert!(check_bytes_fit("N=3", v3, 58, session_bytes(v3, 58), Some(24 << 30)).is_ok());
    }
}
