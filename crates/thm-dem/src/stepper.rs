//! The time step: a fixed sequence of stages over caller-owned state.
//!
//! 1. neighbours: how far the particles moved since the last search (two bounds, one pass);
//!    cell-grid search and merge of the contact histories when a particle (or wall) moved
//!    more than half the skin; the per-particle contact index when the lists changed;
//! 2. contact forces, block by block of particles (blocks of 256 or 512 consecutive
//!    indices, by the particle count, never by the thread count), in parallel over contiguous runs of
//!    blocks (see `blocks.rs`): a block owns the contacts whose first particle it holds (a
//!    range of the sorted list) and its particles' wall contacts; each contact writes only
//!    its own history, report and "carried force" flag; the block sums the forces and
//!    torques on its own particles in contact order (in the particles' force and torque
//!    rows, which the gather then overwrites with the resultants); a contact whose second
//!    particle lies in a later block adds that particle's share to the particle's running
//!    sum of such shares, or, when a contact of an earlier run of blocks reaches the
//!    particle too, leaves it in the contact's spill entry and stamps the particle (every
//!    stamp of a step is the same value); a listed pair that does not touch (and is neither
//!    bonded nor sheared) costs one distance, and is not looked at again, not even its
//!    history, until the drift since then could have closed its gap (a block sweeps its
//!    contacts in chunks of 64: it first lists, without a branch, those that are not such
//!    quiet pairs, then evaluates the listed ones in contact order); these bounds are
//!    forgotten when the state is not the one the stepper advanced last (taken back from a
//!    save) or the contact generation changed (see [`DemState::contact_generation`]);
//!    reports whether a bond broke (a boolean OR);
//! 3. gather and integrate, block by block, in the same parallel region as stage 2: the
//!    gather of a block runs once every contact pass that reaches its particles is done;
//!    every particle takes its running sum, or (where a spill entry may hold a share) sums
//!    the spill entries of its contacts with earlier blocks in contact-index order (those
//!    that carried force, chosen by their flags without a branch, the others adding +0;
//!    when at most a quarter of the contacts did in the previous step, only the stamped
//!    particles look): either way the shares in contact order from +0, so the same bits
//!    for any thread count (no floating-point atomics); then it adds its block's sum,
//!    external force and gravity, Cundall's non-viscous damping (A-Eq. 7) and leapfrog,
//!    with the finiteness check (the first bad particle is a minimum over indices);
//! 4. events: broken-bond events (the contacts are scanned only when a bond broke) and wall
//!    forces, serially in contact order;
//! 5. walls move at their prescribed velocity.
//!
//! Why blocks: storing every contact's full response for a separate gather to read back
//! cost more than the contact law itself once the lists outgrow the cache (10⁵ spheres);
//! a block's own sums stay in cache, a particle's running sum is usually still cached when
//! the later contacts add to it, and only the contacts that reach another thread's run of
//! blocks go through memory a second time.

use crate::blocks::{
    BlockRun, ContactRows, GatherRows, Layout, PassRows, SpillEntry, Stages, contacts_then_gathers,
};
use crate::contact::{
    BondState, ContactHistory, ContactKinematics, ContactLaw, ContactReport, PairInput,
};
use crate::error::{DemError, check_positive, check_range};
use crate::neighbour::CellGrid;
use crate::state::{BondBreak, ContactList, DemState, ParticleState, Wall};
use crate::vec3::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::hint::select_unpredictable;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering::Relaxed};

/// Loops shorter than this run serially (rayon's dispatch would cost more than the work);
/// either way every item is computed by the same code, so the bits do not change.
const PAR_THRESHOLD: usize = 1024;

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
/// per-particle contact index, block sums, spill entries, bounds of pairs proven apart),
/// so one stepper can advance any state.
#[derive(Debug)]
pub struct Stepper<L: ContactLaw> {
    law: L,
    config: StepperConfig,
    grid: CellGrid,
    candidates: Vec<[u32; 2]>,
    merged: ContactList,
    /// Contacts with `pair[0] == i` are `a_start[i]..a_start[i+1]` (the list is sorted).
    a_start: Vec<u32>,
    /// Contacts with `pair[1] == i` whose first particle lies in an earlier block (see
    /// `block`) are `b_entry[b_start[i]..b_start[i+1]]`, ascending: the gather reads their
    /// spill entries.
    b_start: Vec<u32>,
    b_entry: Vec<u32>,
    /// Wall contacts of particle `i` are `wall_start[i]..wall_start[i+1]` (sorted list).
    wall_start: Vec<u32>,
    /// Particles per block, set with the index (see [`block_len`]).
    block: usize,
    /// Per block of particles: one past the last particle its contacts reach (at least the
    /// block's end): what its contact pass reads.
    block_reach: Vec<u32>,
    cursor: Vec<u32>,
    index_key: Option<(u64, usize, usize, usize)>,
    /// Whether each contact carries force in this step (the report's `active` flag again, one
    /// byte per contact, written for every contact by every contact pass): the gather reads a
    /// spill entry only when its contact's flag is set.
    active: Vec<u8>,
    /// Force on B and torque on B of a contact whose B lies in a later block than its A,
    /// written in every step in which it carries force; stale otherwise (the gather then
    /// adds zero instead, see `active`).
    spill: Vec<SpillEntry>,
    /// Per particle: the running sum of the forces and torques of the contacts of earlier
    /// blocks (outside the zones, see `blocks.rs`), added in contact order by the contact
    /// passes (the same sums, bit for bit, as the gather forms from spill entries) and
    /// cleared by the gather that reads them. All zero between steps (`foreign_clean`).
    foreign: Vec<SpillEntry>,
    /// False while a contact pass may have left `foreign` entries that no gather cleared (a
    /// step interrupted by a panic): the next step clears them all.
    foreign_clean: bool,
    /// `touched[i] == stamp` when a contact of an earlier block left particle `i` a spill
    /// entry in this step, stored by the contact pass itself (used only when few contacts
    /// carried force: the gather then reads spill entries only for stamped particles). Every
    /// store of a step writes the same value, so the result does not depend on which thread
    /// stores first: relaxed atomics, plain moves on the common targets, make those
    /// concurrent stores defined behaviour.
    touched: Vec<AtomicU32>,
    stamp: u32,
    /// A listed pair found apart (and unbonded, without shear) stays apart while the drift
    /// (see [`Drift`]) is below its entry: it is not looked at again until then, not even its
    /// history (which the contract of [`DemState::contact_generation`] keeps unedited).
    quiet_below: Vec<f64>,
    /// The step index of the state after this stepper's last successful step: a state at
    /// another step (taken back from a save, or another state) has every listed pair looked
    /// at again, since a bond intact in it may be broken in the state the bounds came from.
    advanced_to: Option<u64>,
    /// Whether the gather reads spill entries only for stamped particles: set when at most
    /// a quarter of the contacts carried force in the previous step. Only the speed depends
    /// on it: a particle that no contact stamped has no contact with an earlier block that
    /// carries force.
    sparse: bool,
    /// Scratch of the contact-and-gather schedule.
    stages: Stages,
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

/// What an inactive contact adds in the gather.
const NO_LOAD: SpillEntry = SpillEntry([Vec3::ZERO; 2]);

/// Particles per block of the contact pass and the gather: the largest of these that makes
/// at least [`BLOCKS_WANTED`] blocks, else the smallest (see [`block_len`]). Blocks are fixed
/// by the particle count, not by the thread count (the order of every sum, and so every
/// bit, depends on the block length only), and each is a plain loop over sub-slices.
const BLOCK_LENS: [usize; 2] = [256, 512];

/// Blocks wanted per state: the runs of the threads are cut at block boundaries, so on two
/// threads a block is about 1/16 of a run (the 10⁴-sphere bed: 256 particles, about 20 µs
/// of one thread's work). Longer blocks cost a little less per particle (about 1 % on one
/// thread on that bed, 3 % on the 10⁵ bed).
const BLOCKS_WANTED: usize = 32;

/// The block length for `n` particles (see [`BLOCK_LENS`]).
fn block_len(n: usize) -> usize {
    BLOCK_LENS
        .iter()
        .rev()
        .copied()
        .find(|&len| n / len >= BLOCKS_WANTED)
        .unwrap_or(BLOCK_LENS[0])
}

/// Particles per block of the drift measurement (a maximum: any partition gives the same
/// bits).
const DRIFT_BLOCK: usize = 512;

/// Contacts per chunk of the contact pass's two sweeps (list the contacts that are not quiet,
/// then evaluate them): at most 256 (the list holds `u8` offsets). Only the speed depends
/// on it.
const LIVE_CHUNK: usize = 64;
const _: () = assert!(LIVE_CHUNK <= 256);

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
            block: BLOCK_LENS[0],
            block_reach: Vec::new(),
            cursor: Vec::new(),
            index_key: None,
            active: Vec::new(),
            spill: Vec::new(),
            foreign: Vec::new(),
            foreign_clean: true,
            touched: Vec::new(),
            stamp: 0,
            quiet_below: Vec::new(),
            advanced_to: None,
            sparse: false,
            stages: Stages::default(),
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
        if self.advanced_to.take() != Some(state.step) {
            self.quiet_below.fill(f64::NEG_INFINITY);
        }
        self.next_stamp(state.particles.len());
        let (any_broke, active_count, first_bad) = self.forces_and_motion(state, drift);
        // Few contacts carried force: the next step's gather visits only the stamped
        // particles (a choice of speed only, see `touched`).
        self.sparse = active_count.saturating_mul(4) <= state.contacts.len();
        self.collect_events(state, any_broke);
        if let Some(index) = first_bad {
            return Err(DemError::NonFinite {
                quantity: "position or velocity",
                index,
                step: state.step,
            });
        }
        let dt = self.config.params.time_step;
        for w in &mut state.walls {
            w.point += w.velocity * dt;
        }
        state.step += 1;
        state.time += dt;
        self.advanced_to = Some(state.step);
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
        reserve_to(&mut self.merged.report, headroom);
        reserve_to(&mut state.contacts.pair, headroom);
        reserve_to(&mut state.contacts.history, headroom);
        reserve_to(&mut state.contacts.report, headroom);
        reserve_to(&mut self.active, headroom);
        reserve_to(&mut self.spill, headroom);
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
        let block = block_len(n);
        self.block = block;
        self.block_reach.clear();
        self.block_reach.extend((0..n.div_ceil(block)).map(|c| {
            let (s, e) = (c * block, ((c + 1) * block).min(n));
            let own = &state.contacts.pair[self.a_start[s] as usize..self.a_start[e] as usize];
            own.iter().map(|p| p[1] + 1).fold(e as u32, u32::max)
        }));
        let (start, entry, cursor) = (&mut self.b_start, &mut self.b_entry, &mut self.cursor);
        start.clear();
        start.resize(n + 1, 0);
        // Only the contacts whose two particles lie in different blocks: the block of A
        // sums the others itself.
        let foreign = |p: &[u32; 2]| p[0] as usize / block != p[1] as usize / block;
        for p in state.contacts.pair.iter().filter(|p| foreign(p)) {
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
            if !foreign(p) {
                continue;
            }
            let b = p[1] as usize;
            entry[cursor[b] as usize] = k as u32;
            cursor[b] += 1;
        }
        // The entries follow the new contact indices (each is read only in a step that wrote
        // it, see `active`).
        self.spill
            .resize(state.contacts.len(), SpillEntry::default());
        // Every pair is looked at in the next step.
        self.quiet_below.clear();
        self.quiet_below
            .resize(state.contacts.len(), f64::NEG_INFINITY);
        Ok(())
    }

    /// Stages 2 and 3 in one parallel region (see [`contacts_then_gathers`]): the forces of
    /// all particle–particle and particle–wall contacts, block by block of particles (the
    /// blocks are fixed by the index, see [`block_len`]), and the gather and integration of each
    /// block once the contacts of its own and of every earlier block are done.
    ///
    /// A block's contact pass owns the contacts whose first particle it holds (a range of
    /// the sorted list) and its particles' wall contacts; it sums every contact's force and
    /// torques on its own particles into their block sums, in contact order (pairs, then
    /// walls), and leaves the force and torque on a second particle of a later block in that
    /// contact's spill entry for the gather. Returns whether a bond broke in this step (an
    /// OR over contacts: the same for any thread count), so that stage 4 scans the reports
    /// only then, how many particle–particle contacts carried force, and the first particle
    /// whose state became non-finite (a minimum over blocks). `drift` is the pair bound `D`
    /// of [`Drift`] for this step.
    fn forces_and_motion(
        &mut self,
        state: &mut DemState,
        drift: f64,
    ) -> (bool, usize, Option<usize>) {
        let n = state.particles.len();
        let DemState {
            particles: p,
            contacts,
            walls,
            wall_contacts,
            ..
        } = state;
        self.active.resize(contacts.len(), 0);
        self.spill.resize(contacts.len(), SpillEntry::default());
        if !self.foreign_clean {
            self.foreign.fill(SpillEntry::default());
        }
        self.foreign.resize(n, SpillEntry::default());
        self.foreign_clean = false;
        let ParticleState {
            kinematics,
            position,
            velocity,
            angular_velocity,
            radius,
            mass,
            inertia,
            temperature,
            fixed,
            external_force,
            external_torque,
            force,
            torque,
            ..
        } = p;
        let parallel = contacts.len() + wall_contacts.len() >= 2 * PAR_THRESHOLD;
        let pass = BlockPass {
            law: &self.law,
            dt: self.config.params.time_step,
            drift,
            gravity: self.config.gravity,
            damping: self.config.params.damping,
            planar: kinematics.is_planar(),
            sparse: self.sparse,
            n,
            block: self.block,
            b_start: &self.b_start,
            b_entry: &self.b_entry,
            radius,
            temperature,
            mass,
            inertia,
            fixed,
            external_force,
            external_torque,
            walls,
            touched: &self.touched,
            stamp: self.stamp,
            broke: AtomicBool::new(false),
            count: AtomicUsize::new(0),
            first_bad: AtomicUsize::new(usize::MAX),
        };
        let starts = BlockStarts {
            n,
            block: self.block,
            a_start: &self.a_start,
            wall_start: &self.wall_start,
        };
        let slices = BlockSlices {
            starts,
            pair: &contacts.pair,
            history: &mut contacts.history,
            report: &mut contacts.report,
            quiet: &mut self.quiet_below,
            wall_pair: &wall_contacts.pair,
            wall_history: &mut wall_contacts.history,
            wall_report: &mut wall_contacts.report,
        };
        // A block's spill entries are those of its contacts (one per contact).
        let layout = Layout {
            n,
            block: self.block,
            spill_start: &self.a_start,
            reach: &self.block_reach,
        };
        let rows = PassRows::new(
            position,
            velocity,
            angular_velocity,
            force,
            torque,
            &mut self.spill,
            &mut self.active,
            &mut self.foreign,
        );
        contacts_then_gathers(
            layout,
            &rows,
            slices,
            &mut self.stages,
            parallel,
            &|c, block, rows| pass.block(c, block, rows),
            &|j, rows| pass.gather(j, rows),
        );
        // Every gather ran and cleared its particles' entries.
        self.foreign_clean = true;
        let first_bad = pass.first_bad.into_inner();
        (
            pass.broke.into_inner(),
            pass.count.into_inner(),
            (first_bad != usize::MAX).then_some(first_bad),
        )
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

    /// Stage 4: broken-bond events (in contact order; the contacts are scanned only when
    /// stage 2 reported a break) and the forces on the walls.
    fn collect_events(&self, state: &mut DemState, any_broke: bool) {
        if any_broke {
            for (pair, r) in state.contacts.pair.iter().zip(&state.contacts.report) {
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
        let list = &state.wall_contacts;
        for (k, pair) in list.pair.iter().enumerate() {
            if list.report[k].active {
                state.walls[pair[1] as usize].force += list.force_on_b(k);
            }
        }
    }
}

/// Where each block of the contact pass begins in the particle, contact and wall-contact
/// lists.
#[derive(Clone, Copy)]
struct BlockStarts<'a> {
    n: usize,
    block: usize,
    a_start: &'a [u32],
    wall_start: &'a [u32],
}

impl BlockStarts<'_> {
    /// The first particle, contact and wall contact of block `c` (`c` may be one past the
    /// last block).
    fn of(&self, c: usize) -> (usize, usize, usize) {
        let s = (c * self.block).min(self.n);
        (s, self.a_start[s] as usize, self.wall_start[s] as usize)
    }
}

/// The mutable per-contact slices of a run of whole blocks of particles `s..e`: contacts
/// `a_start[s]..a_start[e]` and wall contacts `wall_start[s]..wall_start[e]`.
struct BlockSlices<'a> {
    starts: BlockStarts<'a>,
    pair: &'a [[u32; 2]],
    history: &'a mut [ContactHistory],
    report: &'a mut [ContactReport],
    quiet: &'a mut [f64],
    wall_pair: &'a [[u32; 2]],
    wall_history: &'a mut [ContactHistory],
    wall_report: &'a mut [ContactReport],
}

impl<'a> BlockSlices<'a> {
    /// Splits before contact `c` and wall contact `w` (offsets into `self`).
    fn split(self, c: usize, w: usize) -> (Self, Self) {
        let (pair, pair_rest) = self.pair.split_at(c);
        let (history, history_rest) = self.history.split_at_mut(c);
        let (report, report_rest) = self.report.split_at_mut(c);
        let (quiet, quiet_rest) = self.quiet.split_at_mut(c);
        let (wall_pair, wall_pair_rest) = self.wall_pair.split_at(w);
        let (wall_history, wall_history_rest) = self.wall_history.split_at_mut(w);
        let (wall_report, wall_report_rest) = self.wall_report.split_at_mut(w);
        let starts = self.starts;
        (
            Self {
                starts,
                pair,
                history,
                report,
                quiet,
                wall_pair,
                wall_history,
                wall_report,
            },
            Self {
                starts,
                pair: pair_rest,
                history: history_rest,
                report: report_rest,
                quiet: quiet_rest,
                wall_pair: wall_pair_rest,
                wall_history: wall_history_rest,
                wall_report: wall_report_rest,
            },
        )
    }
}

impl BlockRun for BlockSlices<'_> {
    fn split_at_block(self, run: Range<usize>, at: usize) -> (Self, Self) {
        let (_, c0, w0) = self.starts.of(run.start);
        let (_, c, w) = self.starts.of(at);
        self.split(c - c0, w - w0)
    }
}

/// What the contact pass and the gather of every block read (besides the rows that
/// [`contacts_then_gathers`] lends them) and what they report.
struct BlockPass<'a, L> {
    law: &'a L,
    dt: f64,
    drift: f64,
    gravity: Vec3,
    damping: f64,
    planar: bool,
    /// Whether the gather reads spill entries only for stamped particles (see `touched`).
    sparse: bool,
    n: usize,
    /// Particles per block (see [`block_len`]).
    block: usize,
    b_start: &'a [u32],
    b_entry: &'a [u32],
    radius: &'a [f64],
    temperature: &'a [f64],
    mass: &'a [f64],
    inertia: &'a [f64],
    fixed: &'a [bool],
    external_force: &'a [Vec3],
    external_torque: &'a [Vec3],
    walls: &'a [Wall],
    touched: &'a [AtomicU32],
    stamp: u32,
    /// Whether a bond broke, how many particle–particle contacts carried force, the first
    /// particle whose state became non-finite (`usize::MAX` if none): an OR, an integer sum
    /// and a minimum over blocks, the same for any thread count.
    broke: AtomicBool,
    count: AtomicUsize,
    first_bad: AtomicUsize,
}

impl<L: ContactLaw> BlockPass<'_, L> {
    /// Particles `s..e` of block `c`.
    fn particles(&self, c: usize) -> Range<usize> {
        (c * self.block).min(self.n)..((c + 1) * self.block).min(self.n)
    }

    /// The contact pass of block `c`: particles `s..e`, their contacts as first particle,
    /// then their wall contacts, in list order. Reads the kinematics of particles `s..`
    /// only (a pair `[a, b]` of the block has `s <= a < e` and `a < b`; a particle outside
    /// the rows panics) and writes its contacts' data, their spill entries and its block
    /// sums.
    fn block(&self, c: usize, out: BlockSlices<'_>, rows: ContactRows<'_>) {
        let BlockSlices {
            starts: _,
            pair,
            history,
            report,
            quiet,
            wall_pair,
            wall_history,
            wall_report,
        } = out;
        let Range { start: s, end: e } = self.particles(c);
        let ContactRows {
            position: x,
            velocity: v,
            angular_velocity: w,
            spill,
            active,
            mut foreign,
            block_force: force,
            block_torque: torque,
        } = rows;
        force.fill(Vec3::ZERO);
        torque.fill(Vec3::ZERO);
        let (radius, t) = (self.radius, self.temperature);
        let (drift, dt) = (self.drift, self.dt);
        let (mut broke, mut count) = (false, 0);
        // Chunk by chunk of `LIVE_CHUNK` contacts (small enough that the chunk's histories
        // are still in L1 when evaluated): first list the contacts that are not quiet, i.e.
        // not proven apart since they were last looked at (below), by a store that is kept or
        // overwritten instead of a branch (which contacts are quiet follows no pattern a
        // branch predictor could learn). Only the bounds are read: a quiet contact's history
        // is the cleared one and its activity flag is 0, as the evaluation that found it
        // apart left them (the bounds are reset when the index is rebuilt, when the state is
        // not the one this stepper advanced last, and a caller that edits a history
        // increments the contact generation). Then evaluate those in contact order (the
        // block sums' order is unchanged: a quiet contact adds nothing).
        let mut live = [0_u8; LIVE_CHUNK];
        for base in (0..pair.len()).step_by(LIVE_CHUNK) {
            let end = (base + LIVE_CHUNK).min(pair.len());
            let mut m = 0;
            for (k, &q) in quiet.iter().enumerate().take(end).skip(base) {
                // `m <= k - base < LIVE_CHUNK <= 256`: stored always, kept when live.
                live[m] = (k - base) as u8;
                let is_quiet = drift < q;
                m += usize::from(!is_quiet);
            }
            for &j in &live[..m] {
                let k = base + usize::from(j);
                let (h, rep, on, q, sp, pair) = (
                    &mut history[k],
                    &mut report[k],
                    &mut active[k],
                    &mut quiet[k],
                    &mut spill[k],
                    &pair[k],
                );
                let (a, b) = (pair[0] as usize, pair[1] as usize);
                let (ra, rb) = (radius[a], radius[b]);
                let branch = x[b - s] - x[a - s];
                // A listed pair that neither touches nor is bonded nor carries shear costs one
                // squared distance. Its history's normal doubles as the flag "report already
                // cleared": every evaluation below sets it to a unit vector.
                if h.bond != BondState::Intact && is_zero(h.shear_force) {
                    let reach = ra + rb - h.reference_penetration;
                    let d2 = branch.norm_squared();
                    if reach <= 0.0 || d2 >= reach * reach {
                        if !is_zero(h.normal) {
                            h.normal = Vec3::ZERO;
                            *rep = ContactReport::default();
                        }
                        // Its gap g closes by at most 2 (D(t) + D(t₀)) by step t: apart while
                        // D(t) < g/2 − D(t₀) (less a margin far above the round-off of g and D).
                        if reach > 0.0 {
                            *q = 0.5 * (d2.sqrt() - reach - 1e-9 * reach) - drift;
                        }
                        *on = 0;
                        continue;
                    }
                }
                *q = f64::NEG_INFINITY;
                let (va, vb) = (v[a - s], v[b - s]);
                let kin =
                    ContactKinematics::from_pair(branch, vb - va, w[a - s], w[b - s], ra, rb, dt);
                let input = PairInput {
                    radius_a: ra,
                    radius_b: rb,
                    temperature: 0.5 * (t[a] + t[b]),
                };
                let r = self.law.respond(&input, &kin, h);
                *rep = ContactReport::from(&r);
                *on = u8::from(r.active);
                broke |= r.broke.is_some();
                if r.active {
                    count += 1;
                    force[a - s] -= r.force_on_b;
                    torque[a - s] += r.torque_on_a;
                    if b < e {
                        force[b - s] += r.force_on_b;
                        torque[b - s] += r.torque_on_b;
                    } else if let Some(SpillEntry([f, t])) = foreign.get(b) {
                        *f += r.force_on_b;
                        *t += r.torque_on_b;
                    } else {
                        // Component by component: a whole-entry copy went through the
                        // stack with mixed widths, and the loads of a copy spanning two
                        // stores wait for them.
                        sp.0[0] = r.force_on_b;
                        sp.0[1] = r.torque_on_b;
                        self.touched[b].store(self.stamp, Relaxed);
                    }
                }
            }
        }
        for ((h, rep), pair) in wall_history
            .iter_mut()
            .zip(wall_report.iter_mut())
            .zip(wall_pair)
        {
            let (a, wall) = (pair[0] as usize, &self.walls[pair[1] as usize]);
            let ra = radius[a];
            // As for pairs: apart, unbonded and without shear costs one distance.
            if h.bond != BondState::Intact && is_zero(h.shear_force) {
                let gap = (x[a - s] - wall.point).dot(wall.normal);
                if ra - gap - h.reference_penetration <= 0.0 {
                    if !is_zero(h.normal) {
                        h.normal = Vec3::ZERO;
                        *rep = ContactReport::default();
                    }
                    continue;
                }
            }
            let kin = ContactKinematics::from_wall(
                x[a - s],
                v[a - s],
                w[a - s],
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
            let r = self.law.respond(&input, &kin, h);
            *rep = ContactReport::from(&r);
            if r.active {
                force[a - s] -= r.force_on_b;
                torque[a - s] += r.torque_on_a;
            }
        }
        self.broke.fetch_or(broke, Relaxed);
        self.count.fetch_add(count, Relaxed);
    }

    /// The gather and integration of block `c` (stage 3 of the module documentation):
    /// each particle sums the spill entries of its contacts with earlier blocks in
    /// contact-index order (those that carried force), then adds the sum its own block
    /// formed (see [`BlockPass::block`]), external force and gravity; then Cundall's
    /// non-viscous damping (A-Eq. 7) and the leapfrog update, with the finiteness check.
    /// Fixed particles move at their prescribed velocity; plane kinematics keep `z = 0`,
    /// `v_z = 0`, `ω_x = ω_y = 0`. Runs after the contact passes of blocks `0..=c`.
    fn gather(&self, c: usize, rows: GatherRows<'_>) {
        let Range { start: s, end: e } = self.particles(c);
        let (g, dt, alpha, planar, sparse) = (
            self.gravity,
            self.dt,
            self.damping,
            self.planar,
            self.sparse,
        );
        let (b_start, b_entry) = (self.b_start, self.b_entry);
        let (touched, stamp) = (self.touched, self.stamp);
        // The spill entries of a particle of block `c` belong to contacts of earlier blocks,
        // i.e. lie below `a_start[s]`, where the rows end.
        let GatherRows {
            position: xs,
            velocity: vs,
            angular_velocity: ws,
            force: fs,
            torque: ts,
            spill,
            active,
            mut foreign,
        } = rows;
        let mut bad = usize::MAX;
        let ranges = b_start[s..=e].windows(2);
        let loads = self.fixed[s..e].iter().zip(
            self.external_force[s..e]
                .iter()
                .zip(&self.external_torque[s..e]),
        );
        for (j, (((((((x, v), w), f_out), t_out), (&m, &inertia)), (&fixed, (fe, te))), b_range)) in
            xs.iter_mut()
                .zip(vs.iter_mut())
                .zip(ws.iter_mut())
                .zip(fs.iter_mut())
                .zip(ts.iter_mut())
                .zip(self.mass[s..e].iter().zip(&self.inertia[s..e]))
                .zip(loads)
                .zip(ranges)
                .enumerate()
        {
            let i = s + j;
            let mut fi = Vec3::ZERO;
            let mut ti = Vec3::ZERO;
            if let Some(sums) = foreign.as_deref_mut() {
                // One thread: the contact passes summed them already, in the same order.
                let SpillEntry([f, t]) = std::mem::take(&mut sums[j]);
                fi = f;
                ti = t;
            } else if !(sparse && touched[i].load(Relaxed) != stamp) {
                // An inactive contact adds +0 (which changes no bit of a sum that starts at
                // +0), chosen without a branch (which contacts carry force follows no pattern)
                // and without reading its stale spill entry.
                for &k in &b_entry[b_range[0] as usize..b_range[1] as usize] {
                    let k = k as usize;
                    let SpillEntry([f, t]) =
                        *select_unpredictable(active[k] != 0, &spill[k], &NO_LOAD);
                    fi += f;
                    ti += t;
                }
            }
            // The block sums (see `BlockPass::block`) are in the output rows until here.
            fi += *f_out;
            ti += *t_out;
            let (f_total, t_total) = (fi + *fe + g * m, ti + *te);
            *f_out = f_total;
            *t_out = t_total;
            // Updated in registers and stored once: the finiteness check must not read back
            // components just stored one by one (a load spanning two stores waits for them).
            let (mut vi, mut wi) = (*v, *w);
            if !fixed {
                let inv_m = 1.0 / m;
                let inv_i = 1.0 / inertia;
                let f = cundall_damping(f_total, vi, dt * inv_m, alpha);
                let t = cundall_damping(t_total, wi, dt * inv_i, alpha);
                vi += f * (dt * inv_m);
                wi += t * (dt * inv_i);
                if planar {
                    vi.z = 0.0;
                    wi.x = 0.0;
                    wi.y = 0.0;
                }
            }
            let xi = *x + vi * dt;
            *v = vi;
            *w = wi;
            *x = xi;
            if !all_finite(xi, vi, wi) {
                bad = bad.min(i);
            }
        }
        if bad != usize::MAX {
            self.first_bad.fetch_min(bad, Relaxed);
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
        let s = c * DRIFT_BLOCK;
        let e = (s + DRIFT_BLOCK).min(n);
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
    let blocks = n.div_ceil(DRIFT_BLOCK);
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
                out.report.push(old.report[k]);
            }
            k += 1;
        }
        if k < old.len() && old.pair[k] == c {
            out.pair.push(c);
            out.history.push(old.history[k]);
            out.report.push(old.report[k]);
            k += 1;
        } else {
            out.push(c, ContactHistory::UNBONDED);
        }
    }
    while k < old.len() {
        if old.history[k].bond == BondState::Intact {
            out.pair.push(old.pair[k]);
            out.history.push(old.history[k]);
            out.report.push(old.report[k]);
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
        .zip(&state.contacts.report)
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
