"""Shared fixtures: the `thm` command of this checkout and shortened copies of the scenarios."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
SCENARIOS = ROOT / "scenarios"


def thm_binary() -> Path:
    """`thm` built from this checkout (THM_BIN overrides); built in release if missing."""
    if "THM_BIN" in os.environ:
        return Path(os.environ["THM_BIN"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary = target / "release" / "thm"
    if not binary.exists():
        subprocess.run(
            ["cargo", "build", "--release", "-q", "-p", "thm-cli"], cwd=ROOT, check=True
        )
    return binary


@pytest.fixture(scope="session")
def thm_bin() -> Path:
    return thm_binary()


def shortened(name: str, end: str, every: dict, tmp: Path) -> Path:
    """scenarios/NAME.toml with `[time] end` and `[output]` intervals replaced."""
    text = (SCENARIOS / f"{name}.toml").read_text()
    text, n = re.subn(r'(?m)^end = .*$', f'end = "{end}"', text, count=1)
    assert n == 1
    for key, value in every.items():
        text, n = re.subn(rf"(?m)^{key} = .*$", f"{key} = {value}", text, count=1)
        assert n == 1, key
    path = tmp / f"{name}.toml"
    path.write_text(text)
    return path


def run_cli(thm_bin: Path, *args, check=True, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(thm_bin), *map(str, args)], capture_output=True, text=True, check=check, **kw
    )


def output_files(out: Path) -> dict:
    """Every file a run wrote except the summary (it records the wall time), by relative
    path, as bytes."""
    files = {}
    for p in sorted(out.rglob("*")):
        if p.is_file() and p.name != "summary.md":
            files[str(p.relative_to(out))] = p.read_bytes()
    return files
