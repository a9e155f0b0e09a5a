"""Transient 2-D finite-element reference of the guidance magnet with solid iron (issue 26).

Voltage steps ``U = R I0 -> R I1`` at a fixed gap on the cross-section of
``benchmarks/fem_guidance.py`` (its geometry, tensor mesh and regions: pole bars, legs and
yoke, the rail, the coil sides; half model y >= 0, A = 0 on the box), solved with the
magnetodynamic method of ``benchmarks/fem_u_magnet_transient.py`` (``UMagnetFem``'s time
stepping, reused by subclassing: P1, lumped conductor mass, variable-step BDF2, Newton with
the coil current and one electric-potential gradient per conducting body, zero net current
per body)::

    sigma (dA/dt - u_b) - div( nu grad A ) = J_coil,    U = R I + dpsi/dt

What conducts is what maglevkit's guidance network gives eddy elements, all solid
``9SMnPb28`` (``src/maglevkit/magnets/guidance.py``: the legs, the yoke and the rail; the
pole bars in the legs' branches with ``eddy_model = "lumped"``, their own ladders with
``"ladder"``):

* the magnet (pole bars, legs, yoke) is one conducting body, the rail another; the body's
  eddy currents run along the track and close at its far ends (the 2-D picture, as the
  network's ``EddyCurrent.solid_rectangular`` of a bar much wider than thick);
* the legs and the yoke carry the depth ratio ``k = section_length / (yokes_per_section x
  yoke_width)`` of ``fem_guidance.py`` in their reluctivity (the real flux density is ``k B``)
  and so also in their conductivity: in the real yoke the flux per unit depth, hence the
  electric field along the track, is ``k`` times the model's, and Ampere's law at a fixed
  position along the track sees the real current density ``k sigma dA/dt``.  The model's
  eddy power over the section length is then the real power over the yokes' width.
* the coil: ``turns_per_yoke`` conductors per side over the section length, the circuit
  ``yokes_per_section x resistance_per_yoke`` (one section, as one circuit of the network;
  both sections alike), ``psi = turns x`` the flux through the yokes (fem_guidance.py).

``python benchmarks/fem_guidance_transient.py --fem cases`` (``study``: mesh and time step
at the first case; ``noeddy``: the steps with sigma = 0) records
``benchmarks/results/fem_guidance_transient.json``; without ``--fem`` it compares the
recorded runs with the flux model (``tr-guidance``, its 2-D cut with ``end_effects = false``
and the bundled file; ``eddy_model`` ``"lumped"`` and ``"ladder"``) and prints the tables of
docs/validation_fem.md (section "Guidance magnet: voltage-step transient"); ``--figure
docs/figures/fem-guidance-transient.png`` draws the steps.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem_common import Reluctivity  # noqa: E402
from fem_guidance import Geometry, build_mesh, regions  # noqa: E402
from fem_u_magnet_transient import (  # noqa: E402
    P1,
    UMagnetFem,
    _fem_energy,
    _record,
    body_energies,
    metrics,
    rise_time,
    time_grid,
)

import maglevkit as mk  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results" / "fem_guidance_transient.json"
MAGNET = "tr-guidance"

#: (label, gap [m], I0 [A], I1 [A]): below the knee (33.6 A at 10 mm) at two gaps, and into
#: saturation
CASES = (("10 mm, 10 -> 20 A", 0.010, 10.0, 20.0),
         ("6 mm, 10 -> 20 A", 0.006, 10.0, 20.0),
         ("10 mm, 20 -> 50 A", 0.010, 20.0, 50.0))
T_END = 4.0                  # s (the eddy time constants of 40-70 mm solid steel are ~1 s)
REFINE = 2.0                 # fem_guidance.build_mesh's refinement (1.5 mm at iron edges)
DT0, BLOCK, DT_MAX = 5e-5, 8, 0.02
#: convergence at the first case: (label, refine, dt0, block, dt_max)
STUDY = (("mesh x 1.5", 1.5 * REFINE, DT0, BLOCK, DT_MAX),
         ("dt / 2", REFINE, DT0 / 2, 2 * BLOCK, DT_MAX / 2))


class GuidanceFem(UMagnetFem):
    """The guidance cross-section as a :class:`UMagnetFem`: its time stepping
    (``step_response``, ``static``) on the mesh, bodies, materials and coil of
    ``fem_guidance.py``; per-region reluctivity (the legs' and yoke's depth ratio)."""

    def __init__(self, g: Geometry, s: float, *, refine: float = REFINE,
                 sigma: float | None = None, resistance: float) -> None:
        self.s, self.g = s, g
        self.mesh = build_mesh(g, s, refine)
        self.fe = fe = P1(self.mesh)
        bars, rail, yokes, _, sign = regions(self.mesh, g, s)
        k = g.depth / g.yoke_depth
        mat, rail_mat = mk.get_material(g.material), mk.get_material(g.rail_material)
        self.sigma = 1.0 / float(mat.resistivity_ohm_m) if sigma is None else sigma
        rail_share = float(mat.resistivity_ohm_m) / float(rail_mat.resistivity_ohm_m)
        self.R = resistance
        # conductor masses weighted by the part's conductivity over self.sigma (the legs' and
        # yoke's k: module docstring); the zero-current rows and the eddy power use the same
        self.m_core = fe.lumped(bars) + k * fe.lumped(yokes)
        self.m_rail = rail_share * fe.lumped(rail)
        self.vol_core, self.vol_rail = self.m_core.sum(), self.m_rail.sum()
        self.iron_e = self.iron = bars | rail | yokes
        self.nside = g.turns                        # conductors per coil side
        self.ac = g.build * g.ll * g.hc             # one coil side's area
        w = sign * fe.area / 3.0
        self.bsign = np.bincount(fe.t.ravel(), np.repeat(w[None], 3, 0).ravel(), fe.n)
        self.kpsi = 2.0 * g.depth * self.nside / self.ac * self.bsign   # both halves
        p = self.mesh.p
        bnd = self.mesh.boundary_nodes()
        self.free = np.setdiff1d(np.arange(fe.n), bnd[p[1, bnd] > 1e-9])  # y = 0: natural
        # per-region tables of mu0 nu, the Newton coefficient and the energy density
        bb = np.concatenate([np.linspace(0.0, 3.0, 30001), np.linspace(3.0, 20.0, 3401)[1:]])
        self._tb = bb
        self._region = np.zeros(fe.t.shape[1], dtype=int)
        self._tables = []
        for idx, (mask, material, ratio) in enumerate(
                ((bars, g.material, 1.0), (rail, g.rail_material, 1.0),
                 (yokes, g.material, k)), start=1):
            self._region[mask] = idx
            rel = Reluctivity(material=material, depth_ratio=ratio)
            tnu, tc = rel.nu_r(bb)
            h = np.asarray(mk.get_material(material).field_strength(ratio * bb), dtype=float)
            # w(B) = int_0^B H(k b) db: the real part's energy per model volume
            wb = np.concatenate([[0.0], np.cumsum(0.5 * (h[1:] + h[:-1]) * np.diff(bb))])
            self._tables.append((idx, tnu, tc, wb))

    def _coeffs(self, A: np.ndarray):  # type: ignore[no-untyped-def]
        ax, ay = self.fe.grad(A)
        b = np.hypot(ax, ay)
        nu, c = np.ones_like(b), np.zeros_like(b)
        for idx, tnu, tc, _ in self._tables:
            m = self._region == idx
            nu[m] = np.interp(b[m], self._tb, tnu)
            c[m] = np.interp(b[m], self._tb, tc)
        return ax, ay, b, nu, c

    def energy(self, A: np.ndarray) -> float:
        """Stored magnetic energy [J] of the section (both halves)."""
        from fem_common import MU0

        ax, ay = self.fe.grad(A)
        b = np.hypot(ax, ay)
        w = b**2 / (2 * MU0)
        for idx, _, _, wb in self._tables:
            m = self._region == idx
            w[m] = np.interp(b[m], self._tb, wb)
        return float(2.0 * self.g.depth * np.sum(w * self.fe.area))


def geometry() -> Geometry:
    return Geometry.from_magnet(mk.load_magnet(MAGNET))


def section_resistance() -> float:
    """One circuit's resistance [ohm] of the bundled network (yokes_per_section x
    resistance_per_yoke)."""
    return float(mk.load_magnet(MAGNET).network.resistances[0])


def run_fem(part: str) -> dict:
    """The FEM runs of ``part`` (``cases``, ``study``, ``noeddy``)."""
    g, R = geometry(), section_resistance()
    sigma = 0.0 if part == "noeddy" else None
    if part == "study":
        label0, s0, i0, i1 = CASES[0]
        runs = [(f"{label0}, {lab}", s0, i0, i1, ref, dt0, blk, dtm)
                for lab, ref, dt0, blk, dtm in STUDY]
    else:
        runs = [(label, s, i0, i1, REFINE, DT0, BLOCK, DT_MAX) for label, s, i0, i1 in CASES]
    out: list[dict] = []
    for label, s, i0, i1, refine, dt0, block, dt_max in runs:
        fem = GuidanceFem(g, s, refine=refine, sigma=sigma, resistance=R)
        r = fem.step_response(i0, i1, time_grid(T_END, dt0, block, dt_max))
        rec = _record(r, label, float("nan"))
        rec.pop("h_surface_m")
        rec.update(refine=refine, dt0_s=dt0, block=block, dt_max_s=dt_max, resistance_ohm=R,
                   factorisations=fem.factorisations)
        out.append(rec)
        print(f"{part} {label}: {r.nodes} nodes, {r.time_s.size - 1} steps, "
              f"{fem.factorisations} LU, {r.wall_s:.0f} s, energy residual "
              f"{r.energy_residual:.1e}", flush=True)
    return {"generated_by": f"benchmarks/fem_guidance_transient.py --fem {part}",
            "t_end_s": T_END, "runs": out}


def load(part: str = "cases") -> list[dict]:
    """Recorded FEM runs of ``part``."""
    return json.loads(RESULTS.read_text())[part]["runs"]


def model_step(ref: dict, magnet: mk.Magnet) -> dict:
    """The flux model of ``magnet`` (both sections stepped alike, as the FEM's section) at
    the recorded step's time points: current of circuit 0, eddy energy per section."""
    fm = mk.FluxModel(magnet, rtol=1e-7, compiled="never")
    R = magnet.network.resistances
    t0 = time.process_time()
    res = mk.simulate(fm, np.asarray(ref["time_s"]), gaps_m=ref["gap_m"],
                      voltages_V=R * ref["i1_A"], initial_currents_A=ref["i0_A"])
    core, rail = body_energies(res) if res.eddy_branch_names else (0.0, 0.0)
    return {"time_s": res.time_s, "current_A": res.currents_A[:, 0],
            "eddy_loss_J": 0.5 * res.eddy_loss_J, "e_core_J": 0.5 * core,
            "e_rail_J": 0.5 * rail, "cpu_s": time.process_time() - t0,
            "eddy_elements": len(res.eddy_branch_names)}


def guidance_magnet(*, end_effects: bool = True, eddy_currents: bool = True,
                    **options: object) -> mk.Magnet:
    """The bundled ``tr-guidance`` (``end_effects = true``: its air paths over the yokes'
    depth) or its 2-D cut (``false``: every path over the section length, as the FEM; the
    network of the statics tables in docs/validation_fem.md, there without eddy elements),
    with the ``load_magnet`` options (``eddy_model``, ``eddy_layers``)."""
    mag = mk.load_magnet(MAGNET, eddy_currents=eddy_currents, **options)
    if end_effects:
        return mag
    params = dict(mag.parameters)
    params["magnet"] = {**params["magnet"], "end_effects": False}
    params["provenance"] = {**params["provenance"],
                            "magnet.end_effects": "[E] modelling choice: 2-D cut"}
    return mk.build_magnet(params, options=mag.options, source=mag.source)


#: the models held against the FEM: label -> magnet (built on first use); "ladder" is the
#: guidance kind's ``eddy_model = "ladder"`` (legs, pole bars, yoke and rail as slab ladders;
#: the bundled file's since guideswitch, so "lumped" is named)
MODELS = {"2-D cut, lumped": lambda: guidance_magnet(end_effects=False, eddy_model="lumped"),
          "2-D cut, ladder n = 6": lambda: guidance_magnet(
              end_effects=False, eddy_model="ladder", eddy_layers=6),
          "2-D cut, ladder n = 8": lambda: guidance_magnet(
              end_effects=False, eddy_model="ladder", eddy_layers=8),
          "bundled, lumped": lambda: guidance_magnet(eddy_model="lumped"),
          "bundled, ladder n = 8": lambda: guidance_magnet(eddy_model="ladder", eddy_layers=8)}
#: the same networks without eddy elements against the FEM with sigma = 0
STATIC_MODELS = {"2-D cut, no eddy currents vs FEM sigma = 0":
                     lambda: guidance_magnet(end_effects=False, eddy_currents=False),
                 "bundled, no eddy currents vs FEM sigma = 0":
                     lambda: guidance_magnet(eddy_currents=False)}


def fem_change(run: dict, base: dict) -> float:
    """Largest |I_run - I_base| for t >= 1 ms on the base run's time points, as a share of
    the step."""
    tb = np.asarray(base["time_s"])
    late = tb >= 1e-3 - 1e-12
    other = np.interp(tb, np.asarray(run["time_s"]), np.asarray(run["current_A"]))
    return float(np.max(np.abs(other - np.asarray(base["current_A"]))[late])
                 / (base["i1_A"] - base["i0_A"]))


def compare() -> tuple[list[str], dict]:
    """Markdown tables of the model against the recorded FEM, and the metrics."""
    data = json.loads(RESULTS.read_text())
    cases, study = data["cases"]["runs"], data.get("study", {}).get("runs", [])
    noeddy = {r["label"]: r for r in data.get("noeddy", {}).get("runs", [])}
    lines = ["FEM convergence (first case; the current at 0.1 / 0.5 / 2 s, its largest change "
             "against the production run for t >= 1 ms in % of the step, t63):", "",
             "| run | nodes | steps | I(0.1 s) [A] | I(0.5 s) [A] | I(2 s) [A] | max change [%] "
             "| t63 [ms] | E_eddy [J] | energy residual | wall [s] |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in [cases[0], *study]:
        t, i = np.asarray(r["time_s"]), np.asarray(r["current_A"])
        e = _fem_energy(r, "eddy_power_core_W") + _fem_energy(r, "eddy_power_rail_W")
        at = [float(np.interp(x, t, i)) for x in (0.1, 0.5, 2.0)]
        lines.append(f"| {r['label']} (refine {r['refine']:g}, dt0 {r['dt0_s'] * 1e6:g} us, "
                     f"dt_max {r['dt_max_s'] * 1e3:g} ms) | {r['nodes']} | {r['steps']} | "
                     f"{at[0]:.4f} | {at[1]:.4f} | {at[2]:.4f} | "
                     f"{100 * fem_change(r, cases[0]):.3f} | "
                     f"{1e3 * rise_time(t, i, r['i0_A'], r['i1_A']):.2f} | {e:.2f} | "
                     f"{r['energy_residual']:.1e} | {r['wall_s']:.0f} |")
    table: dict = {}
    lines += ["", "Flux model (`tr-guidance`, split network) vs FEM; err: (model - FEM) "
              "current in % of the step, max over t >= 1 ms; t63: "
              "time to 63.2 % of the step; E_eddy per section over the run:", "",
              "| case | model | err at 1 ms [%] | max err [%] | t63 model / FEM [ms] | "
              "t63 err [%] | E_eddy model / FEM [J] | rail model / FEM [J] | eddy elements | "
              "CPU [s] |", "|---|---|---|---|---|---|---|---|---|---|"]
    mags = {label: make() for label, make in MODELS.items()}
    static_mags = {label: make() for label, make in STATIC_MODELS.items()}
    for ref in cases:
        variants = [(label, ref, mag) for label, mag in mags.items()]
        if ref["label"] in noeddy:
            variants += [(label, noeddy[ref["label"]], mag)
                         for label, mag in static_mags.items()]
        for name, fem, mag in variants:
            run = model_step(fem, mag)
            m = metrics(run["time_s"], run["current_A"], run["eddy_loss_J"], fem)
            m.update(e_rail_J=run["e_rail_J"], cpu_s=run["cpu_s"],
                     e_rail_fem_J=_fem_energy(fem, "eddy_power_rail_W"),
                     eddy_elements=run["eddy_elements"])
            table[ref["label"], name] = m
            lines.append(
                f"| {ref['label']} | {name} | {100 * m['err_1ms']:+.1f} | "
                f"{100 * m['err_max']:.1f} | {1e3 * m['t63_s']:.1f} / {1e3 * m['t63_fem_s']:.1f} "
                f"| {100 * (m['t63_s'] / m['t63_fem_s'] - 1):+.1f} | {m['e_eddy_J']:.2f} / "
                f"{m['e_eddy_fem_J']:.2f} | {m['e_rail_J']:.2f} / {m['e_rail_fem_J']:.2f} | "
                f"{m['eddy_elements']} | {m['cpu_s']:.1f} |")
    return lines, table


#: the models drawn by :func:`plot` (label -> matplotlib colour and line style)
PLOTTED = {"2-D cut, lumped": ("tab:red", "--"), "2-D cut, ladder n = 8": ("tab:blue", "-"),
           "bundled, lumped": ("tab:orange", ":"), "bundled, ladder n = 8": ("tab:cyan", "-.")}


def plot(path: str) -> None:
    """The recorded FEM steps against the flux model: normalised current and its error in %
    of the step (the 5 % aim shaded), one column per step."""
    from maglevkit.plotting import plt, save

    cases = load("cases")
    fig, ax = plt.subplots(2, len(cases), figsize=(4.4 * len(cases), 6.6), squeeze=False,
                           sharex=True)
    mags = {label: MODELS[label]() for label in PLOTTED}
    for j, ref in enumerate(cases):
        tf, i_f = np.asarray(ref["time_s"]), np.asarray(ref["current_A"])
        i0, step = ref["i0_A"], ref["i1_A"] - ref["i0_A"]
        ax[0, j].semilogx(tf[1:], (i_f[1:] - i0) / step, "k-", lw=3, alpha=0.4, label="FEM")
        for label, (col, ls) in PLOTTED.items():
            run = model_step(ref, mags[label])
            i = np.interp(tf, run["time_s"], run["current_A"])
            ax[0, j].semilogx(tf[1:], (i[1:] - i0) / step, color=col, ls=ls, label=label)
            ax[1, j].semilogx(tf[1:], 100 * (i - i_f)[1:] / step, color=col, ls=ls,
                              label=label)
        ax[0, j].set_title(f"{MAGNET}: {ref['label']}")
        ax[0, j].set_ylabel("(I - I0)/(I1 - I0)")
        ax[1, j].set_ylabel("(I - I_FEM)/(I1 - I0) [%]")
        ax[1, j].axhspan(-5, 5, color="0.9", zorder=0)
        ax[1, j].set_ylim(-15, 15)
        ax[1, j].set_xlabel("t [s]")
        for a in ax[:, j]:
            a.grid(True, which="both", alpha=0.3)
    ax[0, 0].legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    save(fig, path)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--fem", choices=("cases", "study", "noeddy"),
                    help="run that part of the FEM and store it in "
                         "benchmarks/results/fem_guidance_transient.json")
    ap.add_argument("--figure", default="",
                    help="draw the recorded steps against the flux model into this PNG")
    args = ap.parse_args(argv)
    if args.figure:
        plot(args.figure)
        return
    if args.fem:
        out = run_fem(args.fem)
        data = json.loads(RESULTS.read_text()) if RESULTS.exists() else {}
        data[args.fem] = out
        RESULTS.write_text(json.dumps(data, separators=(",", ":")) + "\n")
        print(f"wrote {RESULTS}")
        return
    print("\n".join(compare()[0]))


if __name__ == "__main__":
    main()
