"""Magnet bank: cost per circuit-step against an independent minimal compiled kernel.

The baseline is written here, independently of the package: a plain C function that
advances N circuits of eq. 8 by one RK4 step each, with bicubic per-cell polynomials whose
coefficients come from SciPy's ``RectBivariateSpline`` (node values and derivatives,
Hermite form) rather than from the package's table builder.  It is compiled with the
system C compiler (-O3) and called through ctypes, one call per step, as the bank is.
"""

from __future__ import annotations

import ctypes
import os
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import maglevkit as mk
from maglevkit.reduced import bank as bank_mod
from maglevkit.reduced.bank import MagnetBank
from maglevkit.reduced.core import extend_axis, extend_values
from maglevkit.reduced.lanes import lane_target

TITLE = "Magnet bank: cost per circuit-step at 1 ms (RK4), against an independent C kernel"

DT = 1e-3
SIZES = (1, 10, 100, 1000)

_C_SOURCE = r"""
#include <math.h>
static void lookup(const double *c, int nl, double s0, double ids, int ns, double i0,
                   double idi, int ni, double s, double i, double *lt, double *dl, double *f) {
    double u = (s - s0) * ids, v = (i - i0) * idi;
    int k = (int)floor(u), l = (int)floor(v);
    if (k < 0) k = 0; if (k > ns - 1) k = ns - 1;
    if (l < 0) l = 0; if (l > ni - 1) l = ni - 1;
    double t = u - k, w = v - l, out[3];
    const double *cc = c + ((long)k * nl + l) * 48;
    for (int m = 0; m < 3; ++m) {
        const double *q = cc + 16 * m;
        double acc = 0.0;
        for (int p = 3; p >= 0; --p)
            acc = acc * t + (((q[4*p+3] * w + q[4*p+2]) * w + q[4*p+1]) * w + q[4*p]);
        out[m] = acc;
    }
    *lt = out[0]; *dl = out[1]; *f = out[2];
}
void bank_step(int n, const double *table, const long *offset, const double *par,
               const double *x0, const double *s, const double *u, const double *sd,
               double h, double *x1, double *coil, double *force) {
    for (int j = 0; j < n; ++j) {
        const double *p = par + 8 * j, *c = table + offset[j];
        double s0 = p[0], ids = p[1], i0 = p[2], idi = p[3], r = p[4], a = p[5];
        int ns = (int)p[6], ni = (int)p[7];
        double x = x0[j], lt, dl, f, k[4], xs = x, ss;
        for (int st = 0; st < 4; ++st) {
            double hh = st == 0 ? 0.0 : (st == 3 ? h : 0.5 * h);
            xs = st == 0 ? x : x + hh * k[st - 1];
            ss = s[j] + sd[j] * hh;
            lookup(c, ni, s0, ids, ns, i0, idi, ni, ss, xs, &lt, &dl, &f);
            k[st] = ((u[j] - r * xs) / a - dl * xs * sd[j]) / lt;
        }
        x = x + h / 6.0 * (k[0] + 2.0 * k[1] + 2.0 * k[2] + k[3]);
        lookup(c, ni, s0, ids, ns, i0, idi, ni, s[j] + sd[j] * h, x, &lt, &dl, &f);
        x1[j] = x;
        coil[j] = u[j] / r - (u[j] - r * x) / (a * r);
        force[j] = f;
    }
}
"""


def _baseline_table(gs: np.ndarray, gi: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Bicubic cell coefficients (cells_s, cells_i, 3, 4, 4) from RectBivariateSpline."""
    from scipy.interpolate import RectBivariateSpline

    hs, hi = gs[1] - gs[0], gi[1] - gi[0]
    herm = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0], [-3, 3, -2, -1], [2, -2, 1, 1]])
    out = np.zeros((gs.size - 1, gi.size - 1, 3, 4, 4))
    for m, v in enumerate(values):
        sp = RectBivariateSpline(gs, gi, v, kx=3, ky=3, s=0)
        f = sp(gs, gi)
        ft = sp(gs, gi, dx=1) * hs
        fw = sp(gs, gi, dy=1) * hi
        ftw = sp(gs, gi, dx=1, dy=1) * hs * hi
        for k in range(gs.size - 1):
            for j in range(gi.size - 1):
                g = np.zeros((4, 4))
                g[:2, :2] = f[k:k + 2, j:j + 2]
                g[:2, 2:] = fw[k:k + 2, j:j + 2]
                g[2:, :2] = ft[k:k + 2, j:j + 2]
                g[2:, 2:] = ftw[k:k + 2, j:j + 2]
                out[k, j, m] = herm @ g @ herm.T
    return out


class _Baseline:
    """The independent C kernel for ``n`` copies of the given maps' circuits."""

    def __init__(self, maps: mk.CharacteristicMaps, n: int, lib: ctypes.CDLL) -> None:
        gs, gi = extend_axis(maps.gaps_m), extend_axis(maps.currents_A)
        tabs, pars = [], []
        r_el = maps.dataset["resistance_ohm"].values
        r_ec = maps.dataset["eddy_resistance_fit_ohm"].values
        for j, c in enumerate(maps.circuits):
            vals = np.stack([extend_values(extend_values(maps.variable(v, c), axis=0), axis=1)
                             for v in ("inductance_H", "dL_ds_H_per_m", "force_N")])
            tabs.append(_baseline_table(gs, gi, vals).ravel())
            pars.append([gs[0], 1 / (gs[1] - gs[0]), gi[0], 1 / (gi[1] - gi[0]), r_el[j],
                         1 + r_el[j] / r_ec[j], gs.size - 1, gi.size - 1])
        nc = len(maps.circuits)
        self.table = np.concatenate(tabs)
        starts = np.cumsum([0] + [t.size for t in tabs[:-1]])
        self.offset = np.array([starts[k % nc] for k in range(n)], dtype=np.int64)
        self.par = np.array([pars[k % nc] for k in range(n)], dtype=float).ravel()
        self.n = n
        self.x1, self.coil, self.force = np.zeros(n), np.zeros(n), np.zeros(n)
        self.inputs = [np.zeros(n) for _ in range(4)]
        # raw pointers to persistent buffers: the call costs ~1 us (ndpointer argument
        # checks would cost ~5 us per argument and dominate at small n)
        arrays = [self.table, self.offset, self.par, *self.inputs, self.x1, self.coil, self.force]
        self.ptrs = [a.ctypes.data_as(ctypes.c_void_p) for a in arrays]
        self.fn = lib.bank_step
        vp = ctypes.c_void_p
        self.fn.argtypes = [ctypes.c_int, vp, vp, vp, vp, vp, vp, vp, ctypes.c_double, vp, vp, vp]
        self.fn.restype = None

    def step(self, x: np.ndarray, s: np.ndarray, u: np.ndarray, sd: np.ndarray, h: float
             ) -> np.ndarray:
        """One step of every circuit; inputs copied into the bound buffers (as the bank's
        buffered call does), the new currents returned as a copy."""
        for buf, v in zip(self.inputs, (x, s, u, sd), strict=True):
            buf[:] = v
        p = self.ptrs
        self.fn(self.n, p[0], p[1], p[2], p[3], p[4], p[5], p[6], h, p[7], p[8], p[9])
        return self.x1.copy()


def _compile_baseline(tmp: Path) -> ctypes.CDLL:
    src = tmp / "baseline.c"
    src.write_text(_C_SOURCE)
    lib = tmp / "baseline.so"
    subprocess.run(["cc", "-O3", "-shared", "-fPIC", str(src), "-o", str(lib), "-lm"], check=True)
    return ctypes.CDLL(str(lib))


def _per_step(fn, steps: int) -> float:  # type: ignore[no-untyped-def]
    """Best of 5 runs of CPU time per call (process time: robust against other load on
    the machine; equal to wall time on an idle one)."""
    fn()
    best = np.inf
    for _ in range(5):
        t0 = time.process_time()
        for _ in range(steps):
            fn()
        best = min(best, (time.process_time() - t0) / steps)
    return best


def _import_time() -> float:
    code = "import time; t = time.perf_counter(); import maglevkit; print(time.perf_counter() - t)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip())


def _accuracy(magnet_name: str) -> list[str]:
    """Interpolation error of each method: maps on a coarse grid (every other point of a
    fine grid) against the fine grid's points that the coarse grid does not contain."""
    mag = mk.load_magnet(magnet_name)
    fine_g, fine_i = np.linspace(0.005, 0.016, 23), np.linspace(0.0, 80.0, 81)
    fine = mk.build_maps(mag, gaps_m=fine_g, currents_A=fine_i, progress=False)
    coarse = mk.build_maps(mag, gaps_m=fine_g[::2], currents_A=fine_i[::2], progress=False)
    from maglevkit.reduced.tables import cell_table

    gs, gi = extend_axis(coarse.gaps_m), extend_axis(coarse.currents_A)
    mask = np.ones((fine_g.size, fine_i.size), dtype=bool)
    mask[::2, ::2] = False
    G, II = np.meshgrid(fine_g, fine_i, indexing="ij")
    rows = []
    for method in ("bicubic", "monotone", "bilinear"):
        errs = []
        for v in ("inductance_H", "dL_ds_H_per_m", "force_N"):
            worst = 0.0
            for c in coarse.circuits:
                vals = extend_values(extend_values(coarse.variable(v, c), axis=0), axis=1)
                tab = cell_table(gs, gi, vals[None], method=method)
                est = tab.evaluate(G[mask], II[mask])[..., 0]
                ref = fine.variable(v, c)[mask]
                worst = max(worst, float(np.max(np.abs(est - ref)) / np.max(np.abs(ref))))
            errs.append(worst)
        rows.append(f"| {method} | " + " | ".join(f"{e:.2e}" for e in errs) + " |")
    return rows


def _size_row(maps: mk.CharacteristicMaps, n: int, lib: ctypes.CDLL, cache: Path
              ) -> tuple[str, tuple[float, float, float]]:
    """One table row: ``n`` circuits (n/2 TR09 magnets, or one magnet for n = 1)."""
    members = {f"m{k}": maps for k in range(max(1, n // 2))}
    t0 = time.perf_counter()
    bank = MagnetBank(members, compiled="always", cache_dir=cache)
    st = bank.initial_state(gaps_m=0.010, currents_A=33.5)
    u = bank.resistance_ohm * 33.5 * 1.05
    t_build = time.perf_counter() - t0
    t0 = time.perf_counter()
    bank.step(st, DT, u)
    t_first = time.perf_counter() - t0
    bank2 = MagnetBank(members, compiled="always", cache_dir=cache)
    t0 = time.perf_counter()
    bank2.step(st, DT, u)
    t_cached = time.perf_counter() - t0
    nc = bank.n_circuits
    steps = max(200, min(20000, 200000 // nc))
    state = [st]
    sd = np.zeros(nc)

    def bank_step() -> None:
        state[0], _ = bank.step(state[0], DT, u, gap_rates_m_per_s=sd)

    t_bank = _per_step(bank_step, steps)
    # the in-place stepper: voltages, gaps and gap rates written in every step (as a
    # co-simulation does, and as the baseline's call copies its four inputs)
    stepper = bank.stepper(st, DT)
    g_in = np.full(nc, 0.010)

    def stepper_step() -> None:
        stepper.advance(voltages_V=u, gaps_m=g_in, gap_rates_m_per_s=sd)

    t_stepper = _per_step(stepper_step, steps)
    # the same step through CasADi's own code generation, and lanes 2 wide (what a
    # processor without AVX2 gets)
    other = {}
    for key, codegen, target in (("casadi", "casadi", None), ("lanes2", "lanes", (2, False, ()))):
        orig = bank_mod.lane_target
        if target is not None:
            bank_mod.lane_target = lambda target=target: target  # type: ignore[assignment]
        try:
            b2 = MagnetBank(members, compiled="always", cache_dir=cache, codegen=codegen)
            st2 = [b2.initial_state(gaps_m=0.010, currents_A=33.5)]
            b2.step(st2[0], DT, u, gap_rates_m_per_s=sd)
        finally:
            bank_mod.lane_target = orig

        def other_step(b2: MagnetBank = b2, st2: list = st2) -> None:
            st2[0], _ = b2.step(st2[0], DT, u, gap_rates_m_per_s=sd)

        other[key] = _per_step(other_step, steps)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        interp = MagnetBank(members, compiled="never")
    ist = [interp.initial_state(gaps_m=0.010, currents_A=33.5)]

    def interp_step() -> None:
        ist[0], _ = interp.step(ist[0], DT, u, gap_rates_m_per_s=sd)

    t_interp = _per_step(interp_step, max(5, steps // 50))
    base = _Baseline(maps, nc, lib)
    # agreement on a spread of states (different cells per circuit)
    rng = np.random.default_rng(0)
    x = rng.uniform(5.0, 60.0, nc)
    s = rng.uniform(0.006, 0.015, nc)
    rate = rng.uniform(-0.05, 0.05, nc)
    volts = rng.uniform(0.0, 100.0, nc)
    xb = base.step(x, s, volts, rate, DT)
    _, ob = bank.step(bank.initial_state(gaps_m=s, currents_A=x), DT, volts, gap_rates_m_per_s=rate)
    agree = float(np.max(np.abs(xb - ob.inductor_currents_A) / np.abs(xb)))
    t_base = _per_step(lambda: base.step(x, s, u, sd, DT), steps)
    loop_txt = "-"
    if nc <= 100:
        singles = [mk.CurrentModel(maps) for _ in range(max(1, nc // 2))]
        sst = [m.initial_state(gaps_m=0.010, currents_A=33.5) for m in singles]
        us = singles[0].resistance_ohm * 33.5 * 1.05

        def loop() -> None:
            for k, m in enumerate(singles):
                sst[k], _ = m.step(sst[k], DT, us, gaps_m=0.010, gap_rates_m_per_s=0.0)

        t_loop = _per_step(loop, max(20, steps // 20))
        loop_txt = f"{t_loop / nc * 1e9:.0f}"
    row = (f"| {nc} | {t_bank / nc * 1e9:.0f} | {t_stepper / nc * 1e9:.0f} | "
           f"{other['lanes2'] / nc * 1e9:.0f} | "
           f"{other['casadi'] / nc * 1e9:.0f} | {t_interp / nc * 1e9:.0f} | "
           f"{loop_txt} | {t_base / nc * 1e9:.0f} | {t_bank / t_base:.2f} | "
           f"{t_stepper / t_base:.2f} | {DT / t_bank:.0f} | {DT / t_stepper:.0f} | "
           f"{other['casadi'] / t_bank:.1f} | {agree:.1e} |")
    return row, (t_build, t_first, t_cached)


def run() -> str:
    if shutil.which("cc") is None:
        return "No C compiler on this machine: the compiled bank and the baseline need one."
    maps = mk.build_maps(mk.load_magnet("tr09-standard"), gaps_m=np.linspace(0.005, 0.016, 12),
                         currents_A=np.linspace(0.0, 80.0, 41), progress=False)
    rows = []
    cache = Path(tempfile.mkdtemp(prefix="maglevkit-bench-cache-"))
    compile_cost = {}
    with tempfile.TemporaryDirectory() as tmp:
        lib = _compile_baseline(Path(tmp))
        for n in SIZES:
            row, cost = _size_row(maps, n, lib, cache)
            rows.append(row)
            compile_cost[max(2, n)] = cost
    shutil.rmtree(cache, ignore_errors=True)
    comp_rows = [f"| {nc} | {b:.2f} | {f:.2f} | {c * 1e3:.0f} |"
                 for nc, (b, f, c) in compile_cost.items()]
    acc = _accuracy("tr09-standard")
    imp = min(_import_time() for _ in range(3))
    return "\n".join([
        "TR09 standard magnets (2 circuits each; maps 12 x 41 points, shared by all "
        "magnets), one `MagnetBank.step` of 1 ms (RK4, 1 sub-step) per call; times per "
        "circuit-step in ns (CPU time of the benchmark process, best of 5 runs), each "
        "a whole call from Python.  *bank step* is `MagnetBank.step` (new state and "
        "output objects per call) with the default compiled kernel "
        f"(`codegen='lanes'`: {lane_target()[0]} circuits per SIMD vector on this "
        "machine), *stepper* the same kernel through `MagnetBank.stepper` "
        "(`BankStepper.advance(voltages_V=, gaps_m=, gap_rates_m_per_s=)`: inputs copied into bound "
        "buffers, outputs left in alternating buffers), *2 lanes* the same generator "
        "forced to 2-wide vectors (what a processor "
        "without AVX2 gets), *CasADi C* CasADi's own code generation of the same function "
        "(`codegen='casadi'`), *interpreted* the same CasADi function on its virtual "
        "machine, *step loop* one `CurrentModel.step` per magnet, *baseline* the "
        "independent scalar C kernel written in this benchmark (called once per step "
        "through ctypes, its four inputs copied into bound buffers and its result "
        "copied out).  Ratio = bank / baseline (the figure of merit; target <= 2 at "
        "N >= 100), for `step` and for the stepper; RTF = real-time factor at 1 kHz "
        "(target >= 50 at 100 circuits); speed-up = CasADi C / bank step; agreement = "
        "max relative difference of the currents after one step, bank "
        "vs baseline.",
        "",
        "| circuits | bank step [ns] | stepper [ns] | 2 lanes [ns] | CasADi C [ns] | "
        "interpreted [ns] | step loop [ns] | baseline [ns] | ratio step | ratio stepper | "
        "RTF step | RTF stepper | speed-up | agreement |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        "Set-up and compile cost [s] (bank construction; first step incl. C generation and "
        "compilation; first step of a second bank of the same magnets, which finds the "
        "compiled library in the on-disk cache [ms]):",
        "",
        "| circuits | construct [s] | first step, compile [s] | first step, cached [ms] |",
        "|---|---|---|---|",
        *comp_rows,
        "",
        f"`import maglevkit` in a fresh interpreter: {imp:.2f} s (best of 3).",
        "",
        "Interpolation accuracy: maps on a 12 x 41 grid evaluated at the points of a "
        "23 x 81 grid that the coarse grid lacks, max error relative to each map's largest "
        "value (TR09 standard, both circuits):",
        "",
        "| interpolation | L~ | dL/ds | F |",
        "|---|---|---|---|",
        *acc,
    ])


if __name__ == "__main__":
    os.environ.setdefault("PYTHONWARNINGS", "ignore")
    print(run())
