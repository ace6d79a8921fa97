//! # thm-py
//!
//! The native part of the `thm` Python module (`thm._thm`, built by maturin with PyO3's stable
//! ABI): scenario runs stepped from Python, the state as numpy arrays, checkpoints, and the
//! equation of state over arrays. The Python package (`python/thm`) wraps it; users import
//! `thm`, not this module.
//!
//! What it does:
//! - **Runs.** A scenario from a TOML file or a Python dict (converted to TOML and read by the
//!   same code as `thm run`, so an error names the same key path) is opened as a
//!   [`thm_scenarios::registry::DynRun`] and stepped one step at a time on the file's output
//!   schedule; the files written (history, frames, checkpoints, summary) are those of
//!   `thm run`, bit for bit, and a checkpoint written from Python resumes under `thm run` and
//!   the other way round.
//! - **State arrays.** Each kind names its arrays (`sphere_temperature`, `pore_pressure`,
//!   `point_stress`, …); reading one copies it once into a new numpy array (a snapshot: a later
//!   step never changes or frees memory a Python array points to, and a remesh may change the
//!   number of pores). Writable arrays (temperatures, point velocities, sphere loads) are part
//!   of the state, so a checkpoint keeps what was written.
//! - **Equation of state.** `pressure`, `density` and `closure` of `thm eos` over contiguous
//!   `f64` arrays, with the same models (`pr`, `pr-corrected`, and IAPWS-IF97 for water).
//!
//! Errors: a Rust error becomes a Python exception carrying the message `thm run` or
//! `thm eos` prints (`ScenarioError(ValueError)` with a `key` attribute for a scenario value,
//! `RunError(RuntimeError)` for a run that cannot go on, `EosError(ValueError)` with the
//! element `index`). A panic inside a step is caught and raised as `RunError`; the run is then
//! closed. Steps run with the GIL released; Ctrl-C is seen between steps, where the run writes
//! a checkpoint and the summary and raises `KeyboardInterrupt` naming the checkpoint.

#![deny(clippy::unwrap_used, clippy::expect_used)]

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, TryLockError};

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyKeyboardInterrupt, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use thm_eos::{Branch, EosError, EquationOfState, Iapws97Water, Model, PengRobinson, PoreClosure};
use thm_scenarios::config::ScenarioDocument;
use thm_scenarios::error::RunError;
use thm_scenarios::registry::{self, DocError, DynRun, parse_document, read_document};
use thm_scenarios::scenario::Outcome;

/// The module's exceptions (Python names `thm.ScenarioError`, `thm.RunError`,
/// `thm.EosError`).
mod exc {
    use pyo3::exceptions::{PyRuntimeError, PyValueError};

    pyo3::create_exception!(
        thm,
        ScenarioError,
        PyValueError,
        "A scenario value is missing, unknown, of the wrong type or unit, or out of range; \
         `key` is its dotted key path."
    );
    pyo3::create_exception!(
        thm,
        RunError,
        PyRuntimeError,
        "A run cannot go on: an unstable or refused step, a full disk, a foreign checkpoint."
    );
    pyo3::create_exception!(
        thm,
        EosError,
        PyValueError,
        "An equation-of-state input has no physical answer; `index` is the element (flat \
         index)."
    );
}
use exc::{EosError as EosErrorPy, RunError as RunError_, ScenarioError};

/// The Python exception for a run error: scenario errors keep their key path.
fn run_error(py: Python<'_>, e: &RunError) -> PyErr {
    let message = e.to_string();
    match e {
        RunError::Config { error, .. } => {
            let err = ScenarioError::new_err(message);
            // Attribute setting on a fresh exception object cannot fail in practice; if it
            // does, the message still carries the key.
            let _ = err.value(py).setattr("key", error.key.clone());
            err
        }
        RunError::Syntax { .. } | RunError::Input { .. } => ScenarioError::new_err(message),
        _ => RunError_::new_err(message),
    }
}

/// A Python value as TOML, or `(key path, message)`.
fn to_toml(obj: &Bound<'_, PyAny>, key: &str) -> Result<toml::Value, (String, String)> {
    let wrong = |what: String| (display_key(key), what);
    if obj.is_instance_of::<PyBool>() {
        return obj
            .extract::<bool>()
            .map(toml::Value::Boolean)
            .map_err(|e| wrong(e.to_string()));
    }
    if obj.is_instance_of::<PyInt>() {
        return obj
            .extract::<i64>()
            .map(toml::Value::Integer)
            .map_err(|_| wrong("integer does not fit in 64 bits".into()));
    }
    if obj.is_instance_of::<PyFloat>() {
        return obj
            .extract::<f64>()
            .map(toml::Value::Float)
            .map_err(|e| wrong(e.to_string()));
    }
    if obj.is_instance_of::<PyString>() {
        return obj
            .extract::<String>()
            .map(toml::Value::String)
            .map_err(|e| wrong(e.to_string()));
    }
    if let Ok(dict) = obj.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in dict.iter() {
            let name: String = k.extract().map_err(|_| {
                wrong(format!(
                    "dictionary keys must be strings, got `{}`",
                    type_name(&k)
                ))
            })?;
            let sub = if key.is_empty() {
                name.clone()
            } else {
                format!("{key}.{name}")
            };
            table.insert(name, to_toml(&v, &sub)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, v) in obj
            .try_iter()
            .map_err(|e| wrong(e.to_string()))?
            .enumerate()
        {
            let v = v.map_err(|e| wrong(e.to_string()))?;
            items.push(to_toml(&v, &format!("{key}[{i}]"))?);
        }
        return Ok(toml::Value::Array(items));
    }
    // numpy scalars: integers through `__index__`, floats through `__float__`.
    if obj.hasattr("__index__").unwrap_or(false)
        && let Ok(i) = obj.extract::<i64>()
    {
        return Ok(toml::Value::Integer(i));
    }
    if obj.hasattr("__float__").unwrap_or(false)
        && let Ok(x) = obj.extract::<f64>()
    {
        return Ok(toml::Value::Float(x));
    }
    Err(wrong(format!(
        "a Python `{}` has no scenario form; use bool, int, float, str, list or dict",
        type_name(obj)
    )))
}

fn display_key(key: &str) -> String {
    if key.is_empty() {
        "(top level)".into()
    } else {
        key.into()
    }
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// Where a scenario comes from: a file, or a dict (shown as `<dict>` in messages).
fn read_scenario(source: &Bound<'_, PyAny>) -> PyResult<(ScenarioDocument, PathBuf)> {
    let py = source.py();
    if let Ok(dict) = source.cast::<PyDict>() {
        let file = PathBuf::from("<dict>");
        let value = to_toml(dict.as_any(), "").map_err(|(key, message)| {
            run_error(
                py,
                &RunError::Config {
                    path: file.clone(),
                    error: thm_scenarios::error::ConfigError::new(key, message),
                },
            )
        })?;
        let text = toml::to_string(&value).map_err(|e| {
            run_error(
                py,
                &RunError::Syntax {
                    path: file.clone(),
                    message: e.to_string(),
                },
            )
        })?;
        let doc = parse_document(&text).map_err(|e| {
            let err = match e {
                DocError::Syntax(message) => RunError::Syntax {
                    path: file.clone(),
                    message,
                },
                DocError::Config(error) => RunError::Config {
                    path: file.clone(),
                    error,
                },
            };
            run_error(py, &err)
        })?;
        return Ok((doc, file));
    }
    let path: PathBuf = source.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "a scenario is a path (str or os.PathLike) or a dict, got `{}`",
            type_name(source)
        ))
    })?;
    let doc = read_document(&path).map_err(|e| run_error(py, &e))?;
    Ok((doc, path))
}

/// Checks a scenario (a file path or a dict) as `thm run` does before it writes anything;
/// raises `ScenarioError` naming the key path.
#[pyfunction]
fn validate(source: &Bound<'_, PyAny>) -> PyResult<()> {
    let py = source.py();
    let (doc, file) = read_scenario(source)?;
    registry::validate(&doc).map_err(|error| run_error(py, &RunError::Config { path: file, error }))
}

/// The scenario kinds, as `kind` tags.
#[pyfunction]
fn kinds_list() -> Vec<String> {
    registry::names()
        .split(", ")
        .map(|k| k.trim_matches('`').to_string())
        .collect()
}

/// A scenario run stepped from Python (see the module docs).
#[pyclass(module = "thm._thm", name = "Run")]
struct PyRun {
    inner: Mutex<Option<Box<dyn DynRun>>>,
    kind: &'static str,
    out: PathBuf,
    file: PathBuf,
}

/// A run's outcome as a dict.
fn outcome_dict<'py>(py: Python<'py>, outcome: &Outcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let (finished, steps, ckpt) = match outcome {
        Outcome::Finished { steps, checkpoint } => (true, *steps, checkpoint),
        Outcome::Interrupted { steps, checkpoint } => (false, *steps, checkpoint),
    };
    d.set_item("finished", finished)?;
    d.set_item("steps", steps)?;
    d.set_item("checkpoint", ckpt.to_string_lossy().into_owned())?;
    Ok(d)
}

impl PyRun {
    fn lock(&self) -> PyResult<MutexGuard<'_, Option<Box<dyn DynRun>>>> {
        match self.inner.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::WouldBlock) => Err(RunError_::new_err(
                "the run is busy in another thread; step and read it from one thread",
            )),
            Err(TryLockError::Poisoned(p)) => Ok(p.into_inner()),
        }
    }

    fn closed() -> PyErr {
        RunError_::new_err(
            "the run is closed (finished, or stopped by an error); open a new Run, or resume from its last checkpoint",
        )
    }

    /// One step with the GIL released; a panic closes the run and raises `RunError`.
    fn advance_one(py: Python<'_>, slot: &mut Option<Box<dyn DynRun>>) -> PyResult<()> {
        let run = slot.as_mut().ok_or_else(Self::closed)?;
        let result = py.detach(|| catch_unwind(AssertUnwindSafe(|| run.advance(false))));
        match result {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => {
                let err = run_error(py, &e);
                if !matches!(e, RunError::Ended { .. }) {
                    *slot = None;
                }
                Err(err)
            }
            Err(panic) => {
                *slot = None;
                let what = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown".into());
                Err(RunError_::new_err(format!(
                    "internal error in a step (a bug; please report it with the scenario): {what}"
                )))
            }
        }
    }

    /// After Ctrl-C: a checkpoint and the summary of an interrupted run, then
    /// `KeyboardInterrupt` naming the checkpoint. The run stays open.
    fn interrupted(py: Python<'_>, run: &mut Box<dyn DynRun>, file: &Path, out: &Path) -> PyErr {
        match run.finish() {
            Ok(Outcome::Interrupted { steps, checkpoint })
            | Ok(Outcome::Finished { steps, checkpoint }) => PyKeyboardInterrupt::new_err(format!(
                "stopped after step {steps}; checkpoint {} (continue with Run({:?}, out={:?}, resume={:?}) or thm run {} --out {} --resume {})",
                checkpoint.display(),
                file.display().to_string(),
                out.display().to_string(),
                checkpoint.display().to_string(),
                file.display(),
                out.display(),
                checkpoint.display()
            )),
            Err(e) => run_error(py, &e),
        }
    }

    /// Steps until `done(steps_done)` or the end, calling `callback(self)` every `every`
    /// steps; checks Ctrl-C after every step.
    fn step_loop(
        slf: &Bound<'_, Self>,
        max_steps: u64,
        every: u64,
        callback: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<u64> {
        let py = slf.py();
        let this = slf.borrow();
        let mut done = 0u64;
        while done < max_steps {
            {
                let mut guard = this.lock()?;
                let slot = &mut *guard;
                Self::advance_one(py, slot)?;
                done += 1;
                if let Err(e) = py.check_signals() {
                    let run = slot.as_mut().ok_or_else(Self::closed)?;
                    if e.is_instance_of::<PyKeyboardInterrupt>(py) {
                        return Err(Self::interrupted(py, run, &this.file, &this.out));
                    }
                    return Err(e);
                }
            }
            // Calls fall on step indices that are multiples of `every`, as history rows do.
            if let Some(cb) = callback
                && every > 0
            {
                let at = this.lock()?.as_ref().ok_or_else(Self::closed)?.steps_done();
                if at % every == 0 {
                    cb.call1((slf,))?;
                }
            }
        }
        Ok(done)
    }
}

#[pymethods]
impl PyRun {
    /// `Run(source, out=None, resume=None)`: opens a run of a scenario file or dict.
    ///
    /// `out` defaults to `runs/<file stem>` for a file and is required for a dict; `resume`
    /// continues from a checkpoint of the same scenario (written by `thm run` or by Python).
    #[new]
    #[pyo3(signature = (source, out=None, resume=None))]
    fn new(
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        out: Option<PathBuf>,
        resume: Option<PathBuf>,
    ) -> PyResult<Self> {
        let (doc, file) = read_scenario(source)?;
        let out = match out {
            Some(o) => o,
            None if source.is_instance_of::<PyDict>() => {
                return Err(PyValueError::new_err(
                    "out: a scenario given as a dict needs an output folder (out=...)",
                ));
            }
            None => thm_scenarios::default_out(&file),
        };
        let run = py
            .detach(|| registry::open(doc, &file, &out, resume.as_deref()))
            .map_err(|e| run_error(py, &e))?;
        Ok(Self {
            kind: run.kind(),
            inner: Mutex::new(Some(run)),
            out,
            file,
        })
    }

    /// The scenario kind.
    #[getter]
    fn kind(&self) -> &'static str {
        self.kind
    }

    /// The output folder.
    #[getter]
    fn out(&self) -> String {
        self.out.to_string_lossy().into_owned()
    }

    /// Steps completed.
    #[getter]
    fn steps_done(&self) -> PyResult<u64> {
        Ok(self.lock()?.as_ref().ok_or_else(Self::closed)?.steps_done())
    }

    /// Steps of the whole run.
    #[getter]
    fn n_steps(&self) -> PyResult<u64> {
        Ok(self.lock()?.as_ref().ok_or_else(Self::closed)?.n_steps())
    }

    /// The time step \[s\].
    #[getter]
    fn dt(&self) -> PyResult<f64> {
        Ok(self.lock()?.as_ref().ok_or_else(Self::closed)?.dt())
    }

    /// Simulated time \[s\] (steps done × time step).
    #[getter]
    fn time(&self) -> PyResult<f64> {
        let g = self.lock()?;
        let r = g.as_ref().ok_or_else(Self::closed)?;
        Ok(r.steps_done() as f64 * r.dt())
    }

    /// Whether the run is still open.
    #[getter]
    fn is_open(&self) -> PyResult<bool> {
        Ok(self.lock()?.is_some())
    }

    /// Advances `n` steps (default 1); returns the steps done.
    #[pyo3(signature = (n=1))]
    fn step(slf: &Bound<'_, Self>, n: u64) -> PyResult<u64> {
        Self::step_loop(slf, n, 0, None)
    }

    /// Advances to the end time, or by at most `steps`, calling `callback(run)` every `every`
    /// steps; returns the steps done.
    #[pyo3(signature = (steps=None, every=0, callback=None))]
    fn advance(
        slf: &Bound<'_, Self>,
        steps: Option<u64>,
        every: u64,
        callback: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<u64> {
        let left = {
            let this = slf.borrow();
            let g = this.lock()?;
            let r = g.as_ref().ok_or_else(Self::closed)?;
            r.n_steps() - r.steps_done()
        };
        if callback.is_some() && every == 0 {
            return Err(PyValueError::new_err(
                "every: a callback needs every >= 1 (steps between calls)",
            ));
        }
        if let Some(cb) = callback
            && !cb.is_callable()
        {
            return Err(PyTypeError::new_err(
                "callback: must be callable as callback(run)",
            ));
        }
        Self::step_loop(slf, steps.unwrap_or(left).min(left), every, callback)
    }

    /// The monitored values now, `{"name [unit]": value}`, time first.
    fn monitor<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut g = self.lock()?;
        let r = g.as_mut().ok_or_else(Self::closed)?;
        let (headers, values) = r.monitor();
        let d = PyDict::new(py);
        for (h, v) in headers.into_iter().zip(values) {
            d.set_item(h, v)?;
        }
        Ok(d)
    }

    /// The state arrays: `{name: (unit, columns, writable)}`.
    fn array_info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let g = self.lock()?;
        let r = g.as_ref().ok_or_else(Self::closed)?;
        let d = PyDict::new(py);
        for a in r.arrays() {
            d.set_item(a.name, (a.unit, a.columns, a.writable))?;
        }
        Ok(d)
    }

    /// A copy of state array `name` as a flat numpy array and its column count.
    fn array_flat<'py>(
        &self,
        py: Python<'py>,
        name: &str,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, usize)> {
        let g = self.lock()?;
        let r = g.as_ref().ok_or_else(Self::closed)?;
        let arrays = r.arrays();
        let Some(a) = arrays.iter().find(|a| a.name == name) else {
            let names: Vec<&str> = arrays.iter().map(|a| a.name).collect();
            return Err(PyKeyError_new(format!(
                "no state array `{name}` in kind `{}`; arrays: {}",
                self.kind,
                names.join(", ")
            )));
        };
        Ok((PyArray1::from_slice(py, &a.values), a.columns))
    }

    /// Replaces writable state array `name` with `values` (flat, contiguous float64).
    fn set_array_flat(&self, name: &str, values: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let py = values.py();
        let slice = values
            .as_slice()
            .map_err(|_| PyValueError::new_err("values: must be contiguous"))?;
        let mut g = self.lock()?;
        let r = g.as_mut().ok_or_else(Self::closed)?;
        r.set_array(name, slice).map_err(|e| run_error(py, &e))
    }

    /// Writes a checkpoint of the current step; returns its path. The run goes on.
    fn checkpoint(&self, py: Python<'_>) -> PyResult<String> {
        let mut g = self.lock()?;
        let r = g.as_mut().ok_or_else(Self::closed)?;
        let path = py
            .detach(|| r.checkpoint())
            .map_err(|e| run_error(py, &e))?;
        Ok(path.to_string_lossy().into_owned())
    }

    /// Ends the run: at the end time its last checkpoint and the summary; before it, a
    /// checkpoint of the current step and an interrupted run's summary. Returns
    /// `{"finished", "steps", "checkpoint"}` and closes the run.
    fn finish<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut g = self.lock()?;
        let r = g.as_mut().ok_or_else(Self::closed)?;
        let outcome = py.detach(|| r.finish()).map_err(|e| run_error(py, &e))?;
        *g = None;
        outcome_dict(py, &outcome)
    }
}

#[allow(non_snake_case)]
fn PyKeyError_new(message: String) -> PyErr {
    pyo3::exceptions::PyKeyError::new_err(message)
}

/// The equation of state a (fluid, model) pair names.
enum Fluid {
    Pr(PengRobinson),
    Iapws(Iapws97Water),
}

impl Fluid {
    fn new(fluid: &str, model: &str) -> PyResult<Self> {
        let model_of = |m: &str| match m {
            "pr" => Ok(Model::Pr),
            "pr-corrected" => Ok(Model::PrCorrected),
            other => Err(PyValueError::new_err(format!(
                "model: unknown model `{other}` (allowed: pr, pr-corrected, iapws97 for water)"
            ))),
        };
        match (fluid.to_ascii_lowercase().as_str(), model) {
            ("water", "iapws97") => Ok(Fluid::Iapws(Iapws97Water)),
            ("water", m) => Ok(Fluid::Pr(PengRobinson::water(model_of(m)?))),
            ("air", "iapws97") => Err(PyValueError::new_err(
                "model: iapws97 is for water only; air uses pr",
            )),
            ("air", m) => {
                model_of(m)?;
                Ok(Fluid::Pr(PengRobinson::air()))
            }
            (other, _) => Err(PyValueError::new_err(format!(
                "fluid: unknown fluid `{other}` (allowed: water, air)"
            ))),
        }
    }

    fn eos(&self) -> &(dyn EquationOfState + Sync) {
        match self {
            Fluid::Pr(e) => e,
            Fluid::Iapws(e) => e,
        }
    }
}

fn eos_error(index: usize, e: &EosError) -> PyErr {
    Python::attach(|py| {
        let err = EosErrorPy::new_err(format!("element {index}: {e}"));
        let _ = err.value(py).setattr("index", index);
        err
    })
}

fn slice_of<'a>(a: &'a PyReadonlyArray1<'_, f64>, name: &str) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|_| PyValueError::new_err(format!("{name}: must be contiguous")))
}

/// `on_error`: "raise" (the first failing element raises `EosError`) or "nan" (failing
/// elements give NaN).
fn nan_on_error(on_error: &str) -> PyResult<bool> {
    match on_error {
        "raise" => Ok(false),
        "nan" => Ok(true),
        other => Err(PyValueError::new_err(format!(
            "on_error: `{other}` is not one of raise, nan"
        ))),
    }
}

/// Maps `f` over equal-length inputs with the GIL released: `M` output arrays.
fn map_elements<const N: usize, const M: usize>(
    py: Python<'_>,
    inputs: [&[f64]; N],
    nan: bool,
    f: impl Fn([f64; N]) -> Result<[f64; M], EosError> + Sync,
) -> PyResult<[Vec<f64>; M]> {
    let n = inputs[0].len();
    if inputs.iter().any(|a| a.len() != n) {
        return Err(PyValueError::new_err(
            "inputs must have the same length (broadcast them first)",
        ));
    }
    let out = py.detach(|| {
        let mut out: [Vec<f64>; M] = std::array::from_fn(|_| Vec::with_capacity(n));
        (0..n).try_for_each(|i| {
            let values = match f(std::array::from_fn(|k| inputs[k][i])) {
                Ok(v) => v,
                Err(_) if nan => [f64::NAN; M],
                Err(e) => return Err((i, e)),
            };
            out.iter_mut().zip(values).for_each(|(o, v)| o.push(v));
            Ok(())
        })?;
        Ok(out)
    });
    out.map_err(|(i, e)| eos_error(i, &e))
}

/// Pressure \[Pa\] at temperature \[K\] and density \[kg/m³\], elementwise.
#[pyfunction]
#[pyo3(signature = (temperature, density, fluid="water", model="pr-corrected", on_error="raise"))]
fn eos_pressure<'py>(
    py: Python<'py>,
    temperature: PyReadonlyArray1<'py, f64>,
    density: PyReadonlyArray1<'py, f64>,
    fluid: &str,
    model: &str,
    on_error: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let f = Fluid::new(fluid, model)?;
    let nan = nan_on_error(on_error)?;
    let (t, rho) = (
        slice_of(&temperature, "temperature")?,
        slice_of(&density, "density")?,
    );
    let eos = f.eos();
    let [out] = map_elements(py, [t, rho], nan, |[t, rho]| Ok([eos.pressure(t, rho)?]))?;
    Ok(PyArray1::from_vec(py, out))
}

fn branch_of(branch: &str) -> PyResult<Branch> {
    match branch.to_ascii_lowercase().as_str() {
        "liquid" => Ok(Branch::Liquid),
        "gas" => Ok(Branch::Gas),
        other => Err(PyValueError::new_err(format!(
            "branch: unknown branch `{other}` (allowed: liquid, gas)"
        ))),
    }
}

/// Density \[kg/m³\] at temperature \[K\] and pressure \[Pa\] on a branch, elementwise.
#[pyfunction]
#[pyo3(signature = (temperature, pressure, branch="liquid", fluid="water", model="pr-corrected", on_error="raise"))]
fn eos_density<'py>(
    py: Python<'py>,
    temperature: PyReadonlyArray1<'py, f64>,
    pressure: PyReadonlyArray1<'py, f64>,
    branch: &str,
    fluid: &str,
    model: &str,
    on_error: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let f = Fluid::new(fluid, model)?;
    let b = branch_of(branch)?;
    let nan = nan_on_error(on_error)?;
    let (t, p) = (
        slice_of(&temperature, "temperature")?,
        slice_of(&pressure, "pressure")?,
    );
    let eos = f.eos();
    let [out] = map_elements(py, [t, p], nan, |[t, p]| Ok([eos.density(t, p, b)?]))?;
    Ok(PyArray1::from_vec(py, out))
}

/// Type of the closure's four outputs.
type ClosureArrays<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

/// Two-phase pore closure (water + air): `(liquid_fraction, pressure, rho_liquid, rho_gas)`
/// from temperature \[K\], pore volume \[m³\] and the phase masses \[kg\], elementwise.
#[pyfunction]
#[pyo3(signature = (temperature, volume, liquid_mass, gas_mass, model="pr-corrected", on_error="raise"))]
fn eos_closure<'py>(
    py: Python<'py>,
    temperature: PyReadonlyArray1<'py, f64>,
    volume: PyReadonlyArray1<'py, f64>,
    liquid_mass: PyReadonlyArray1<'py, f64>,
    gas_mass: PyReadonlyArray1<'py, f64>,
    model: &str,
    on_error: &str,
) -> PyResult<ClosureArrays<'py>> {
    let m = match model {
        "pr" => Model::Pr,
        "pr-corrected" => Model::PrCorrected,
        other => {
            return Err(PyValueError::new_err(format!(
                "model: unknown closure model `{other}` (allowed: pr, pr-corrected)"
            )));
        }
    };
    let nan = nan_on_error(on_error)?;
    let pore = thm_eos::water_air_closure(m);
    let inputs = [
        slice_of(&temperature, "temperature")?,
        slice_of(&volume, "volume")?,
        slice_of(&liquid_mass, "liquid_mass")?,
        slice_of(&gas_mass, "gas_mass")?,
    ];
    let [a, p, rl, rg] = map_elements(py, inputs, nan, |[t, v, ml, mg]| {
        let s = pore.close(t, v, ml, mg)?;
        Ok([
            s.liquid_fraction,
            s.pressure,
            s.liquid_density,
            s.gas_density,
        ])
    })?;
    Ok((
        PyArray1::from_vec(py, a),
        PyArray1::from_vec(py, p),
        PyArray1::from_vec(py, rl),
        PyArray1::from_vec(py, rg),
    ))
}

/// The native module `thm._thm`.
#[pymodule]
fn _thm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<PyRun>()?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(kinds_list, m)?)?;
    m.add_function(wrap_pyfunction!(eos_pressure, m)?)?;
    m.add_function(wrap_pyfunction!(eos_density, m)?)?;
    m.add_function(wrap_pyfunction!(eos_closure, m)?)?;
    m.add("ScenarioError", py.get_type::<ScenarioError>())?;
    m.add("RunError", py.get_type::<RunError_>())?;
    m.add("EosError", py.get_type::<EosErrorPy>())?;
    Ok(())
}
