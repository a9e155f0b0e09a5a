"""Transrapid-type levitation magnet: a row of poles under the slotted long stator.

Standard magnets (two 6-pole half magnets, two circuits) and bow magnets (three
circuits) are the same builder; which pole feeds which circuit is a parameter.
Longitudinal cut (x along the track, poles hang under the stator, see docs/magnets.md)::

        S1 --stator-- S2 --stator-- S3 ...      stator yoke (laminated long-stator pack)
        |             |             |
       gap1          gap2          gap3         air gap + stator teeth (one gap input each)
        |             |             |
        H1 ==leak_pp== H2 ==leak_pp== H3 ...    pole heads (pole face level)
        |  \\          |  \\          |
      core1 leak_pb  core2 leak_pb core3        pole cores with coils, polarity + - + ...
        |  /          |  /          |
        K1 ---back--- K2 ---back--- K3 ...      pole back (solid)

Per pole k: ``core_k`` (K_k -> H_k, coil, saturable, eddy currents), ``gap_k``
(H_k -> S_k: air gap with Carter's coefficient of the stator slots, the recessed
linear-generator grooves of the pole face and the fringing flanks, in series with the
saturable stator teeth), ``leak_pb_k`` (H_k -> K_k: leakage around the coil back into
the pole back).  Between neighbours: ``back_k`` (K_k -> K_k+1), ``stator_k``
(S_k -> S_k+1), ``leak_pp_k`` (H_k -> H_k+1).  The paper's Fig. 3 flux paths map to:
nominal flux -> the ``pole_area / s'`` term, LIG flux -> the groove term
``A_g / (s' + d_g)``, notch flux into the stator slots -> Carter's coefficient, leakage
-> ``leak_pp``/``leak_pb``.  All formulas and their sources: docs/magnets.md.

End poles are built like the inner poles (same core, coil and turns); they differ only
in having one neighbour, so their outer flank leaks into the pole back (extra
``leak_pb`` length) instead of to a neighbour pole.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from ..circuit.elements import AirGap, EddyCurrent, Element, IronPath, LeakagePermeance
from ..circuit.network import Branch, Circuit, Coil, Network
from ..errors import ParameterFileError
from ..materials import MU0, Material
from .base import (
    ModelOptions,
    PlausibleRange,
    Schema,
    register_kind,
    resistivity,
    resolve_material,
    take,
)

__all__ = ["build_levitation_magnet", "pole_gap_names"]

MAGNET_SCHEMA = {
    "kind": Schema(str),
    "name": Schema(str, required=False, default="levitation magnet"),
    "poles": Schema(int, unit="-"),
    "pole_pitch": Schema(float, unit="m"),
    "pole_length": Schema(float, unit="m"),
    "pole_width": Schema(float, unit="m"),
    "core_height": Schema(float, unit="m"),
    "coil_height": Schema(float, unit="m"),
    "coil_thickness": Schema(float, unit="m"),
    "coil_to_face": Schema(float, unit="m"),
    "turns_per_pole": Schema(float, unit="-", whole=True),
    "resistance_per_pole": Schema(float, unit="ohm"),
    "back_height": Schema(float, unit="m"),
    "back_width": Schema(float, unit="m"),
    "lig_grooves": Schema(int, unit="-", check="nonnegative"),
    "lig_groove_width": Schema(float, unit="m"),
    "lig_groove_depth": Schema(float, unit="m"),
    "material": Schema(str),
    "resistivity": Schema(float, required=False, unit="ohm m"),
}
CIRCUITS_SCHEMA = {
    "names": Schema(list),
    "assignment": Schema(list),
}
STATOR_SCHEMA = {
    "slot_pitch": Schema(float, unit="m"),
    "slot_opening": Schema(float, unit="m"),
    "slot_depth": Schema(float, unit="m"),
    "yoke_height": Schema(float, unit="m"),
    "width": Schema(float, unit="m"),
    "material": Schema(str),
}


def pole_gap_names(poles: int) -> tuple[str, ...]:
    """Gap input names ``("p01", "p02", ...)`` of a magnet with ``poles`` poles."""
    return tuple(f"p{k:02d}" for k in range(1, poles + 1))


def _circuits(raw: Any, poles: int) -> tuple[list[str], list[int]]:
    """Validate ``[circuits]``: names, and the 1-based circuit number of every pole."""
    c = take(raw, CIRCUITS_SCHEMA, "circuits")
    names = c["names"]
    if not names or not all(isinstance(n, str) and n for n in names):
        raise ParameterFileError(f"[circuits] names = {names!r}: expected a list of non-empty "
                                 "strings, one per electric circuit")
    if len(set(names)) != len(names):
        raise ParameterFileError(f"[circuits] names = {names!r}: circuit names must be unique")
    assign = c["assignment"]
    if len(assign) != poles:
        raise ParameterFileError(
            f"[circuits] assignment has {len(assign)} entries but the magnet has {poles} poles; "
            "give the circuit number (1-based) of every pole, in pole order")
    n = len(names)
    for k, a in enumerate(assign, start=1):
        if isinstance(a, bool) or not isinstance(a, int) or not 1 <= a <= n:
            raise ParameterFileError(
                f"[circuits] assignment: pole {k} -> {a!r} is not a circuit number; "
                f"allowed are 1..{n} (names: {', '.join(names)})")
    empty = [names[i] for i in range(n) if (i + 1) not in assign]
    if empty:
        raise ParameterFileError(f"[circuits] circuit(s) {empty} feed no pole; every circuit "
                                 "named in 'names' needs at least one pole in 'assignment'")
    return list(names), list(assign)


def build_levitation_magnet(params: Mapping[str, Any], materials: Mapping[str, Material],
                            options: ModelOptions) -> tuple[str, Network]:
    """Build a levitation magnet network from parsed parameters (see module docstring)."""
    m = take(params["magnet"], MAGNET_SCHEMA, "magnet")
    for table in ("circuits", "stator"):
        if table not in params:
            raise ParameterFileError(f"missing the [{table}] table")
    st = take(params["stator"], STATOR_SCHEMA, "stator")
    poles = m["poles"]
    if poles < 2:
        raise ParameterFileError(f"[magnet] poles = {poles}: a levitation magnet needs >= 2 "
                                 "poles (flux returns through the neighbouring pole)")
    names, assign = _circuits(params["circuits"], poles)

    tau, lp, wp = m["pole_pitch"], m["pole_length"], m["pole_width"]
    hcore, hc, tc, hf = m["core_height"], m["coil_height"], m["coil_thickness"], m["coil_to_face"]
    hb, wb = m["back_height"], m["back_width"]
    ng, bg, dg = m["lig_grooves"], m["lig_groove_width"], m["lig_groove_depth"]
    window = tau - lp
    if window <= 2.0 * tc:
        raise ParameterFileError(
            f"[magnet] two coils of coil_thickness {tc:g} m do not fit between neighbouring "
            f"pole cores (pole_pitch - pole_length = {window:g} m)")
    if hc + hf > hcore:
        raise ParameterFileError(f"[magnet] coil_height + coil_to_face = {hc + hf:g} m exceeds "
                                 f"core_height = {hcore:g} m; the coil must fit on the core")
    if ng * bg >= lp:
        raise ParameterFileError(f"[magnet] {ng} LIG grooves of width {bg:g} m leave no pole "
                                 f"face on a pole of length {lp:g} m")
    if st["width"] < wp:
        raise ParameterFileError(f"[stator] width = {st['width']:g} m is narrower than the pole "
                                 f"width {wp:g} m; the stator must cover the pole face")
    if st["slot_opening"] >= st["slot_pitch"]:
        raise ParameterFileError("[stator] slot_opening must be smaller than slot_pitch")

    core_mat = resolve_material(m["material"], materials, "magnet")
    stator_mat = resolve_material(st["material"], materials, "stator")
    gaps = pole_gap_names(poles)

    # ---- air gap of one pole: face teeth, LIG grooves, flanks; Carter for the stator slots
    face_area = (lp - ng * bg) * wp
    grooves = ((ng * bg * wp, dg),) if ng > 0 else ()
    overhang = 0.5 * (st["width"] - wp)
    edges: list[tuple[float, float]] = []
    if options.fringing:
        edges += [(wp, hf), (wp, hf)]                         # flanks facing the neighbours
        if overhang > 0.0:
            r = min(hf, overhang)                             # limited by the stator edge
            edges += [(lp, r), (lp, r)]
    tooth_area = lp * wp * (1.0 - st["slot_opening"] / st["slot_pitch"])
    core_len = hcore + 0.5 * hb
    stator_area = st["yoke_height"] * st["width"]

    # ---- leakage estimates (Roters' method, docs/magnets.md)
    # neighbour poles: parallel faces across the window; the MMF rises linearly along
    # the coil (energy-equivalent height h_c/3) and is full on the flank above it
    g_pp = MU0 * wp * (hc / 3.0 + hf) / window
    # around the coil into the own pole back: half hollow cylinders around the coil's
    # cross-section (inner radius h_c/2, radial extent t_c) along the coil sides that do
    # not face a neighbour pole: both across-track sides, plus the outer side of an end pole
    side = lp + 2.0 * tc

    def g_pb(k: int) -> float:
        length = 2.0 * side + (wp + 2.0 * tc) * ((k == 0) + (k == poles - 1))
        return MU0 * length * math.log(1.0 + tc / (0.5 * hc)) / math.pi

    rho = resistivity(m["resistivity"], core_mat, "magnet") if options.eddy_currents else 0.0

    branches: list[Branch] = []
    for k in range(poles):
        p = gaps[k]
        core: list[Element] = [IronPath(f"iron_core_{p}", core_len, lp * wp, core_mat)]
        if options.eddy_currents:
            core.append(EddyCurrent.solid_rectangular(f"eddy_core_{p}", lp, wp, core_len, rho))
        branches.append(Branch(f"core_{p}", f"K{k + 1}", f"H{k + 1}", tuple(core)))
        branches.append(Branch(f"gap_{p}", f"H{k + 1}", f"S{k + 1}", (
            AirGap(f"gap_{p}", gap_input=p, pole_area=face_area, fringe_edges=tuple(edges),
                   slot_pitch=st["slot_pitch"], slot_opening=st["slot_opening"],
                   recesses=grooves),
            IronPath(f"iron_teeth_{p}", st["slot_depth"], tooth_area, stator_mat),
        )))
        if options.leakage:
            branches.append(Branch(f"leak_pb_{p}", f"H{k + 1}", f"K{k + 1}",
                                   (LeakagePermeance(f"leak_pb_{p}", g_pb(k)),)))
    for k in range(poles - 1):
        q = f"{gaps[k]}_{gaps[k + 1]}"
        back: list[Element] = [IronPath(f"iron_back_{q}", tau, hb * wb, core_mat)]
        if options.eddy_currents:
            back.append(EddyCurrent.solid_rectangular(f"eddy_back_{q}", hb, wb, tau, rho))
        branches.append(Branch(f"back_{q}", f"K{k + 1}", f"K{k + 2}", tuple(back)))
        branches.append(Branch(f"stator_{q}", f"S{k + 1}", f"S{k + 2}",
                               (IronPath(f"iron_stator_{q}", tau, stator_area, stator_mat),)))
        if options.leakage:
            branches.append(Branch(f"leak_pp_{q}", f"H{k + 1}", f"H{k + 2}",
                                   (LeakagePermeance(f"leak_pp_{q}", g_pp),)))

    # Alternating polarity: pole 1 drives flux up (towards the stator), pole 2 down, ...
    circuits = []
    for i, cname in enumerate(names):
        coils = tuple(Coil(f"core_{gaps[k]}", m["turns_per_pole"], 1 if k % 2 == 0 else -1)
                      for k in range(poles) if assign[k] == i + 1)
        circuits.append(Circuit(cname, m["resistance_per_pole"] * len(coils), coils))
    return m["name"], Network(tuple(branches), tuple(circuits), name=m["name"])


def levitation_magnet_range(params: Mapping[str, Any]) -> PlausibleRange:
    """Plausible inputs: gaps up to the smaller pole-face dimension, currents up to
    :data:`~maglevkit.magnets.base.MAX_CURRENT_DENSITY_A_PER_M2` in one pole's coil
    (``turns_per_pole`` on ``coil_height x coil_thickness``)."""
    m = params["magnet"]
    lp, wp = float(m["pole_length"]), float(m["pole_width"])
    return PlausibleRange.from_geometry(
        gap_m=min(lp, wp), gap_basis="the pole " + ("length" if lp <= wp else "width"),
        turns=float(m["turns_per_pole"]),
        winding_area_m2=float(m["coil_height"]) * float(m["coil_thickness"]),
        winding="the coil of one pole")


register_kind("levitation_magnet", build_levitation_magnet, ("circuits", "stator"),
              levitation_magnet_range)
