//! Per-quadrature-point storage, laid out cell by cell (CSR offsets), for history variables
//! and output fields. With the structured annulus, [`crate::mesh::RingLayout::qp_ring`] maps a
//! (cell, point) pair to its ring and position, so a streamline is walked by visiting the cells
//! of one radial layer in order.

#[derive(Clone, Debug)]
pub struct QpData<T> {
    pub offsets: Vec<usize>,
    pub data: Vec<T>,
}

impl<T: Clone> QpData<T> {
    /// `per_cell[c]` points in cell `c`, all initialised to `init`.
    pub fn new(per_cell: impl IntoIterator<Item = usize>, init: T) -> Self {
        let mut offsets = vec![0];
        for n in per_cell {
            let last = *offsets.last().unwrap_or(&0);
            offsets.push(last + n);
        }
        let total = *offsets.last().unwrap_or(&0);
        Self {
            offsets,
            data: vec![init; total],
        }
    }
    pub fn cell(&self, c: usize) -> &[T] {
        &self.data[self.offsets[c]..self.offsets[c + 1]]
    }
    pub fn cell_mut(&mut self, c: usize) -> &mut [T] {
        &mut self.data[self.offsets[c]..self.offsets[c + 1]]
    }
}
