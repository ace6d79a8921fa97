//! Closed-form solutions of the heat problems of Krzaczek et al. (2023), A-Sects. 4–5, in the
//! default build because scenarios compare with them as they run: the effective properties
//! of the bar (A-Eq. 63), the cooling bar (A-Eqs. 60–61), the same bar with a uniform flow
//! along it, and the steady conduction–advection profile. The verification cases
//! (`verification`, feature `verification`) check the solver against them.

/// Table 1 inputs and the equivalent-solid properties of A-Eq. 63.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarMaterial {
    /// Porosity (fluid volume fraction) of the bar.
    pub porosity: f64,
    /// Water density \[kg/m³\].
    pub water_density: f64,
    /// λ_eff = Σ φ_k λ_k (A-Eq. 63) \[W/(m K)\].
    pub conductivity: f64,
    /// ρ_eff = Σ φ_k ρ_k (A-Eq. 63) \[kg/m³\].
    pub density: f64,
    /// c_p,eff = Σ φ_k c_p,k (A-Eq. 63 as printed, volume average) \[J/(kg K)\].
    pub specific_heat_volume_average: f64,
    /// Σ φ_k ρ_k c_p,k: the volumetric heat capacity of the mixture \[J/(m³ K)\].
    pub volumetric_heat_capacity: f64,
}

impl BarMaterial {
    /// Solid 2600 kg/m³, 920 J/(kg K), 3.7 W/(m K); water 998 kg/m³, 4187 J/(kg K),
    /// 0.6 W/(m K) (Table 1); porosity 0.1106, the value for which A-Eq. 63 gives the paper's
    /// λ_eff = 3.357 W/(m K) (the paper says "roughly 10 %").
    pub fn paper() -> Self {
        let (phi, rho_w) = (0.1106, 998.0);
        let (rho_s, c_s, l_s) = (2600.0, 920.0, 3.7);
        let (c_w, l_w) = (4187.0, 0.6);
        Self {
            porosity: phi,
            water_density: rho_w,
            conductivity: (1.0 - phi) * l_s + phi * l_w,
            density: (1.0 - phi) * rho_s + phi * rho_w,
            specific_heat_volume_average: (1.0 - phi) * c_s + phi * c_w,
            volumetric_heat_capacity: (1.0 - phi) * rho_s * c_s + phi * rho_w * c_w,
        }
    }

    /// Mass-weighted specific heat (ρc)_eff / ρ_eff \[J/(kg K)\].
    pub fn specific_heat(&self) -> f64 {
        self.volumetric_heat_capacity / self.density
    }

    /// Effective diffusivity λ_eff / (ρc)_eff \[m²/s\].
    pub fn diffusivity(&self) -> f64 {
        self.conductivity / self.volumetric_heat_capacity
    }
}

/// T(x, t) of the bar 0 ≤ x ≤ L, initially `t_initial`, both ends held at `t_end`
/// (A-Eqs. 60–61 read as T = T_end + Σ D_n sin(nπx/L) exp(−n²π²αt/L²), D_n = 4(T_0 − T_end)/(nπ)
/// for odd n, 0 for even n).
pub fn fourier_bar_temperature(
    x: f64,
    t: f64,
    length: f64,
    diffusivity: f64,
    t_initial: f64,
    t_end: f64,
) -> f64 {
    let pi = std::f64::consts::PI;
    let mut s = 0.0;
    let mut n = 1u32;
    loop {
        let nf = f64::from(n);
        let decay = (-(nf * pi / length).powi(2) * diffusivity * t).exp();
        let term = 4.0 * (t_initial - t_end) / (nf * pi) * (nf * pi * x / length).sin() * decay;
        s += term;
        if (decay < 1e-16 && n > 1) || n > 200_001 {
            break;
        }
        n += 2;
    }
    t_end + s
}

/// T(x, t) of the bar 0 ≤ x ≤ L of an equivalent medium through which heat is also carried
/// at the front speed `front_velocity` V = (ρc)_fluid u_D / (ρc)_eff (u_D the Darcy flux, in
/// +x), initially `t_initial`, both ends held at `t_end`:
/// (ρc)_eff ∂T/∂t + (ρc)_fluid u_D ∂T/∂x = λ_eff ∂²T/∂x², i.e. ∂T/∂t + V ∂T/∂x = α ∂²T/∂x².
///
/// With θ = T − T_end = w exp(a x − b t), a = V/(2α), b = V²/(4α), w obeys the plain heat
/// equation with w(0) = w(L) = 0 and w(x, 0) = θ₀ e^{−a x}, so
/// θ = e^{a x − b t} Σ B_n sin(k_n x) e^{−α k_n² t}, k_n = nπ/L,
/// B_n = 2 θ₀ k_n (1 − (−1)ⁿ e^{−a L}) / (L (a² + k_n²)).
/// At V = 0 this is [`fourier_bar_temperature`]. The bar Péclet number V L / α must stay
/// below about 1400 (e^{aL/2} in range).
pub fn advection_diffusion_bar_temperature(
    x: f64,
    t: f64,
    length: f64,
    diffusivity: f64,
    front_velocity: f64,
    t_initial: f64,
    t_end: f64,
) -> f64 {
    let pi = std::f64::consts::PI;
    let a = front_velocity / (2.0 * diffusivity);
    let b = front_velocity * front_velocity / (4.0 * diffusivity);
    let theta0 = t_initial - t_end;
    let far_end = (-a * length).exp();
    let mut s = 0.0;
    let mut n = 1u32;
    loop {
        let nf = f64::from(n);
        let k = nf * pi / length;
        let decay = (-k * k * diffusivity * t).exp();
        let sign = if n.is_multiple_of(2) { 1.0 } else { -1.0 };
        let b_n = 2.0 * theta0 * k * (1.0 - sign * far_end) / (length * (a * a + k * k));
        s += b_n * (k * x).sin() * decay;
        if (decay < 1e-16 && n > 1) || n > 400_001 {
            break;
        }
        n += 1;
    }
    t_end + (a * x - b * t).exp() * s
}

/// Steady T(x) of u T' = α T'' on [0, 1] with T(0) = t0, T(1) = t1.
pub fn advection_diffusion_profile(x: f64, peclet: f64, t0: f64, t1: f64) -> f64 {
    let w = ((peclet * (x - 1.0)).exp() - (-peclet).exp()) / (1.0 - (-peclet).exp());
    t0 + (t1 - t0) * w
}
