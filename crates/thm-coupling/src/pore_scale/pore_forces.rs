//! Pore pressure on the spheres through the cell corners, with each pore's undrained response
//! inside the coupled step ([`super::params::PressureForce::CellCorners`]).
//!
//! A pore cell is a triangle whose corners are anchored to circles (`thm-vpn-mesh`, motion:
//! a vertex sits at the mean of its anchors' transported points, so `∂x_v/∂c_s = I / n_v` for
//! each of its `n_v` anchor circles `s`; a vertex on a box side keeps its normal coordinate,
//! a box corner does not move). The pore volume `V_i = w A_i` therefore has the exact
//! gradient
//!
//! `g_is = ∂V_i/∂c_s = w Σ_{v ∈ i, s anchors v} (1 / n_v) ∂A_i/∂x_v`,
//! with `∂A/∂x_a = ½ (y_b − y_c, x_c − x_b)` for a counter-clockwise triangle `a, b, c`.
//!
//! A vertex also turns with its anchor circles (its offset is carried by the circle's
//! rotation), so turning a sphere changes the pores around it too; that part, a fluid torque
//! `Σ_i P_i ∂V_i/∂θ_s`, is left out here (measured in case a: the volume changes it leaves
//! unexplained moved the undrained pressures by up to about 8·10⁴ Pa per coupled step).
//!
//! The force of the pore pressures on sphere `s` is `F_s = Σ_i P_i g_is`: the work the fluid
//! does on the spheres, `Σ_i P_i dV_i`, so a uniform pressure, which does no work on a
//! tessellation whose pore area does not depend on the centres, pushes no sphere. A-Eqs. 52–53
//! put `P_i e_k w n` on the sphere behind each wall face only; a triangle whose corners are
//! anchored to spheres with no wall face on it is then reshaped by those spheres without
//! resisting them (`docs/cases/bar_contraction_free.md`).
//!
//! Within the coupled step each pore answers undrained (its masses fixed) to the volume change
//! `ΔV_i = Σ_s g_is · (c_s − c_s⁰)`, updated before every DEM sub-step, so the spheres feel
//! the pressure they squeeze in while they move; the flow stage then finds the drained state
//! as before. The response is a two-phase spring fitted to the closure (A-Eq. 29) at the
//! step's start: the liquid volume `V_q = V_q⁰ (1 − (P − P⁰)/K_q)` and the gas volume
//! `V_g = V_g⁰ K_p / (K_p + P − P⁰)`, with the phases' bulk moduli `K_q`, `K_p` of the fluid
//! model, and `V_q + V_g = V⁰ + ΔV` solved in closed form (a quadratic in `P`), floored at
//! `P = 0`. Its tangent at the start is the flow's `K/V` (`1/K = α_q/K_q + α_p/K_p`), and like
//! the closure it stiffens without bound as the gas is squeezed out: a linear response
//! underestimates the pressure of a pore that loses a sizeable part of its gas (by 45 % in a
//! pore of 8·10⁻¹² m³ moved by 0.2 µm), and the DEM then closes it further than the flow
//! allows.
//!
//! An explicit DEM would have to resolve this stiffness: a liquid-filled pore of 10⁻¹² m³
//! pushes its spheres with `k = K g²/V` of order 10¹¹ N/m, `ω Δt_D` of 4 at case a's scaled
//! DEM step, and without gas the stiffness grows without bound. (The first form of this
//! option halved the DEM sub-step to keep `ω h ≤ 1/2` and stopped a step whose pores stiffened
//! past `ω h = 1`; case a then stopped at 0.41 s, and with the narrow-gap apertures at 1.63 s,
//! each time at a sphere whose pores needed sub-steps far below 10⁻⁷ s.) The pores' springs
//! are therefore integrated implicitly ([`UndrainedPores::implicit_correction`]): after each
//! explicit DEM sub-step the velocities solve `(M + h² K) v = M v*`, backward Euler in the
//! spring forces linearised about the sub-step's start (`K = Σ_i k_i g_i g_iᵀ` with the
//! tangent `k_i`), which is stable at any stiffness; the tangent is taken again at every
//! sub-step, so the hyperbolic stiffening of a pore losing its gas is followed.

use thm_dem::{DemState, Vec3};
use thm_vpn_flow::{FlowState, Phase, PoreFluid};
use thm_vpn_mesh::{PackingMesh, VertexConstraint};

use super::error::CouplingError;

/// Sparse `∂V_i/∂c_s` of every pore (compressed rows by pore).
#[derive(Debug, Clone, Default)]
pub struct PoreVolumeGradient {
    start: Vec<u32>,
    sphere: Vec<u32>,
    gradient: Vec<[f64; 2]>,
}

impl PoreVolumeGradient {
    /// Builds the gradient of every pore volume from the mesh as it is; `pore_cell[i]` is pore
    /// `i`'s cell.
    pub fn build(&mut self, mesh: &PackingMesh, pore_cell: &[u32]) -> Result<(), CouplingError> {
        let m = &mesh.mesh;
        let a = &mesh.anchors;
        let w = m.thickness;
        self.start.clear();
        self.sphere.clear();
        self.gradient.clear();
        self.start.push(0);
        let mut row: Vec<(u32, [f64; 2])> = Vec::with_capacity(12);
        for (i, &cell) in pore_cell.iter().enumerate() {
            let cell = cell as usize;
            let Some(&corners) = m.cell_vertices.get(cell) else {
                return Err(CouplingError::StateMismatch {
                    what: "pore cell of the mesh",
                    got: cell,
                    expected: m.n_cells(),
                });
            };
            let x = corners.map(|v| m.vertices[v as usize]);
            let signed = (x[1][0] - x[0][0]) * (x[2][1] - x[0][1])
                - (x[1][1] - x[0][1]) * (x[2][0] - x[0][0]);
            let orient = if signed >= 0.0 { 0.5 * w } else { -0.5 * w };
            row.clear();
            for k in 0..3 {
                let (b, c) = (x[(k + 1) % 3], x[(k + 2) % 3]);
                let mut g = [orient * (b[1] - c[1]), orient * (c[0] - b[0])];
                let v = corners[k] as usize;
                match a.constraint.get(v) {
                    Some(VertexConstraint::Free) => {}
                    Some(VertexConstraint::OnSide(side)) => g[usize::from(*side >= 2)] = 0.0,
                    Some(VertexConstraint::Fixed) => continue,
                    None => {
                        return Err(CouplingError::StateMismatch {
                            what: "vertex anchors",
                            got: a.len(),
                            expected: v + 1,
                        });
                    }
                }
                let (s0, s1) = (a.start[v] as usize, a.start[v + 1] as usize);
                if s1 == s0 {
                    continue;
                }
                let share = 1.0 / (s1 - s0) as f64;
                for &s in &a.circle[s0..s1] {
                    match row.iter_mut().find(|(t, _)| *t == s) {
                        Some((_, acc)) => {
                            acc[0] += share * g[0];
                            acc[1] += share * g[1];
                        }
                        None => row.push((s, [share * g[0], share * g[1]])),
                    }
                }
            }
            row.sort_unstable_by_key(|(s, _)| *s);
            for &(s, g) in &row {
                if !(g[0].is_finite() && g[1].is_finite()) {
                    return Err(CouplingError::Unphysical {
                        stage: "fluid forces",
                        quantity: "pore volume gradient",
                        place: "pore",
                        index: i,
                        value: if g[0].is_finite() { g[1] } else { g[0] },
                        step: 0,
                        why: "not finite",
                    });
                }
                self.sphere.push(s);
                self.gradient.push(g);
            }
            self.start.push(self.sphere.len() as u32);
        }
        Ok(())
    }

    /// Number of pores.
    pub fn n_pores(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// The spheres and gradients `∂V_i/∂c_s` \[m²\] of pore `i`.
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[[f64; 2]]) {
        let (a, b) = (self.start[i] as usize, self.start[i + 1] as usize);
        (&self.sphere[a..b], &self.gradient[a..b])
    }

    /// This gradient without the entries of the spheres marked in `drop`, into `out`.
    pub fn without_spheres(&self, drop: &[bool], out: &mut PoreVolumeGradient) {
        out.start.clear();
        out.sphere.clear();
        out.gradient.clear();
        out.start.push(0);
        for i in 0..self.n_pores() {
            let (s, g) = self.row(i);
            for (&s, &g) in s.iter().zip(g) {
                if !drop.get(s as usize).copied().unwrap_or(false) {
                    out.sphere.push(s);
                    out.gradient.push(g);
                }
            }
            out.start.push(out.sphere.len() as u32);
        }
    }

    /// Adds `Σ_i P_i ∂V_i/∂c_s` to `out[s]` \[N\].
    pub fn add_forces(&self, pressure: &[f64], out: &mut [[f64; 2]]) {
        for (i, &p) in pressure.iter().enumerate().take(self.n_pores()) {
            let (s, g) = self.row(i);
            for (&s, g) in s.iter().zip(g) {
                if let Some(o) = out.get_mut(s as usize) {
                    o[0] += p * g[0];
                    o[1] += p * g[1];
                }
            }
        }
    }
}

/// The undrained pore response over one coupled step (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct UndrainedPores {
    gradient: PoreVolumeGradient,
    /// `gradient` without the entries of held spheres (the implicit correction's rows).
    free: PoreVolumeGradient,
    start_pressure: Vec<f64>,
    liquid_volume: Vec<f64>,
    gas_volume: Vec<f64>,
    liquid_modulus: Vec<f64>,
    gas_modulus: Vec<f64>,
    start_centre: Vec<[f64; 2]>,
    other_force: Vec<[f64; 2]>,
    pressure: Vec<f64>,
    tangent: Vec<f64>,
    force: Vec<[f64; 2]>,
    /// Conjugate-gradient vectors of [`UndrainedPores::implicit_correction`] (per sphere:
    /// the explicit velocities, the correction, residual, preconditioned residual, direction
    /// and product).
    cg: [Vec<[f64; 2]>; 6],
    /// Its Jacobi preconditioner (per sphere and axis).
    cg_diagonal: Vec<[f64; 2]>,
}

/// Relative residual at which the implicit correction's conjugate gradients stop.
const IMPLICIT_TOLERANCE: f64 = 1e-12;
/// Most conjugate-gradient iterations of one implicit correction.
const IMPLICIT_ITERATIONS: usize = 500;

/// Pressure and tangent stiffness `−dP/dV` of the two-phase spring of one pore (module docs)
/// for the volume change `dv`.
fn spring(p0: f64, vq: f64, vg: f64, kq: f64, kp: f64, dv: f64) -> (f64, f64) {
    // Shifted pressure Π = P − P⁰ + K_p solves a Π² + b Π − c = 0.
    let a = if vq > 0.0 { vq / kq } else { 0.0 };
    let b = vg + dv - a * kp;
    let c = kp * vg;
    let pi = if c <= 0.0 {
        if a > 0.0 { (-b / a).max(0.0) } else { 0.0 }
    } else if b >= 0.0 {
        2.0 * c / (b + (b * b + 4.0 * a * c).sqrt())
    } else {
        (-b + (b * b + 4.0 * a * c).sqrt()) / (2.0 * a)
    };
    let p = pi + p0 - kp;
    if p <= 0.0 {
        return (0.0, 0.0);
    }
    let denom = 2.0 * a * pi + b;
    let tangent = if denom > 0.0 { pi / denom } else { 0.0 };
    (p, tangent)
}

impl UndrainedPores {
    /// Starts a coupled step: the gradients of the mesh as it is, the pressures and phase
    /// volumes of the flow state with the bulk moduli `fluid` gives them, the centres of
    /// `dem`, and `other_force` (the shear of A-Eq. 54), which is held over the step.
    pub fn begin<F: PoreFluid>(
        &mut self,
        mesh: &PackingMesh,
        pore_cell: &[u32],
        flow: &FlowState,
        fluid: &F,
        dem: &DemState,
        other_force: &[[f64; 2]],
    ) -> Result<(), CouplingError> {
        self.gradient.build(mesh, pore_cell)?;
        self.gradient
            .without_spheres(&dem.particles.fixed, &mut self.free);
        let np = self.gradient.n_pores();
        if flow.pressure.len() != np {
            return Err(CouplingError::StateMismatch {
                what: "flow pores",
                got: flow.pressure.len(),
                expected: np,
            });
        }
        let p = &dem.particles;
        self.start_pressure.clear();
        self.start_pressure.extend_from_slice(&flow.pressure);
        self.liquid_volume.clear();
        self.gas_volume.clear();
        self.liquid_modulus.clear();
        self.gas_modulus.clear();
        for i in 0..np {
            let (v, a, t) = (flow.volume[i], flow.liquid_fraction[i], flow.temperature[i]);
            let modulus = |phase, density: f64| -> Result<f64, CouplingError> {
                let k = fluid.bulk_modulus(phase, density, t).map_err(|_| {
                    CouplingError::Unphysical {
                        stage: "fluid forces",
                        quantity: "phase bulk modulus",
                        place: "pore",
                        index: i,
                        value: density,
                        step: flow.step,
                        why: "the fluid model gives no bulk modulus there",
                    }
                })?;
                if k.is_finite() && k > 0.0 {
                    Ok(k)
                } else {
                    Err(CouplingError::Unphysical {
                        stage: "fluid forces",
                        quantity: "phase bulk modulus",
                        place: "pore",
                        index: i,
                        value: k,
                        step: flow.step,
                        why: "not finite and positive",
                    })
                }
            };
            let kq = if a > 0.0 {
                modulus(Phase::Liquid, flow.liquid_density[i])?
            } else {
                1.0
            };
            let kp = if a < 1.0 {
                modulus(Phase::Gas, flow.gas_density[i])?
            } else {
                1.0
            };
            self.liquid_volume.push(a * v);
            self.gas_volume.push((1.0 - a) * v);
            self.liquid_modulus.push(kq);
            self.gas_modulus.push(kp);
        }
        self.start_centre.clear();
        self.start_centre
            .extend(p.position.iter().map(|x| [x.x, x.y]));
        self.other_force.clear();
        self.other_force.extend_from_slice(other_force);
        self.pressure.clear();
        self.tangent.clear();
        for i in 0..np {
            let (p, k) = self.response(i, 0.0);
            self.pressure.push(p);
            self.tangent.push(k);
        }
        self.force.resize(p.len(), [0.0; 2]);
        Ok(())
    }

    fn response(&self, i: usize, dv: f64) -> (f64, f64) {
        spring(
            self.start_pressure[i],
            self.liquid_volume[i],
            self.gas_volume[i],
            self.liquid_modulus[i],
            self.gas_modulus[i],
            dv,
        )
    }

    /// Sets the spheres' external forces from the pressures their present centres give (and
    /// the tangents [`UndrainedPores::implicit_correction`] uses).
    pub fn apply(&mut self, dem: &mut DemState, step: u64) -> Result<(), CouplingError> {
        let p = &mut dem.particles;
        for i in 0..self.gradient.n_pores() {
            let (s, g) = self.gradient.row(i);
            let mut dv = 0.0;
            for (&s, g) in s.iter().zip(g) {
                let (x, x0) = (p.position[s as usize], self.start_centre[s as usize]);
                dv += g[0] * (x.x - x0[0]) + g[1] * (x.y - x0[1]);
            }
            let (pressure, tangent) = self.response(i, dv);
            self.pressure[i] = pressure;
            self.tangent[i] = tangent;
        }
        self.force.copy_from_slice(&self.other_force);
        self.gradient.add_forces(&self.pressure, &mut self.force);
        for (out, f) in p.external_force.iter_mut().zip(&self.force) {
            *out = Vec3::new(f[0], f[1], 0.0);
        }
        for s in 0..self.force.len() {
            if !(self.force[s][0].is_finite() && self.force[s][1].is_finite()) {
                return Err(CouplingError::Unphysical {
                    stage: "DEM",
                    quantity: "pore pressure force",
                    place: "sphere",
                    index: s,
                    value: self.force[s][0] + self.force[s][1],
                    step,
                    why: "not finite",
                });
            }
        }
        Ok(())
    }

    /// `out = K x` with `K = Σ_i k_i g_i g_iᵀ` over the free spheres (`k_i` the tangents of the
    /// last [`UndrainedPores::apply`]).
    /// `free` holds the gradient rows without their held spheres (a held sphere's entries
    /// were skipped, so the sums are the same to the bit).
    fn product(free: &PoreVolumeGradient, tangent: &[f64], x: &[[f64; 2]], out: &mut [[f64; 2]]) {
        out.fill([0.0; 2]);
        for (i, &k) in tangent.iter().enumerate().take(free.n_pores()) {
            if k == 0.0 {
                continue;
            }
            let (s, g) = free.row(i);
            let mut d = 0.0;
            for (&s, g) in s.iter().zip(g) {
                let x = x[s as usize];
                d += g[0] * x[0] + g[1] * x[1];
            }
            let kd = k * d;
            for (&s, g) in s.iter().zip(g) {
                let o = &mut out[s as usize];
                o[0] += kd * g[0];
                o[1] += kd * g[1];
            }
        }
    }

    /// After a DEM step of `h` taken with the forces of [`UndrainedPores::apply`]: makes the
    /// pores' springs implicit. The explicit step gave `v*` with the pore forces of the step's
    /// start; backward Euler in the linearised spring forces,
    /// `F(x + h v) ≈ F(x) − h K v` with `K = Σ_i k_i g_i g_iᵀ`, gives `(M + h² K) v = M v*`.
    /// The correction `δ = v* − v` solves `(M + h² K) δ = h² K v*` (conjugate gradients,
    /// Jacobi-preconditioned, `M + h² K` symmetric positive definite over the free spheres),
    /// and the spheres take `v = v* − δ`, `x = x* − h δ`. Unconditionally stable for the
    /// linearised springs, so the sub-step need not resolve the stiffness of a pore that is
    /// nearly out of gas.
    pub fn implicit_correction(
        &mut self,
        dem: &mut DemState,
        h: f64,
        step: u64,
    ) -> Result<(), CouplingError> {
        let n = dem.particles.len();
        let h2 = h * h;
        for v in &mut self.cg {
            v.clear();
            v.resize(n, [0.0; 2]);
        }
        self.cg_diagonal.clear();
        self.cg_diagonal.resize(n, [0.0; 2]);
        let p = &dem.particles;
        let [velocity, delta, r, z, d, q] = &mut self.cg;
        // Right-hand side h² K v* into r (δ = 0 to start, so the residual is the rhs).
        for (out, v) in velocity.iter_mut().zip(&p.velocity) {
            *out = [v.x, v.y];
        }
        Self::product(&self.free, &self.tangent, velocity, r);
        let mut rhs_norm = 0.0;
        for r in r.iter_mut() {
            r[0] *= h2;
            r[1] *= h2;
            rhs_norm += r[0] * r[0] + r[1] * r[1];
        }
        if rhs_norm == 0.0 {
            return Ok(());
        }
        for (s, diag) in self.cg_diagonal.iter_mut().enumerate() {
            *diag = [p.mass[s]; 2];
        }
        for i in 0..self.free.n_pores() {
            let k = self.tangent[i];
            let (s, g) = self.free.row(i);
            for (&s, g) in s.iter().zip(g) {
                let diag = &mut self.cg_diagonal[s as usize];
                diag[0] += h2 * k * g[0] * g[0];
                diag[1] += h2 * k * g[1] * g[1];
            }
        }
        let precondition = |r: &[[f64; 2]], z: &mut [[f64; 2]], diag: &[[f64; 2]]| {
            for ((z, r), d) in z.iter_mut().zip(r).zip(diag) {
                *z = [r[0] / d[0], r[1] / d[1]];
            }
        };
        let dot = |a: &[[f64; 2]], b: &[[f64; 2]]| -> f64 {
            a.iter()
                .zip(b)
                .map(|(a, b)| a[0] * b[0] + a[1] * b[1])
                .sum()
        };
        precondition(r, z, &self.cg_diagonal);
        d.copy_from_slice(z);
        let mut rz = dot(r, z);
        let mut converged = false;
        for _ in 0..IMPLICIT_ITERATIONS {
            Self::product(&self.free, &self.tangent, d, q);
            for (s, (q, d)) in q.iter_mut().zip(d.iter()).enumerate() {
                let m = if p.fixed[s] { 0.0 } else { p.mass[s] };
                q[0] = m * d[0] + h2 * q[0];
                q[1] = m * d[1] + h2 * q[1];
            }
            let dq = dot(d, q);
            if dq.is_nan() || dq <= 0.0 {
                converged = rz == 0.0;
                break;
            }
            let alpha = rz / dq;
            let mut r_norm = 0.0;
            for (((delta, r), d), q) in delta
                .iter_mut()
                .zip(r.iter_mut())
                .zip(d.iter())
                .zip(q.iter())
            {
                delta[0] += alpha * d[0];
                delta[1] += alpha * d[1];
                r[0] -= alpha * q[0];
                r[1] -= alpha * q[1];
                r_norm += r[0] * r[0] + r[1] * r[1];
            }
            if r_norm <= IMPLICIT_TOLERANCE * IMPLICIT_TOLERANCE * rhs_norm {
                converged = true;
                break;
            }
            precondition(r, z, &self.cg_diagonal);
            let rz_new = dot(r, z);
            let beta = rz_new / rz;
            rz = rz_new;
            for (d, z) in d.iter_mut().zip(z.iter()) {
                d[0] = z[0] + beta * d[0];
                d[1] = z[1] + beta * d[1];
            }
        }
        if !converged {
            return Err(CouplingError::Unphysical {
                stage: "DEM",
                quantity: "implicit pore spring residual",
                place: "packing",
                index: 0,
                value: (dot(r, r) / rhs_norm).sqrt(),
                step,
                why: "the conjugate gradients did not converge",
            });
        }
        let p = &mut dem.particles;
        for (s, delta) in delta.iter().enumerate() {
            if p.fixed[s] {
                continue;
            }
            p.velocity[s].x -= delta[0];
            p.velocity[s].y -= delta[1];
            p.position[s].x -= h * delta[0];
            p.position[s].y -= h * delta[1];
            if !(p.position[s].x.is_finite() && p.position[s].y.is_finite()) {
                return Err(CouplingError::Unphysical {
                    stage: "DEM",
                    quantity: "implicit pore spring correction",
                    place: "sphere",
                    index: s,
                    value: delta[0] + delta[1],
                    step,
                    why: "not finite",
                });
            }
        }
        Ok(())
    }

    /// The pressure force alone, `Σ_i P_i⁰ ∂V_i/∂c_s`, at the step's start pressures, added to
    /// `out`.
    pub fn add_start_forces(&self, out: &mut [[f64; 2]]) {
        self.gradient.add_forces(&self.start_pressure, out);
    }

    /// The undrained pressures of the last [`UndrainedPores::apply`] (the start pressures
    /// after [`UndrainedPores::begin`]) \[Pa\].
    pub fn pressures(&self) -> &[f64] {
        &self.pressure
    }

    /// The undrained tangent stiffnesses `−dP_i/dV_i` of the last
    /// [`UndrainedPores::apply`] \[Pa/m³\].
    pub fn tangents(&self) -> &[f64] {
        &self.tangent
    }
}
