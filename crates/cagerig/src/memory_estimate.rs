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
            rows: "vertices",
            cage_vertices,
            needed_gib: gib(bytes),
            phi_gib: Some(gib(vertices
                .saturating_mul(cage_vertices)
                .saturating_mul(8))),
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

/// Checks that a dense `rows × cols` f64 matrix (Φ, Λ: `#V × #C`) can be allocated now, by
/// reserving its bytes and freeing them at once. faer aborts the process when an allocation
/// fails ("memory allocation failed"); the library calls this first, so that a request beyond
/// what the system will hand out is a [`RigError::TooLarge`] naming it instead.
pub fn check_dense_allocation(what: &str, rows: usize, cols: usize) -> Result<(), RigError> {
    check_table_allocation(what, rows, "vertices", cols)
}

/// [`check_dense_allocation`] for an intermediate `rows × cols` f64 table whose rows are
/// `rows_label` (MaxVol's B = ΦΦ̃⁻¹, the CoR similarity tables, …), before an allocation that
/// is not ours to make fallible (faer's).
pub fn check_table_allocation(
    what: &str,
    rows: usize,
    rows_label: &'static str,
    cols: usize,
) -> Result<(), RigError> {
    reserved_table(what, rows, rows_label, cols).map(drop)
}

/// A zeroed `rows × cols` f64 table (row- or column-major is the caller's), allocated
/// fallibly: a size the system refuses is a [`RigError::TooLarge`] naming `what` and its rows
/// (`rows_label`), not an abort.
pub fn zeroed_table(
    what: &str,
    rows: usize,
    rows_label: &'static str,
    cols: usize,
) -> Result<Vec<f64>, RigError> {
    let mut table = reserved_table(what, rows, rows_label, cols)?;
    table.resize(rows * cols, 0.0);
    Ok(table)
}

/// An empty vector with room for `rows × cols` f64, or the error of [`zeroed_table`].
fn reserved_table(
    what: &str,
    rows: usize,
    rows_label: &'static str,
    cols: usize,
) -> Result<Vec<f64>, RigError> {
    let entries = rows
        .checked_mul(cols)
        .filter(|n| n.checked_mul(8).is_some_and(|b| b <= isize::MAX as usize));
    if let Some(n) = entries {
        let mut table = Vec::<f64>::new();
        if table.try_reserve_exact(n).is_ok() {
            return Ok(table);
        }
    }
    let (vertices, cage_vertices) = (rows as u64, cols as u64);
    let bytes = vertices.saturating_mul(cage_vertices).saturating_mul(8);
    let available = available_bytes();
    Err(RigError::TooLarge(Box::new(MemoryNeed {
        what: what.to_string(),
        vertices,
        rows: rows_label,
        cage_vertices,
        needed_gib: gib(bytes),
        phi_gib: None,
        limit_gib: gib(available.unwrap_or(0)),
        limit: if available.is_some() {
            "are available (the allocation was refused)"
        } else {
            "could be reserved (the allocation was refused)"
        },
    })))
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

    #[test]
    fn a_dense_matrix_the_system_refuses_is_an_error_not_an_abort() {
        assert!(check_dense_allocation("Φ", 133_073, 58).is_ok());
        // 2^61 entries: the byte count overflows.
        let e = check_dense_allocation("cage coordinates Φ", 1 << 31, 1 << 30)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cage coordinates Φ") && e.contains("GiB"), "{e}");
        // 2^56 bytes (64 PiB): representable, but no system reserves it.
        let e = check_dense_allocation("Λ", 1 << 40, 1 << 13)
            .unwrap_err()
            .to_string();
        assert!(e.contains("refused"), "{e}");
    }

    #[test]
    fn tables_are_zeroed_or_refused_with_their_rows_named() {
        let table = zeroed_table("B", 3, "rows", 4).unwrap();
        assert_eq!(table, vec![0.0; 12]);
        assert!(zeroed_table("empty", 0, "rows", 4).unwrap().is_empty());
        let e = zeroed_table("CoR similarity tables", 1 << 40, "grid nodes", 1 << 13)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("CoR similarity tables")
                && e.contains("grid nodes")
                && !e.contains("Φ alone"),
            "{e}"
        );
        let e = check_table_allocation("MaxVol B", usize::MAX, "candidate rows", 2)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("MaxVol B") && e.contains("candidate rows"),
            "{e}"
        );
    }
}
