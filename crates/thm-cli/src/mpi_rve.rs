//! The RVE stage over MPI ranks (feature `mpi`): every rank runs the same MPM step and owns
//! one contiguous block of material points ([`thm_coupling::multiscale::partition`] by
//! [`thm_coupling::multiscale::rve_cost`]); it steps only its block's RVEs
//! ([`RveMaterial::step_block`]) and all-gathers the fixed-size outcomes in point order, so
//! every rank continues with the same bits as a run without MPI. A rank whose block fails
//! sets an error flag that is all-reduced (max) before the gather; every rank then returns the
//! error of the lowest failing point (the owning rank's message, the others a
//! [`MpiRveError::OtherRank`]).
//!
//! The RVEs of points a rank does not own are not advanced there (only their diagnostics
//! are), so the assignment is fixed for the run (made from the states every rank starts
//! with); a checkpoint would have to gather the owners' RVEs first, which this module does
//! not do yet.

use mpi::collective::SystemOperation;
use mpi::datatype::PartitionMut;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use std::ops::Range;
use thm_coupling::multiscale::{
    MultiscaleError, PointOutcome, RveMaterial, RvePoint, partition, rve_cost,
};
use thm_mpm::{BatchConstitutive, MaterialInput, MaterialResponse};

/// Numbers per point on the wire: the 7 of the response, 6 diagnostics (substeps exact as
/// f64) and the cost.
pub const WIRE_LEN: usize = 14;

/// Errors of the distributed RVE stage.
#[derive(Debug, thiserror::Error)]
pub enum MpiRveError {
    /// This rank's block failed.
    #[error("rank {rank}: {source}")]
    Local {
        /// This rank.
        rank: i32,
        /// The RVE stage's error.
        source: MultiscaleError,
    },
    /// Another rank's block failed (that rank reports the cause).
    #[error("rank {rank} failed at MPM step {step}; see its message")]
    OtherRank {
        /// The lowest failing rank.
        rank: i32,
        /// The MPM step (0-based count of exchanges on this rank).
        step: u64,
    },
    /// The MPM seam's own error.
    #[error(transparent)]
    Mpm(#[from] thm_mpm::MpmError),
    /// A material error outside the blocks (the quasi-static check, on every rank alike).
    #[error(transparent)]
    Material(#[from] MultiscaleError),
}

/// [`RveMaterial`] with its RVE stage spread over the ranks of `MPI_COMM_WORLD` (MPI must be
/// initialised). The communicator is fetched per exchange rather than held: rsmpi's handles
/// are neither `Send` nor `Sync`, which `BatchConstitutive` requires.
#[derive(Debug)]
pub struct MpiRveMaterial {
    material: RveMaterial,
    blocks: Vec<Range<usize>>,
    outcomes: Vec<PointOutcome>,
    send: Vec<f64>,
    recv: Vec<f64>,
    costs: Vec<f64>,
    exchanges: u64,
    /// Seconds spent in this rank's RVE block, summed over the run.
    pub compute_seconds: f64,
    /// Seconds spent in the error all-reduce and the gather, summed over the run.
    pub comm_seconds: f64,
}

impl MpiRveMaterial {
    /// Wraps `material` for the ranks of the world communicator.
    pub fn new(material: RveMaterial) -> Self {
        Self {
            material,
            blocks: Vec::new(),
            outcomes: Vec::new(),
            send: Vec::new(),
            recv: Vec::new(),
            costs: Vec::new(),
            exchanges: 0,
            compute_seconds: 0.0,
            comm_seconds: 0.0,
        }
    }

    /// The blocks of points, one per rank (empty before the first exchange).
    pub fn blocks(&self) -> &[Range<usize>] {
        &self.blocks
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
            substeps: w[12] as u32,
        };
        (out, w[13])
    }

    fn exchange(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), MpiRveError> {
        let world = SimpleCommunicator::world();
        let n = states.len();
        let size = world.size() as usize;
        let rank = world.rank();
        if self.blocks.is_empty() || self.blocks.last().map(|b| b.end) != Some(n) {
            if self.costs.len() != n {
                self.costs = states.iter().map(rve_cost).collect();
            }
            self.blocks = partition(&self.costs, size);
        }
        let mine = self.blocks[rank as usize].clone();
        self.outcomes.resize(n, PointOutcome::default());
        let t0 = std::time::Instant::now();
        let local = self.material.step_block(
            &mut states[mine.clone()],
            &inputs[mine.clone()],
            mine.start,
            &mut self.outcomes[mine.clone()],
        );
        let t1 = std::time::Instant::now();
        self.compute_seconds += (t1 - t0).as_secs_f64();
        // Lowest failing rank, or `size` when none failed.
        let flag = if local.is_err() { rank } else { size as i32 };
        let mut first_failed = size as i32;
        world.all_reduce_into(&flag, &mut first_failed, SystemOperation::min());
        if first_failed < size as i32 {
            self.comm_seconds += t1.elapsed().as_secs_f64();
            self.exchanges += 1;
            return Err(match local {
                Err(source) => MpiRveError::Local { rank, source },
                Ok(()) => MpiRveError::OtherRank {
                    rank: first_failed,
                    step: self.exchanges - 1,
                },
            });
        }
        self.send.clear();
        for (out, s) in self.outcomes[mine.clone()]
            .iter()
            .zip(&states[mine.clone()])
        {
            Self::encode(out, rve_cost(s), &mut self.send);
        }
        let counts: Vec<i32> = self
            .blocks
            .iter()
            .map(|b| (b.len() * WIRE_LEN) as i32)
            .collect();
        let displs: Vec<i32> = self
            .blocks
            .iter()
            .map(|b| (b.start * WIRE_LEN) as i32)
            .collect();
        self.recv.resize(n * WIRE_LEN, 0.0);
        {
            let mut part = PartitionMut::new(&mut self.recv[..], counts, displs);
            world.all_gather_varcount_into(&self.send[..], &mut part);
        }
        self.comm_seconds += t1.elapsed().as_secs_f64();
        self.costs.resize(n, 0.0);
        for ((w, out), c) in self
            .recv
            .chunks_exact(WIRE_LEN)
            .zip(self.outcomes.iter_mut())
            .zip(self.costs.iter_mut())
        {
            let (o, cost) = Self::decode(w);
            *out = o;
            *c = cost;
        }
        self.material.finish(states, &self.outcomes, responses);
        self.exchanges += 1;
        Ok(self.material.check_quasi_static(states)?)
    }
}

impl BatchConstitutive for MpiRveMaterial {
    type PointState = RvePoint;
    type Error = MpiRveError;

    fn respond_batch(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), MpiRveError> {
        self.exchange(states, inputs, responses)
    }

    fn wave_modulus(&self, state: &RvePoint) -> f64 {
        state.wave_modulus
    }
}
