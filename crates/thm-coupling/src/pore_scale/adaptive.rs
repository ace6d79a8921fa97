//! The adaptive coupled step for a moving skeleton.
//!
//! The coupled step holds the fluid forces over Δt_C (choice 1 of the crate docs). While the
//! bonds hold, the spheres barely move and Δt_C can be long; when a bond breaks, a sphere it
//! released keeps the whole fluid force of the step's start (a few newtons on a sphere
//! against a side wall of the bar) with nothing to balance it, and a long step throws it
//! across its pores before the flow can answer with a pressure change. The rule here bounds
//! the motion instead of the step: a coupled step is accepted when no sphere moved more than
//! `max_displacement` (a fraction of the smallest radius) and is otherwise taken again from
//! the saved state at half the length; after each accepted step the next is `growth` times
//! longer, up to `max_step`. Rejected steps leave no trace: the state is restored and the
//! stepper rebuilt from it, as after a checkpoint.

use serde::{Deserialize, Serialize};
use thm_vpn_flow::PoreFluid;

use super::error::CouplingError;
use super::{PoreScaleState, PoreScaleStepper};

/// The adaptive coupled step, as read from a file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingStepParams {
    /// Longest coupled step \[s\] (> 0).
    pub max_step: f64,
    /// Shortest coupled step \[s\] (> 0, ≤ `max_step`): a step this short that still moves a
    /// sphere too far is an error.
    pub min_step: f64,
    /// Largest sphere displacement in one coupled step, as a fraction of the smallest sphere
    /// radius (> 0, ≤ 1).
    pub max_displacement: f64,
    /// Factor on the step after an accepted one (≥ 1, ≤ 10).
    pub growth: f64,
}

/// A validated [`CouplingStepParams`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CouplingStepRule {
    params: CouplingStepParams,
}

impl CouplingStepParams {
    /// Checks every field; the error names it and its range.
    pub fn validate(&self) -> Result<CouplingStepRule, CouplingError> {
        let checks: [(&'static str, f64, &'static str, bool); 4] = [
            ("max_step", self.max_step, "> 0 s", self.max_step > 0.0),
            (
                "min_step",
                self.min_step,
                "> 0 s and <= max_step",
                self.min_step > 0.0 && self.min_step <= self.max_step,
            ),
            (
                "max_displacement",
                self.max_displacement,
                "> 0 and <= 1 (fraction of the smallest radius)",
                self.max_displacement > 0.0 && self.max_displacement <= 1.0,
            ),
            (
                "growth",
                self.growth,
                ">= 1 and <= 10",
                (1.0..=10.0).contains(&self.growth),
            ),
        ];
        for (field, value, range, ok) in checks {
            if !(ok && value.is_finite()) {
                return Err(CouplingError::Parameter {
                    field,
                    range,
                    value,
                });
            }
        }
        Ok(CouplingStepRule { params: *self })
    }
}

impl CouplingStepRule {
    /// The parameters.
    pub fn params(&self) -> &CouplingStepParams {
        &self.params
    }
}

/// What [`PoreScaleStepper::advance`] did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AdvanceReport {
    /// Accepted coupled steps.
    pub steps: u64,
    /// Steps taken again shorter.
    pub rejected: u64,
    /// Shortest accepted step \[s\].
    pub shortest: f64,
    /// Largest sphere displacement of an accepted step \[m\].
    pub largest_displacement: f64,
    /// Energy that entered through the outer boundary over the accepted steps \[J\].
    pub boundary_energy: f64,
    /// Remeshes in the accepted steps.
    pub remeshes: u64,
    /// Wall seconds of each stage over every step tried (accepted, and rejected for moving a
    /// sphere too far; a step that failed in a stage is not counted).
    pub stage_seconds: super::StageSeconds,
    /// Wall seconds of saving the state before each step and restoring it after a rejection.
    pub retake_seconds: f64,
}

/// The sphere that moved furthest between `before` and `after`, and how far \[m\].
pub fn largest_displacement(before: &PoreScaleState, after: &PoreScaleState) -> (usize, f64) {
    before
        .dem
        .particles
        .position
        .iter()
        .zip(&after.dem.particles.position)
        .map(|(a, b)| ((b.x - a.x).powi(2) + (b.y - a.y).powi(2) + (b.z - a.z).powi(2)).sqrt())
        .enumerate()
        .fold(
            (0, 0.0),
            |best, (i, d)| if d > best.1 { (i, d) } else { best },
        )
}

impl<F: PoreFluid> PoreScaleStepper<F> {
    /// Advances `state` by `dt` \[s\] in coupled steps chosen by `rule`; the last step ends
    /// exactly at the end of `dt`. The coupled step holds the fluid forces over its length, so
    /// a sphere that a breaking bond releases keeps the whole fluid force of the step's start
    /// with nothing to balance it: a step is accepted when no sphere moved more than
    /// [`CouplingStepParams::max_displacement`] times the smallest radius, and is otherwise
    /// taken again from the saved state at half the length (the stepper rebuilt from it, as
    /// after a checkpoint); after each accepted step the next is
    /// [`CouplingStepParams::growth`] times longer, up to [`CouplingStepParams::max_step`]. A step that fails (an error of any stage) is
    /// also taken again shorter; at `min_step` its error is returned, with the state restored
    /// to the start of that step.
    pub fn advance(
        &mut self,
        state: &mut PoreScaleState,
        dt: f64,
        rule: &CouplingStepRule,
    ) -> Result<AdvanceReport, CouplingError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(CouplingError::Parameter {
                field: "dt",
                range: "> 0 s",
                value: dt,
            });
        }
        let p = rule.params;
        let limit = p.max_displacement
            * state
                .dem
                .particles
                .radius
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min);
        let mut report = AdvanceReport {
            shortest: f64::INFINITY,
            ..AdvanceReport::default()
        };
        let mut left = dt;
        while left > 0.0 {
            let tried = if state.coupling_step > 0.0 {
                state.coupling_step.clamp(p.min_step, p.max_step)
            } else {
                p.max_step
            };
            // The last step takes what is left (within round-off of the tried length).
            let last = tried >= left * (1.0 - 1e-9);
            let h = if last { left } else { tried };
            let clock = std::time::Instant::now();
            let saved = state.clone();
            report.retake_seconds += clock.elapsed().as_secs_f64();
            let outcome = self.step(state, h);
            if let Ok(r) = &outcome {
                report.stage_seconds.accumulate(&r.stage_seconds);
            }
            let moved = largest_displacement(&saved, state);
            match outcome {
                Ok(r) if moved.1 <= limit => {
                    left = if last { 0.0 } else { left - h };
                    report.steps += 1;
                    report.shortest = report.shortest.min(h);
                    report.largest_displacement = report.largest_displacement.max(moved.1);
                    report.boundary_energy += r.boundary_energy;
                    report.remeshes += u64::from(r.remeshed.is_some());
                    state.coupling_step = (tried * p.growth).min(p.max_step);
                }
                outcome => {
                    let clock = std::time::Instant::now();
                    *state = saved;
                    self.rebuild(state)?;
                    report.retake_seconds += clock.elapsed().as_secs_f64();
                    if h <= p.min_step {
                        outcome?;
                        return Err(CouplingError::CouplingStepTooSmall {
                            sphere: moved.0,
                            displacement: moved.1,
                            limit,
                            step_length: h,
                            min_step: p.min_step,
                            time: state.time,
                        });
                    }
                    report.rejected += 1;
                    state.coupling_step = (0.5 * h).max(p.min_step);
                }
            }
        }
        Ok(report)
    }
}
