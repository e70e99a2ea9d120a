"""The cost of calling navfuse from Python against the command line, on the same
configuration: `navfuse run CONFIG --out DIR` (a subprocess, the files written) against
`navfuse.run(CONFIG)` (the DataFrames in memory) and `navfuse.run(CONFIG, out=DIR)`
(both). Best of --repeat runs each, alternated.

    python python/bench/overhead.py [CONFIG ...] [--repeat 5] [--navfuse target/release/navfuse]

Default configurations: the shipped demo, and the KF-GINS stand-in (one hour at 200 Hz,
../shared/data/kf-gins; skipped with a message when absent).
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import navfuse

ROOT = Path(__file__).resolve().parents[2]


def best(f, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("configs", nargs="*")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--navfuse", default=str(ROOT / "target" / "release" / "navfuse"))
    a = ap.parse_args()
    configs = [Path(c) for c in a.configs] or [ROOT / "examples/demo/drive_excerpt.toml",
                                               ROOT / "examples/kfgins-synthetic.toml"]
    print(f"{'configuration':<28}{'epochs':>9}{'CLI [s]':>10}{'py mem [s]':>12}{'py+files [s]':>14}{'mem/CLI':>9}{'files/CLI':>11}")
    for cfg in configs:
        if not cfg.exists():
            print(f"{cfg.name}: skipped (missing)")
            continue
        try:
            navfuse.run(cfg)  # warm the page cache
        except navfuse.InputError as e:
            print(f"{cfg.name}: skipped ({e.file}: not readable here; ../shared/data missing?)")
            continue
        with tempfile.TemporaryDirectory() as tmp:
            cli = lambda: subprocess.run([a.navfuse, "run", str(cfg), "--out", tmp + "/cli", "-q"],
                                         check=True)
            mem = lambda: navfuse.run(cfg)
            files = lambda: navfuse.run(cfg, out=tmp + "/py")
            t = {"cli": [], "mem": [], "files": []}
            for _ in range(a.repeat):
                for k, f in (("cli", cli), ("mem", mem), ("files", files)):
                    t[k].append(best(f, 1))
            n = len(navfuse.run(cfg).solution)
        c, m, f = min(t["cli"]), min(t["mem"]), min(t["files"])
        print(f"{cfg.name:<28}{n:>9}{c:>10.3f}{m:>12.3f}{f:>14.3f}{m / c:>9.2f}{f / c:>11.2f}")


if __name__ == "__main__":
    sys.exit(main())
