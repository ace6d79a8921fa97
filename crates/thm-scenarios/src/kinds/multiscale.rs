//! The skeleton the MPM×DEM kinds share.
//!
//! The biaxial test, the column collapse and the silo discharge run on
//! `thm_coupling::multiscale::MultiscaleModel` (their loading protocols and recorders live
//! there); as kinds they are one [`Multiscale`] each, which does for all three what a
//! multiscale run needs alike — swapping the checkpoint state into the model for a step,
//! restoring it, spreading the RVE stage over processes, the state arrays, a sample of the
//! history every [`SAMPLE_EVERY`] steps — around a [`MultiscaleKind`]: its parameters and how
//! they build the model, what it samples, monitors, writes as frames and profiles, and sums
//! up. The checkpoint state is the kind's own struct ([`KindState`]), so each kind keeps the
//! field names its checkpoints have always had.

use serde::Serialize;
use serde::de::DeserializeOwned;
use thm_coupling::multiscale::distributed::SharedDistribution;
use thm_coupling::multiscale::{MultiscaleModel, Protocol, RveMaterial, RvePoint};
use thm_io::{Column, IoError};
use thm_mpm::MpmState;

use crate::arrays::{StateArray, mpm_rve_arrays, set_points_array};
use crate::config::TimeControl;
use crate::error::{ConfigError, RunError, physics_error};
use crate::profiles::Profile;
use crate::scenario::{FrameSink, Scenario};
use crate::summary::SummaryRow;

/// Steps between the samples of a kind's history (its profiles).
pub const SAMPLE_EVERY: u64 = 10;

/// The checkpoint state of a multiscale kind: the points with their RVEs, the protocol's
/// running sums and the kind's samples.
pub trait KindState<C: Protocol>: Serialize + DeserializeOwned {
    /// One sample of the kind's history.
    type Sample;
    /// A state of its parts.
    fn from_parts(mpm: MpmState<RvePoint>, totals: C::Totals, samples: Vec<Self::Sample>) -> Self;
    /// The points with their RVEs.
    fn mpm(&self) -> &MpmState<RvePoint>;
    /// The running sums.
    fn totals(&self) -> &C::Totals;
    /// The samples.
    fn samples(&self) -> &[Self::Sample];
    /// The parts, to change.
    fn parts_mut(
        &mut self,
    ) -> (
        &mut MpmState<RvePoint>,
        &mut C::Totals,
        &mut Vec<Self::Sample>,
    );
}

/// Declares the checkpoint state of a multiscale kind: `mpm`, `totals` and the kind's samples
/// under the field name `$samples` its checkpoints carry.
macro_rules! kind_state {
    ($(#[$meta:meta])* $name:ident for $case:ty {
        $(#[$samples_doc:meta])* $samples:ident: Vec<$sample:ty>
    }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            /// Points with their RVEs.
            pub mpm: thm_mpm::MpmState<thm_coupling::multiscale::RvePoint>,
            /// The protocol's running sums.
            pub totals: <$case as thm_coupling::multiscale::Protocol>::Totals,
            $(#[$samples_doc])*
            pub $samples: Vec<$sample>,
        }

        impl $crate::kinds::multiscale::KindState<$case> for $name {
            type Sample = $sample;
            fn from_parts(
                mpm: thm_mpm::MpmState<thm_coupling::multiscale::RvePoint>,
                totals: <$case as thm_coupling::multiscale::Protocol>::Totals,
                $samples: Vec<$sample>,
            ) -> Self {
                Self { mpm, totals, $samples }
            }
            fn mpm(&self) -> &thm_mpm::MpmState<thm_coupling::multiscale::RvePoint> {
                &self.mpm
            }
            fn totals(&self) -> &<$case as thm_coupling::multiscale::Protocol>::Totals {
                &self.totals
            }
            fn samples(&self) -> &[$sample] {
                &self.$samples
            }
            fn parts_mut(
                &mut self,
            ) -> (
                &mut thm_mpm::MpmState<thm_coupling::multiscale::RvePoint>,
                &mut <$case as thm_coupling::multiscale::Protocol>::Totals,
                &mut Vec<$sample>,
            ) {
                (&mut self.mpm, &mut self.totals, &mut self.$samples)
            }
        }
    };
}
pub(crate) use kind_state;

/// What a multiscale kind adds to the skeleton (see the module docs).
pub trait MultiscaleKind: Sized {
    /// The `kind` tag.
    const KIND: &'static str;
    /// Layout version of [`Self::State`] in checkpoints.
    const STATE_VERSION: u32;
    /// The kind's sections of the scenario file.
    type Params: DeserializeOwned + Serialize;
    /// The case of the multiscale skeleton the kind runs.
    type Case: Protocol;
    /// The checkpoint state.
    type State: KindState<Self::Case>;

    /// Validates the parameters (errors name the key path) and builds the model and the
    /// kind's output scratch.
    fn init(
        params: &Self::Params,
        time: &TimeControl,
    ) -> Result<(MultiscaleModel<Self::Case>, Self), ConfigError>;
    /// The samples the run starts with. Default: none.
    fn first_samples(
        _model: &MultiscaleModel<Self::Case>,
    ) -> Vec<<Self::State as KindState<Self::Case>>::Sample> {
        Vec::new()
    }
    /// The sample of `record` (taken every [`SAMPLE_EVERY`] steps), if the kind samples now.
    fn sample(
        record: &<Self::Case as Protocol>::Record,
        totals: &<Self::Case as Protocol>::Totals,
    ) -> Option<<Self::State as KindState<Self::Case>>::Sample>;
    /// The monitored quantities (time is added by the driver).
    fn monitor_columns(&self) -> Vec<Column>;
    /// Their values for `record`, the row of `state`.
    fn monitor(
        &self,
        record: &<Self::Case as Protocol>::Record,
        state: &Self::State,
        values: &mut Vec<f64>,
    );
    /// The frame of `state`.
    fn frame(
        &mut self,
        model: &MultiscaleModel<Self::Case>,
        state: &Self::State,
        sink: &mut FrameSink<'_>,
    ) -> Result<(), IoError>;
    /// The profiles of `state`. Default: none.
    fn profiles(&self, _state: &Self::State) -> Vec<Profile> {
        Vec::new()
    }
    /// The figures of merit at the end, `record` the row of `state`.
    fn summary(
        &self,
        model: &MultiscaleModel<Self::Case>,
        record: &<Self::Case as Protocol>::Record,
        state: &Self::State,
    ) -> Vec<SummaryRow>;
}

/// A multiscale kind on the skeleton: the model (its `state` and `totals` are swapped in for
/// each step) and the kind's output scratch.
#[derive(Debug)]
pub struct Multiscale<K: MultiscaleKind> {
    model: MultiscaleModel<K::Case>,
    kind: K,
}

impl<K: MultiscaleKind> Multiscale<K> {
    /// Runs `f` on the model with `state` swapped in.
    fn with_state<R>(
        &mut self,
        state: &mut K::State,
        f: impl FnOnce(&mut MultiscaleModel<K::Case>) -> R,
    ) -> R {
        let (mpm, totals, _) = state.parts_mut();
        std::mem::swap(&mut self.model.state, mpm);
        std::mem::swap(&mut self.model.totals, totals);
        let r = f(&mut self.model);
        let (mpm, totals, _) = state.parts_mut();
        std::mem::swap(&mut self.model.state, mpm);
        std::mem::swap(&mut self.model.totals, totals);
        r
    }

    /// The history row of `state` (the wall reactions are the stepper's last step's).
    fn record(&self, state: &K::State) -> <K::Case as Protocol>::Record {
        self.model.record_of(state.mpm(), state.totals())
    }
}

impl<K: MultiscaleKind> Scenario for Multiscale<K>
where
    MultiscaleModel<K::Case>: std::fmt::Debug,
{
    const KIND: &'static str = K::KIND;
    const STATE_VERSION: u32 = K::STATE_VERSION;
    type Params = K::Params;
    type State = K::State;

    fn distribute(&mut self, distribution: &SharedDistribution) -> Result<(), RunError> {
        self.model.distribute(distribution);
        Ok(())
    }

    fn synchronise(&mut self, state: &mut K::State) -> Result<(), RunError> {
        let (step, time) = (state.mpm().step, state.mpm().time);
        self.with_state(state, |m| m.synchronise())
            .map_err(physics_error(step, time))
    }

    fn arrays<'s>(&'s self, state: &'s K::State) -> Vec<StateArray<'s>> {
        mpm_rve_arrays(&state.mpm().points, &state.mpm().material)
    }

    fn set_array(
        &mut self,
        state: &mut K::State,
        name: &str,
        values: &[f64],
    ) -> Result<(), RunError> {
        set_points_array(&mut state.parts_mut().0.points, name, values)
    }

    fn init(params: &K::Params, time: &TimeControl) -> Result<(Self, K::State), ConfigError> {
        let (model, kind) = K::init(params, time)?;
        let state =
            K::State::from_parts(model.state.clone(), model.totals, K::first_samples(&model));
        Ok((Self { model, kind }, state))
    }

    fn restore(&mut self, state: &K::State) -> Result<(), RunError> {
        let mpm = state.mpm();
        self.model
            .restore(mpm.clone(), *state.totals())
            .map_err(physics_error(mpm.step, mpm.time))
    }

    fn step(&mut self, state: &mut K::State, step: u64, _dt: f64) -> Result<(), RunError> {
        let time = state.mpm().time;
        self.with_state(state, |m| m.step())
            .map_err(physics_error(step, time))?;
        if state.mpm().step.is_multiple_of(SAMPLE_EVERY)
            && let Some(sample) = K::sample(&self.record(state), state.totals())
        {
            state.parts_mut().2.push(sample);
        }
        Ok(())
    }

    fn monitor_columns(&self) -> Vec<Column> {
        self.kind.monitor_columns()
    }

    fn monitor(&self, state: &K::State, values: &mut Vec<f64>) {
        self.kind.monitor(&self.record(state), state, values);
    }

    fn frame(&mut self, state: &K::State, sink: &mut FrameSink<'_>) -> Result<(), IoError> {
        self.kind.frame(&self.model, state, sink)
    }

    fn profiles(&self, state: &K::State, _time: f64) -> Vec<Profile> {
        self.kind.profiles(state)
    }

    fn summary(&self, state: &K::State, _time: f64) -> Vec<SummaryRow> {
        self.kind.summary(&self.model, &self.record(state), state)
    }
}

/// Refuses a time step beyond the stability limit of B-Eqs. 30–31 of the model as built.
pub fn check_time_step<C: Protocol>(
    model: &MultiscaleModel<C>,
    time: &TimeControl,
) -> Result<(), ConfigError> {
    let limit = model.time_step_limit();
    if time.dt > limit {
        return Err(ConfigError::new(
            "time.step",
            format!(
                "must be ≤ {limit:e} s (B-Eqs. 30–31 stability limit), got {} s",
                time.dt
            ),
        ));
    }
    Ok(())
}

/// The time left after a settling of `settle_steps` steps, which must leave steps of the
/// run; else an error at `time.end`.
pub fn time_after_settling(settle_steps: u64, time: &TimeControl) -> Result<f64, ConfigError> {
    if settle_steps >= time.n_steps {
        return Err(ConfigError::new(
            "time.end",
            format!(
                "must leave steps after the settling ({settle_steps} steps of {} s)",
                time.dt
            ),
        ));
    }
    Ok((time.n_steps - settle_steps) as f64 * time.dt)
}

/// Each point's temperature rise above `t0` and mean pressure `−(σ_xx + σ_yy)/2`
/// (compression positive), into `rise` and `pressure`.
pub fn rise_and_pressure(
    points: &thm_mpm::MaterialPoints,
    t0: f64,
    rise: &mut [f64],
    pressure: &mut [f64],
) {
    for k in 0..points.len() {
        rise[k] = points.temperature[k] - t0;
        pressure[k] = -0.5 * (points.stress[k][0] + points.stress[k][1]);
    }
}

/// Brings every process's copy of `points` up to date when `material` is distributed (see
/// `thm_coupling::multiscale::distributed`); nothing otherwise. For the kinds that step a
/// material of their own (the rod, the square).
pub(crate) fn synchronise_points(
    material: &RveMaterial,
    points: &mut [RvePoint],
    step: u64,
    time: f64,
) -> Result<(), RunError> {
    match material.distribution() {
        Some(d) => thm_coupling::multiscale::distributed::lock(d)
            .synchronise(points)
            .map_err(physics_error(step, time)),
        None => Ok(()),
    }
}
