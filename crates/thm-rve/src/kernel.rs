//! The contact loop of [`crate::RveStepper::compute_contact_forces`], written for speed
//! with the floating-point operations of `thm-dem`'s disk contact law unchanged.
//!
//! `thm_dem`'s law ([`thm_dem::ContactKinematics::from_pair`], [`thm_dem::update_contact`]
//! with [`thm_dem::LinearSpring`]'s properties) is one long chain of dependent operations per
//! contact (a root, a quotient, the frame rotation, the Coulomb limit, possibly a second root
//! and quotient) with branches on the contact state. Here the same operations run on
//! [`LANES`] contacts at once, each quantity an array with one contact per lane: the lanes
//! are independent, so the compiler packs them into vector instructions and the chains of
//! several contacts overlap; the branches of the contact-state machine become per-lane
//! selects between results computed for every lane. Every lane computes exactly the
//! operations the scalar law computes for its contact, in the same order, and a select only
//! picks among them, so each contact's result has the law's bits.
//!
//! Two passes: [`classify`] computes every pair's periodic branch vector, settles the pairs
//! that are apart and unbonded (the law would return zero) and lists the others;
//! [`evaluate`] runs the law on the listed ones, [`LANES`] at a time, and sums disk forces,
//! torques, the contact moment and the friction work in list order (the order of the
//! scalar loop, so the sums have its bits too).

use crate::mat2::Mat2;
use crate::state::PeriodicContacts;
use thm_dem::{BondState, ContactHistory, LinearSpring, Vec2};

/// Contacts evaluated together.
pub(crate) const LANES: usize = 4;

type Lane = [f64; LANES];
/// Per-lane condition: all bits set where true (what a vector comparison yields, so that
/// selects are bitwise and/or, not branches).
type Mask = [u64; LANES];

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

#[inline(always)]
fn map<F: Fn(usize) -> f64>(f: F) -> Lane {
    std::array::from_fn(f)
}

#[inline(always)]
fn mask<F: Fn(usize) -> bool>(f: F) -> Mask {
    std::array::from_fn(|j| if f(j) { u64::MAX } else { 0 })
}

#[inline(always)]
fn and(a: &Mask, b: &Mask) -> Mask {
    std::array::from_fn(|j| a[j] & b[j])
}

#[inline(always)]
fn and_not(a: &Mask, b: &Mask) -> Mask {
    std::array::from_fn(|j| a[j] & !b[j])
}

#[inline(always)]
fn or(a: &Mask, b: &Mask) -> Mask {
    std::array::from_fn(|j| a[j] | b[j])
}

/// `a` where `m`, else `b`, bit for bit.
#[inline(always)]
fn select(m: &Mask, a: &Lane, b: &Lane) -> Lane {
    map(|j| f64::from_bits((a[j].to_bits() & m[j]) | (b[j].to_bits() & !m[j])))
}

/// `x.max(0.0)` as the law's `f64::max` compiles it on x86-64 (`maxsd x, 0`): `x` when
/// `x > 0`, else `+0` (NaN and `−0` included), written as a select so that it packs.
#[inline(always)]
fn max0(x: f64) -> f64 {
    if x > 0.0 { x } else { 0.0 }
}

/// Pass 1: branch vectors of every pair (stored in `contacts.branch`), the apart and
/// unbonded pairs zeroed (history and force, as the scalar loop's early exit does), the others'
/// indices into `active`, in list order.
pub(crate) fn classify(
    contacts: &mut PeriodicContacts,
    disk: &[DiskRecord],
    h: &Mat2,
    active: &mut Vec<u32>,
) {
    active.clear();
    if active.capacity() < contacts.pair.capacity() {
        active.reserve_exact(contacts.pair.capacity() - active.len());
    }
    for (k, ((((pair, shift), history), force_on_b), branch_out)) in contacts
        .pair
        .iter()
        .zip(&contacts.shift)
        .zip(contacts.history.iter_mut())
        .zip(contacts.force_on_b.iter_mut())
        .zip(contacts.branch.iter_mut())
        .enumerate()
    {
        let (da, db) = (&disk[pair[0] as usize], &disk[pair[1] as usize]);
        let lattice = h.apply_vec2(Vec2::new(f64::from(shift[0]), f64::from(shift[1])));
        let branch = db.position + lattice - da.position;
        *branch_out = branch;
        let reach = da.radius + db.radius;
        if history.bond != BondState::Intact && branch.norm_squared() >= reach * reach {
            history.shear_force = Vec2::ZERO;
            history.normal = Vec2::ZERO;
            *force_on_b = Vec2::ZERO;
        } else {
            active.push(k as u32);
        }
    }
}

/// Pass 2: the law on the `active` contacts, [`LANES`] at a time; sums into `load` (which
/// must be zero on entry), and returns the contact moment `Σ f ⊗ b` and the friction work.
pub(crate) fn evaluate(
    law: &LinearSpring,
    contacts: &mut PeriodicContacts,
    disk: &[DiskRecord],
    load: &mut [DiskLoad],
    active: &[u32],
    l: &Mat2,
    dt: f64,
) -> (Mat2, f64) {
    let law = Law::of(law);
    match law.bond {
        Some(bond) => evaluate_with::<true>(&law, bond, contacts, disk, load, active, l, dt),
        None => evaluate_with::<false>(&law, [0.0; 4], contacts, disk, load, active, l, dt),
    }
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn evaluate_with<const BOND: bool>(
    law: &Law,
    bond: [f64; 4],
    contacts: &mut PeriodicContacts,
    disk: &[DiskRecord],
    load: &mut [DiskLoad],
    active: &[u32],
    l: &Mat2,
    dt: f64,
) -> (Mat2, f64) {
    let mut moment = Mat2::ZERO;
    let mut heat = 0.0;
    let mut start = 0;
    while start < active.len() {
        let count = (active.len() - start).min(LANES);
        // A short last group repeats its last contact in the spare lanes; their results are
        // dropped.
        let idx: [usize; LANES] =
            std::array::from_fn(|j| active[start + j.min(count - 1)] as usize);
        let out = lanes::<BOND>(law, bond, contacts, disk, &idx, l, dt);
        for (j, &k) in idx.iter().enumerate().take(count) {
            let h = &mut contacts.history[k];
            h.normal = Vec2::new(out.nx[j], out.ny[j]);
            h.shear_force = Vec2::new(out.sx[j], out.sy[j]);
            if out.broke[j] != 0 {
                h.bond = BondState::Broken;
            }
            let f = Vec2::new(out.fx[j], out.fy[j]);
            contacts.force_on_b[k] = f;
            let [a, b] = contacts.pair[k];
            let la = &mut load[a as usize];
            la.force -= f;
            la.torque += out.ta[j];
            let lb = &mut load[b as usize];
            lb.force += f;
            lb.torque += out.tb[j];
            moment = moment.add_scaled(&Mat2::outer_vec2(f, contacts.branch[k]), 1.0);
            heat += out.work[j];
        }
        start += count;
    }
    (moment, heat)
}

/// What the law leaves for the contacts of one group.
struct Out {
    nx: Lane,
    ny: Lane,
    sx: Lane,
    sy: Lane,
    fx: Lane,
    fy: Lane,
    ta: Lane,
    tb: Lane,
    work: Lane,
    broke: Mask,
}

/// The law on the contacts `idx` (one per lane): `ContactKinematics::<Vec2>::from_pair`,
/// `LinearSpring::properties` and `update_contact`, operation for operation.
#[inline(always)]
fn lanes<const BOND: bool>(
    law: &Law,
    bond: [f64; 4],
    contacts: &PeriodicContacts,
    disk: &[DiskRecord],
    idx: &[usize; LANES],
    l: &Mat2,
    dt: f64,
) -> Out {
    // Gathers.
    let pair: [[u32; 2]; LANES] = std::array::from_fn(|j| contacts.pair[idx[j]]);
    let da: [&DiskRecord; LANES] = std::array::from_fn(|j| &disk[pair[j][0] as usize]);
    let db: [&DiskRecord; LANES] = std::array::from_fn(|j| &disk[pair[j][1] as usize]);
    let hist: [&ContactHistory<Vec2>; LANES] = std::array::from_fn(|j| &contacts.history[idx[j]]);
    let bx = map(|j| contacts.branch[idx[j]].x);
    let by = map(|j| contacts.branch[idx[j]].y);
    let ra = map(|j| da[j].radius);
    let rb = map(|j| db[j].radius);
    let wa = map(|j| da[j].spin);
    let wb = map(|j| db[j].spin);
    let intact = mask(|j| hist[j].bond == BondState::Intact);
    let hnx = map(|j| hist[j].normal.x);
    let hny = map(|j| hist[j].normal.y);
    let hsx = map(|j| hist[j].shear_force.x);
    let hsy = map(|j| hist[j].shear_force.y);
    let ref_pen = map(|j| hist[j].reference_penetration);
    // Relative velocity `v_b − v_a + L b` (B-Eq. 45).
    let m = &l.0;
    let rvx = map(|j| (db[j].velocity.x - da[j].velocity.x) + (m[0][0] * bx[j] + m[0][1] * by[j]));
    let rvy = map(|j| (db[j].velocity.y - da[j].velocity.y) + (m[1][0] * bx[j] + m[1][1] * by[j]));

    // ContactKinematics::from_pair.
    let distance = map(|j| (bx[j] * bx[j] + by[j] * by[j]).sqrt());
    let inv = map(|j| 1.0 / distance[j]);
    let positive = mask(|j| distance[j] > 0.0);
    let nx = select(&positive, &map(|j| bx[j] * inv[j]), &[1.0; LANES]);
    let ny = select(&positive, &map(|j| by[j] * inv[j]), &[0.0; LANES]);
    let penetration = map(|j| ra[j] + rb[j] - distance[j]);
    let arm_a = map(|j| ra[j] - 0.5 * penetration[j]);
    let arm_b = map(|j| rb[j] - 0.5 * penetration[j]);
    let omega = map(|j| wa[j] * arm_a[j] + wb[j] * arm_b[j]);
    // v_rel = rv − ω × n with ω × n = (−ω n_y, ω n_x).
    let vx = map(|j| rvx[j] - -omega[j] * ny[j]);
    let vy = map(|j| rvy[j] - omega[j] * nx[j]);
    let vn = map(|j| vx[j] * nx[j] + vy[j] * ny[j]);
    let six = map(|j| (vx[j] - nx[j] * vn[j]) * dt);
    let siy = map(|j| (vy[j] - ny[j] * vn[j]) * dt);

    // LinearSpring::properties (bond strengths only; the rest are constants).
    let (tensile, bond_shear) = if BOND {
        let [beta, ts, t_ref, ratio] = bond;
        let temperature = map(|j| 0.5 * (da[j].temperature + db[j].temperature));
        let mean_radius = map(|j| 0.5 * (ra[j] + rb[j]));
        let rise = map(|j| temperature[j] - t_ref);
        let coefficient = map(|j| {
            if rise[j] <= ts {
                beta * (ts - rise[j]) / ts
            } else {
                0.0
            }
        });
        let fnb = map(|j| coefficient[j] * law.kn * mean_radius[j]);
        (fnb, map(|j| ratio * fnb[j]))
    } else {
        ([0.0; LANES], [0.0; LANES])
    };

    // update_contact.
    let unset = mask(|j| hnx[j] == 0.0 && hny[j] == 0.0);
    let ox = select(&unset, &nx, &hnx);
    let oy = select(&unset, &ny, &hny);
    let overlap = map(|j| penetration[j] - ref_pen[j]);
    let separated = and_not(&mask(|j| overlap[j] <= 0.0), &intact);
    // carry_tangential(shear, old normal, normal).
    let c = map(|j| ox[j] * nx[j] + oy[j] * ny[j]);
    let flipped = mask(|j| c[j] <= -1.0 + 1e-12);
    let vdn = map(|j| hsx[j] * nx[j] + hsy[j] * ny[j]);
    let along = map(|j| ox[j] * hsy[j] - oy[j] * hsx[j]);
    let rx = select(
        &flipped,
        &map(|j| hsx[j] - nx[j] * vdn[j]),
        &map(|j| -ny[j] * along[j]),
    );
    let ry = select(
        &flipped,
        &map(|j| hsy[j] - ny[j] * vdn[j]),
        &map(|j| nx[j] * along[j]),
    );
    let normal_force = map(|j| law.kn * overlap[j]);
    let sx = map(|j| rx[j] - six[j] * law.kt);
    let sy = map(|j| ry[j] - siy[j] * law.kt);
    let s2 = map(|j| sx[j] * sx[j] + sy[j] * sy[j]);
    let tension = mask(|j| -normal_force[j] > tensile[j]);
    let strength = map(|j| max0(bond_shear[j] + 0.0));
    let sheared = mask(|j| s2[j] > strength[j] * strength[j]);
    let broke = and(&intact, &or(&tension, &sheared));
    let bonded = and_not(&intact, &broke);
    // Coulomb limit of an unbonded (or just broken) contact.
    let compressive = map(|j| max0(normal_force[j]));
    let limit = map(|j| compressive[j] * law.mu);
    let sliding = and_not(&mask(|j| s2[j] > limit[j] * limit[j]), &bonded);
    let trial = map(|j| s2[j].sqrt());
    let scale = map(|j| limit[j] / trial[j]);
    let moving = mask(|j| trial[j] > 0.0);
    let slid_x = select(&moving, &map(|j| sx[j] * scale[j]), &[0.0; LANES]);
    let slid_y = select(&moving, &map(|j| sy[j] * scale[j]), &[0.0; LANES]);
    let work_sliding = if law.kt > 0.0 {
        map(|j| limit[j] * (trial[j] - limit[j]) / law.kt)
    } else {
        [0.0; LANES]
    };
    let fn_final = select(&bonded, &normal_force, &compressive);
    let shear_x = select(&sliding, &slid_x, &sx);
    let shear_y = select(&sliding, &slid_y, &sy);
    let work = select(&sliding, &work_sliding, &[0.0; LANES]);
    let fx = map(|j| nx[j] * fn_final[j] + shear_x[j]);
    let fy = map(|j| ny[j] * fn_final[j] + shear_y[j]);
    let moment = map(|j| nx[j] * fy[j] - ny[j] * fx[j]);
    let ta = map(|j| moment[j] * -arm_a[j]);
    let tb = map(|j| moment[j] * -arm_b[j]);

    // A separated contact (unbonded, no overlap) keeps its new normal and nothing else.
    let zero = [0.0; LANES];
    Out {
        nx,
        ny,
        sx: select(&separated, &zero, &shear_x),
        sy: select(&separated, &zero, &shear_y),
        fx: select(&separated, &zero, &fx),
        fy: select(&separated, &zero, &fy),
        ta: select(&separated, &zero, &ta),
        tb: select(&separated, &zero, &tb),
        work: select(&separated, &zero, &work),
        broke: and_not(&broke, &separated),
    }
}
