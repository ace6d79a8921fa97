//! Seeded random packings of circles and exact area references, for tests, verification and
//! benchmarks (the DEM builds the real packings; this crate must not depend on it).
//!
//! [`random_packing`]: diameters uniform in `[d_min, d_max]` are drawn until their total area
//! reaches `nominal_fraction × box area`; centres start uniformly at random inside the box and
//! are relaxed (Jacobi sweeps pushing apart every pair whose overlap exceeds
//! `allowed_overlap × smaller radius`, then clamping every circle inside the box). Finally the
//! radii are scaled by a common factor found by bisection so that the porosity (box area not
//! covered by circles, from [`union_area`]) equals `target_porosity`.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::mesher::{Circle, Contact};

/// How to generate a packing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackingSpec {
    /// Lower-left corner of the box \[m\].
    pub box_min: [f64; 2],
    /// Upper-right corner of the box \[m\].
    pub box_max: [f64; 2],
    /// Smallest diameter \[m\].
    pub d_min: f64,
    /// Largest diameter \[m\].
    pub d_max: f64,
    /// Total circle area over box area before relaxation [-].
    pub nominal_fraction: f64,
    /// Overlap left by the relaxation, as a fraction of the smaller radius [-].
    pub allowed_overlap: f64,
    /// Relaxation sweeps.
    pub sweeps: usize,
    /// Porosity the final radius scaling aims at (`None`: no scaling).
    pub target_porosity: Option<f64>,
    /// Seed of the ChaCha8 generator.
    pub seed: u64,
}

impl PackingSpec {
    /// The 20 × 80 mm bar of paper A (Sect. 3): diameters 4–8 mm, porosity ≈ 10 %.
    pub fn paper_bar(seed: u64) -> Self {
        Self {
            box_min: [0.0, 0.0],
            box_max: [0.020, 0.080],
            d_min: 0.004,
            d_max: 0.008,
            nominal_fraction: 0.95,
            allowed_overlap: 0.05,
            sweeps: 400,
            target_porosity: Some(0.10),
            seed,
        }
    }
}

/// Exact area of the union of discs (Green's theorem over the uncovered arcs).
pub fn union_area(circles: &[Circle]) -> f64 {
    use std::f64::consts::TAU;
    let pairs = crate::mesher::overlapping_pairs(circles);
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); circles.len()];
    for [a, b] in pairs {
        nb[a as usize].push(b);
        nb[b as usize].push(a);
    }
    let mut total = 0.0;
    let mut intervals: Vec<(f64, f64)> = Vec::new();
    for (i, ci) in circles.iter().enumerate() {
        intervals.clear();
        let mut covered = false;
        for &j in &nb[i] {
            let (j, cj) = (j as usize, &circles[j as usize]);
            let e = [cj.centre[0] - ci.centre[0], cj.centre[1] - ci.centre[1]];
            let d = (e[0] * e[0] + e[1] * e[1]).sqrt();
            let (ri, rj) = (ci.radius, cj.radius);
            if d >= ri + rj {
                continue;
            }
            if d <= rj - ri {
                // Inside j (identical circles: the later one is covered by the earlier one).
                if d == 0.0 && ri == rj && j > i {
                    continue;
                }
                covered = true;
                break;
            }
            if d <= ri - rj {
                continue;
            }
            let phi = e[1].atan2(e[0]);
            let w = ((d * d + ri * ri - rj * rj) / (2.0 * d * ri))
                .clamp(-1.0, 1.0)
                .acos();
            let (mut a, b) = ((phi - w).rem_euclid(TAU), (phi + w).rem_euclid(TAU));
            if b < a {
                intervals.push((a, TAU));
                a = 0.0;
            }
            intervals.push((a, b));
        }
        if covered {
            continue;
        }
        intervals.sort_by(|x, y| x.0.total_cmp(&y.0));
        let arc = |t0: f64, t1: f64| {
            let (r, c) = (ci.radius, ci.centre);
            0.5 * (r * r * (t1 - t0)
                + r * (c[0] * (t1.sin() - t0.sin()) - c[1] * (t1.cos() - t0.cos())))
        };
        let mut cur = 0.0;
        for &(a, b) in &intervals {
            if a > cur {
                total += arc(cur, a);
            }
            cur = cur.max(b);
        }
        if cur < TAU {
            total += arc(cur, TAU);
        }
    }
    total
}

/// Exact solid area of circle `i` after the cuts along the radical lines (disc minus the
/// circular segments beyond each chord), when the chords of circle `i` do not cross each other
/// and no circle contains another; `None` otherwise.
pub fn cut_circle_area(circles: &[Circle], i: usize) -> Option<f64> {
    use std::f64::consts::{PI, TAU};
    let ci = &circles[i];
    let r = ci.radius;
    let mut area = PI * r * r;
    let mut spans: Vec<(f64, f64)> = Vec::new();
    for (j, cj) in circles.iter().enumerate() {
        if j == i {
            continue;
        }
        let e = [cj.centre[0] - ci.centre[0], cj.centre[1] - ci.centre[1]];
        let d = (e[0] * e[0] + e[1] * e[1]).sqrt();
        if d >= r + cj.radius {
            continue;
        }
        if d <= (r - cj.radius).abs() {
            return None;
        }
        let a = (d * d + r * r - cj.radius * cj.radius) / (2.0 * d);
        area -= r * r * (a / r).clamp(-1.0, 1.0).acos() - a * (r * r - a * a).max(0.0).sqrt();
        let w = (a / r).clamp(-1.0, 1.0).acos();
        let phi = e[1].atan2(e[0]);
        spans.push(((phi - w).rem_euclid(TAU), 2.0 * w));
    }
    // Chord arcs must be pairwise disjoint.
    for (k, &(a0, w0)) in spans.iter().enumerate() {
        for &(a1, w1) in &spans[k + 1..] {
            let d01 = (a1 - a0).rem_euclid(TAU);
            let d10 = (a0 - a1).rem_euclid(TAU);
            if d01 < w0 || d10 < w1 {
                return None;
            }
        }
    }
    Some(area)
}

/// Every overlapping pair as a contact, with normal stress `stiffness × overlap / (r_a + r_b)`
/// \[Pa\] (a stand-in for the DEM's contact stress).
pub fn overlap_contacts(circles: &[Circle], stiffness: f64) -> Vec<Contact> {
    crate::mesher::overlapping_pairs(circles)
        .into_iter()
        .map(|[a, b]| {
            let (ca, cb) = (&circles[a as usize], &circles[b as usize]);
            let d = ((cb.centre[0] - ca.centre[0]).powi(2) + (cb.centre[1] - ca.centre[1]).powi(2))
                .sqrt();
            let rr = ca.radius + cb.radius;
            Contact {
                circles: [a, b],
                normal_stress: stiffness * (rr - d) / rr,
            }
        })
        .collect()
}

fn relax(circles: &mut [Circle], spec: &PackingSpec) {
    let n = circles.len();
    let mut shift = vec![[0.0f64; 2]; n];
    for _ in 0..spec.sweeps {
        shift.iter_mut().for_each(|s| *s = [0.0; 2]);
        let pairs = crate::mesher::overlapping_pairs(circles);
        let mut worst: f64 = 0.0;
        for [a, b] in pairs {
            let (a, b) = (a as usize, b as usize);
            let (ca, cb) = (circles[a], circles[b]);
            let e = [cb.centre[0] - ca.centre[0], cb.centre[1] - ca.centre[1]];
            let d = (e[0] * e[0] + e[1] * e[1]).sqrt();
            let allowed = spec.allowed_overlap * ca.radius.min(cb.radius);
            let excess = ca.radius + cb.radius - d - allowed;
            if excess <= 0.0 {
                continue;
            }
            worst = worst.max(excess / ca.radius.min(cb.radius));
            let u = if d > 0.0 {
                [e[0] / d, e[1] / d]
            } else {
                let t = (a as f64) * 2.399_963;
                [t.cos(), t.sin()]
            };
            let h = 0.5 * excess;
            shift[a][0] -= h * u[0];
            shift[a][1] -= h * u[1];
            shift[b][0] += h * u[0];
            shift[b][1] += h * u[1];
        }
        for (c, s) in circles.iter_mut().zip(&shift) {
            for (k, sk) in s.iter().enumerate() {
                let lo = spec.box_min[k] + c.radius;
                let hi = spec.box_max[k] - c.radius;
                c.centre[k] = (c.centre[k] + 0.6 * sk).clamp(lo, hi.max(lo));
            }
        }
        if worst < 1e-3 {
            break;
        }
    }
}

/// A seeded random packing inside the box (every circle inside it).
pub fn random_packing(spec: &PackingSpec) -> Vec<Circle> {
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let (lx, ly) = (
        spec.box_max[0] - spec.box_min[0],
        spec.box_max[1] - spec.box_min[1],
    );
    let box_area = lx * ly;
    let mut circles = Vec::new();
    let mut area = 0.0;
    while area < spec.nominal_fraction * box_area {
        let d = rng.random_range(spec.d_min..=spec.d_max);
        let r = 0.5 * d;
        let x = spec.box_min[0] + r + rng.random::<f64>() * (lx - d).max(0.0);
        let y = spec.box_min[1] + r + rng.random::<f64>() * (ly - d).max(0.0);
        circles.push(Circle {
            centre: [x, y],
            radius: r,
            owner: circles.len() as u32,
        });
        area += std::f64::consts::PI * r * r;
    }
    relax(&mut circles, spec);
    if let Some(target) = spec.target_porosity {
        let base = circles.clone();
        let scaled = |k: f64| {
            let mut c = base.clone();
            for ci in c.iter_mut() {
                ci.radius *= k;
                for m in 0..2 {
                    let lo = spec.box_min[m] + ci.radius;
                    let hi = spec.box_max[m] - ci.radius;
                    ci.centre[m] = ci.centre[m].clamp(lo, hi.max(lo));
                }
            }
            c
        };
        let porosity = |c: &[Circle]| 1.0 - union_area(c) / box_area;
        let (mut lo, mut hi) = (0.8, 1.3);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if porosity(&scaled(mid)) > target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        circles = scaled(0.5 * (lo + hi));
    }
    circles
}
