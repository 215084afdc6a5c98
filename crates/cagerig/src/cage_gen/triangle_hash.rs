//! Dynamic spatial hash of the cage's triangles during simplification: a dense grid of cells,
//! each listing the triangles whose box overlaps it. Edge collapses remove and insert a few
//! triangles per step, which a static tree would have to refit; the hash updates in place.

use glam::DVec3;

use super::bvh::Aabb;

/// Triangles (by id) bucketed by the grid cells their boxes overlap.
#[derive(Debug, Clone)]
pub struct TriangleHash {
    origin: DVec3,
    cell: f64,
    dims: [usize; 3],
    cells: Vec<Vec<u32>>,
    /// Per triangle id: the cell range it was inserted in (empty when absent).
    ranges: Vec<Option<([usize; 3], [usize; 3])>>,
    /// Per triangle id: last query stamp that reported it (deduplication).
    stamps: Vec<u32>,
    stamp: u32,
}

impl TriangleHash {
    /// A hash over `bounds` with cubic cells of side `cell`.
    pub fn new(bounds: Aabb, cell: f64) -> Self {
        let extent = (bounds.max - bounds.min).max(DVec3::splat(cell));
        let dims = (extent / cell)
            .ceil()
            .as_uvec3()
            .to_array()
            .map(|n| (n as usize).max(1));
        Self {
            origin: bounds.min,
            cell,
            dims,
            cells: vec![Vec::new(); dims[0] * dims[1] * dims[2]],
            ranges: Vec::new(),
            stamps: Vec::new(),
            stamp: 0,
        }
    }

    fn cell_range(&self, b: &Aabb) -> ([usize; 3], [usize; 3]) {
        let clamp = |p: DVec3| {
            let c = ((p - self.origin) / self.cell).floor();
            std::array::from_fn(|k| (c[k].max(0.0) as usize).min(self.dims[k] - 1))
        };
        (clamp(b.min), clamp(b.max))
    }

    fn for_cells(&self, (lo, hi): ([usize; 3], [usize; 3]), mut f: impl FnMut(usize)) {
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    f(x + self.dims[0] * (y + self.dims[1] * z));
                }
            }
        }
    }

    /// Inserts triangle `id` with box `b`.
    pub fn insert(&mut self, id: u32, b: &Aabb) {
        let i = id as usize;
        if self.ranges.len() <= i {
            self.ranges.resize(i + 1, None);
            self.stamps.resize(i + 1, 0);
        }
        let range = self.cell_range(b);
        let mut cells = std::mem::take(&mut self.cells);
        self.for_cells(range, |c| cells[c].push(id));
        self.cells = cells;
        self.ranges[i] = Some(range);
    }

    /// Removes triangle `id` (no-op when absent).
    pub fn remove(&mut self, id: u32) {
        let Some(range) = self.ranges.get_mut(id as usize).and_then(Option::take) else {
            return;
        };
        let mut cells = std::mem::take(&mut self.cells);
        self.for_cells(range, |c| {
            if let Some(k) = cells[c].iter().position(|&t| t == id) {
                cells[c].swap_remove(k);
            }
        });
        self.cells = cells;
    }

    /// Calls `f` once with every triangle whose cells overlap box `b` (a superset of the
    /// triangles whose boxes overlap `b`).
    pub fn query(&mut self, b: &Aabb, mut f: impl FnMut(u32)) {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.iter_mut().for_each(|s| *s = 0);
            self.stamp = 1;
        }
        let range = self.cell_range(b);
        let (stamp, cells, stamps) = (self.stamp, &self.cells, &mut self.stamps);
        let (lo, hi) = range;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    for &t in &cells[x + self.dims[0] * (y + self.dims[1] * z)] {
                        if stamps[t as usize] != stamp {
                            stamps[t as usize] = stamp;
                            f(t);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn insert_query_remove() {
        let bounds = Aabb {
            min: DVec3::ZERO,
            max: DVec3::splat(10.0),
        };
        let mut hash = TriangleHash::new(bounds, 1.0);
        let tri = |p: DVec3| Aabb::of_triangle(&[p, p + DVec3::X * 2.5, p + DVec3::Y]);
        hash.insert(0, &tri(DVec3::splat(1.0)));
        hash.insert(1, &tri(DVec3::splat(7.0)));
        let mut hits = Vec::new();
        hash.query(&tri(DVec3::new(2.0, 1.5, 1.2)), |t| hits.push(t));
        assert_eq!(hits, vec![0]);
        hash.remove(0);
        hits.clear();
        hash.query(&bounds, |t| hits.push(t));
        assert_eq!(hits, vec![1]);
    }
}
