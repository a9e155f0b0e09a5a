"""The one figure-folder check the vehicle figures share (``plotting.figure_directory``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from maglevkit.errors import InputError
from maglevkit.plotting import figure_directory


def test_creates_only_the_last_level(tmp_path: Path) -> None:
    out = figure_directory(tmp_path / "figs")
    assert out == tmp_path / "figs" and out.is_dir()
    assert figure_directory(out) == out          # an existing folder is used as it is


def test_a_missing_parent_is_refused_naming_both(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="does not exist") as err:
        figure_directory(tmp_path / "typo" / "figs")
    assert str(tmp_path / "typo" / "figs") in str(err.value)
    assert not (tmp_path / "typo").exists()      # nothing was built
