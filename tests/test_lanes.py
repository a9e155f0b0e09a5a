"""SIMD-lane code generation (reduced/lanes.py): the same numbers as CasADi, every lane width.

The lane kernel translates a CasADi function's algorithm instruction by instruction, so
its results must equal CasADi's own evaluation bit for bit (same IEEE operations in the
same order; compiled with -ffp-contract=off, so no fused multiply-adds).  The checks
compare with ``numpy.testing.assert_array_equal`` (exact; NaN equals NaN), on random and
on special inputs (NaN, inf, signed zeros, indices outside the table, non-integral
indices), for every width the generator offers on this machine and with instance counts
that are not multiples of the width (the tail block).
"""

from __future__ import annotations

import ctypes
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import maglevkit as mk
from maglevkit.errors import InputError
from maglevkit.models.compiled import build_source, find_compiler
from maglevkit.reduced.bank import MagnetBank
from maglevkit.reduced.lanes import LaneInput, lane_source, lane_target

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="needs a C compiler")

N = 7            # instances: one full block of 4 and a tail of 3 (or 3 blocks of 2 + 1)
TABLE = np.linspace(-3.0, 5.0, 80) ** 3


def _widths() -> list[tuple[int, bool]]:
    w, avx2, _ = lane_target()
    out = [(1, False), (2, False)]
    if avx2:
        out.append((4, True))
    return out


def _function() -> ca.Function:
    """Every translated operation once, and gathers from a constant table: at an index
    "integer offsets + base" (the fast path when the base is whole and inside the table)
    and at an arbitrary computed index."""
    x, y = ca.MX.sym("x"), ca.MX.sym("y")
    p = ca.MX.sym("p", 3)
    table = ca.MX(ca.DM(TABLE))
    base = ca.floor(x) * p[0]                       # whole, or NaN/inf, or out of range
    idx = ca.DM(np.array([0.0, 1.0, 2.0, 3.0, 7.0, 4.0])) + base
    g = table[idx]
    h = table[ca.fabs(y) * 3.3]                     # non-integral index: truncated
    c5 = x > -5.0                                   # one node for the selects below
    e = [x + y, x - y, x * y, x / y, -x, 2 * x, x ** 2, 1 / y, ca.fabs(y),
         ca.floor(y), ca.ceil(x), ca.fmin(x, y), ca.fmax(x, y), ca.fmin(p[1], x),
         ca.fmax(x, p[1]), x < y, x <= y, x == y, x != y, ca.logic_and(x, y),
         ca.logic_or(x, p[2]), ca.logic_not(x), ca.if_else(x < p[1], y, 0.0),
         ca.sqrt(ca.fabs(x)), ca.exp(-ca.fabs(y)), ca.log(ca.fabs(x) + 1), ca.sin(x),
         ca.cos(y), ca.tanh(x), ca.atan2(x, y), ca.power(ca.fabs(x), y), ca.sign(y),
         ca.fmod(x, 0.7), ca.erf(y), g[0] + g[1] * g[2] - g[3] * g[4] + g[5], h, p[0] * x,
         # two-sided selects (if_else_zero(c, a) + if_else_zero(!c, b)): a branch on "c
         # in every lane" in the lanes' C; true in every lane of a block without NaN x,
         # mixed in others; and the operands the other way round, with a signed zero
         # (ceil gives -0 for y in (-1, 0))
         ca.if_else(c5, ca.ceil(y), y * p[2]), ca.if_else(x < p[1], ca.ceil(y), 2 * y),
         ca.if_else(ca.logic_not(c5), 3 * y, 0.0) + ca.if_else(c5, ca.ceil(y), 0.0),
         # fmin/fmax with a literal operand (AVX2: a shorter compare), signed zeros
         ca.fmax(ca.ceil(y), 0.0), ca.fmin(ca.ceil(y), 0.0), ca.fmin(x, 1.5),
         ca.fmax(-0.0 + ca.ceil(y), -1.0)]
    return ca.Function("probe", [x, y, p], e)


def _inputs(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    x = rng.uniform(-4.0, 12.0, N)
    y = rng.uniform(-3.0, 3.0, N)
    x[:4] = [np.nan, np.inf, -0.0, 1e300]           # special values in the first block
    y[4:7] = [0.0, -np.inf, np.nan]
    p = np.vstack([rng.integers(1, 6, N).astype(float), rng.uniform(-1, 1, N),
                   rng.uniform(-1, 1, N)])
    p[0, 6] = 0.5                                   # non-integral base for one instance
    # bases at the table's end: 72 (largest offset 7 -> index 79, the last element) and
    # 73 (index 80: one past the end, NaN)
    x[4], x[5] = 72.9, 73.2
    p[0, 4] = p[0, 5] = 1.0
    return x, y, p


def _run_lanes(f: ca.Function, width: int, avx2: bool, x: np.ndarray, y: np.ndarray,
               p: np.ndarray, interleave: int = 1) -> list[np.ndarray]:
    src = ("#include <math.h>\n"
           + lane_source(f, name="probe_k", n=N, inputs=[LaneInput("instance"),
                                                         LaneInput("instance"),
                                                         LaneInput("baked", p)],
                         width=width, avx2=avx2, interleave=interleave)
           + "void probe(const double **arg, double **res) { probe_k(arg, res); }\n")
    with tempfile.TemporaryDirectory() as tmp:
        flags = ("-O3", "-shared", "-fPIC", "-ffp-contract=off") + (("-mavx2",) if avx2 else ())
        lib = ctypes.CDLL(str(build_source("probe", src.encode(), cache=Path(tmp),
                                           flags=flags)))
        outs = [np.zeros(N) for _ in range(f.n_out())]
        args = (ctypes.c_void_p * 2)(x.ctypes.data, y.ctypes.data)
        res = (ctypes.c_void_p * len(outs))(*[o.ctypes.data for o in outs])
        lib.probe(args, res)
    return outs


# interleave 2: two blocks per iteration, the second partly past the end (the bank's
# setting); 3: with width 2 the third block of the second iteration lies wholly past the
# N = 7 instances and must write nothing (with width 4 it is cut to the 2 blocks N fills)
@pytest.mark.parametrize("interleave", [1, 2, 3])
@pytest.mark.parametrize("width,avx2", _widths())
def test_lane_kernel_equals_casadi_bit_for_bit(width: int, avx2: bool, interleave: int) -> None:
    f = _function()
    x, y, p = _inputs(np.random.default_rng(width))
    got = _run_lanes(f, width, avx2, x, y, p, interleave)
    ref = f.map(N)(x[None], y[None], p)
    with np.errstate(all="ignore"):
        for k, r in enumerate(ref):
            # bit patterns: signed zeros and the sign of NaN included
            np.testing.assert_array_equal(got[k].view(np.int64),
                                          np.asarray(r, dtype=float).ravel().view(np.int64),
                                          err_msg=f"output {k} ({width} lanes)")
    # the special inputs reached the gathers' general path: NaN outside the table; the
    # base at the end of the table is inside, one further is outside
    assert np.isnan(got[34][0]) and np.isnan(got[34][1])
    assert np.isfinite(got[34][4]) and np.isnan(got[34][5])


def test_interleave_needs_instances_for_its_blocks() -> None:
    """A kernel for at most one block of instances is the one-block code whatever the
    interleave (no wasted block, the same library); more instances take the interleaved
    loop; a bad interleave is refused."""
    f = _function()
    p3 = np.ones((3, 3))
    p9 = np.ones((3, 9))

    def src(n: int, p: np.ndarray, interleave: int) -> str:
        return lane_source(f, name="probe_k", n=n, inputs=[LaneInput("instance"),
                                                          LaneInput("instance"),
                                                          LaneInput("baked", p)],
                           width=4, interleave=interleave)

    assert src(3, p3, 2) == src(3, p3, 1)
    assert "c0 += 2 * W" in src(9, p9, 2) and "c0 += W" in src(9, p9, 1)
    with pytest.raises(ValueError, match="interleave"):
        src(9, p9, 0)


def test_unsupported_operation_is_refused() -> None:
    a = ca.MX.sym("a", 2, 2)
    f = ca.Function("m", [a], [ca.mtimes(a, a)[0, 0]])
    with pytest.raises(NotImplementedError):
        lane_source(f, name="m_k", n=3, inputs=[LaneInput("instance")])


@pytest.fixture(scope="module")
def mixed_maps() -> list[mk.CharacteristicMaps]:
    g, i = np.linspace(0.006, 0.016, 6), np.linspace(0.0, 60.0, 7)
    return [mk.build_maps(mk.load_magnet(name), gaps_m=g, currents_A=i, progress=False)
            for name in ("u-magnet", "tr09-standard")]


def test_bank_lanes_equal_casadi_code_and_virtual_machine(mixed_maps, tmp_path) -> None:
    """The bank's step through lanes, through CasADi's generated C and on CasADi's
    virtual machine: identical outputs (all seven, n_bad included) for random states and
    for circuits with NaN inputs, gaps and currents outside the maps."""
    u, tr = mixed_maps
    members = {"a": u, "b": tr, "c": u, "d": tr}                    # 1+2+1+2 = 6 circuits
    calls = {}
    for cg, mode in (("lanes", "always"), ("casadi", "always"), ("casadi", "never")):
        bank = MagnetBank(members, compiled=mode, codegen=cg, cache_dir=tmp_path)
        calls[(cg, mode)] = bank._kernel(1e-3)
        if cg == "lanes":
            bank_lanes = bank
    nc = bank.n_circuits
    rng = np.random.default_rng(3)
    for trial in range(4):
        x = rng.uniform(1.0, 55.0, nc)
        s = rng.uniform(0.0065, 0.0155, nc)
        v = rng.uniform(-50.0, 150.0, nc)
        sd = rng.uniform(-0.05, 0.05, nc)
        if trial == 3:
            v[1], s[2], x[4], sd[5] = np.nan, 0.05, 500.0, np.inf
        results = {key: call(x, s, v, sd, 1e-3) for key, call in calls.items()}
        ref = results[("casadi", "never")]
        for key, res in results.items():
            for k, (a, b) in enumerate(zip(res, ref, strict=True)):
                a, b = np.atleast_1d(a).astype(float), np.atleast_1d(b).astype(float)
                # bit patterns, except the sign of a NaN (the member sums of a NaN force
                # differ in it between CasADi's own C and its virtual machine)
                nan = np.isnan(b)
                np.testing.assert_array_equal(np.isnan(a), nan, err_msg=f"{key} output {k}")
                np.testing.assert_array_equal(a[~nan].view(np.int64), b[~nan].view(np.int64),
                                              err_msg=f"{key} output {k} trial {trial}")
        assert (ref[4] > 0) == (trial == 3)          # the flag count sees the bad circuits
    assert bank_lanes._lanes            # the lanes library was built and used (no fallback)


def test_codegen_option_is_checked(mixed_maps) -> None:
    with pytest.raises(InputError, match="codegen = 'simd'.*'lanes' or 'casadi'"):
        MagnetBank({"m": mixed_maps[0]}, codegen="simd")


def test_reused_work_slot_of_a_table_is_not_gathered_from() -> None:
    """CasADi reuses a large constant's work slot for later values; a gather from such a
    later (non-constant) value must be refused, not served from the old table (found in
    review: it gave table values instead of y's)."""
    x, y = ca.MX.sym("x"), ca.MX.sym("y")
    a = ca.MX(ca.DM(np.arange(100.0) + 1000.0))[ca.floor(x)]
    v = y[[0] * 100] * 1.0 + 0.0                    # 100 elements, not a constant
    f = ca.Function("reuse", [x, y], [a + v[ca.floor(x) + 1]])
    with pytest.raises(NotImplementedError, match="non-constant"):
        lane_source(f, name="reuse_k", n=3, inputs=[LaneInput("instance")] * 2)


def test_kernels_of_two_widths_in_one_file() -> None:
    """Each width has its own out-of-line gather (found in review: one definition per
    file, for the first kernel's width, gave wrong slow-path values for the second)."""
    f = _function()
    x, y, p = _inputs(np.random.default_rng(5))
    parts = [lane_source(f, name=f"probe_w{w}", n=N, inputs=[LaneInput("instance"),
                                                             LaneInput("instance"),
                                                             LaneInput("baked", p)], width=w)
             for w in (1, 2)]
    src = ("#include <math.h>\n" + "".join(parts)
           + "void probe(const double **arg, double **res) { probe_w2(arg, res); }\n")
    with tempfile.TemporaryDirectory() as tmp:
        lib = ctypes.CDLL(str(build_source("probe2", src.encode(), cache=Path(tmp),
                                           flags=("-O3", "-shared", "-fPIC",
                                                  "-ffp-contract=off"))))
        outs = [np.zeros(N) for _ in range(f.n_out())]
        args = (ctypes.c_void_p * 2)(x.ctypes.data, y.ctypes.data)
        res = (ctypes.c_void_p * len(outs))(*[o.ctypes.data for o in outs])
        lib.probe(args, res)
    ref = f.map(N)(x[None], y[None], p)
    with np.errstate(all="ignore"):
        for k, r in enumerate(ref):
            np.testing.assert_array_equal(outs[k].view(np.int64),
                                          np.asarray(r, dtype=float).ravel().view(np.int64))


def test_two_sided_selects_become_guess_branches() -> None:
    """The probe's three two-sided selects are written as branches on "the condition holds
    in every lane" (the bank's hinted table lookups rely on it for their speed; the values
    are checked bit for bit above); a one-sided select is not."""
    f = _function()
    _, _, p = _inputs(np.random.default_rng(1))
    for width, avx2 in _widths():
        src = lane_source(f, name="probe_k", n=N, inputs=[LaneInput("instance"),
                                                          LaneInput("instance"),
                                                          LaneInput("baked", p)],
                          width=width, avx2=avx2)
        assert src.count(f"lanes_guess_select_w{width}(") == 1 + 3     # definition + calls
