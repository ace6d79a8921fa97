//! Many RVEs stepped in parallel, one per material point.
//!
//! Each RVE is advanced serially by its own stepper (its own scratch buffers) and RVEs are
//! distributed over the rayon pool; nothing is reduced across RVEs, so the results are the
//! same bits for any number of threads. States are the caller's (a slice, contiguous per
//! RVE: each RVE's arrays stay together in memory while one worker steps it).

use crate::error::RveError;
use crate::params::RveConfig;
use crate::state::RveState;
use crate::stepper::{RveLoad, RveResponse, RveStepper};
use rayon::prelude::*;

/// Scratch for a batch of RVEs: one stepper per RVE.
#[derive(Debug, Clone)]
pub struct RveBatch {
    steppers: Vec<RveStepper>,
}

impl RveBatch {
    /// A batch of `count` RVEs sharing one configuration.
    pub fn new(config: RveConfig, count: usize) -> Self {
        Self {
            steppers: vec![RveStepper::new(config); count],
        }
    }

    /// Number of RVEs.
    pub fn len(&self) -> usize {
        self.steppers.len()
    }

    /// True when the batch is empty.
    pub fn is_empty(&self) -> bool {
        self.steppers.is_empty()
    }

    /// One macroscopic step of every RVE under its own load, in the current rayon pool.
    /// Returns the responses in RVE order, or the error of the lowest-numbered failing RVE.
    pub fn respond(
        &mut self,
        states: &mut [RveState],
        loads: &[RveLoad],
    ) -> Result<Vec<RveResponse>, RveError> {
        let n = self.steppers.len();
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
        let results: Vec<Result<RveResponse, RveError>> = self
            .steppers
            .par_iter_mut()
            .zip(states.par_iter_mut())
            .zip(loads.par_iter())
            .with_min_len(1)
            .map(|((stepper, state), load)| stepper.respond(state, load))
            .collect();
        results.into_iter().collect()
    }
}
