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
}

impl RveBatch {
    /// A batch of `count` RVEs sharing one configuration.
    pub fn new(config: RveConfig, count: usize) -> Self {
        Self {
            steppers: vec![RveStepper::new(config); count.clamp(1, MAX_STEPPERS)],
            count,
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
        let n = self.count;
        if states.len() != n {
            return Err(RveError::LengthMismatch {
                field: "states",
                len: states.len(),
                expected: n,
            });
        }
        if loads.len() != n {
            return Err(RveError::LengthMismatch {
                field: "loads",
                len: loads.len(),
                expected: n,
            });
        }
        let mut responses = vec![RveResponse::default(); n];
        if n == 0 {
            return Ok(responses);
        }
        let chunk = n.div_ceil(self.steppers.len());
        let errors: Vec<Option<RveError>> = self
            .steppers
            .par_iter_mut()
            .zip(
                states
                    .par_chunks_mut(chunk)
                    .zip(loads.par_chunks(chunk))
                    .zip(responses.par_chunks_mut(chunk)),
            )
            .with_min_len(1)
            .map(|(stepper, ((states, loads), responses))| {
                let mut first = None;
                for ((state, load), response) in states.iter_mut().zip(loads).zip(responses) {
                    match stepper.respond(state, load) {
                        Ok(r) => *response = r,
                        Err(e) => {
                            first.get_or_insert(e);
                        }
                    }
                }
                first
            })
            .collect();
        match errors.into_iter().flatten().next() {
            Some(e) => Err(e),
            None => Ok(responses),
        }
    }
}
