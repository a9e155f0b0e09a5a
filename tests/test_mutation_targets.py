"""The mutation check's targets still exist (tools/mutation.py).

A mutation whose snippet no longer occurs in its file is reported "snippet not found" and
checks nothing: six had gone stale after code moved.  Every snippet must occur exactly once
in its file, and every test it names must exist as a test function.
"""
from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _mutations() -> tuple:
    spec = importlib.util.spec_from_file_location("_mutation_tool", ROOT / "tools" / "mutation.py")
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod            # dataclasses look the module up by name
    spec.loader.exec_module(mod)
    return tuple(mod.MUTATIONS)


MUTATIONS = _mutations()


@pytest.mark.parametrize("mutation", MUTATIONS, ids=[m.name for m in MUTATIONS])
def test_snippet_occurs_once_and_named_tests_exist(mutation) -> None:  # type: ignore[no-untyped-def]
    source = (ROOT / mutation.file).read_text()
    assert source.count(mutation.snippet) == 1, (mutation.name, mutation.file)
    assert mutation.replacement != mutation.snippet
    for node in mutation.tests:
        path, _, rest = node.partition("::")
        text = (ROOT / path).read_text()
        func = rest.split("::")[-1].split("[")[0]
        assert re.search(rf"^\s*def {re.escape(func)}\(", text, re.M), node
