"""The equation of state over numpy arrays: what ``thm eos`` computes, elementwise.

Inputs broadcast against each other (numpy rules); the result has the broadcast shape, or is a
float for scalar inputs. Models: ``"pr"`` (plain Peng-Robinson), ``"pr-corrected"`` (with the
liquid-water volume correction of Krzaczek et al. 2023, the default) and, for water,
``"iapws97"`` (IAPWS-IF97). ``on_error="raise"`` raises ``thm.EosError`` at the first element
with no physical answer (its flat ``index`` attached); ``on_error="nan"`` gives NaN there.
Units: K, kg/m^3, Pa, m^3, kg.
"""

from __future__ import annotations

from typing import Tuple

import numpy as np

from . import _thm

__all__ = ["pressure", "density", "closure"]


def _flat(*arrays):
    b = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in arrays])
    shape = b[0].shape
    return shape, [np.ascontiguousarray(a).ravel() for a in b]


def _shaped(out: np.ndarray, shape):
    return float(out[0]) if shape == () else out.reshape(shape)


def pressure(temperature, density, fluid: str = "water", model: str = "pr-corrected",
             on_error: str = "raise"):
    """Pressure [Pa] at temperature [K] and density [kg/m^3]."""
    shape, (t, rho) = _flat(temperature, density)
    return _shaped(_thm.eos_pressure(t, rho, fluid, model, on_error), shape)


def density(temperature, pressure, branch: str = "liquid", fluid: str = "water",
            model: str = "pr-corrected", on_error: str = "raise"):
    """Density [kg/m^3] at temperature [K] and pressure [Pa] on ``branch`` (``"liquid"``: the
    smallest molar volume above the co-volume; ``"gas"``: the largest)."""
    shape, (t, p) = _flat(temperature, pressure)
    return _shaped(_thm.eos_density(t, p, branch, fluid, model, on_error), shape)


def closure(temperature, volume, liquid_mass, gas_mass, model: str = "pr-corrected",
            on_error: str = "raise") -> Tuple:
    """Two-phase pore closure, water and air (Krzaczek et al. 2023): from temperature [K],
    pore volume [m^3] and the phase masses [kg], ``(liquid_fraction, pressure [Pa],
    liquid_density, gas_density [kg/m^3])``."""
    shape, flat = _flat(temperature, volume, liquid_mass, gas_mass)
    out = _thm.eos_closure(*flat, model, on_error)
    return tuple(_shaped(o, shape) for o in out)
