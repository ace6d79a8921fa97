"""Runs a scenario from Python and plots its history with matplotlib.

    python crates/thm-py/examples/plot_history.py [SCENARIO.toml] [--out DIR]

Steps the scenario to its end (Ctrl-C stops it after the current step with a checkpoint),
samples a state array every 100 steps through a callback, then plots every monitored column of
`history.csv` against time, with the sampled spread of the kind's temperature array, into
`DIR/history.png`.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import thm

ROOT = Path(__file__).resolve().parents[3]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default=ROOT / "scenarios/lumped_cooling.toml")
    parser.add_argument("--out", default=None, help="output folder (default runs/<stem>-py)")
    args = parser.parse_args()
    scenario = Path(args.scenario)
    out = Path(args.out) if args.out else Path("runs") / f"{scenario.stem}-py"

    run = thm.Run(scenario, out=out)
    temperature = next((n for n in run.array_info() if n.endswith("temperature")), None)
    samples = []

    def sample(r: thm.Run) -> None:
        if temperature is not None:
            t = r[temperature]
            samples.append((r.time, t.min(), t.max()))

    outcome = run.run(every=100, callback=sample)
    print(f"{run.kind}: {outcome['steps']} steps, results in {out}")

    history = out / "history.csv"
    header = history.read_text().splitlines()[0].split(",")
    data = np.loadtxt(history, delimiter=",", skiprows=1, ndmin=2)
    columns = header[1:]
    fig, axes = plt.subplots(len(columns), 1, figsize=(7, 2.2 * len(columns)), sharex=True)
    for k, (ax, name) in enumerate(zip(np.atleast_1d(axes), columns)):
        ax.plot(data[:, 0], data[:, k + 1], label="history.csv")
        if samples and name.startswith(("min_temperature", "max_temperature")):
            s = np.array(samples)
            col = 1 if name.startswith("min") else 2
            ax.plot(s[:, 0], s[:, col], "o", ms=3, label=f"{temperature} (callback)")
            ax.legend(fontsize=7)
        ax.set_ylabel(name, fontsize=8)
    np.atleast_1d(axes)[-1].set_xlabel(header[0])
    fig.tight_layout()
    fig.savefig(out / "history.png", dpi=120)
    print(f"plot: {out / 'history.png'}")


if __name__ == "__main__":
    main()
