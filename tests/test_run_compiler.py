"""The compiler runner ends the whole process group on a time-out (split26 found that
``subprocess.run(timeout=)`` killed the ``cc`` driver only and left ``cc1`` running as an
orphan for minutes)."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from maglevkit.models.compiled import run_compiler

pytestmark = pytest.mark.skipif(os.name != "posix", reason="process groups are POSIX")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie (exited, not yet reaped by init) counts as gone
    stat = Path(f"/proc/{pid}/stat")
    return not (stat.exists() and stat.read_text().split(")")[-1].split()[0] == "Z")


def test_a_timed_out_compiler_leaves_no_grandchild(tmp_path: Path) -> None:
    pidfile = tmp_path / "grandchild.pid"
    # a "driver" that starts a long-running "cc1" and waits for it, as cc does
    driver = ("import subprocess, sys; "
              "p = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)']); "
              f"open({str(pidfile)!r}, 'w').write(str(p.pid)); p.wait()")
    t0 = time.monotonic()
    with pytest.raises(subprocess.TimeoutExpired):
        run_compiler([sys.executable, "-c", driver], timeout_s=2.0)
    assert time.monotonic() - t0 < 20          # returns at the time-out, not after 60 s
    grandchild = int(pidfile.read_text())
    deadline = time.monotonic() + 5
    while _alive(grandchild) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(grandchild), "the compiler's child outlived the time-out"


def test_a_finished_command_gives_its_output_and_code() -> None:
    done = run_compiler([sys.executable, "-c",
                         "import sys; print('out'); print('err', file=sys.stderr); sys.exit(3)"])
    assert (done.returncode, done.stdout.strip(), done.stderr.strip()) == (3, "out", "err")
