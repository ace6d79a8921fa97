//! Homogenised measures of an RVE: stress (B-Eq. 49), fabric conductivity (B-Eq. 34),
//! stiffness (B-Eq. 58), energies, void ratio, unbalanced force.

use crate::mat2::Mat2;
use crate::params::RveParams;
use crate::state::RveState;
use thm_dem::{BondState, Vec2};

/// Homogenised stress of B-Eq. 49 \[Pa\], compression positive:
/// `σ = (1/V) Σ_c f^c ⊗ b^c + (1/V) Σ_p m_p v_f^p ⊗ v_f^p` with `f^c` the force on `b` from
/// `a`, `b^c` the branch vector `a → b` (a repulsive contact gives `f·b > 0`) and `V` the cell
/// volume `det H · z_p`. The contact part is that of the last force evaluation.
pub fn stress(state: &RveState, thickness: f64) -> Mat2 {
    let volume = state.volume(thickness);
    let d = &state.disks;
    let mut kinetic = Mat2::ZERO;
    for (&m, &v) in d.mass.iter().zip(&d.velocity) {
        kinetic = kinetic.add_scaled(&Mat2::outer(v, v), m);
    }
    state
        .contact_moment
        .add_scaled(&kinetic, 1.0)
        .scale(1.0 / volume)
}

/// Contact part of B-Eq. 49 recomputed from the stored forces and branch vectors \[Pa\].
pub fn contact_stress(state: &RveState, thickness: f64) -> Mat2 {
    let c = &state.contacts;
    let mut m = Mat2::ZERO;
    for (f, b) in c.force_on_b.iter().zip(&c.branch) {
        m = m.add_scaled(&Mat2::outer_vec2(*f, *b), 1.0);
    }
    m.scale(1.0 / state.volume(thickness))
}

/// Whether contact `c` conducts heat: it carried force at the last evaluation or holds an
/// intact bond.
#[inline]
fn conducts(state: &RveState, c: usize) -> bool {
    state.contacts.force_on_b[c] != Vec2::ZERO
        || state.contacts.history[c].bond == BondState::Intact
}

/// Fabric conductivity tensor of B-Eq. 34 \[W/(m K)\]:
/// `k_ij = (1/V) Σ_p r_i r_j / (α l)` over the heat pipes, one per conducting contact, with
/// `r` the branch vector joining the two centres through the contact, `l = |r|` its length and
/// `α` the thermal resistance per length. Symmetric by construction; positive definite when the
/// pipes span the plane.
pub fn conductivity(state: &RveState, params: &RveParams) -> Mat2 {
    let mut k = Mat2::ZERO;
    for c in 0..state.contacts.len() {
        if !conducts(state, c) {
            continue;
        }
        let r = state.contacts.branch[c];
        let l = r.norm();
        if l > 0.0 {
            k = k.add_scaled(
                &Mat2::outer_vec2(r, r),
                1.0 / (params.thermal_resistance * l),
            );
        }
    }
    k.scale(1.0 / state.volume(params.thickness))
}

/// A fourth-order 2D tensor `D[α][β][γ][φ]`.
pub type Tensor4 = [[[[f64; 2]; 2]; 2]; 2];

/// Stiffness tensor of B-Eq. 58 \[Pa\]:
/// `D_αβγφ = (1/V) Σ_c (k_n n_α l_β n_γ l_φ + k_t t_α l_β t_γ l_φ)` over the contacts carrying
/// force, with `n` the unit normal, `t` the unit tangent and `l` the branch vector.
pub fn stiffness(state: &RveState, params: &RveParams) -> Tensor4 {
    let (kn, kt) = (
        params.contact.normal_stiffness,
        params.contact.tangential_stiffness,
    );
    let mut d: Tensor4 = [[[[0.0; 2]; 2]; 2]; 2];
    for c in 0..state.contacts.len() {
        if !conducts(state, c) {
            continue;
        }
        let l = state.contacts.branch[c];
        let len = l.norm();
        if len <= 0.0 {
            continue;
        }
        let n = [l.x / len, l.y / len];
        let t = [-n[1], n[0]];
        let lv = [l.x, l.y];
        for (a, da) in d.iter_mut().enumerate() {
            for (b, db) in da.iter_mut().enumerate() {
                for (g, dg) in db.iter_mut().enumerate() {
                    for (p, v) in dg.iter_mut().enumerate() {
                        *v += kn * n[a] * lv[b] * n[g] * lv[p] + kt * t[a] * lv[b] * t[g] * lv[p];
                    }
                }
            }
        }
    }
    let inv = 1.0 / state.volume(params.thickness);
    for v in d.iter_mut().flatten().flatten().flatten() {
        *v *= inv;
    }
    d
}

/// Kinetic energy of the fluctuating motion (translation and rotation) \[J\].
pub fn kinetic_energy(state: &RveState) -> f64 {
    let d = &state.disks;
    let mut e = 0.0;
    for i in 0..d.len() {
        e += 0.5 * d.mass[i] * d.velocity[i].norm_squared()
            + 0.5 * d.inertia[i] * d.angular_velocity[i].norm_squared();
    }
    e
}

/// Elastic energy stored in the contact springs at the last evaluation \[J\]:
/// `Σ (F_n² / 2k_n + |F_t|² / 2k_t)`.
pub fn elastic_energy(state: &RveState, params: &RveParams) -> f64 {
    let (kn, kt) = (
        params.contact.normal_stiffness,
        params.contact.tangential_stiffness,
    );
    let c = &state.contacts;
    let mut e = 0.0;
    for i in 0..c.len() {
        let f = c.force_on_b[i];
        if f == Vec2::ZERO {
            continue;
        }
        let ft = c.history[i].shear_force;
        let fnv = f - ft;
        e += 0.5 * fnv.norm_squared() / kn;
        if kt > 0.0 {
            e += 0.5 * ft.norm_squared() / kt;
        }
    }
    e
}

/// Ratio of the mean unbalanced disk force to the mean contact force (0 for a packing in
/// equilibrium).
pub fn unbalanced_force_ratio(state: &RveState) -> f64 {
    let d = &state.disks;
    let n = d.len().max(1) as f64;
    let mean_unbalanced = d.force.iter().map(|f| f.norm()).sum::<f64>() / n;
    let (mut sum, mut count) = (0.0, 0usize);
    for f in &state.contacts.force_on_b {
        if *f != Vec2::ZERO {
            sum += f.norm();
            count += 1;
        }
    }
    if count == 0 {
        return f64::INFINITY;
    }
    mean_unbalanced / (sum / count as f64)
}
