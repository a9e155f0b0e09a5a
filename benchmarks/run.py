"""Run every benchmarks/bench_*.py module and write BENCHMARKS.md.

Contract for a benchmark module: it defines ``TITLE: str`` and ``run() -> str``, which
does the measurement and returns a Markdown section body (tables preferred, figures as
ratios where possible: speed-up, real-time factor).  Modules run in name order.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import importlib.util
import os
import platform
import sys
import time
from pathlib import Path

import casadi
import numpy as np


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{cpu}; {os.cpu_count()} logical cores; Python {platform.python_version()}; "
            f"CasADi {casadi.__version__}; NumPy {np.__version__}; {platform.system()} "
            f"{platform.release()}")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--output", default="BENCHMARKS.md")
    ap.add_argument("--only", default="", help="substring of the module names to run")
    args = ap.parse_args()
    here = Path(__file__).parent
    sections = []
    for path in sorted(here.glob("bench_*.py")):
        if args.only and args.only not in path.stem:
            continue
        spec = importlib.util.spec_from_file_location(path.stem, path)
        assert spec and spec.loader
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        print(f"running {path.name} ...", flush=True)
        t0 = time.perf_counter()
        body = mod.run()
        dt = time.perf_counter() - t0
        sections.append(f"## {mod.TITLE}\n\n{body.strip()}\n\n_(section ran in {dt:.1f} s)_\n")
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    text = ("# Benchmarks\n\nWritten by `make bench` (benchmarks/run.py); every figure below was "
            f"measured in that run.\n\n- date: {now}\n- machine: {_machine()}\n\n"
            + "\n".join(sections))
    Path(args.output).write_text(text)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
