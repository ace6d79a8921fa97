"""Coupled thermo-hydro-mechanics of granular and porous materials, from Python.

The same scenarios, files and checkpoints as ``thm run``::

    import thm

    run = thm.Run("scenarios/lumped_cooling.toml", out="runs/cooling")
    run.advance(every=100, callback=lambda r: print(r.time, r["sphere_temperature"].min()))
    run.finish()

A scenario is a TOML file or a dict of the same shape; a mistake raises ``ScenarioError``
naming the key path (``particles.radius: ...``). ``Run`` steps on the file's output schedule
and writes what ``thm run`` writes, bit for bit; ``checkpoint()`` and ``resume=`` interoperate
with ``thm run --resume``. State arrays (``run["sphere_temperature"]``, ``run["pore_pressure"]``,
``run["point_stress"]``) are numpy copies taken when read; writable ones (temperatures, point
velocities, sphere loads) are set with ``run["point_temperature"] = values`` between steps.
Ctrl-C during ``step``/``advance`` writes a checkpoint after the current step and raises
``KeyboardInterrupt`` naming it. The equation of state over arrays is in ``thm.eos``.
"""

from __future__ import annotations

import math
import os
from typing import Any, Callable, Dict, NamedTuple, Optional, Union

import numpy as np

from . import _thm
from . import eos

ScenarioError = _thm.ScenarioError
RunError = _thm.RunError
EosError = _thm.EosError

__all__ = [
    "Run",
    "ArrayInfo",
    "validate",
    "kinds",
    "eos",
    "ScenarioError",
    "RunError",
    "EosError",
]

Scenario = Union[str, "os.PathLike[str]", Dict[str, Any]]


def validate(scenario: Scenario) -> None:
    """Checks a scenario (file path or dict) as ``thm run`` does before it writes anything.

    Raises ``ScenarioError`` naming the key path of the first mistake.
    """
    _thm.validate(_source(scenario))


def kinds() -> list:
    """The scenario kinds (``kind`` tags)."""
    return list(_thm.kinds_list())


def _source(scenario: Scenario):
    if isinstance(scenario, dict):
        return scenario
    return os.fspath(scenario)


class ArrayInfo(NamedTuple):
    """What a state array holds: its unit, values per row and whether it can be written."""

    unit: str
    columns: int
    writable: bool


class Run:
    """A scenario run stepped from Python.

    ``Run(scenario, out=None, resume=None)``: ``scenario`` is a TOML file path or a dict;
    ``out`` is the output folder (default ``runs/<file stem>``; required for a dict); ``resume``
    a checkpoint of the same scenario to continue from (written by ``thm run`` or by Python).
    A fresh run refuses an output folder that already holds a run.
    """

    def __init__(
        self,
        scenario: Scenario,
        out: Optional[Union[str, "os.PathLike[str]"]] = None,
        resume: Optional[Union[str, "os.PathLike[str]"]] = None,
    ) -> None:
        self._run = _thm.Run(
            _source(scenario),
            None if out is None else os.fspath(out),
            None if resume is None else os.fspath(resume),
        )
        self._info: Optional[Dict[str, ArrayInfo]] = None

    # -- where the run stands -------------------------------------------------------------
    @property
    def kind(self) -> str:
        """The scenario kind."""
        return self._run.kind

    @property
    def out(self) -> str:
        """The output folder."""
        return self._run.out

    @property
    def steps_done(self) -> int:
        """Steps completed."""
        return self._run.steps_done

    @property
    def n_steps(self) -> int:
        """Steps of the whole run."""
        return self._run.n_steps

    @property
    def dt(self) -> float:
        """The time step [s]."""
        return self._run.dt

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return self._run.time

    @property
    def is_open(self) -> bool:
        """Whether the run can still be stepped (not finished or stopped by an error)."""
        return self._run.is_open

    # -- stepping -------------------------------------------------------------------------
    def step(self, n: int = 1) -> int:
        """Advances ``n`` steps; returns the steps done. Past the end time: ``RunError``."""
        if n < 0:
            raise ValueError(f"n: must be >= 0, got {n}")
        return self._run.step(n)

    def advance(
        self,
        steps: Optional[int] = None,
        *,
        until: Optional[float] = None,
        every: int = 0,
        callback: Optional[Callable[["Run"], Any]] = None,
    ) -> int:
        """Advances to the end time, by at most ``steps`` steps, or until simulated time
        ``until`` [s] (the first step at or after it), calling ``callback(run)`` every ``every``
        steps. Returns the steps done."""
        if steps is not None and until is not None:
            raise ValueError("give steps or until, not both")
        if until is not None:
            if not math.isfinite(until):
                raise ValueError(f"until: must be a finite time in s, got {until}")
            steps = max(0, math.ceil(until / self.dt * (1.0 - 1e-12)) - self.steps_done)
        if steps is not None and steps < 0:
            raise ValueError(f"steps: must be >= 0, got {steps}")
        wrapped = None if callback is None else (lambda _native: callback(self))
        return self._run.advance(steps, every, wrapped)

    def run(self, every: int = 0, callback: Optional[Callable[["Run"], Any]] = None) -> dict:
        """Advances to the end time and finishes (summary written); returns ``finish()``'s
        dict."""
        self.advance(every=every, callback=callback)
        return self.finish()

    def checkpoint(self) -> str:
        """Writes a checkpoint of the current step; returns its path. The run goes on."""
        return self._run.checkpoint()

    def finish(self) -> dict:
        """Ends the run and writes the summary: ``{"finished", "steps", "checkpoint"}``.

        Before the end time this is an interrupted run's ending: a checkpoint of the current
        step that ``Run(..., resume=...)`` or ``thm run --resume`` continues."""
        return dict(self._run.finish())

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None and self._run.is_open:
            self.finish()

    # -- state ----------------------------------------------------------------------------
    def monitor(self) -> Dict[str, float]:
        """The monitored values now (the ``history.csv`` columns), time first."""
        return dict(self._run.monitor())

    def array_info(self) -> Dict[str, ArrayInfo]:
        """The kind's state arrays: ``{name: ArrayInfo(unit, columns, writable)}``."""
        return {k: ArrayInfo(*v) for k, v in self._run.array_info().items()}

    def array(self, name: str) -> np.ndarray:
        """A copy of state array ``name``: shape ``(rows,)`` or ``(rows, columns)``."""
        flat, columns = self._run.array_flat(name)
        return flat if columns == 1 else flat.reshape(-1, columns)

    def arrays(self) -> Dict[str, np.ndarray]:
        """Copies of every state array."""
        return {name: self.array(name) for name in self._run.array_info()}

    def set_array(self, name: str, values) -> None:
        """Replaces writable state array ``name`` (same shape as ``array(name)``; a scalar is
        broadcast). The values are part of the state: a checkpoint keeps them."""
        info = self.array_info().get(name)
        if info is None:
            raise KeyError(f"no state array `{name}` in kind `{self.kind}`")
        current = self.array(name)
        data = np.broadcast_to(np.asarray(values, dtype=np.float64), current.shape)
        self._run.set_array_flat(name, np.ascontiguousarray(data).ravel())

    def __getitem__(self, name: str) -> np.ndarray:
        return self.array(name)

    def __setitem__(self, name: str, values) -> None:
        self.set_array(name, values)

    def __repr__(self) -> str:
        state = "open" if self.is_open else "closed"
        if not self.is_open:
            return f"<thm.Run kind={self.kind} out={self.out!r} {state}>"
        return (
            f"<thm.Run kind={self.kind} step {self.steps_done}/{self.n_steps} "
            f"t={self.time:.6g} s out={self.out!r}>"
        )
