"""Shared fixtures: the repository's example data, the `mtec` command as the reference the
module must agree with, and simulated scenarios."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

import mtec

REPO = Path(__file__).resolve().parents[4]
EXAMPLES = REPO / "examples"


def _mtec_binary():
    """The CLI built from this workspace: $MTEC_BIN, else target/debug/mtec, else PATH."""
    env = os.environ.get("MTEC_BIN")
    if env:
        return env
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for profile in ("debug", "release"):
        p = target / profile / "mtec"
        if p.is_file():
            return str(p)
    return shutil.which("mtec")


class Cli:
    """Runs `mtec ARGS...`; the reference numbers and files the module must reproduce."""

    def __init__(self, binary):
        self.binary = binary

    def run(self, *args, cwd=None):
        r = subprocess.run(
            [self.binary, *map(str, args)], capture_output=True, text=True, cwd=cwd
        )
        assert r.returncode == 0, f"mtec {' '.join(map(str, args))}: {r.stderr}"
        return r.stdout

    def json(self, *args):
        return json.loads(self.run(*args))


@pytest.fixture(scope="session")
def cli():
    b = _mtec_binary()
    if b is None:
        # in CI the CLI is always built first (.ci/run): its absence is a failure there
        if os.environ.get("CI"):
            pytest.fail("the mtec CLI (the reference of these tests) was not found: set MTEC_BIN")
        pytest.skip("the mtec CLI is not built (cargo build -p mtec-cli, or set MTEC_BIN)")
    return Cli(b)


@pytest.fixture(scope="session")
def sim(tmp_path_factory):
    """`sim(scenario)`: the scenario's files (seed 1), simulated once per session."""
    cache = {}

    def get(scenario):
        if scenario not in cache:
            cache[scenario] = mtec.simulate(scenario, tmp_path_factory.mktemp(scenario), seed=1)
        return cache[scenario]

    return get


def read_csv_columns(path):
    """A CSV file's columns as numpy arrays (floats where every cell is a number)."""
    import numpy as np

    lines = [l for l in Path(path).read_text().splitlines() if l and not l.startswith("#")]
    header = lines[0].split(",")
    cells = [l.split(",") for l in lines[1:]]
    cols = {}
    for j, name in enumerate(header):
        col = [c[j] for c in cells]
        try:
            cols[name] = np.array([float(x) for x in col])
        except ValueError:
            cols[name] = np.array(col)
    return cols
