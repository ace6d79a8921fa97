//! The constitutive seam and the materials shipped with the crate.
//!
//! A material point hands its velocity gradient `L`, temperature, temperature rate, current
//! stress and the time step to a [`Constitutive`] model and gets back the new stress, a heat
//! source `Q_t` (W/m³, B-Eq. 1) and a 2 × 2 conductivity tensor `k_ij` (B-Eq. 3; anisotropic
//! allowed). History lives in a per-point `PointState` owned by the caller's
//! [`crate::MpmState`], so a model may be anything from linear elasticity to a DEM RVE.

use crate::error::MpmError;
use crate::points::{Mat2, Sym2, validate_conductivity};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// What a material point hands to its material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialInput {
    /// Index of the point (for error messages).
    pub point: usize,
    /// Velocity gradient `L_ij = ∂v_i/∂x_j` at the point, row-major `[xx, xy, yx, yy]` (1/s).
    pub velocity_gradient: Mat2,
    /// Deformation gradient after this step (row-major).
    pub deformation_gradient: Mat2,
    /// Remapped (smooth) temperature after this step, B-Eq. 29.
    pub temperature: f64,
    /// Temperature rate `Ṫ = Σ_I φ_Ip T_I,t` of this step (K/s), consistent with B-Eq. 28.
    pub temperature_rate: f64,
    /// Stress at the start of the step `[σxx, σyy, σxy]` (Pa).
    pub stress: Sym2,
    /// Current mass density `m_p / V_p` (kg/m³).
    pub density: f64,
    /// Time step (s).
    pub dt: f64,
}

/// What a material returns (the default: all zero).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MaterialResponse {
    /// Stress at the end of the step `[σxx, σyy, σxy]` (Pa).
    pub stress: Sym2,
    /// Heat source `Q_t` (W/m³), e.g. friction heat of an RVE.
    pub heat_source: f64,
    /// Conductivity tensor `[kxx, kyy, kxy]` (W/(m K)), symmetric positive semi-definite.
    pub conductivity: Sym2,
}

/// A constitutive model behind the seam.
pub trait Constitutive: Sync {
    /// Per-point history (plastic strain, an RVE, ...). Owned by the caller's state.
    type PointState: Clone + Send + Sync + std::fmt::Debug + Serialize + DeserializeOwned;

    /// The history of a fresh point.
    fn initial_state(&self) -> Self::PointState;

    /// Advances one point by one step.
    fn respond(
        &self,
        state: &mut Self::PointState,
        input: &MaterialInput,
    ) -> Result<MaterialResponse, MpmError>;

    /// The modulus that sets the mechanical time-step limit B-Eq. 30 (Pa): `Δt < l_e/√(M/ρ)`.
    fn wave_modulus(&self, state: &Self::PointState) -> f64;

    /// The conductivity of a fresh point `[kxx, kyy, kxy]` (W/(m K)).
    fn initial_conductivity(&self) -> Sym2;
}

/// A constitutive model whose points are advanced together, one call per step: the batched
/// form of the seam, for models whose points are expensive and best stepped as one batch (a DEM
/// RVE per point, stepped on a thread pool or, later, on other ranks). [`crate::Mpm::step_batch`]
/// gathers every point first, then hands all inputs over in one call.
///
/// The model may hold scratch (`&mut self`); per-point history lives in the caller's
/// [`crate::MpmState`]. Any per-point [`Constitutive`] model runs through this seam as
/// [`PerPoint`], with the same bits as [`crate::Mpm::step`].
pub trait BatchConstitutive: Sync {
    /// Per-point history, owned by the caller's state.
    type PointState: Clone + Send + Sync + std::fmt::Debug + Serialize + DeserializeOwned;
    /// The model's error; the stepper's own errors convert into it.
    type Error: From<MpmError> + std::fmt::Debug;

    /// Advances every point by one step: `responses[p]` for `inputs[p]` and `states[p]` (all
    /// three slices have one entry per point, in point order).
    fn respond_batch(
        &mut self,
        states: &mut [Self::PointState],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), Self::Error>;

    /// The modulus that sets the mechanical time-step limit B-Eq. 30 (Pa).
    fn wave_modulus(&self, state: &Self::PointState) -> f64;
}

/// A per-point [`Constitutive`] model behind the batched seam: points are handed to it in
/// chunks on the rayon pool, each chunk in point order; the error of the lowest point is
/// returned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerPoint<M>(pub M);

/// Points per work item of [`PerPoint::respond_batch`].
const PER_POINT_CHUNK: usize = 512;

impl<M: Constitutive> BatchConstitutive for PerPoint<M> {
    type PointState = M::PointState;
    type Error = MpmError;

    fn respond_batch(
        &mut self,
        states: &mut [M::PointState],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), MpmError> {
        use rayon::prelude::*;
        if states.len() != inputs.len() || responses.len() != inputs.len() {
            return Err(MpmError::MaterialStateCount {
                states: states.len(),
                points: inputs.len(),
            });
        }
        let model = &self.0;
        let err = states
            .par_chunks_mut(PER_POINT_CHUNK)
            .zip(inputs.par_chunks(PER_POINT_CHUNK))
            .zip(responses.par_chunks_mut(PER_POINT_CHUNK))
            .filter_map(|((s, i), r)| {
                for ((s, i), r) in s.iter_mut().zip(i).zip(r.iter_mut()) {
                    match model.respond(s, i) {
                        Ok(x) => *r = x,
                        Err(e) => return Some(e),
                    }
                }
                None
            })
            .min_by_key(|e| match e {
                MpmError::Material { point, .. }
                | MpmError::InvalidPoint { index: point, .. }
                | MpmError::NonFinite { index: point, .. } => *point,
                _ => 0,
            });
        match err {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn wave_modulus(&self, state: &M::PointState) -> f64 {
        self.0.wave_modulus(state)
    }
}

/// Parameters of [`LinearThermoElastic`] (serde form).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermoElasticParameters {
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν, in (−1, 0.5).
    pub poisson_ratio: f64,
    /// Linear thermal expansion coefficient β (1/K).
    pub thermal_expansion: f64,
    /// Conductivity tensor `[kxx, kyy, kxy]` (W/(m K)).
    pub conductivity: Sym2,
}

/// Linear isotropic thermo-elasticity, B-Eqs. 50–51, plane strain, Jaumann stress rate:
///
/// ```text
/// ε̇ = sym(L) − β Ṫ I₂,   σ_{n+1} = σ_n + Δt [ λ tr(ε̇) I₂ + 2 G ε̇ + W σ_n − σ_n W ]
/// ```
///
/// with `λ = Eν/((1+ν)(1−2ν))`, `G = E/(2(1+ν))`, `W = skew(L)`. `I₂` is the in-plane unit
/// tensor (the literal reading of B-Eq. 51 in 2D; see the crate docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinearThermoElastic {
    lambda: f64,
    shear_modulus: f64,
    thermal_expansion: f64,
    conductivity: Sym2,
}

impl LinearThermoElastic {
    /// Validates the parameters.
    pub fn new(p: &ThermoElasticParameters) -> Result<Self, MpmError> {
        if !(p.youngs_modulus.is_finite() && p.youngs_modulus > 0.0) {
            return Err(MpmError::InvalidParameter {
                name: "youngs_modulus".into(),
                value: p.youngs_modulus,
                allowed: "(0, inf) Pa",
            });
        }
        if !(p.poisson_ratio > -1.0 && p.poisson_ratio < 0.5) {
            return Err(MpmError::InvalidParameter {
                name: "poisson_ratio".into(),
                value: p.poisson_ratio,
                allowed: "(-1, 0.5)",
            });
        }
        if !p.thermal_expansion.is_finite() {
            return Err(MpmError::InvalidParameter {
                name: "thermal_expansion".into(),
                value: p.thermal_expansion,
                allowed: "finite 1/K",
            });
        }
        validate_conductivity("conductivity", p.conductivity)?;
        let (e, nu) = (p.youngs_modulus, p.poisson_ratio);
        Ok(Self {
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            shear_modulus: e / (2.0 * (1.0 + nu)),
            thermal_expansion: p.thermal_expansion,
            conductivity: p.conductivity,
        })
    }

    /// Lamé's first parameter λ (Pa).
    pub fn lambda(&self) -> f64 {
        self.lambda
    }
    /// Shear modulus G (Pa).
    pub fn shear_modulus(&self) -> f64 {
        self.shear_modulus
    }
}

/// Jaumann co-rotational term `(W σ − σ W)` for `W = skew(L)`, as `[xx, yy, xy]`.
#[inline]
pub fn jaumann_spin_term(l: Mat2, s: Sym2) -> Sym2 {
    let w = 0.5 * (l[1] - l[2]); // W_xy
    [2.0 * w * s[2], -2.0 * w * s[2], w * (s[1] - s[0])]
}

impl Constitutive for LinearThermoElastic {
    type PointState = ();

    fn initial_state(&self) {}

    #[inline]
    fn respond(&self, _: &mut (), input: &MaterialInput) -> Result<MaterialResponse, MpmError> {
        let l = input.velocity_gradient;
        let th = self.thermal_expansion * input.temperature_rate;
        let exx = l[0] - th;
        let eyy = l[3] - th;
        let exy = 0.5 * (l[1] + l[2]);
        let tr = exx + eyy;
        let g2 = 2.0 * self.shear_modulus;
        let s = input.stress;
        let j = jaumann_spin_term(l, s);
        let dt = input.dt;
        Ok(MaterialResponse {
            stress: [
                s[0] + dt * (self.lambda * tr + g2 * exx + j[0]),
                s[1] + dt * (self.lambda * tr + g2 * eyy + j[1]),
                s[2] + dt * (g2 * exy + j[2]),
            ],
            heat_source: 0.0,
            conductivity: self.conductivity,
        })
    }

    fn wave_modulus(&self, _: &()) -> f64 {
        self.lambda + 2.0 * self.shear_modulus
    }

    fn initial_conductivity(&self) -> Sym2 {
        self.conductivity
    }
}

/// A material with no stiffness: zero stress, constant conductivity. Pure heat conduction in
/// a medium that flows freely, and the cheapest possible constitutive call (benchmarks).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StresslessConductor {
    conductivity: Sym2,
}

impl StresslessConductor {
    /// Validates the conductivity tensor.
    pub fn new(conductivity: Sym2) -> Result<Self, MpmError> {
        validate_conductivity("conductivity", conductivity)?;
        Ok(Self { conductivity })
    }
}

impl Constitutive for StresslessConductor {
    type PointState = ();
    fn initial_state(&self) {}
    #[inline]
    fn respond(&self, _: &mut (), _: &MaterialInput) -> Result<MaterialResponse, MpmError> {
        Ok(MaterialResponse {
            stress: [0.0; 3],
            heat_source: 0.0,
            conductivity: self.conductivity,
        })
    }
    fn wave_modulus(&self, _: &()) -> f64 {
        0.0
    }
    fn initial_conductivity(&self) -> Sym2 {
        self.conductivity
    }
}

/// Parameters of [`DruckerPrager`] (serde form).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DruckerPragerParameters {
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν, in (−1, 0.5).
    pub poisson_ratio: f64,
    /// Friction angle φ (degrees), in [0, 90).
    pub friction_angle_deg: f64,
    /// Dilatancy angle ψ (degrees), in [0, φ].
    pub dilatancy_angle_deg: f64,
    /// Cohesion c ≥ 0 (Pa).
    pub cohesion: f64,
    /// Linear thermal expansion coefficient β (1/K), in-plane as in [`LinearThermoElastic`].
    pub thermal_expansion: f64,
    /// Conductivity tensor `[kxx, kyy, kxy]` (W/(m K)).
    pub conductivity: Sym2,
}

/// Per-point history of [`DruckerPrager`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct DruckerPragerState {
    /// Out-of-plane stress σzz (Pa), plane strain.
    pub stress_zz: f64,
    /// Accumulated equivalent plastic shear strain `Σ Δλ`.
    pub plastic_strain: f64,
}

/// Elastic–perfectly plastic Drucker–Prager, plane strain, with the cone matched to
/// Mohr–Coulomb in plane strain: `f = √J₂ + α_φ I₁ − k_φ`, `α = tan φ/√(9 + 12 tan² φ)`,
/// `k_φ = 3c/√(9 + 12 tan² φ)`, non-associated potential `g = √J₂ + α_ψ I₁`, tension positive.
/// Elastic predictor with the Jaumann rate, radial return to the cone, or to the apex where
/// the return overshoots it. A second example of the [`Constitutive`] seam (granular column
/// collapse, silos).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DruckerPrager {
    lambda: f64,
    shear_modulus: f64,
    bulk_modulus: f64,
    alpha_phi: f64,
    alpha_psi: f64,
    k_phi: f64,
    /// `1/(G + 9 K α_φ α_ψ)`: plastic multiplier per unit of yield-function excess.
    inverse_plastic_modulus: f64,
    thermal_expansion: f64,
    conductivity: Sym2,
}

impl DruckerPrager {
    /// Validates the parameters.
    pub fn new(p: &DruckerPragerParameters) -> Result<Self, MpmError> {
        let elastic = LinearThermoElastic::new(&ThermoElasticParameters {
            youngs_modulus: p.youngs_modulus,
            poisson_ratio: p.poisson_ratio,
            thermal_expansion: p.thermal_expansion,
            conductivity: p.conductivity,
        })?;
        if !(0.0..90.0).contains(&p.friction_angle_deg) {
            return Err(MpmError::InvalidParameter {
                name: "friction_angle_deg".into(),
                value: p.friction_angle_deg,
                allowed: "[0, 90) degrees",
            });
        }
        if !(0.0..=p.friction_angle_deg).contains(&p.dilatancy_angle_deg) {
            return Err(MpmError::InvalidParameter {
                name: "dilatancy_angle_deg".into(),
                value: p.dilatancy_angle_deg,
                allowed: "[0, friction_angle_deg] degrees",
            });
        }
        if !(p.cohesion.is_finite() && p.cohesion >= 0.0) {
            return Err(MpmError::InvalidParameter {
                name: "cohesion".into(),
                value: p.cohesion,
                allowed: "[0, inf) Pa",
            });
        }
        let cone = |deg: f64| {
            let t = deg.to_radians().tan();
            (
                t / (9.0 + 12.0 * t * t).sqrt(),
                1.0 / (9.0 + 12.0 * t * t).sqrt(),
            )
        };
        let (alpha_phi, inv) = cone(p.friction_angle_deg);
        let (alpha_psi, _) = cone(p.dilatancy_angle_deg);
        let g = elastic.shear_modulus;
        let bulk_modulus = elastic.lambda + 2.0 * g / 3.0;
        Ok(Self {
            lambda: elastic.lambda,
            shear_modulus: g,
            bulk_modulus,
            alpha_phi,
            alpha_psi,
            k_phi: 3.0 * p.cohesion * inv,
            inverse_plastic_modulus: 1.0 / (g + 9.0 * bulk_modulus * alpha_phi * alpha_psi),
            thermal_expansion: p.thermal_expansion,
            conductivity: p.conductivity,
        })
    }

    /// The yield function `f = √J₂ + α_φ I₁ − k_φ` of an in-plane stress and σzz (Pa).
    pub fn yield_function(&self, s: Sym2, szz: f64) -> f64 {
        let i1 = s[0] + s[1] + szz;
        let m = i1 / 3.0;
        let d = [s[0] - m, s[1] - m, szz - m];
        let j2 = 0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + s[2] * s[2];
        j2.sqrt() + self.alpha_phi * i1 - self.k_phi
    }
}

impl Constitutive for DruckerPrager {
    type PointState = DruckerPragerState;

    fn initial_state(&self) -> DruckerPragerState {
        DruckerPragerState::default()
    }

    #[inline]
    fn respond(
        &self,
        state: &mut DruckerPragerState,
        input: &MaterialInput,
    ) -> Result<MaterialResponse, MpmError> {
        let l = input.velocity_gradient;
        let dt = input.dt;
        let th = self.thermal_expansion * input.temperature_rate;
        let exx = l[0] - th;
        let eyy = l[3] - th;
        let exy = 0.5 * (l[1] + l[2]);
        let tr = exx + eyy;
        let g2 = 2.0 * self.shear_modulus;
        let s = input.stress;
        let j = jaumann_spin_term(l, s);
        // Elastic trial.
        let mut t = [
            s[0] + dt * (self.lambda * tr + g2 * exx + j[0]),
            s[1] + dt * (self.lambda * tr + g2 * eyy + j[1]),
            s[2] + dt * (g2 * exy + j[2]),
        ];
        let mut tzz = state.stress_zz + dt * self.lambda * tr;
        let i1 = t[0] + t[1] + tzz;
        let m = i1 * (1.0 / 3.0);
        let d = [t[0] - m, t[1] - m, tzz - m];
        let j2 = 0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) + t[2] * t[2];
        // f = √J₂ − c with c = k_φ − α_φ I₁: inside the cone when c ≥ 0 and J₂ ≤ c², which
        // needs no square root.
        let c = self.k_phi - self.alpha_phi * i1;
        let elastic = c >= 0.0 && j2 <= c * c;
        let sqrt_j2 = if elastic { 0.0 } else { j2.sqrt() };
        let f = sqrt_j2 - c;
        if !elastic && f > 0.0 {
            let g = self.shear_modulus;
            let k = self.bulk_modulus;
            let dl = f * self.inverse_plastic_modulus;
            if sqrt_j2 - g * dl > 0.0 {
                let scale = 1.0 - g * dl / sqrt_j2;
                let m_new = m - 3.0 * k * self.alpha_psi * dl;
                t = [m_new + d[0] * scale, m_new + d[1] * scale, t[2] * scale];
                tzz = m_new + d[2] * scale;
                state.plastic_strain += dl;
            } else {
                // Return to the apex I₁ = k_φ/α_φ (zero stress when cohesionless).
                let apex = if self.alpha_phi > 0.0 {
                    self.k_phi / (3.0 * self.alpha_phi)
                } else {
                    m
                };
                t = [apex, apex, 0.0];
                tzz = apex;
                state.plastic_strain += sqrt_j2 / g;
            }
        }
        state.stress_zz = tzz;
        Ok(MaterialResponse {
            stress: t,
            heat_source: 0.0,
            conductivity: self.conductivity,
        })
    }

    fn wave_modulus(&self, _: &DruckerPragerState) -> f64 {
        self.lambda + 2.0 * self.shear_modulus
    }

    fn initial_conductivity(&self) -> Sym2 {
        self.conductivity
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(l: Mat2, stress: Sym2) -> MaterialInput {
        MaterialInput {
            point: 0,
            velocity_gradient: l,
            deformation_gradient: [1.0, 0.0, 0.0, 1.0],
            temperature: 0.0,
            temperature_rate: 0.0,
            stress,
            density: 1.0,
            dt: 1e-3,
        }
    }

    /// Drucker–Prager: stress never leaves the cone under arbitrary straining, elastic
    /// response below yield equals the thermo-elastic one, and pure shear of a confined
    /// sample saturates at √J₂ = k_φ − α_φ I₁.
    #[test]
    fn drucker_prager_stays_on_or_inside_the_cone() {
        let p = DruckerPragerParameters {
            youngs_modulus: 1e6,
            poisson_ratio: 0.3,
            friction_angle_deg: 30.0,
            dilatancy_angle_deg: 0.0,
            cohesion: 100.0,
            thermal_expansion: 0.0,
            conductivity: [1.0, 1.0, 0.0],
        };
        let dp = DruckerPrager::new(&p).unwrap();
        let el = LinearThermoElastic::new(&ThermoElasticParameters {
            youngs_modulus: 1e6,
            poisson_ratio: 0.3,
            thermal_expansion: 0.0,
            conductivity: [1.0, 1.0, 0.0],
        })
        .unwrap();
        // Below yield: identical to elasticity.
        let mut st = dp.initial_state();
        let l = [-1e-3, 2e-4, 1e-4, -5e-4];
        let a = dp.respond(&mut st, &input(l, [0.0; 3])).unwrap();
        let b = el.respond(&mut (), &input(l, [0.0; 3])).unwrap();
        for k in 0..3 {
            assert!((a.stress[k] - b.stress[k]).abs() < 1e-12);
        }
        // Confine, then shear hard: f ≤ 0 at every step, and f = 0 once plastic.
        let mut st = dp.initial_state();
        let mut s = [0.0; 3];
        for _ in 0..200 {
            let r = dp
                .respond(&mut st, &input([-0.05, 0.0, 0.0, -0.05], s))
                .unwrap();
            s = r.stress;
        }
        for _ in 0..2000 {
            let r = dp
                .respond(&mut st, &input([0.0, 0.5, 0.5, 0.0], s))
                .unwrap();
            s = r.stress;
            let f = dp.yield_function(s, st.stress_zz);
            assert!(f <= 1e-9 * dp.k_phi.max(1.0) + 1e-9, "f = {f}");
        }
        assert!(st.plastic_strain > 0.0);
        assert!(dp.yield_function(s, st.stress_zz).abs() < 1e-6);
        // Tension beyond the apex returns to the apex.
        let mut st = dp.initial_state();
        let r = dp
            .respond(&mut st, &input([10.0, 0.0, 0.0, 10.0], [0.0; 3]))
            .unwrap();
        let apex = dp.k_phi / (3.0 * dp.alpha_phi);
        assert!((r.stress[0] - apex).abs() < 1e-9 && (r.stress[1] - apex).abs() < 1e-9);
    }
}
