//! The stages of one RVE exchange (B-Algorithm 1, lines 11–19), each a function that can be
//! tested alone:
//!
//! 1. [`dem_substeps`]: the DEM time rule, `N` DEM steps per MPM step;
//! 2. [`rve_loads`]: each point's velocity gradient and remapped temperature (B-Eq. 29) to
//!    its RVE's load (B-Algorithm 1, lines 12 and 15);
//! 3. the DEM steps of every RVE as one batch (`thm_rve::RveBatch`, line 16);
//! 4. [`mpm_response`]: stress (B-Eq. 49, sign turned to tension positive), heat source
//!    (B-Eq. 33) and conductivity (B-Eq. 34) back to the point (lines 18–19);
//! 5. [`axial_moduli`] (B-Eq. 58) for the time-step limit B-Eq. 30, and
//!    [`quasi_static_measures`] for the quasi-static check.

use thm_mpm::{MaterialInput, MaterialResponse};
use thm_rve::{Mat2, RveLoad, RveParams, RveResponse, RveState, measure};

/// DEM steps per MPM step of `dt` (s): `N = ⌈dt / (c √(m_min / k_n))⌉` for the smallest
/// (already density-scaled) disk mass `min_mass` (kg), the normal stiffness `k_n` (N/m) and
/// the step fraction `c`. At least 1; saturates at `u32::MAX`.
pub fn dem_substeps(dt: f64, min_mass: f64, normal_stiffness: f64, step_fraction: f64) -> u32 {
    let limit = step_fraction * (min_mass / normal_stiffness).sqrt();
    let n = (dt / limit).ceil();
    if n.is_nan() || n < 1.0 {
        1
    } else if n >= f64::from(u32::MAX) {
        u32::MAX
    } else {
        n as u32
    }
}

/// Smallest disk mass of an RVE (kg).
pub fn min_disk_mass(state: &RveState) -> f64 {
    state
        .disks
        .mass
        .iter()
        .fold(f64::INFINITY, |m, &v| m.min(v))
}

/// Multiplies every disk's mass and inertia by the density scaling `s` (the DEM time rule).
pub fn scale_density(state: &mut RveState, s: f64) {
    for m in &mut state.disks.mass {
        *m *= s;
    }
    for i in &mut state.disks.inertia {
        *i *= s;
    }
}

/// The RVE load of one material point: `L` (thm-mpm's row-major `[xx, xy, yx, yy]`, the
/// same layout as `thm_rve::Mat2`'s rows), temperature `T_p + kelvin_offset` (K), the MPM step
/// and `substeps` DEM steps.
pub fn rve_load(input: &MaterialInput, kelvin_offset: f64, substeps: u32) -> RveLoad {
    let l = input.velocity_gradient;
    RveLoad {
        velocity_gradient: Mat2::new(l[0], l[1], l[2], l[3]),
        temperature: input.temperature + kelvin_offset,
        dt: input.dt,
        substeps,
    }
}

/// [`rve_load`] for every point, with each RVE's own `N` from [`dem_substeps`].
pub fn rve_loads<S: AsRef<RveState>>(
    inputs: &[MaterialInput],
    states: &[S],
    params: &RveParams,
    kelvin_offset: f64,
    step_fraction: f64,
    loads: &mut Vec<RveLoad>,
) {
    loads.clear();
    loads.extend(inputs.iter().zip(states).map(|(input, s)| {
        let n = dem_substeps(
            input.dt,
            min_disk_mass(s.as_ref()),
            params.contact.normal_stiffness,
            step_fraction,
        );
        rve_load(input, kelvin_offset, n)
    }));
}

/// What a material point receives from its RVE: the symmetric part of the RVE stress with
/// the sign turned (B-Eq. 49 is compression positive, thm-mpm tension positive) as
/// `[σxx, σyy, σxy]`, the friction heat source `Q` (W/m³, B-Eq. 33) and the symmetric part of
/// the fabric conductivity (B-Eq. 34) as `[kxx, kyy, kxy]`.
///
/// B-Eq. 34 is a sum of outer products, positive semi-definite; when a single heat pipe is
/// left (an RVE dilated in a flow) it is of rank one and rounding can make
/// `k_xx k_yy − k_xy²` a few ulps negative, which `thm-mpm` refuses. `k_xy` is then set to
/// `±√(k_xx k_yy)(1 − 4ε)`, the rank-one value within rounding ([`psd_conductivity`]).
pub fn mpm_response(r: &RveResponse) -> MaterialResponse {
    let s = &r.stress;
    let k = &r.conductivity;
    MaterialResponse {
        stress: [-s.at(0, 0), -s.at(1, 1), -0.5 * (s.at(0, 1) + s.at(1, 0))],
        heat_source: r.heat_source,
        conductivity: psd_conductivity([k.at(0, 0), k.at(1, 1), 0.5 * (k.at(0, 1) + k.at(1, 0))]),
    }
}

/// `[k_xx, k_yy, k_xy]` with `k_xy` clamped to `±√(k_xx k_yy)(1 − 4ε)` when rounding has
/// made `k_xx k_yy < k_xy²` (see [`mpm_response`]); unchanged otherwise (and when not
/// finite, which `thm-mpm` reports).
pub fn psd_conductivity(k: [f64; 3]) -> [f64; 3] {
    if k[0] >= 0.0 && k[1] >= 0.0 && k[0] * k[1] < k[2] * k[2] {
        let m = (k[0] * k[1]).sqrt() * (1.0 - 4.0 * f64::EPSILON);
        [k[0], k[1], m.copysign(k[2])]
    } else {
        k
    }
}

/// The axial entries `[D_xxxx, D_yyyy]` of the stiffness tensor B-Eq. 58 (Pa), over the
/// contacts carrying force or holding an intact bond (as `thm_rve::measure::stiffness`, without
/// the other 14 entries). Their larger one is the P-wave modulus of B-Eq. 30.
pub fn axial_moduli(state: &RveState, params: &RveParams) -> [f64; 2] {
    contact_measures(state, params).axial_moduli
}

/// What one pass over an RVE's contacts gives the exchange.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactMeasures {
    /// [`axial_moduli`] (Pa).
    pub axial_moduli: [f64; 2],
    /// `thm_rve::measure::elastic_energy`, to the same bits.
    pub elastic_energy: f64,
}

/// [`axial_moduli`] and the contacts' elastic energy in one pass over the contacts.
pub fn contact_measures(state: &RveState, params: &RveParams) -> ContactMeasures {
    let (kn, kt) = (
        params.contact.normal_stiffness,
        params.contact.tangential_stiffness,
    );
    let c = &state.contacts;
    let mut d = [0.0; 2];
    let mut e = 0.0;
    for ((f, b), h) in c.force_on_b.iter().zip(&c.branch).zip(&c.history) {
        if *f != thm_dem::Vec2::ZERO {
            let ft = h.shear_force;
            let fnv = *f - ft;
            e += 0.5 * fnv.norm_squared() / kn;
            if kt > 0.0 {
                e += 0.5 * ft.norm_squared() / kt;
            }
        } else if h.bond != thm_dem::BondState::Intact {
            continue;
        }
        let l2 = b.x * b.x + b.y * b.y;
        if l2 <= 0.0 {
            continue;
        }
        // n = b/|b|, t = (−n_y, n_x): k_n n_x² l_x² + k_t t_x² l_x² = l_x² (k_n b_x² + k_t b_y²)/|b|².
        d[0] += b.x * b.x * (kn * b.x * b.x + kt * b.y * b.y) / l2;
        d[1] += b.y * b.y * (kn * b.y * b.y + kt * b.x * b.x) / l2;
    }
    let inv = 1.0 / state.volume(params.thickness);
    ContactMeasures {
        axial_moduli: [d[0] * inv, d[1] * inv],
        elastic_energy: e,
    }
}

/// The quasi-static measures of an RVE after its step, `(I, E_k/E_el)`:
///
/// * the inertial number `I = γ̇ d̄ √(s ρ_s / p)` (GDR MiDi 2004) with `γ̇ = √(2 ḋ'_ij ḋ'_ij)`
///   the deviatoric rate of `sym L` (the rate form of `ε_q`, B-Eq. 48 with n = 2), `d̄` the mean
///   reference diameter, `s ρ_s` the (scaled) disk density and `p = ½ tr σ` the RVE's mean
///   pressure (∞ when `p ≤ 0` and `γ̇ > 0`): how fast the imposed shear rearranges the grains
///   against the time pressure needs to move them;
/// * the ratio of the fluctuating kinetic energy to the elastic energy of the contacts
///   (0 when both vanish, ∞ for motion without stored energy): whether the volumetric and
///   thermal loading (B-Eq. 37), which `I` does not see, leaves the RVE vibrating.
pub fn quasi_static_measures(
    state: &RveState,
    params: &RveParams,
    density_scaling: f64,
    input: &MaterialInput,
    stress: &Mat2,
) -> (f64, f64) {
    let ee = measure::elastic_energy(state, params);
    quasi_static_measures_with(state, params, density_scaling, input, stress, ee)
}

/// [`quasi_static_measures`] with the contacts' elastic energy already known
/// ([`contact_measures`]).
pub fn quasi_static_measures_with(
    state: &RveState,
    params: &RveParams,
    density_scaling: f64,
    input: &MaterialInput,
    stress: &Mat2,
    elastic_energy: f64,
) -> (f64, f64) {
    let ee = elastic_energy;
    let l = input.velocity_gradient;
    let half_diff = 0.5 * (l[0] - l[3]);
    let dxy = 0.5 * (l[1] + l[2]);
    let rate = (2.0 * (2.0 * half_diff * half_diff + 2.0 * dxy * dxy)).sqrt();
    let r = &state.disks.reference_radius;
    let d_mean = 2.0 * r.iter().sum::<f64>() / r.len().max(1) as f64;
    let p = 0.5 * stress.trace();
    let inertial = if rate == 0.0 {
        0.0
    } else if p > 0.0 {
        rate * d_mean * (density_scaling * params.density / p).sqrt()
    } else {
        f64::INFINITY
    };
    let ek = measure::kinetic_energy(state);
    let ratio = if ek == 0.0 {
        0.0
    } else if ee > 0.0 {
        ek / ee
    } else {
        f64::INFINITY
    };
    (inertial, ratio)
}
