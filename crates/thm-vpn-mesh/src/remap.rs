//! Conservative transfer of extensive cell fields from an old mesh to a new one.
//!
//! [`RemapOperator::new`] intersects every old triangle with the new triangles it touches
//! and stores the overlap areas `A(o ∩ n)` as a sparse old → new matrix. The new cell holding
//! the old cell's centroid is found by a visibility walk from the previous old cell's seed
//! (old cells that follow each other are neighbours, see the mesher's locality order), or,
//! where the walk fails, in a uniform bin grid of the new cells; from it a breadth-first walk over
//! the new mesh's faces visits the new cells meeting the old one (the new cells meeting a
//! convex cell form an edge-connected set) and stops when the overlaps found cover the old
//! cell (to 10⁻⁹ of its area). Each pair is intersected by [`triangle_overlap_area`]: a
//! separating-edge test, then Sutherland–Hodgman clipping by the edges that cut, in fixed
//! buffers. [`RemapOperator::apply`] moves an extensive field
//! `q` (a phase mass, an energy) with it:
//!
//! - the admissible new cells of an old cell `o` are those of the field's [`CellFilter`]
//!   (fluid fields go only to fluid cells; solid fields to cells of the same sphere);
//! - `q_o` is split over the admissible cells that overlap `o`, in proportion to the overlap
//!   areas, normalised by their sum (so the part of `o` now covered by cells of the other kind
//!   does not lose its content: it is spread over the admissible part of `o`); the last share
//!   is `q_o` minus the others, so each old cell's content is handed on exactly;
//! - if no admissible cell overlaps `o` (a pore closed, a crack opened elsewhere), `q_o` goes to
//!   the admissible new cell nearest to `o`: a breadth-first search over the new mesh's faces
//!   starts from the cells overlapping `o` (or, if `o` overlaps no new cell — it lies outside
//!   the new mesh or turned inside out — from the new cell holding `o`'s centroid, else from the
//!   new cell with the nearest centroid, found by [`RemapOperator::new`] in a grid of the new
//!   centroids) and takes, in the first layer that
//!   holds admissible cells, the one whose centroid is nearest to `o`'s.
//!
//! The new total therefore equals the old total up to the rounding of the sums (relative
//! error of order `n_cells · ε`). Intensive fields (pressure, temperature) are not remapped:
//! they are recomputed from the remapped masses and energies (A-Sect. 2.4).

use std::collections::VecDeque;

use crate::error::MeshError;
use crate::mesh::{CellKind, NONE, PoreMesh};

/// Which new cells may receive a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellFilter {
    /// Fluid cells only (phase masses, fluid energy).
    Fluid,
    /// Solid cells of the same owner as the old cell (solid energy); falls back to any solid
    /// cell when the owner has none nearby.
    SameOwner,
    /// Any cell.
    Any,
}

impl CellFilter {
    fn name(self) -> &'static str {
        match self {
            CellFilter::Fluid => "fluid",
            CellFilter::SameOwner => "solid",
            CellFilter::Any => "any",
        }
    }
}

/// The sparse overlap matrix between an old and a new mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct RemapOperator {
    offsets: Vec<u32>,
    target: Vec<u32>,
    area: Vec<f64>,
    /// For each old cell without overlaps (ascending): the new cell holding its centroid, or
    /// else the new cell with the nearest centroid.
    nearest_new: Vec<(u32, u32)>,
    old_kind: Vec<CellKind>,
    old_centroid: Vec<[f64; 2]>,
    new_kind: Vec<CellKind>,
    new_centroid: Vec<[f64; 2]>,
    new_adjacency: Vec<[u32; 3]>,
}

/// Largest vertex count of a triangle clipped by three half-planes (6), with room for the
/// extra crossings round-off can create on near-degenerate input.
const CLIP_CAPACITY: usize = 8;

/// The walk over the new cells meeting an old cell stops once the overlaps found add up to
/// this fraction of the old cell's area (what is left can only be slivers of relative size
/// below 10⁻⁹, far below the accuracy of the fields moved; totals are exact regardless).
const COVERED_FRACTION: f64 = 1.0 - 1e-9;

/// `(p1 − p0) × (q − p0)`: positive when `q` is left of the directed line `p0 → p1`.
#[inline(always)]
fn orient(p0: [f64; 2], p1: [f64; 2], q: [f64; 2]) -> f64 {
    (p1[0] - p0[0]) * (q[1] - p0[1]) - (p1[1] - p0[1]) * (q[0] - p0[0])
}

/// Area of the intersection of two counter-clockwise triangles \[m²\].
///
/// Both triangles are first moved to a local origin (`a`'s first corner), so the result
/// does not lose digits to the distance from the global origin. The nine orientations of
/// `a`'s corners against `b`'s edges decide the common cases at once: an edge with all of
/// `a` on its outer side separates them (area 0, exactly); `a` inside `b` gives `a`'s area.
/// Otherwise `a` is clipped by the edges of `b` that cut it (Sutherland–Hodgman) in two
/// fixed-size buffers, with no allocation, and the area is that of the clipped polygon.
///
/// Each clipping step is compiled once per polygon size (`clip_by_edge` is generic over
/// it), so its loops are unrolled; a polygon vertex is written whether or not it is kept
/// and kept by advancing the output count. The steps, their order and the arithmetic are
/// those of a generic loop over the vertices, so the area is the same bit for bit.
pub fn triangle_overlap_area(a: &[[f64; 2]; 3], b: &[[f64; 2]; 3]) -> f64 {
    let o = a[0];
    let a = a.map(|p| [p[0] - o[0], p[1] - o[1]]);
    let b = b.map(|p| [p[0] - o[0], p[1] - o[1]]);
    // side_a[k][i]: corner i of `a` against edge k of `b`.
    let side_a: [[f64; 3]; 3] = std::array::from_fn(|k| {
        let (p0, p1) = (b[k], b[(k + 1) % 3]);
        a.map(|q| orient(p0, p1, q))
    });
    // One test for the three separating edges (a jump per edge would be mispredicted for
    // the neighbours that turn out not to overlap).
    let outside = side_a.map(|row| row[0] <= 0.0 && row[1] <= 0.0 && row[2] <= 0.0);
    if outside[0] | outside[1] | outside[2] {
        return 0.0;
    }
    let keeps = side_a.map(|row| row[0] >= 0.0 && row[1] >= 0.0 && row[2] >= 0.0);
    if keeps[0] && keeps[1] && keeps[2] {
        return (0.5 * orient(a[0], a[1], a[2])).max(0.0);
    }
    // Clip `a` by the edges of `b` that cut it. An edge with all three corners of `a` on its
    // inner side leaves every polygon inside `a` unchanged, so it is skipped; the first edge
    // that cuts uses the orientations already computed.
    let mut poly = Polygon {
        p: [[0.0; 2]; CLIP_BUFFER],
        n: 3,
    };
    poly.p[..3].copy_from_slice(&a);
    let mut original = true;
    for k in 0..3 {
        if keeps[k] {
            continue;
        }
        let (p0, p1) = (b[k], b[(k + 1) % 3]);
        let src = &poly.p;
        poly = match (original, poly.n) {
            (true, _) => clip_by_edge(src, &side_a[k]),
            (false, 3) => clip_by_edge(src, &sides::<3>(src, p0, p1)),
            (false, 4) => clip_by_edge(src, &sides::<4>(src, p0, p1)),
            (false, 5) => clip_by_edge(src, &sides::<5>(src, p0, p1)),
            (false, 6) => clip_by_edge(src, &sides::<6>(src, p0, p1)),
            (false, 7) => clip_by_edge(src, &sides::<7>(src, p0, p1)),
            (false, _) => clip_by_edge(src, &sides::<8>(src, p0, p1)),
        };
        original = false;
        if poly.n < 3 {
            return 0.0;
        }
    }
    match poly.n {
        3 => polygon_area::<3>(&poly.p),
        4 => polygon_area::<4>(&poly.p),
        5 => polygon_area::<5>(&poly.p),
        6 => polygon_area::<6>(&poly.p),
        7 => polygon_area::<7>(&poly.p),
        _ => polygon_area::<8>(&poly.p),
    }
}

/// Room for a clipped polygon: [`CLIP_CAPACITY`] kept vertices plus the slot a dropped
/// vertex is written to.
const CLIP_BUFFER: usize = CLIP_CAPACITY + 1;

/// A polygon of at most [`CLIP_CAPACITY`] vertices in a fixed buffer.
#[derive(Clone, Copy)]
struct Polygon {
    p: [[f64; 2]; CLIP_BUFFER],
    n: usize,
}

/// Orientations of the first `N` vertices of `p` against the line `p0 → p1`.
#[inline(always)]
fn sides<const N: usize>(p: &[[f64; 2]; CLIP_BUFFER], p0: [f64; 2], p1: [f64; 2]) -> [f64; N] {
    std::array::from_fn(|i| orient(p0, p1, p[i]))
}

/// One Sutherland–Hodgman step on the first `N` vertices of `src` with orientations `s`
/// against a line: the polygon clipped to the inner half-plane (orientation ≥ 0). A vertex
/// is kept, and the crossing of an edge whose ends lie on different sides is added, while
/// fewer than [`CLIP_CAPACITY`] vertices have been written.
///
/// Without a branch: every vertex and every edge's crossing point is written to the next
/// free slot and kept by advancing the count (which side a vertex is on is as good as random,
/// so a jump on it would be mispredicted about every other time). A crossing that is not kept
/// may be computed from a zero denominator; its slot is overwritten or lies past the count.
#[inline(always)]
fn clip_by_edge<const N: usize>(src: &[[f64; 2]; CLIP_BUFFER], s: &[f64; N]) -> Polygon {
    let mut dst = Polygon {
        p: [[0.0; 2]; CLIP_BUFFER],
        n: 0,
    };
    let mut m = 0usize;
    for i in 0..N {
        let j = if i + 1 == N { 0 } else { i + 1 };
        let (su, sv) = (s[i], s[j]);
        dst.p[m] = src[i];
        m += usize::from(su >= 0.0 && m < CLIP_CAPACITY);
        let crosses = (su >= 0.0) != (sv >= 0.0) && m < CLIP_CAPACITY;
        let t = su / (su - sv);
        let (u, v) = (src[i], src[j]);
        dst.p[m] = [u[0] + t * (v[0] - u[0]), u[1] + t * (v[1] - u[1])];
        m += usize::from(crosses);
    }
    dst.n = m;
    dst
}

/// Area of the counter-clockwise polygon formed by the first `N` vertices of `p`
/// (shoelace), 0 for a negative round-off result.
#[inline(always)]
fn polygon_area<const N: usize>(p: &[[f64; 2]; CLIP_BUFFER]) -> f64 {
    let mut twice = 0.0;
    for i in 0..N {
        let (u, v) = (p[i], p[if i + 1 == N { 0 } else { i + 1 }]);
        twice += u[0] * v[1] - u[1] * v[0];
    }
    (0.5 * twice).max(0.0)
}

/// The index of the point of `points` nearest to `from` (the first one of the nearest, by
/// index; 0 if no distance is below `f64::MAX`), by a scan over all of them.
fn nearest_centroid(points: &[[f64; 2]], from: [f64; 2]) -> u32 {
    let mut best = (f64::MAX, 0u32);
    for (c, g) in points.iter().enumerate() {
        let d = (g[0] - from[0]).powi(2) + (g[1] - from[1]).powi(2);
        if d < best.0 {
            best = (d, c as u32);
        }
    }
    best.1
}

/// A uniform grid of points (about one per bin) for nearest-point queries that give the
/// same answer as [`nearest_centroid`]'s scan.
struct PointGrid {
    lo: [f64; 2],
    /// Bin sides and their inverses (bin coordinates are `(p − lo) · inv`, rounded down; the
    /// search allows one ring for the rounding).
    h: [f64; 2],
    inv: [f64; 2],
    n: [usize; 2],
    /// Points of bin `b` are `items[start[b]..start[b + 1]]`; `None` when a coordinate is
    /// not finite (the queries then scan).
    bins: Option<(Vec<u32>, Vec<u32>)>,
}

impl PointGrid {
    #[inline(never)]
    fn new(points: &[[f64; 2]]) -> Self {
        let finite = points.iter().flatten().all(|v| v.is_finite());
        let (lo, hi) = bounds(points);
        let mut grid = Self {
            lo,
            h: [1.0; 2],
            inv: [1.0; 2],
            n: [1; 2],
            bins: None,
        };
        if !finite || points.is_empty() {
            return grid;
        }
        let span = [hi[0] - lo[0], hi[1] - lo[1]];
        let side = (span[0].max(f64::MIN_POSITIVE) * span[1].max(f64::MIN_POSITIVE)
            / points.len() as f64)
            .sqrt();
        for (k, &extent) in span.iter().enumerate() {
            grid.n[k] = ((extent / side) as usize + 1).clamp(1, 4096);
            grid.h[k] = (extent / grid.n[k] as f64).max(f64::MIN_POSITIVE);
        }
        grid.inv = [1.0 / grid.h[0], 1.0 / grid.h[1]];
        // Bin of every point, computed once for the count and the fill.
        let bin_of: Vec<u32> = points.iter().map(|&p| grid.bin(p) as u32).collect();
        let mut start = vec![0u32; grid.n[0] * grid.n[1] + 1];
        for &b in &bin_of {
            start[b as usize + 1] += 1;
        }
        for b in 1..start.len() {
            start[b] += start[b - 1];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; points.len()];
        for (c, &b) in bin_of.iter().enumerate() {
            let slot = &mut fill[b as usize];
            items[*slot as usize] = c as u32;
            *slot += 1;
        }
        grid.bins = Some((start, items));
        grid
    }

    fn coords(&self, p: [f64; 2]) -> [usize; 2] {
        // Truncation is the floor here: the argument is clamped to ≥ 0 first (NaN to 0).
        std::array::from_fn(|k| {
            (((p[k] - self.lo[k]) * self.inv[k]).max(0.0) as usize).min(self.n[k] - 1)
        })
    }

    fn bin(&self, p: [f64; 2]) -> usize {
        let [x, y] = self.coords(p);
        y * self.n[0] + x
    }

    /// The point nearest to `from`, ties to the lower index (what [`nearest_centroid`]
    /// returns): the bins are searched in square rings around the bin of `from` until the
    /// best distance is below the distance to the next ring (less one ring for the rounding
    /// of the bin coordinates).
    #[inline(never)]
    fn nearest(&self, points: &[[f64; 2]], from: [f64; 2]) -> u32 {
        let Some((start, items)) = &self.bins else {
            return nearest_centroid(points, from);
        };
        if !(from[0].is_finite() && from[1].is_finite()) {
            return nearest_centroid(points, from);
        }
        let [gx, gy] = self.coords(from);
        let (nx, ny) = (self.n[0] as isize, self.n[1] as isize);
        let h = self.h[0].min(self.h[1]);
        let mut best = (f64::MAX, NONE);
        let visit = |x: isize, y: isize, best: &mut (f64, u32)| {
            if x < 0 || y < 0 || x >= nx || y >= ny {
                return;
            }
            let b = (y * nx + x) as usize;
            for &c in &items[start[b] as usize..start[b + 1] as usize] {
                let g = points[c as usize];
                let d = (g[0] - from[0]).powi(2) + (g[1] - from[1]).powi(2);
                if d < best.0 || (d == best.0 && c < best.1) {
                    *best = (d, c);
                }
            }
        };
        let (gx, gy) = (gx as isize, gy as isize);
        for r in 0..=nx.max(ny) {
            if r == 0 {
                visit(gx, gy, &mut best);
            } else {
                for x in gx - r..=gx + r {
                    visit(x, gy - r, &mut best);
                    visit(x, gy + r, &mut best);
                }
                for y in gy - r + 1..gy + r {
                    visit(gx - r, y, &mut best);
                    visit(gx + r, y, &mut best);
                }
            }
            let reach = (r - 1).max(0) as f64 * h;
            if best.1 != NONE && best.0 < reach * reach {
                break;
            }
        }
        if best.1 == NONE { 0 } else { best.1 }
    }
}

fn tri_points(m: &PoreMesh, c: usize) -> [[f64; 2]; 3] {
    m.cell_vertices[c].map(|v| m.vertices[v as usize])
}

/// Lower and upper corners of the bounding box of `points` (`([MAX; 2], [MIN; 2])` for none).
fn bounds<'a>(points: impl IntoIterator<Item = &'a [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    let (mut a, mut b) = ([f64::MAX; 2], [f64::MIN; 2]);
    for q in points {
        for k in 0..2 {
            a[k] = a[k].min(q[k]);
            b[k] = b[k].max(q[k]);
        }
    }
    (a, b)
}

/// True when `g` lies in the closed counter-clockwise triangle `t`.
#[inline(always)]
fn holds(t: &[[f64; 2]; 3], g: [f64; 2]) -> bool {
    orient(t[0], t[1], g) >= 0.0 && orient(t[1], t[2], g) >= 0.0 && orient(t[2], t[0], g) >= 0.0
}

/// Longest walk [`walk_to`] takes before it gives up (the bin grid answers then). Most walks
/// from the previous seed take a few steps; at the jumps of the space-filling curve (a few
/// dozen in a mesh) they take up to a few hundred, still far cheaper than building the bin
/// grid (as much as some 10⁵ steps).
const WALK_STEPS: usize = 2048;

/// The cell of `tri` holding `g`, found by a visibility walk from cell `from` over
/// `adjacency` (`adjacency[c][k]` is the cell across the edge from corner `k` to `k + 1`):
/// from each cell it steps across the edge that `g` lies furthest outside of. `None` when
/// `from` is [`NONE`], the walk reaches the mesh boundary (`g` outside, or beyond a concave
/// outline) or takes more than [`WALK_STEPS`] steps (a walk can cycle in a constrained
/// triangulation); the caller then searches its bin grid.
fn walk_to(tri: &[[[f64; 2]; 3]], adjacency: &[[u32; 3]], from: u32, g: [f64; 2]) -> Option<u32> {
    let mut c = from;
    for _ in 0..WALK_STEPS {
        let t = tri.get(c as usize)?;
        let s = [
            orient(t[0], t[1], g),
            orient(t[1], t[2], g),
            orient(t[2], t[0], g),
        ];
        if s[0] >= 0.0 && s[1] >= 0.0 && s[2] >= 0.0 {
            return Some(c);
        }
        let k = if s[0] <= s[1] && s[0] <= s[2] {
            0
        } else if s[1] <= s[2] {
            1
        } else {
            2
        };
        c = adjacency[c as usize][k];
        if c == NONE {
            return None;
        }
    }
    None
}

/// A uniform grid over the new mesh listing, for every bin, the cells whose bounding box
/// meets it (bins of about 1.5 mean cell sides, at most about four per cell).
struct CellBins {
    lo: [f64; 2],
    h: [f64; 2],
    n: [usize; 2],
    /// Cells of bin `b` are `items[start[b]..start[b + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl CellBins {
    #[inline(never)]
    fn new(new: &PoreMesh, bbox: &[([f64; 2], [f64; 2])]) -> Self {
        let nn = bbox.len();
        let (lo, hi) = bounds(&new.vertices);
        let total_area: f64 = new.cell_area.iter().map(|a| a.abs()).sum();
        let mut h = if nn > 0 {
            (total_area / nn as f64).sqrt() * 1.5
        } else {
            1.0
        };
        if h.is_nan() || h <= 0.0 {
            h = 1.0;
        }
        let span = [(hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0)];
        // At most about four bins per cell.
        let min_h = (span[0] * span[1] / (4.0 * nn.max(1) as f64)).sqrt();
        if min_h.is_finite() && h < min_h {
            h = min_h;
        }
        let n = [
            ((span[0] / h) as usize + 1).clamp(1, 4096),
            ((span[1] / h) as usize + 1).clamp(1, 4096),
        ];
        let mut bins = Self {
            lo,
            h: [
                (span[0] / n[0] as f64).max(f64::MIN_POSITIVE),
                (span[1] / n[1] as f64).max(f64::MIN_POSITIVE),
            ],
            n,
            start: vec![0u32; n[0] * n[1] + 1],
            items: Vec::new(),
        };
        let ranges: Vec<[usize; 4]> = bbox
            .iter()
            .map(|&(a, b)| {
                let (x0, x1, y0, y1) = bins.range(a, b);
                [x0, x1, y0, y1]
            })
            .collect();
        let nx = n[0];
        for &[x0, x1, y0, y1] in &ranges {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    bins.start[y * nx + x + 1] += 1;
                }
            }
        }
        for b in 0..n[0] * n[1] {
            bins.start[b + 1] += bins.start[b];
        }
        bins.items = vec![0u32; bins.start[n[0] * n[1]] as usize];
        let mut fill = bins.start.clone();
        for (c, &[x0, x1, y0, y1]) in ranges.iter().enumerate() {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let b = y * nx + x;
                    bins.items[fill[b] as usize] = c as u32;
                    fill[b] += 1;
                }
            }
        }
        bins
    }

    /// Bin columns `x0..=x1` and rows `y0..=y1` meeting the box `a..b` (clamped to the grid).
    fn range(&self, a: [f64; 2], b: [f64; 2]) -> (usize, usize, usize, usize) {
        // Truncation is the floor here: the argument is clamped to ≥ 0 first.
        let ix = |x: f64| (((x - self.lo[0]) / self.h[0]).max(0.0) as usize).min(self.n[0] - 1);
        let iy = |y: f64| (((y - self.lo[1]) / self.h[1]).max(0.0) as usize).min(self.n[1] - 1);
        (ix(a[0]), ix(b[0]), iy(a[1]), iy(b[1]))
    }

    fn cells(&self, x: usize, y: usize) -> &[u32] {
        let b = y * self.n[0] + x;
        &self.items[self.start[b] as usize..self.start[b + 1] as usize]
    }

    /// The first cell (in bin order) holding `g`.
    fn holding(&self, tri: &[[[f64; 2]; 3]], g: [f64; 2]) -> Option<u32> {
        let (x, _, y, _) = self.range(g, g);
        self.cells(x, y)
            .iter()
            .copied()
            .find(|&c| holds(&tri[c as usize], g))
    }
}

impl RemapOperator {
    /// Intersects the cells of `old` with the cells of `new`.
    pub fn new(old: &PoreMesh, new: &PoreMesh) -> Result<Self, MeshError> {
        for (what, m) in [("old mesh vertex", old), ("new mesh vertex", new)] {
            for (index, v) in m.vertices.iter().enumerate() {
                for &value in v {
                    if !value.is_finite() {
                        return Err(MeshError::NonFinite { what, index, value });
                    }
                }
            }
        }
        let nn = new.n_cells();
        // Packed corner coordinates and bounding boxes of the new cells (one contiguous
        // record per cell).
        let new_tri: Vec<[[f64; 2]; 3]> = (0..nn).map(|c| tri_points(new, c)).collect();
        let new_bbox: Vec<([f64; 2], [f64; 2])> = new_tri.iter().map(bounds).collect();
        let mut new_adjacency = vec![[NONE; 3]; nn];
        for (c, faces) in new.cell_faces.iter().enumerate() {
            for k in 0..3 {
                let [a, b] = new.face_cells[faces[k] as usize];
                new_adjacency[c][k] = if a == c as u32 { b } else { a };
            }
        }
        // The bin grid of the new cells, built the first time a walk fails.
        let mut bins: Option<CellBins> = None;
        // Old cells: seed with the new cell holding the old centroid, then walk across faces
        // while the overlap is positive (the new cells meeting a convex old cell form an
        // edge-connected set). If no new cell holds the centroid, test every binned candidate.
        let no = old.n_cells();
        let mut offsets = Vec::with_capacity(no + 1);
        offsets.push(0u32);
        let mut target = Vec::with_capacity(no * 6);
        let mut area = Vec::with_capacity(no * 6);
        let mut stamp = vec![NONE; nn];
        let mut queue: Vec<u32> = Vec::with_capacity(64);
        // The seed of the previous old cell: neighbouring old cells are neighbours in memory
        // (the mesher's locality order), so the walk to the next seed is short.
        // The first walk starts at new cell 0, which the locality order puts in the same corner
        // as old cell 0.
        let mut previous_seed = 0;
        // For old cells turned inside out (no overlap by definition): the new cell holding
        // their centroid, where `apply` starts its nearest-cell search.
        let mut held: Vec<(u32, u32)> = Vec::new();
        for o in 0..no {
            let p = tri_points(old, o);
            let tag = o as u32;
            if nn > 0 {
                let g = [
                    (p[0][0] + p[1][0] + p[2][0]) / 3.0,
                    (p[0][1] + p[1][1] + p[2][1]) / 3.0,
                ];
                let walked = walk_to(&new_tri, &new_adjacency, previous_seed, g);
                if orient(p[0], p[1], p[2]).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                    // A clockwise or flat triangle overlaps nothing ([`triangle_overlap_area`]
                    // takes counter-clockwise triangles and returns 0 for the others).
                    if let Some(s) = walked {
                        held.push((tag, s));
                        previous_seed = s;
                    }
                    offsets.push(target.len() as u32);
                    continue;
                }
                let seed = walked.or_else(|| {
                    bins.get_or_insert_with(|| CellBins::new(new, &new_bbox))
                        .holding(&new_tri, g)
                });
                let (a, b) = bounds(&p);
                match seed {
                    Some(s) => {
                        previous_seed = s;
                        // Once the overlaps found cover the old cell, what is left on the
                        // stack can only touch it in slivers below round-off: stop there.
                        let full = COVERED_FRACTION * 0.5 * orient(p[0], p[1], p[2]);
                        let mut covered = 0.0;
                        // Breadth first: the seed's neighbours, which hold most of the
                        // rest of the old cell, come before their own neighbours.
                        stamp[s as usize] = tag;
                        queue.clear();
                        queue.push(s);
                        let mut head = 0;
                        while head < queue.len() && covered < full {
                            let c = queue[head];
                            head += 1;
                            let (tlo, thi) = new_bbox[c as usize];
                            if tlo[0] >= b[0] || thi[0] <= a[0] || tlo[1] >= b[1] || thi[1] <= a[1]
                            {
                                continue;
                            }
                            let ov = triangle_overlap_area(&p, &new_tri[c as usize]);
                            if ov > 0.0 {
                                target.push(c);
                                area.push(ov);
                                covered += ov;
                                for &n in &new_adjacency[c as usize] {
                                    if n != NONE && stamp[n as usize] != tag {
                                        stamp[n as usize] = tag;
                                        queue.push(n);
                                    }
                                }
                            }
                        }
                    }
                    None => {
                        let bins = bins.get_or_insert_with(|| CellBins::new(new, &new_bbox));
                        let (x0, x1, y0, y1) = bins.range(a, b);
                        for y in y0..=y1 {
                            for x in x0..=x1 {
                                for &c in bins.cells(x, y) {
                                    if stamp[c as usize] == tag {
                                        continue;
                                    }
                                    stamp[c as usize] = tag;
                                    let (ca, cb) = new_bbox[c as usize];
                                    if ca[0] > b[0] || cb[0] < a[0] || ca[1] > b[1] || cb[1] < a[1]
                                    {
                                        continue;
                                    }
                                    let ov = triangle_overlap_area(&p, &new_tri[c as usize]);
                                    if ov > 0.0 {
                                        target.push(c);
                                        area.push(ov);
                                    }
                                }
                            }
                        }
                    }
                }
            }
            offsets.push(target.len() as u32);
        }
        // Old cells that meet no new cell (turned inside out, or outside the new mesh): where
        // `apply` starts its search for the nearest admissible cell, the new cell holding the
        // old centroid if the walk found one, else the new cell with the nearest centroid
        // (through a grid of the new centroids, built only if needed).
        let mut nearest_new = Vec::new();
        if nn > 0 {
            let mut grid = None;
            let mut held = held.into_iter().peekable();
            for o in 0..no {
                if offsets[o] != offsets[o + 1] {
                    continue;
                }
                if let Some((_, s)) = held.next_if(|&(h, _)| h as usize == o) {
                    nearest_new.push((o as u32, s));
                } else if let Some(&from) = old.cell_centroid.get(o) {
                    let grid = grid.get_or_insert_with(|| PointGrid::new(&new.cell_centroid));
                    nearest_new.push((o as u32, grid.nearest(&new.cell_centroid, from)));
                }
            }
        }
        Ok(Self {
            offsets,
            target,
            area,
            nearest_new,
            old_kind: old.cell_kind.clone(),
            old_centroid: old.cell_centroid.clone(),
            new_kind: new.cell_kind.clone(),
            new_centroid: new.cell_centroid.clone(),
            new_adjacency,
        })
    }

    /// Overlaps of old cell `o`: `(new cell, area)` pairs.
    pub fn overlaps(&self, o: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let (a, b) = (self.offsets[o] as usize, self.offsets[o + 1] as usize);
        self.target[a..b]
            .iter()
            .copied()
            .zip(self.area[a..b].iter().copied())
    }

    fn admissible(&self, filter: CellFilter, old: CellKind, new: CellKind, strict: bool) -> bool {
        match filter {
            CellFilter::Any => true,
            CellFilter::Fluid => new.is_fluid(),
            CellFilter::SameOwner => match (old, new) {
                (CellKind::Solid { owner: a }, CellKind::Solid { owner: b }) => !strict || a == b,
                (CellKind::Fluid, CellKind::Solid { .. }) => true,
                _ => false,
            },
        }
    }

    /// Breadth-first search from `seeds` for the nearest admissible cell.
    fn nearest(
        &self,
        seeds: &[u32],
        ok: impl Fn(u32) -> bool,
        from: [f64; 2],
        seen: &mut [u32],
        tag: u32,
    ) -> u32 {
        let mut layer: VecDeque<u32> = VecDeque::new();
        for &s in seeds {
            if seen[s as usize] != tag {
                seen[s as usize] = tag;
                layer.push_back(s);
            }
        }
        while !layer.is_empty() {
            let mut best = (f64::MAX, NONE);
            for &c in &layer {
                if ok(c) {
                    let g = self.new_centroid[c as usize];
                    let d = (g[0] - from[0]).powi(2) + (g[1] - from[1]).powi(2);
                    if d < best.0 || (d == best.0 && c < best.1) {
                        best = (d, c);
                    }
                }
            }
            if best.1 != NONE {
                return best.1;
            }
            let mut next = VecDeque::new();
            for &c in &layer {
                for &n in &self.new_adjacency[c as usize] {
                    if n != NONE && seen[n as usize] != tag {
                        seen[n as usize] = tag;
                        next.push_back(n);
                    }
                }
            }
            layer = next;
        }
        NONE
    }

    /// Transfers the extensive field `old_values` (one value per old cell) to `new_values`
    /// (overwritten, one per new cell); only new cells admitted by `filter` receive content.
    pub fn apply(
        &self,
        filter: CellFilter,
        old_values: &[f64],
        new_values: &mut [f64],
    ) -> Result<(), MeshError> {
        let (no, nn) = (self.old_kind.len(), self.new_kind.len());
        if old_values.len() != no {
            return Err(MeshError::LengthMismatch {
                what: "old_values",
                expected: no,
                got: old_values.len(),
            });
        }
        if new_values.len() != nn {
            return Err(MeshError::LengthMismatch {
                what: "new_values",
                expected: nn,
                got: new_values.len(),
            });
        }
        for (index, &value) in old_values.iter().enumerate() {
            if !value.is_finite() {
                return Err(MeshError::NonFinite {
                    what: "old_values",
                    index,
                    value,
                });
            }
        }
        new_values.fill(0.0);
        let mut seen = vec![NONE; nn];
        let mut searches = 0u32;
        for (o, &q) in old_values.iter().enumerate() {
            if q == 0.0 {
                continue;
            }
            let ok_kind = self.old_kind[o];
            let mut placed = false;
            for strict in [true, false] {
                let sum: f64 = self
                    .overlaps(o)
                    .filter(|&(c, _)| {
                        self.admissible(filter, ok_kind, self.new_kind[c as usize], strict)
                    })
                    .map(|(_, a)| a)
                    .sum();
                if sum > 0.0 {
                    let mut given = 0.0;
                    let mut last = NONE;
                    let mut last_area = 0.0;
                    for (c, a) in self.overlaps(o) {
                        if self.admissible(filter, ok_kind, self.new_kind[c as usize], strict) {
                            if last != NONE {
                                let share = q * (last_area / sum);
                                new_values[last as usize] += share;
                                given += share;
                            }
                            last = c;
                            last_area = a;
                        }
                    }
                    new_values[last as usize] += q - given;
                    placed = true;
                    break;
                }
            }
            if placed {
                continue;
            }
            // No admissible overlap: nearest admissible cell.
            let mut seeds: Vec<u32> = self.overlaps(o).map(|(c, _)| c).collect();
            let from = self.old_centroid[o];
            if seeds.is_empty() && nn > 0 {
                let seed = match self.nearest_new.binary_search_by_key(&(o as u32), |e| e.0) {
                    Ok(k) => self.nearest_new[k].1,
                    Err(_) => nearest_centroid(&self.new_centroid, from),
                };
                seeds.push(seed);
            }
            let mut cell = NONE;
            for strict in [true, false] {
                searches += 1;
                cell = self.nearest(
                    &seeds,
                    |c| self.admissible(filter, ok_kind, self.new_kind[c as usize], strict),
                    from,
                    &mut seen,
                    searches,
                );
                if cell != NONE {
                    break;
                }
            }
            if cell == NONE {
                return Err(MeshError::NoTargetCell {
                    cell: o,
                    value: q,
                    filter: filter.name(),
                });
            }
            new_values[cell as usize] += q;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const CAP: usize = CLIP_CAPACITY;

    // The generic (loop-based) clipper this module used before its steps were specialised by
    // polygon size: the reference the specialised one must match bit for bit.
    fn reference_overlap_area(a: &[[f64; 2]; 3], b: &[[f64; 2]; 3]) -> f64 {
        let o = a[0];
        let a = a.map(|p| [p[0] - o[0], p[1] - o[1]]);
        let b = b.map(|p| [p[0] - o[0], p[1] - o[1]]);
        // side_a[k][i]: corner i of `a` against edge k of `b` (and the other way round).
        let mut side_a = [[0.0f64; 3]; 3];
        for (k, row) in side_a.iter_mut().enumerate() {
            let (p0, p1) = (b[k], b[(k + 1) % 3]);
            *row = [
                orient(p0, p1, a[0]),
                orient(p0, p1, a[1]),
                orient(p0, p1, a[2]),
            ];
            if row.iter().all(|&s| s <= 0.0) {
                return 0.0;
            }
        }
        if side_a.iter().flatten().all(|&s| s >= 0.0) {
            return (0.5 * orient(a[0], a[1], a[2])).max(0.0);
        }
        // Clip `a` by the edges of `b` that cut it. An edge with all three corners of `a` on its
        // inner side leaves every polygon inside `a` unchanged, so it is skipped; while nothing
        // has been cut, the orientations are those already computed.
        let mut bufs = [[[0.0f64; 2]; CAP]; 2];
        bufs[0][..3].copy_from_slice(&a);
        let (mut cur, mut n, mut original) = (0usize, 3usize, true);
        for (k, row) in side_a.iter().enumerate() {
            if row.iter().all(|&s| s >= 0.0) {
                continue;
            }
            let (p0, p1) = (b[k], b[(k + 1) % 3]);
            let mut side = [0.0f64; CAP];
            if original {
                side[..3].copy_from_slice(row);
            } else {
                for (s, &q) in side[..n].iter_mut().zip(&bufs[cur][..n]) {
                    *s = orient(p0, p1, q);
                }
            }
            let [first, second] = &mut bufs;
            n = if cur == 0 {
                reference_clip(&first[..n], &side[..n], second)
            } else {
                reference_clip(&second[..n], &side[..n], first)
            };
            cur = 1 - cur;
            original = false;
            if n < 3 {
                return 0.0;
            }
        }
        reference_polygon_area(&bufs[cur][..n])
    }

    /// One Sutherland–Hodgman step: the polygon `src` with orientations `side` against a line
    /// (≥ 0 inside) clipped to the inner half-plane into `dst`; returns the new vertex count.
    #[inline(always)]
    fn reference_clip(src: &[[f64; 2]], side: &[f64], dst: &mut [[f64; 2]; CAP]) -> usize {
        let n = src.len();
        let mut m = 0usize;
        for i in 0..n {
            let j = if i + 1 == n { 0 } else { i + 1 };
            let (su, sv) = (side[i], side[j]);
            if su >= 0.0 && m < CAP {
                dst[m] = src[i];
                m += 1;
            }
            if (su >= 0.0) != (sv >= 0.0) && m < CAP {
                let t = su / (su - sv);
                let (u, v) = (src[i], src[j]);
                dst[m] = [u[0] + t * (v[0] - u[0]), u[1] + t * (v[1] - u[1])];
                m += 1;
            }
        }
        m
    }

    /// Area of a counter-clockwise polygon (shoelace), 0 for fewer than three vertices or a
    /// negative round-off result.
    fn reference_polygon_area(p: &[[f64; 2]]) -> f64 {
        let n = p.len();
        if n < 3 {
            return 0.0;
        }
        let mut twice = 0.0;
        for i in 0..n {
            let (u, v) = (p[i], p[if i + 1 == n { 0 } else { i + 1 }]);
            twice += u[0] * v[1] - u[1] * v[0];
        }
        (0.5 * twice).max(0.0)
    }

    fn ccw(mut t: [[f64; 2]; 3]) -> [[f64; 2]; 3] {
        if orient(t[0], t[1], t[2]) < 0.0 {
            t.swap(1, 2);
        }
        t
    }

    /// Random pairs, near-copies (as between an old and a new mesh of slightly moved
    /// circles), shared corners and shared edges: the same bits as the generic clipper.
    #[test]
    fn specialised_clipper_matches_the_generic_one_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut cut = 0;
        for case in 0..200_000 {
            let mut pt = || [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)];
            let a = ccw([pt(), pt(), pt()]);
            let eps = [1e-1, 1e-3, 1e-8, 0.0][case % 4];
            let mut b = match (case / 4) % 4 {
                0 => [pt(), pt(), pt()],
                1 => a.map(|p| {
                    let d = pt();
                    [p[0] + eps * d[0], p[1] + eps * d[1]]
                }),
                2 => [a[0], pt(), pt()],
                _ => [a[1], a[0], pt()],
            };
            b = ccw(b);
            let shift = [1e3 * ((case % 7) as f64 - 3.0), 0.25];
            let (a, b) = (
                a.map(|p| [p[0] + shift[0], p[1] + shift[1]]),
                b.map(|p| [p[0] + shift[0], p[1] + shift[1]]),
            );
            for (x, y) in [(&a, &b), (&b, &a)] {
                let (got, want) = (triangle_overlap_area(x, y), reference_overlap_area(x, y));
                assert_eq!(
                    got.to_bits(),
                    want.to_bits(),
                    "case {case}: {got} vs {want}"
                );
                if got > 0.0 && got < 0.5 * orient(x[0], x[1], x[2]) {
                    cut += 1;
                }
            }
        }
        assert!(cut > 100_000, "only {cut} pairs were clipped");
    }

    /// The grid search for the nearest point gives the scan's answer (ties to the lower
    /// index), for queries inside, on and far outside the point cloud, with duplicate points
    /// and clustered points.
    #[test]
    fn grid_nearest_point_equals_the_scan() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for case in 0..40 {
            let n = 1 + case * 37;
            let mut pts: Vec<[f64; 2]> = (0..n)
                .map(|k| {
                    if k % 9 == 4 {
                        [0.3, 0.7]
                    } else if case % 3 == 0 {
                        [rng.random_range(0.0..1e-3), rng.random_range(0.0..1.0)]
                    } else {
                        [rng.random_range(-1.0..2.0), rng.random_range(0.5..0.75)]
                    }
                })
                .collect();
            if case % 5 == 1 {
                pts.extend_from_slice(&pts.clone()[..n / 2]);
            }
            let grid = PointGrid::new(&pts);
            for q in 0..300 {
                let from = match q % 4 {
                    0 => pts[q % pts.len()],
                    1 => [0.3, 0.7],
                    2 => [rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0)],
                    _ => [rng.random_range(-1.0..2.0), rng.random_range(0.0..1.0)],
                };
                assert_eq!(
                    grid.nearest(&pts, from),
                    nearest_centroid(&pts, from),
                    "case {case}, query {from:?}"
                );
            }
        }
        let bad = [[0.0, 0.0], [f64::NAN, 1.0], [2.0, 2.0]];
        let grid = PointGrid::new(&bad);
        assert_eq!(grid.nearest(&bad, [1.9, 1.9]), 2);
    }
}
