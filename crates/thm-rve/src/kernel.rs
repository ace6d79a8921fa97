//! The contact loop of [`crate::RveStepper::compute_contact_forces`], written for speed
//! with the floating-point operations of `thm-dem`'s disk contact law unchanged.
//!
//! `thm_dem`'s law ([`thm_dem::ContactKinematics::from_pair`], [`thm_dem::update_contact`]
//! with [`thm_dem::LinearSpring`]'s properties) is one long chain of dependent operations per
//! contact (a root, a quotient, the frame rotation, the Coulomb limit, a second root and
//! quotient) with branches on the contact state. Evaluated contact after contact, the chain
//! of one contact is longer than what the processor can look ahead, so it mostly waits.
//! Here the law is cut into stages, each a plain loop over a block of [`BLOCK`] contacts held
//! as one array per quantity: within a stage the contacts are independent, so the compiler
//! packs them into vector instructions and the processor overlaps the short chains of many
//! contacts. The branches of the contact-state machine become per-contact selects between
//! results computed for every contact. Each contact still gets exactly the operations the
//! scalar law computes for it, in the same order, and a select only picks among them, so its
//! result has the law's bits.
//!
//! One pass over the pair list ([`contact_forces`]) computes every pair's periodic branch
//! vector, settles the pairs that are apart and unbonded (the law would return zero) and
//! collects the others into the block; each full block runs through the law and is summed
//! into disk forces, torques, the contact moment and the friction work in list order (the
//! order of the scalar loop, so the sums have its bits too). On x86-64 processors with AVX2
//! the same code runs compiled for AVX2 (four contacts per instruction instead of two).

use crate::mat2::Mat2;
use crate::state::PeriodicContacts;
use thm_dem::{BondState, ContactHistory, LinearSpring, Vec2};

/// What a contact needs of a disk, in one record.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct DiskRecord {
    pub position: Vec2,
    pub velocity: Vec2,
    pub spin: f64,
    pub radius: f64,
    pub temperature: f64,
}

/// Force and torque summed over a disk's contacts.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct DiskLoad {
    pub force: Vec2,
    pub torque: f64,
}

/// The constants of the law for one configuration.
#[derive(Debug, Clone, Copy)]
struct Law {
    kn: f64,
    kt: f64,
    mu: f64,
    /// Thermal bond: `β_a`, `T_s`, reference temperature, `μ_b`.
    bond: Option<[f64; 4]>,
}

impl Law {
    fn of(law: &LinearSpring) -> Self {
        let p = law.params();
        Self {
            kn: p.normal_stiffness,
            kt: p.tangential_stiffness,
            mu: p.friction_coefficient,
            bond: p.thermal_bond.map(|b| {
                [
                    b.strength_coefficient,
                    b.threshold_temperature_rise,
                    b.reference_temperature,
                    b.shear_ratio,
                ]
            }),
        }
    }
}

/// `x.max(0.0)` as the law's `f64::max` compiles on x86-64 (`maxsd x, 0`, whose equal or
/// NaN case returns the second operand; AArch64's `fmaxnm` agrees): `x` when `x > 0`, else
/// `+0` (NaN and `−0` included), written as a select so that it vectorises.
#[inline(always)]
fn max0(x: f64) -> f64 {
    if x > 0.0 { x } else { 0.0 }
}

/// Contacts evaluated per block: the block's scratch (about 30 arrays) stays in L1.
pub(crate) const BLOCK: usize = 64;

/// Scratch of one block of contacts, one array per quantity (structure of arrays, so that
/// each stage below is a plain loop the compiler vectorises).
#[derive(Clone)]
pub(crate) struct Block {
    index: [u32; BLOCK],
    bx: [f64; BLOCK],
    by: [f64; BLOCK],
    ra: [f64; BLOCK],
    rb: [f64; BLOCK],
    wa: [f64; BLOCK],
    wb: [f64; BLOCK],
    rvx: [f64; BLOCK],
    rvy: [f64; BLOCK],
    temperature: [f64; BLOCK],
    hnx: [f64; BLOCK],
    hny: [f64; BLOCK],
    hsx: [f64; BLOCK],
    hsy: [f64; BLOCK],
    ref_pen: [f64; BLOCK],
    intact: [u64; BLOCK],
    nx: [f64; BLOCK],
    ny: [f64; BLOCK],
    arm_a: [f64; BLOCK],
    arm_b: [f64; BLOCK],
    overlap: [f64; BLOCK],
    sx: [f64; BLOCK],
    sy: [f64; BLOCK],
    s2: [f64; BLOCK],
    limit: [f64; BLOCK],
    normal_force: [f64; BLOCK],
    sliding: [u64; BLOCK],
    separated: [u64; BLOCK],
    broke: [u64; BLOCK],
    fx: [f64; BLOCK],
    fy: [f64; BLOCK],
    ta: [f64; BLOCK],
    tb: [f64; BLOCK],
    work: [f64; BLOCK],
}

impl Block {
    pub(crate) fn new() -> Box<Self> {
        let z = [0.0; BLOCK];
        let u = [0; BLOCK];
        Box::new(Self {
            index: [0; BLOCK],
            bx: z,
            by: z,
            ra: z,
            rb: z,
            wa: z,
            wb: z,
            rvx: z,
            rvy: z,
            temperature: z,
            hnx: z,
            hny: z,
            hsx: z,
            hsy: z,
            ref_pen: z,
            intact: u,
            nx: z,
            ny: z,
            arm_a: z,
            arm_b: z,
            overlap: z,
            sx: z,
            sy: z,
            s2: z,
            limit: z,
            normal_force: z,
            sliding: u,
            separated: u,
            broke: u,
            fx: z,
            fy: z,
            ta: z,
            tb: z,
            work: z,
        })
    }
}

impl std::fmt::Debug for Block {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Block")
    }
}

/// A per-contact condition stored between stages: all bits set where true.
#[inline(always)]
fn flag(c: bool) -> u64 {
    if c { u64::MAX } else { 0 }
}

/// The contact loop: for every listed pair in list order, its periodic branch vector `b =
/// x_b + H s − x_a` (stored in `contacts.branch`); a pair apart and unbonded is settled at
/// once (the law would return zero and clear its history: no force, nothing summed); the
/// others are collected into a block, and each full block goes through the law
/// ([`stage_kinematics`], [`stage_law`], [`stage_force`]) and is summed into `load` (zero on
/// entry), the contact moment `Σ f ⊗ b` and the friction work, in list order. Returns the
/// moment and the work.
#[allow(clippy::too_many_arguments)]
#[allow(unsafe_code)] // One call, proven below.
pub(crate) fn contact_forces(
    law: &LinearSpring,
    contacts: &mut PeriodicContacts,
    disk: &[DiskRecord],
    load: &mut [DiskLoad],
    block: &mut Block,
    h: &Mat2,
    l: &Mat2,
    dt: f64,
) -> (Mat2, f64) {
    let law = Law::of(law);
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: `contact_forces_avx2` is an ordinary safe function compiled with AVX2
        // enabled; the only requirement for calling it is that the processor running it
        // supports AVX2, which `is_x86_feature_detected!` has just checked at run time. AVX2
        // changes only which vector instructions the same IEEE operations compile to (Rust
        // never contracts a product and a sum into a fused multiply-add), so the results are
        // the same bits; the test `avx2_and_baseline_give_the_same_bits` compares both paths.
        return unsafe { contact_forces_avx2(&law, contacts, disk, load, block, h, l, dt) };
    }
    contact_forces_with(&law, contacts, disk, load, block, h, l, dt)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
fn contact_forces_avx2(
    law: &Law,
    contacts: &mut PeriodicContacts,
    disk: &[DiskRecord],
    load: &mut [DiskLoad],
    block: &mut Block,
    h: &Mat2,
    l: &Mat2,
    dt: f64,
) -> (Mat2, f64) {
    contact_forces_with(law, contacts, disk, load, block, h, l, dt)
}

/// [`contact_forces`] without the run-time choice (the baseline instruction set).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn contact_forces_with(
    law: &Law,
    contacts: &mut PeriodicContacts,
    disk: &[DiskRecord],
    load: &mut [DiskLoad],
    block: &mut Block,
    h: &Mat2,
    l: &Mat2,
    dt: f64,
) -> (Mat2, f64) {
    let mut moment = Mat2::ZERO;
    let mut heat = 0.0;
    let m = &l.0;
    let len = contacts.len();
    let pairs = &contacts.pair[..len];
    let shifts = &contacts.shift[..len];
    let histories = &mut contacts.history[..len];
    let forces = &mut contacts.force_on_b[..len];
    let branches = &mut contacts.branch[..len];
    let mut n = 0;
    for k in 0..len {
        let pair = pairs[k];
        let shift = shifts[k];
        let (da, db) = (&disk[pair[0] as usize], &disk[pair[1] as usize]);
        let lattice = h.apply_vec2(Vec2::new(f64::from(shift[0]), f64::from(shift[1])));
        let branch = db.position + lattice - da.position;
        branches[k] = branch;
        let reach = da.radius + db.radius;
        let history = &mut histories[k];
        if history.bond != BondState::Intact && branch.norm_squared() >= reach * reach {
            history.shear_force = Vec2::ZERO;
            history.normal = Vec2::ZERO;
            forces[k] = Vec2::ZERO;
            continue;
        }
        let b = &mut *block;
        b.index[n] = k as u32;
        b.bx[n] = branch.x;
        b.by[n] = branch.y;
        b.ra[n] = da.radius;
        b.rb[n] = db.radius;
        b.wa[n] = da.spin;
        b.wb[n] = db.spin;
        // Relative velocity `v_b − v_a + L b` (B-Eq. 45).
        b.rvx[n] = (db.velocity.x - da.velocity.x) + (m[0][0] * branch.x + m[0][1] * branch.y);
        b.rvy[n] = (db.velocity.y - da.velocity.y) + (m[1][0] * branch.x + m[1][1] * branch.y);
        b.temperature[n] = 0.5 * (da.temperature + db.temperature);
        b.hnx[n] = history.normal.x;
        b.hny[n] = history.normal.y;
        b.hsx[n] = history.shear_force.x;
        b.hsy[n] = history.shear_force.y;
        b.ref_pen[n] = history.reference_penetration;
        b.intact[n] = flag(history.bond == BondState::Intact);
        n += 1;
        if n == BLOCK {
            run_block(law, block, n, dt);
            scatter(
                pairs,
                branches,
                histories,
                forces,
                load,
                block,
                n,
                &mut moment,
                &mut heat,
            );
            n = 0;
        }
    }
    if n > 0 {
        run_block(law, block, n, dt);
        scatter(
            pairs,
            branches,
            histories,
            forces,
            load,
            block,
            n,
            &mut moment,
            &mut heat,
        );
    }
    (moment, heat)
}

/// The law on the first `n` contacts of a block.
#[inline(always)]
fn run_block(law: &Law, block: &mut Block, n: usize, dt: f64) {
    stage_kinematics(block, n);
    match law.bond {
        Some(bond) => stage_law::<true>(law, bond, block, n, dt),
        None => stage_law::<false>(law, [0.0; 4], block, n, dt),
    }
    stage_force(law, block, n);
}

/// `ContactKinematics::<Vec2>::from_pair`'s normal, penetration and lever arms, and the
/// overlap beyond the bond's reference penetration.
#[inline(always)]
fn stage_kinematics(b: &mut Block, n: usize) {
    assert!(n <= BLOCK);
    for i in 0..n {
        let (bx, by, ra, rb) = (b.bx[i], b.by[i], b.ra[i], b.rb[i]);
        let distance = (bx * bx + by * by).sqrt();
        let inv = 1.0 / distance;
        let positive = distance > 0.0;
        b.nx[i] = if positive { bx * inv } else { 1.0 };
        b.ny[i] = if positive { by * inv } else { 0.0 };
        let penetration = ra + rb - distance;
        b.arm_a[i] = ra - 0.5 * penetration;
        b.arm_b[i] = rb - 0.5 * penetration;
        b.overlap[i] = penetration - b.ref_pen[i];
    }
}

/// The rest of `from_pair` (shear increment), `LinearSpring::properties` (bond strengths)
/// and `update_contact` up to the Coulomb test: trial shear force, its squared norm, the
/// limit, and the state flags.
#[inline(always)]
fn stage_law<const BOND: bool>(law: &Law, bond: [f64; 4], b: &mut Block, n: usize, dt: f64) {
    assert!(n <= BLOCK);
    let [beta, ts, t_ref, ratio] = bond;
    for i in 0..n {
        let (nx, ny) = (b.nx[i], b.ny[i]);
        let (arm_a, arm_b) = (b.arm_a[i], b.arm_b[i]);
        let omega = b.wa[i] * arm_a + b.wb[i] * arm_b;
        // v_rel = rv − ω × n with ω × n = (−ω n_y, ω n_x).
        let vx = b.rvx[i] - -omega * ny;
        let vy = b.rvy[i] - omega * nx;
        let vn = vx * nx + vy * ny;
        let six = (vx - nx * vn) * dt;
        let siy = (vy - ny * vn) * dt;
        let (tensile, bond_shear) = if BOND {
            let mean_radius = 0.5 * (b.ra[i] + b.rb[i]);
            let rise = b.temperature[i] - t_ref;
            let coefficient = if rise <= ts {
                beta * (ts - rise) / ts
            } else {
                0.0
            };
            let fnb = coefficient * law.kn * mean_radius;
            (fnb, ratio * fnb)
        } else {
            (0.0, 0.0)
        };
        let (hnx, hny, hsx, hsy) = (b.hnx[i], b.hny[i], b.hsx[i], b.hsy[i]);
        let unset = hnx == 0.0 && hny == 0.0;
        let ox = if unset { nx } else { hnx };
        let oy = if unset { ny } else { hny };
        let overlap = b.overlap[i];
        let intact = b.intact[i] != 0;
        // carry_tangential(shear, old normal, normal).
        let c = ox * nx + oy * ny;
        let flipped = c <= -1.0 + 1e-12;
        let vdn = hsx * nx + hsy * ny;
        let along = ox * hsy - oy * hsx;
        let rx = if flipped { hsx - nx * vdn } else { -ny * along };
        let ry = if flipped { hsy - ny * vdn } else { nx * along };
        let normal_force = law.kn * overlap;
        let sx = rx - six * law.kt;
        let sy = ry - siy * law.kt;
        let s2 = sx * sx + sy * sy;
        let tension = -normal_force > tensile;
        let strength = max0(bond_shear + 0.0);
        let sheared = s2 > strength * strength;
        let broke = intact & (tension | sheared);
        let bonded = intact & !broke;
        let compressive = max0(normal_force);
        let limit = compressive * law.mu;
        let separated = !intact & (overlap <= 0.0);
        b.sx[i] = sx;
        b.sy[i] = sy;
        b.s2[i] = s2;
        b.limit[i] = limit;
        b.normal_force[i] = if bonded { normal_force } else { compressive };
        b.sliding[i] = flag(!bonded & (s2 > limit * limit));
        b.separated[i] = flag(separated);
        b.broke[i] = flag(broke & !separated);
    }
}

/// The Coulomb slip of `update_contact` and the force and torques of its response; zero for
/// a separated contact (unbonded, no overlap).
#[inline(always)]
fn stage_force(law: &Law, b: &mut Block, n: usize) {
    assert!(n <= BLOCK);
    let kt_positive = law.kt > 0.0;
    for i in 0..n {
        let (sx, sy, s2, limit) = (b.sx[i], b.sy[i], b.s2[i], b.limit[i]);
        let trial = s2.sqrt();
        let scale = limit / trial;
        let moving = trial > 0.0;
        let slid_x = if moving { sx * scale } else { 0.0 };
        let slid_y = if moving { sy * scale } else { 0.0 };
        let work_sliding = if kt_positive {
            limit * (trial - limit) / law.kt
        } else {
            0.0
        };
        let sliding = b.sliding[i] != 0;
        let shear_x = if sliding { slid_x } else { sx };
        let shear_y = if sliding { slid_y } else { sy };
        let work = if sliding { work_sliding } else { 0.0 };
        let (nx, ny, fn_) = (b.nx[i], b.ny[i], b.normal_force[i]);
        let fx = nx * fn_ + shear_x;
        let fy = ny * fn_ + shear_y;
        let moment = nx * fy - ny * fx;
        let ta = moment * -b.arm_a[i];
        let tb = moment * -b.arm_b[i];
        let separated = b.separated[i] != 0;
        b.sx[i] = if separated { 0.0 } else { shear_x };
        b.sy[i] = if separated { 0.0 } else { shear_y };
        b.fx[i] = if separated { 0.0 } else { fx };
        b.fy[i] = if separated { 0.0 } else { fy };
        b.ta[i] = if separated { 0.0 } else { ta };
        b.tb[i] = if separated { 0.0 } else { tb };
        b.work[i] = if separated { 0.0 } else { work };
    }
}

/// Writes the results of the first `n` contacts of a block back (history, force) and sums
/// them in list order.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn scatter(
    pairs: &[[u32; 2]],
    branches: &[Vec2],
    histories: &mut [ContactHistory<Vec2>],
    forces: &mut [Vec2],
    load: &mut [DiskLoad],
    b: &Block,
    n: usize,
    moment: &mut Mat2,
    heat: &mut f64,
) {
    assert!(n <= BLOCK);
    for i in 0..n {
        let k = b.index[i] as usize;
        let h = &mut histories[k];
        h.normal = Vec2::new(b.nx[i], b.ny[i]);
        h.shear_force = Vec2::new(b.sx[i], b.sy[i]);
        if b.broke[i] != 0 {
            h.bond = BondState::Broken;
        }
        let f = Vec2::new(b.fx[i], b.fy[i]);
        forces[k] = f;
        let [ia, ib] = pairs[k];
        let la = &mut load[ia as usize];
        la.force -= f;
        la.torque += b.ta[i];
        let lb = &mut load[ib as usize];
        lb.force += f;
        lb.torque += b.tb[i];
        *moment = moment.add_scaled(&Mat2::outer_vec2(f, branches[k]), 1.0);
        *heat += b.work[i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packing::{ConsolidationParams, PackingParams, consolidate, random_packing};
    use crate::params::RveParams;
    use crate::state::RveState;
    use crate::stepper::RveStepper;
    use thm_dem::ThermalBondParams;

    fn records(state: &RveState) -> Vec<DiskRecord> {
        let d = &state.disks;
        (0..d.len())
            .map(|i| DiskRecord {
                position: Vec2::from_xy(d.position[i]),
                velocity: Vec2::from_xy(d.velocity[i]),
                spin: d.angular_velocity[i].z,
                radius: d.radius[i],
                temperature: d.temperature[i],
            })
            .collect()
    }

    fn bits(c: &PeriodicContacts, load: &[DiskLoad], moment: &Mat2, heat: f64) -> Vec<u64> {
        let mut out = vec![heat.to_bits()];
        out.extend(moment.0.iter().flatten().map(|v| v.to_bits()));
        for l in load {
            out.extend([l.force.x, l.force.y, l.torque].map(f64::to_bits));
        }
        for k in 0..c.len() {
            let h = &c.history[k];
            out.extend(
                [
                    h.shear_force.x,
                    h.shear_force.y,
                    h.normal.x,
                    h.normal.y,
                    c.force_on_b[k].x,
                    c.force_on_b[k].y,
                    c.branch[k].x,
                    c.branch[k].y,
                ]
                .map(f64::to_bits),
            );
            out.push(h.bond as u64);
        }
        out
    }

    /// The kernel as the processor runs it (compiled for AVX2 where it has it) and compiled
    /// for the baseline instruction set give the same bits, step after step of a bonded
    /// packing sheared and heated until its bonds break. (On a processor without AVX2 both
    /// are the baseline and the test only checks that the dispatch is sound.)
    #[test]
    fn avx2_and_baseline_give_the_same_bits() {
        let mut p = RveParams::paper_b_table_1();
        let config = p.validate().unwrap();
        let mut packing = PackingParams::paper_b(11);
        packing.disk_count = 80;
        let mut state = random_packing(&packing, &config).unwrap();
        consolidate(
            &mut state,
            &config,
            &ConsolidationParams::isotropic(1e5, 0.01),
        )
        .unwrap();
        p.contact.friction_coefficient = 0.2;
        p.contact.thermal_bond = Some(ThermalBondParams {
            strength_coefficient: 0.02,
            threshold_temperature_rise: 5.0,
            reference_temperature: p.reference_temperature,
            shear_ratio: 0.5,
        });
        let config = p.validate().unwrap();
        assert!(state.install_bonds() > 20);
        let installed = state.contacts.intact_bond_count();
        let mut stepper = RveStepper::new(config);
        let dt = 2e-6;
        let l = Mat2::new(0.0, 2e-4 / dt, 0.0, -5e-5 / dt);
        let mut block = Block::new();
        for k in 0..400 {
            let t = p.reference_temperature + 0.02 * f64::from(k);
            stepper.set_temperature(&mut state, t).unwrap();
            stepper.step(&mut state, &l, dt).unwrap();
            let disk = records(&state);
            let h = *state.cell.matrix();
            let law = Law::of(config.law());
            let (mut a, mut b) = (state.contacts.clone(), state.contacts.clone());
            let (mut load_a, mut load_b) = (
                vec![DiskLoad::default(); disk.len()],
                vec![DiskLoad::default(); disk.len()],
            );
            let (ma, ha) = contact_forces(
                config.law(),
                &mut a,
                &disk,
                &mut load_a,
                &mut block,
                &h,
                &l,
                dt,
            );
            let (mb, hb) =
                contact_forces_with(&law, &mut b, &disk, &mut load_b, &mut block, &h, &l, dt);
            assert!(
                bits(&a, &load_a, &ma, ha) == bits(&b, &load_b, &mb, hb),
                "step {k}"
            );
        }
        let left = state.contacts.intact_bond_count();
        assert!(left < installed / 2, "{installed} → {left} bonds");
    }
}
