"""Experiment behind docs/flux_model.md, "Integrator choice".

The flux DAE integrated by CVODES after eliminating the algebraic part (a Newton solve
inside every right-hand side, started from the interval's initial algebraic state) vs IDAS
on the full DAE, same tolerances, 1 s at a 1 ms hold step (gap sine 5 Hz +- 1 mm,
voltage +20 % at 0.1 s).

Usage: python benchmarks/experiment_cvodes_elimination.py {u-magnet|tr09-standard}
Not part of `make bench` (a one-off measurement that uses package internals).
"""

from __future__ import annotations

import sys
import time

import casadi as ca
import numpy as np

import maglevkit as mk
from maglevkit.circuit import assemble
from maglevkit.models import flux as fx


def main(name: str) -> None:
    mag = mk.load_magnet(name)
    fm = mk.FluxModel(mag)
    d = fx.flux_dae(mag.network, "idas", 1e-6, 1e-8, 20000, 2, 3)
    net = d.network
    eq = assemble(net)
    res_ohm = net.resistances
    r, ng, nl, nc = d.n_diff, d.n_gaps, d.n_loops, d.n_circuits
    y, u = ca.SX.sym("y", r), ca.SX.sym("U", nc)
    x, s, cur = eq.x, eq.s, eq.I
    hv = ca.vertcat(-eq.residual, u - res_ohm * cur)
    ydot = ca.mtimes(ca.DM(np.linalg.pinv(d.K)), hv)
    alg = ca.vertcat(ca.mtimes(ca.DM(d.D), x) - y, ca.mtimes(ca.DM(d.Q), hv))
    z = ca.vertcat(x, cur)
    gfun = ca.Function("g", [z, ca.vertcat(y, s, u)], [alg])
    # residual rows mix Wb, A and V; 1e-7 is reachable in double precision for all of them
    rf = ca.rootfinder("zs", "newton", gfun, {"error_on_fail": True, "abstol": 1e-7,
                                              "max_iter": 50})
    xd = ca.MX.sym("xd", r + ng)
    p = ca.MX.sym("p", 1 + nc + ng + nl + nc)
    hm, um, ratem, zg = p[0], p[1:1 + nc], p[1 + nc:1 + nc + ng], p[1 + nc + ng:]
    zs = rf(zg, ca.vertcat(xd, um))
    fy = ca.Function("fy", [ca.vertcat(y, s), z, u], [ydot])
    ode = hm * ca.vertcat(fy(xd, zs, um), ratem)
    integ = ca.integrator("cv", "cvodes", {"x": xd, "p": p, "ode": ode}, 0.0, 1.0,
                          {"reltol": 1e-6, "abstol": 1e-10, "max_num_steps": 20000})
    i0 = 20.0 if name == "u-magnet" else 34.0
    w0 = np.asarray(fm.initial_state(gaps_m=0.01, currents_A=i0)._vector(), dtype=float)
    wm, pm = ca.MX.sym("w", d.nw), ca.MX.sym("pp", 1 + nc + ng)
    nx = r + ng
    sol = integ(x0=wm[:nx], p=ca.vertcat(pm, wm[nx:]))
    zf = rf(wm[nx:], ca.vertcat(sol["xf"], pm[1:1 + nc]))
    step = ca.Function("cstep", [wm, pm], [ca.vertcat(sol["xf"], zf)])
    n = 1000
    tt = np.arange(n) * 1e-3
    pp = np.zeros((1 + nc + ng, n))
    pp[0] = 1e-3
    pp[1:1 + nc] = res_ohm[:, None] * i0 * np.where(tt >= 0.1, 1.2, 1.0)
    pp[1 + nc:] = 2 * np.pi * 5 * 1e-3 * np.cos(2 * np.pi * 5 * tt)[None, :]
    print(f"{name}: {d.nw} states ({r} differential, {nl} loop fluxes)")
    for f, label in ((d.accum(n), "IDAS on the DAE"), (step.mapaccum("acc", n),
                                                         "CVODES + Newton")):
        t0 = time.perf_counter()
        out = f(w0, pp)
        wall = time.perf_counter() - t0
        w = np.asarray(out[0] if isinstance(out, (list, tuple)) else out)
        print(f"  {label:16s} wall {wall:.3f} s, real-time factor {1 / wall:.2f}, "
              f"final currents {w[-nc:, -1]}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "u-magnet")
