//! The RVE stage spread over processes (ranks): the seam a distributed run (`thm run` built
//! with MPI) plugs into, and everything above the wire.
//!
//! Every process runs the same MPM step, which is cheap next to the RVEs and deterministic, so
//! the processes stay in lock-step. The material points are cut into one contiguous block per
//! process ([`partition`] of a per-point cost); a process steps only its block's RVEs
//! ([`BlockMaterial::step_block`], which `RveMaterial` implements with rayon threads inside) and the processes all-gather one
//! fixed-size record per point ([`PointOutcome`] and the seconds its RVE took, [`WIRE_LEN`]
//! numbers) in point order. Each RVE is stepped alone and nothing is reduced across RVEs, so every
//! process continues with the bits of a run on one process, whatever the process and thread
//! counts.
//!
//! Between synchronisations a process holds current RVEs only for its own block; the copies
//! of the other points keep their diagnostics current (from the gathered outcomes) but not
//! their disks. [`Distribution::synchronise`] all-gathers the owned RVEs so that every
//! process holds every current RVE (the caller does it before anything reads the disks: a
//! frame, a checkpoint, the summary, an event that changes every RVE), and then re-balances
//! the blocks by measured cost: each point's RVE seconds summed since the last re-balancing,
//! which every process holds alike (they travel with the outcomes), so the assignment is
//! deterministic given the measurements and the same on every process. The first blocks,
//! before anything is measured, balance [`rve_cost`] (contacts × substeps). No bit of any
//! result depends on the assignment. A checkpoint written after it is the same file as a run on one process writes, so
//! a run resumes with any process count.
//!
//! A block that fails (an RVE that breaks down) sets a flag that every process reduces; the
//! lowest failing process broadcasts its message and every process returns
//! [`MultiscaleError::Distributed`] with it, so the run ends on every process at the same step
//! with the cause.
//!
//! [`Collective`] is the whole seam (seven collective operations, no MPI type); `thm-cli`
//! implements it over MPI, [`ThreadGroup`] over threads of one process (tests, and checking a
//! distributed set-up without MPI).

use std::ops::Range;
use std::sync::{Arc, Barrier, Mutex, PoisonError};
use std::time::Instant;

use thm_mpm::{MaterialInput, MaterialResponse};

use super::error::MultiscaleError;
use super::point::{PointOutcome, RvePoint, partition, rve_cost};

/// Numbers per point on the wire: the 7 of the response (stress, heat source,
/// conductivity), 5 diagnostics, the substeps and intact bonds (integers, exact as `f64`) and
/// the seconds the point's RVE took (its measured cost).
pub const WIRE_LEN: usize = 15;

/// What the distributed stage needs of a material: stepping a contiguous block of points,
/// the seconds each point's RVE took, and applying and checking the gathered outcomes
/// (`super::material::RveMaterial` implements it; the material hands each exchange to the
/// distribution, which steps this process's block through this seam).
pub trait BlockMaterial {
    /// Steps the points `first..first + states.len()` (`inputs` theirs) and writes each
    /// point's outcome; errors name the failing point by its material index.
    fn step_block(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        first: usize,
        outcomes: &mut [PointOutcome],
    ) -> Result<(), MultiscaleError>;
    /// Wall-clock seconds each point of the last block took, in order.
    fn step_seconds(&self) -> &[f64];
    /// Applies every point's outcome (all blocks gathered, in point order) to its history
    /// and response.
    fn finish(
        &self,
        states: &mut [RvePoint],
        outcomes: &[PointOutcome],
        responses: &mut [MaterialResponse],
    );
    /// The quasi-static check over all points (lowest failing point first).
    fn check_quasi_static(&self, states: &[RvePoint]) -> Result<(), MultiscaleError>;
}

/// The collective operations a distributed RVE stage needs. Every process calls each of them
/// at the same point of the run, in the same order (they are collectives, as in MPI).
pub trait Collective: Send + Sync + std::fmt::Debug {
    /// Number of processes.
    fn size(&self) -> usize;
    /// This process's index, `0..size`.
    fn rank(&self) -> usize;
    /// The lowest process on which `failed` is true, the same answer on every process.
    fn first_failed(&self, failed: bool) -> Option<usize>;
    /// Whether `flag` is true on any process.
    fn any(&self, flag: bool) -> bool;
    /// Replaces `bytes` on every process by those of process `root`.
    fn broadcast_bytes(&self, root: usize, bytes: &mut Vec<u8>);
    /// Every process's `send`, concatenated in process order, into `recv`; `counts[r]` is the
    /// length process `r` sends, known to all, and `recv.len()` their sum.
    fn all_gather_f64(&self, send: &[f64], counts: &[usize], recv: &mut [f64]);
    /// Every process's `send`, concatenated in process order, into `recv` (resized); returns
    /// the length each process sent.
    fn all_gather_bytes(&self, send: &[u8], recv: &mut Vec<u8>) -> Vec<usize>;
}

/// What a distributed RVE stage measured, for the run's summary.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DistributionStats {
    /// Exchanges (MPM steps) done.
    pub exchanges: u64,
    /// Seconds this process spent stepping its block's RVEs.
    pub compute_seconds: f64,
    /// Seconds this process spent in the failure reduction and the outcome gather (waiting for
    /// the slowest process included).
    pub comm_seconds: f64,
    /// Synchronisations done.
    pub syncs: u64,
    /// Seconds this process spent synchronising (encoding, gathering, decoding RVEs).
    pub sync_seconds: f64,
    /// Bytes of RVE state this process received in synchronisations.
    pub sync_bytes: u64,
    /// Largest over mean of the blocks' costs as assigned now (by the RVE seconds they were
    /// re-balanced by; by [`rve_cost`] before the first re-balancing).
    pub predicted_imbalance: f64,
    /// Largest over mean of the processes' block compute seconds between the last two
    /// synchronisations (1 when balanced; 0 before the first).
    pub measured_imbalance: f64,
}

/// A distributed RVE stage: the collective, the blocks and the scratch of the exchange.
#[derive(Debug)]
pub struct Distribution {
    collective: Arc<dyn Collective>,
    blocks: Vec<Range<usize>>,
    /// Per point: [`rve_cost`] until an exchange is measured, then the RVE seconds summed
    /// since the last re-balancing.
    costs: Vec<f64>,
    measured: bool,
    outcomes: Vec<PointOutcome>,
    send: Vec<f64>,
    recv: Vec<f64>,
    counts: Vec<usize>,
    bytes: Vec<u8>,
    gathered: Vec<u8>,
    compute_at_sync: f64,
    stats: DistributionStats,
}

/// A [`Distribution`] shared by the materials of one model (the column has one before and
/// one after its release) and by the driver that synchronises it.
pub type SharedDistribution = Arc<Mutex<Distribution>>;

/// Locks a shared distribution (a panic in another holder leaves nothing half-written that
/// the next exchange relies on: the blocks are re-derived when they do not fit).
pub fn lock(d: &SharedDistribution) -> std::sync::MutexGuard<'_, Distribution> {
    d.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Distribution {
    /// A distribution over `collective`'s processes.
    pub fn new(collective: Arc<dyn Collective>) -> Self {
        Self {
            collective,
            blocks: Vec::new(),
            costs: Vec::new(),
            measured: false,
            outcomes: Vec::new(),
            send: Vec::new(),
            recv: Vec::new(),
            counts: Vec::new(),
            bytes: Vec::new(),
            gathered: Vec::new(),
            compute_at_sync: 0.0,
            stats: DistributionStats::default(),
        }
    }

    /// The same, shared.
    pub fn shared(collective: Arc<dyn Collective>) -> SharedDistribution {
        Arc::new(Mutex::new(Self::new(collective)))
    }

    /// The collective.
    pub fn collective(&self) -> &Arc<dyn Collective> {
        &self.collective
    }

    /// The blocks of points, one per process (empty before the first exchange).
    pub fn blocks(&self) -> &[Range<usize>] {
        &self.blocks
    }

    /// What was measured so far.
    pub fn stats(&self) -> DistributionStats {
        self.stats
    }

    /// Blocks for `states` from their costs when the current ones do not cover them.
    fn ensure_blocks(&mut self, states: &[RvePoint]) {
        let n = states.len();
        if self.blocks.last().map(|b| b.end) != Some(n) || self.costs.len() != n {
            self.costs.clear();
            self.costs.extend(states.iter().map(rve_cost));
            self.measured = false;
            self.rebalance();
        }
    }

    /// Blocks that balance the current costs; the measured ones then start again from zero.
    fn rebalance(&mut self) {
        self.partition_costs();
        if self.measured {
            self.costs.fill(0.0);
            self.measured = false;
        }
    }

    fn partition_costs(&mut self) {
        let size = self.collective.size();
        self.blocks = partition(&self.costs, size);
        let total: f64 = self.costs.iter().sum();
        let largest = self
            .blocks
            .iter()
            .map(|b| self.costs[b.clone()].iter().sum::<f64>())
            .fold(0.0_f64, f64::max);
        self.stats.predicted_imbalance = if total > 0.0 {
            largest * size as f64 / total
        } else {
            1.0
        };
    }

    fn mine(&self) -> Range<usize> {
        self.blocks
            .get(self.collective.rank())
            .cloned()
            .unwrap_or(0..0)
    }

    /// One exchange of `material` (B-Algorithm 1, lines 12–19): this process's block stepped,
    /// failures agreed, the outcomes gathered and applied to every point, the quasi-static
    /// check. The same results on every process.
    pub fn exchange<M: BlockMaterial + ?Sized>(
        &mut self,
        material: &mut M,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), MultiscaleError> {
        let n = states.len();
        if inputs.len() != n || responses.len() != n {
            return Err(thm_mpm::MpmError::MaterialStateCount {
                states: n,
                points: inputs.len().min(responses.len()),
            }
            .into());
        }
        self.ensure_blocks(states);
        let mine = self.mine();
        self.outcomes.resize(n, PointOutcome::default());
        let t0 = Instant::now();
        let local = material.step_block(
            &mut states[mine.clone()],
            &inputs[mine.clone()],
            mine.start,
            &mut self.outcomes[mine.clone()],
        );
        let t1 = Instant::now();
        self.stats.compute_seconds += (t1 - t0).as_secs_f64();
        let step = self.stats.exchanges;
        self.stats.exchanges += 1;
        if let Some(failed) = self.collective.first_failed(local.is_err()) {
            let mut message = match &local {
                Err(e) if failed == self.collective.rank() => e.to_string().into_bytes(),
                _ => Vec::new(),
            };
            self.collective.broadcast_bytes(failed, &mut message);
            self.stats.comm_seconds += t1.elapsed().as_secs_f64();
            return Err(MultiscaleError::Distributed {
                process: failed,
                exchange: step,
                message: String::from_utf8_lossy(&message).into_owned(),
            });
        }
        self.send.clear();
        for (out, &seconds) in self.outcomes[mine.clone()]
            .iter()
            .zip(material.step_seconds())
        {
            encode(out, seconds, &mut self.send);
        }
        self.counts.clear();
        self.counts
            .extend(self.blocks.iter().map(|b| b.len() * WIRE_LEN));
        self.recv.resize(n * WIRE_LEN, 0.0);
        self.collective
            .all_gather_f64(&self.send, &self.counts, &mut self.recv);
        self.stats.comm_seconds += t1.elapsed().as_secs_f64();
        if !self.measured {
            self.costs.fill(0.0);
            self.measured = true;
        }
        for ((w, out), c) in self
            .recv
            .chunks_exact(WIRE_LEN)
            .zip(self.outcomes.iter_mut())
            .zip(self.costs.iter_mut())
        {
            let seconds;
            (*out, seconds) = decode(w);
            *c += seconds;
        }
        material.finish(states, &self.outcomes, responses);
        material.check_quasi_static(states)
    }

    /// Brings every process's copy of every RVE up to date (each process sends the RVEs of
    /// its block, `bincode`-encoded, and takes the others'), measures the imbalance since the
    /// last synchronisation and re-balances the blocks by the RVE seconds measured since the
    /// last re-balancing. Every
    /// process must call it at the same point. Before the first exchange there is nothing to
    /// bring (every process holds the same start).
    pub fn synchronise(&mut self, states: &mut [RvePoint]) -> Result<(), MultiscaleError> {
        if self.blocks.is_empty() {
            return Ok(());
        }
        let t0 = Instant::now();
        let n = states.len();
        if self.blocks.last().map(|b| b.end) != Some(n) {
            return Err(MultiscaleError::DistributedState {
                detail: format!(
                    "{n} points to synchronise, the blocks cover {}",
                    self.blocks.last().map_or(0, |b| b.end)
                ),
            });
        }
        let mine = self.mine();
        self.bytes.clear();
        bincode::serde::encode_into_std_write(
            &states[mine.clone()],
            &mut self.bytes,
            bincode::config::standard(),
        )
        .map_err(|e| MultiscaleError::DistributedState {
            detail: format!("encoding the RVEs of points {mine:?}: {e}"),
        })?;
        let lengths = self
            .collective
            .all_gather_bytes(&self.bytes, &mut self.gathered);
        let me = self.collective.rank();
        let mut offset = 0;
        for (r, (block, len)) in self.blocks.iter().zip(&lengths).enumerate() {
            let part = &self.gathered[offset..offset + len];
            offset += len;
            if r == me {
                continue;
            }
            let (points, _): (Vec<RvePoint>, usize) =
                bincode::serde::decode_from_slice(part, bincode::config::standard()).map_err(
                    |e| MultiscaleError::DistributedState {
                        detail: format!("decoding the RVEs of process {r}: {e}"),
                    },
                )?;
            if points.len() != block.len() {
                return Err(MultiscaleError::DistributedState {
                    detail: format!(
                        "process {r} sent {} RVEs for points {block:?}",
                        points.len()
                    ),
                });
            }
            self.stats.sync_bytes += *len as u64;
            for (s, p) in states[block.clone()].iter_mut().zip(points) {
                *s = p;
            }
        }
        // Measured imbalance: every process's block seconds since the last synchronisation.
        let since = [self.stats.compute_seconds - self.compute_at_sync];
        self.compute_at_sync = self.stats.compute_seconds;
        let size = self.collective.size();
        let mut all = vec![0.0; size];
        self.collective
            .all_gather_f64(&since, &vec![1; size], &mut all);
        let mean = all.iter().sum::<f64>() / size as f64;
        let largest = all.iter().copied().fold(0.0_f64, f64::max);
        self.stats.measured_imbalance = if mean > 0.0 { largest / mean } else { 1.0 };
        self.rebalance();
        self.stats.syncs += 1;
        self.stats.sync_seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }
}

fn encode(out: &PointOutcome, cost: f64, wire: &mut Vec<f64>) {
    let r = &out.response;
    wire.extend_from_slice(&r.stress);
    wire.push(r.heat_source);
    wire.extend_from_slice(&r.conductivity);
    wire.extend_from_slice(&[
        out.wave_modulus,
        out.friction_work,
        out.rve_volume,
        out.inertial_number,
        out.kinetic_ratio,
        f64::from(out.substeps),
        f64::from(out.intact_bonds),
        cost,
    ]);
}

fn decode(w: &[f64]) -> (PointOutcome, f64) {
    let out = PointOutcome {
        response: MaterialResponse {
            stress: [w[0], w[1], w[2]],
            heat_source: w[3],
            conductivity: [w[4], w[5], w[6]],
        },
        wave_modulus: w[7],
        friction_work: w[8],
        rve_volume: w[9],
        inertial_number: w[10],
        kinetic_ratio: w[11],
        // Integers below 2^32 travel exactly as f64.
        substeps: w[12] as u32,
        intact_bonds: w[13] as u32,
    };
    (out, w[14])
}

/// The processes of a distributed run as threads of one process: each thread holds one
/// `ThreadGroup` handle (from [`ThreadGroup::new`]) and the collectives meet at a barrier.
/// For tests and for checking a distributed set-up without MPI; every handle must be driven
/// by its own thread.
#[derive(Debug, Clone)]
pub struct ThreadGroup {
    rank: usize,
    shared: Arc<GroupShared>,
}

#[derive(Debug)]
struct GroupShared {
    barrier: Barrier,
    slots: Mutex<Vec<Vec<u8>>>,
}

impl ThreadGroup {
    /// `size` handles, one per process (thread), ranks `0..size`.
    pub fn new(size: usize) -> Vec<Self> {
        let size = size.max(1);
        let shared = Arc::new(GroupShared {
            barrier: Barrier::new(size),
            slots: Mutex::new(vec![Vec::new(); size]),
        });
        (0..size)
            .map(|rank| Self {
                rank,
                shared: Arc::clone(&shared),
            })
            .collect()
    }

    fn slots(&self) -> std::sync::MutexGuard<'_, Vec<Vec<u8>>> {
        self.shared
            .slots
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// Every process's bytes, in process order: write own slot, meet, read all, meet again
    /// (so that no slot is overwritten before everyone has read it).
    fn exchange(&self, mine: &[u8]) -> Vec<Vec<u8>> {
        {
            let mut slots = self.slots();
            slots[self.rank].clear();
            slots[self.rank].extend_from_slice(mine);
        }
        self.shared.barrier.wait();
        let all = self.slots().clone();
        self.shared.barrier.wait();
        all
    }
}

impl Collective for ThreadGroup {
    fn size(&self) -> usize {
        self.slots().len()
    }

    fn rank(&self) -> usize {
        self.rank
    }

    fn first_failed(&self, failed: bool) -> Option<usize> {
        self.exchange(&[u8::from(failed)])
            .iter()
            .position(|b| b.first() == Some(&1))
    }

    fn any(&self, flag: bool) -> bool {
        self.first_failed(flag).is_some()
    }

    fn broadcast_bytes(&self, root: usize, bytes: &mut Vec<u8>) {
        let all = self.exchange(if self.rank == root { bytes } else { &[] });
        if let Some(b) = all.get(root) {
            bytes.clone_from(b);
        }
    }

    fn all_gather_f64(&self, send: &[f64], counts: &[usize], recv: &mut [f64]) {
        let mine: Vec<u8> = send.iter().flat_map(|v| v.to_le_bytes()).collect();
        let all = self.exchange(&mine);
        let values = all.iter().zip(counts).flat_map(|(b, &c)| {
            b.chunks_exact(8)
                .take(c)
                .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
        });
        for (r, v) in recv.iter_mut().zip(values) {
            *r = v;
        }
    }

    fn all_gather_bytes(&self, send: &[u8], recv: &mut Vec<u8>) -> Vec<usize> {
        let all = self.exchange(send);
        recv.clear();
        for b in &all {
            recv.extend_from_slice(b);
        }
        all.iter().map(Vec::len).collect()
    }
}
