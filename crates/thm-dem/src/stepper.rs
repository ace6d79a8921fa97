//! The time step: a fixed sequence of stages over caller-owned state.
//!
//! 1. neighbours: how far the particles moved since the last search (two bounds, one pass);
//!    cell-grid search and merge of the contact histories when a particle (or wall) moved
//!    more than half the skin; the per-particle contact index when the lists changed;
//! 2. contact forces: every contact in parallel, each writing only its own history, response
//!    and "carried force" flag, and stamping its particles when it carried force (every
//!    stamp of a step is the same value); a listed pair that does not touch (and is neither
//!    bonded nor sheared) costs one distance, and is not looked at again until the drift
//!    since then could have closed its gap; reports whether a bond broke (a boolean OR);
//! 3. events: broken-bond events (the contacts are scanned only when a bond broke) and wall
//!    forces, serially in contact order;
//! 4. gather and integrate, one pass over the particles: every particle sums its own contacts
//!    in contact-index order (those that carried force; when at most a quarter of the
//!    contacts did, only the stamped particles look: the others would add only zeros), plus
//!    external force and gravity (no floating-point atomics: the same bits for any thread
//!    count), then Cundall's non-viscous damping (A-Eq. 7) and leapfrog, with the finiteness
//!    check (the first bad particle is a minimum over indices);
//! 5. walls move at their prescribed velocity.

use crate::contact::{
    BondState, ContactHistory, ContactKinematics, ContactLaw, ContactResponse, PairInput,
};
use crate::error::{DemError, check_positive, check_range};
use crate::neighbour::CellGrid;
use crate::state::{BondBreak, ContactList, DemState, ParticleState};
use crate::vec3::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

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
/// per-particle contact index, particle records), so one stepper can advance any state.
#[derive(Debug)]
pub struct Stepper<L: ContactLaw> {
    law: L,
    config: StepperConfig,
    grid: CellGrid,
    candidates: Vec<[u32; 2]>,
    merged: ContactList,
    /// Contacts with `pair[0] == i` are `a_start[i]..a_start[i+1]` (the list is sorted).
    a_start: Vec<u32>,
    /// Contacts with `pair[1] == i` are `b_entry[b_start[i]..b_start[i+1]]`, ascending.
    b_start: Vec<u32>,
    b_entry: Vec<u32>,
    /// Wall contacts of particle `i` are `wall_start[i]..wall_start[i+1]` (sorted list).
    wall_start: Vec<u32>,
    cursor: Vec<u32>,
    index_key: Option<(u64, usize, usize, usize)>,
    /// Whether each contact carried force in this step: the gather skips the others, whose
    /// force and torques are zero.
    active: Vec<u8>,
    wall_active: Vec<u8>,
    /// `touched[i] == stamp` when particle `i` has a contact that carried force in this step,
    /// stored by the contact pass itself (used only when few contacts did: the gather then
    /// skips the other particles). Every store of a step writes the same value, so the
    /// result does not depend on which thread stores first: relaxed atomics, plain moves on
    /// the common targets, make those concurrent stores defined behaviour.
    touched: Vec<AtomicU32>,
    stamp: u32,
    /// A listed pair found apart (and unbonded, without shear) stays apart while the drift
    /// (see [`Drift`]) is below its entry: it is not looked at again until then.
    quiet_below: Vec<f64>,
}

/// How far the particles moved since the last neighbour search, as two bounds.
#[derive(Debug, Clone, Copy)]
struct Drift {
    /// `max_i |x_i − x_i⁰| + max_i max(R_i − R_i⁰, 0)`: the Verlet criterion (no pair farther
    /// than `R_a + R_b + skin` at the search can have come into contact while this is below
    /// half the skin).
    verlet: f64,
    /// `D = max_i |x_i − x_i⁰| + max_i |R_i − R_i⁰|`: from step t₀ to step t the gap of a pair
    /// closes by at most `2 (D(t) + D(t₀))`.
    pair: f64,
}

/// Particles per block of the per-particle passes: blocks are fixed by the index, not by the
/// thread count, and each is a plain loop over sub-slices (no per-element bounds checks).
const BLOCK: usize = 512;

impl<L: ContactLaw> Stepper<L> {
    /// A stepper with empty scratch buffers.
    pub fn new(law: L, config: StepperConfig) -> Self {
        Self {
            law,
            config,
            grid: CellGrid::default(),
            candidates: Vec::new(),
            merged: ContactList::default(),
            a_start: Vec::new(),
            b_start: Vec::new(),
            b_entry: Vec::new(),
            wall_start: Vec::new(),
            cursor: Vec::new(),
            index_key: None,
            active: Vec::new(),
            wall_active: Vec::new(),
            touched: Vec::new(),
            stamp: 0,
            quiet_below: Vec::new(),
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
        let drift = self.update_neighbours(state)?;
        self.next_stamp(state.particles.len());
        let (any_broke, active_count) = self.compute_contact_forces(state, drift);
        self.collect_events(state, any_broke);
        // Few contacts carried force: the gather visits only the stamped particles.
        let sparse = active_count.saturating_mul(4) <= state.contacts.len();
        self.gather_and_integrate(state, sparse)?;
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

    /// Stage 1: measures how far the particles moved since the last search; rebuilds the
    /// contact lists when the Verlet criterion asks for it, and the per-particle contact index
    /// when the lists changed. Returns the pair drift `D` since the (possibly new) search.
    fn update_neighbours(&mut self, state: &mut DemState) -> Result<f64, DemError> {
        let mut drift = measure_drift(state);
        let half_skin = 0.5 * self.config.params.verlet_skin;
        let wall_max = state
            .walls
            .iter()
            .zip(&state.search_reference_wall_point)
            .map(|(w, p0)| (w.point - *p0).norm())
            .fold(0.0, f64::max);
        let n = state.particles.len();
        let stale = state.search_reference_position.len() != n
            || state.search_reference_radius.len() != n
            || state.search_reference_wall_point.len() != state.walls.len();
        if stale || drift.verlet + wall_max > half_skin || !drift.verlet.is_finite() {
            state.validate()?;
            self.search(state);
            drift.pair = 0.0;
        }
        let key = (
            state.contact_generation,
            state.contacts.len(),
            state.wall_contacts.len(),
            n,
        );
        if self.index_key != Some(key) {
            state.validate()?;
            self.build_index(state)?;
            self.index_key = Some(key);
        }
        Ok(drift.pair)
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
        reserve_to(&mut self.active, headroom);
        reserve_to(&mut self.quiet_below, headroom);
        reserve_to(&mut self.b_entry, headroom);

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
        let wall_headroom = state.wall_contacts.len() + state.wall_contacts.len() / 4 + 16;
        reserve_to(&mut self.wall_active, wall_headroom);

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

    /// The per-particle contact index; checks that both lists are sorted by pair (as
    /// [`ContactList`] requires), which makes a particle's own contacts (as `a`, and its wall
    /// contacts) contiguous ranges.
    fn build_index(&mut self, state: &DemState) -> Result<(), DemError> {
        let n = state.particles.len();
        for list in [&state.contacts, &state.wall_contacts] {
            if let Some(k) = (1..list.len()).find(|&k| list.pair[k - 1] >= list.pair[k]) {
                return Err(DemError::InvalidContact {
                    index: k,
                    a: list.pair[k][0] as usize,
                    b: list.pair[k][1] as usize,
                    particle_count: n,
                });
            }
        }
        start_of_first(n, &state.contacts.pair, &mut self.a_start);
        start_of_first(n, &state.wall_contacts.pair, &mut self.wall_start);
        let (start, entry, cursor) = (&mut self.b_start, &mut self.b_entry, &mut self.cursor);
        start.clear();
        start.resize(n + 1, 0);
        for p in &state.contacts.pair {
            start[p[1] as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        entry.clear();
        entry.resize(start[n] as usize, 0);
        cursor.clear();
        cursor.extend_from_slice(&start[..n]);
        for (k, p) in state.contacts.pair.iter().enumerate() {
            let b = p[1] as usize;
            entry[cursor[b] as usize] = k as u32;
            cursor[b] += 1;
        }
        // Every pair is looked at in the next step.
        self.quiet_below.clear();
        self.quiet_below
            .resize(state.contacts.len(), f64::NEG_INFINITY);
        Ok(())
    }

    /// Stage 2: forces of all particle–particle and particle–wall contacts, in parallel.
    /// Returns whether a bond broke in this step (an OR over contacts: the same for any
    /// thread count), so that stage 3 scans the responses only then, and how many
    /// particle–particle contacts carried force. `drift` is the pair bound `D` of [`Drift`]
    /// for this step.
    fn compute_contact_forces(&mut self, state: &mut DemState, drift: f64) -> (bool, usize) {
        let dt = self.config.params.time_step;
        let law = &self.law;
        let DemState {
            particles: p,
            contacts,
            walls,
            wall_contacts,
            ..
        } = state;
        let (x, radius, v, w, t) = (
            &p.position[..],
            &p.radius[..],
            &p.velocity[..],
            &p.angular_velocity[..],
            &p.temperature[..],
        );
        self.active.resize(contacts.len(), 0);
        self.wall_active.resize(wall_contacts.len(), 0);
        let (touched, stamp) = (&self.touched[..], self.stamp);
        type Item<'a> = (
            (
                (
                    (&'a mut ContactHistory, &'a mut ContactResponse),
                    &'a mut u8,
                ),
                &'a mut f64,
            ),
            &'a [u32; 2],
        );
        let particle_contact = |((((h, r), active), quiet), pair): Item<'_>| {
            // Proven apart since it was last looked at (below), and its history is still the
            // cleared one (any evaluation sets the normal; a bond installed meanwhile or a
            // restored state is seen at once).
            if drift < *quiet && h.bond != BondState::Intact && is_zero(h.normal) {
                *active = 0;
                return 0;
            }
            let (a, b) = (pair[0] as usize, pair[1] as usize);
            let (ra, rb) = (radius[a], radius[b]);
            let branch = x[b] - x[a];
            // A listed pair that neither touches nor is bonded nor carries shear costs one
            // squared distance. Its history's normal doubles as the flag "response already
            // cleared": every evaluation below sets it to a unit vector.
            if h.bond != BondState::Intact && is_zero(h.shear_force) {
                let reach = ra + rb - h.reference_penetration;
                let d2 = branch.norm_squared();
                if reach <= 0.0 || d2 >= reach * reach {
                    if !is_zero(h.normal) {
                        h.normal = Vec3::ZERO;
                        *r = ContactResponse::default();
                    }
                    // Its gap g closes by at most 2 (D(t) + D(t₀)) by step t: apart while
                    // D(t) < g/2 − D(t₀) (less a margin far above the round-off of g and D).
                    if reach > 0.0 {
                        *quiet = 0.5 * (d2.sqrt() - reach - 1e-9 * reach) - drift;
                    }
                    *active = 0;
                    return 0;
                }
            }
            *quiet = f64::NEG_INFINITY;
            let kin = ContactKinematics::from_pair(branch, v[b] - v[a], w[a], w[b], ra, rb, dt);
            let input = PairInput {
                radius_a: ra,
                radius_b: rb,
                temperature: 0.5 * (t[a] + t[b]),
            };
            *r = law.respond(&input, &kin, h);
            *active = u8::from(r.active);
            if r.active {
                touched[a].store(stamp, Relaxed);
                touched[b].store(stamp, Relaxed);
            }
            // Bit 0: a bond broke; bit 1: the contact carried force.
            u8::from(r.broke.is_some()) | (*active << 1)
        };
        // Blocks of contacts, each a plain loop (the per-item cost of rayon's adaptors is
        // comparable to that of a listed pair that does not touch).
        type Chunk<'a> = (
            (
                (
                    (&'a mut [ContactHistory], &'a mut [ContactResponse]),
                    &'a mut [u8],
                ),
                &'a mut [f64],
            ),
            &'a [[u32; 2]],
        );
        let chunk = |((((h, r), a), q), p): Chunk<'_>| {
            h.iter_mut()
                .zip(r.iter_mut())
                .zip(a.iter_mut())
                .zip(q.iter_mut())
                .zip(p.iter())
                .fold((false, 0), |(broke, count), item| {
                    let bits = particle_contact(item);
                    (broke | (bits & 1 != 0), count + usize::from(bits >> 1))
                })
        };
        let (any_broke, active_count) = if contacts.len() >= PAR_THRESHOLD {
            contacts
                .history
                .par_chunks_mut(MIN_PAR_LEN)
                .zip(contacts.response.par_chunks_mut(MIN_PAR_LEN))
                .zip(self.active.par_chunks_mut(MIN_PAR_LEN))
                .zip(self.quiet_below.par_chunks_mut(MIN_PAR_LEN))
                .zip(contacts.pair.par_chunks(MIN_PAR_LEN))
                .map(chunk)
                .reduce(|| (false, 0), |x, y| (x.0 | y.0, x.1 + y.1))
        } else {
            chunk((
                (
                    (
                        (&mut contacts.history[..], &mut contacts.response[..]),
                        &mut self.active[..],
                    ),
                    &mut self.quiet_below[..],
                ),
                &contacts.pair[..],
            ))
        };
        let walls: &[crate::state::Wall] = walls;
        type WallItem<'a> = (
            (
                (&'a mut ContactHistory, &'a mut ContactResponse),
                &'a mut u8,
            ),
            &'a [u32; 2],
        );
        let wall_contact = |(((h, r), active), pair): WallItem<'_>| {
            let (a, wall) = (pair[0] as usize, &walls[pair[1] as usize]);
            let ra = radius[a];
            // As for pairs: apart, unbonded and without shear costs one distance.
            if h.bond != BondState::Intact && is_zero(h.shear_force) {
                let gap = (x[a] - wall.point).dot(wall.normal);
                if ra - gap - h.reference_penetration <= 0.0 {
                    if !is_zero(h.normal) {
                        h.normal = Vec3::ZERO;
                        *r = ContactResponse::default();
                    }
                    *active = 0;
                    return;
                }
            }
            let kin = ContactKinematics::from_wall(
                x[a],
                v[a],
                w[a],
                ra,
                wall.point,
                wall.normal,
                wall.velocity,
                dt,
            );
            let input = PairInput {
                radius_a: ra,
                radius_b: ra,
                temperature: t[a],
            };
            *r = law.respond(&input, &kin, h);
            *active = u8::from(r.active);
            if r.active {
                touched[a].store(stamp, Relaxed);
            }
        };
        if wall_contacts.len() >= PAR_THRESHOLD {
            wall_contacts
                .history
                .par_chunks_mut(MIN_PAR_LEN)
                .zip(wall_contacts.response.par_chunks_mut(MIN_PAR_LEN))
                .zip(self.wall_active.par_chunks_mut(MIN_PAR_LEN))
                .zip(wall_contacts.pair.par_chunks(MIN_PAR_LEN))
                .for_each(|(((h, r), a), p)| {
                    h.iter_mut()
                        .zip(r.iter_mut())
                        .zip(a.iter_mut())
                        .zip(p.iter())
                        .for_each(wall_contact)
                });
        } else {
            wall_contacts
                .history
                .iter_mut()
                .zip(wall_contacts.response.iter_mut())
                .zip(self.wall_active.iter_mut())
                .zip(wall_contacts.pair.iter())
                .for_each(wall_contact);
        }
        (any_broke, active_count)
    }

    /// A new stamp for this step's contact pass (see `touched`), with `touched` sized for
    /// `n` particles; clears the stamps when the counter wraps.
    fn next_stamp(&mut self, n: usize) {
        if self.touched.len() != n {
            self.touched.clear();
            self.touched.resize_with(n, || AtomicU32::new(0));
        }
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.touched.iter_mut().for_each(|t| *t.get_mut() = 0);
            self.stamp = 1;
        }
    }

    /// Stage 3: broken-bond events (in contact order; the contacts are scanned only when
    /// stage 2 reported a break) and the forces on the walls.
    fn collect_events(&self, state: &mut DemState, any_broke: bool) {
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

    /// Stages 4 and 5 in one pass over the particles: each sums its own contacts in
    /// contact-index order (as `b`, then as `a`, then its walls; contacts that carried no
    /// force are skipped, adding their zeros would not change a bit), plus external force and
    /// gravity; then Cundall's non-viscous damping (A-Eq. 7) and the leapfrog update, with the
    /// finiteness check (the first bad particle is a minimum over indices). Fixed particles
    /// move at their prescribed velocity; plane kinematics keep `z = 0`, `v_z = 0`,
    /// `ω_x = ω_y = 0`.
    fn gather_and_integrate(&self, state: &mut DemState, sparse: bool) -> Result<(), DemError> {
        let g = self.config.gravity;
        let dt = self.config.params.time_step;
        let alpha = self.config.params.damping;
        let step = state.step;
        let DemState {
            particles,
            contacts,
            wall_contacts,
            ..
        } = state;
        let ParticleState {
            kinematics,
            position,
            velocity,
            angular_velocity,
            mass,
            inertia,
            fixed,
            external_force,
            external_torque,
            force,
            torque,
            ..
        } = particles;
        let planar = kinematics.is_planar();
        let n = position.len();
        let (resp, active) = (&contacts.response[..], &self.active[..]);
        let (wresp, wactive) = (&wall_contacts.response[..], &self.wall_active[..]);
        let (a_start, b_start, b_entry) = (&self.a_start[..], &self.b_start[..], &self.b_entry);
        let wall_start = &self.wall_start[..];
        let (touched, stamp) = (&self.touched[..], self.stamp);
        type Block<'a> = (
            usize,
            (
                (
                    ((&'a mut [Vec3], &'a mut [Vec3]), &'a mut [Vec3]),
                    &'a mut [Vec3],
                ),
                &'a mut [Vec3],
            ),
        );
        // Returns the first particle of the block whose state became non-finite, else
        // `usize::MAX`.
        let block = |(c, ((((xs, vs), ws), fs), ts)): Block<'_>| -> usize {
            let s = c * BLOCK;
            let e = s + xs.len();
            let mut first_bad = usize::MAX;
            let ranges = b_start[s..=e]
                .windows(2)
                .zip(a_start[s..=e].windows(2))
                .zip(wall_start[s..=e].windows(2));
            let loads = fixed[s..e]
                .iter()
                .zip(external_force[s..e].iter().zip(&external_torque[s..e]));
            for (
                j,
                (
                    ((((((x, v), w), f_out), t_out), (&m, &inertia)), (&fixed, (fe, te))),
                    ((b_range, a_range), w_range),
                ),
            ) in xs
                .iter_mut()
                .zip(vs.iter_mut())
                .zip(ws.iter_mut())
                .zip(fs.iter_mut())
                .zip(ts.iter_mut())
                .zip(mass[s..e].iter().zip(&inertia[s..e]))
                .zip(loads)
                .zip(ranges)
                .enumerate()
            {
                let i = s + j;
                let mut fi = Vec3::ZERO;
                let mut ti = Vec3::ZERO;
                if !(sparse && touched[i].load(Relaxed) != stamp) {
                    for &k in &b_entry[b_range[0] as usize..b_range[1] as usize] {
                        let k = k as usize;
                        if active[k] != 0 {
                            fi += resp[k].force_on_b;
                            ti += resp[k].torque_on_b;
                        }
                    }
                    let own = a_range[0] as usize..a_range[1] as usize;
                    for (r, &on) in resp[own.clone()].iter().zip(&active[own]) {
                        if on != 0 {
                            fi -= r.force_on_b;
                            ti += r.torque_on_a;
                        }
                    }
                    let own = w_range[0] as usize..w_range[1] as usize;
                    for (r, &on) in wresp[own.clone()].iter().zip(&wactive[own]) {
                        if on != 0 {
                            fi -= r.force_on_b;
                            ti += r.torque_on_a;
                        }
                    }
                }
                *f_out = fi + *fe + g * m;
                *t_out = ti + *te;
                if !fixed {
                    let inv_m = 1.0 / m;
                    let inv_i = 1.0 / inertia;
                    let f = cundall_damping(*f_out, *v, dt * inv_m, alpha);
                    let t = cundall_damping(*t_out, *w, dt * inv_i, alpha);
                    *v += f * (dt * inv_m);
                    *w += t * (dt * inv_i);
                    if planar {
                        v.z = 0.0;
                        w.x = 0.0;
                        w.y = 0.0;
                    }
                }
                *x += *v * dt;
                if !all_finite(*x, *v, *w) {
                    first_bad = first_bad.min(i);
                }
            }
            first_bad
        };
        let first_bad = if n >= PAR_THRESHOLD {
            position
                .par_chunks_mut(BLOCK)
                .zip(velocity.par_chunks_mut(BLOCK))
                .zip(angular_velocity.par_chunks_mut(BLOCK))
                .zip(force.par_chunks_mut(BLOCK))
                .zip(torque.par_chunks_mut(BLOCK))
                .enumerate()
                .map(block)
                .min()
                .unwrap_or(usize::MAX)
        } else {
            position
                .chunks_mut(BLOCK)
                .zip(velocity.chunks_mut(BLOCK))
                .zip(angular_velocity.chunks_mut(BLOCK))
                .zip(force.chunks_mut(BLOCK))
                .zip(torque.chunks_mut(BLOCK))
                .enumerate()
                .map(block)
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

/// True when all nine components are finite. A NaN or an infinity makes their sum
/// non-finite; a finite sum proves them finite (the one-by-one test runs only when the sum
/// overflowed or a component is not finite).
#[inline]
fn all_finite(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let s = a + b + c;
    (s.x + s.y + s.z).is_finite() || (a.is_finite() && b.is_finite() && c.is_finite())
}

/// True when all components are +0.0 (a cleared vector; a −0.0 takes the general path).
#[inline]
fn is_zero(v: Vec3) -> bool {
    (v.x.to_bits() | v.y.to_bits() | v.z.to_bits()) == 0
}

/// The two drift bounds of [`Drift`] (zero when there is no reference yet: the caller
/// searches then anyway).
fn measure_drift(state: &DemState) -> Drift {
    let p = &state.particles;
    let n = p.len();
    let (x0, r0) = (
        &state.search_reference_position,
        &state.search_reference_radius,
    );
    if x0.len() != n || r0.len() != n {
        return Drift {
            verlet: 0.0,
            pair: 0.0,
        };
    }
    // Per block: max |Δx|², max ΔR, max −ΔR.
    let block = |c: usize| -> [f64; 3] {
        let s = c * BLOCK;
        let e = (s + BLOCK).min(n);
        let mut m = [0.0_f64; 3];
        for ((x, x0), (r, r0)) in p.position[s..e]
            .iter()
            .zip(&x0[s..e])
            .zip(p.radius[s..e].iter().zip(&r0[s..e]))
        {
            // Plain comparisons (`maxsd`); `f64::max` would also sort out NaNs, which the
            // finiteness checks of the integration and of the search report anyway.
            let (d2, dr) = ((*x - *x0).norm_squared(), r - r0);
            m[0] = if d2 > m[0] { d2 } else { m[0] };
            m[1] = if dr > m[1] { dr } else { m[1] };
            m[2] = if -dr > m[2] { -dr } else { m[2] };
        }
        m
    };
    let max3 = |a: [f64; 3], b: [f64; 3]| [a[0].max(b[0]), a[1].max(b[1]), a[2].max(b[2])];
    let blocks = n.div_ceil(BLOCK);
    let m = if n >= PAR_THRESHOLD {
        (0..blocks)
            .into_par_iter()
            .map(block)
            .reduce(|| [0.0; 3], max3)
    } else {
        (0..blocks).map(block).fold([0.0; 3], max3)
    };
    let dx = m[0].sqrt();
    Drift {
        verlet: dx + m[1],
        pair: dx + m[1].max(m[2]),
    }
}

/// `start[i]..start[i+1]` are the entries of a sorted pair list whose first index is `i`.
fn start_of_first(n: usize, pairs: &[[u32; 2]], start: &mut Vec<u32>) {
    start.clear();
    start.resize(n + 1, 0);
    for p in pairs {
        start[p[0] as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
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
