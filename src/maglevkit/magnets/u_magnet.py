"""Parametric U-magnet (two legs, one yoke, one coil per leg) above a flat rail.

Network (see docs/equations.md, section "U-magnet")::

    YL --leg_left(coil n/2)--> PL --gap_left--> RL --rail--> RR --gap_right--> PR
    PR --leg_right(coil n/2)--> YR --yoke--> YL          PL --leakage--> PR

Geometry (all m): pole face ``A = pole_width x depth``; pole-centre distance
``c = window_width + pole_width``; leg path ``leg_height + yoke_thickness/2``;
yoke path ``c``; rail path ``c + rail.thickness``.

Estimates of the secondary flux paths (Roters' method, facts.md section 3):

* fringing at each pole edge that faces the rail: ``2 mu0 w/pi ln(1 + pi r/(2 s))``, with
  ``r`` the flank height between pole face and coil (``coil_gap_to_pole_face``); on the
  outer edge ``r`` is limited by the rail overhang; the two depth-wise ends fringe
  only with ``end_effects = true``.
* leakage across the window between the legs: ``mu0 depth / window_width x (coil_height/3
  + coil_gap_to_pole_face)``; the MMF between the legs rises linearly along the coil
  (energy-equivalent height 1/3) and is full between coil and pole face.  With
  ``end_effects`` two quarter cylinders per leg end are added.
* eddy currents: one element per iron part, solid bars (Saint-Venant formula) or a
  laminated stack (``sheet_thickness``); the rail is always solid.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..circuit.elements import AirGap, EddyCurrent, Element, IronPath, LeakagePermeance
from ..circuit.network import Branch, Circuit, Coil, Network
from ..errors import ParameterFileError
from ..materials import MU0, Material
from .base import ModelOptions, Schema, register_kind, resolve_material, take

MAGNET_SCHEMA = {
    "kind": Schema(str),
    "name": Schema(str, required=False, default="U-magnet"),
    "turns": Schema(float, unit="-"),
    "resistance": Schema(float, unit="ohm"),
    "depth": Schema(float, unit="m"),
    "pole_width": Schema(float, unit="m"),
    "leg_height": Schema(float, unit="m"),
    "yoke_thickness": Schema(float, unit="m"),
    "window_width": Schema(float, unit="m"),
    "coil_thickness": Schema(float, unit="m"),
    "coil_height": Schema(float, unit="m"),
    "coil_gap_to_pole_face": Schema(float, unit="m", check="nonnegative"),
    "end_effects": Schema(bool),
    "material": Schema(str),
    "laminated": Schema(bool, required=False, default=False),
    "sheet_thickness": Schema(float, required=False, unit="m"),
    "resistivity": Schema(float, required=False, unit="ohm m"),
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
    if options.fringing and gcp > 0.0:
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
    eddy: dict[str, Element] = {}
    if options.eddy_currents:
        rho_core = _resistivity(m["resistivity"], core, "magnet")
        rho_rail = _resistivity(r["resistivity"], rail_mat, "rail")
        if m["laminated"]:
            t = m["sheet_thickness"]
            eddy["leg_left"] = EddyCurrent.laminated("eddy_leg_left", area, leg_len, rho_core, t)
            eddy["leg_right"] = EddyCurrent.laminated("eddy_leg_right", area, leg_len, rho_core, t)
            eddy["yoke"] = EddyCurrent.laminated("eddy_yoke", ty * d, c, rho_core, t)
        else:
            eddy["leg_left"] = EddyCurrent.solid_rectangular("eddy_leg_left", wp, d, leg_len,
                                                             rho_core)
            eddy["leg_right"] = EddyCurrent.solid_rectangular("eddy_leg_right", wp, d, leg_len,
                                                              rho_core)
            eddy["yoke"] = EddyCurrent.solid_rectangular("eddy_yoke", ty, d, c, rho_core)
        eddy["rail"] = EddyCurrent.solid_rectangular("eddy_rail", r["thickness"], d, rail_len,
                                                     rho_rail)

    def with_eddy(key: str, *els: Element) -> tuple[Element, ...]:
        return (*els, eddy[key]) if key in eddy else els

    branches = [
        Branch("leg_left", "YL", "PL",
               with_eddy("leg_left", IronPath("iron_leg_left", leg_len, area, core))),
        Branch("gap_left", "PL", "RL", (gap("gap_left"),)),
        Branch("rail", "RL", "RR",
               with_eddy("rail", IronPath("iron_rail", rail_len, r["thickness"] * d, rail_mat))),
        Branch("gap_right", "RR", "PR", (gap("gap_right"),)),
        Branch("leg_right", "PR", "YR",
               with_eddy("leg_right", IronPath("iron_leg_right", leg_len, area, core))),
        Branch("yoke", "YR", "YL",
               with_eddy("yoke", IronPath("iron_yoke", c, ty * d, core))),
    ]
    if options.leakage:
        g_window = MU0 * d / ww * (hc / 3.0 + gcp)
        if m["end_effects"]:
            g_window += 4.0 * 0.52 * MU0 * (hc / 3.0 + gcp)   # quarter cylinders at the leg ends
        branches.append(Branch("leakage", "PL", "PR",
                               (LeakagePermeance("leakage_window", g_window),)))
    half = 0.5 * m["turns"]
    circuit = Circuit("coil", m["resistance"],
                      (Coil("leg_left", half), Coil("leg_right", half)))
    return m["name"], Network(tuple(branches), (circuit,), name=m["name"])


register_kind("u_magnet", build_u_magnet, ("rail",))
