"""Runs stepped from Python against `thm run`: the same files bit for bit, checkpoints that
cross between the two, key-path errors, writable state, Ctrl-C and the GIL."""

from __future__ import annotations

import math
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import thm
from conftest import output_files, run_cli, shortened

# Shortened scenarios of every family: (file stem, end, output intervals chosen so that rows,
# frames and checkpoints fall on steps the Python side steps across in odd chunks).
CASES = {
    "lumped_cooling": ("lumped_cooling", "60 s", dict(history_every=7, frame_every=20, checkpoint_every=25)),
    "mpm_semi_infinite_bar": ("mpm_semi_infinite_bar", "0.03 s", dict(history_every=7, frame_every=100, checkpoint_every=150)),
    "mpm_dem_rod": ("mpm_dem_rod", "0.006 s", dict(history_every=7, frame_every=20, checkpoint_every=25)),
    "pore_scale_bar": ("bar_cooling", "6 s", dict(history_every=1, frame_every=2, checkpoint_every=4)),
    "dem_uniaxial_tension_bar": ("dem_uniaxial_tension_bar", "20 us", dict(history_every=7, frame_every=40, checkpoint_every=45, end_strain=5e-6)),
    "mpm_dem_biaxial": ("mpm_dem_biaxial_dense", "0.01 s", dict(history_every=7, frame_every=10, checkpoint_every=9)),
}


def case_file(kind: str, tmp: Path) -> Path:
    stem, end, every = CASES[kind]
    return shortened(stem, end, every, tmp)


@pytest.mark.parametrize("kind", sorted(CASES))
def test_python_run_writes_what_thm_run_writes(thm_bin, tmp_path, kind):
    file = case_file(kind, tmp_path)
    run_cli(thm_bin, "run", file, "--out", tmp_path / "cli")

    seen = []
    run = thm.Run(file, out=tmp_path / "py")
    assert run.kind == kind
    run.step(3)
    # Reading state and monitors between steps must not change what is written.
    run.advance(steps=11, every=2, callback=lambda r: seen.append((r.steps_done, r.arrays(), r.monitor())))
    assert [s[0] for s in seen] == [4, 6, 8, 10, 12, 14][: len(seen)]
    run.advance()
    assert run.steps_done == run.n_steps
    with pytest.raises(thm.RunError, match="reached its end time"):
        run.step()
    outcome = run.finish()
    assert outcome["finished"] and outcome["steps"] == run_cli_steps(tmp_path / "cli")
    cli, py = output_files(tmp_path / "cli"), output_files(tmp_path / "py")
    assert sorted(cli) == sorted(py)
    for name in cli:
        assert cli[name] == py[name], name
    with pytest.raises(thm.RunError, match="closed"):
        run.step()


def run_cli_steps(out: Path) -> int:
    ckpts = sorted((out / "checkpoints").glob("step_*.ckpt"))
    return int(ckpts[-1].stem.split("_")[1])


def test_checkpoint_from_python_resumes_under_thm_run(thm_bin, tmp_path):
    file = case_file("mpm_dem_rod", tmp_path)
    run_cli(thm_bin, "run", file, "--out", tmp_path / "whole")
    run = thm.Run(file, out=tmp_path / "cut")
    run.step(17)  # not a checkpoint step of the schedule
    ckpt = run.checkpoint()
    assert ckpt.endswith("step_0000000017.ckpt")
    stopped = run.finish()
    assert not stopped["finished"] and stopped["steps"] == 17
    run_cli(thm_bin, "run", file, "--out", tmp_path / "cut", "--resume", ckpt)
    whole, cut = output_files(tmp_path / "whole"), output_files(tmp_path / "cut")
    for name in whole:
        assert whole[name] == cut[name], name


def test_checkpoint_from_thm_run_resumes_in_python(thm_bin, tmp_path):
    file = case_file("pore_scale_bar", tmp_path)
    run_cli(thm_bin, "run", file, "--out", tmp_path / "whole")
    shutil.copytree(tmp_path / "whole", tmp_path / "again")
    run = thm.Run(file, out=tmp_path / "again", resume=tmp_path / "again/checkpoints/step_0000000004.ckpt")
    assert run.steps_done == 4
    run.run()
    whole, again = output_files(tmp_path / "whole"), output_files(tmp_path / "again")
    for name in whole:
        assert whole[name] == again[name], name


def test_foreign_checkpoint_is_refused_with_the_cli_message(thm_bin, tmp_path):
    rod = case_file("mpm_dem_rod", tmp_path)
    cooling = case_file("lumped_cooling", tmp_path)
    run_cli(thm_bin, "run", cooling, "--out", tmp_path / "cooling")
    ckpt = tmp_path / "cooling/checkpoints/step_0000000025.ckpt"
    cli = run_cli(thm_bin, "run", rod, "--out", tmp_path / "a", "--resume", ckpt, check=False)
    assert cli.returncode != 0
    with pytest.raises(thm.RunError) as e:
        thm.Run(rod, out=tmp_path / "b", resume=ckpt)
    assert f"error: {e.value}" in cli.stderr


def lumped_dict(**particles):
    d = {
        "kind": "lumped_cooling",
        "time": {"step": "0.5 s", "end": "20 s"},
        "output": {"history_every": 4, "frame_every": 0, "checkpoint_every": 0},
        "particles": {
            "lattice": [6, 5],
            "spacing": "25 mm",
            "radius": "8 mm",
            "radius_spread": 0.5,
            "density": "7850 kg/m^3",
            "specific_heat": "0.46 kJ/(kg K)",
            "initial_temperature": "600 degC",
        },
        "fluid": {"temperature": "20 degC", "heat_transfer_coefficient": "25 W/(m^2 K)"},
    }
    d["particles"].update(particles)
    return d


@pytest.mark.parametrize(
    "change, key, message",
    [
        (dict(radiuss="8 mm"), "particles.radiuss", "unknown key"),
        (dict(radius="8 MPa"), "particles.radius", "not a length"),
        (dict(radius_spread=1.5), "particles.radius_spread", "must be in [0, 1)"),
        (dict(lattice=[0, 5]), "particles.lattice", "nx, ny"),
        (dict(density=object()), "particles.density", "no scenario form"),
    ],
)
def test_invalid_dict_names_the_key_path(tmp_path, change, key, message):
    with pytest.raises(thm.ScenarioError) as e:
        thm.Run(lumped_dict(**change), out=tmp_path / "x")
    assert e.value.key == key
    assert str(e.value).startswith(f"<dict>: {key}: ")
    assert message in str(e.value)
    with pytest.raises(thm.ScenarioError):
        thm.validate(lumped_dict(**change))
    assert not (tmp_path / "x" / "scenario.toml").exists()


def test_dict_and_file_give_the_same_key_error(thm_bin, tmp_path):
    file = tmp_path / "bad.toml"
    file.write_text(
        (Path(__file__).resolve().parents[3] / "scenarios/lumped_cooling.toml")
        .read_text()
        .replace('radius = "8 mm"', 'radius = "8 MPa"')
    )
    cli = run_cli(thm_bin, "run", file, "--out", tmp_path / "o", check=False)
    with pytest.raises(thm.ScenarioError) as e:
        thm.Run(file, out=tmp_path / "p")
    assert e.value.key == "particles.radius"
    assert f"error: {e.value}" in cli.stderr


def test_written_temperatures_cool_exactly_and_are_checkpointed(tmp_path):
    run = thm.Run(lumped_dict(), out=tmp_path / "a")
    run.step(10)
    n = run["sphere_temperature"].shape[0]
    written = np.linspace(500.0, 900.0, n)
    run["sphere_temperature"] = written
    assert run["sphere_temperature"].tobytes() == written.tobytes()
    run.step(1)
    # Lumped capacitance: T = T_f + (T_0 - T_f) exp(-dt / tau), tau = rho c r / (3 h).
    r = run["sphere_radius"]
    tau = 7850.0 * 460.0 * r / (3.0 * 25.0)
    expected = 293.15 + (written - 293.15) * np.exp(-0.5 / tau)
    assert np.max(np.abs(run["sphere_temperature"] / expected - 1.0)) < 1e-14
    ckpt = run.checkpoint()
    after = run["sphere_temperature"]
    run.finish()
    resumed = thm.Run(lumped_dict(), out=tmp_path / "a", resume=ckpt)
    assert resumed.steps_done == 11
    assert resumed["sphere_temperature"].tobytes() == after.tobytes()


def test_refused_writes_name_the_array_and_range(tmp_path):
    run = thm.Run(lumped_dict(), out=tmp_path / "a")
    with pytest.raises(thm.ScenarioError, match="not a writable array of this kind; writable: `sphere_temperature`"):
        run["sphere_radius"] = 1.0
    with pytest.raises(thm.ScenarioError, match=r"value 3 must be finite and in \(0, 100000\] K, got -1"):
        t = run["sphere_temperature"]
        t[3] = -1.0
        run["sphere_temperature"] = t
    with pytest.raises(KeyError, match="no state array `pressure`"):
        run["pressure"]
    # A refused write leaves the state as it was.
    assert np.all(run["sphere_temperature"] == 873.15)


def test_state_arrays_of_the_coupled_kinds(tmp_path):
    run = thm.Run(case_file("pore_scale_bar", tmp_path), out=tmp_path / "bar")
    run.step(3)
    a = run.arrays()
    n_pores = a["pore_pressure"].shape[0]
    for name in ["pore_liquid_fraction", "pore_volume", "pore_temperature", "pore_liquid_mass", "pore_gas_mass"]:
        assert a[name].shape == (n_pores,)
    assert np.all((a["pore_liquid_fraction"] >= 0) & (a["pore_liquid_fraction"] <= 1))
    assert np.all(np.isfinite(a["pore_pressure"])) and np.all(a["pore_volume"] > 0)
    # Heat only flows between the fixed end temperatures of the case and the initial field.
    t = a["cell_temperature"]
    assert t.min() >= 293.15 - 1e-9 and t.max() <= 368.16 + 1e-9
    assert a["sphere_position"].shape == (a["sphere_radius"].shape[0], 3)
    assert not any(info.writable for info in run.array_info().values())
    run.finish()

    rod = thm.Run(case_file("mpm_dem_rod", tmp_path), out=tmp_path / "rod")
    info = rod.array_info()
    assert info["point_stress"] == thm.ArrayInfo("Pa", 3, False)
    assert info["point_temperature"].writable and info["point_velocity"].writable
    v = rod["point_velocity"]
    rod["point_velocity"] = np.zeros_like(v)
    rod.step(1)
    assert rod["point_stress"].shape == (v.shape[0], 3)
    # B-Sect. 5.2.1: 50 points, each a regular packing of 400 disks.
    assert v.shape[0] == 50 and np.all(rod["point_rve_disks"] == 400)
    assert np.all(rod["point_dem_substeps"] >= 1)
    assert np.all(rod["point_void_ratio"] > 0) and np.all(rod["point_coordination"] > 0)
    rod.finish()


def test_gil_is_released_while_stepping(tmp_path):
    run = thm.Run(case_file("mpm_dem_rod", tmp_path), out=tmp_path / "rod")
    worker = threading.Thread(target=lambda: run.advance(steps=40))
    ticks = 0
    worker.start()
    start = time.perf_counter()
    while worker.is_alive():
        ticks += 1
    elapsed = time.perf_counter() - start
    worker.join()
    assert run.steps_done == 40
    # Holding the GIL through a step would leave this thread a switch interval (5 ms) now and
    # then; released, it spins freely: at least 10^5 iterations per second of stepping.
    assert elapsed > 0.05 and ticks / elapsed > 1e5


# The child installs Python's own Ctrl-C handler: a process started in the background of a
# shell without job control (`cmd &`, `nohup`) inherits SIGINT ignored, and Python then
# installs none, so the signal would never reach the run (how this test failed on CI
# machines that start the suite that way).
CHILD = textwrap.dedent(
    """
    import signal, sys, thm
    inherited = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    run = thm.Run(sys.argv[1], out=sys.argv[2])
    print("stepping", inherited, flush=True)
    try:
        run.advance()
    except KeyboardInterrupt as e:
        print("INTERRUPTED", run.steps_done, e, flush=True)
        sys.exit(130)
    print("FINISHED", flush=True)
    """
)


def test_ctrl_c_stops_after_the_step_with_a_checkpoint(thm_bin, tmp_path):
    long = shortened("mpm_dem_rod", "1 s", dict(history_every=7, frame_every=20, checkpoint_every=100000), tmp_path)
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    child = subprocess.Popen(
        [sys.executable, str(script), str(long), str(tmp_path / "cut")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    assert child.stdout.readline().startswith("stepping")
    time.sleep(1.0)
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=60)
    assert child.returncode == 130, (out, err)
    m = re.search(r"INTERRUPTED (\d+) stopped after step (\d+); checkpoint (\S+)", out)
    assert m, out
    k = int(m.group(1))
    assert int(m.group(2)) == k
    ckpt = Path(m.group(3))
    assert ckpt.name == f"step_{k:010d}.ckpt" and ckpt.exists()
    # Continue under `thm run` to 13 steps past the interruption: the same files as a run
    # that was never interrupted.
    end = shortened("mpm_dem_rod", f"{(k + 13) * 1e-4!r} s", dict(history_every=7, frame_every=20, checkpoint_every=100000), tmp_path / "..")
    run_cli(thm_bin, "run", end, "--out", tmp_path / "cut", "--resume", ckpt)
    run_cli(thm_bin, "run", end, "--out", tmp_path / "whole")
    whole, cut = output_files(tmp_path / "whole"), output_files(tmp_path / "cut")
    for name in whole:
        if name.startswith("checkpoints/"):
            continue  # the interrupted run also holds the checkpoint of its interruption
        assert whole[name] == cut[name], name
    last = f"checkpoints/step_{k + 13:010d}.ckpt"
    assert whole[last] == cut[last]


def test_example_script_plots_a_history(tmp_path):
    pytest.importorskip("matplotlib")
    file = case_file("lumped_cooling", tmp_path)
    example = Path(__file__).resolve().parents[1] / "examples/plot_history.py"
    done = subprocess.run(
        [sys.executable, str(example), str(file), "--out", str(tmp_path / "ex")],
        capture_output=True, text=True, timeout=300,
    )
    assert done.returncode == 0, done.stderr
    png = (tmp_path / "ex/history.png").read_bytes()
    assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 10_000


@pytest.mark.parametrize("scenario", sorted(p.stem for p in (Path(__file__).resolve().parents[3] / "scenarios").glob("*.toml")))
def test_every_scenario_stops_after_one_step_with_a_summary(tmp_path, scenario):
    # Stopping a run early (Ctrl-C, finish before the end) must leave a checkpoint and a
    # summary whatever the kind shows at that point.
    file = Path(__file__).resolve().parents[3] / "scenarios" / f"{scenario}.toml"
    run = thm.Run(file, out=tmp_path / "o")
    run.step(1)
    stopped = run.finish()
    assert not stopped["finished"] and stopped["steps"] == 1
    assert Path(stopped["checkpoint"]).exists()
    assert "interrupted" in (tmp_path / "o" / "summary.md").read_text()
