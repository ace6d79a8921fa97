//! MPI under `thm run` (feature `mpi`): [`MpiCollective`], the
//! [`thm_coupling::multiscale::Collective`] of `MPI_COMM_WORLD`, and [`init`], which starts MPI
//! once for the process. Everything above the wire (blocks, balance, synchronisation, failure
//! agreement) is `thm_coupling::multiscale::distributed`; this module only moves bytes.
//!
//! MPI calls are made from the thread that called [`init`] only (the driver's); the rayon
//! threads that step a rank's RVEs make none, so MPI's default (single-threaded) level is
//! enough.

use std::sync::Arc;

use mpi::collective::SystemOperation;
use mpi::datatype::PartitionMut;
use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use thm_coupling::multiscale::Collective;

/// The processes of `MPI_COMM_WORLD`. Holds no MPI handle (rsmpi's are neither `Send` nor
/// `Sync`, which the RVE material needs): the world communicator is fetched per call.
#[derive(Debug, Clone, Copy)]
pub struct MpiCollective {
    size: usize,
    rank: usize,
}

/// Starts MPI (once per process) and returns the universe (MPI ends when it is dropped) and,
/// when the world has more than one process, its collective.
pub fn init() -> Option<(Universe, Option<Arc<dyn Collective>>)> {
    let universe = mpi::initialize()?;
    let world = universe.world();
    let size = usize::try_from(world.size()).unwrap_or(1);
    let rank = usize::try_from(world.rank()).unwrap_or(0);
    let collective: Option<Arc<dyn Collective>> =
        (size > 1).then(|| Arc::new(MpiCollective { size, rank }) as Arc<dyn Collective>);
    Some((universe, collective))
}

fn to_i32(n: usize) -> i32 {
    i32::try_from(n).unwrap_or(i32::MAX)
}

/// Displacements of consecutive blocks of `counts`.
fn displacements(counts: &[i32]) -> Vec<i32> {
    counts
        .iter()
        .scan(0i32, |at, &c| {
            let d = *at;
            *at = at.saturating_add(c);
            Some(d)
        })
        .collect()
}

impl Collective for MpiCollective {
    fn size(&self) -> usize {
        self.size
    }

    fn rank(&self) -> usize {
        self.rank
    }

    fn first_failed(&self, failed: bool) -> Option<usize> {
        let world = SimpleCommunicator::world();
        let flag = if failed {
            to_i32(self.rank)
        } else {
            to_i32(self.size)
        };
        let mut first = 0i32;
        world.all_reduce_into(&flag, &mut first, SystemOperation::min());
        usize::try_from(first).ok().filter(|&r| r < self.size)
    }

    fn any(&self, flag: bool) -> bool {
        let world = SimpleCommunicator::world();
        let mut any = 0i32;
        world.all_reduce_into(&i32::from(flag), &mut any, SystemOperation::max());
        any > 0
    }

    fn broadcast_bytes(&self, root: usize, bytes: &mut Vec<u8>) {
        let world = SimpleCommunicator::world();
        let root = world.process_at_rank(to_i32(root));
        let mut len = bytes.len() as u64;
        root.broadcast_into(&mut len);
        bytes.resize(usize::try_from(len).unwrap_or(0), 0);
        root.broadcast_into(&mut bytes[..]);
    }

    fn all_gather_f64(&self, send: &[f64], counts: &[usize], recv: &mut [f64]) {
        let world = SimpleCommunicator::world();
        let counts: Vec<i32> = counts.iter().map(|&c| to_i32(c)).collect();
        let displs = displacements(&counts);
        let mut part = PartitionMut::new(recv, counts, displs);
        world.all_gather_varcount_into(send, &mut part);
    }

    fn all_gather_bytes(&self, send: &[u8], recv: &mut Vec<u8>) -> Vec<usize> {
        let world = SimpleCommunicator::world();
        let mut counts = vec![0i32; self.size];
        world.all_gather_into(&to_i32(send.len()), &mut counts[..]);
        let total: usize = counts
            .iter()
            .map(|&c| usize::try_from(c).unwrap_or(0))
            .sum();
        recv.resize(total, 0);
        let displs = displacements(&counts);
        let lengths = counts
            .iter()
            .map(|&c| usize::try_from(c).unwrap_or(0))
            .collect();
        let mut part = PartitionMut::new(&mut recv[..], counts, displs);
        world.all_gather_varcount_into(send, &mut part);
        lengths
    }
}
