"""The one CasADi buffer binder (``maglevkit.models.compiled.BoundCall``)."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from maglevkit.errors import SolverError
from maglevkit.models.compiled import BoundCall


def _f() -> ca.Function:
    x, m = ca.SX.sym("x", 3), ca.SX.sym("M", 2, 3)
    return ca.Function("f", [x, m], [ca.mtimes(m, x), ca.sum1(x)])


def test_in_place_call_equals_casadi_call() -> None:
    f = _f()
    x = np.array([1.0, -2.0, 0.5])
    m = np.arange(6.0).reshape(2, 3)
    ref = [np.asarray(r).ravel() for r in f(x, m)]
    bound = BoundCall(f)
    bound.args[0][:] = x
    bound.args[1][:] = m.ravel(order="F")       # CasADi's nonzeros are column-major
    bound.eval()
    # same arithmetic, same order of operations in CasADi's VM: exactly equal
    assert np.array_equal(bound.res[0], ref[0]) and np.array_equal(bound.res[1], ref[1])
    out = bound(x, m.ravel(order="F"))
    assert np.array_equal(out[0], ref[0])
    out[0][:] = 0.0                                # copies: the bound output is unchanged
    assert np.array_equal(bound.res[0], ref[0])


def test_given_arrays_are_bound_by_pointer() -> None:
    f = _f()
    block = np.zeros(4)
    x = np.zeros(3)
    bound = BoundCall(f, args={0: x}, res={0: block[:2], 1: block[3:]})
    bound.args[1][:] = 1.0
    x[:] = [1.0, 2.0, 3.0]                         # written by the caller, seen by the call
    bound.eval()
    assert bound.args[0] is x
    assert np.array_equal(block, [6.0, 6.0, 0.0, 6.0])


def test_later_binding_of_an_input_block() -> None:
    f = _f()
    bound = BoundCall(f, unbound=(0,))
    assert bound.args[0] is None
    rows = np.arange(6.0).reshape(2, 3)
    bound.args[1][:] = 1.0
    for k in range(2):
        bound.bind_arg(0, rows[k])
        bound.eval()
        assert bound.res[1][0] == rows[k].sum()


@pytest.mark.parametrize("bad", [np.zeros(4), np.zeros(3, dtype=np.float32),
                                 np.zeros(6)[::2]])
def test_wrong_buffers_are_refused(bad: np.ndarray) -> None:
    with pytest.raises(SolverError, match=r"input 0 of 'f' must be bound to 3 contiguous"):
        BoundCall(_f(), args={0: bad})
