//! Welding by position and connected pieces of a triangle soup.
//!
//! Real meshes duplicate vertices along UV or normal seams; cage generation only needs the
//! geometry, but the validator needs the connected pieces of the surface (a piece that never
//! touches the cage is wholly inside or wholly outside it), so seams must not split pieces.

use std::collections::HashMap;

use glam::DVec3;

/// Result of [`weld_by_position`].
#[derive(Debug, Clone, PartialEq)]
pub struct Welded {
    /// For each input vertex, its welded vertex (`#V` entries in `0..num_welded`).
    pub welded_of: Vec<u32>,
    /// Number of distinct welded vertices.
    pub num_welded: usize,
}

/// Merges vertices closer than `tolerance` (grid hashing with cell = tolerance, 27-cell
/// neighbourhood; a vertex joins the first earlier representative within the tolerance).
/// `tolerance = 0` merges exactly equal positions only.
pub fn weld_by_position(positions: &[DVec3], tolerance: f64) -> Welded {
    let mut welded_of = Vec::with_capacity(positions.len());
    let mut representatives: Vec<DVec3> = Vec::new();
    if tolerance <= 0.0 {
        let mut exact: HashMap<[u64; 3], u32> = HashMap::with_capacity(positions.len());
        for p in positions {
            // +0.0 so that -0.0 and 0.0 weld.
            let key = [
                (p.x + 0.0).to_bits(),
                (p.y + 0.0).to_bits(),
                (p.z + 0.0).to_bits(),
            ];
            let next = exact.len() as u32;
            welded_of.push(*exact.entry(key).or_insert(next));
        }
        let num_welded = exact.len();
        return Welded {
            welded_of,
            num_welded,
        };
    }
    let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(positions.len());
    let cell_of = |p: DVec3| (p / tolerance).floor().as_i64vec3().to_array();
    for p in positions {
        let c = cell_of(*p);
        let mut found = None;
        'search: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz])
                        && let Some(&r) = list
                            .iter()
                            .find(|&&r| representatives[r as usize].distance(*p) <= tolerance)
                    {
                        found = Some(r);
                        break 'search;
                    }
                }
            }
        }
        let r = found.unwrap_or_else(|| {
            let r = representatives.len() as u32;
            representatives.push(*p);
            cells.entry(c).or_default().push(r);
            r
        });
        welded_of.push(r);
    }
    Welded {
        welded_of,
        num_welded: representatives.len(),
    }
}

/// Connected pieces of a triangle soup after welding: for every piece, one input vertex
/// (the representative) — triangles sharing a welded vertex are connected; a vertex used by no
/// triangle is a piece of its own.
pub fn piece_representatives(
    num_vertices: usize,
    triangles: &[[u32; 3]],
    welded: &Welded,
) -> Vec<usize> {
    let mut parent: Vec<u32> = (0..welded.num_welded as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for tri in triangles {
        let w = tri.map(|v| welded.welded_of[v as usize]);
        for k in 1..3 {
            let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[k]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut seen = vec![false; welded.num_welded];
    let mut reps = Vec::new();
    for v in 0..num_vertices {
        let root = find(&mut parent, welded.welded_of[v]) as usize;
        if !seen[root] {
            seen[root] = true;
            reps.push(v);
        }
    }
    reps
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seams_weld_and_pieces_count() {
        // Two triangles sharing an edge through duplicated seam vertices, plus a far triangle.
        let p = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::X,
            DVec3::new(-0.0, 1.0, 0.0),
            DVec3::ONE,
            DVec3::splat(5.0),
            DVec3::splat(6.0),
            DVec3::new(5.0, 6.0, 5.0),
        ];
        let tris = [[0, 1, 2], [3, 5, 4], [6, 7, 8]];
        let exact = weld_by_position(&p, 0.0);
        assert_eq!(exact.num_welded, 7);
        assert_eq!(exact.welded_of[3], exact.welded_of[1]);
        assert_eq!(piece_representatives(p.len(), &tris, &exact), vec![0, 6]);
        let mut near = p.clone();
        near[3] += DVec3::splat(1e-9);
        assert_eq!(weld_by_position(&near, 1e-8).num_welded, 7);
        assert_eq!(weld_by_position(&near, 0.0).num_welded, 8);
    }
}
