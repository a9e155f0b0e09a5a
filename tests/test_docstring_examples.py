"""The ``Examples`` sections of the package's docstrings run and print what they show
(every module of the package with a ``>>>`` example is collected)."""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
MODULES = sorted(
    ".".join(p.relative_to(SRC).with_suffix("").parts)
    for p in (SRC / "maglevkit").rglob("*.py")
    if ">>>" in p.read_text()
)


def test_some_modules_have_examples() -> None:
    assert "maglevkit.reduced.bank" in MODULES and "maglevkit.reduced.stepper" in MODULES


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name: str) -> None:
    mod = importlib.import_module(name)
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0
    assert result.failed == 0
