//! Periodic neighbour search on a cell grid in reduced coordinates.
//!
//! The unit square of reduced coordinates is cut into `n_0 × n_1` bins with
//! `n_k = ⌊w_k / reach⌋`, `w_k` the perpendicular width of the cell across axis `k` and
//! `reach = 2 R_max + skin`: two disks closer than `reach` differ by less than `1/n_k` in
//! reduced coordinate `k`, so the 3 × 3 bins around a disk (wrapped periodically) hold all its
//! neighbours. For fewer than 3 bins along an axis every pair is tested. Pairs come out sorted,
//! so the list does not depend on anything but the positions.

use crate::cell::PeriodicCell;
use crate::error::RveError;
use thm_dem::Vec3;

/// A candidate pair `[a, b]` (`a < b`) with the image shift of `b`.
pub type Candidate = ([u32; 2], [i32; 2]);

/// Reusable buffers of the periodic grid.
#[derive(Debug, Clone, Default)]
pub struct PeriodicGrid {
    bin_of: Vec<u32>,
    bin_start: Vec<u32>,
    sorted: Vec<u32>,
    cursor: Vec<u32>,
    reduced: Vec<Vec3>,
}

impl PeriodicGrid {
    /// Heap memory of the buffers \[bytes\].
    pub fn heap_bytes(&self) -> usize {
        fn cap<T>(v: &Vec<T>) -> usize {
            v.capacity() * std::mem::size_of::<T>()
        }
        cap(&self.bin_of)
            + cap(&self.bin_start)
            + cap(&self.sorted)
            + cap(&self.cursor)
            + cap(&self.reduced)
    }

    /// All pairs whose periodic gap is below `skin`, sorted by pair. `position` must lie in the
    /// cell (reduced coordinates in `[0, 1)`). Fails with [`RveError::CellTooSmall`] when the
    /// cell is narrower than twice the reach (a pair could then touch two images).
    pub fn pairs_within(
        &mut self,
        cell: &PeriodicCell,
        position: &[Vec3],
        radius: &[f64],
        skin: f64,
        out: &mut Vec<Candidate>,
    ) -> Result<(), RveError> {
        out.clear();
        let n = position.len();
        let r_max = radius.iter().fold(0.0_f64, |m, &r| m.max(r));
        let reach = 2.0 * r_max + skin;
        let mut dims = [0usize; 2];
        for (k, d) in dims.iter_mut().enumerate() {
            let width = cell.width(k);
            if !width.is_finite() || width < 2.0 * reach {
                return Err(RveError::CellTooSmall {
                    axis: k,
                    width,
                    minimum: 2.0 * reach,
                });
            }
            *d = ((width / reach).floor() as usize).clamp(1, 1 << 12);
        }
        self.reduced.clear();
        self.reduced
            .extend(position.iter().map(|&x| cell.to_reduced(x)));
        let h = *cell.matrix();
        let test = |a: usize, b: usize, ra: &Vec3, rb: &Vec3, out: &mut Vec<Candidate>| {
            let d = *rb - *ra;
            let s = [-(d.x.round() as i32), -(d.y.round() as i32)];
            let branch = h.apply(Vec3::new(d.x + f64::from(s[0]), d.y + f64::from(s[1]), 0.0));
            let cutoff = radius[a] + radius[b] + skin;
            if branch.norm_squared() < cutoff * cutoff {
                out.push(([a as u32, b as u32], s));
            }
        };
        if dims[0] < 3 || dims[1] < 3 {
            for a in 0..n {
                for b in a + 1..n {
                    test(a, b, &self.reduced[a], &self.reduced[b], out);
                }
            }
            return Ok(());
        }
        let bins = dims[0] * dims[1];
        let coord = |v: f64, d: usize| -> usize {
            let k = (v * d as f64).floor();
            if k <= 0.0 { 0 } else { (k as usize).min(d - 1) }
        };
        self.bin_of.clear();
        self.bin_of.extend(
            self.reduced
                .iter()
                .map(|r| (coord(r.x, dims[0]) + dims[0] * coord(r.y, dims[1])) as u32),
        );
        self.bin_start.clear();
        self.bin_start.resize(bins + 1, 0);
        for &c in &self.bin_of {
            self.bin_start[c as usize + 1] += 1;
        }
        for c in 0..bins {
            self.bin_start[c + 1] += self.bin_start[c];
        }
        self.sorted.clear();
        self.sorted.resize(n, 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.bin_start[..bins]);
        for (i, &c) in self.bin_of.iter().enumerate() {
            self.sorted[self.cursor[c as usize] as usize] = i as u32;
            self.cursor[c as usize] += 1;
        }
        for a in 0..n {
            let c = self.bin_of[a] as usize;
            let (cx, cy) = (c % dims[0], c / dims[0]);
            for dy in [dims[1] - 1, 0, 1] {
                let y = (cy + dy) % dims[1];
                for dx in [dims[0] - 1, 0, 1] {
                    let x = (cx + dx) % dims[0];
                    let bin = x + dims[0] * y;
                    let (lo, hi) = (
                        self.bin_start[bin] as usize,
                        self.bin_start[bin + 1] as usize,
                    );
                    for &b in &self.sorted[lo..hi] {
                        let b = b as usize;
                        if b > a {
                            test(a, b, &self.reduced[a], &self.reduced[b], out);
                        }
                    }
                }
            }
        }
        out.sort_unstable_by_key(|c| c.0);
        Ok(())
    }
}
