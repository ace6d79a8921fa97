//! The time step: a fixed sequence of named stages over caller-owned state.
//!
//! 1. [`Stepper::update_neighbours`]: Verlet-list check; cell-grid search and merge of the
//!    contact histories when a particle (or wall) moved more than half the skin;
//! 2. [`Stepper::compute_contact_forces`]: every contact in parallel, each writing only its own
//!    history and response, reading the particles from one compact record each (copied in
//!    parallel at the start of the stage); reports whether a bond broke (a boolean OR);
//! 3. [`Stepper::collect_events`]: broken-bond events (the contacts are scanned only when a
//!    bond broke) and wall forces, serially in contact order;
//! 4. [`Stepper::gather_forces`]: every particle sums its own contacts in contact-index order,
//!    plus external force and gravity (no atomics: the same bits for any thread count);
//! 5. [`Stepper::integrate`]: Cundall's non-viscous damping (A-Eq. 7) and leapfrog, with the
//!    finiteness check in the same pass (the first bad particle is a minimum over indices);
//! 6. walls move at their prescribed velocity.

use crate::contact::{
    BondState, ContactHistory, ContactKinematics, ContactLaw, ContactResponse, PairInput,
};
use crate::error::{DemError, check_positive, check_range};
use crate::neighbour::CellGrid;
use crate::state::{BondBreak, ContactList, DemState, ParticleState};
use crate::vec3::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Loops shorter than this run serially (rayon's dispatch would cost more than the work);
/// either way every item is computed by the same code, so the bits do not change.
const PAR_THRESHOLD: usize = 1024;
/// Smallest chunk handed to a rayon worker.
const MIN_PAR_LEN: usize = 256;

/// Parameters of the time integration, as read from a file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepperParams {
    /// Time step Δt \[s\] (see [`critical_time_step`]).
    pub time_step: f64,
    /// Cundall's non-viscous damping `α_d` ∈ [0, 1) (A-Eq. 7; Krzaczek et al. use 0.08).
    pub damping: f64,
    /// Gravitational acceleration \[m/s²\].
    pub gravity: [f64; 3],
    /// Verlet skin \[m\]: pairs closer than `R_a + R_b + skin` are listed; the list is rebuilt
    /// when a particle or wall moved (or a radius grew) by more than half of it.
    pub verlet_skin: f64,
}

/// Validated [`StepperParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepperConfig {
    params: StepperParams,
    gravity: Vec3,
}

impl StepperParams {
    /// Validates.
    pub fn validate(&self) -> Result<StepperConfig, DemError> {
        check_positive("time_step", self.time_step)?;
        check_range("damping", self.damping, 0.0, 0.999_999, "[0, 1)")?;
        for (k, g) in self.gravity.iter().enumerate() {
            let field = ["gravity[0]", "gravity[1]", "gravity[2]"][k];
            check_range(field, *g, -1e6, 1e6, "[-1e6, 1e6] m/s²")?;
        }
        check_positive("verlet_skin", self.verlet_skin)?;
        Ok(StepperConfig {
            params: *self,
            gravity: Vec3::new(self.gravity[0], self.gravity[1], self.gravity[2]),
        })
    }
}

impl StepperConfig {
    /// The validated parameters.
    pub fn params(&self) -> &StepperParams {
        &self.params
    }
}

/// Advances a [`DemState`] with a contact law. Holds only scratch buffers (neighbour grid,
/// per-particle contact index), so one stepper can advance any state.
#[derive(Debug)]
pub struct Stepper<L: ContactLaw> {
    law: L,
    config: StepperConfig,
    grid: CellGrid,
    candidates: Vec<[u32; 2]>,
    merged: ContactList,
    /// `csr_start[i]..csr_start[i+1]` indexes `csr_entry` for particle `i`; an entry is
    /// `contact << 1 | is_b`.
    csr_start: Vec<u32>,
    csr_entry: Vec<u32>,
    wall_csr_start: Vec<u32>,
    wall_csr_entry: Vec<u32>,
    csr_cursor: Vec<u32>,
    csr_key: Option<(u64, usize, usize, usize)>,
    record: Vec<ParticleRecord>,
}

/// What a contact reads of a particle, in one record: two cache lines per particle of a pair
/// instead of one line in each of five arrays.
#[derive(Debug, Clone, Copy, Default)]
struct ParticleRecord {
    position: Vec3,
    velocity: Vec3,
    angular_velocity: Vec3,
    radius: f64,
    temperature: f64,
}

impl<L: ContactLaw> Stepper<L> {
    /// A stepper with empty scratch buffers.
    pub fn new(law: L, config: StepperConfig) -> Self {
        Self {
            law,
            config,
            grid: CellGrid::default(),
            candidates: Vec::new(),
            merged: ContactList::default(),
            csr_start: Vec::new(),
            csr_entry: Vec::new(),
            wall_csr_start: Vec::new(),
            wall_csr_entry: Vec::new(),
            csr_cursor: Vec::new(),
            csr_key: None,
            record: Vec::new(),
        }
    }

    /// The contact law.
    pub fn law(&self) -> &L {
        &self.law
    }

    /// The configuration.
    pub fn config(&self) -> &StepperConfig {
        &self.config
    }

    /// Replaces the time step (e.g. after radii changed) \[s\].
    pub fn set_time_step(&mut self, dt: f64) -> Result<(), DemError> {
        self.config.params.time_step = check_positive("time_step", dt)?;
        Ok(())
    }

    /// One time step. Runs in the current rayon pool; the result does not depend on its size.
    pub fn step(&mut self, state: &mut DemState) -> Result<(), DemError> {
        self.update_neighbours(state)?;
        let any_broke = self.compute_contact_forces(state);
        self.collect_events(state, any_broke);
        self.gather_forces(state);
        self.integrate(state)?;
        let dt = self.config.params.time_step;
        for w in &mut state.walls {
            w.point += w.velocity * dt;
        }
        state.step += 1;
        state.time += dt;
        Ok(())
    }

    /// `n` steps.
    pub fn run(&mut self, state: &mut DemState, n: u64) -> Result<(), DemError> {
        for _ in 0..n {
            self.step(state)?;
        }
        Ok(())
    }

    /// Stage 1: rebuilds the contact lists when the Verlet criterion asks for it, and the
    /// per-particle contact index when the lists changed.
    pub fn update_neighbours(&mut self, state: &mut DemState) -> Result<(), DemError> {
        if self.needs_search(state) {
            state.validate()?;
            self.search(state);
        }
        let key = (
            state.contact_generation,
            state.contacts.len(),
            state.wall_contacts.len(),
            state.particles.len(),
        );
        if self.csr_key != Some(key) {
            state.validate()?;
            let n = state.particles.len();
            let cursor = &mut self.csr_cursor;
            build_csr(
                n,
                &state.contacts.pair,
                true,
                &mut self.csr_start,
                &mut self.csr_entry,
                cursor,
            );
            build_csr(
                n,
                &state.wall_contacts.pair,
                false,
                &mut self.wall_csr_start,
                &mut self.wall_csr_entry,
                cursor,
            );
            self.csr_key = Some(key);
        }
        Ok(())
    }

    fn needs_search(&self, state: &DemState) -> bool {
        let p = &state.particles;
        if state.search_reference_position.len() != p.len()
            || state.search_reference_radius.len() != p.len()
            || state.search_reference_wall_point.len() != state.walls.len()
        {
            return true;
        }
        let half_skin = 0.5 * self.config.params.verlet_skin;
        let displacement = |((x, x0), (r, r0)): ((&Vec3, &Vec3), (&f64, &f64))| {
            (*x - *x0).norm() + (r - r0).max(0.0)
        };
        let particle_max = if p.len() >= PAR_THRESHOLD {
            p.position
                .par_iter()
                .zip(&state.search_reference_position)
                .zip(p.radius.par_iter().zip(&state.search_reference_radius))
                .with_min_len(MIN_PAR_LEN)
                .map(displacement)
                .reduce(|| 0.0, f64::max)
        } else {
            p.position
                .iter()
                .zip(&state.search_reference_position)
                .zip(p.radius.iter().zip(&state.search_reference_radius))
                .map(displacement)
                .fold(0.0, f64::max)
        };
        let wall_max = state
            .walls
            .iter()
            .zip(&state.search_reference_wall_point)
            .map(|(w, p0)| (w.point - *p0).norm())
            .fold(0.0, f64::max);
        particle_max + wall_max > half_skin || !particle_max.is_finite()
    }

    fn search(&mut self, state: &mut DemState) {
        let skin = self.config.params.verlet_skin;
        self.grid
            .pairs_within(&state.particles, skin, &mut self.candidates);
        merge_contacts(&state.contacts, &self.candidates, &mut self.merged);
        std::mem::swap(&mut state.contacts, &mut self.merged);
        // Keep 25 % headroom in the contact buffers so that the pair count may fluctuate
        // without reallocating.
        let headroom = state.contacts.len() + state.contacts.len() / 4 + 16;
        reserve_to(&mut self.candidates, headroom);
        reserve_to(&mut self.merged.pair, headroom);
        reserve_to(&mut self.merged.history, headroom);
        reserve_to(&mut self.merged.response, headroom);
        reserve_to(&mut state.contacts.pair, headroom);
        reserve_to(&mut state.contacts.history, headroom);
        reserve_to(&mut state.contacts.response, headroom);

        self.candidates.clear();
        let p = &state.particles;
        for i in 0..p.len() {
            for (w, wall) in state.walls.iter().enumerate() {
                if (p.position[i] - wall.point).dot(wall.normal) - p.radius[i] < skin {
                    self.candidates.push([i as u32, w as u32]);
                }
            }
        }
        merge_contacts(&state.wall_contacts, &self.candidates, &mut self.merged);
        std::mem::swap(&mut state.wall_contacts, &mut self.merged);

        state.search_reference_position.clear();
        state
            .search_reference_position
            .extend_from_slice(&p.position);
        state.search_reference_radius.clear();
        state.search_reference_radius.extend_from_slice(&p.radius);
        state.search_reference_wall_point.clear();
        state
            .search_reference_wall_point
            .extend(state.walls.iter().map(|w| w.point));
        state.contact_generation += 1;
    }

    /// Stage 2: forces of all particle–particle and particle–wall contacts, in parallel.
    /// Returns whether a bond broke in this step (an OR over contacts: the same for any
    /// thread count), so that stage 3 scans the responses only then.
    pub fn compute_contact_forces(&mut self, state: &mut DemState) -> bool {
        let dt = self.config.params.time_step;
        let law = &self.law;
        let DemState {
            particles: p,
            contacts,
            walls,
            wall_contacts,
            ..
        } = state;
        let p: &ParticleState = p;
        let n = p.len();
        self.record.clear();
        self.record.resize(n, ParticleRecord::default());
        let fill = |(i, rec): (usize, &mut ParticleRecord)| {
            *rec = ParticleRecord {
                position: p.position[i],
                velocity: p.velocity[i],
                angular_velocity: p.angular_velocity[i],
                radius: p.radius[i],
                temperature: p.temperature[i],
            };
        };
        if n >= PAR_THRESHOLD {
            self.record
                .par_iter_mut()
                .enumerate()
                .with_min_len(MIN_PAR_LEN)
                .for_each(fill);
        } else {
            self.record.iter_mut().enumerate().for_each(fill);
        }
        let rec: &[ParticleRecord] = &self.record;
        let particle_contact =
            |((h, r), pair): ((&mut ContactHistory, &mut ContactResponse), &[u32; 2])| {
                let (pa, pb) = (&rec[pair[0] as usize], &rec[pair[1] as usize]);
                let branch = pb.position - pa.position;
                // Candidate pairs that do not touch (most of a Verlet list) cost one
                // squared distance; their response is cleared only if it was not already.
                if h.bond != BondState::Intact && h.shear_force == Vec3::ZERO {
                    let reach = pa.radius + pb.radius - h.reference_penetration;
                    if reach <= 0.0 || branch.norm_squared() >= reach * reach {
                        h.normal = Vec3::ZERO;
                        if r.active || r.broke.is_some() {
                            *r = ContactResponse::default();
                        }
                        return false;
                    }
                }
                let kin = ContactKinematics::from_pair(
                    branch,
                    pb.velocity - pa.velocity,
                    pa.angular_velocity,
                    pb.angular_velocity,
                    pa.radius,
                    pb.radius,
                    dt,
                );
                let input = PairInput {
                    radius_a: pa.radius,
                    radius_b: pb.radius,
                    temperature: 0.5 * (pa.temperature + pb.temperature),
                };
                *r = law.respond(&input, &kin, h);
                r.broke.is_some()
            };
        let any_broke = if contacts.len() >= PAR_THRESHOLD {
            contacts
                .history
                .par_iter_mut()
                .zip(contacts.response.par_iter_mut())
                .zip(contacts.pair.par_iter())
                .with_min_len(MIN_PAR_LEN)
                .map(particle_contact)
                .reduce(|| false, |x, y| x | y)
        } else {
            contacts
                .history
                .iter_mut()
                .zip(contacts.response.iter_mut())
                .zip(contacts.pair.iter())
                .map(particle_contact)
                .fold(false, |x, y| x | y)
        };
        let walls: &[crate::state::Wall] = walls;
        let wall_contact =
            |((h, r), pair): ((&mut ContactHistory, &mut ContactResponse), &[u32; 2])| {
                let (a, w) = (pair[0] as usize, pair[1] as usize);
                let wall = &walls[w];
                let kin = ContactKinematics::from_wall(
                    p.position[a],
                    p.velocity[a],
                    p.angular_velocity[a],
                    p.radius[a],
                    wall.point,
                    wall.normal,
                    wall.velocity,
                    dt,
                );
                let input = PairInput {
                    radius_a: p.radius[a],
                    radius_b: p.radius[a],
                    temperature: p.temperature[a],
                };
                *r = law.respond(&input, &kin, h);
            };
        if wall_contacts.len() >= PAR_THRESHOLD {
            wall_contacts
                .history
                .par_iter_mut()
                .zip(wall_contacts.response.par_iter_mut())
                .zip(wall_contacts.pair.par_iter())
                .with_min_len(MIN_PAR_LEN)
                .for_each(wall_contact);
        } else {
            wall_contacts
                .history
                .iter_mut()
                .zip(wall_contacts.response.iter_mut())
                .zip(wall_contacts.pair.iter())
                .for_each(wall_contact);
        }
        any_broke
    }

    /// Stage 3: broken-bond events (in contact order; the contacts are scanned only when
    /// stage 2 reported a break) and the forces on the walls.
    pub fn collect_events(&self, state: &mut DemState, any_broke: bool) {
        if any_broke {
            for (pair, r) in state.contacts.pair.iter().zip(&state.contacts.response) {
                if let Some(mode) = r.broke {
                    state.bond_breaks.push(BondBreak {
                        a: pair[0],
                        b: pair[1],
                        step: state.step,
                        mode,
                    });
                }
            }
        }
        for w in &mut state.walls {
            w.force = Vec3::ZERO;
        }
        for (pair, r) in state
            .wall_contacts
            .pair
            .iter()
            .zip(&state.wall_contacts.response)
        {
            state.walls[pair[1] as usize].force += r.force_on_b;
        }
    }

    /// Stage 4: resultant force and torque per particle, summed in contact-index order.
    pub fn gather_forces(&self, state: &mut DemState) {
        let g = self.config.gravity;
        let DemState {
            particles,
            contacts,
            wall_contacts,
            ..
        } = state;
        let ParticleState {
            force,
            torque,
            external_force,
            external_torque,
            mass,
            ..
        } = particles;
        let (cs, ce) = (&self.csr_start, &self.csr_entry);
        let (ws, we) = (&self.wall_csr_start, &self.wall_csr_entry);
        let resp = &contacts.response;
        let wresp = &wall_contacts.response;
        let n = force.len();
        let gather = |(i, (f, t)): (usize, (&mut Vec3, &mut Vec3))| {
            let mut fi = Vec3::ZERO;
            let mut ti = Vec3::ZERO;
            for &e in &ce[cs[i] as usize..cs[i + 1] as usize] {
                let r = &resp[(e >> 1) as usize];
                if e & 1 == 1 {
                    fi += r.force_on_b;
                    ti += r.torque_on_b;
                } else {
                    fi -= r.force_on_b;
                    ti += r.torque_on_a;
                }
            }
            for &e in &we[ws[i] as usize..ws[i + 1] as usize] {
                let r = &wresp[(e >> 1) as usize];
                fi -= r.force_on_b;
                ti += r.torque_on_a;
            }
            *f = fi + external_force[i] + g * mass[i];
            *t = ti + external_torque[i];
        };
        if n >= PAR_THRESHOLD {
            force
                .par_iter_mut()
                .zip(torque.par_iter_mut())
                .enumerate()
                .with_min_len(MIN_PAR_LEN)
                .for_each(gather);
        } else {
            force
                .iter_mut()
                .zip(torque.iter_mut())
                .enumerate()
                .for_each(gather);
        }
    }

    /// Stage 5: damping (A-Eq. 7) and leapfrog update; fixed particles move at their
    /// prescribed velocity; plane kinematics keep `z = 0`, `v_z = 0`, `ω_x = ω_y = 0`.
    pub fn integrate(&self, state: &mut DemState) -> Result<(), DemError> {
        let dt = self.config.params.time_step;
        let alpha = self.config.params.damping;
        let step = state.step;
        let ParticleState {
            kinematics,
            position,
            velocity,
            angular_velocity,
            mass,
            inertia,
            fixed,
            force,
            torque,
            ..
        } = &mut state.particles;
        let planar = kinematics.is_planar();
        let n = position.len();
        // Advances particle `i`; returns `i` when its state became non-finite, else `usize::MAX`,
        // so the first bad particle is the minimum (the same for any thread count).
        let advance = |(i, ((x, v), w)): (usize, ((&mut Vec3, &mut Vec3), &mut Vec3))| {
            if !fixed[i] {
                let inv_m = 1.0 / mass[i];
                let inv_i = 1.0 / inertia[i];
                let f = cundall_damping(force[i], *v, dt * inv_m, alpha);
                let t = cundall_damping(torque[i], *w, dt * inv_i, alpha);
                *v += f * (dt * inv_m);
                *w += t * (dt * inv_i);
                if planar {
                    v.z = 0.0;
                    w.x = 0.0;
                    w.y = 0.0;
                }
            }
            *x += *v * dt;
            if x.is_finite() && v.is_finite() && w.is_finite() {
                usize::MAX
            } else {
                i
            }
        };
        let first_bad = if n >= PAR_THRESHOLD {
            position
                .par_iter_mut()
                .zip(velocity.par_iter_mut())
                .zip(angular_velocity.par_iter_mut())
                .enumerate()
                .with_min_len(MIN_PAR_LEN)
                .map(advance)
                .min()
                .unwrap_or(usize::MAX)
        } else {
            position
                .iter_mut()
                .zip(velocity.iter_mut())
                .zip(angular_velocity.iter_mut())
                .enumerate()
                .map(advance)
                .min()
                .unwrap_or(usize::MAX)
        };
        let bad = (first_bad != usize::MAX).then_some(first_bad);
        match bad {
            Some(index) => Err(DemError::NonFinite {
                quantity: "position or velocity",
                index,
                step,
            }),
            None => Ok(()),
        }
    }
}

fn reserve_to<T>(v: &mut Vec<T>, capacity: usize) {
    if v.capacity() < capacity {
        v.reserve(capacity - v.len());
    }
}

/// Cundall's non-viscous damping per component (A-Eq. 7, as YADE's `NewtonIntegrator`):
/// `F_k ← F_k (1 − α_d sgn(F_k v_k))` with `v_k` the mid-step velocity estimate
/// `v_k^{n−½} + ½ Δt F_k/m`: a force that accelerates is reduced, one that decelerates is
/// increased.
#[inline]
pub fn cundall_damping(f: Vec3, v: Vec3, dt_over_m: f64, alpha: f64) -> Vec3 {
    if alpha == 0.0 {
        return f;
    }
    // A select rather than a branch: the sign of `F_k v_k` of a vibrating particle is
    // unpredictable. `1 − copysign(α, s)` is `1 − α` or `1 + α`, the same bits as before.
    let damp = |fk: f64, vk: f64| {
        let s = fk * (vk + 0.5 * dt_over_m * fk);
        let damped = fk * (1.0 - alpha.copysign(s));
        if s != 0.0 { damped } else { fk }
    };
    Vec3::new(damp(f.x, v.x), damp(f.y, v.y), damp(f.z, v.z))
}

/// Merges the old sorted contact list with sorted candidate pairs into `out`: candidates
/// keep their history (or start unbonded); old contacts that are not candidates survive only
/// while their bond is intact.
fn merge_contacts(old: &ContactList, candidates: &[[u32; 2]], out: &mut ContactList) {
    out.clear();
    let mut k = 0;
    for &c in candidates {
        while k < old.len() && old.pair[k] < c {
            if old.history[k].bond == BondState::Intact {
                out.pair.push(old.pair[k]);
                out.history.push(old.history[k]);
                out.response.push(old.response[k]);
            }
            k += 1;
        }
        if k < old.len() && old.pair[k] == c {
            out.pair.push(c);
            out.history.push(old.history[k]);
            out.response.push(old.response[k]);
            k += 1;
        } else {
            out.push(c, ContactHistory::UNBONDED);
        }
    }
    while k < old.len() {
        if old.history[k].bond == BondState::Intact {
            out.pair.push(old.pair[k]);
            out.history.push(old.history[k]);
            out.response.push(old.response[k]);
        }
        k += 1;
    }
}

/// Per-particle contact index in compressed rows, each row in ascending contact order.
fn build_csr(
    n: usize,
    pairs: &[[u32; 2]],
    both: bool,
    start: &mut Vec<u32>,
    entry: &mut Vec<u32>,
    cursor: &mut Vec<u32>,
) {
    start.clear();
    start.resize(n + 1, 0);
    for p in pairs {
        start[p[0] as usize + 1] += 1;
        if both {
            start[p[1] as usize + 1] += 1;
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    entry.clear();
    entry.resize(start[n] as usize, 0);
    cursor.clear();
    cursor.extend_from_slice(&start[..n]);
    for (k, p) in pairs.iter().enumerate() {
        let k = k as u32;
        let a = p[0] as usize;
        entry[cursor[a] as usize] = k << 1;
        cursor[a] += 1;
        if both {
            let b = p[1] as usize;
            entry[cursor[b] as usize] = (k << 1) | 1;
            cursor[b] += 1;
        }
    }
}

/// Critical time step estimate \[s\]: for every free particle `√(m / Σ(K_n + K_s))` over its
/// contacts carrying force (or bonded) and `√(I / Σ K_s R²)`, minimised. For a linear
/// system this is `√2` below the leapfrog stability limit `2/ω_max` (Gershgorin bound on
/// `ω_max² ≤ 2 Σk/m`). Particles with no contact are given two contacts with a twin.
pub fn critical_time_step<L: ContactLaw>(state: &DemState, law: &L) -> f64 {
    let p = &state.particles;
    let n = p.len();
    let mut k_trans = vec![0.0; n];
    let mut k_rot = vec![0.0; n];
    let mut add = |i: usize, kn: f64, ks: f64| {
        k_trans[i] += kn + ks;
        k_rot[i] += ks * p.radius[i] * p.radius[i];
    };
    for ((pair, h), r) in state
        .contacts
        .pair
        .iter()
        .zip(&state.contacts.history)
        .zip(&state.contacts.response)
    {
        if !(r.active || h.bond == BondState::Intact) {
            continue;
        }
        let (a, b) = (pair[0] as usize, pair[1] as usize);
        let props = law.properties(&PairInput {
            radius_a: p.radius[a],
            radius_b: p.radius[b],
            temperature: 0.5 * (p.temperature[a] + p.temperature[b]),
        });
        add(a, props.normal_stiffness, props.shear_stiffness);
        add(b, props.normal_stiffness, props.shear_stiffness);
    }
    let mut dt = f64::INFINITY;
    for i in 0..n {
        if p.fixed[i] {
            continue;
        }
        let (kt, kr) = if k_trans[i] > 0.0 {
            (k_trans[i], k_rot[i])
        } else {
            let props = law.properties(&PairInput {
                radius_a: p.radius[i],
                radius_b: p.radius[i],
                temperature: p.temperature[i],
            });
            let ks = props.shear_stiffness;
            (
                2.0 * (props.normal_stiffness + ks),
                2.0 * ks * p.radius[i] * p.radius[i],
            )
        };
        dt = dt.min((p.mass[i] / kt).sqrt());
        if kr > 0.0 {
            dt = dt.min((p.inertia[i] / kr).sqrt());
        }
    }
    dt
}
