//! The step's contact pass and gather as one parallel region over blocks of particles.
//!
//! A block's contact pass (contact `c`) reads the particles of its own and of later blocks
//! (a contact `[a, b]` has `a < b`), up to the last particle its contacts reach, and writes
//! its own contacts' data and block sums; the gather of block `j` (gather `j`) sums what
//! the contacts of earlier blocks left for its particles, adds the block sums and moves the
//! particles of `j`. What a contact leaves for a particle of a later block is added at once
//! to that particle's running sum (in contact order: the contacts of a run of blocks are
//! taken in order by one thread), unless a contact of an earlier run reaches the particle
//! too: then it goes to the contact's spill entry, and the gather sums the spill entries
//! in contact order. Both give the same bits: a running sum in contact order from +0.
//!
//! On several threads the blocks are cut into as many contiguous runs as threads; each
//! thread takes the next run and does, in order, contact `c` and, unless a contact of an
//! earlier run reaches block `c` (the run's "zone", a prefix of it about one layer of
//! particles long), gather `c`; then it waits until every earlier run's contacts are done
//! and gathers its zone. Spill entries are written only for the contacts that reach a zone,
//! and a thread reads what another wrote only there. The runs are cut where the blocks'
//! costs in the last call (contact and gather timed apart) give each run the same work
//! before its zone gathers, which wait for the earlier runs and are shared by all threads
//! at the end (see [`Costs::cut`]).
//!
//! A waiting thread spins, then yields its core between polls (the run it waits for may
//! have lost its core on a loaded machine): a rayon worker that sleeps costs a futex wake
//! (about 60 µs per step on the 10⁴-sphere bed).
//!
//! Which thread runs a contact or a gather, and where the runs are cut, changes nothing in
//! the result.
//!
//! The rows that a contact and a gather see (see [`ContactRows`] and [`GatherRows`]) are
//! borrowed from slices shared by all threads; this module's schedule is what makes those
//! borrows disjoint, so the unsafe code (and its proof) stays in this module.
#![allow(unsafe_code)]

use crate::vec3::Vec3;
use std::hint::spin_loop;
use std::marker::PhantomData;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

/// Spins (with the CPU's pause hint, up to about 140 cycles each on recent x86) before a
/// waiting thread starts yielding its core between polls.
const SPINS_BEFORE_YIELD: u32 = 1 << 8;

/// How long a thread with nothing to take waits for the others before it leaves the rest to
/// them: a few contact blocks of the 10⁴-sphere bed (about 40 µs each) on an unloaded
/// machine, so that only a thread that lost its core waits longer.
const MAX_WAIT: Duration = Duration::from_micros(150);

/// At most this many runs (threads) share one call.
const MAX_RUNS: usize = 64;

/// Force and torque that a contact leaves for the gather of a later block (on its second
/// particle), and a particle's running sum of those.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct SpillEntry(pub [Vec3; 2]);

/// The part of the contact pass's data that belongs to a run of whole blocks, split
/// between blocks.
pub(crate) trait BlockRun: Sized + Send {
    /// Splits the data of blocks `run` before block `at` (`run.start < at < run.end`).
    fn split_at_block(self, run: Range<usize>, at: usize) -> (Self, Self);
}

/// A slice that the contacts and gathers of one [`contacts_then_gathers`] call share, its
/// rows borrowed by each of them for its own duration. Which rows a contact or a gather may
/// borrow is proven in [`contacts_then_gathers`]; the borrow checker only sees that the
/// whole slice is borrowed mutably for `'a`.
struct Rows<'a, T> {
    ptr: *mut T,
    len: usize,
    _slice: PhantomData<&'a mut [T]>,
}

// SAFETY: a `Rows` is a `&'a mut [T]` handed to several threads; what each may do with its
// rows is stated by the unsafe methods, whose callers prove that no row is written by one
// thread while another thread borrows it. With that, sending or sharing it is as sound as
// sending a `&mut [T]` (`T: Send`) or sharing a `&[T]` (`T: Sync`).
unsafe impl<T: Send> Send for Rows<'_, T> {}
// SAFETY: as above.
unsafe impl<T: Send + Sync> Sync for Rows<'_, T> {}

impl<'a, T> Rows<'a, T> {
    /// Shares `slice` for `'a`.
    fn new(slice: &'a mut [T]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _slice: PhantomData,
        }
    }

    /// Rows `r`, read-only. Panics unless `r` lies within the slice.
    ///
    /// # Safety
    ///
    /// No thread may write any of the rows `r` (through [`Rows::rows_mut`]) while the returned
    /// slice is in use.
    // SAFETY: an unsafe fn because its soundness rests on the caller's promise above; the
    // bounds are checked here.
    unsafe fn rows(&self, r: Range<usize>) -> &[T] {
        assert!(r.start <= r.end && r.end <= self.len, "rows out of range");
        // SAFETY: in bounds (checked above) of a slice that lives for 'a; no writer meanwhile
        // (the caller's promise).
        unsafe { std::slice::from_raw_parts(self.ptr.add(r.start), r.end - r.start) }
    }

    /// Rows `r`, writable. Panics unless `r` lies within the slice.
    ///
    /// # Safety
    ///
    /// No other borrow of any of the rows `r` (from [`Rows::rows`] or [`Rows::rows_mut`], by
    /// any thread) may be in use while the returned slice is.
    // SAFETY: an unsafe fn because its soundness rests on the caller's promise above; the
    // bounds are checked here.
    #[allow(clippy::mut_from_ref)]
    unsafe fn rows_mut(&self, r: Range<usize>) -> &mut [T] {
        assert!(r.start <= r.end && r.end <= self.len, "rows out of range");
        // SAFETY: in bounds (checked above); exclusive for its use (the caller's promise).
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(r.start), r.end - r.start) }
    }
}

/// The slices that contacts and gathers share: the particles' kinematics (read by contacts,
/// moved by gathers), resultant force and torque (the block sums, written by a block's
/// contact, then read and overwritten with the resultant by its gather) and spill entries
/// with their contacts'
/// activity flags (written by the contact that owns them, read by the gathers of later
/// blocks).
pub(crate) struct PassRows<'a> {
    position: Rows<'a, Vec3>,
    velocity: Rows<'a, Vec3>,
    angular_velocity: Rows<'a, Vec3>,
    force: Rows<'a, Vec3>,
    torque: Rows<'a, Vec3>,
    spill: Rows<'a, SpillEntry>,
    active: Rows<'a, u8>,
    foreign: Rows<'a, SpillEntry>,
}

impl<'a> PassRows<'a> {
    /// Shares the slices for `'a`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        position: &'a mut [Vec3],
        velocity: &'a mut [Vec3],
        angular_velocity: &'a mut [Vec3],
        force: &'a mut [Vec3],
        torque: &'a mut [Vec3],
        spill: &'a mut [SpillEntry],
        active: &'a mut [u8],
        foreign: &'a mut [SpillEntry],
    ) -> Self {
        Self {
            position: Rows::new(position),
            velocity: Rows::new(velocity),
            angular_velocity: Rows::new(angular_velocity),
            force: Rows::new(force),
            torque: Rows::new(torque),
            spill: Rows::new(spill),
            active: Rows::new(active),
            foreign: Rows::new(foreign),
        }
    }
}

/// What the contact of block `c` (particles `s..e`) sees: the kinematics of particles `s..n`
/// (`position[0]` is particle `s`), its own spill entries and activity flags (`[0]` is its
/// first contact) and its block sums, held in the force and torque rows of its particles
/// (`[0]` is particle `s`).
pub(crate) struct ContactRows<'r> {
    pub position: &'r [Vec3],
    pub velocity: &'r [Vec3],
    pub angular_velocity: &'r [Vec3],
    pub spill: &'r mut [SpillEntry],
    pub active: &'r mut [u8],
    /// The running sums of the particles to which the contact adds its share directly
    /// (see the module documentation); a particle of a later block outside them gets a
    /// spill entry.
    pub foreign: ForeignRows<'r>,
    pub block_force: &'r mut [Vec3],
    pub block_torque: &'r mut [Vec3],
}

/// What the gather of block `j` (particles `s..e`) sees: its particles' kinematics, force
/// and torque (`[0]` is particle `s`, all writable; force and torque hold the block sums
/// on entry), and the spill entries and activity flags of the contacts of blocks `0..j`
/// (read-only).
pub(crate) struct GatherRows<'r> {
    pub position: &'r mut [Vec3],
    pub velocity: &'r mut [Vec3],
    pub angular_velocity: &'r mut [Vec3],
    pub force: &'r mut [Vec3],
    pub torque: &'r mut [Vec3],
    pub spill: &'r [SpillEntry],
    pub active: &'r [u8],
    /// The running sums of the block's particles, which the gather reads and clears; `None`
    /// when the block lies in a zone (then `spill` and `active` hold what earlier blocks
    /// left, else they are empty).
    pub foreign: Option<&'r mut [SpillEntry]>,
}

/// How the particles and spill entries fall into blocks: block `c` holds particles
/// `c·block..(c+1)·block` (the last one fewer, up to `n`) and spill entries
/// `spill_start[s]..spill_start[e]` of its particles `s..e`.
#[derive(Clone, Copy)]
pub(crate) struct Layout<'a> {
    pub n: usize,
    pub block: usize,
    pub spill_start: &'a [u32],
    /// Per block: one past the last particle its contacts reach (at least its own end).
    pub reach: &'a [u32],
}

/// Running sums of particles `start..start + sums.len()` (see [`ContactRows::foreign`]).
pub(crate) struct ForeignRows<'r> {
    pub start: usize,
    pub sums: &'r mut [SpillEntry],
}

impl ForeignRows<'_> {
    /// The running sum of particle `i`, if it is one of these.
    #[inline]
    pub fn get(&mut self, i: usize) -> Option<&mut SpillEntry> {
        self.sums.get_mut(i.wrapping_sub(self.start))
    }
}

impl Layout<'_> {
    fn blocks(&self) -> usize {
        self.n.div_ceil(self.block)
    }

    fn particles(&self, c: usize) -> Range<usize> {
        (c * self.block).min(self.n)..((c + 1) * self.block).min(self.n)
    }

    fn spill(&self, c: usize) -> Range<usize> {
        let p = self.particles(c);
        self.spill_start[p.start] as usize..self.spill_start[p.end] as usize
    }

    /// The particles whose kinematics contact `c` reads.
    fn read_by(&self, c: usize) -> Range<usize> {
        let p = self.particles(c);
        p.start..(self.reach[c] as usize).clamp(p.end, self.n)
    }
}

/// The first block of the run `q` with its data (the rest stays in `q`); `None` when empty.
fn take_front<S: BlockRun>(q: &mut Option<(Range<usize>, S)>) -> Option<(usize, S)> {
    let (run, data) = q.take()?;
    match run.len() {
        0 => None,
        1 => Some((run.start, data)),
        _ => {
            let c = run.start;
            let (low, high) = data.split_at_block(run.clone(), c + 1);
            *q = Some((c + 1..run.end, high));
            Some((c, low))
        }
    }
}

/// The blocks `..end` of the run `q` with their data (the rest stays in `q`).
fn take_until<S: BlockRun>(
    q: &mut Option<(Range<usize>, S)>,
    end: usize,
) -> Option<(Range<usize>, S)> {
    let (run, data) = q.take()?;
    if end >= run.end {
        return Some((run, data));
    }
    if end <= run.start {
        *q = Some((run, data));
        return None;
    }
    let (low, high) = data.split_at_block(run.clone(), end);
    *q = Some((end..run.end, high));
    Some((run.start..end, low))
}

/// When dropped during a panic, tells the other threads to stop waiting, so that rayon's
/// join can pass the panic on.
struct AbortOnPanic<'a>(&'a AtomicBool);

impl Drop for AbortOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Release);
        }
    }
}

/// Runs `contact(c, data of block c, rows of contact c)` and `gather(c, rows of gather c)`
/// for every block `c` of `layout`, with `scratch`; on the calling thread and, with
/// `parallel`, on the other threads of the current rayon pool (one run of blocks each, see
/// the module documentation). Panics if `layout.spill_start` decreases from block to block
/// or a row lies outside its slice (a contact that reads a particle outside
/// `layout.read_by(c)`).
///
/// Runs: run `t` holds blocks `bound[t]..bound[t + 1]` (particles `s_t..r_t`); its zone is
/// its particles below `z_t`, the largest `reach` of the blocks of earlier runs rounded up
/// to a block boundary (clamped to `s_t..r_t`; `z_0 = s_0`); one thread is one run.
///
/// Why the row borrows are disjoint (the proof of the unsafe blocks below):
///
/// - each run is taken by exactly one thread, which runs its contacts in block order, the
///   gather of a block outside the zone right after its contact, and the gathers of its
///   zone after its own contacts and after every earlier run has set its "contacts done"
///   flag (release / acquire, so all those contacts' writes happen before); a contact's
///   or gather's rows are borrowed only for its call (`ContactRows<'r>`, `GatherRows<'r>`);
///   when this function returns (also by a panic) no contact or gather is running (rayon's
///   join waits for every thread);
/// - contact `c` of run `t` borrows kinematics rows `read_by(c)` read-only, its own force
///   and torque rows (block sums) and its own spill and activity rows writable, and the
///   running sums `max(s_c, z_t)..r_t` writable; gather `j` borrows its particle rows
///   (kinematics, force, torque, and its running sums outside the zone) writable and, in a
///   zone only, the spill and activity rows `0..spill_start[s_j]` read-only;
/// - two contacts: kinematics are only read; block sums, spill and activity rows are each
///   contact's own; running sums lie in the contact's own run, and two contacts of one run
///   never run at once;
/// - contact `c` of run `t` and gather `j` of run `u` at the same time: `u != t` (a run is
///   one thread). If `u > t`: a zone gather waits for run `t`'s contacts, so `j` is outside
///   the zone, `s_j >= z_u >= reach[c]` (kinematics disjoint), it borrows no spill or
///   activity rows, and its running sums lie in run `u`. If `u < t`: `j`'s particles and
///   sums lie below `s_t <= s_c`, and its spill rows end at `spill_start[s_j] <=
///   spill_start[s_c]`, where `c`'s begin (nondecreasing, checked on entry);
/// - two gathers: their particle rows and running sums are disjoint; spill is only read.
///
/// So no row is written while another borrow of it is alive.
#[allow(clippy::too_many_arguments)]
pub(crate) fn contacts_then_gathers<S: BlockRun>(
    layout: Layout<'_>,
    rows: &PassRows<'_>,
    data: S,
    scratch: &mut Stages,
    parallel: bool,
    contact: &(impl Fn(usize, S, ContactRows<'_>) + Sync),
    gather: &(impl Fn(usize, GatherRows<'_>) + Sync),
) {
    let blocks = layout.blocks();
    assert!(
        (0..blocks).all(|c| layout.spill(c).start <= layout.spill(c).end),
        "spill entries out of block order"
    );
    assert!(layout.reach.len() >= blocks, "a reach per block");
    if blocks == 0 {
        return;
    }
    let threads = if parallel {
        rayon::current_num_threads().min(blocks).min(MAX_RUNS)
    } else {
        1
    };
    let Stages {
        bound,
        zone,
        progress,
        next_zone,
        contact_cost,
        gather_cost,
    } = scratch;
    if contact_cost.len() != blocks {
        contact_cost.clear();
        contact_cost.resize_with(blocks, || AtomicU64::new(1));
        gather_cost.clear();
        gather_cost.resize_with(blocks, || AtomicU64::new(0));
    }
    let costs = Costs {
        layout,
        contact: contact_cost,
        gather: gather_cost,
    };
    // The zone gathers wait for the earlier runs and are shared at the end, so the runs are
    // cut to equal costs without them; their cost depends on the cut, hence a second cut.
    let deferred = costs.cut(threads, 0, bound);
    costs.cut(threads, deferred, bound);
    // Zones: the largest reach of every earlier run.
    zone.clear();
    let mut reach = 0_usize;
    for t in 0..threads {
        let first = layout.particles(bound[t]).start;
        let end = layout.particles(bound[t + 1] - 1).end;
        let z = reach.div_ceil(layout.block) * layout.block;
        zone.push(z.clamp(first, end));
        for c in bound[t]..bound[t + 1] {
            reach = reach.max(layout.reach[c] as usize);
        }
    }
    progress.truncate(0);
    progress.resize_with(threads, || AtomicUsize::new(0));
    next_zone.truncate(0);
    next_zone.extend(bound[..threads].iter().map(|&b| AtomicUsize::new(b)));
    let (bound, zone, progress, next_zone, contact_cost, gather_cost) = (
        &bound[..],
        &zone[..],
        &progress[..],
        &next_zone[..],
        &contact_cost[..],
        &gather_cost[..],
    );
    let contact = |t: usize, c: usize, data: S| {
        let p = layout.particles(c);
        let run_end = layout.particles(bound[t + 1] - 1).end;
        let sums = p.start.max(zone[t])..run_end;
        // SAFETY: the rows of contact `c` of run `t` (see above).
        let r = unsafe {
            ContactRows {
                position: rows.position.rows(layout.read_by(c)),
                velocity: rows.velocity.rows(layout.read_by(c)),
                angular_velocity: rows.angular_velocity.rows(layout.read_by(c)),
                spill: rows.spill.rows_mut(layout.spill(c)),
                active: rows.active.rows_mut(layout.spill(c)),
                foreign: ForeignRows {
                    start: sums.start,
                    sums: rows.foreign.rows_mut(sums),
                },
                block_force: rows.force.rows_mut(p.clone()),
                block_torque: rows.torque.rows_mut(p),
            }
        };
        contact(c, data, r);
    };
    let gather = |t: usize, j: usize| {
        let p = layout.particles(j);
        let in_zone = p.start < zone[t];
        let below = if in_zone {
            layout.spill_start[p.start] as usize
        } else {
            0
        };
        // SAFETY: the rows of gather `j` of run `t` (see above).
        let r = unsafe {
            GatherRows {
                position: rows.position.rows_mut(p.clone()),
                velocity: rows.velocity.rows_mut(p.clone()),
                angular_velocity: rows.angular_velocity.rows_mut(p.clone()),
                force: rows.force.rows_mut(p.clone()),
                torque: rows.torque.rows_mut(p.clone()),
                spill: rows.spill.rows(0..below),
                active: rows.active.rows(0..below),
                foreign: (!in_zone).then(|| rows.foreign.rows_mut(p)),
            }
        };
        gather(j, r);
    };
    let schedule = Mutex::new((0_usize, Some((0..blocks, data))));
    let abort = AtomicBool::new(false);
    // Per run: how many of its contacts are done (in block order), the next zone gather to
    // take; over all runs: runs whose contacts and gathers outside the zone are done, zone
    // gathers done.
    let zone_end = |t: usize| {
        bound[t + 1]
            .min(zone[t].div_ceil(layout.block))
            .max(bound[t])
    };
    let zone_total: usize = (0..threads).map(|t| zone_end(t) - bound[t]).sum();
    let runs_finished = AtomicUsize::new(0);
    let zones_finished = AtomicUsize::new(0);
    let participant = || {
        let _abort = AbortOnPanic(&abort);
        loop {
            let (t, mut run) = {
                let mut s = schedule.lock().unwrap_or_else(PoisonError::into_inner);
                let t = s.0;
                if t >= threads {
                    break;
                }
                s.0 += 1;
                (t, take_until(&mut s.1, bound[t + 1]))
            };
            let zone_blocks = bound[t]..zone_end(t);
            while let Some((c, block)) = take_front(&mut run) {
                let started = Instant::now();
                contact(t, c, block);
                let contact_done = Instant::now();
                contact_cost[c].store(elapsed(started, contact_done), Ordering::Relaxed);
                progress[t].store(c + 1 - bound[t], Ordering::Release);
                if !zone_blocks.contains(&c) {
                    gather(t, c);
                    gather_cost[c].store(nanos(contact_done), Ordering::Relaxed);
                }
            }
            runs_finished.fetch_add(1, Ordering::Release);
        }
        // Zone gathers, by whichever thread finds one ready: gather `j` of run `t` once every
        // earlier run's contacts and run `t`'s contacts up to `j` are done. A thread with
        // nothing to take waits until all is done (so that it does not sleep in rayon's join)
        // but gives up after `MAX_WAIT`: the thread that finishes the last run's contacts
        // finds every zone gather ready.
        let mut waiter = Waiter::default();
        loop {
            if abort.load(Ordering::Acquire) {
                return;
            }
            let mut took = false;
            let mut earlier_done = true;
            for t in 0..threads {
                if earlier_done {
                    let done = progress[t].load(Ordering::Acquire);
                    loop {
                        let j = next_zone[t].load(Ordering::Relaxed);
                        if j >= zone_end(t) || j - bound[t] >= done {
                            break;
                        }
                        if next_zone[t]
                            .compare_exchange(j, j + 1, Ordering::Relaxed, Ordering::Relaxed)
                            .is_ok()
                        {
                            let started = Instant::now();
                            gather(t, j);
                            gather_cost[j].store(nanos(started), Ordering::Relaxed);
                            zones_finished.fetch_add(1, Ordering::Release);
                            took = true;
                        }
                    }
                    earlier_done = done == bound[t + 1] - bound[t];
                }
            }
            if runs_finished.load(Ordering::Acquire) == threads
                && zones_finished.load(Ordering::Acquire) == zone_total
            {
                return;
            }
            if took {
                waiter = Waiter::default();
            } else if !waiter.poll() {
                return;
            }
        }
    };
    participants(threads, &participant);
}

/// Nanoseconds since `t`.
fn nanos(t: Instant) -> u64 {
    elapsed(t, Instant::now())
}

/// Nanoseconds from `t` to `u`.
fn elapsed(t: Instant, u: Instant) -> u64 {
    u64::try_from(u.saturating_duration_since(t).as_nanos()).unwrap_or(u64::MAX)
}

/// The blocks' costs in the last call, and where they cut the runs.
struct Costs<'a> {
    layout: Layout<'a>,
    contact: &'a [AtomicU64],
    gather: &'a [AtomicU64],
}

impl Costs<'_> {
    /// Block `c`'s contact and gather costs in the last call (a contact at least 1 ns).
    fn of(&self, c: usize) -> (u64, u64) {
        (
            self.contact[c].load(Ordering::Relaxed).max(1),
            self.gather[c].load(Ordering::Relaxed),
        )
    }

    /// Cuts the blocks into `threads` runs (`bound[t]..bound[t + 1]`, none empty) such that
    /// each run's cost without its zone gathers is about `1/threads` of the total less
    /// `deferred` (the zone gathers' cost, shared by all threads once the runs are done);
    /// returns the cost of this cut's zone gathers.
    ///
    /// With a run's own work `X` each and zone gathers `Z` in all, the last thread is done
    /// at about `X + Z / threads`, the total over the threads; runs of equal total cost
    /// instead leave the threads with zones idle for their zone gathers' cost while the
    /// earlier runs finish.
    fn cut(&self, threads: usize, deferred: u64, bound: &mut Vec<usize>) -> u64 {
        let blocks = self.layout.blocks();
        let total: u64 = (0..blocks).map(|c| self.of(c).0 + self.of(c).1).sum();
        let own = total.saturating_sub(deferred);
        bound.clear();
        bound.push(0);
        // Over the runs so far: the work outside zones, the zone gathers, the largest reach
        // (whose block ends the current run's zone).
        let (mut sum, mut zone_gathers, mut reach) = (0_u64, 0_u64, 0_usize);
        let mut zone_end = 0;
        let mut c = 0;
        for t in 1..=threads {
            let target = if t == threads {
                u64::MAX
            } else {
                own * t as u64 / threads as u64
            };
            loop {
                if c >= blocks {
                    break;
                }
                let (k, g) = self.of(c);
                let weight = if c < zone_end { k } else { k + g };
                let last_allowed = blocks - (threads - t);
                // At least one block per run, and one left for each later run.
                if c > bound[t - 1] && (c >= last_allowed || sum + weight / 2 >= target) {
                    break;
                }
                sum += weight;
                if c < zone_end {
                    zone_gathers += g;
                }
                reach = reach.max(self.layout.reach[c] as usize);
                c += 1;
            }
            bound.push(c);
            zone_end = reach.div_ceil(self.layout.block).max(c);
        }
        zone_gathers
    }
}

/// Polls for another thread's progress: spins, then yields its core between polls, and
/// after [`MAX_WAIT`] says to stop waiting (and let rayon's join sleep if it must).
#[derive(Default)]
struct Waiter {
    polls: u32,
    since: Option<Instant>,
}

impl Waiter {
    /// One poll; `false` once [`MAX_WAIT`] has passed since the first.
    fn poll(&mut self) -> bool {
        let since = *self.since.get_or_insert_with(Instant::now);
        if self.polls < SPINS_BEFORE_YIELD {
            spin_loop();
        } else {
            std::thread::yield_now();
        }
        self.polls += 1;
        !self.polls.is_multiple_of(64) || since.elapsed() < MAX_WAIT
    }
}

/// Runs `f` `count` times in parallel (rayon's join).
fn participants(count: usize, f: &(impl Fn() + Sync)) {
    if count <= 1 {
        f();
    } else {
        let half = count / 2;
        rayon::join(|| participants(half, f), || participants(count - half, f));
    }
}

/// Scratch for [`contacts_then_gathers`]: the runs' bounds and zones, and their flags.
#[derive(Debug, Default)]
pub(crate) struct Stages {
    bound: Vec<usize>,
    zone: Vec<usize>,
    progress: Vec<AtomicUsize>,
    next_zone: Vec<AtomicUsize>,
    /// Per block: the time its contact and its gather took in the last call \[ns\] (where
    /// the runs are cut; only the speed depends on them).
    contact_cost: Vec<AtomicU64>,
    gather_cost: Vec<AtomicU64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of blocks of `BLOCK_LEN` entries each (the last may be shorter).
    struct Run<'a>(&'a mut [u64]);
    const BLOCK_LEN: usize = 3;

    impl BlockRun for Run<'_> {
        fn split_at_block(self, run: Range<usize>, at: usize) -> (Self, Self) {
            let k = ((at - run.start) * BLOCK_LEN).min(self.0.len());
            let (a, b) = self.0.split_at_mut(k);
            (Run(a), Run(b))
        }
    }

    /// Arrays for `n` particles, one spill entry per particle; block `c`'s contacts reach
    /// `span` blocks beyond it.
    struct Arrays {
        kin: [Vec<Vec3>; 5],
        spill: Vec<SpillEntry>,
        active: Vec<u8>,
        foreign: Vec<SpillEntry>,
        spill_start: Vec<u32>,
        reach: Vec<u32>,
    }

    impl Arrays {
        fn new(n: usize, span: usize) -> Self {
            let z = || vec![Vec3::ZERO; n];
            let blocks = n.div_ceil(BLOCK_LEN);
            Self {
                kin: [z(), z(), z(), z(), z()],
                spill: vec![SpillEntry::default(); n],
                active: vec![0; n],
                foreign: vec![SpillEntry::default(); n],
                spill_start: (0..=n as u32).collect(),
                reach: (0..blocks)
                    .map(|c| (((c + 1 + span) * BLOCK_LEN).min(n)) as u32)
                    .collect(),
            }
        }

        fn rows(&mut self) -> (Layout<'_>, PassRows<'_>) {
            let [x, v, w, f, t] = &mut self.kin;
            let layout = Layout {
                n: x.len(),
                block: BLOCK_LEN,
                spill_start: &self.spill_start,
                reach: &self.reach,
            };
            (
                layout,
                PassRows::new(
                    x,
                    v,
                    w,
                    f,
                    t,
                    &mut self.spill,
                    &mut self.active,
                    &mut self.foreign,
                ),
            )
        }
    }

    /// Contact c writes its block's entries, block sums and spill entries, and adds one to
    /// every later particle it reaches: to its running sum, or (outside the sums it is
    /// lent) to a counter standing for a spill entry. Gather j checks that every contact
    /// reaching it is done, that the ones and the counters add up to the number of contacts
    /// reaching each particle, that a zone gather sees the spill entries of every earlier
    /// block, and moves its particles.
    fn run(threads: usize, parallel: bool, len: usize, span: usize, steps: usize) {
        let blocks = len.div_ceil(BLOCK_LEN);
        let mut arrays = Arrays::new(len, span);
        let reach = arrays.reach.clone();
        let mut stages = Stages::default();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for _ in 0..steps {
            let mut own = vec![0_u64; len];
            let seen: Vec<AtomicUsize> = (0..blocks).map(|_| AtomicUsize::new(0)).collect();
            let gathered: Vec<AtomicUsize> = (0..blocks).map(|_| AtomicUsize::new(0)).collect();
            let spilled: Vec<AtomicUsize> = (0..len).map(|_| AtomicUsize::new(0)).collect();
            let (layout, rows) = arrays.rows();
            pool.install(|| {
                contacts_then_gathers(
                    layout,
                    &rows,
                    Run(&mut own),
                    &mut stages,
                    parallel,
                    &|c, Run(s), mut r| {
                        assert!(s.len() <= BLOCK_LEN && !s.is_empty());
                        let start = c * BLOCK_LEN;
                        assert_eq!(r.position.len(), reach[c] as usize - start);
                        for (j, x) in s.iter_mut().enumerate() {
                            *x = (start + j) as u64 + 1;
                        }
                        assert_eq!(r.active.len(), r.spill.len());
                        for ((f, sp), on) in r
                            .block_force
                            .iter_mut()
                            .zip(r.spill.iter_mut())
                            .zip(r.active.iter_mut())
                        {
                            *f = Vec3::new(c as f64, 0.0, 0.0);
                            sp.0[0] = Vec3::new(c as f64 + 1.0, 0.0, 0.0);
                            *on = (c % 251) as u8 + 1;
                        }
                        let end = (start + BLOCK_LEN).min(len);
                        for (p, spill) in
                            spilled.iter().enumerate().take(reach[c] as usize).skip(end)
                        {
                            match r.foreign.get(p) {
                                Some(sum) => sum.0[0].x += 1.0,
                                None => {
                                    spill.fetch_add(1, Ordering::Relaxed);
                                }
                            }
                        }
                        assert_eq!(seen[c].fetch_add(1, Ordering::Relaxed), 0);
                    },
                    &|j, r| {
                        let start = j * BLOCK_LEN;
                        for c in 0..=j {
                            if c == j || reach[c] as usize > start {
                                assert_eq!(
                                    seen[c].load(Ordering::Relaxed),
                                    1,
                                    "gather {j} before contact {c}"
                                );
                            }
                        }
                        if r.foreign.is_none() {
                            assert_eq!(r.spill.len(), start);
                            for (k, (sp, on)) in r.spill.iter().zip(r.active).enumerate() {
                                assert_eq!(sp.0[0].x, (k / BLOCK_LEN) as f64 + 1.0);
                                assert_eq!(*on, ((k / BLOCK_LEN) % 251) as u8 + 1);
                            }
                        } else {
                            assert!(r.spill.is_empty() && r.active.is_empty());
                        }
                        let mut sums = r.foreign;
                        for (i, (x, f)) in r.position.iter_mut().zip(r.force.iter_mut()).enumerate()
                        {
                            let p = start + i;
                            let reaching = (0..j).filter(|&c| reach[c] as usize > p).count() as f64;
                            let direct = match sums.as_deref_mut() {
                                Some(s) => std::mem::take(&mut s[i]).0[0].x,
                                None => 0.0,
                            };
                            let spill = spilled[p].load(Ordering::Relaxed) as f64;
                            assert_eq!(direct + spill, reaching, "particle {p}");
                            if sums.is_none() {
                                assert_eq!(direct, 0.0);
                            } else {
                                assert_eq!(spill, 0.0, "particle {p}");
                            }
                            assert_eq!(f.x, j as f64);
                            x.x += 1.0;
                            f.x = -1.0;
                        }
                        assert_eq!(gathered[j].fetch_add(1, Ordering::Relaxed), 0);
                    },
                );
            });
            let want: Vec<u64> = (1..=len as u64).collect();
            assert_eq!(own, want, "{threads} {parallel} {len}");
            assert!(gathered.iter().all(|g| g.load(Ordering::Relaxed) == 1));
            assert!(arrays.kin[3].iter().all(|f| f.x == -1.0));
            assert!(arrays.foreign.iter().all(|f| *f == SpillEntry::default()));
        }
        assert!(arrays.kin[0].iter().all(|x| x.x == steps as f64));
    }

    #[test]
    fn every_contact_and_gather_once_and_in_dependency_order() {
        for threads in [1, 2, 3, 5] {
            for parallel in [false, true] {
                for len in [0, 1, 3, 4, 7, 30, 31, 300] {
                    for span in [0, 1, 4] {
                        run(threads, parallel, len, span, 3);
                    }
                }
            }
        }
    }

    /// The cut of `blocks` blocks of one particle each, block `c` reaching `span` blocks
    /// on, with contact costs `k` and gather costs `g`.
    fn cut_of(
        k: &[u64],
        g: &[u64],
        span: usize,
        threads: usize,
        deferred: u64,
    ) -> (Vec<usize>, u64) {
        let n = k.len();
        let reach: Vec<u32> = (0..n).map(|c| (c + 1 + span).min(n) as u32).collect();
        let spill_start = vec![0_u32; n + 1];
        let atomic = |v: &[u64]| v.iter().map(|&x| AtomicU64::new(x)).collect::<Vec<_>>();
        let (contact, gather) = (atomic(k), atomic(g));
        let costs = Costs {
            layout: Layout {
                n,
                block: 1,
                spill_start: &spill_start,
                reach: &reach,
            },
            contact: &contact,
            gather: &gather,
        };
        let mut bound = Vec::new();
        let zone_gathers = costs.cut(threads, deferred, &mut bound);
        (bound, zone_gathers)
    }

    #[test]
    fn the_zone_gathers_are_left_out_of_the_balance() {
        // 40 blocks of cost 10 + 10; run 1's zone is its first 2 blocks. Runs of equal
        // total cost would be cut at 20; without the zone gathers (20 in all, shared at
        // the end) run 1's own work is 21 · 20 − 20 = 400 against run 0's 19 · 20 = 380.
        let (k, g) = (vec![10; 40], vec![10; 40]);
        let (bound, zone_gathers) = cut_of(&k, &g, 2, 2, 0);
        assert_eq!((bound, zone_gathers), (vec![0, 20, 40], 20));
        let (bound, zone_gathers) = cut_of(&k, &g, 2, 2, 20);
        assert_eq!((bound, zone_gathers), (vec![0, 19, 40], 20));
    }

    proptest::proptest! {
        #[test]
        fn the_runs_cover_every_block_in_order_and_balance_their_own_work(
            costs in proptest::collection::vec((1_u64..1000, 0_u64..200), 1..80),
            span in 0_usize..6,
            threads in 1_usize..6,
        ) {
            let (k, g): (Vec<u64>, Vec<u64>) = costs.into_iter().unzip();
            let blocks = k.len();
            let threads = threads.min(blocks);
            let (first, deferred) = cut_of(&k, &g, span, threads, 0);
            let (bound, zone_gathers) = cut_of(&k, &g, span, threads, deferred);
            for b in [&first, &bound] {
                proptest::prop_assert_eq!(b.len(), threads + 1);
                proptest::prop_assert_eq!((b[0], b[threads]), (0, blocks));
                proptest::prop_assert!(b.windows(2).all(|w| w[0] < w[1]), "{:?}", b);
            }
            // The zone of run t: its blocks that an earlier run's block reaches.
            let mut own = vec![0_u64; threads];
            let mut in_zones = 0;
            for t in 0..threads {
                let reached = (0..bound[t]).map(|c| c + 1 + span).max().unwrap_or(0);
                for c in bound[t]..bound[t + 1] {
                    own[t] += k[c];
                    if c < reached {
                        in_zones += g[c];
                    } else {
                        own[t] += g[c];
                    }
                }
            }
            proptest::prop_assert_eq!(zone_gathers, in_zones);
            // Each cut falls within one block's cost of where the own work (less the
            // deferred zone gathers) is shared equally.
            let heaviest = (0..blocks).map(|c| k[c] + g[c]).max().unwrap_or(0);
            let target = (own.iter().sum::<u64>() + in_zones - deferred) / threads as u64;
            for t in 0..threads - 1 {
                let at = own[..=t].iter().sum::<u64>();
                let want = target * (t as u64 + 1);
                proptest::prop_assert!(
                    at + heaviest >= want && at <= want + heaviest || bound[t + 1] == t + 1
                        || bound[t + 1] == blocks - (threads - t - 1),
                    "{:?} {:?}", bound, own
                );
            }
        }
    }

    #[test]
    fn a_panicking_contact_reaches_the_caller() {
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut v = vec![0_u64; 30];
            let mut arrays = Arrays::new(30, 2);
            let mut stages = Stages::default();
            let (layout, rows) = arrays.rows();
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                pool.install(|| {
                    contacts_then_gathers(
                        layout,
                        &rows,
                        Run(&mut v),
                        &mut stages,
                        true,
                        &|c, _, _| assert_ne!(c, 4, "contact 4"),
                        &|_, _| {},
                    );
                })
            }));
            assert!(r.is_err(), "{threads}");
        }
    }

    #[test]
    fn rows_borrow_disjoint_ranges_on_several_threads() {
        let mut v = vec![0_u64; 64];
        let rows = Rows::new(&mut v);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        pool.install(|| {
            rayon::scope(|s| {
                for k in 0..4 {
                    let rows = &rows;
                    s.spawn(move |_| {
                        // SAFETY: each task borrows its own 16 rows only.
                        let r = unsafe { rows.rows_mut(16 * k..16 * k + 16) };
                        r.iter_mut().for_each(|x| *x = k as u64);
                    });
                }
            });
        });
        // SAFETY: no other borrow is alive.
        let all = unsafe { rows.rows(0..64) };
        assert!(all.iter().enumerate().all(|(i, &x)| x == (i / 16) as u64));
        let out_of_range = std::panic::AssertUnwindSafe(|| {
            // SAFETY: no other borrow is alive (and the range is rejected anyway).
            unsafe { rows.rows(60..65).len() }
        });
        assert!(std::panic::catch_unwind(out_of_range).is_err());
    }
}
