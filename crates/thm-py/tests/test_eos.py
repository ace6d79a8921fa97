"""`thm.eos` against `thm eos` on the same rows, to the last bit."""

from __future__ import annotations

import numpy as np
import pytest

import thm
from conftest import run_cli


def cli_table(thm_bin, table, model, header, rows):
    text = header + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n"
    done = run_cli(thm_bin, "eos", table, "--model", model, input=text)
    lines = done.stdout.strip().splitlines()[1:]
    return [line.split(",") for line in lines]


TEMPERATURES = np.array([280.0, 293.15, 300.0, 350.0, 373.15, 450.0, 600.0, 700.0])


@pytest.mark.parametrize("model", ["pr", "pr-corrected"])
@pytest.mark.parametrize("fluid", ["water", "air"])
def test_pressure_equals_cli_bitwise(thm_bin, model, fluid):
    rho = np.array([0.5, 1.2, 20.0, 300.0, 900.0, 850.0, 1.0e-3, 50.0])
    rows = [(fluid, repr(float(t)), repr(float(r))) for t, r in zip(TEMPERATURES, rho)]
    cli = cli_table(thm_bin, "pressure", model, "fluid,T,rho", rows)
    ours = thm.eos.pressure(TEMPERATURES, rho, fluid=fluid, model=model)
    expected = np.array([float(r[3]) for r in cli])
    assert ours.shape == expected.shape
    assert ours.tobytes() == expected.tobytes()


@pytest.mark.parametrize("model", ["pr", "pr-corrected"])
@pytest.mark.parametrize("branch", ["liquid", "gas"])
def test_density_equals_cli_bitwise(thm_bin, model, branch):
    p = np.array([1.0e3, 1.0e5, 2.0e5, 1.0e6, 5.0e6, 1.0e7, 3.0e5, 2.2e7])
    rows = [("water", repr(float(t)), repr(float(x)), branch) for t, x in zip(TEMPERATURES, p)]
    cli = cli_table(thm_bin, "density", model, "fluid,T,P,branch", rows)
    ours = thm.eos.density(TEMPERATURES, p, branch=branch, model=model)
    expected = np.array([float(r[4]) for r in cli])
    assert ours.tobytes() == expected.tobytes()


@pytest.mark.parametrize("model", ["pr", "pr-corrected"])
def test_closure_equals_cli_bitwise(thm_bin, model):
    t = np.array([278.16, 293.16, 330.0, 368.16])
    v = np.array([1e-9, 2e-10, 5e-9, 1e-8])
    ml = np.array([5e-7, 1e-7, 2e-6, 9e-6])
    mg = np.array([1e-12, 2e-13, 6e-12, 1.1e-11])
    rows = [tuple(repr(float(x)) for x in r) for r in zip(t, v, ml, mg)]
    cli = cli_table(thm_bin, "closure", model, "T,V,m_liquid,m_gas", rows)
    ours = thm.eos.closure(t, v, ml, mg, model=model)
    for k in range(4):
        expected = np.array([float(r[4 + k]) for r in cli])
        assert ours[k].tobytes() == expected.tobytes()


def test_broadcasting_and_scalars():
    p = thm.eos.pressure(300.0, [[1.0, 2.0], [3.0, 4.0]], fluid="air")
    assert p.shape == (2, 2)
    assert isinstance(thm.eos.pressure(300.0, 1.0, fluid="air"), float)
    # Air at low density is close to the ideal gas: P = rho R T / M within 0.1 %.
    ideal = 1.0 * 8314.462618 * 300.0 / 28.96
    assert abs(thm.eos.pressure(300.0, 1.0, fluid="air") / ideal - 1.0) < 1e-3


def test_iapws97_table5_verification_values():
    # IAPWS-IF97, Table 5 (region 1): T = 300 K, p = 3 MPa: v = 0.100215168e-2 m^3/kg;
    # T = 300 K, p = 80 MPa: v = 0.971180894e-3 m^3/kg.
    rho = thm.eos.density([300.0, 300.0], [3.0e6, 80.0e6], model="iapws97")
    assert np.allclose(rho, [1 / 0.100215168e-2, 1 / 0.971180894e-3], rtol=1e-8, atol=0)


def test_errors_name_the_element_and_nan_mode():
    with pytest.raises(thm.EosError) as e:
        thm.eos.pressure([300.0, -5.0, 300.0], 1.0, fluid="air")
    assert e.value.index == 1
    assert "element 1" in str(e.value)
    out = thm.eos.pressure([300.0, -5.0], 1.0, fluid="air", on_error="nan")
    assert np.isfinite(out[0]) and np.isnan(out[1])
    with pytest.raises(ValueError, match="unknown fluid `steam`"):
        thm.eos.pressure(300.0, 1.0, fluid="steam")
    with pytest.raises(ValueError, match="iapws97 is for water only"):
        thm.eos.pressure(300.0, 1.0, fluid="air", model="iapws97")
    with pytest.raises(ValueError, match="on_error"):
        thm.eos.pressure(300.0, 1.0, on_error="ignore")
