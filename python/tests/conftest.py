"""Shared fixtures: the repository root, the navfuse binary (for the comparisons with
the CLI), a short simulated scenario."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "examples" / "demo" / "drive_excerpt.toml"


def navfuse_bin():
    """The navfuse command: $NAVFUSE_BIN, the workspace's release build, or PATH."""
    for p in (os.environ.get("NAVFUSE_BIN"), ROOT / "target" / "release" / "navfuse",
              shutil.which("navfuse")):
        if p and Path(p).is_file():
            return str(p)
    return None


@pytest.fixture(scope="session")
def cli():
    b = navfuse_bin()
    if b is None:
        pytest.skip("skipped: no navfuse binary (cargo build --release, or set NAVFUSE_BIN)")

    def call(*args, check=True):
        return subprocess.run([b, *map(str, args)], check=check, capture_output=True, text=True)

    return call


@pytest.fixture(scope="session")
def cli_demo(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli-demo")
    cli("run", DEMO, "--out", out, "-q")
    return out


# A short car scenario (60 s of seed001's drive at 50 Hz), for the simulator and the
# Monte Carlo tests.
SHORT_SCENARIO = ROOT / "python" / "tests" / "data" / "short_car.toml"
