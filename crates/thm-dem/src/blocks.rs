//! The step's contact pass and gather as one parallel region over blocks of particles.
//!
//! A block's contact pass (contact `c`) reads the particles of its own and of later blocks
//! (a contact `[a, b]` has `a < b`) and writes its own contacts' data and block sums; the
//! gather of block `j` (gather `j`) reads the block sums of `j` and the spill entries left
//! for `j` by earlier blocks, and moves the particles of `j`. So gather `j` may run as soon
//! as contacts `0..=j` are done, while later contacts are still running: the threads of
//! the pool take contacts in ascending order and each runs the gather of the block it has
//! just finished when every earlier contact is done too; when no contact is left they share
//! the gathers still waiting (about a fifth of a contact's time each), so the threads finish
//! within a gather of each other instead of up to a contact block apart.
//!
//! A thread with nothing to take spins while another thread is inside a contact or a gather
//! (pure computation, so the wait is finite) and returns only when all are done: a rayon
//! worker that finds nothing to steal goes to sleep after a few microseconds, and waking
//! it again (a futex wake of a halted virtual CPU) cost about 60 µs per step on the
//! 10⁴-sphere bed, more than the imbalance it waited for. Only past [`MAX_WAIT`] (the thread
//! it waits for lost its core on a loaded machine) does it return earlier and leave the
//! remaining jobs to the threads still working.
//!
//! Which thread runs a contact or a gather changes nothing in its result.
//!
//! The rows that a contact and a gather see (see [`ContactRows`] and [`GatherRows`]) are
//! borrowed from slices shared by all threads; this module's schedule is what makes those
//! borrows disjoint, so the unsafe code (and its proof) stays in this module.
#![allow(unsafe_code)]

use crate::vec3::Vec3;
use std::hint::spin_loop;
use std::marker::PhantomData;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

/// Spins (with the CPU's pause hint, up to about 140 cycles each on recent x86) before a
/// waiting thread starts yielding its core between polls: a thread that holds the contact
/// or gather it waits for may have been descheduled on a loaded (or oversubscribed)
/// machine. Yielding does not sleep: an idle core returns at once.
const SPINS_BEFORE_YIELD: u32 = 1 << 8;

/// How long a thread waits for another's contact or gather before it leaves the work to the
/// others: a few contact blocks of the 10⁴-sphere bed (about 40 µs each) on an unloaded
/// machine, so that only a thread that lost its core waits longer.
const MAX_WAIT: Duration = Duration::from_micros(150);

/// Force and torque that a contact leaves for the gather of a later block (on its second
/// particle). Aligned to a 64-byte cache line: writing or reading one touches one line.
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
    /// On one thread only (else `None`): the sums of the contacts of earlier blocks on
    /// particles `s..n`, to which the contact adds those on its later blocks' particles in
    /// contact order instead of leaving spill entries (`[0]` is particle `s`).
    pub foreign: Option<&'r mut [SpillEntry]>,
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
    /// On one thread only (else `None`): the sums of the contacts of earlier blocks on the
    /// block's particles (see [`ContactRows::foreign`]), which the gather reads and clears.
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
}

/// Where a block stands in one [`contacts_then_gathers`] call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    Waiting,
    ContactTaken,
    ContactDone,
    GatherTaken,
}

/// The shared schedule of one call: handed out and updated only under its mutex.
struct Schedule<'s, S> {
    /// Blocks `next..`, whose contacts nobody has taken yet, with their data.
    rest: Option<(Range<usize>, S)>,
    stage: &'s mut [Stage],
    /// Contacts `0..prefix` are all done: gathers `0..prefix` may run.
    prefix: usize,
    /// Gathers below `scan` are all taken.
    scan: usize,
}

enum Job<S> {
    Contact(usize, S),
    Gather(usize),
    /// Nothing to take now, but contacts are running.
    Wait,
    /// Every gather is taken.
    Finished,
}

impl<S: BlockRun> Schedule<'_, S> {
    /// Contact `c` returned: advances the prefix of done contacts; then gather `c` if it
    /// may run now, else the next job.
    fn contact_done(&mut self, c: usize) -> Job<S> {
        self.stage[c] = Stage::ContactDone;
        while self.prefix < self.stage.len() && self.stage[self.prefix] == Stage::ContactDone {
            self.prefix += 1;
        }
        if c < self.prefix {
            self.stage[c] = Stage::GatherTaken;
            return Job::Gather(c);
        }
        self.next_job()
    }

    /// The next contact (ascending), else the first gather that may run, else whether to
    /// wait or stop.
    fn next_job(&mut self) -> Job<S> {
        if let Some((c, data)) = take_front(&mut self.rest) {
            self.stage[c] = Stage::ContactTaken;
            return Job::Contact(c, data);
        }
        while self.scan < self.stage.len() && self.stage[self.scan] == Stage::GatherTaken {
            self.scan += 1;
        }
        if self.scan == self.stage.len() {
            return Job::Finished;
        }
        match (self.scan..self.prefix).find(|&j| self.stage[j] == Stage::ContactDone) {
            Some(j) => {
                self.stage[j] = Stage::GatherTaken;
                Job::Gather(j)
            }
            None => Job::Wait,
        }
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

/// When dropped during a panic, tells the other threads to stop taking work and stop
/// waiting, so that rayon's join can pass the panic on.
struct AbortOnPanic<'a>(&'a AtomicBool);

impl Drop for AbortOnPanic<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Release);
        }
    }
}

/// Runs `contact(c, data of block c, rows of contact c)` and then `gather(c, rows of gather
/// c)` for every block `c` of `layout`, with `stage` as scratch; contacts and gathers run on
/// the calling thread and, with `parallel`, on the other threads of the current rayon pool
/// (up to one per block). Panics if `layout.spill_start` decreases from block to block or
/// a row lies outside its slice.
///
/// Why the row borrows are disjoint (the proof of the unsafe blocks below):
///
/// - each contact and each gather runs exactly once, and when this function returns (also
///   by a panic) none is running: a thread stops only when every gather is done or another
///   thread panicked, and rayon's join waits for every thread;
/// - gather `j` starts only after contacts `0..=j` have returned, and everything they wrote
///   happens before it (the schedule's mutex orders them); a contact's or gather's rows are
///   borrowed only for its call (`ContactRows<'r>`, `GatherRows<'r>` cannot outlive it);
/// - contact `c` (particles `s_c..e_c`) borrows kinematics rows `s_c..n` read-only and its
///   own force and torque rows `s_c..e_c` (its block sums) and spill and activity rows
///   `spill(c)` writable; gather `j` borrows particle rows `s_j..e_j` (kinematics, force and
///   torque) writable and spill and activity rows `0..spill_start[s_j]` read-only;
/// - while gather `j` runs, every contact still running has `c > j`, so `s_c >= e_j` (its
///   kinematics, force and torque rows lie above block `j`) and, `spill_start`
///   being nondecreasing at block boundaries (checked on entry), its spill and activity
///   rows start at `spill_start[s_c] >= spill_start[s_j]`; contacts borrow pairwise
///   disjoint force, torque, spill and activity rows, gathers pairwise disjoint particle
///   rows.
///
/// - on one thread only (no other thread runs a contact or a gather), contact `c` also
///   borrows the per-particle rows `s_c..n` of the foreign sums writable, and gather `j`
///   rows `s_j..e_j`; one runs after the other on that thread;
///
/// So no row is written while another borrow of it is alive.
#[allow(clippy::too_many_arguments)]
pub(crate) fn contacts_then_gathers<S: BlockRun>(
    layout: Layout<'_>,
    rows: &PassRows<'_>,
    data: S,
    stage: &mut Stages,
    parallel: bool,
    contact: &(impl Fn(usize, S, ContactRows<'_>) + Sync),
    gather: &(impl Fn(usize, GatherRows<'_>) + Sync),
) {
    let blocks = layout.blocks();
    assert!(
        (0..blocks).all(|c| layout.spill(c).start <= layout.spill(c).end),
        "spill entries out of block order"
    );
    let n = layout.n;
    let contact = |c: usize, data: S, serial: bool| {
        let p = layout.particles(c);
        // SAFETY: the rows of contact `c` (see above).
        let r = unsafe {
            ContactRows {
                position: rows.position.rows(p.start..n),
                velocity: rows.velocity.rows(p.start..n),
                angular_velocity: rows.angular_velocity.rows(p.start..n),
                spill: rows.spill.rows_mut(layout.spill(c)),
                active: rows.active.rows_mut(layout.spill(c)),
                foreign: serial.then(|| rows.foreign.rows_mut(p.start..n)),
                block_force: rows.force.rows_mut(p.clone()),
                block_torque: rows.torque.rows_mut(p),
            }
        };
        contact(c, data, r);
    };
    let gather = |j: usize, serial: bool| {
        let p = layout.particles(j);
        let below = layout.spill_start[p.start] as usize;
        // SAFETY: the rows of gather `j` (see above).
        let r = unsafe {
            GatherRows {
                position: rows.position.rows_mut(p.clone()),
                velocity: rows.velocity.rows_mut(p.clone()),
                angular_velocity: rows.angular_velocity.rows_mut(p.clone()),
                force: rows.force.rows_mut(p.clone()),
                torque: rows.torque.rows_mut(p.clone()),
                spill: rows.spill.rows(0..below),
                active: rows.active.rows(0..below),
                foreign: serial.then(|| rows.foreign.rows_mut(p)),
            }
        };
        gather(j, r);
    };
    let stage = stage.for_blocks(blocks);
    let threads = if parallel {
        rayon::current_num_threads().min(blocks)
    } else {
        1
    };
    if threads <= 1 {
        // In order on this thread: contact c, then gather c (contacts 0..=c are done).
        let mut rest = Some((0..blocks, data));
        while let Some((c, block)) = take_front(&mut rest) {
            contact(c, block, true);
            gather(c, true);
        }
        return;
    }
    let stage = &mut stage[..blocks];
    stage.fill(Stage::Waiting);
    let (contact, gather) = (&contact, &gather);
    let schedule = Mutex::new(Schedule {
        rest: Some((0..blocks, data)),
        stage,
        prefix: 0,
        scan: 0,
    });
    let gathers_done = AtomicUsize::new(0);
    let abort = AtomicBool::new(false);
    let participant = || {
        let _abort = AbortOnPanic(&abort);
        let lock = || schedule.lock().unwrap_or_else(PoisonError::into_inner);
        let mut job = lock().next_job();
        let mut waiter = Waiter::default();
        loop {
            if abort.load(Ordering::Acquire) {
                return;
            }
            job = match job {
                Job::Contact(c, block) => {
                    waiter = Waiter::default();
                    contact(c, block, false);
                    lock().contact_done(c)
                }
                Job::Gather(j) => {
                    waiter = Waiter::default();
                    gather(j, false);
                    gathers_done.fetch_add(1, Ordering::Release);
                    lock().next_job()
                }
                // Another thread is inside a contact that a gather waits for. Past the
                // waiting time (a descheduled thread on a loaded machine), this thread leaves
                // the rest to the threads still working: each job may run on any of them.
                Job::Wait if waiter.poll() => lock().next_job(),
                Job::Wait => return,
                Job::Finished => break,
            };
        }
        // Every gather is taken: wait for those still running elsewhere, so that this
        // thread does not go to sleep in rayon's join (see the module documentation).
        while gathers_done.load(Ordering::Acquire) < blocks
            && !abort.load(Ordering::Acquire)
            && waiter.poll()
        {}
    };
    participants(threads, &participant);
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

/// Scratch for [`contacts_then_gathers`]: one stage per block.
#[derive(Debug, Default)]
pub(crate) struct Stages(Vec<Stage>);

impl Stages {
    /// At least `blocks` stages.
    fn for_blocks(&mut self, blocks: usize) -> &mut [Stage] {
        if self.0.len() < blocks {
            self.0.resize(blocks, Stage::Waiting);
        }
        &mut self.0
    }
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

    /// Arrays for `n` particles, one spill entry per particle.
    struct Arrays {
        kin: [Vec<Vec3>; 5],
        spill: Vec<SpillEntry>,
        active: Vec<u8>,
        foreign: Vec<SpillEntry>,
        spill_start: Vec<u32>,
    }

    impl Arrays {
        fn new(n: usize) -> Self {
            let z = || vec![Vec3::ZERO; n];
            Self {
                kin: [z(), z(), z(), z(), z()],
                spill: vec![SpillEntry::default(); n],
                active: vec![0; n],
                foreign: vec![SpillEntry::default(); n],
                spill_start: (0..=n as u32).collect(),
            }
        }

        fn rows(&mut self) -> (Layout<'_>, PassRows<'_>) {
            let [x, v, w, f, t] = &mut self.kin;
            let layout = Layout {
                n: x.len(),
                block: BLOCK_LEN,
                spill_start: &self.spill_start,
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

    /// Contact c writes its block's entries, block sums and spill entries; gather j checks
    /// that contacts 0..=j are done and wrote theirs, and moves its particles.
    fn run(threads: usize, parallel: bool, len: usize) {
        let blocks = len.div_ceil(BLOCK_LEN);
        let mut own = vec![0_u64; len];
        let mut arrays = Arrays::new(len);
        let seen: Vec<AtomicUsize> = (0..blocks).map(|_| AtomicUsize::new(0)).collect();
        let gathered: Vec<AtomicUsize> = (0..blocks).map(|_| AtomicUsize::new(0)).collect();
        let mut stages = Stages::default();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (layout, rows) = arrays.rows();
        pool.install(|| {
            contacts_then_gathers(
                layout,
                &rows,
                Run(&mut own),
                &mut stages,
                parallel,
                &|c, Run(s), r| {
                    assert!(s.len() <= BLOCK_LEN && !s.is_empty());
                    assert_eq!(r.position.len(), len - c * BLOCK_LEN);
                    for (j, x) in s.iter_mut().enumerate() {
                        *x = (c * BLOCK_LEN + j) as u64 + 1;
                    }
                    assert_eq!(r.active.len(), r.spill.len());
                    let serial = threads == 1 || !parallel || blocks == 1;
                    assert_eq!(
                        r.foreign.map(|f| f.len()),
                        serial.then_some(r.position.len())
                    );
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
                    assert_eq!(seen[c].fetch_add(1, Ordering::Relaxed), 0);
                },
                &|j, r| {
                    for s in &seen[..=j] {
                        assert_eq!(s.load(Ordering::Relaxed), 1, "gather {j} too early");
                    }
                    assert_eq!(r.spill.len(), j * BLOCK_LEN);
                    let serial = threads == 1 || !parallel || blocks == 1;
                    assert_eq!(
                        r.foreign.map(|f| f.len()),
                        serial.then_some(r.position.len())
                    );
                    for (k, (sp, on)) in r.spill.iter().zip(r.active).enumerate() {
                        assert_eq!(sp.0[0].x, (k / BLOCK_LEN) as f64 + 1.0);
                        assert_eq!(*on, ((k / BLOCK_LEN) % 251) as u8 + 1);
                    }
                    for (x, f) in r.position.iter_mut().zip(r.force.iter_mut()) {
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
        assert!(arrays.kin[0].iter().all(|x| x.x == 1.0));
        assert!(arrays.kin[3].iter().all(|f| f.x == -1.0));
    }

    #[test]
    fn every_contact_and_gather_once_and_in_dependency_order() {
        for threads in [1, 2, 3, 5] {
            for parallel in [false, true] {
                for len in [0, 1, 3, 4, 7, 30, 31, 300] {
                    run(threads, parallel, len);
                }
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
            let mut arrays = Arrays::new(30);
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
