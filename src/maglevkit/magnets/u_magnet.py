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
  ``eddy_model = "ladder_split"``: the ladder with the rail split under and between the
  poles (its flux rises across each pole face and is uniform between the poles: eddy
  length ``window_width + 2 pole_width/3``, docs/equations.md section 1b).  On the cell
  network (``discretisation = "grid"``) ``"ladder"`` puts the part's slab ladder on every
  cell link that carries an eddy element (the rail's flux along its length is the
  cells' own, so ``"ladder_split"`` is refused there).

``flux_paths = "split"`` (lumped network only; default ``"standard"``, the paths above):
three changes of the air paths, each from geometry, chosen by the 2-D FEM's region fluxes
(docs/validation_fem.md, "Calibration on the split network"), no value fitted to it:

* the fringe at each pole edge in Roters' decomposition for a pole facing a plane: a
  quarter cylinder of radius ``s`` beside the edge, ``0.52 mu0 w`` (gap-independent, its own
  branch ``edge_cylinders_*`` from the pole tip to the rail, a leakage permeance for the
  calibration factors), and outside it the quarter annulus from the flank below the coil,
  ``(2 mu0 w/pi) ln(1 + r/s)`` (in the air gap element, ``r`` as above).  The FEM carries
  1.6-2.1 times the standard fringe's flux across the gap beside the pole, all of it from
  the flank below the coil;
* no window-flank quarter circles: the window's air is counted once, by the strips across
  it (the FEM's leg-to-leg leakage from the coil region is 0.27 mWb per leg at 20 mm /
  5 A, the standard network's flank and window paths 0.46);
* the air through the coil's cross-section beside every leg segment (``coil_air_*``),
  in parallel with the segment's iron and carrying its turns, linked width
  ``t_c - t_c^2/(3 w_w)`` over both flanks (the TR09 split network's law,
  :mod:`maglevkit.magnets.levitation`); the segment's eddy element sits in series with
  both (node ``E_*``), so ``eddy_model = "lumped"`` only.

``flux_paths = "window"`` (lumped network, ``end_effects = false``; issue 25, u20c25): the
split network's iron, coil air and window strips with the edges' air from the conformal
map of a right-angled pole edge over a plane instead of Roters' decomposition:

* the flanks below the coil by the map (``edge_flank_per_mu0``), the window's flank only
  up to where its tubes' local path ``s v(x)`` reaches the window's centre plane, ``x_w =
  (2/pi)(a - s atan(a/s))`` (``a = window_width/2``), the flank above ``x_w`` straight to
  that plane at the rail's potential (in the air gap element, :class:`WindowFringeGap`);
* instead of the quarter cylinders, the face's corner flux of each edge (branch
  ``edge_corner_*``, :class:`~maglevkit.circuit.elements.EdgeCornerPermeance`): the map's
  ``0.195 mu0 w`` per edge, growing with the gap because the coil's MMF falls along the
  flank from ``coil_gap_to_pole_face`` up and the inner edge faces the window's centre
  plane.  Gap-dependent, so the calibration factors leave it alone (``gap_offset_m``
  aside).  The network the U-magnet's held-out calibration check meets its 2 % with
  (docs/validation_fem.md, "The face's corner flux from geometry").

``discretisation = "grid"`` replaces the legs, yoke and rail by grids of iron cells
(:func:`_build_grid`); its air is the Roters tubes above attached to the cells
(``air_model = "tubes"``, default) or a cell network as well (``air_model = "cells"``,
:func:`_air_cells`: window, coil sides with their turns, outside air in a box
``air_margin`` beyond the magnet, ``air_gap_rows`` rows of cells in the gap).

"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import casadi as ca
import numpy as np

from ..circuit.elements import (
    AirGap,
    EddyCurrent,
    EdgeCornerPermeance,
    Element,
    FringePermeance,
    GapLayerPermeance,
    IronPath,
    LeakagePermeance,
    edge_flank_per_mu0,
    symbolic,
)
from ..circuit.ladder import ladder_branches, saint_venant_factor
from ..circuit.network import Branch, Circuit, Coil, Network
from ..errors import ParameterFileError
from ..materials import MU0, IdealIron, Material
from .base import (
    ModelOptions,
    PlausibleRange,
    Schema,
    register_kind,
    resistivity,
    resolve_material,
    take,
)

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
    "discretisation": Schema(str, required=False, default="lumped"),
    "grid_columns": Schema(int, required=False, default=3, unit="-"),
    "coil_air": Schema(bool, required=False, default=False),
    "air_model": Schema(str, required=False, default="tubes"),
    "air_gap_rows": Schema(int, required=False, default=4, unit="-"),
    "air_margin": Schema(float, required=False, default=0.2, unit="m"),
    "flux_paths": Schema(str, required=False, default="standard"),
}
FLUX_PATHS = ("standard", "split", "window")
"""Air paths of the lumped network: ``"standard"`` (default), ``"split"`` or ``"window"``
(module docstring)."""
QUARTER_CYLINDER = 0.52
"""Roters' quarter cylinder, ``G = 0.52 mu0 l`` (docs/sources.md sec. 3): at the leg ends
(``end_effects``) and, with ``flux_paths = "split"``, beside each pole edge facing the rail."""
DISCRETISATIONS = ("lumped", "grid")
AIR_MODELS = ("tubes", "cells")
RAIL_SCHEMA = {
    "thickness": Schema(float, unit="m"),
    "width": Schema(float, unit="m"),
    "material": Schema(str),
    "resistivity": Schema(float, required=False, unit="ohm m"),
}


@dataclass(frozen=True)
class WindowFringeGap(AirGap):
    """The ``flux_paths = "window"`` air gap: both edges' flanks by the conformal map of a
    right-angled pole edge (:func:`~maglevkit.circuit.elements.edge_flank_per_mu0`), the
    first edge of ``fringe_edges`` facing the window, whose centre plane (at the rail's
    potential, by antisymmetry) is ``window_half_m`` from the flank.

    A tube leaving that flank at height ``x`` has the local path ``s v(x)`` (``v - atan v =
    pi x/(2 s)``); where it exceeds ``a`` = ``window_half_m`` it goes straight to the
    centre plane instead, so the flank fringes up to ``x_w = (2/pi)(a - s atan(a/s))``
    (below ``r`` from ~12 mm on for the bundled magnet) and the rest of it, ``[x_w, r]``,
    reaches the rail's potential over ``a``: ``mu0 w (r - x_w)/a``, continuous through
    ``x_w = r`` (docs/equations.md sec. 6; docs/validation_fem.md, u20mm25, u20c25).

    Parameters
    ----------
    window_half_m : float
        Distance from the first edge's flank to the window's centre plane [m], > 0.
    (the rest as :class:`~maglevkit.circuit.elements.AirGap`)
    """

    window_half_m: float = math.inf

    def _add_fringe(self, g: Any, s: Any) -> Any:
        for k, (w, r) in enumerate(self.fringe_edges):
            if k > 0:
                g = g + edge_flank_per_mu0(w, r, s)
                continue
            a = self.window_half_m
            sym = symbolic(s) or symbolic(a) or symbolic(r)
            x_w = 2.0 / math.pi * (a - s * (ca.atan(a / s) if sym else np.arctan(a / s)))
            flank = ca.fmin(r, x_w) if sym else np.minimum(r, x_w)
            g = g + edge_flank_per_mu0(w, flank, s) + w * (r - flank) / a
        return g


def build_u_magnet(params: Mapping[str, Any], materials: Mapping[str, Material],
                   options: ModelOptions) -> tuple[str, Network]:
    """Build the U-magnet network from parsed parameters (see module docstring).

    Parameters
    ----------
    params : mapping
        The parsed parameter file (its ``magnet`` table and the tables this kind
        needs: ``rail``).
    materials : mapping of str to Material
        Materials defined in the file (by name), besides the built-in records.
    options : ModelOptions
        Physics switches (saturation, fringing, leakage, eddy currents).

    Returns
    -------
    (kind, network) : tuple of str and Network
        The magnet kind and its equivalent magnetic circuit.

    Raises
    ------
    ParameterFileError
        Missing tables, unknown or missing keys, bad values, or a geometry that does not
        fit together.
    """
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
    if m["discretisation"] not in DISCRETISATIONS:
        raise ParameterFileError(f"[magnet] discretisation = {m['discretisation']!r}: expected "
                                 f"one of {', '.join(map(repr, DISCRETISATIONS))}")
    given = set(params["magnet"])
    only = {"lumped": ("grid_columns", "coil_air", "air_model", "air_gap_rows", "air_margin"),
            "grid": ("coil_segments", "flux_paths")}
    for key in only[m["discretisation"]]:
        if key in given:
            raise ParameterFileError(
                f"[magnet] {key} does not apply to discretisation = {m['discretisation']!r} "
                f"(it is a key of the {'grid' if m['discretisation'] == 'lumped' else 'lumped'}"
                " network); remove it or change the discretisation")
    if m["flux_paths"] not in FLUX_PATHS:
        raise ParameterFileError(f"[magnet] flux_paths = {m['flux_paths']!r}: expected one of "
                                 f"{', '.join(map(repr, FLUX_PATHS))}")
    if (m["flux_paths"] in ("split", "window") and options.eddy_currents
            and options.eddy_model != "lumped"):
        raise ParameterFileError(
            f"[magnet] flux_paths = \"{m['flux_paths']}\" has lumped eddy elements only "
            f"(eddy_model {options.eddy_model!r} requested): use eddy_model = \"lumped\" or "
            "flux_paths = \"standard\"")
    if m["flux_paths"] == "window" and m["end_effects"]:
        raise ParameterFileError(
            "[magnet] flux_paths = \"window\" is a 2-D cross-section's network (its edge laws "
            "are 2-D conformal maps): it needs end_effects = false, got end_effects = true")
    if m["air_model"] not in AIR_MODELS:
        raise ParameterFileError(f"[magnet] air_model = {m['air_model']!r}: expected one of "
                                 f"{', '.join(map(repr, AIR_MODELS))}")
    if m["air_model"] == "tubes":
        for key in ("air_gap_rows", "air_margin"):
            if key in given:
                raise ParameterFileError(f"[magnet] {key} applies to air_model = \"cells\" "
                                         "only; remove it or set air_model = \"cells\"")
    else:
        if m["coil_air"]:
            raise ParameterFileError("[magnet] coil_air is a path of the Roters-tube air model; "
                                     "air_model = \"cells\" has the coil sides as cells "
                                     "already: remove coil_air")
        if not (options.leakage and options.fringing):
            raise ParameterFileError(
                "[magnet] air_model = \"cells\" solves all air paths as one field, so "
                "leakage and fringing cannot be switched off separately; use "
                "air_model = \"tubes\" for ModelOptions(leakage=False) or (fringing=False)")
        if m["air_gap_rows"] > 8:
            raise ParameterFileError(f"[magnet] air_gap_rows = {m['air_gap_rows']}: at most 8 "
                                     "rows of cells across the gap")
    if m["grid_columns"] > 12:
        raise ParameterFileError(f"[magnet] grid_columns = {m['grid_columns']}: at most 12 "
                                 "cells across the pole width (the cell network grows as its "
                                 "square)")
    core = resolve_material(m["material"], materials, "magnet")
    rail_mat = resolve_material(r["material"], materials, "rail")

    rho_core = rho_rail = 0.0
    if options.eddy_currents:
        rho_core = resistivity(m["resistivity"], core, "magnet")
        rho_rail = resistivity(r["resistivity"], rail_mat, "rail")
    if m["discretisation"] == "grid":
        if options.eddy_currents and options.eddy_model == "ladder_split":
            raise ParameterFileError(
                "[magnet] discretisation = \"grid\" resolves the rail's flux along its "
                "length itself; eddy_model 'ladder_split' (the lumped network's rail split) "
                "does not apply: use 'ladder' or 'lumped'")
        for mat, where in ((core, "magnet"), (rail_mat, "rail")):
            if isinstance(mat, IdealIron):
                raise ParameterFileError(
                    f"[{where}] material {mat.name!r} is ideal iron: the grid network joins "
                    "iron cells in closed loops of iron alone, which need a finite "
                    "permeability; use discretisation = \"lumped\" or a real material")

        def eddy_part(name: str, part: str, length: float, width: float,
                      main: bool) -> tuple[Element, ...]:
            # along the part's main flux direction only; scaled so that a uniform dB/dt in
            # the part dissipates what the part's single element does (docs/equations.md)
            if not options.eddy_currents or not main:
                return ()
            thick = {"leg": wp, "yoke": ty, "rail": r["thickness"]}[part]
            share = thick / width                   # parallel cells across the part
            if part == "rail":
                el = EddyCurrent.solid_rectangular("e", thick, d, length, rho_rail)
            elif m["laminated"]:
                el = EddyCurrent.laminated("e", thick * d, length, rho_core, m["sheet_thickness"])
            else:
                el = EddyCurrent.solid_rectangular("e", thick, d, length, rho_core)
            return (EddyCurrent(f"eddy_{name}", el.conductance_S * share),)

        grid_branches, grid_coils = _build_grid(m, r, core, rail_mat, options, eddy_part)
        if options.eddy_currents and options.eddy_model != "lumped":
            grid_branches = _grid_ladders(grid_branches, m, r, rho_core, rho_rail,
                                          options.eddy_layers)
        circuit = Circuit("coil", m["resistance"], tuple(grid_coils))
        return m["name"], Network(tuple(grid_branches), (circuit,), name=m["name"])

    return m["name"], lumped_network(m, r, core, rail_mat, options)


def lumped_network(m: Mapping[str, Any], r: Mapping[str, Any], core: Material,
                   rail_mat: Material, options: ModelOptions) -> Network:
    """The lumped U-magnet network (``discretisation = "lumped"``, module docstring).

    The one builder of the lumped network: :func:`build_u_magnet` calls it with the
    checked numbers of a parameter file, the design optimisation (:mod:`maglevkit.design`)
    with CasADi symbols for the geometry it varies (exact geometry derivatives; the
    geometry checks of :func:`build_u_magnet` are then the optimiser's constraints, and
    the two branches whose existence depends on the geometry -- the outer-flank fringe and
    the window-flank leakage -- are kept with their extent clipped at 0, which gives the
    same permeance as leaving them out).

    Parameters
    ----------
    m : mapping
        The checked ``[magnet]`` table (:data:`MAGNET_SCHEMA`; lengths [m], ``turns`` [-],
        ``resistance`` [ohm]); geometry entries may be CasADi ``SX`` symbols.
    r : mapping
        The checked ``[rail]`` table (``thickness``, ``width`` [m]).
    core, rail_mat : Material
        The magnet's and the rail's iron.
    options : ModelOptions
        Physics switches.

    Returns
    -------
    Network
        The equivalent magnetic circuit (one circuit ``"coil"``).
    """

    wp, hl, ty = m["pole_width"], m["leg_height"], m["yoke_thickness"]
    ww, hc, gcp = m["window_width"], m["coil_height"], m["coil_gap_to_pole_face"]
    d = m["depth"]
    span = ww + 2.0 * wp
    area = wp * d
    c = ww + wp
    overhang = 0.5 * (r["width"] - span)
    edges: list[tuple[float, float]] = []
    if options.fringing:
        edges.append((d, gcp))                            # inner flank, towards the window
        if symbolic(overhang):      # design: the clipped radius (0 without overhang: no fringe)
            edges.append((d, ca.fmax(0.0, ca.fmin(gcp, overhang))))
        elif overhang > 0.0:
            edges.append((d, min(gcp, overhang)))         # outer flank, limited by the rail edge
        if m["end_effects"]:
            edges += [(wp, gcp), (wp, gcp)]               # the two depth-wise ends

    window = m["flux_paths"] == "window"
    split = m["flux_paths"] == "split" or window     # "window": the split network's iron and air

    # "split": Roters' decomposition of an edge's fringe towards the rail: a quarter
    # cylinder of radius s beside the edge (gap-independent, its own branch below) and the
    # quarter annulus outside it from the flank below the coil, (2 mu0 w/pi) ln(1 + r/s),
    # which is the AirGap's fringe form (2 mu0 w/pi) ln(1 + pi r'/(2 s)) with r' = 2 r/pi
    fringes = (tuple((w, 2.0 * radius / math.pi) for w, radius in edges)
               if split and not window else tuple(edges))

    def gap(name: str) -> AirGap:
        if window:
            return WindowFringeGap(name, gap_input=name.removeprefix("gap_"), pole_area_m2=area,
                                   fringe_edges=fringes, window_half_m=0.5 * ww)
        return AirGap(name, gap_input=name.removeprefix("gap_"), pole_area_m2=area,
                      fringe_edges=fringes)

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
            return [Branch(name, start, end, (iron, *eddy(f"eddy_{name}", width, iron.length_m,
                                                          rho, solid)))]
        if m["laminated"] and not solid:       # diffusion across each sheet
            return ladder_branches(name, start, end, iron, thickness_m=m["sheet_thickness"],
                                   resistivity_ohm_m=rho, layers=options.eddy_layers)
        # solid bar: slab across the width; with end_effects the Saint-Venant factor of
        # the finite depth (the eddy currents close within the depth), else the 2-D slab
        factor = saint_venant_factor(width, d) if m["end_effects"] else 1.0
        if solid and options.eddy_model == "ladder_split":
            # rail split under and between the poles: the flux enters the rail over each
            # pole face (rising linearly across it), runs uniform between the poles and
            # hardly reaches the overhangs: eddy length ww + 2 wp/3 (docs/equations.md 1b)
            factor *= (ww + 2.0 * wp / 3.0) / iron.length_m
        return ladder_branches(name, start, end, iron, thickness_m=width, resistivity_ohm_m=rho,
                               layers=options.eddy_layers, factor=factor)

    rho_core = rho_rail = 0.0
    if options.eddy_currents:
        rho_core = resistivity(m["resistivity"], core, "magnet")
        rho_rail = resistivity(r["resistivity"], rail_mat, "rail")

    # "split": linked air width beside a leg in the coil's cross-section, both flanks: the
    # window flank's harmonic potential D (y/l)(1 - x/a) (a = half the window) weighted by
    # the linked share 1 - x/t_c of the turns, t_c/2 - t_c^2/(6a); the outer flank faces
    # open air (a -> oo): t_c/2
    tc = m["coil_thickness"]
    coil_air_width = tc - tc * tc / (3.0 * ww)
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
            iron = IronPath(f"iron_{name}", seg_len[j], area, core)
            if split and options.leakage:
                # "split": the air through the coil's cross-section beside the segment, in
                # parallel with the iron and carrying the segment's turns, so it sees the
                # iron's own drop; the segment's eddy element in series with both (node E),
                # as in the TR09 split network (magnets/levitation.py)
                air = f"coil_air_{side}_{j}"
                mid = f"E_{side}_{j}" if options.eddy_currents else end_
                branches += [Branch(name, start, mid, (iron,)), Branch(air, start, mid, (
                    LeakagePermeance(air, MU0 * d * coil_air_width / seg_len[j]),))]
                if options.eddy_currents:
                    branches.append(Branch(f"eddy_{name}", mid, end_,
                                           eddy(f"eddy_{name}", wp, seg_len[j], rho_core, False)))
                coils += [Coil(name, seg_turns[j], pole=side, pole_turns=half),
                          Coil(air, seg_turns[j], pole=side, pole_turns=half)]
                continue
            branches += part(name, start, end_, iron, wp)
            coils.append(Coil(name, seg_turns[j], pole=side))
    branches += [Branch("gap_left", "PL", "RL", (gap("gap_left"),))]
    branches += part("rail", "RL", "RR",
                     IronPath("iron_rail", rail_len, r["thickness"] * d, rail_mat),
                     r["thickness"], solid=True)
    branches += [Branch("gap_right", "RR", "PR", (gap("gap_right"),))]
    if window and edges:
        # the face's corner flux of each edge from the conformal map with the coil's MMF
        # falling along the flank and the window's centre plane (inner edge): 0.195 mu0 w
        # per free edge, growing with the gap (docs/equations.md sec. 1)
        halves = (0.5 * ww, *([math.inf] * (len(edges) - 1)))
        for side, pair in (("left", ("PL", "RL")), ("right", ("RR", "PR"))):
            branches.append(Branch(f"edge_corner_{side}", *pair, (EdgeCornerPermeance(
                f"edge_corner_{side}", gap_input=side, width_m=d, coil_from_m=gcp,
                coil_height_m=hc, window_halves_m=halves),)))
    elif split and edges:
        # the edges' quarter cylinders (Roters: 0.52 mu0 w each), pole face to rail
        g_cyl = QUARTER_CYLINDER * MU0 * sum(w for w, _ in edges)
        for side, pair in (("left", ("PL", "RL")), ("right", ("RR", "PR"))):
            branches.append(Branch(f"edge_cylinders_{side}", *pair, (
                LeakagePermeance(f"edge_cylinders_{side}", g_cyl),)))
    branches += part("yoke", "YR", "YL", IronPath("iron_yoke", c, ty * d, core), ty)
    if options.leakage:
        ends = 4.0 * QUARTER_CYLINDER * MU0 if m["end_effects"] else 0.0   # leg ends
        branches.append(Branch("leakage", "PL", "PR", (
            LeakagePermeance("leakage_window", MU0 * d * gcp / ww + ends * gcp),)))
        for k in range(K):
            branches.append(Branch(f"leakage_{k + 1}", left[k + 1], right[k + 1], (
                LeakagePermeance(f"leakage_window_{k + 1}", MU0 * d * h / ww + ends * h),)))
        widths = d + (2.0 * wp if m["end_effects"] else 0.0)
        for k, y in enumerate(y_nodes):
            y0, y1 = y - 0.5 * h, y + 0.5 * h
            g = LeakagePermeance.quarter_hollow_cylinder("o", widths, y0, h).value_H   # outer
            if split:
                pass     # the window's air is the strips across it (module docstring)
            elif symbolic(y0) or symbolic(ww):        # design: the clipped window strip
                g += LeakagePermeance.quarter_hollow_cylinder(
                    "i", d, y0, ca.fmax(0.0, ca.fmin(y1, 0.5 * ww) - y0)).value_H
            elif y0 < 0.5 * ww:                                                     # window
                g += LeakagePermeance.quarter_hollow_cylinder(
                    "i", d, y0, min(y1, 0.5 * ww) - y0).value_H
            branches.append(Branch(f"flank_left_{k + 1}", left[k + 1], "RL",
                                   (LeakagePermeance(f"flank_left_{k + 1}", g),)))
            branches.append(Branch(f"flank_right_{k + 1}", "RR", right[k + 1],
                                   (LeakagePermeance(f"flank_right_{k + 1}", g),)))
    circuit = Circuit("coil", m["resistance"], tuple(coils))
    return Network(tuple(branches), (circuit,), name=m["name"])


# ----------------------------------------------------------------------------------------
# discretisation = "grid": the iron as a network of cells (non-uniform saturation)
# ----------------------------------------------------------------------------------------


def _divide(a: float, b: float, cell: float) -> list[float]:
    """Equal subdivision of ``[a, b]`` into cells of at most ``cell`` (at least one)."""
    n = max(1, math.ceil((b - a) / cell - 1e-9))
    return [a + (b - a) * k / n for k in range(n + 1)]


def _lines(*pieces: tuple[float, float], cell: float) -> list[float]:
    out: list[float] = []
    for a, b in pieces:
        pts = _divide(a, b, cell)
        out += pts if not out else pts[1:]
    return out


def _overlap(a: float, b: float, lo: float, hi: float) -> float:
    return max(0.0, min(b, hi) - max(a, lo))


def grid_lines(m: Mapping[str, Any], r: Mapping[str, Any]
               ) -> tuple[list[float], list[float], list[float], list[float], int]:
    """Cell boundaries of the "grid" network [m]: frame x and y (legs and yoke; pole
    faces at y = 0), rail x and y (rail top at 0), and the number of leg rows.

    ``m``, ``r``: the checked ``[magnet]`` and ``[rail]`` tables.  Frame cell ``(i, j)``
    is node ``F{i}_{j}``, rail cell ``(i, j)`` node ``S{i}_{j}`` (x index first).
    """
    wp, hl, ty, ww = m["pole_width"], m["leg_height"], m["yoke_thickness"], m["window_width"]
    hc, gcp = m["coil_height"], m["coil_gap_to_pole_face"]
    cell = wp / m["grid_columns"]
    xi, xo = 0.5 * ww, 0.5 * ww + wp
    xf = _lines((-xo, -xi), (-xi, xi), (xi, xo), cell=cell)
    xs = _lines((-0.5 * r["width"], -xo), cell=cell)[:-1] + xf \
        + _lines((xo, 0.5 * r["width"]), cell=cell)[1:]
    yl = _lines((0.0, gcp), (gcp, gcp + hc), (gcp + hc, hl), cell=cell)
    yf = yl + _lines((hl, hl + ty), cell=cell)[1:]
    yr = _lines((-r["thickness"], 0.0), cell=cell)
    return xf, yf, xs, yr, len(yl) - 1


def _build_grid(m: Mapping[str, Any], r: Mapping[str, Any], core: Material, rail_mat: Material,
                options: ModelOptions,
                eddy_part: Callable[..., tuple[Element, ...]]) -> tuple[list[Branch], list[Coil]]:
    """Branches and coils of the cell network (docs/equations.md, U-magnet "grid").

    Legs, yoke and rail are tensor grids of rectangular cells of at most
    ``pole_width / grid_columns`` (x across the magnet, y up, pole faces at y = 0); a node
    sits at each cell centre, neighbouring cells are joined by an iron path of their
    centre distance and shared face.  The gap under each leg column, the fringing at the
    pole edges, the window leakage per leg row and the flank leakage per coil row attach
    to the cells where their flux enters the iron.
    """
    d, wp = m["depth"], m["pole_width"]
    ww, hc, gcp = m["window_width"], m["coil_height"], m["coil_gap_to_pole_face"]
    wr = r["width"]
    cell = wp / m["grid_columns"]
    xi, xo = 0.5 * ww, 0.5 * ww + wp
    half_turns = 0.5 * m["turns"]
    y_coil = (gcp, gcp + hc)
    xf, yf, xs, yr, nleg = grid_lines(m, r)
    def centres(v: list[float]) -> list[float]:
        return [0.5 * (a + b) for a, b in zip(v[:-1], v[1:], strict=True)]

    cxf, cyf, cxs, cyr = centres(xf), centres(yf), centres(xs), centres(yr)

    def leg_side(x: float) -> str | None:
        if -xo < x < -xi:
            return "left"
        if xi < x < xo:
            return "right"
        return None

    def frame_iron(i: int, j: int) -> bool:
        return j >= nleg or leg_side(cxf[i]) is not None

    branches: list[Branch] = []
    coils: list[Coil] = []

    def iron(name: str, length: float, width: float, mat: Material) -> IronPath:
        return IronPath(name, length, width * d, mat)

    def add_coil(name: str, side: str, turns: float) -> None:
        if turns > 1e-12 * half_turns:
            coils.append(Coil(name, turns, -1 if side == "left" else 1, pole=side,
                              pole_turns=half_turns))

    # frame: horizontal and vertical iron links
    for j in range(len(cyf)):
        for i in range(len(cxf)):
            if not frame_iron(i, j):
                continue
            if i + 1 < len(cxf) and frame_iron(i + 1, j):
                name = f"frame_h_{i}_{j}"
                length = cxf[i + 1] - cxf[i]
                branches.append(Branch(name, f"F{i}_{j}", f"F{i + 1}_{j}", (
                    iron(f"iron_{name}", length, yf[j + 1] - yf[j], core),
                    *eddy_part(name, "yoke", length, yf[j + 1] - yf[j], j >= nleg))))
            if j + 1 < len(cyf) and frame_iron(i, j + 1):
                name = f"frame_v_{i}_{j}"
                length = cyf[j + 1] - cyf[j]
                side = leg_side(cxf[i])
                branches.append(Branch(name, f"F{i}_{j}", f"F{i}_{j + 1}", (
                    iron(f"iron_{name}", length, xf[i + 1] - xf[i], core),
                    *eddy_part(name, "leg", length, xf[i + 1] - xf[i], side is not None))))
                if side is not None:
                    add_coil(name, side, half_turns * _overlap(cyf[j], cyf[j + 1], *y_coil) / hc)
    # air inside the coil sides, between the leg flank and the winding's centre plane: the
    # winding (concentrated at its centre plane) encloses it with the leg, so it is a
    # parallel path of the leg link carrying the same turns
    if options.leakage and m["coil_air"]:
        for side in ("left", "right"):
            edge_cols = [k for k, v in enumerate(cxf) if leg_side(v) == side]
            for i in (edge_cols[0], edge_cols[-1]):
                for j in range(nleg):
                    ov = _overlap(cyf[j], cyf[j + 1], *y_coil)
                    if ov <= 0.0:
                        continue
                    length = cyf[j + 1] - cyf[j]
                    name = f"coil_air_{i}_{j}"
                    branches.append(Branch(name, f"F{i}_{j}", f"F{i}_{j + 1}", (
                        LeakagePermeance(f"air_{name}",
                                         MU0 * d * 0.5 * m["coil_thickness"] * ov / length**2),)))
                    add_coil(name, side, half_turns * ov / hc)
    # rail: horizontal and vertical iron links
    for j in range(len(cyr)):
        for i in range(len(cxs)):
            if i + 1 < len(cxs):
                name = f"rail_h_{i}_{j}"
                length = cxs[i + 1] - cxs[i]
                branches.append(Branch(name, f"S{i}_{j}", f"S{i + 1}_{j}", (
                    iron(f"iron_{name}", length, yr[j + 1] - yr[j], rail_mat),
                    *eddy_part(name, "rail", length, yr[j + 1] - yr[j], True))))
            if j + 1 < len(cyr):
                name = f"rail_v_{i}_{j}"
                branches.append(Branch(name, f"S{i}_{j}", f"S{i}_{j + 1}", (
                    iron(f"iron_{name}", cyr[j + 1] - cyr[j], xs[i + 1] - xs[i], rail_mat),)))
    if m["air_model"] == "cells":
        _air_cells(m, r, core, rail_mat, branches, add_coil, xf, yf, xs, yr, frame_iron)
        return branches, coils
    top = len(cyr) - 1                        # rail row at its top surface
    off = xs.index(xf[0])                     # rail column under frame column 0

    def rail_column(x: float) -> int:
        return min(max(bisect.bisect_right(xs, x) - 1, 0), len(cxs) - 1)

    def rail_top(i: int) -> tuple[str, IronPath]:
        """Rail surface cell ``i``: its node and the half-cell path down to its centre."""
        return f"S{i}_{top}", iron(f"iron_rail_top_{i}", 0.5 * (yr[-1] - yr[-2]), xs[i + 1] - xs[i],
                                   rail_mat)

    # gap: one tube per leg column, pole face to rail surface
    for i, x in enumerate(cxf):
        side = leg_side(x)
        if side is None:
            continue
        w = xf[i + 1] - xf[i]
        gname = f"gap_{side}"
        node_r, half_r = rail_top(i + off)
        half_f = iron(f"iron_face_{i}", 0.5 * (yf[1] - yf[0]), w, core)
        air = AirGap(f"air_{gname}_{i}", gap_input=side, pole_area_m2=w * d)
        el: tuple[Element, ...] = (half_f, air, replace(half_r, name=f"iron_rail_face_{i}"))
        a, b = (f"F{i}_0", node_r) if side == "left" else (node_r, f"F{i}_0")
        branches.append(Branch(f"{gname}_{i}", a, b, el if side == "left" else el[::-1]))
    # leg columns at the window flank (inner) and at the outer flank
    cols = {side: [k for k, v in enumerate(cxf) if leg_side(v) == side] for side in ("left", "right")}
    inner = {"left": cols["left"][-1], "right": cols["right"][0]}
    outer = {"left": cols["left"][0], "right": cols["right"][-1]}
    # fringing at the pole edges (flank of height gcp below the coil), landing beside the pole
    if options.fringing:
        overhang = 0.5 * (wr - ww - 2.0 * wp)
        for side, sgn in (("left", -1.0), ("right", 1.0)):
            for edge, x_edge, out_sign, radius in (
                    ("inner", sgn * xi, -sgn, gcp),
                    ("outer", sgn * xo, sgn, min(gcp, overhang) if overhang > 0 else 0.0)):
                if radius <= 0.0:
                    continue
                i = inner[side] if edge == "inner" else outer[side]
                land = rail_column(x_edge + out_sign * 0.5 * min(radius, cell))
                node_r, half_r = rail_top(land)
                name = f"fringe_{side}_{edge}"
                el = (iron(f"iron_{name}", 0.5 * (xf[i + 1] - xf[i]), yf[1] - yf[0], core),
                      FringePermeance(f"air_{name}", gap_input=side, width_m=d, radius_m=radius),
                      replace(half_r, name=f"iron_rail_{name}"))
                a, b = (f"F{i}_0", node_r) if side == "left" else (node_r, f"F{i}_0")
                branches.append(Branch(name, a, b, el if side == "left" else el[::-1]))
    if options.leakage:
        i_left, i_right = inner["left"], inner["right"]
        o_left, o_right = outer["left"], outer["right"]
        wcol = xf[i_left + 1] - xf[i_left]
        for j in range(nleg):
            dy = yf[j + 1] - yf[j]
            name = f"leakage_{j}"
            branches.append(Branch(name, f"F{i_left}_{j}", f"F{i_right}_{j}", (
                iron(f"iron_{name}_l", 0.5 * wcol, dy, core),
                LeakagePermeance(f"air_{name}", MU0 * d * dy / ww),
                iron(f"iron_{name}_r", 0.5 * wcol, dy, core))))
            y0, y1 = max(yf[j], gcp), min(yf[j + 1], gcp + hc)
            if y1 <= y0:
                continue
            # flank leakage (Roters quarter circles to the pole-face level), per coil row
            tubes = [("outer", o_left, o_right,
                      LeakagePermeance.quarter_hollow_cylinder("o", d, y0, y1 - y0).value_H,
                      xo + 0.5 * (y0 + y1))]
            if y0 < 0.5 * ww:
                y1w = min(y1, 0.5 * ww)
                tubes.append(("window", i_left, i_right, LeakagePermeance.quarter_hollow_cylinder(
                    "i", d, y0, y1w - y0).value_H, xi - 0.5 * (y0 + y1w)))
            for kind, il, ir, g, dist in tubes:
                for side, i, sgn in (("left", il, -1.0), ("right", ir, 1.0)):
                    node_r, half_r = rail_top(rail_column(sgn * min(dist, 0.5 * wr - 1e-9)))
                    name = f"flank_{side}_{kind}_{j}"
                    el = (iron(f"iron_{name}", 0.5 * wcol, dy, core),
                          LeakagePermeance(f"air_{name}", g),
                          replace(half_r, name=f"iron_rail_{name}"))
                    a, b = (f"F{i}_{j}", node_r) if side == "left" else (node_r, f"F{i}_{j}")
                    branches.append(Branch(name, a, b, el if side == "left" else el[::-1]))
    return branches, coils


CORNER_REFINEMENT = (0.1, 0.25, 0.5)
"""Air-cell grid lines at these fractions of the cell size beside each pole edge and above
the pole faces (``air_model = "cells"``)."""


def _graded(a: float, length: float, cell: float, growth: float = 1.5) -> list[float]:
    """Lines from ``a`` outwards over ``length`` (sign gives the direction), first cell
    ``cell``, each next one ``growth`` times longer, the last one stretched to end exactly
    at ``a + length``."""
    out, x, h = [], 0.0, cell
    total = abs(length)
    while x + h < total - 1e-12:
        x += h
        out.append(x)
        h *= growth
    if out and total - out[-1] < 0.5 * h / growth:
        out.pop()
    out.append(total)
    sgn = 1.0 if length > 0 else -1.0
    return [a + sgn * v for v in out]


def _air_cells(m: Mapping[str, Any], r: Mapping[str, Any], core: Material, rail_mat: Material,
               branches: list[Branch], add_coil: Callable[[str, str, float], None],
               xf: list[float], yf: list[float], xs: list[float], yr: list[float],
               frame_iron: Callable[[int, int], bool]) -> None:
    """The air around the iron as a cell network (``air_model = "cells"``,
    docs/equations.md sec. 6): a tensor grid of air cells over a box around the magnet
    and the rail, one row of cells filling the gap, the winding bundles as air cells whose
    vertical links carry the turns that enclose them with the leg."""
    d, wp, ww = m["depth"], m["pole_width"], m["window_width"]
    tc, hc, gcp = m["coil_thickness"], m["coil_height"], m["coil_gap_to_pole_face"]
    hl, ty = m["leg_height"], m["yoke_thickness"]
    tr, wr = r["thickness"], r["width"]
    cell = wp / m["grid_columns"]
    xi, xo = 0.5 * ww, 0.5 * ww + wp
    half_turns = 0.5 * m["turns"]
    margin = m["air_margin"]
    eps = 1e-9 * wp
    # x lines: the rail's (they contain the frame's), the bundle faces and layers, the box
    xb = max(0.5 * wr, xo + tc)
    xl = set(xs)
    for sgn in (-1.0, 1.0):
        xl.update(sgn * a for a in _divide(xo, xo + tc, cell) + _divide(xi - tc, xi, cell))
        if xo + tc > 0.5 * wr:                      # coil sides beyond the rail's edge
            xl.update(sgn * v for v in _divide(0.5 * wr, xo + tc, cell))
        xl.update(sgn * v for v in _graded(xb, margin, cell))
        # finer air next to the pole edges, where the field concentrates
        xl.update(sgn * (xi - f * cell) for f in CORNER_REFINEMENT)
        xl.update(sgn * (xo + f * cell) for f in CORNER_REFINEMENT)
    X: list[float] = []
    for v in sorted(xl):
        if not X or v - X[-1] > eps:
            X.append(v)
    cx = [0.5 * (a + b) for a, b in zip(X[:-1], X[1:], strict=True)]
    # rows from the bottom: below the rail and the rail (relative to the rail top), the gap,
    # the frame's rows and above the yoke (absolute, pole faces at 0)
    below = _graded(-tr, -margin, cell)[::-1]
    rail_lines = [*below, *yr]
    top = hl + ty
    up_lines = sorted({*yf, *(f * cell for f in CORNER_REFINEMENT), *_graded(top, margin, cell)})
    rows: list[tuple[str, float, float]] = [("rail", a, b) for a, b in
                                            zip(rail_lines[:-1], rail_lines[1:], strict=True)]
    ngap = m["air_gap_rows"]
    rows += [("gap", 0.0, 0.0)] * ngap           # each s/ngap high
    rows += [("up", a, b) for a, b in zip(up_lines[:-1], up_lines[1:], strict=True)]

    def iron_node(ix: int, iy: int) -> tuple[str, float, float, float, float] | None:
        """The iron cell at air-grid cell (ix, iy): node, its x and y extent."""
        kind, lo, hi = rows[iy]
        x = cx[ix]
        if kind == "rail" and -0.5 * wr < x < 0.5 * wr and lo >= yr[0] - eps:
            i = bisect.bisect_right(xs, x) - 1
            j = bisect.bisect_right(yr, 0.5 * (lo + hi)) - 1
            return f"S{i}_{j}", xs[i], xs[i + 1], yr[j], yr[j + 1]
        if kind == "up" and -xo < x < xo and hi <= top + eps:
            i = bisect.bisect_right(xf, x) - 1
            j = bisect.bisect_right(yf, 0.5 * (lo + hi)) - 1
            if frame_iron(i, j):
                return f"F{i}_{j}", xf[i], xf[i + 1], yf[j], yf[j + 1]
        return None

    def side_of(x: float) -> str:
        return "left" if x < 0.0 else "right"

    def bundle(x: float) -> tuple[str, float] | None:
        """(side, share of the row's turns) of a column inside a winding bundle: the
        conductors between the column and the bundle's far face."""
        ax = abs(x)
        if xo < ax < xo + tc:
            return side_of(x), 1.0 - (ax - xo) / tc
        if xi - tc < ax < xi:
            return side_of(x), 1.0 - (xi - ax) / tc
        return None

    def air_half(name: str, iy: int, ix: int, along: str, width: float) -> Element:
        """Half of air cell (ix, iy) along x or y, cross-section ``width`` x depth."""
        kind, lo, hi = rows[iy]
        if along == "x":
            half = 0.5 * (X[ix + 1] - X[ix])
            if kind == "gap":
                return GapLayerPermeance(name, gap_input=side_of(cx[ix]), width_m=d / ngap,
                                         length_m=half)
            return LeakagePermeance(name, MU0 * d * width / half)
        if kind == "gap":
            return AirGap(name, gap_input=side_of(cx[ix]), pole_area_m2=2.0 * ngap * width * d)
        return LeakagePermeance(name, MU0 * d * width / (0.5 * (hi - lo)))

    def node(ix: int, iy: int) -> str:
        hit = iron_node(ix, iy)
        return hit[0] if hit is not None else f"A{ix}_{iy}"

    def coil_rows(iy: int) -> float:
        """Coil height between the centres of rows iy and iy + 1 (up rows only)."""
        (k0, a0, b0), (k1, a1, b1) = rows[iy], rows[iy + 1]
        if k0 != "up" or k1 != "up":
            return 0.0
        return _overlap(0.5 * (a0 + b0), 0.5 * (a1 + b1), gcp, gcp + hc)

    for iy in range(len(rows)):
        kind, lo, hi = rows[iy]
        for ix in range(len(cx)):
            here = iron_node(ix, iy)
            w = X[ix + 1] - X[ix]
            # horizontal neighbour
            if ix + 1 < len(cx):
                there = iron_node(ix + 1, iy)
                h = hi - lo
                if here is None or there is None:
                    name = f"air_h_{ix}_{iy}"
                    els: list[Element] = []
                    for k, hit in ((ix, here), (ix + 1, there)):
                        if hit is None:
                            els.append(air_half(f"{name}_{k}", iy, k, "x", h))
                        else:
                            nd, a, b, ya, yb = hit
                            face = X[ix + 1]
                            dist = face - 0.5 * (a + b) if k == ix else 0.5 * (a + b) - face
                            els.append(IronPath(f"iron_{name}_{k}", dist, h * d,
                                                rail_mat if nd.startswith("S") else core))
                    branches.append(Branch(name, node(ix, iy), node(ix + 1, iy), tuple(els)))
            # vertical neighbour
            if iy + 1 < len(rows):
                there = iron_node(ix, iy + 1)
                if here is None or there is None:
                    name = f"air_v_{ix}_{iy}"
                    els = []
                    for k, hit in ((iy, here), (iy + 1, there)):
                        if hit is None:
                            els.append(air_half(f"{name}_{k}", k, ix, "y", w))
                        else:
                            nd, a, b, ya, yb = hit
                            kk, lo2, hi2 = rows[k]
                            face = hi2 if k == iy else lo2       # shared face, own frame
                            dist = abs(face - 0.5 * (ya + yb))
                            els.append(IronPath(f"iron_{name}_{k}", dist, w * d,
                                                rail_mat if nd.startswith("S") else core))
                    branches.append(Branch(name, node(ix, iy), node(ix, iy + 1), tuple(els)))
                    share = bundle(cx[ix])
                    ov = coil_rows(iy)
                    if share is not None and ov > 0.0 and here is None and there is None:
                        add_coil(name, share[0], half_turns * share[1] * ov / hc)


def _grid_ladders(branches: list[Branch], m: Mapping[str, Any], r: Mapping[str, Any],
                  rho_core: float, rho_rail: float, layers: int) -> list[Branch]:
    """The grid's eddy elements replaced by ladders (``eddy_model = "ladder"``).

    Every link that carries an eddy element (along its part's main flux) becomes the
    nested tubes of the part's slab (thickness: pole width, yoke or rail thickness, or the
    sheet of a laminated core) on the link's own section: ``n`` parallel links of one row
    then have the part's ladder impedance exactly (conductances ``n`` times, permeances
    ``1/n`` of the part's), and the grid's statics are unchanged (parallel tubes of one
    material and length carry one flux density).
    """
    d = m["depth"]
    out: list[Branch] = []
    for br in branches:
        eddy = [el for el in br.elements if isinstance(el, EddyCurrent)]
        if not eddy:
            out.append(br)
            continue
        (iron,) = [el for el in br.elements if isinstance(el, IronPath)]
        kind = br.name.split("_")[0] + "_" + br.name.split("_")[1]
        if kind == "rail_h":
            thick, rho, solid = r["thickness"], rho_rail, True
        else:
            thick = m["yoke_thickness"] if kind == "frame_h" else m["pole_width"]
            rho, solid = rho_core, not m["laminated"]
        factor = 1.0
        if not solid:
            thick = m["sheet_thickness"]
        elif m["end_effects"]:
            factor = saint_venant_factor(thick, d)
        out += ladder_branches(br.name, br.start, br.end, iron, thickness_m=thick,
                               resistivity_ohm_m=rho, layers=layers, factor=factor)
    return out


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
