"""Python-side overhead per step and the cost of reading state arrays.

    cargo build --release -p thm-benchmarks --bin run_steps
    pip install ./crates/thm-py
    python benchmarks/python/step_overhead.py [--rounds 7]

For each scenario, alternating rounds time the same steps driven
  rust     by `run_steps` (the driver alone, no Python),
  advance  by one `Run.advance(steps=N)` call (Rust loop; GIL released and Ctrl-C checked
           every step),
  step     by a Python loop of `Run.step()`,
  callback by `Run.advance` with a callback every step that reads one state array,
and prints the median seconds per step and each one's overhead against `rust`. Then the median
time to read each state array. Not a timed test: run it on a quiet machine.
"""

from __future__ import annotations

import argparse
import re
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import thm

ROOT = Path(__file__).resolve().parents[2]
RUN_STEPS = ROOT / "target/release/run_steps"


def lumped_10k(tmp: Path) -> Path:
    text = (ROOT / "scenarios/lumped_cooling.toml").read_text()
    text = re.sub(r"(?m)^lattice = .*$", "lattice = [100, 100]", text)
    text = re.sub(r"(?m)^spacing = .*$", 'spacing = "25 mm"', text)
    text = re.sub(r"(?m)^history_every = .*$", "history_every = 1000000", text)
    text = re.sub(r"(?m)^frame_every = .*$", "frame_every = 0", text)
    text = re.sub(r"(?m)^checkpoint_every = .*$", "checkpoint_every = 0", text)
    path = tmp / "lumped_10k.toml"
    path.write_text(text)
    return path


def quiet_copy(name: str, tmp: Path) -> Path:
    text = (ROOT / f"scenarios/{name}.toml").read_text()
    text = re.sub(r"(?m)^history_every = .*$", "history_every = 1000000", text)
    text = re.sub(r"(?m)^frame_every = .*$", "frame_every = 0", text)
    text = re.sub(r"(?m)^checkpoint_every = .*$", "checkpoint_every = 0", text)
    path = tmp / f"{name}.toml"
    path.write_text(text)
    return path


def rust_round(file: Path, out: Path, steps: int) -> float:
    done = subprocess.run(
        [str(RUN_STEPS), str(file), str(out), str(steps), "1"],
        check=True, capture_output=True, text=True,
    )
    return float(done.stdout.split()[0])


def python_round(file: Path, out: Path, steps: int, mode: str, array: str) -> float:
    run = thm.Run(file, out=out)
    t = time.perf_counter()
    if mode == "advance":
        run.advance(steps=steps)
    elif mode == "step":
        for _ in range(steps):
            run.step()
    else:
        run.advance(steps=steps, every=1, callback=lambda r: r[array])
    return (time.perf_counter() - t) / steps


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()
    if not RUN_STEPS.exists():
        raise SystemExit(f"{RUN_STEPS} missing: cargo build --release -p thm-benchmarks --bin run_steps")
    tmp = Path(tempfile.mkdtemp(prefix="thm-overhead-"))
    cases = [
        ("lumped_cooling, 10^4 spheres", lumped_10k(tmp), 2000, "sphere_temperature"),
        ("mpm_dem_rod, 50 points x 400 disks", quiet_copy("mpm_dem_rod", tmp), 100, "point_stress"),
    ]
    print("| scenario | driver | median s/step | overhead vs rust |")
    print("|---|---|---|---|")
    for label, file, steps, array in cases:
        times = {m: [] for m in ["rust", "advance", "step", "callback"]}
        for k in range(args.rounds):
            for mode in times:
                out = tmp / f"{file.stem}_{mode}_{k}"
                if mode == "rust":
                    times[mode].append(rust_round(file, out, steps))
                else:
                    times[mode].append(python_round(file, out, steps, mode, array))
                shutil.rmtree(out, ignore_errors=True)
        base = statistics.median(times["rust"])
        for mode, ts in times.items():
            m = statistics.median(ts)
            print(f"| {label} | {mode} | {m:.3e} | {100 * (m / base - 1):+.1f} % |")

    print()
    print("| scenario | array | shape | median read time |")
    print("|---|---|---|---|")
    for label, file, _, _ in cases:
        run = thm.Run(file, out=tmp / f"{file.stem}_arrays")
        run.step(2)
        for name in run.array_info():
            ts = []
            for _ in range(51):
                t = time.perf_counter()
                a = run[name]
                ts.append(time.perf_counter() - t)
            print(f"| {label} | {name} | {a.shape} | {statistics.median(ts) * 1e6:.1f} us |")
        run.finish()
    shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
