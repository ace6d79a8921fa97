//! The regular 2D background grid: square cells of edge `l_e`, nodes numbered row by row.

use crate::error::MpmError;
use serde::{Deserialize, Serialize};

/// Parameters of the background grid (serde form, validated by [`Grid::new`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridParameters {
    /// Lower-left corner of the grid (m).
    pub origin: [f64; 2],
    /// Edge length of the square cells, `l_e` of B-Eqs. 30–31 (m).
    pub cell_size: f64,
    /// Number of cells along x and y (at least 2 each, so every point sees 3 × 3 nodes).
    pub cells: [usize; 2],
}

/// A validated regular grid. Node `(i, j)` sits at `origin + (i, j) · cell_size` and has the
/// flat index `j · nodes[0] + i`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Grid {
    origin: [f64; 2],
    cell_size: f64,
    cells: [usize; 2],
}

impl Grid {
    /// Validates the parameters.
    pub fn new(p: &GridParameters) -> Result<Self, MpmError> {
        for (k, name) in [(0, "grid.origin[0]"), (1, "grid.origin[1]")] {
            if !p.origin[k].is_finite() {
                return Err(MpmError::InvalidParameter {
                    name: name.into(),
                    value: p.origin[k],
                    allowed: "finite",
                });
            }
        }
        if !(p.cell_size.is_finite() && p.cell_size > 0.0) {
            return Err(MpmError::InvalidParameter {
                name: "grid.cell_size".into(),
                value: p.cell_size,
                allowed: "(0, inf) m",
            });
        }
        for (k, name) in [(0, "grid.cells[0]"), (1, "grid.cells[1]")] {
            if p.cells[k] < 2 || p.cells[k] > (1 << 24) {
                return Err(MpmError::InvalidParameter {
                    name: name.into(),
                    value: p.cells[k] as f64,
                    allowed: "[2, 2^24]",
                });
            }
        }
        Ok(Self {
            origin: p.origin,
            cell_size: p.cell_size,
            cells: p.cells,
        })
    }

    /// Lower-left corner (m).
    pub fn origin(&self) -> [f64; 2] {
        self.origin
    }
    /// Cell edge `l_e` (m).
    pub fn cell_size(&self) -> f64 {
        self.cell_size
    }
    /// Cells along x and y.
    pub fn cells(&self) -> [usize; 2] {
        self.cells
    }
    /// Nodes along x and y (`cells + 1`).
    pub fn nodes(&self) -> [usize; 2] {
        [self.cells[0] + 1, self.cells[1] + 1]
    }
    /// Total number of nodes.
    pub fn node_count(&self) -> usize {
        (self.cells[0] + 1) * (self.cells[1] + 1)
    }
    /// Upper-right corner (m).
    pub fn upper(&self) -> [f64; 2] {
        [
            self.origin[0] + self.cells[0] as f64 * self.cell_size,
            self.origin[1] + self.cells[1] as f64 * self.cell_size,
        ]
    }
    /// Flat index of node `(i, j)`.
    #[inline]
    pub fn node_index(&self, i: usize, j: usize) -> usize {
        j * (self.cells[0] + 1) + i
    }
    /// Position of node `(i, j)` (m).
    #[inline]
    pub fn node_position(&self, i: usize, j: usize) -> [f64; 2] {
        [
            self.origin[0] + i as f64 * self.cell_size,
            self.origin[1] + j as f64 * self.cell_size,
        ]
    }
    /// Positions of all nodes in flat order (m), for output.
    pub fn node_positions(&self) -> Vec<[f64; 2]> {
        let [nx, ny] = self.nodes();
        let mut out = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                out.push(self.node_position(i, j));
            }
        }
        out
    }
}
