//! Seeded random polydisperse packings in a rectangle (planar) or a box (3D), compacted to a
//! target porosity, with stress-free bonds at the contacts; plain-text CSV input/output.
//!
//! Method: radii are drawn uniformly in diameter from `[d_min, d_max]` (ChaCha8, seeded) until
//! the solid fraction `Σ A_i / A` (planar: disk areas over the rectangle; 3D: sphere volumes
//! over the box) reaches `1 − porosity`, then all radii are scaled by one factor `s ≤ 1` so
//! that it is met exactly (`s` is reported; it is within a few per cent of 1 for specimens of
//! 40 or more particles). Overlaps count twice in this definition, as in the porosity of a
//! DEM specimen with overlapping particles. The particles are placed at random with their radii
//! shrunk to 40 %, grown linearly to full size over a frictionless, cohesionless DEM run between
//! rigid walls at the box faces (damping 0.5), and relaxed. Bonds are then installed between
//! every pair whose surfaces are closer than `bond_gap` (or overlap), stress-free at that
//! distance. Intended for specimens up to ~10⁴ particles; large benchmark packings use
//! [`lattice_packing`].
//!
//! [`area_porosity`] measures the other porosity, the uncovered share of a rectangle with
//! overlaps counted once ("the empty area between the spheres" of Krzaczek et al., A-Sect. 3):
//! for the A-Sect. 3 bar a generator porosity of 10 % leaves 12.8 % uncovered, 6 % leaves
//! about 10.6 %.

use crate::contact::{ContactHistory, LinearSpringParams};
use crate::error::{DemError, check_positive, check_range};
use crate::state::{ContactList, DemState, Kinematics, ParticleState, Wall};
use crate::stepper::{Stepper, StepperParams};
use crate::vec3::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// Parameters of the random packing generator.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PackingParams {
    /// Spheres in a plane (one layer), disks, or spheres in 3D.
    pub kinematics: Kinematics,
    /// Lower corner of the box \[m\] (`z` ignored for planar kinematics).
    pub box_min: [f64; 3],
    /// Upper corner of the box \[m\].
    pub box_max: [f64; 3],
    /// Smallest diameter \[m\].
    pub diameter_min: f64,
    /// Largest diameter \[m\].
    pub diameter_max: f64,
    /// Target porosity `1 − Σ A_i / A` (planar) or `1 − Σ V_i / V` (3D).
    pub porosity: f64,
    /// Surfaces closer than this get a bond \[m\].
    pub bond_gap: f64,
    /// Seed of the ChaCha8 generator.
    pub seed: u64,
    /// Steps of the growth phase (and again of the relaxation).
    pub compaction_steps: u64,
}

impl PackingParams {
    /// The bar of Krzaczek et al. (A-Sect. 3): 20 × 80 mm, diameters 4–8 mm, porosity 10 %,
    /// one layer of spheres; bonds across gaps up to 0.4 mm (10 % of the smallest diameter).
    pub fn paper_a_bar(seed: u64) -> Self {
        Self {
            kinematics: Kinematics::SpheresInPlane,
            box_min: [0.0, 0.0, 0.0],
            box_max: [0.02, 0.08, 0.0],
            diameter_min: 0.004,
            diameter_max: 0.008,
            porosity: 0.10,
            bond_gap: 0.0004,
            seed,
            compaction_steps: 6000,
        }
    }

    fn validate(&self) -> Result<(), DemError> {
        for k in 0..3 {
            check_range("box_min", self.box_min[k], -1e6, 1e6, "finite")?;
            check_range("box_max", self.box_max[k], -1e6, 1e6, "finite")?;
        }
        let dims = if self.kinematics.is_planar() { 2 } else { 3 };
        for k in 0..dims {
            if self.box_max[k] - self.box_min[k] < self.diameter_max {
                return Err(DemError::InvalidParameter {
                    field: "box_max",
                    value: self.box_max[k],
                    allowed: "box_min + diameter_max or more along each axis",
                });
            }
        }
        check_positive("diameter_min", self.diameter_min)?;
        check_range(
            "diameter_max",
            self.diameter_max,
            self.diameter_min,
            1e6,
            "[diameter_min, 1e6]",
        )?;
        check_range("porosity", self.porosity, 0.0, 0.95, "[0, 0.95]")?;
        check_range("bond_gap", self.bond_gap, 0.0, 1e6, "[0, 1e6]")?;
        if self.compaction_steps == 0 {
            return Err(DemError::InvalidParameter {
                field: "compaction_steps",
                value: 0.0,
                allowed: "1 or more",
            });
        }
        Ok(())
    }
}

/// Centres, radii and bonds of a packing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Packing {
    /// Kinematics it was made for.
    pub kinematics: Kinematics,
    /// Centres \[m\].
    pub centres: Vec<Vec3>,
    /// Radii \[m\].
    pub radii: Vec<f64>,
    /// Bonded pairs `(a, b)`, `a < b`, sorted.
    pub bonds: Vec<(usize, usize)>,
}

/// What the generator achieved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackingReport {
    /// Porosity of the final packing (same definition as the target).
    pub porosity: f64,
    /// Factor applied to all drawn radii to meet the target porosity exactly.
    pub radius_scale: f64,
    /// Largest overlap over the smaller radius of a pair.
    pub max_relative_overlap: f64,
    /// Mean coordination number of the bonds, `2 N_b / N`.
    pub bond_coordination: f64,
}

/// Most characters of a bad field that a packing-file error quotes.
pub const QUOTE_CHARS: usize = 48;

/// `field`, or its first [`QUOTE_CHARS`] characters followed by `…` when longer.
fn quote(field: &str) -> String {
    if field.chars().count() <= QUOTE_CHARS {
        field.to_owned()
    } else {
        let mut q: String = field.chars().take(QUOTE_CHARS).collect();
        q.push('…');
        q
    }
}

impl Packing {
    /// The particle state (uniform density \[kg/m³\] and temperature \[K\]) with the bonds
    /// installed stress-free at their current distance.
    pub fn to_state(&self, density: f64, temperature: f64) -> Result<DemState, DemError> {
        let particles = ParticleState::new(
            self.kinematics,
            density,
            temperature,
            &self.centres,
            &self.radii,
        )?;
        let mut state = DemState::new(particles, Vec::new());
        let n = self.centres.len();
        for (index, &(a, b)) in self.bonds.iter().enumerate() {
            if a >= b || b >= n {
                return Err(DemError::InvalidContact {
                    index,
                    a,
                    b,
                    particle_count: n,
                });
            }
            let pen = self.radii[a] + self.radii[b] - (self.centres[b] - self.centres[a]).norm();
            state
                .contacts
                .push([a as u32, b as u32], ContactHistory::bonded_at(pen));
        }
        let sorted = state.contacts.pair.windows(2).all(|w| w[0] < w[1]);
        if !sorted {
            let mut order: Vec<usize> = (0..state.contacts.len()).collect();
            order.sort_by_key(|&k| state.contacts.pair[k]);
            order.dedup_by_key(|k| state.contacts.pair[*k]);
            let old = std::mem::take(&mut state.contacts);
            for k in order {
                state.contacts.push(old.pair[k], old.history[k]);
            }
        }
        Ok(state)
    }

    /// The packing with its particles renumbered so that particles close in space are close
    /// in index (see [`locality_order`], cells of the largest diameter), and, for each new
    /// index, the old one. Bonds follow their particles (each pair written `a < b`, sorted).
    /// The physics does not depend on the numbering; the contact pass does: it reads the
    /// second particle of every pair, and on a bed of 10⁵ spheres numbered along its widest
    /// axis first that particle lies 10⁴ indices away, beyond the caches (the counterpart of
    /// the atom sort that LAMMPS and LIGGGHTS make before a run).
    pub fn in_locality_order(&self) -> (Packing, Vec<usize>) {
        let largest = self.radii.iter().fold(0.0_f64, |m, &r| m.max(r));
        let order = locality_order(&self.centres, 2.0 * largest);
        let mut new_index = vec![0; order.len()];
        for (new, &old) in order.iter().enumerate() {
            new_index[old] = new;
        }
        let index = |i: usize| new_index.get(i).copied().unwrap_or(i);
        let mut bonds: Vec<(usize, usize)> = self
            .bonds
            .iter()
            .map(|&(a, b)| {
                let (a, b) = (index(a), index(b));
                (a.min(b), a.max(b))
            })
            .collect();
        bonds.sort_unstable();
        let packing = Packing {
            kinematics: self.kinematics,
            centres: order.iter().map(|&i| self.centres[i]).collect(),
            radii: order.iter().map(|&i| self.radii[i]).collect(),
            bonds,
        };
        (packing, order)
    }

    /// Writes the packing as CSV: `particle,x,y,z,radius` and `bond,a,b` rows (SI units;
    /// numbers in Rust's shortest round-trip form, so reading gives the same bits).
    pub fn to_csv(&self) -> String {
        let mut s = String::new();
        let kin = match self.kinematics {
            Kinematics::Spheres3d => "spheres_3d",
            Kinematics::SpheresInPlane => "spheres_in_plane",
            Kinematics::Disks => "disks",
        };
        let _ = writeln!(s, "# thm-dem packing; kinematics={kin}");
        let _ = writeln!(s, "kind,x_or_a,y_or_b,z,radius");
        for (c, r) in self.centres.iter().zip(&self.radii) {
            let _ = writeln!(s, "particle,{:?},{:?},{:?},{:?}", c.x, c.y, c.z, r);
        }
        for (a, b) in &self.bonds {
            let _ = writeln!(s, "bond,{a},{b}");
        }
        s
    }

    /// Reads the CSV written by [`Packing::to_csv`]. Errors name the line and quote at most
    /// [`QUOTE_CHARS`] characters of the offending field.
    pub fn from_csv(text: &str) -> Result<Self, DemError> {
        let err = |line: usize, reason: String| DemError::PackingFile { line, reason };
        let mut kinematics = None;
        let mut centres = Vec::new();
        let mut radii = Vec::new();
        let mut bonds = Vec::new();
        for (k, raw) in text.lines().enumerate() {
            let line = k + 1;
            let l = raw.trim();
            if let Some(rest) = l.strip_prefix('#') {
                if let Some(v) = rest.split("kinematics=").nth(1) {
                    kinematics = Some(match v.trim() {
                        "spheres_3d" => Kinematics::Spheres3d,
                        "spheres_in_plane" => Kinematics::SpheresInPlane,
                        "disks" => Kinematics::Disks,
                        other => {
                            return Err(err(
                                line,
                                format!("unknown kinematics `{}`", quote(other)),
                            ));
                        }
                    });
                }
                continue;
            }
            if l.is_empty() || l.starts_with("kind,") {
                continue;
            }
            let fields: Vec<&str> = l.split(',').map(str::trim).collect();
            let num = |i: usize| -> Result<f64, DemError> {
                let f = fields
                    .get(i)
                    .ok_or_else(|| err(line, format!("missing field {}", i + 1)))?;
                let v: f64 = f
                    .parse()
                    .map_err(|_| err(line, format!("`{}` is not a number", quote(f))))?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(err(line, format!("`{}` is not finite", quote(f))))
                }
            };
            match fields[0] {
                "particle" => {
                    centres.push(Vec3::new(num(1)?, num(2)?, num(3)?));
                    let r = num(4)?;
                    if r <= 0.0 {
                        return Err(err(line, format!("radius {r} must be positive")));
                    }
                    radii.push(r);
                }
                "bond" => {
                    let idx = |i: usize| -> Result<usize, DemError> {
                        let f = fields
                            .get(i)
                            .ok_or_else(|| err(line, format!("missing field {}", i + 1)))?;
                        f.parse().map_err(|_| {
                            err(line, format!("`{}` is not a particle index", quote(f)))
                        })
                    };
                    bonds.push((idx(1)?, idx(2)?));
                }
                other => return Err(err(line, format!("unknown row kind `{}`", quote(other)))),
            }
        }
        let n = centres.len();
        for (line, &(a, b)) in bonds.iter().enumerate() {
            if a >= b || b >= n {
                return Err(err(0, format!("bond {line} ({a}, {b}) needs a < b < {n}")));
            }
        }
        Ok(Self {
            kinematics: kinematics
                .ok_or_else(|| err(1, "missing `# ... kinematics=` header".into()))?,
            centres,
            radii,
            bonds,
        })
    }

    /// Writes the CSV to a file.
    pub fn write_csv(&self, path: &std::path::Path) -> Result<(), DemError> {
        std::fs::write(path, self.to_csv()).map_err(|e| DemError::PackingFile {
            line: 0,
            reason: e.to_string(),
        })
    }

    /// Reads a CSV file.
    pub fn read_csv(path: &std::path::Path) -> Result<Self, DemError> {
        let text = std::fs::read_to_string(path).map_err(|e| DemError::PackingFile {
            line: 0,
            reason: e.to_string(),
        })?;
        Self::from_csv(&text)
    }
}

fn solid_measure(kin: Kinematics, r: f64) -> f64 {
    if kin.is_planar() {
        std::f64::consts::PI * r * r
    } else {
        4.0 / 3.0 * std::f64::consts::PI * r * r * r
    }
}

/// Generates a random packing (see the module docs); `density` \[kg/m³\] sets the masses of
/// the compaction run only.
pub fn random_packing(
    params: &PackingParams,
    density: f64,
) -> Result<(Packing, PackingReport), DemError> {
    params.validate()?;
    check_positive("density", density)?;
    let kin = params.kinematics;
    let planar = kin.is_planar();
    let lo = Vec3::new(
        params.box_min[0],
        params.box_min[1],
        if planar { 0.0 } else { params.box_min[2] },
    );
    let hi = Vec3::new(
        params.box_max[0],
        params.box_max[1],
        if planar { 0.0 } else { params.box_max[2] },
    );
    let size = hi - lo;
    let measure = if planar {
        size.x * size.y
    } else {
        size.x * size.y * size.z
    };
    let target = (1.0 - params.porosity) * measure;
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut radii = Vec::new();
    let mut solid = 0.0;
    while solid < target {
        let r = 0.5 * rng.random_range(params.diameter_min..=params.diameter_max);
        radii.push(r);
        solid += solid_measure(kin, r);
        if radii.len() > 5_000_000 {
            return Err(DemError::Packing {
                reason: "more than 5e6 particles requested".into(),
            });
        }
    }
    let exponent = if planar { 0.5 } else { 1.0 / 3.0 };
    let radius_scale = (target / solid).powf(exponent);
    for r in &mut radii {
        *r *= radius_scale;
    }
    // Random placement at 40 % size, avoiding overlaps where possible.
    let shrink = 0.4;
    let mut centres: Vec<Vec3> = Vec::with_capacity(radii.len());
    for &r in &radii {
        let rs = r * shrink;
        let mut best = Vec3::ZERO;
        for attempt in 0..200 {
            let c = Vec3::new(
                rng.random_range(lo.x + rs..=hi.x - rs),
                rng.random_range(lo.y + rs..=hi.y - rs),
                if planar {
                    0.0
                } else {
                    rng.random_range(lo.z + rs..=hi.z - rs)
                },
            );
            best = c;
            let clear = centres
                .iter()
                .zip(&radii)
                .all(|(o, ro)| (*o - c).norm() >= rs + ro * shrink);
            if clear || attempt == 199 {
                break;
            }
        }
        centres.push(best);
    }
    // Frictionless, cohesionless compaction between walls.
    let r_mean = radii.iter().sum::<f64>() / radii.len() as f64;
    let kn = 1e6 * r_mean / 1e-3;
    let law = LinearSpringParams {
        normal_stiffness: kn,
        tangential_stiffness: 0.0,
        friction_coefficient: 0.0,
        thermal_bond: None,
    }
    .validate()?;
    let particles = ParticleState::new(kin, density, 293.15, &centres, &radii)?;
    let m_min = particles.mass.iter().fold(f64::MAX, |m, &v| m.min(v));
    let mut walls = vec![
        Wall::new(lo, Vec3::new(1.0, 0.0, 0.0))?,
        Wall::new(hi, Vec3::new(-1.0, 0.0, 0.0))?,
        Wall::new(lo, Vec3::new(0.0, 1.0, 0.0))?,
        Wall::new(hi, Vec3::new(0.0, -1.0, 0.0))?,
    ];
    if !planar {
        walls.push(Wall::new(lo, Vec3::new(0.0, 0.0, 1.0))?);
        walls.push(Wall::new(hi, Vec3::new(0.0, 0.0, -1.0))?);
    }
    let mut state = DemState::new(particles, walls);
    let coordination = if planar { 6.0 } else { 12.0 };
    let dt = 0.3 * (m_min / (coordination * kn)).sqrt();
    let skin = 0.2 * params.diameter_min;
    let stepper_params = StepperParams {
        time_step: dt,
        damping: 0.5,
        gravity: [0.0; 3],
        verlet_skin: skin,
    };
    let mut stepper = Stepper::new(law, stepper_params.validate()?);
    let n_grow = params.compaction_steps;
    for k in 0..n_grow {
        let s = shrink + (1.0 - shrink) * (k + 1) as f64 / n_grow as f64;
        for (r, r0) in state.particles.radius.iter_mut().zip(&radii) {
            *r = r0 * s;
        }
        stepper.step(&mut state)?;
    }
    stepper.run(&mut state, params.compaction_steps)?;
    let centres = state.particles.position.clone();
    // Keep inside the box (walls are soft).
    let mut max_rel: f64 = 0.0;
    let pairs = crate::neighbour::pairs_within(&state.particles, params.bond_gap);
    for &(a, b) in &pairs {
        let pen = radii[a] + radii[b] - (centres[b] - centres[a]).norm();
        max_rel = max_rel.max(pen / radii[a].min(radii[b]));
    }
    let solid_final: f64 = radii.iter().map(|&r| solid_measure(kin, r)).sum();
    let report = PackingReport {
        porosity: 1.0 - solid_final / measure,
        radius_scale,
        max_relative_overlap: max_rel,
        bond_coordination: 2.0 * pairs.len() as f64 / radii.len() as f64,
    };
    Ok((
        Packing {
            kinematics: kin,
            centres,
            radii,
            bonds: pairs,
        },
        report,
    ))
}

/// Area porosity of a planar packing: the share of the rectangle `[lo, hi]` \[m\] not
/// covered by any particle's circle (overlaps count once: "the empty area between the
/// spheres", A-Sect. 3), measured at the centres of square cells of side `cell` \[m\]; the
/// error is of the order of the perimeter-weighted cell size.
pub fn area_porosity(
    packing: &Packing,
    lo: [f64; 2],
    hi: [f64; 2],
    cell: f64,
) -> Result<f64, DemError> {
    check_positive("cell", cell)?;
    check_range("hi[0]", hi[0], lo[0] + cell, 1e6, "lo[0] + cell or more")?;
    check_range("hi[1]", hi[1], lo[1] + cell, 1e6, "lo[1] + cell or more")?;
    let nx = ((hi[0] - lo[0]) / cell).round().max(1.0) as usize;
    let ny = ((hi[1] - lo[1]) / cell).round().max(1.0) as usize;
    if nx.saturating_mul(ny) > 100_000_000 {
        return Err(DemError::InvalidParameter {
            field: "cell",
            value: cell,
            allowed: "at most 1e8 cells on the rectangle",
        });
    }
    let (hx, hy) = ((hi[0] - lo[0]) / nx as f64, (hi[1] - lo[1]) / ny as f64);
    // Mark covered cells circle by circle: O(Σ cells per circle), not O(cells × circles).
    let mut covered = vec![false; nx * ny];
    for (c, &r) in packing.centres.iter().zip(&packing.radii) {
        let j0 = (((c.y - r - lo[1]) / hy).floor().max(0.0) as usize).min(ny);
        let j1 = (((c.y + r - lo[1]) / hy).ceil().max(0.0) as usize).min(ny);
        for j in j0..j1 {
            let y = lo[1] + (j as f64 + 0.5) * hy;
            let half = r * r - (y - c.y) * (y - c.y);
            if half < 0.0 {
                continue;
            }
            let half = half.sqrt();
            // Cells whose centre x satisfies |x − c.x| ≤ half.
            let i0 = ((c.x - half - lo[0]) / hx - 0.5).ceil().max(0.0) as usize;
            let i1 = ((c.x + half - lo[0]) / hx - 0.5).floor();
            if i1 < 0.0 {
                continue;
            }
            let i1 = (i1 as usize).min(nx - 1);
            for i in i0..=i1.max(i0).min(nx - 1) {
                if i <= i1 {
                    covered[j * nx + i] = true;
                }
            }
        }
    }
    let empty = covered.iter().filter(|&&c| !c).count();
    Ok(empty as f64 / (nx * ny) as f64)
}

/// A numbering of the centres in which particles close in space are close in index: the
/// centres are binned into cubic cells of edge `cell` \[m\] over their bounding box, the
/// cells are taken in row-major order with the axis of fewest cells varying fastest and the
/// axis of most cells slowest (ties in x, y, z order), and the centres of one cell keep their
/// relative order. Returns, for each new index, the old one (a permutation of
/// `0..centres.len()`).
///
/// A particle's neighbours then lie within about `n_fast · n_mid` cells of it in index, the
/// cross-section of the box across its longest axis: for a bed of 100 × 100 × 10 particles,
/// 10³ particles instead of the 10⁴ of a numbering along its width first. A `cell` that is not
/// positive and finite, or centres that are not finite, leave the order as it is (identity).
pub fn locality_order(centres: &[Vec3], cell: f64) -> Vec<usize> {
    let identity: Vec<usize> = (0..centres.len()).collect();
    let finite = centres
        .iter()
        .all(|c| c.x.is_finite() && c.y.is_finite() && c.z.is_finite());
    if centres.is_empty() || !(cell > 0.0 && cell.is_finite()) || !finite {
        return identity;
    }
    let axis = |c: &Vec3, k: usize| [c.x, c.y, c.z][k];
    let lo: [f64; 3] =
        std::array::from_fn(|k| centres.iter().fold(f64::INFINITY, |m, c| m.min(axis(c, k))));
    let hi: [f64; 3] = std::array::from_fn(|k| {
        centres
            .iter()
            .fold(f64::NEG_INFINITY, |m, c| m.max(axis(c, k)))
    });
    // Cells per axis, at most 2²⁰ (a key of three such indices fits a u64).
    const MAX_CELLS: u64 = 1 << 20;
    let cells: [u64; 3] = std::array::from_fn(|k| {
        (((hi[k] - lo[k]) / cell) as u64)
            .saturating_add(1)
            .min(MAX_CELLS)
    });
    let mut axes = [0, 1, 2];
    axes.sort_by_key(|&k| cells[k]);
    let key = |c: &Vec3| {
        axes.iter().rev().fold(0_u64, |key, &k| {
            let i = (((axis(c, k) - lo[k]) / cell) as u64).min(cells[k] - 1);
            key * cells[k] + i
        })
    };
    let mut order = identity;
    order.sort_by_key(|&i| key(&centres[i]));
    order
}

/// A bonded packing for benchmarks: a jittered square (planar) or cubic (3D) lattice of
/// spacing `spacing` \[m\], radii uniform in `[0.5, 0.56]·spacing` (so neighbours overlap
/// slightly), `nx × ny × nz` particles (`nz` ignored in planar kinematics), bonds at all pairs
/// closer than `0.05·spacing`. Seeded.
pub fn lattice_packing(
    kin: Kinematics,
    counts: [usize; 3],
    spacing: f64,
    seed: u64,
) -> Result<Packing, DemError> {
    check_positive("spacing", spacing)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let nz = if kin.is_planar() { 1 } else { counts[2] };
    let mut centres = Vec::with_capacity(counts[0] * counts[1] * nz);
    let mut radii = Vec::with_capacity(centres.capacity());
    for k in 0..nz {
        for j in 0..counts[1] {
            for i in 0..counts[0] {
                let mut jit = || rng.random_range(-0.02..0.02) * spacing;
                let c = Vec3::new(
                    i as f64 * spacing + jit(),
                    j as f64 * spacing + jit(),
                    if kin.is_planar() {
                        0.0
                    } else {
                        k as f64 * spacing + jit()
                    },
                );
                centres.push(c);
                radii.push(spacing * rng.random_range(0.5..0.56));
            }
        }
    }
    let particles = ParticleState::new(kin, 1.0, 1.0, &centres, &radii)?;
    let bonds = crate::neighbour::pairs_within(&particles, 0.05 * spacing);
    Ok(Packing {
        kinematics: kin,
        centres,
        radii,
        bonds,
    })
}

/// Bonds from a neighbour search (here rather than in `state`, which the search itself
/// reads).
impl DemState {
    /// Installs stress-free bonds between all pairs whose surfaces are closer than
    /// `max_gap` \[m\] (or overlap): the bond's zero-force penetration is the current one.
    /// Existing contacts between such pairs become bonded; a neighbour search is forced.
    pub fn install_bonds(&mut self, max_gap: f64) -> Result<usize, DemError> {
        crate::error::check_range("max_gap", max_gap, 0.0, f64::MAX, "[0, ∞)")?;
        let pairs = crate::neighbour::pairs_within(&self.particles, max_gap);
        let mut merged = ContactList::default();
        let mut old = 0;
        let mut count = 0;
        for (a, b) in pairs {
            let key = [a as u32, b as u32];
            while old < self.contacts.len() && self.contacts.pair[old] < key {
                merged.push(self.contacts.pair[old], self.contacts.history[old]);
                old += 1;
            }
            let pen = self.particles.radius[a] + self.particles.radius[b]
                - (self.particles.position[b] - self.particles.position[a]).norm();
            let mut h = ContactHistory::bonded_at(pen);
            if old < self.contacts.len() && self.contacts.pair[old] == key {
                h.normal = self.contacts.history[old].normal;
                old += 1;
            }
            merged.push(key, h);
            count += 1;
        }
        while old < self.contacts.len() {
            merged.push(self.contacts.pair[old], self.contacts.history[old]);
            old += 1;
        }
        self.contacts = merged;
        self.search_reference_position.clear();
        self.contact_generation += 1;
        Ok(count)
    }
}
