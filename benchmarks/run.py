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
import re
import sys
import time
from pathlib import Path

# one BLAS thread: the benchmarks measure one core, and idle BLAS worker threads that
# spin-wait after a matrix call would count in the process's CPU time (set before NumPy
# is imported)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import casadi  # noqa: E402
import numpy as np  # noqa: E402


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


def merge_sections(old: str, sections: list[str]) -> str:
    """``old`` with the sections whose ``## title`` line matches one of ``sections``
    replaced (new titles appended); everything before the first section is kept."""
    chunks = re.split(r"(?m)^(?=## )", old)
    head, parts = chunks[0], {c.split("\n", 1)[0]: c for c in chunks[1:]}
    for sec in sections:
        parts[sec.split("\n", 1)[0]] = sec
    return head.rstrip("\n") + "\n\n" + "\n".join(v.rstrip("\n") + "\n" for v in parts.values())


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--output", default="BENCHMARKS.md")
    ap.add_argument("--only", default="", help="substring of the module names to run")
    ap.add_argument("--merge", action="store_true",
                    help="replace only the sections run now in an existing output file (each "
                         "section states when it ran)")
    ap.add_argument("--note", default="", help="a line about this run (e.g. CPU pinning)")
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
        stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        note = f"; {args.note}" if args.note else ""
        sections.append(f"## {mod.TITLE}\n\n{body.strip()}\n\n_(section ran in {dt:.1f} s, "
                        f"finished {stamp}{note})_\n")
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    out = Path(args.output)
    if args.merge and out.is_file():
        text = merge_sections(out.read_text(), sections)
    else:
        text = ("# Benchmarks\n\nWritten by `make bench` (benchmarks/run.py); every figure below "
                "was measured in the run whose time its section states.\n\n"
                f"- date: {now}\n- machine: {_machine()}\n\n" + "\n".join(sections))
    out.write_text(text)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
