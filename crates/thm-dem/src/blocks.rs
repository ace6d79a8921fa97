//! Block scheduling of the step's parallel passes: every thread of the current rayon pool
//! takes whole blocks from one shared queue until none is left, then waits (spinning) for
//! the blocks still being computed elsewhere.
//!
//! Why not `rayon::join` recursion or a parallel iterator: a block of the contact pass costs
//! tens of microseconds, so the two halves of a split finish up to a block apart, and a rayon
//! worker that finds nothing to steal goes to sleep after a few microseconds; waking it
//! again (a futex wake of a halted virtual CPU) cost about 60 µs per step on the 10⁴-sphere
//! bed, more than the imbalance itself. Here a thread that has run out of blocks waits only
//! while another thread is inside a block, i.e. at most one block's time, and returns to
//! rayon's join when the last block is done, so nobody sleeps between the passes.
//!
//! The blocks do not change: which thread computes a block changes nothing in its result.

use std::hint::spin_loop;
use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// Spins (with the CPU's pause hint) before a waiting thread starts yielding its core: a
/// block is done in tens of microseconds on an unloaded machine, but a thread that holds one
/// may have been descheduled on a loaded one.
const SPINS_BEFORE_YIELD: u32 = 1 << 14;

/// The part of a pass's data that belongs to a run of whole blocks, split between blocks.
pub(crate) trait BlockRun: Sized + Send {
    /// Splits the data of blocks `run` before block `at` (`run.start < at < run.end`).
    fn split_at_block(self, run: Range<usize>, at: usize) -> (Self, Self);
}

/// Counts a block as done when dropped, also when its computation panics: a thread waiting
/// for the count then stops waiting, and rayon's join passes the panic on.
struct DoneOnDrop<'a>(&'a AtomicUsize);

impl Drop for DoneOnDrop<'_> {
    fn drop(&mut self) {
        self.0.fetch_add(1, Ordering::Release);
    }
}

/// Runs `work(c, data of block c)` once for every block `c` of `blocks`. With `parallel` and
/// more than one thread in the current pool, every thread (up to one per block) takes blocks
/// from the front of the queue, except one that takes them from the back (so that, with two
/// threads, each keeps about the same contiguous half from pass to pass and from step to
/// step); otherwise the blocks run in order on the calling thread.
///
/// `work` must not wait for other rayon work (the passes' blocks are plain loops): a thread
/// that has run out of blocks waits until the blocks taken by others are done, which is
/// finite only because each of them is being computed by a thread that waits for nothing.
pub(crate) fn for_each_block<S: BlockRun>(
    blocks: Range<usize>,
    data: S,
    parallel: bool,
    work: &(impl Fn(usize, S) + Sync),
) {
    let threads = if parallel {
        rayon::current_num_threads().min(blocks.len())
    } else {
        1
    };
    if threads <= 1 {
        let mut rest = Some((blocks, data));
        while let Some((c, block)) = take(&mut rest, false) {
            work(c, block);
        }
        return;
    }
    let total = blocks.len();
    let queue = Mutex::new(Some((blocks, data)));
    let done = AtomicUsize::new(0);
    let participant = |from_back: bool| {
        loop {
            // Only the split runs under the lock (a few pointer splits per block).
            let next = take(
                &mut queue.lock().unwrap_or_else(PoisonError::into_inner),
                from_back,
            );
            let Some((c, block)) = next else { break };
            let _done = DoneOnDrop(&done);
            work(c, block);
        }
        let mut spins = 0_u32;
        while done.load(Ordering::Acquire) < total {
            if spins < SPINS_BEFORE_YIELD {
                spins += 1;
                spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
    };
    participants(0..threads, threads - 1, &participant);
}

/// The next block of the queue `q` (its first, or its last with `from_back`), with its data;
/// `None` when the queue is empty.
fn take<S: BlockRun>(q: &mut Option<(Range<usize>, S)>, from_back: bool) -> Option<(usize, S)> {
    let (run, data) = q.take()?;
    match run.len() {
        0 => None,
        1 => Some((run.start, data)),
        _ if from_back => {
            let c = run.end - 1;
            let (low, high) = data.split_at_block(run.clone(), c);
            *q = Some((run.start..c, low));
            Some((c, high))
        }
        _ => {
            let c = run.start;
            let (low, high) = data.split_at_block(run.clone(), c + 1);
            *q = Some((c + 1..run.end, high));
            Some((c, low))
        }
    }
}

/// Runs `f` once per index of `ids` in parallel (rayon's join), `f(true)` for `back`.
fn participants(ids: Range<usize>, back: usize, f: &(impl Fn(bool) + Sync)) {
    if ids.len() == 1 {
        f(ids.start == back);
    } else {
        let mid = ids.start + ids.len() / 2;
        rayon::join(
            || participants(ids.start..mid, back, f),
            || participants(mid..ids.end, back, f),
        );
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

    fn fill(threads: usize, parallel: bool, len: usize) -> (Vec<u64>, usize) {
        let mut v = vec![0_u64; len];
        let blocks = len.div_ceil(BLOCK_LEN);
        let calls = AtomicUsize::new(0);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            for_each_block(0..blocks, Run(&mut v), parallel, &|c, Run(s)| {
                calls.fetch_add(1, Ordering::Relaxed);
                assert!(s.len() <= BLOCK_LEN && !s.is_empty());
                for (j, x) in s.iter_mut().enumerate() {
                    *x += (c * BLOCK_LEN + j) as u64 + 1;
                }
            });
        });
        (v, calls.into_inner())
    }

    #[test]
    fn every_block_once_with_its_own_data() {
        for threads in [1, 2, 3, 5] {
            for parallel in [false, true] {
                for len in [0, 1, 3, 4, 7, 30, 31] {
                    let (v, calls) = fill(threads, parallel, len);
                    assert_eq!(calls, len.div_ceil(BLOCK_LEN), "{threads} {parallel} {len}");
                    let want: Vec<u64> = (1..=len as u64).collect();
                    assert_eq!(v, want, "{threads} {parallel} {len}");
                }
            }
        }
    }

    #[test]
    fn a_panicking_block_reaches_the_caller() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let mut v = vec![0_u64; 30];
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| {
                for_each_block(0..10, Run(&mut v), true, &|c, _| {
                    assert_ne!(c, 4, "block 4");
                });
            })
        }));
        assert!(r.is_err());
    }
}
