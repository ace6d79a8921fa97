//! The DEM step of an RVE: a fixed sequence of named stages over caller-owned state.
//!
//! 1. [`RveStepper::integrate`]: with the forces of the last evaluation, local damping,
//!    leapfrog for the fluctuating velocity, then the centres move with `ẋ = v_f + L x` and the
//!    cell with `Ḣ = L H` (B-Eqs. 42, 46), both by the same explicit step so that reduced
//!    coordinates see only the fluctuation;
//! 2. [`RveStepper::update_neighbours`]: Verlet check; when a disk moved, the cell deformed or
//!    a radius grew enough to use up the skin, disks are wrapped back into the cell
//!    (B-Eqs. 43–44), the periodic grid lists the near pairs and the contact histories are
//!    carried over pair by pair;
//! 3. [`RveStepper::compute_contact_forces`]: every listed pair, in list order, with the
//!    periodic branch vector `b = x_b + H s − x_a` and the relative velocity
//!    `v_f,b − v_f,a + L b` (B-Eq. 45) of the motion just made, through `thm-dem`'s contact law
//!    (B-Eqs. 35–40); sums disk forces, the contact part of B-Eq. 49 and the friction work of
//!    B-Eq. 32.
//!
//! Forces are evaluated last, at the configuration the step ends in: the stress, fabric and
//! stiffness measured after a step (B-Eqs. 34, 49, 58) belong to the state's own positions and
//! cell, not to those one DEM step earlier, and the shear increment of each evaluation uses the
//! `L` and `Δt` of the motion it follows. (Measured one step early, the stress of an RVE that
//! drives a material point lags its deformation by `Δt/N`, a negative damping that makes the
//! coupled explicit scheme unstable.) A state whose forces were never evaluated starts with
//! zero forces, so its first step moves nothing but the affine field.
//!
//! [`RveStepper::respond`] wraps `substeps` steps with the temperature update (B-Eq. 37) and
//! returns stress, heat source and conductivity (B-Eqs. 33, 34, 49).

use crate::error::{RveError, check_positive};
use crate::kernel::{self, Block, DiskLoad, DiskRecord};
use crate::mat2::Mat2;
use crate::measure;
use crate::neighbour::{Candidate, PeriodicGrid};
use crate::params::RveConfig;
use crate::state::{PeriodicContacts, RveState};
use serde::{Deserialize, Serialize};
use thm_dem::{ContactHistory, Vec2, Vec3};

/// What the material point imposes on its RVE for one macroscopic step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RveLoad {
    /// Velocity gradient **L** \[1/s\], held over the step.
    pub velocity_gradient: Mat2,
    /// Temperature of the material point \[K\].
    pub temperature: f64,
    /// Macroscopic time step Δt \[s\].
    pub dt: f64,
    /// DEM steps per macroscopic step `N` (B-Eq. 33); the DEM step is `Δt / N`.
    pub substeps: u32,
}

/// What the RVE returns to its material point.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct RveResponse {
    /// Homogenised stress σ of B-Eq. 49 \[Pa\], compression positive (the paper's sign).
    pub stress: Mat2,
    /// Friction heat source `Q = Σ E_f / (V N Δt_D)` of B-Eq. 33 \[W/m³\].
    pub heat_source: f64,
    /// Fabric conductivity tensor of B-Eq. 34 \[W/(m K)\].
    pub conductivity: Mat2,
}

/// Advances an [`RveState`]. Holds the configuration and scratch buffers only, so one stepper
/// can advance any state (a batch keeps one per chunk of RVEs).
#[derive(Debug, Clone)]
pub struct RveStepper {
    config: RveConfig,
    grid: PeriodicGrid,
    candidates: Vec<Candidate>,
    merged: PeriodicContacts,
    temperature: Vec<f64>,
    disk: Vec<DiskRecord>,
    load: Vec<DiskLoad>,
    block: Box<Block>,
}

impl RveStepper {
    /// A stepper with empty scratch buffers.
    pub fn new(config: RveConfig) -> Self {
        Self {
            config,
            grid: PeriodicGrid::default(),
            candidates: Vec::new(),
            merged: PeriodicContacts::default(),
            temperature: Vec::new(),
            disk: Vec::new(),
            load: Vec::new(),
            block: Block::new(),
        }
    }

    /// Heap memory of the scratch buffers \[bytes\].
    pub fn heap_bytes(&self) -> usize {
        fn cap<T>(v: &Vec<T>) -> usize {
            v.capacity() * std::mem::size_of::<T>()
        }
        self.grid.heap_bytes()
            + cap(&self.candidates)
            + self.merged.heap_bytes()
            + cap(&self.temperature)
            + cap(&self.disk)
            + cap(&self.load)
            + std::mem::size_of::<Block>()
    }

    /// The configuration.
    #[inline]
    pub fn config(&self) -> &RveConfig {
        &self.config
    }

    /// Replaces the configuration (e.g. the friction coefficient after consolidation).
    pub fn set_config(&mut self, config: RveConfig) {
        self.config = config;
    }

    /// One DEM step of `dt` under the velocity gradient `l`. Returns the friction heat of the
    /// step, `E_f` of B-Eq. 32 \[J\].
    pub fn step(&mut self, state: &mut RveState, l: &Mat2, dt: f64) -> Result<f64, RveError> {
        // The integration leaves the disk records the contact loop reads; a rebuild of the
        // pair list may wrap centres into the cell, so the records' centres follow it.
        self.integrate_into_records(state, l, dt)?;
        if self.update_neighbours(state)? {
            for (record, x) in self.disk.iter_mut().zip(&state.disks.position) {
                record.position = Vec2::from_xy(*x);
            }
        }
        let heat = self.forces_from_records(state, l, dt);
        state.step += 1;
        state.time += dt;
        state.friction_heat_total += heat;
        Ok(heat)
    }

    /// Verlet skin \[m\] of this configuration for a state.
    fn skin(&self, state: &RveState) -> f64 {
        let r_min = state
            .disks
            .reference_radius
            .iter()
            .fold(f64::INFINITY, |m, &r| m.min(r));
        self.config.params().verlet_skin_ratio * r_min
    }

    /// Stage 1: rebuilds the pair list when the skin may be used up. Returns whether it did.
    pub fn update_neighbours(&mut self, state: &mut RveState) -> Result<bool, RveError> {
        if !self.needs_rebuild(state) {
            return Ok(false);
        }
        let skin = self.skin(state);
        // Wrap disks back into the cell (B-Eqs. 43–44); fluctuating velocities are periodic
        // (B-Eq. 45b) and stay as they are.
        for x in &mut state.disks.position {
            let p = state.cell.period_of(*x);
            if p != [0, 0] {
                *x -= state.cell.lattice_vector(p);
            }
        }
        self.grid.pairs_within(
            &state.cell,
            &state.disks.position,
            &state.disks.radius,
            skin,
            &mut self.candidates,
        )?;
        // Carry the histories over, pair by pair (both lists are sorted).
        let old = &state.contacts;
        self.merged.clear();
        self.merged.reserve_for(self.candidates.len());
        let mut k = 0;
        for &(pair, shift) in &self.candidates {
            while k < old.len() && old.pair[k] < pair {
                k += 1;
            }
            let history = if k < old.len() && old.pair[k] == pair {
                old.history[k]
            } else {
                ContactHistory::UNBONDED
            };
            self.merged.push(pair, shift, history);
        }
        // Intact bonds whose pair left the list would vanish silently; the list keeps every
        // pair within the skin, and a bond stretched beyond the skin has broken in tension
        // long before (its strength is far below k_n · skin for B-Eq. 38's β_b ≪ 1).
        std::mem::swap(&mut state.contacts, &mut self.merged);
        let anchor = &mut state.anchor;
        anchor.reduced_position.clear();
        anchor.reduced_position.extend(
            state
                .disks
                .position
                .iter()
                .map(|&x| state.cell.to_reduced(x)),
        );
        anchor.radius.clear();
        anchor.radius.extend_from_slice(&state.disks.radius);
        anchor.cell = *state.cell.matrix();
        anchor.skin = skin;
        Ok(true)
    }

    fn needs_rebuild(&self, state: &RveState) -> bool {
        let a = &state.anchor;
        let n = state.len();
        if a.skin <= 0.0 || a.reduced_position.len() != n || a.radius.len() != n {
            return true;
        }
        let h = state.cell.matrix();
        let deformation = match a.cell.inverse() {
            Some(inv) => h.mul(&inv).add_scaled(&Mat2::IDENTITY, -1.0),
            None => return true,
        };
        let e = deformation.contract(&deformation).sqrt();
        let mut max_disp2 = 0.0_f64;
        let mut max_growth = 0.0_f64;
        let mut r_max = 0.0_f64;
        // Fluctuating displacement since the build: `H (X − X₀) = x − H X₀`.
        for (((x, x0), r), r0) in state
            .disks
            .position
            .iter()
            .zip(&a.reduced_position)
            .zip(&state.disks.radius)
            .zip(&a.radius)
        {
            let d = Vec2::from_xy(*x) - h.apply_vec2(Vec2::from_xy(*x0));
            // Selects rather than `f64::max` (which also orders ±0 and skips NaN in a longer
            // sequence): the same maxima up to the sign of a zero, which the test below
            // cannot see, so the same decision, and a loop the compiler vectorises.
            let (d2, growth) = (d.norm_squared(), r - r0);
            max_disp2 = if d2 > max_disp2 { d2 } else { max_disp2 };
            max_growth = if growth > max_growth {
                growth
            } else {
                max_growth
            };
            r_max = if *r0 > r_max { *r0 } else { r_max };
        }
        let used = 2.0 * max_disp2.sqrt() + e * (2.0 * r_max + a.skin) + 2.0 * max_growth;
        !used.is_finite() || used >= a.skin
    }

    /// Stage 2: contact forces at the present configuration. Fills the disk force and torque
    /// arrays, the per-contact force and branch, and the contact moment `Σ f ⊗ b`. Returns the
    /// friction work of the step (B-Eq. 32) \[J\].
    ///
    /// The disks are first copied into one compact record each (centre, velocity, spin,
    /// radius, temperature), so a contact reads two records instead of ten arrays, and the
    /// forces are summed in list order into compact accumulators.
    pub fn compute_contact_forces(&mut self, state: &mut RveState, l: &Mat2, dt: f64) -> f64 {
        let disks = &state.disks;
        self.disk.clear();
        self.disk.extend(
            disks
                .position
                .iter()
                .zip(&disks.velocity)
                .zip(&disks.angular_velocity)
                .zip(&disks.radius)
                .zip(&disks.temperature)
                .map(|((((x, v), w), &radius), &temperature)| DiskRecord {
                    position: Vec2::from_xy(*x),
                    velocity: Vec2::from_xy(*v),
                    spin: w.z,
                    radius,
                    temperature,
                }),
        );
        self.forces_from_records(state, l, dt)
    }

    /// [`RveStepper::compute_contact_forces`] with the disk records already filled from the
    /// state.
    fn forces_from_records(&mut self, state: &mut RveState, l: &Mat2, dt: f64) -> f64 {
        let law = self.config.law();
        let disks = &mut state.disks;
        self.load.clear();
        self.load.resize(disks.len(), DiskLoad::default());
        let h = *state.cell.matrix();
        let (moment, heat) = kernel::contact_forces(
            law,
            &mut state.contacts,
            &self.disk,
            &mut self.load,
            &mut self.block,
            &h,
            l,
            dt,
        );
        let load = &self.load;
        for ((f, t), ld) in disks
            .force
            .iter_mut()
            .zip(disks.torque.iter_mut())
            .zip(load.iter())
        {
            *f = ld.force.to_vec3();
            *t = Vec3::new(0.0, 0.0, ld.torque);
        }
        state.contact_moment = moment;
        heat
    }

    /// Stage 3: local damping and the leapfrog step of the fluctuating motion, the affine
    /// motion of the centres and the deformation of the cell. Stops with
    /// [`RveError::NonFinite`] on the first non-finite velocity or position.
    pub fn integrate(&self, state: &mut RveState, l: &Mat2, dt: f64) -> Result<(), RveError> {
        let alpha = self.config.params().local_damping;
        let disks = &mut state.disks;
        let mut finite = true;
        for ((((((x, v), w), &m), &inertia), f), t) in disks
            .position
            .iter_mut()
            .zip(disks.velocity.iter_mut())
            .zip(disks.angular_velocity.iter_mut())
            .zip(&disks.mass)
            .zip(&disks.inertia)
            .zip(&disks.force)
            .zip(&disks.torque)
        {
            let (x_new, v_new, w_new) = advance(x, v, w, m, inertia, f, t, l, dt, alpha);
            finite &= v_new.is_finite() && w_new.is_finite() && x_new.is_finite();
        }
        if !finite {
            return Err(first_non_finite(state));
        }
        state.cell.deform(l, dt)
    }

    /// [`RveStepper::integrate`] that also fills the disk records of the contact loop with
    /// the new motion (one pass over the disks instead of two).
    fn integrate_into_records(
        &mut self,
        state: &mut RveState,
        l: &Mat2,
        dt: f64,
    ) -> Result<(), RveError> {
        let alpha = self.config.params().local_damping;
        let disks = &mut state.disks;
        let mut finite = true;
        self.disk.clear();
        self.disk.extend(
            disks
                .position
                .iter_mut()
                .zip(disks.velocity.iter_mut())
                .zip(disks.angular_velocity.iter_mut())
                .zip(&disks.mass)
                .zip(&disks.inertia)
                .zip(&disks.force)
                .zip(&disks.torque)
                .zip(&disks.radius)
                .zip(&disks.temperature)
                .map(
                    |((((((((x, v), w), &m), &inertia), f), t), &radius), &temperature)| {
                        let (x_new, v_new, w_new) =
                            advance(x, v, w, m, inertia, f, t, l, dt, alpha);
                        // `&`, not `&&`: no branch per disk.
                        finite &= v_new.is_finite() & w_new.is_finite() & x_new.is_finite();
                        DiskRecord {
                            position: x_new,
                            velocity: v_new,
                            spin: w_new,
                            radius,
                            temperature,
                        }
                    },
                ),
        );
        if !finite {
            return Err(first_non_finite(state));
        }
        state.cell.deform(l, dt)
    }

    /// Sets every disk to `temperature` and its radius to `R⁽⁰⁾ (1 + β (T − T_ref))`
    /// (B-Eq. 37); masses are kept, inertias follow the radius.
    pub fn set_temperature(
        &mut self,
        state: &mut RveState,
        temperature: f64,
    ) -> Result<(), RveError> {
        check_positive("temperature", temperature)?;
        if state.disks.temperature.iter().all(|&t| t == temperature) {
            return Ok(());
        }
        self.temperature.clear();
        self.temperature.resize(state.len(), temperature);
        let p = self.config.params();
        state.disks.expand_from_reference(
            p.thermal_expansion_coefficient,
            p.reference_temperature,
            &self.temperature,
        )?;
        Ok(())
    }

    /// One macroscopic step of a material point: temperature (B-Eq. 37), `substeps` DEM
    /// steps of `Δt / N` under **L**, then stress (B-Eq. 49), heat source (B-Eq. 33) and
    /// conductivity (B-Eq. 34).
    pub fn respond(
        &mut self,
        state: &mut RveState,
        load: &RveLoad,
    ) -> Result<RveResponse, RveError> {
        if !load.velocity_gradient.is_finite() {
            return Err(RveError::InvalidParameter {
                field: "velocity_gradient",
                value: load.velocity_gradient.max_abs(),
                allowed: "finite",
            });
        }
        check_positive("dt", load.dt)?;
        if load.substeps == 0 {
            return Err(RveError::InvalidParameter {
                field: "substeps",
                value: 0.0,
                allowed: "[1, 2^32)",
            });
        }
        self.set_temperature(state, load.temperature)?;
        let h = load.dt / f64::from(load.substeps);
        let mut heat = 0.0;
        for _ in 0..load.substeps {
            heat += self.step(state, &load.velocity_gradient, h)?;
        }
        let thickness = self.config.params().thickness;
        let volume = state.volume(thickness);
        Ok(RveResponse {
            stress: measure::stress(state, thickness),
            heat_source: heat / (volume * load.dt),
            conductivity: measure::conductivity(state, self.config.params()),
        })
    }
}

/// One disk's leapfrog step (see [`RveStepper::integrate`]): writes the new centre, velocity
/// and spin and returns them.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn advance(
    x: &mut Vec3,
    v: &mut Vec3,
    w: &mut Vec3,
    m: f64,
    inertia: f64,
    f: &Vec3,
    t: &Vec3,
    l: &Mat2,
    dt: f64,
    alpha: f64,
) -> (Vec2, Vec2, f64) {
    let (dt_m, dt_i) = (dt / m, dt / inertia);
    let (fx, fy, tz) = (
        local_damping(f.x, v.x, dt_m, alpha),
        local_damping(f.y, v.y, dt_m, alpha),
        local_damping(t.z, w.z, dt_i, alpha),
    );
    let v_new = Vec2::new(v.x + fx * dt_m, v.y + fy * dt_m);
    let w_new = w.z + tz * dt_i;
    let x_old = Vec2::from_xy(*x);
    let x_new = x_old + (v_new + l.apply_vec2(x_old)) * dt;
    *v = v_new.to_vec3();
    *w = Vec3::new(0.0, 0.0, w_new);
    *x = x_new.to_vec3();
    (x_new, v_new, w_new)
}

/// Cundall's local non-viscous damping of one component: `F − α |F| sgn(v)` with the mid-step
/// velocity estimate `v + ½ Δt F / m` (`dt_m` = Δt / m).
#[inline]
fn local_damping(f: f64, v: f64, dt_m: f64, alpha: f64) -> f64 {
    if alpha == 0.0 {
        return f;
    }
    let v_mid = v + 0.5 * f * dt_m;
    // A select rather than a branch: the sign of a vibrating disk's velocity is unpredictable.
    let damped = f - (alpha * f.abs()).copysign(v_mid);
    if v_mid != 0.0 { damped } else { f }
}

/// The first disk with a non-finite velocity or position (after an integration that produced
/// one).
fn first_non_finite(state: &RveState) -> RveError {
    let d = &state.disks;
    for i in 0..d.len() {
        let quantity = if !(d.velocity[i].is_finite() && d.angular_velocity[i].is_finite()) {
            "fluctuating velocity"
        } else if !d.position[i].is_finite() {
            "position"
        } else {
            continue;
        };
        return RveError::NonFinite {
            quantity,
            index: i,
            step: state.step,
        };
    }
    RveError::NonFinite {
        quantity: "position",
        index: 0,
        step: state.step,
    }
}
