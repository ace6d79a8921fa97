"""Wall time of every scenario under `scenarios/`, measured on a sample of its steps.

    pip install ./crates/thm-py
    python benchmarks/python/scenario_costs.py [--budget 8] [--max-steps 400] [NAME ...]

Each scenario is opened with its outputs off (no history rows, frames or checkpoints before
the end), stepped one step at a time until `--budget` seconds of stepping or `--max-steps`
steps, and reported with the time to open it (packing, consolidation), the median step, the
disk-steps per step of the MPM x DEM kinds (sum over points of RVE disks x DEM steps of the
step, from the state arrays `point_rve_disks` and `point_dem_substeps`), their rate, and the
projected wall time of the whole run (open + steps x median step). The thread count is rayon's
default (RAYON_NUM_THREADS, else one per core). Prints a Markdown table; not a timed test.
"""

from __future__ import annotations

import argparse
import re
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

import thm

ROOT = Path(__file__).resolve().parents[2]


def quiet_copy(path: Path, tmp: Path) -> Path:
    text = path.read_text()
    for key, value in [("history_every", "1000000000"), ("frame_every", "0"), ("checkpoint_every", "0")]:
        text, n = re.subn(rf"(?m)^{key} = .*$", f"{key} = {value}", text)
        if n == 0:
            text = re.sub(r"(?m)^\[output\]$", f"[output]\n{key} = {value}", text)
            if f"{key} = {value}" not in text:
                text = text.replace("[time]", f"[output]\n{key} = {value}\n\n[time]", 1)
    out = tmp / path.name
    out.write_text(text)
    return out


def hms(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.1f} s"
    if seconds < 7200:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("names", nargs="*", help="scenario file stems (default: all)")
    parser.add_argument("--budget", type=float, default=8.0, help="seconds of stepping per scenario")
    parser.add_argument("--max-steps", type=int, default=400)
    args = parser.parse_args()
    files = sorted((ROOT / "scenarios").glob("*.toml"))
    if args.names:
        files = [f for f in files if f.stem in args.names]
    tmp = Path(tempfile.mkdtemp(prefix="thm-costs-"))
    print("| scenario | kind | steps of the run | open | median step | steps timed | disk-steps per step | M disk-steps/s | projected wall time |")
    print("|---|---|---|---|---|---|---|---|---|")
    for f in files:
        file = quiet_copy(f, tmp)
        t0 = time.perf_counter()
        run = thm.Run(file, out=tmp / f.stem)
        opened = time.perf_counter() - t0
        info = run.array_info()
        rve = "point_rve_disks" in info
        times, work = [], []
        start = time.perf_counter()
        while (
            run.steps_done < run.n_steps - 1
            and len(times) < args.max_steps
            and time.perf_counter() - start < args.budget
        ):
            t = time.perf_counter()
            run.step()
            times.append(time.perf_counter() - t)
            if rve:
                work.append(float(np.dot(run["point_rve_disks"], run["point_dem_substeps"])))
        step = statistics.median(times) if times else float("nan")
        disk_steps = statistics.median(work) if work else None
        rate = f"{disk_steps / step / 1e6:.2f}" if disk_steps else "-"
        projected = opened + run.n_steps * step
        print(
            f"| {f.stem} | {run.kind} | {run.n_steps} | {opened:.2f} s | {step * 1e3:.3g} ms | {len(times)} "
            f"| {f'{disk_steps:.3e}' if disk_steps else '-'} | {rate} | {hms(projected)} |",
            flush=True,
        )
        run.finish()
        shutil.rmtree(tmp / f.stem, ignore_errors=True)
    shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
