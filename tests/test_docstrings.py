"""Every public function, method and constructor documents its parameters (numpy style).

The audit (``tools/docstring_audit.py``) lists public callables whose docstring leaves a
parameter out of its Parameters / Other Parameters / Attributes section. The callables not
yet documented are listed in ``tests/docstring_debt.txt``; that list may only shrink: a
new public callable with an undocumented parameter fails, and so does a listed one that
has since been documented (remove it from the list).
"""

from __future__ import annotations

from pathlib import Path

from .conftest import load_script

ROOT = Path(__file__).resolve().parent.parent
DEBT = Path(__file__).resolve().parent / "docstring_debt.txt"


def _audit():  # type: ignore[no-untyped-def]
    return load_script(ROOT / "tools" / "docstring_audit.py")


def _debt() -> set[str]:
    return {line.split(":")[0].strip() for line in DEBT.read_text().splitlines()
            if line.strip() and not line.startswith("#")}


def test_documented_names_parser() -> None:
    doc = """Summary.

    Parameters
    ----------
    gap_m : float
        Air gap [m].
    a, b : int
        Two at once.
    **options
        Passed on.

    Returns
    -------
    force_N : float
        Not a parameter.
    """
    assert _audit().documented_names(doc) == {"gap_m", "a", "b", "options"}


def test_no_new_undocumented_parameters() -> None:
    gaps = _audit().gaps()
    new = sorted(set(gaps) - _debt())
    assert not new, "undocumented parameters (add a Parameters section with units):\n" + "\n".join(
        f"{k}: {', '.join(gaps[k])}" for k in new)


def test_debt_list_is_not_stale() -> None:
    gaps = _audit().gaps()
    done = sorted(_debt() - set(gaps))
    assert not done, "documented now - remove from tests/docstring_debt.txt:\n" + "\n".join(done)
