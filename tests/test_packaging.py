"""The package installs from a built wheel with all of its data (magnet files, C sources, headers)."""

from __future__ import annotations

import fnmatch
import os
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "src" / "maglevkit"


def _data_files() -> list[str]:
    """Every file of the package that is not Python source, relative to the package."""
    skip = {".py", ".pyc"}
    return sorted(p.relative_to(PACKAGE).as_posix() for p in PACKAGE.rglob("*")
                  if p.is_file() and p.suffix not in skip and "__pycache__" not in p.parts)


def test_package_data_globs_cover_every_data_file() -> None:
    # a data file that no package-data glob names is missing from the wheel (and so from
    # every non-editable install) while all editable tests still pass
    globs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-data"]["maglevkit"]
    files = _data_files()
    assert files, "no data files found: wrong package path?"
    missing = [f for f in files if not any(fnmatch.fnmatch(f, g) and f.count("/") == g.count("/")
                                           for g in globs)]
    assert not missing, f"not in [tool.setuptools.package-data]: {missing}"


@pytest.mark.slow
def test_wheel_installs_and_runs_the_demo(tmp_path: Path) -> None:
    # build the wheel, install it into a fresh venv (dependencies from the package index),
    # run the CLI from outside the source tree: the bundled files must come from the wheel
    dist = tmp_path / "dist"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", str(dist),
                    str(ROOT)], check=True, timeout=600)
    wheel = next(dist.glob("maglevkit-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    for f in _data_files():
        assert f"maglevkit/{f}" in names
    # without PYTHONPATH: a source tree on it would make pip and Python see the source,
    # not the wheel
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["MPLBACKEND"] = "Agg"
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    python = env_dir / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "--quiet", str(wheel)], check=True,
                   timeout=1200, env=env, cwd=tmp_path)
    assert (env_dir / "bin" / "maglevkit").exists()
    out = tmp_path / "out"
    proc = subprocess.run([str(env_dir / "bin" / "maglevkit"), "demo", "--out", str(out)],
                          capture_output=True, text=True, cwd=tmp_path, env=env, timeout=1800)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert list(out.glob("*.png")), "the demo wrote no figure"
