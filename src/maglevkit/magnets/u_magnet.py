"""Parametric U-magnet (two legs, one yoke, one coil per leg) above a flat rail.

Network (see docs/equations.md, section "U-magnet"); each leg is split at ``K``
nodes along its coil (``coil_segments``, default 5) so that leakage leaves it part-way
up the winding, as it does in the field (a 2-D FEM of the bundled geometry,
docs/validation_fem.md)::

    YL --leg_left_K--> L_K ... L_1 --leg_left_0--> PL --gap_left--> RL --rail--> RR
    RR --gap_right--> PR --leg_right_0--> R_1 ... R_K --leg_right_K--> YR --yoke--> YL
    PL --leakage--> PR,  L_k --leakage_k--> R_k        (across the window)
    L_k --flank_left_k--> RL,  RR --flank_right_k--> R_k   (flanks beside the coil)

Geometry (all m): pole face ``A = pole_width x depth``; pole-centre distance
``c = window_width + pole_width``; leg path ``leg_height + yoke_thickness/2`` (split at
the nodes ``y_k = coil_gap_to_pole_face + (k - 1/2) h``, ``h = coil_height / K``, above
the pole face; the coil's turns are shared by the segments in proportion to the coil
height they hold); yoke path ``c``; rail path ``c + rail.thickness``.

Estimates of the secondary flux paths (Roters' method, docs/sources.md sec. 3):

* fringing at each pole edge that faces the rail: ``2 mu0 w/pi ln(1 + pi r/(2 s))``, with
  ``r`` the flank height between pole face and coil (``coil_gap_to_pole_face``); on the
  outer edge ``r`` is limited by the rail overhang; the two depth-wise ends fringe
  only with ``end_effects = true``.
* leakage across the window between the legs: parallel faces ``mu0 depth x/window_width``
  for the flank below the coil (``x = coil_gap_to_pole_face``, between the pole tips) and
  for each coil strip (``x = h``, between the nodes ``L_k`` and ``R_k``).  The MMF across
  the window falls along the coil because the nodes see the turns below them; as
  ``K -> oo`` the energy equals the classical ``coil_height/3`` estimate.  With
  ``end_effects`` quarter cylinders ``0.52 mu0 x`` are added at the two leg ends.
* flank leakage beside the coil, per strip ``[y_k - h/2, y_k + h/2]``: Roters' quarter
  circles from the flank at height ``y`` down to the level of the pole face (path
  ``pi y / 2``), i.e. quarter hollow cylinders ``2 mu0 w/pi ln(y_top/y_bottom)``, on the
  outer flank over the whole coil height and on the window flank as long as the circle
  lands before the window's centre plane (``y <= window_width/2``; above it the window
  leakage takes over).  The further path across the gap is left out: this flux spreads
  into the wide air space beside the pole, and the FEM shows it adds flux linkage but
  hardly any force (it does not depend on the gap).
* eddy currents (``eddy_model = "lumped"``, default): one element per iron part, solid bars
  (Saint-Venant formula) or a laminated stack (``sheet_thickness``); the rail is always
  solid.  ``eddy_model = "ladder"``: each part's section is ``eddy_layers`` nested flux
  tubes with their own eddy elements (:mod:`maglevkit.circuit.ladder`), diffusing across
  the bar's width (yoke, rail: their thickness) or across each sheet of a laminated core;
  with ``end_effects = false`` (a 2-D cross-section) the solid bar is the 2-D slab, with
  ``end_effects = true`` its conductances carry the Saint-Venant factor of the finite
  depth (the lumped element always does).  Each leg segment
  carries the eddy currents of its own length (the element conductance is proportional
  to the length), so every branch the winding sits on induces them.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..circuit.elements import (
    AirGap,
    EddyCurrent,
    Element,
    IronPath,
    LeakagePermeance,
    _rectangle_torsion_constant,
)
from ..circuit.ladder import ladder_branches
from ..circuit.network import Branch, Circuit, Coil, Network
from ..errors import ParameterFileError
from ..materials import MU0, Material
from .base import ModelOptions, PlausibleRange, Schema, register_kind, resolve_material, take

MAGNET_SCHEMA = {
    "kind": Schema(str),
    "name": Schema(str, required=False, default="U-magnet"),
    "turns": Schema(float, unit="-", whole=True),
    "resistance": Schema(float, unit="ohm"),
    "depth": Schema(float, unit="m"),
    "pole_width": Schema(float, unit="m"),
    "leg_height": Schema(float, unit="m"),
    "yoke_thickness": Schema(float, unit="m"),
    "window_width": Schema(float, unit="m"),
    "coil_thickness": Schema(float, unit="m"),
    "coil_height": Schema(float, unit="m"),
    "coil_gap_to_pole_face": Schema(float, unit="m"),
    "end_effects": Schema(bool),
    "material": Schema(str),
    "laminated": Schema(bool, required=False, default=False),
    "sheet_thickness": Schema(float, required=False, unit="m"),
    "resistivity": Schema(float, required=False, unit="ohm m"),
    "coil_segments": Schema(int, required=False, default=5, unit="-"),
}
RAIL_SCHEMA = {
    "thickness": Schema(float, unit="m"),
    "width": Schema(float, unit="m"),
    "material": Schema(str),
    "resistivity": Schema(float, required=False, unit="ohm m"),
}


def _resistivity(given: float | None, material: Material, where: str) -> float:
    if given is not None:
        return given
    if material.resistivity is None:
        raise ParameterFileError(
            f"[{where}] material {material.name!r} has no built-in resistivity; give "
            "'resistivity' (ohm m) or build the magnet with eddy_currents=False"
        )
    return material.resistivity


def build_u_magnet(params: Mapping[str, Any], materials: Mapping[str, Material],
                   options: ModelOptions) -> tuple[str, Network]:
    """Build the U-magnet network from parsed parameters (see module docstring)."""
    m = take(params["magnet"], MAGNET_SCHEMA, "magnet")
    if "rail" not in params:
        raise ParameterFileError("missing the [rail] table (thickness, width, material)")
    r = take(params["rail"], RAIL_SCHEMA, "rail")
    if m["laminated"] and m["sheet_thickness"] is None:
        raise ParameterFileError("[magnet] laminated = true needs sheet_thickness [m]")
    if m["sheet_thickness"] is not None and not m["laminated"]:
        raise ParameterFileError("[magnet] sheet_thickness is only meaningful with laminated = true")
    d, wp, hl = m["depth"], m["pole_width"], m["leg_height"]
    ty, ww, tc = m["yoke_thickness"], m["window_width"], m["coil_thickness"]
    hc, gcp = m["coil_height"], m["coil_gap_to_pole_face"]
    if hc + gcp > hl:
        raise ParameterFileError(f"[magnet] coil_height + coil_gap_to_pole_face = {hc + gcp:g} m "
                                 f"exceeds leg_height = {hl:g} m; the coil must fit on the leg")
    if 2.0 * tc >= ww:
        raise ParameterFileError(f"[magnet] two coils of coil_thickness {tc:g} m do not fit in "
                                 f"window_width {ww:g} m")
    span = ww + 2.0 * wp
    if r["width"] < span:
        raise ParameterFileError(f"[rail] width = {r['width']:g} m is narrower than the magnet "
                                 f"({span:g} m across both poles); the rail must cover both poles")
    core = resolve_material(m["material"], materials, "magnet")
    rail_mat = resolve_material(r["material"], materials, "rail")

    area = wp * d
    c = ww + wp
    overhang = 0.5 * (r["width"] - span)
    edges: list[tuple[float, float]] = []
    if options.fringing:
        edges.append((d, gcp))                            # inner flank, towards the window
        if overhang > 0.0:
            edges.append((d, min(gcp, overhang)))         # outer flank, limited by the rail edge
        if m["end_effects"]:
            edges += [(wp, gcp), (wp, gcp)]               # the two depth-wise ends

    def gap(name: str) -> AirGap:
        return AirGap(name, gap_input=name.removeprefix("gap_"), pole_area=area,
                      fringe_edges=tuple(edges))

    leg_len = hl + 0.5 * ty
    rail_len = c + r["thickness"]
    K = m["coil_segments"]
    h = hc / K
    y_nodes = [gcp + (k + 0.5) * h for k in range(K)]
    # leg segments from the pole face up: tip (to the first node), K - 1 coil strips,
    # top (last node to the yoke's mid-line); turns in proportion to the coil they hold
    seg_len = [y_nodes[0], *([h] * (K - 1)), leg_len - y_nodes[-1]]
    half = 0.5 * m["turns"]
    seg_turns = [half * 0.5 / K, *([half / K] * (K - 1)), half * 0.5 / K]
    rho_core = rho_rail = 0.0
    if options.eddy_currents:
        rho_core = _resistivity(m["resistivity"], core, "magnet")
        rho_rail = _resistivity(r["resistivity"], rail_mat, "rail")

    def eddy(name: str, width: float, length: float, rho: float,
             solid: bool) -> tuple[Element, ...]:
        if not options.eddy_currents:
            return ()
        if m["laminated"] and not solid:
            return (EddyCurrent.laminated(name, width * d, length, rho, m["sheet_thickness"]),)
        return (EddyCurrent.solid_rectangular(name, width, d, length, rho),)

    def part(name: str, start: str, end: str, iron: IronPath, width: float,
             solid: bool = False) -> list[Branch]:
        """Branches of one iron part (flux along it, section ``width`` x depth)."""
        rho = rho_rail if solid else rho_core
        if not options.eddy_currents or options.eddy_model == "lumped":
            return [Branch(name, start, end, (iron, *eddy(f"eddy_{name}", width, iron.length,
                                                          rho, solid)))]
        if m["laminated"] and not solid:       # diffusion across each sheet
            return ladder_branches(name, start, end, iron, thickness=m["sheet_thickness"],
                                   resistivity=rho, layers=options.eddy_layers)
        # solid bar: slab across the width; with end_effects the Saint-Venant factor of
        # the finite depth (the eddy currents close within the depth), else the 2-D slab
        factor = (_rectangle_torsion_constant(width, d) / (d * width**3 / 3.0)
                  if m["end_effects"] else 1.0)
        return ladder_branches(name, start, end, iron, thickness=width, resistivity=rho,
                               layers=options.eddy_layers, factor=factor)

    left = ["PL", *(f"L{k + 1}" for k in range(K)), "YL"]
    right = ["PR", *(f"R{k + 1}" for k in range(K)), "YR"]
    branches: list[Branch] = []
    coils: list[Coil] = []
    for j in range(K + 1):
        for side, nodes, sign in (("left", left, 1), ("right", right, -1)):
            name = f"leg_{side}_{j}"
            start, end_ = (nodes[j + 1], nodes[j]) if sign > 0 else (nodes[j], nodes[j + 1])
            # every segment carries the eddy currents of its own length: all of the
            # winding sits on solid (or laminated) iron, so no flux linked by the coil can
            # change without inducing them
            branches += part(name, start, end_, IronPath(f"iron_{name}", seg_len[j], area, core),
                             wp)
            coils.append(Coil(name, seg_turns[j], pole=side))
    branches += [Branch("gap_left", "PL", "RL", (gap("gap_left"),))]
    branches += part("rail", "RL", "RR",
                     IronPath("iron_rail", rail_len, r["thickness"] * d, rail_mat),
                     r["thickness"], solid=True)
    branches += [Branch("gap_right", "RR", "PR", (gap("gap_right"),))]
    branches += part("yoke", "YR", "YL", IronPath("iron_yoke", c, ty * d, core), ty)
    if options.leakage:
        ends = 4.0 * 0.52 * MU0 if m["end_effects"] else 0.0   # quarter cylinders, leg ends
        branches.append(Branch("leakage", "PL", "PR", (
            LeakagePermeance("leakage_window", MU0 * d * gcp / ww + ends * gcp),)))
        for k in range(K):
            branches.append(Branch(f"leakage_{k + 1}", left[k + 1], right[k + 1], (
                LeakagePermeance(f"leakage_window_{k + 1}", MU0 * d * h / ww + ends * h),)))
        widths = d + (2.0 * wp if m["end_effects"] else 0.0)
        for k, y in enumerate(y_nodes):
            y0, y1 = y - 0.5 * h, y + 0.5 * h
            g = LeakagePermeance.quarter_hollow_cylinder("o", widths, y0, h).value   # outer
            if y0 < 0.5 * ww:                                                       # window
                g += LeakagePermeance.quarter_hollow_cylinder(
                    "i", d, y0, min(y1, 0.5 * ww) - y0).value
            branches.append(Branch(f"flank_left_{k + 1}", left[k + 1], "RL",
                                   (LeakagePermeance(f"flank_left_{k + 1}", g),)))
            branches.append(Branch(f"flank_right_{k + 1}", "RR", right[k + 1],
                                   (LeakagePermeance(f"flank_right_{k + 1}", g),)))
    circuit = Circuit("coil", m["resistance"], tuple(coils))
    return m["name"], Network(tuple(branches), (circuit,), name=m["name"])


def u_magnet_range(params: Mapping[str, Any]) -> PlausibleRange:
    """Plausible inputs: gaps up to the pole width, currents up to
    :data:`~maglevkit.magnets.base.MAX_CURRENT_DENSITY_A_PER_M2` in one leg's coil
    (``turns / 2`` on ``coil_height x coil_thickness``)."""
    m = params["magnet"]
    return PlausibleRange.from_geometry(
        gap_m=float(m["pole_width"]), gap_basis="the pole width",
        turns=0.5 * float(m["turns"]),
        winding_area_m2=float(m["coil_height"]) * float(m["coil_thickness"]),
        winding="the coil of one leg")


register_kind("u_magnet", build_u_magnet, ("rail",), u_magnet_range)
