//! Many RVEs stepped in parallel, one per material point.
//!
//! Each RVE is advanced serially by a stepper (scratch buffers only, one per chunk of
//! consecutive RVEs) and the chunks are distributed over the rayon pool; nothing is reduced across RVEs, so the results are the
//! same bits for any number of threads. States are the caller's (a slice, contiguous per
//! RVE: each RVE's arrays stay together in memory while one worker steps it).

use crate::error::RveError;
use crate::params::RveConfig;
use crate::state::RveState;
use crate::stepper::{RveLoad, RveResponse, RveStepper};
use rayon::prelude::*;

/// RVEs share scratch steppers in chunks: at most this many steppers per batch (enough to
/// balance the load over the threads of a workstation, few enough that scratch memory stays
/// small against the states).
const MAX_STEPPERS: usize = 64;

/// Scratch for a batch of RVEs: one stepper per chunk of consecutive RVEs. A stepper holds
/// only scratch buffers, so which stepper advances an RVE changes no bit of its result.
#[derive(Debug, Clone)]
pub struct RveBatch {
    steppers: Vec<RveStepper>,
    count: usize,
    seconds: Vec<f64>,
}

impl RveBatch {
    /// A batch of `count` RVEs sharing one configuration.
    pub fn new(config: RveConfig, count: usize) -> Self {
        Self {
            steppers: vec![RveStepper::new(config); count.clamp(1, MAX_STEPPERS)],
            count,
            seconds: vec![0.0; count],
        }
    }

    /// Number of RVEs.
    pub fn len(&self) -> usize {
        self.count
    }

    /// True when the batch is empty.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Wall-clock seconds each RVE took in the last [`RveBatch::respond_into`] (a measured
    /// cost, e.g. for balancing RVEs over processes; it varies from run to run and no result
    /// depends on it). Zero for an RVE that was not stepped.
    pub fn step_seconds(&self) -> &[f64] {
        &self.seconds
    }

    /// Heap memory of the scratch steppers \[bytes\].
    pub fn heap_bytes(&self) -> usize {
        self.steppers.iter().map(RveStepper::heap_bytes).sum()
    }

    /// One macroscopic step of every RVE under its own load, in the current rayon pool.
    /// Returns the responses in RVE order, or the error of the lowest-numbered failing RVE.
    pub fn respond(
        &mut self,
        states: &mut [RveState],
        loads: &[RveLoad],
    ) -> Result<Vec<RveResponse>, RveError> {
        let mut responses = vec![RveResponse::default(); self.count];
        self.respond_into(states, loads, &mut responses)
            .map_err(|(_, e)| e)?;
        Ok(responses)
    }

    /// [`RveBatch::respond`] into the caller's `responses` (one per RVE; no allocation), with
    /// the index of the lowest-numbered failing RVE beside its error. The states may be any
    /// per-RVE records that hold an [`RveState`] (e.g. a material point's RVE with its
    /// diagnostics). Every RVE of a chunk is
    /// stepped even after one of the chunk failed.
    pub fn respond_into<S: AsMut<RveState> + Send>(
        &mut self,
        states: &mut [S],
        loads: &[RveLoad],
        responses: &mut [RveResponse],
    ) -> Result<(), (usize, RveError)> {
        let n = self.count;
        if responses.len() != n {
            return Err((
                0,
                RveError::LengthMismatch {
                    field: "responses",
                    len: responses.len(),
                    expected: n,
                },
            ));
        }
        if states.len() != n {
            return Err((
                0,
                RveError::LengthMismatch {
                    field: "states",
                    len: states.len(),
                    expected: n,
                },
            ));
        }
        if loads.len() != n {
            return Err((
                0,
                RveError::LengthMismatch {
                    field: "loads",
                    len: loads.len(),
                    expected: n,
                },
            ));
        }
        if n == 0 {
            return Ok(());
        }
        let chunk = n.div_ceil(self.steppers.len());
        self.seconds.clear();
        self.seconds.resize(n, 0.0);
        let first_error = self
            .steppers
            .par_iter_mut()
            .zip(
                states
                    .par_chunks_mut(chunk)
                    .zip(loads.par_chunks(chunk))
                    .zip(responses.par_chunks_mut(chunk))
                    .zip(self.seconds.par_chunks_mut(chunk)),
            )
            .with_min_len(1)
            .enumerate()
            .filter_map(|(c, (stepper, (((states, loads), responses), seconds)))| {
                let mut first = None;
                for (j, (((state, load), response), seconds)) in states
                    .iter_mut()
                    .zip(loads)
                    .zip(responses)
                    .zip(seconds)
                    .enumerate()
                {
                    let start = std::time::Instant::now();
                    match stepper.respond(state.as_mut(), load) {
                        Ok(r) => *response = r,
                        Err(e) => {
                            first.get_or_insert((c * chunk + j, e));
                        }
                    }
                    *seconds = start.elapsed().as_secs_f64();
                }
                first
            })
            .min_by_key(|(i, _)| *i);
        match first_error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}
