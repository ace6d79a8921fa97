//! O(N) neighbour search on a uniform cell grid.
//!
//! Particles are binned by a counting sort into cells of edge `2 R_max + skin` (enlarged when
//! the box would need more than `4N + 64` cells, so memory stays O(N)); each particle then
//! scans the 27 (3D) or 9 (planar) surrounding cells. Pairs come out sorted by `(a, b)`,
//! independent of thread count. Buffers are reused between searches.

use crate::state::ParticleState;
use crate::vec3::Vec3;

/// Reusable buffers of the cell grid.
#[derive(Debug, Clone, Default)]
pub struct CellGrid {
    cell_of: Vec<u32>,
    cell_start: Vec<u32>,
    sorted: Vec<u32>,
    scratch: Vec<u32>,
    origin: Vec3,
    cell_size: f64,
    dims: [usize; 3],
}

impl CellGrid {
    fn cell_coords(&self, p: Vec3) -> [usize; 3] {
        let c = |v: f64, o: f64, d: usize| -> usize {
            let k = ((v - o) / self.cell_size).floor();
            if k <= 0.0 { 0 } else { (k as usize).min(d - 1) }
        };
        [
            c(p.x, self.origin.x, self.dims[0]),
            c(p.y, self.origin.y, self.dims[1]),
            c(p.z, self.origin.z, self.dims[2]),
        ]
    }

    fn bin(&mut self, position: &[Vec3], min_cell: f64) {
        let n = position.len();
        let mut lo = Vec3::new(f64::MAX, f64::MAX, f64::MAX);
        let mut hi = Vec3::new(f64::MIN, f64::MIN, f64::MIN);
        for p in position {
            lo = Vec3::new(lo.x.min(p.x), lo.y.min(p.y), lo.z.min(p.z));
            hi = Vec3::new(hi.x.max(p.x), hi.y.max(p.y), hi.z.max(p.z));
        }
        let extent = hi - lo;
        let max_cells = 4 * n + 64;
        let mut h = min_cell.max(f64::MIN_POSITIVE);
        let dims_for = |h: f64| -> [usize; 3] {
            [
                (extent.x / h) as usize + 1,
                (extent.y / h) as usize + 1,
                (extent.z / h) as usize + 1,
            ]
        };
        let mut dims = dims_for(h);
        while dims[0].saturating_mul(dims[1]).saturating_mul(dims[2]) > max_cells {
            h *= 1.5;
            dims = dims_for(h);
        }
        self.origin = lo;
        self.cell_size = h;
        self.dims = dims;
        let n_cells = dims[0] * dims[1] * dims[2];
        // Reserve the largest grid once, so a growing bounding box never reallocates.
        self.cell_start.clear();
        self.cell_start.reserve(max_cells + 1);
        self.scratch.reserve(max_cells + 1);
        self.cell_of.clear();
        self.cell_start.clear();
        self.cell_start.resize(n_cells + 1, 0);
        for p in position {
            let [i, j, k] = self.cell_coords(*p);
            let cell = (i + dims[0] * (j + dims[1] * k)) as u32;
            self.cell_of.push(cell);
            self.cell_start[cell as usize + 1] += 1;
        }
        for c in 0..n_cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.sorted.clear();
        self.sorted.resize(n, 0);
        // Fill in particle order so each cell lists its particles ascending.
        self.scratch.clear();
        self.scratch.extend_from_slice(&self.cell_start[..n_cells]);
        for (i, &cell) in self.cell_of.iter().enumerate() {
            let slot = &mut self.scratch[cell as usize];
            self.sorted[*slot as usize] = i as u32;
            *slot += 1;
        }
    }

    /// All pairs `a < b` with `|x_b − x_a| < R_a + R_b + gap`, sorted, written to `out`.
    pub fn pairs_within(&mut self, particles: &ParticleState, gap: f64, out: &mut Vec<[u32; 2]>) {
        out.clear();
        let n = particles.len();
        if n < 2 {
            return;
        }
        let r_max = particles.radius.iter().fold(0.0_f64, |m, &r| m.max(r));
        self.bin(&particles.position, 2.0 * r_max + gap);
        let mut found: Vec<u32> = std::mem::take(&mut self.scratch);
        for a in 0..n {
            found.clear();
            let pa = particles.position[a];
            let ra = particles.radius[a];
            let [ci, cj, ck] = self.cell_coords(pa);
            let range = |c: usize, d: usize| c.saturating_sub(1)..=(c + 1).min(d - 1);
            for k in range(ck, self.dims[2]) {
                for j in range(cj, self.dims[1]) {
                    for i in range(ci, self.dims[0]) {
                        let cell = i + self.dims[0] * (j + self.dims[1] * k);
                        let (s, e) = (
                            self.cell_start[cell] as usize,
                            self.cell_start[cell + 1] as usize,
                        );
                        for &b in &self.sorted[s..e] {
                            let bu = b as usize;
                            if bu <= a {
                                continue;
                            }
                            let reach = ra + particles.radius[bu] + gap;
                            if (particles.position[bu] - pa).norm_squared() < reach * reach {
                                found.push(b);
                            }
                        }
                    }
                }
            }
            found.sort_unstable();
            out.extend(found.iter().map(|&b| [a as u32, b]));
        }
        self.scratch = found;
    }
}

/// All pairs `(a, b)`, `a < b`, whose surfaces are closer than `gap` (or overlap), sorted.
pub fn pairs_within(particles: &ParticleState, gap: f64) -> Vec<(usize, usize)> {
    let mut grid = CellGrid::default();
    let mut out = Vec::new();
    grid.pairs_within(particles, gap, &mut out);
    out.iter().map(|p| (p[0] as usize, p[1] as usize)).collect()
}
