"""C code for many instances of one CasADi function, evaluated in SIMD lanes.

CasADi's code generation of ``f.map(n, "serial")`` is a loop that evaluates ``f`` for one
instance after another.  :func:`lane_source` writes C that evaluates ``f`` for ``width``
instances at once: every work value of ``f``'s algorithm becomes one GCC/Clang
vector-extension value (``width`` doubles, one SIMD register for width 4 with AVX2 or
width 2 with SSE2/NEON) and every instruction one vector operation.  The arithmetic is
``f``'s own, instruction by instruction and in the same order, so the results equal
CasADi's virtual machine bit for bit when compiled without floating-point contraction
(``-ffp-contract=off``), signed zeros and NaN signs included (``fmin``/``fmax`` as
selects with glibc's rules: a NaN operand yields the other one, a tie the first).
``width=1`` writes plain scalar C (one instance per loop iteration) with the same
translation.

It reads ``f``'s algorithm through CasADi's instruction API (``instruction_id``,
``instruction_input``, ``instruction_output``, ``instruction_MX``) and supports the
operations of elementwise MX graphs: inputs, constants, unary and binary scalar
operations (with scalar broadcast), ``GetNonzeros`` (element selection) and
``GetNonzerosParam`` (a gather from a constant table at computed indices).  Anything else
raises :class:`NotImplementedError` so that the caller can fall back to CasADi's own
code generation.  Every output must be one scalar per instance.

Gathers whose index vector is "integer offsets + one base" (a per-cell table lookup) are
loads at fixed offsets from the base once the base is checked to be a whole number with
every index inside the table (then ``(int)(offset + base)`` is exactly ``offset + base``);
with AVX2, runs of four consecutive offsets are one 4-double load per lane and a 4 x 4
transpose, other offsets hardware gathers.  Any other base takes CasADi's general
gather (NaN outside the table), out of line.
"""

from __future__ import annotations

import platform
import re
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

__all__ = ["LaneInput", "external_source", "lane_source", "lane_target"]

# The lanes are GCC/Clang vector-extension values (``vd``: ``W`` doubles, ``vl``: their
# bit patterns as 64-bit integers), so that every work value is one SSA value the
# compiler keeps in vector registers.  Templates: a, b the operands (vd expressions or
# scalar literals, which the vector operators broadcast).
# arithmetic in the vector operators themselves
_ARITHMETIC = {
    ca.OP_ADD: "{a} + {b}", ca.OP_SUB: "{a} - {b}", ca.OP_MUL: "{a} * {b}",
    ca.OP_DIV: "{a} / {b}", ca.OP_NEG: "-{a}", ca.OP_TWICE: "2. * {a}",
    ca.OP_SQ: "{a} * {a}", ca.OP_INV: "1. / {a}", ca.OP_ASSIGN: "{a}",
}
_VECTOR = {
    **_ARITHMETIC,
    # comparisons give all-ones/zero masks; & ONE turns them into 1.0/0.0
    ca.OP_LT: "(vd)(({a} < {b}) & ONE)", ca.OP_LE: "(vd)(({a} <= {b}) & ONE)",
    ca.OP_EQ: "(vd)(({a} == {b}) & ONE)", ca.OP_NE: "(vd)(({a} != {b}) & ONE)",
    # C99 fmin/fmax semantics (a NaN operand yields the other one) as a select
    ca.OP_FMIN: "SEL(({a} <= {b}) | ({b} != {b}), {a}, {b})",
    ca.OP_FMAX: "SEL(({a} >= {b}) | ({b} != {b}), {a}, {b})",
    ca.OP_FABS: "(vd)((vl){a} & ABSMASK)",
    ca.OP_IF_ELSE_ZERO: "SEL({a} != ZERO, {b}, ZERO)",
}
# the same operations for one scalar (width 1, and the lane-by-lane fallback)
_SCALAR = {
    **_ARITHMETIC,
    ca.OP_LT: "(double)({a} < {b})", ca.OP_LE: "(double)({a} <= {b})",
    ca.OP_EQ: "(double)({a} == {b})", ca.OP_NE: "(double)({a} != {b})",
    ca.OP_FMIN: "(({a} <= {b} || {b} != {b}) ? {a} : {b})",
    ca.OP_FMAX: "(({a} >= {b} || {b} != {b}) ? {a} : {b})",
    ca.OP_FABS: "fabs({a})", ca.OP_IF_ELSE_ZERO: "({a} ? {b} : 0.0)",
}
# everything else lane by lane through libm (C expressions of scalars x, y)
_PER_LANE_BINARY = {
    ca.OP_POW: "pow({a}, {b})", ca.OP_CONSTPOW: "pow({a}, {b})",
    ca.OP_AND: "(double)({a} && {b})", ca.OP_OR: "(double)({a} || {b})",
    ca.OP_ATAN2: "atan2({a}, {b})", ca.OP_FMOD: "fmod({a}, {b})",
    ca.OP_COPYSIGN: "copysign({a}, {b})", ca.OP_HYPOT: "hypot({a}, {b})",
}
_PER_LANE_UNARY = {
    ca.OP_FLOOR: "floor({a})", ca.OP_CEIL: "ceil({a})", ca.OP_SQRT: "sqrt({a})",
    ca.OP_EXP: "exp({a})", ca.OP_LOG: "log({a})", ca.OP_SIN: "sin({a})",
    ca.OP_COS: "cos({a})", ca.OP_TAN: "tan({a})", ca.OP_ASIN: "asin({a})",
    ca.OP_ACOS: "acos({a})", ca.OP_ATAN: "atan({a})", ca.OP_SINH: "sinh({a})",
    ca.OP_COSH: "cosh({a})", ca.OP_TANH: "tanh({a})", ca.OP_ASINH: "asinh({a})",
    ca.OP_ACOSH: "acosh({a})", ca.OP_ATANH: "atanh({a})", ca.OP_ERF: "erf({a})",
    ca.OP_NOT: "(double)(!{a})",
    ca.OP_SIGN: "({a} < 0 ? -1.0 : ({a} > 0 ? 1.0 : {a}))",     # CasADi's: NaN, +-0 kept
    ca.OP_LOG1P: "log1p({a})", ca.OP_EXPM1: "expm1({a})",
}
_SLOW_GATHER = """#ifndef LANES_GATHER_SLOW_W{w}
#define LANES_GATHER_SLOW_W{w}
/* table[(int)(offs[e] + b[l])] for {w} lanes, NaN outside the table (CasADi's
   GetNonzerosParam; a value that does not truncate into the table, NaN and inf
   included, gives NaN) */
static void __attribute__((noinline)) lanes_gather_slow_w{w}(const double *tbl, int size,
    const double *b, const double *offs, int count, double *out) {{
  int e, l;
  for (e = 0; e < count; ++e) for (l = 0; l < {w}; ++l) {{
    double x = offs[e] + b[l];
    int i = x > -1.0 && x < size ? (int) x : -1;   /* no undefined conversion */
    out[e * {w} + l] = i >= 0 && i < size ? tbl[i] : NAN;
  }}
}}
#endif
"""
_GUESS_SELECT = """#ifndef LANES_GUESS_SELECT_W{w}
#define LANES_GUESS_SELECT_W{w}
/* the lanes where c != 0 take a, the others b (out of line: the branch that calls this is
   the unlikely one, and a call keeps the compiler from turning the branch into a select) */
static {t} __attribute__((noinline)) lanes_guess_select_w{w}({t} c, {t} a, {t} b) {{
  return {sel};
}}
#endif
"""
_PRELUDE = """typedef double vd __attribute__((vector_size(W * 8)));
typedef long long vl __attribute__((vector_size(W * 8)));
#define SEL(m, a, b) ((vd)(((vl)(a) & (m)) | ((vl)(b) & ~(m))))
#define ONE ((vl){0} + 0x3FF0000000000000LL)
#define ABSMASK ((vl){0} + 0x7FFFFFFFFFFFFFFFLL)
#define ZERO ((vd){0})
"""
_TABLE_MIN = 64          # constants with more elements go to a static table


@dataclass(frozen=True)
class LaneInput:
    """How one input of the lane kernel is supplied.

    ``kind``:

    ``"instance"``
        An array per call, element ``e`` of instance ``c`` at ``[e * n + c]`` (one row
        per element, structure of arrays).
    ``"shared"``
        One value per call for all instances (e.g. the step length).
    ``"baked"``
        A constant per instance, ``values`` of shape (numel, n), compiled into the code.
    """

    kind: str
    values: np.ndarray | None = None


def _c_double(v: float) -> str:
    v = float(v)
    if np.isnan(v):
        return "NAN"
    if np.isinf(v):
        return "INFINITY" if v > 0 else "(-INFINITY)"
    return v.hex()


def _table_literal(name: str, values: np.ndarray) -> str:
    flat = np.asarray(values, dtype=float).ravel()
    if np.isfinite(flat).all():                   # the common case, fast: float.hex
        items = ",".join(map(float.hex, flat.tolist()))
    else:
        items = ",".join(_c_double(v) for v in flat)
    return f"static const double {name}[{flat.size}] = {{{items}}};\n"


def lane_source(f: ca.Function, *, name: str, n: int, inputs: Sequence[LaneInput],
                width: int = 4, avx2: bool = False, interleave: int = 1) -> str:
    """C source of ``void name(const double **arg, double **res)`` evaluating ``f`` for
    ``n`` instances, ``width`` at a time.

    Parameters
    ----------
    f : casadi.Function
        An MX function of elementwise operations (module docstring); every output one
        scalar.
    name : str
        C identifier of the generated function.
    n : int
        Number of instances (fixed at generation time).
    inputs : sequence of LaneInput
        One per input of ``f``.  ``arg`` of the generated function holds, in order, the
        inputs that are not ``"baked"``.
    width : int
        Lanes per block (a power of two; 8 suits 2-4 wide vector units).
    interleave : int, default 1
        Blocks of lanes per loop iteration, their statements interleaved one by one (2:
        instances ``c0 ... c0 + W - 1`` and ``c0 + W ... c0 + 2W - 1``).  The arithmetic
        of every instance is the same, so are the results (bit for bit); two independent
        dependency chains side by side let the processor overlap their latencies (a
        kernel whose RK4 stages wait on divisions and table lookups).  Ignored at width 1;
        at most the number of blocks the ``n`` instances fill (``ceil(n / width)``).

    Returns
    -------
    str
        C source (a static table per large constant, then the function; needs
        ``<math.h>``).  ``res[k]`` receives output ``k`` of every instance (length ``n``).

    Raises
    ------
    NotImplementedError
        ``f`` uses an operation this generator does not translate.
    """
    if len(inputs) != f.n_in():
        raise ValueError(f"{f.name()} has {f.n_in()} inputs, {len(inputs)} LaneInputs given")
    for k in range(f.n_out()):
        if f.nnz_out(k) != 1:
            raise NotImplementedError(f"output {f.name_out(k)!r} has {f.nnz_out(k)} elements; "
                                      "lane kernels need scalar outputs")
    w = int(width)
    if avx2 and w != 4:
        raise ValueError("avx2 lanes are 4 wide")
    head: list[str] = []
    body: list[str] = []
    arg_of: dict[int, int] = {}
    for k, spec in enumerate(inputs):
        if spec.kind == "baked":
            vals = np.asarray(spec.values, dtype=float)
            if vals.shape != (f.nnz_in(k), n):
                raise ValueError(f"baked input {k}: shape {vals.shape}, expected "
                                 f"({f.nnz_in(k)}, {n})")
            head.append(_table_literal(f"{name}_in{k}", vals))
        elif spec.kind in ("instance", "shared"):
            arg_of[k] = len(arg_of)
        else:
            raise ValueError(f"LaneInput kind {spec.kind!r}")

    # work[j]: per element of work value j a C expression: a variable "t<i>" (a vd of
    # the lanes, or a double at width 1) or a scalar literal "(...)"
    work: dict[int, list[str]] = {}
    tables: dict[int, tuple[str, int]] = {}      # work index -> static table (name, size)
    # work index -> (integer offsets, scalar base) of an index vector "offsets + base"
    affine: dict[int, tuple[list[int], str]] = {}
    scalar = w == 1
    counter = [0]

    def fresh() -> str:
        counter[0] += 1
        return f"t{counter[0]}"

    def vec(v: str) -> str:
        return v if v.startswith("t") or scalar else "((vd){" + ",".join([v] * w) + "})"

    def at(v: str) -> str:
        return f"{v}[l]" if v.startswith("t") and not scalar else v

    def per_lane(expr: str) -> str:
        if avx2 and expr.startswith(("floor(", "ceil(")) and expr.endswith("[l])"):
            fn, a = expr.split("(", 1)
            t = fresh()
            body.append(f"    vd {t} = (vd)_mm256_{fn}_pd((__m256d){a[:-4]});")
            return t
        t = fresh()
        if scalar:
            body.append(f"    double {t} = {expr};")
        else:
            body.append(f"    vd {t}; for (l = 0; l < W; ++l) {t}[l] = {expr};")
        return t

    def vector(template: str, **ops: str) -> str:
        t = fresh()
        rhs = template.format(**{k: vec(v) for k, v in ops.items()})
        body.append(f"    {'double' if scalar else 'vd'} {t} = {rhs};")
        return t

    # "if_else(c, a, b)" is if_else_zero(c, a) + if_else_zero(!c, b) in CasADi's graph:
    # remembered per element name, so that the sum becomes a branch (guess_select)
    negation: dict[str, str] = {}                # name of !c -> name of c
    zero_unless: dict[str, tuple[str, str]] = {}  # name of if_else_zero(c, v) -> (c, v)

    def guess_select(x: str, y: str) -> str | None:
        """``x + y`` for ``x = if_else_zero(c_x, v_x)``, ``y = if_else_zero(c_y, v_y)`` with
        one condition the negation of the other, as a branch on "the plain condition holds
        in every lane": there the sum is known without waiting for the condition (the
        processor predicts the branch), elsewhere the per-lane select, out of line.  Bit
        for bit the sum: ``v + 0`` or ``0 + v`` in the operands' order.  None: not that
        pattern."""
        if x not in zero_unless or y not in zero_unless:
            return None
        (cx, vx), (cy, vy) = zero_unless[x], zero_unless[y]
        zero = "0.0" if scalar else "ZERO"
        if negation.get(cy) == cx:               # x holds the plain condition
            c, likely, other = cx, f"{vec(vx)} + {zero}", f"{zero} + {vec(vy)}"
        elif negation.get(cx) == cy:             # y does
            c, likely, other = cy, f"{zero} + {vec(vy)}", f"{vec(vx)} + {zero}"
        else:
            return None
        t = fresh()
        if scalar:
            body.append(f"    double {t}; if (__builtin_expect({c} != 0.0, 1)) {t} = {likely}; "
                        f"else {t} = lanes_guess_select_w1({c}, {likely}, {other});")
        else:
            body.append(f"    vd {t}; {{ vl m_ = ({vec(c)} != ZERO); int all_ = 1; "
                        f"for (l = 0; l < W; ++l) all_ &= m_[l] != 0; "
                        f"if (__builtin_expect(all_, 1)) {t} = {likely}; "
                        f"else {t} = lanes_guess_select_w{w}({vec(c)}, {likely}, {other}); }}")
        return t

    def operands(ins: Sequence[int], k: int, size: int) -> list[list[str]]:
        if any(j in tables for j in ins):
            raise NotImplementedError(f"instruction {k}: arithmetic on a large constant")
        return [[work[j][el if len(work[j]) > 1 else 0] for j in ins] for el in range(size)]

    def gather(k: int, tname: str, tsize: int, idx: list[str], aff: tuple[list[int], str] | None
               ) -> list[str]:
        """``table[idx]`` with CasADi's semantics (NaN outside the table)."""
        out = [fresh() for _ in idx]
        decl = "double" if scalar else "vd"
        body.append(f"    {decl} {', '.join(out)};")
        general = "".join(
            f" {{ double x = {at(ix)}; int i = x > -1.0 && x < {tsize} ? (int) x : -1; "
            f"{t}{'' if scalar else '[l]'} = i >= 0"
            f" ? {tname}[i] : NAN; }}" for t, ix in zip(out, idx, strict=True))
        loop = "" if scalar else "for (l = 0; l < W; ++l) "
        if aff is None:
            body.append(f"    {loop}{{{general} }}")
            return out
        # index = integer offsets + one base: if the base is a whole number and every
        # index inside the table, (int)(offset + base) == offset + (int) base exactly,
        # so the elements are loads at fixed offsets from one pointer; otherwise the
        # general gather (out of line, from the same offsets and base)
        offs, base = aff
        lo, hi = min(offs), max(offs)
        oname = f"{name}_o{k}"
        head.append(f"static const double {oname}[{len(offs)}] = "
                    "{" + ",".join(f"{o}.0" for o in offs) + "};\n")
        slow_unpack = "".join(f" {t} = {'sl' if scalar else '*(vd *)(sl + ' + str(j * w) + ')'}"
                              f"{'[' + str(j) + ']' if scalar else ''};"
                              for j, t in enumerate(out))
        slow = (f"double sl[{len(offs) * w}] __attribute__((aligned({8 * w}))); "
                f"lanes_gather_slow_w{w}({tname}, {tsize}, "
                f"{'&b' if scalar else '(const double *) &bv'}, {oname}, {len(offs)}, sl);"
                + slow_unpack)
        if scalar:
            fast = "".join(f" {t} = {tname}[ib + {o}];" for t, o in zip(out, offs, strict=True))
            body.append(
                f"    {{ double b = {base}; int ib = fabs(b) < 1e9 ? (int) b : -1; "
                f"if (b == (double) ib && ib + {lo} >= 0 && ib + {hi} < {tsize}) {{ "
                f"{fast} }} else {{ {slow} }} }}")
            return out
        if avx2 and tsize < 2**31 - 1 - hi:
            # all four lanes at once: runs of four consecutive offsets as one 4-double
            # load per lane and a 4 x 4 transpose (cheaper than hardware gathers, which
            # remain for the other elements)
            parts = []
            j = 0
            while j < len(offs):
                if j + 3 < len(offs) and offs[j + 1:j + 4] == [offs[j] + 1, offs[j] + 2,
                                                               offs[j] + 3]:
                    o = offs[j]
                    c0, c1, c2, c3 = out[j:j + 4]
                    parts.append(
                        f" {{ __m256d r0 = _mm256_loadu_pd({tname} + (i0 + {o})), "
                        f"r1 = _mm256_loadu_pd({tname} + (i1 + {o})), "
                        f"r2 = _mm256_loadu_pd({tname} + (i2 + {o})), "
                        f"r3 = _mm256_loadu_pd({tname} + (i3 + {o})); "
                        "__m256d u0 = _mm256_unpacklo_pd(r0, r1), u1 = _mm256_unpackhi_pd(r0, r1), "
                        "u2 = _mm256_unpacklo_pd(r2, r3), u3 = _mm256_unpackhi_pd(r2, r3); "
                        f"{c0} = (vd)_mm256_permute2f128_pd(u0, u2, 0x20); "
                        f"{c1} = (vd)_mm256_permute2f128_pd(u1, u3, 0x20); "
                        f"{c2} = (vd)_mm256_permute2f128_pd(u0, u2, 0x31); "
                        f"{c3} = (vd)_mm256_permute2f128_pd(u1, u3, 0x31); }}")
                    j += 4
                else:
                    parts.append(f" {out[j]} = (vd)_mm256_i32gather_pd({tname} + {offs[j]}, ix, 8);")
                    j += 1
            fast4 = (" int i0 = _mm_extract_epi32(ix, 0), i1 = _mm_extract_epi32(ix, 1), "
                     "i2 = _mm_extract_epi32(ix, 2), i3 = _mm_extract_epi32(ix, 3);"
                     + "".join(parts))
            body.append(
                f"    {{ vd bv = {vec(base)}; __m256d b = (__m256d)bv; __m256d ok = _mm256_and_pd("
                f"_mm256_cmp_pd(b, _mm256_floor_pd(b), _CMP_EQ_OQ), _mm256_and_pd("
                f"_mm256_cmp_pd(_mm256_add_pd(b, _mm256_set1_pd({lo}.0)), _mm256_setzero_pd(), "
                f"_CMP_GE_OQ), _mm256_cmp_pd(_mm256_add_pd(b, _mm256_set1_pd({hi}.0)), "
                f"_mm256_set1_pd({tsize}.0), _CMP_LT_OQ))); "
                f"if (_mm256_movemask_pd(ok) == 15) {{ __m128i ix = _mm256_cvttpd_epi32(b);"
                f"{fast4} }} else {{ {slow} }} }}")
            return out
        fast = "".join(f" {t}[l] = {tname}[ib + {o}];" for t, o in zip(out, offs, strict=True))
        body.append(
            f"    {{ vd bv = {vec(base)}; int ok = 1; for (l = 0; l < W; ++l) {{ double b = bv[l]; "
            f"int ib = fabs(b) < 1e9 ? (int) b : -1; ok = ok && b == (double) ib && "
            f"ib + {lo} >= 0 && ib + {hi} < {tsize}; }} "
            f"if (ok) {{ for (l = 0; l < W; ++l) {{ int ib = (int) bv[l];{fast} }} }}"
            f" else {{ {slow} }} }}")
        return out

    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        ins, outs = f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_OUTPUT:
            (slot,), (ind,) = ins, outs[:1]
            value = work[slot][0]
            if scalar:
                body.append(f"    res[{ind}][c0] = {value};")
            else:
                body.append(f"    for (l = 0; l < m; ++l) res[{ind}][c0 + l] = {at(value)};")
            continue
        node = f.instruction_MX(k)
        if not node.sparsity().is_dense():
            raise NotImplementedError(f"instruction {k}: sparse value {node.sparsity().dim()}")
        size = int(node.nnz())
        # index-vector bookkeeping: the operands' entries are read before the output
        # (which may reuse an operand's work slot) replaces them
        operand_affine = [affine.get(j) for j in ins]
        operand_work = [work.get(j, []) for j in ins]
        affine.pop(outs[0], None)
        tables.pop(outs[0], None)            # CasADi may reuse a large constant's slot
        if op == ca.OP_INPUT:
            info = node.info()
            ind, off = int(info["ind"]), int(info["offset"])
            spec = inputs[ind]
            names = []
            for el in range(off, off + size):
                if spec.kind == "shared":
                    names.append(per_lane(f"arg[{arg_of[ind]}][{el}]"))
                else:
                    array = (f"{name}_in{ind}" if spec.kind == "baked"
                             else f"arg[{arg_of[ind]}]")
                    names.append(per_lane(f"{array}[{el} * {n} + {'c0' if scalar else 'id[l]'}]"))
            work[outs[0]] = names
        elif op == ca.OP_CONST:
            vals = np.asarray(node.to_DM().nonzeros(), dtype=float)
            if vals.size > _TABLE_MIN:
                tname = f"{name}_c{k}"
                head.append(_table_literal(tname, vals))
                tables[outs[0]] = (tname, vals.size)
                work[outs[0]] = []
            else:
                work[outs[0]] = [f"({_c_double(v)})" for v in vals]
                if vals.size > 1 and np.all(vals == np.round(vals)) and np.all(np.abs(vals) < 2**30):
                    affine[outs[0]] = ([int(v) for v in vals], "")
        elif op == ca.OP_GETNONZEROS:
            info = node.info()
            if "slice" in info:
                sl = info["slice"]
                nz = list(range(int(sl["start"]), int(sl["stop"]), int(sl["step"])))
            elif "nz" in info:
                nz = [int(v) for v in info["nz"]]
            else:
                o, i_ = info["outer"], info["inner"]
                nz = [a + b for a in range(int(o["start"]), int(o["stop"]), int(o["step"]))
                      for b in range(int(i_["start"]), int(i_["stop"]), int(i_["step"]))]
            if ins[0] in tables:
                raise NotImplementedError(f"instruction {k}: element of a large constant")
            src_el = work[ins[0]]
            work[outs[0]] = [src_el[j] if j >= 0 else "(0.0)" for j in nz]
        elif op == ca.OP_GETNONZEROS_PARAM:
            if ins[0] not in tables:
                raise NotImplementedError(f"instruction {k}: gather from a non-constant")
            tname, tsize = tables[ins[0]]
            aff = affine.get(ins[1])
            work[outs[0]] = gather(k, tname, tsize, work[ins[1]],
                                   aff if aff is not None and aff[1] else None)
        elif op in _VECTOR:
            args = operands(ins, k, size)
            tpl = _SCALAR[op] if scalar else _VECTOR[op]
            names = []
            for a in args:
                guessed = guess_select(a[0], a[1]) if op == ca.OP_ADD else None
                names.append(guessed if guessed is not None
                             else vector(tpl, **dict(zip("ab", a, strict=False))))
                if op == ca.OP_IF_ELSE_ZERO:
                    zero_unless[names[-1]] = (a[0], a[1])
            work[outs[0]] = names
            if op == ca.OP_ADD and size > 1:
                # constant integer offsets + a scalar: remember for the gather
                for a_c, other in ((operand_affine[0], operand_work[1]),
                                   (operand_affine[1], operand_work[0])):
                    if a_c is not None and not a_c[1] and len(other) == 1:
                        affine[outs[0]] = (a_c[0], other[0])
        elif op in _PER_LANE_BINARY or op in _PER_LANE_UNARY:
            tpl = _PER_LANE_BINARY.get(op) or _PER_LANE_UNARY[op]
            args = operands(ins, k, size)
            work[outs[0]] = [per_lane(tpl.format(**{c: at(v) for c, v in zip("ab", a, strict=False)}))
                             for a in args]
            if op == ca.OP_NOT:
                negation.update({t: a[0] for t, a in zip(work[outs[0]], args, strict=True)})
        else:
            raise NotImplementedError(f"instruction {k}: operation {op} "
                                      f"({node}) is not translated to lanes")
    guess = _GUESS_SELECT.format(
        w=w, t="double" if scalar else "vd",
        sel="c != 0.0 ? a : b" if scalar else "SEL((c != ZERO), a, b)")
    code = (("#include <immintrin.h>\n" if avx2 else "") + f"#define W {w}\n"
           + ("" if scalar else _PRELUDE) + _SLOW_GATHER.format(w=w) + guess + "".join(head))
    if scalar:
        code += (f"static void {name}(const double **arg, double **res) {{\n"
                f"  long c0;\n"
                f"  for (c0 = 0; c0 < {n}; ++c0) {{\n"
                + "\n".join(body) + "\n  }\n}\n#undef W\n")
        return code
    head_loop = (f"    int l, m = {n} - c0 < W ? (int) ({n} - c0) : W;\n"
                 f"    long id[W];\n"
                 f"    for (l = 0; l < W; ++l) id[l] = l < m ? c0 + l : {n} - 1;\n")
    blocks = int(interleave)
    if blocks < 1 or blocks != interleave:
        raise ValueError(f"interleave = {interleave!r}; use a whole number >= 1")
    # no more blocks than the instances fill: a bank of at most W circuits keeps the
    # one-block code (and its compile time)
    blocks = min(blocks, -(-n // w))

    def in_block(line: str, j: int) -> str:
        # block j's own work names, instances and count
        line = re.sub(r"\bt(\d+)\b", rf"t\1b{j}", line)
        line = re.sub(r"\bid\[", f"id{j}[", line)
        line = re.sub(r"\bc0\b", f"c{j}", line)
        return re.sub(r"\bm\b", f"m{j}", line)

    for j in range(1, blocks):
        # the further blocks: the statements of all blocks alternate (each statement is
        # self-contained: it declares its results and reads earlier ones only); a block
        # past the last instance computes copies of it and writes nothing (m_j <= 0)
        head_loop += (f"    long c{j} = c0 + {j} * W;\n"
                      f"    int m{j} = {n} - c{j} < W ? (int) ({n} - c{j}) : W;\n"
                      f"    long id{j}[W];\n"
                      f"    for (l = 0; l < W; ++l) id{j}[l] = l < m{j} ? c{j} + l : {n} - 1;\n")
    body = [x for line in body for x in (line, *(in_block(line, j) for j in range(1, blocks)))]
    step = "W" if blocks == 1 else f"{blocks} * W"
    code += (f"static void {name}(const double **arg, double **res) {{\n"
            f"  long c0;\n"
            f"  for (c0 = 0; c0 < {n}; c0 += {step}) {{\n" + head_loop
            + "\n".join(body) + "\n  }\n}\n#undef W\n#undef SEL\n#undef ONE\n#undef ABSMASK\n#undef ZERO\n")
    return code


def external_source(name: str, *, inputs: Sequence[tuple[str, int]],
                    outputs: Sequence[tuple[str, int]], body: str, work: int = 0) -> str:
    """C source of a function with CasADi's external calling convention.

    ``casadi.external(name, library)`` loads it like a CasADi-generated function: dense
    column-vector inputs and outputs of the given names and sizes, ``work`` doubles of
    work memory (``w``).  ``body`` is the function's C body; it sees ``arg``, ``res`` and
    ``w`` (an output pointer may be NULL: the caller does not want that output).
    """
    def sparsity(size: int) -> str:
        return "{" + ",".join(str(v) for v in [size, 1, 0, size, *range(size)]) + "}"

    def table(kind: str, items: Sequence[tuple[str, int]]) -> str:
        sps = "".join(f"static const long long int {name}_sp_{kind}{k}[] = {sparsity(sz)};\n"
                      for k, (_, sz) in enumerate(items))
        names = ", ".join(f'"{nm}"' for nm, _ in items)
        cases = "".join(f"    case {k}: return {name}_sp_{kind}{k};\n" for k in range(len(items)))
        return (sps
                + f"long long int {name}_n_{kind}(void) {{ return {len(items)}; }}\n"
                + f"const char *{name}_name_{kind}(long long int i) {{\n"
                + f"  static const char *names[] = {{{names}}};\n"
                + f"  return i >= 0 && i < {len(items)} ? names[i] : 0;\n}}\n"
                + f"const long long int *{name}_sparsity_{kind}(long long int i) {{\n"
                + "  switch (i) {\n" + cases + "    default: return 0;\n  }\n}\n")

    return (table("in", inputs) + table("out", outputs)
            + f"int {name}_work(long long int *sz_arg, long long int *sz_res, "
              "long long int *sz_iw, long long int *sz_w) {\n"
            + f"  if (sz_arg) *sz_arg = {len(inputs)};\n  if (sz_res) *sz_res = {len(outputs)};\n"
            + f"  if (sz_iw) *sz_iw = 0;\n  if (sz_w) *sz_w = {int(work)};\n  return 0;\n}}\n"
            + f"int {name}(const double **arg, double **res, long long int *iw, double *w, "
              "int mem) {\n" + body + "  return 0;\n}\n")


def lane_target() -> tuple[int, bool, tuple[str, ...]]:
    """Lane width, whether to use AVX2, and the extra compiler flags, for this machine.

    AVX2 (4 doubles per vector, hardware gathers) where the processor has it (NumPy's
    run-time CPU detection), otherwise 2 lanes: the SSE2 of every x86-64, or NEON.
    """
    import importlib

    features: dict[str, bool] = {}
    for module in ("numpy._core._multiarray_umath", "numpy.core._multiarray_umath"):
        try:
            features = dict(importlib.import_module(module).__cpu_features__)
            break
        except (ImportError, AttributeError):      # pragma: no cover - other NumPy layouts
            continue
    if platform.machine().lower() in ("x86_64", "amd64") and features.get("AVX2"):
        return 4, True, ("-mavx2",)
    return 2, False, ()
