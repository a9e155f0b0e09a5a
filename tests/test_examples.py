"""The gallery's example scripts run as they are and draw their figures."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("plot_*.py"))


def test_examples_exist() -> None:
    # the gallery must not silently become empty (a renamed folder, a wrong glob)
    assert len(EXAMPLES) >= 3


@pytest.mark.parametrize("script", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs(script: Path, tmp_path: Path) -> None:
    # run in a fresh interpreter, as a user would; save every open figure to check it drew
    runner = (
        "import runpy, sys, matplotlib\n"
        "matplotlib.use('Agg')\n"
        "import matplotlib.pyplot as plt\n"
        f"runpy.run_path({str(script)!r}, run_name='__main__')\n"
        "figs = [plt.figure(n) for n in plt.get_fignums()]\n"
        "assert figs, 'the example drew no figure'\n"
        f"for k, f in enumerate(figs): f.savefig({str(tmp_path)!r} + f'/fig{{k}}.png')\n"
    )
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, "-c", runner], capture_output=True, text=True,
                          cwd=tmp_path, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    pngs = list(tmp_path.glob("fig*.png"))
    assert pngs and all(p.stat().st_size > 5000 for p in pngs)   # a real plot, not a blank canvas
