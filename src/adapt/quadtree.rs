//! A forest of quadtrees of axis-aligned square cells, kept one-irregular (2:1 balanced across
//! edges), with refinement and coarsening.
//!
//! The coarse mesh is a set of unit squares of side `h0` on an integer grid; cell corners are
//! integer coordinates in units of `h0 / 2^MAX_LEVEL` (exact arithmetic for neighbour search).
//! Physical point: x = origin + h0 · i / 2^MAX_LEVEL. A cell of level l has side
//! 2^(MAX_LEVEL − l) integer units. Edges are oriented along +x and +y, so every cell sees a
//! shared edge with the same orientation (no sign flips for odd edge modes).
//!
//! One-irregular: two leaves sharing a part of an edge differ by at most one level, so an edge
//! carries at most one hanging vertex (its midpoint).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A fast multiplicative hasher for integer keys (the default SipHash dominated mesh building).
#[derive(Default, Clone, Copy)]
pub struct FxHasher(u64);

impl Hasher for FxHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_i64(&mut self, i: i64) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    #[inline]
    fn finish(&self) -> u64 {
        // Keys are grid coordinates with many trailing zero bits: fold the high bits down
        // (splitmix64 finaliser) so the table's low-bit bucket index is well spread.
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

/// HashMap with [`FxHasher`].
pub type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;

/// Finest level representable.
pub const MAX_LEVEL: u32 = 28;
const NONE: u32 = u32::MAX;

/// One cell of the forest (leaf or refined).
#[derive(Clone, Debug)]
pub struct Cell {
    pub level: u32,
    /// Integer coordinates of the lower-left corner.
    pub ix: i64,
    pub iy: i64,
    pub parent: u32,
    /// Children in order (lower-left, lower-right, upper-left, upper-right), or `None`.
    pub children: Option<[u32; 4]>,
    /// Polynomial degree (leaves).
    pub degree: u8,
    pub alive: bool,
}

/// The four sides: 0 left (x = x0), 1 right, 2 bottom (y = y0), 3 top.
pub const SIDES: [usize; 4] = [0, 1, 2, 3];

/// What lies across one side of a leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Across {
    Boundary,
    /// A leaf of the same level.
    Same(u32),
    /// A leaf one level coarser: this side is half of its side.
    Coarser(u32),
    /// The neighbour of the same level is refined: two leaves one level finer.
    Finer([u32; 2]),
}

#[derive(Clone, Debug)]
pub struct Quadtree {
    pub origin: [f64; 2],
    pub h0: f64,
    pub cells: Vec<Cell>,
    map: FxMap<(u32, i64, i64), u32>,
}

#[inline]
pub fn size_of_level(level: u32) -> i64 {
    1i64 << (MAX_LEVEL - level)
}

impl Quadtree {
    /// Forest of coarse squares `(i, j)` (lower-left corner at origin + h0·(i, j)), degree `p`.
    pub fn new(origin: [f64; 2], h0: f64, coarse: &[(i64, i64)], p: u8) -> Self {
        let mut t = Self {
            origin,
            h0,
            cells: Vec::new(),
            map: FxMap::default(),
        };
        for &(i, j) in coarse {
            t.push(Cell {
                level: 0,
                ix: i << MAX_LEVEL,
                iy: j << MAX_LEVEL,
                parent: NONE,
                children: None,
                degree: p,
                alive: true,
            });
        }
        t
    }

    /// The L-shaped domain (−1, 1)² \ [0, 1) × (−1, 0] as three unit squares, uniformly refined
    /// `levels` times.
    pub fn l_shape(levels: u32, p: u8) -> Self {
        let mut t = Self::new([-1.0, -1.0], 1.0, &[(0, 0), (0, 1), (1, 1)], p);
        for _ in 0..levels {
            let leaves = t.leaves();
            t.refine(&leaves);
        }
        t
    }

    fn push(&mut self, c: Cell) -> u32 {
        let id = self.cells.len() as u32;
        self.map.insert((c.level, c.ix, c.iy), id);
        self.cells.push(c);
        id
    }

    /// Leaves in a deterministic order (depth-first from the coarse cells).
    pub fn leaves(&self) -> Vec<u32> {
        let mut out = Vec::new();
        let mut stack: Vec<u32> = (0..self.cells.len() as u32)
            .filter(|&c| self.cells[c as usize].alive && self.cells[c as usize].parent == NONE)
            .rev()
            .collect();
        while let Some(c) = stack.pop() {
            match self.cells[c as usize].children {
                None => out.push(c),
                Some(ch) => stack.extend(ch.iter().rev()),
            }
        }
        out
    }

    pub fn is_leaf(&self, c: u32) -> bool {
        self.cells[c as usize].children.is_none()
    }

    /// Side length of cell `c`.
    pub fn h(&self, c: u32) -> f64 {
        self.h0 / (1u64 << self.cells[c as usize].level) as f64
    }

    /// Physical lower-left corner of cell `c`.
    pub fn corner(&self, c: u32) -> [f64; 2] {
        let cell = &self.cells[c as usize];
        [self.to_x(cell.ix, 0), self.to_x(cell.iy, 1)]
    }

    #[inline]
    pub fn to_x(&self, i: i64, dim: usize) -> f64 {
        self.origin[dim] + self.h0 * (i as f64) / (1u64 << MAX_LEVEL) as f64
    }

    /// Map from the reference square [-1, 1]² of cell `c` to physical coordinates.
    #[inline]
    pub fn map_point(&self, c: u32, xi: f64, eta: f64) -> [f64; 2] {
        let [x0, y0] = self.corner(c);
        let h = self.h(c);
        [x0 + 0.5 * h * (xi + 1.0), y0 + 0.5 * h * (eta + 1.0)]
    }

    fn find(&self, level: u32, ix: i64, iy: i64) -> Option<u32> {
        self.map
            .get(&(level, ix, iy))
            .copied()
            .filter(|&c| self.cells[c as usize].alive)
    }

    /// The leaf containing integer point (px, py) (half-open cells), if any.
    pub fn leaf_at_int(&self, px: i64, py: i64) -> Option<u32> {
        let s0 = size_of_level(0);
        let mut c = self.find(0, px.div_euclid(s0) * s0, py.div_euclid(s0) * s0)?;
        loop {
            let cell = &self.cells[c as usize];
            match cell.children {
                None => return Some(c),
                Some(ch) => {
                    let half = size_of_level(cell.level + 1);
                    let i = ((px - cell.ix) >= half) as usize;
                    let j = ((py - cell.iy) >= half) as usize;
                    c = ch[i + 2 * j];
                }
            }
        }
    }

    /// The leaf containing the physical point x, and the point's reference coordinates in it.
    /// Points on a cell boundary go to the cell above/right, except at the domain's upper and
    /// right edges, where the cell below/left is tried.
    pub fn locate(&self, x: [f64; 2]) -> Option<(u32, f64, f64)> {
        let scale = (1u64 << MAX_LEVEL) as f64 / self.h0;
        let px = ((x[0] - self.origin[0]) * scale).floor() as i64;
        let py = ((x[1] - self.origin[1]) * scale).floor() as i64;
        for (dx, dy) in [(0, 0), (-1, 0), (0, -1), (-1, -1)] {
            if let Some(c) = self.leaf_at_int(px + dx, py + dy) {
                let [x0, y0] = self.corner(c);
                let h = self.h(c);
                let xi = 2.0 * (x[0] - x0) / h - 1.0;
                let eta = 2.0 * (x[1] - y0) / h - 1.0;
                if (-1.0 - 1e-9..=1.0 + 1e-9).contains(&xi)
                    && (-1.0 - 1e-9..=1.0 + 1e-9).contains(&eta)
                {
                    return Some((c, xi.clamp(-1.0, 1.0), eta.clamp(-1.0, 1.0)));
                }
            }
        }
        None
    }

    /// What lies across side `side` of leaf `c`.
    pub fn across(&self, c: u32, side: usize) -> Across {
        let cell = &self.cells[c as usize];
        let s = size_of_level(cell.level);
        let (nx, ny) = match side {
            0 => (cell.ix - s, cell.iy),
            1 => (cell.ix + s, cell.iy),
            2 => (cell.ix, cell.iy - s),
            _ => (cell.ix, cell.iy + s),
        };
        if let Some(n) = self.find(cell.level, nx, ny) {
            let ncell = &self.cells[n as usize];
            return match ncell.children {
                None => Across::Same(n),
                Some(ch) => {
                    // Children of the neighbour touching our side.
                    let pair = match side {
                        0 => [ch[1], ch[3]],
                        1 => [ch[0], ch[2]],
                        2 => [ch[2], ch[3]],
                        _ => [ch[0], ch[1]],
                    };
                    Across::Finer(pair)
                }
            };
        }
        if cell.level == 0 {
            return Across::Boundary;
        }
        match self.leaf_at_int(nx, ny) {
            Some(n) if self.cells[n as usize].level < cell.level => Across::Coarser(n),
            Some(n) => Across::Same(n),
            None => Across::Boundary,
        }
    }

    /// Refine the leaves `marked` (others are refined as needed to keep the mesh one-irregular).
    pub fn refine(&mut self, marked: &[u32]) {
        for &c in marked {
            self.refine_one(c);
        }
    }

    fn refine_one(&mut self, c: u32) {
        if !self.is_leaf(c) || !self.cells[c as usize].alive {
            return;
        }
        let level = self.cells[c as usize].level;
        if level + 1 >= MAX_LEVEL {
            return;
        }
        // Balance first: a coarser leaf across any side must be refined.
        for side in SIDES {
            if let Across::Coarser(n) = self.across(c, side) {
                self.refine_one(n);
            }
        }
        let (ix, iy, p) = {
            let cell = &self.cells[c as usize];
            (cell.ix, cell.iy, cell.degree)
        };
        let s = size_of_level(level + 1);
        let mut ch = [0u32; 4];
        for (k, chk) in ch.iter_mut().enumerate() {
            let (i, j) = ((k % 2) as i64, (k / 2) as i64);
            let key = (level + 1, ix + i * s, iy + j * s);
            // A dead cell with the same key (coarsened earlier) is revived.
            *chk = match self.map.get(&key) {
                Some(&id) => {
                    let cell = &mut self.cells[id as usize];
                    cell.alive = true;
                    cell.children = None;
                    cell.degree = p;
                    id
                }
                None => self.push(Cell {
                    level: level + 1,
                    ix: ix + i * s,
                    iy: iy + j * s,
                    parent: c,
                    children: None,
                    degree: p,
                    alive: true,
                }),
            };
        }
        self.cells[c as usize].children = Some(ch);
    }

    /// Coarsen: every refined cell whose four children are leaves all listed in `marked` is
    /// made a leaf again, unless that would break one-irregularity. Returns the number of
    /// cells coarsened.
    pub fn coarsen(&mut self, marked: &[u32]) -> usize {
        let set: std::collections::HashSet<u32> = marked.iter().copied().collect();
        let mut parents: Vec<u32> = marked
            .iter()
            .map(|&c| self.cells[c as usize].parent)
            .filter(|&p| p != NONE)
            .collect();
        parents.sort_unstable();
        parents.dedup();
        let mut n = 0;
        for p in parents {
            let Some(ch) = self.cells[p as usize].children else {
                continue;
            };
            if !ch.iter().all(|&c| self.is_leaf(c) && set.contains(&c)) {
                continue;
            }
            if !self.can_coarsen(p) {
                continue;
            }
            let deg = ch
                .iter()
                .map(|&c| self.cells[c as usize].degree)
                .max()
                .unwrap_or(1);
            for c in ch {
                self.cells[c as usize].alive = false;
            }
            self.cells[p as usize].children = None;
            self.cells[p as usize].degree = deg;
            n += 1;
        }
        n
    }

    /// Making `p` a leaf keeps the mesh one-irregular: no leaf across any of its sides is
    /// more than one level finer than `p`, i.e. the neighbour's children along that side are
    /// leaves.
    fn can_coarsen(&self, p: u32) -> bool {
        for side in SIDES {
            let cell = &self.cells[p as usize];
            let s = size_of_level(cell.level);
            let (nx, ny) = match side {
                0 => (cell.ix - s, cell.iy),
                1 => (cell.ix + s, cell.iy),
                2 => (cell.ix, cell.iy - s),
                _ => (cell.ix, cell.iy + s),
            };
            if let Some(n) = self.find(cell.level, nx, ny) {
                if let Some(ch) = self.cells[n as usize].children {
                    let pair = match side {
                        0 => [ch[1], ch[3]],
                        1 => [ch[0], ch[2]],
                        2 => [ch[2], ch[3]],
                        _ => [ch[0], ch[1]],
                    };
                    if pair.iter().any(|&c| !self.is_leaf(c)) {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// Check one-irregularity of the leaves (tests).
    pub fn is_balanced(&self) -> bool {
        for c in self.leaves() {
            for side in SIDES {
                if let Across::Finer(pair) = self.across(c, side) {
                    if pair.iter().any(|&f| !self.is_leaf(f)) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refine_balances_and_coarsen_restores() {
        let mut t = Quadtree::l_shape(1, 1);
        assert_eq!(t.leaves().len(), 12);
        // Refine repeatedly towards the re-entrant corner (0, 0).
        for _ in 0..5 {
            let marked: Vec<u32> = t
                .leaves()
                .into_iter()
                .filter(|&c| {
                    let [x0, y0] = t.corner(c);
                    let h = t.h(c);
                    x0 <= 0.0 && 0.0 <= x0 + h && y0 <= 0.0 && 0.0 <= y0 + h
                })
                .collect();
            t.refine(&marked);
            assert!(t.is_balanced());
        }
        let area: f64 = t.leaves().iter().map(|&c| t.h(c).powi(2)).sum();
        assert!((area - 3.0).abs() < 1e-12);
        // Locate round-trips.
        for &c in &t.leaves() {
            let x = t.map_point(c, 0.3, -0.2);
            let (c2, xi, eta) = t.locate(x).unwrap();
            assert_eq!(c, c2);
            assert!((xi - 0.3).abs() < 1e-9 && (eta + 0.2).abs() < 1e-9);
        }
        assert!(t.locate([0.5, -0.5]).is_none());
        // Coarsen everything repeatedly: back to the 12 cells of level 1 (level-0 parents have
        // no parent to coarsen into beyond that if all leaves are marked).
        for _ in 0..10 {
            let leaves = t.leaves();
            t.coarsen(&leaves);
            assert!(t.is_balanced());
        }
        assert_eq!(t.leaves().len(), 3);
    }
}
