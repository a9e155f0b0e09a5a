"""Transrapid-type guidance magnet: the cross-section of the paper's Fig. 2.

Aluminium coils surround the yokes; legs connect each yoke to the two pole bars that
face the lateral guidance rail across the gap.  The magnet is split along the track
into sections, one per electric circuit; the pole bars and the rail run through::

      rail:    RU_1 ==rail_u== RU_2 ...          RU_i --rail_i-- RL_i (through the rail)
                |               |
              gap_u_1         gap_u_2             one gap input per section (g1, g2, ...)
                |               |
      bars:     U_1 ==bar_u==  U_2 ...           upper pole bar; leak_i: U_i -> L_i
                |
              leg_u_1 -- YU_1 --yoke_1 (coil)-- YL_1 -- leg_l_1 -- L_1 (lower pole bar)

``flux_paths = "split"`` (``[magnet]`` key; default ``"paper"``, the network above) adds the
paths a 2-D cross-section FEM showed missing (docs/validation_fem.md) and needs the coil's
build ``coil_thickness``::

      YU_i --leg_u_i_0-- MU_i --leg_u_i_1 (+ bar)-- U_i        legs in halves, bar its own
       |  +--top_u_i-- RO_u                                   member; top: corner -> rail
       |  leak_coil_i      leak_leg_i                         back: behind the yoke
    back_i  yoke_i ||       |                                  coil_air: the coil's own
       |    coil_air_i      |                                  cross-section beside the yoke
      YL_i --leg_l_i_1-- ML_i --leg_l_i_0 (+ bar)-- L_i        leak_coil/leak_leg: window

and, beside each face (upper shown; nodes of section i)::

      U --gap_u_i_1--> R1       U --flank_u_i_o--> RO     the face in two strips, the
      U --gap_u_i_2--> R2       U --flank_u_i_i--> RF     flanks by the conformal edge law
      rail: RO -> R1 -> R2 -> RI -> RF --rail_i-- RF_l    h_p/4, h_p/2, h_p/4, t_p/3, middle

(with lumped eddy currents the yoke's eddy element follows ``yoke_i`` and ``coil_air_i``
through a node ``EY_i``), and takes the iron members' lengths from where the flux runs: the
yoke-leg bends from their conformal map (:func:`bend_reduction`), the rail from the face's
entry to the mid-plane without a corner, the inner flank's flux landing ``t_p/3`` below the
face (guide26, docs/validation_fem.md); the legs' top fringe leaves from the yoke-leg corner
and the window's tubes beside the coil's front side from the legs' yoke ends (guidesat26:
where the field's flux leaves them).  Formulas: :func:`_split_paths` and docs/magnets.md.

Eddy currents (solid iron): ``eddy_model = "lumped"`` (default) puts one
``EddyCurrent.solid_rectangular`` element on each half leg (with the pole bar's iron), the
yoke and the rail; ``eddy_model = "ladder"`` makes each of them and each pole bar a slab
ladder of ``eddy_layers`` tubes (:func:`maglevkit.circuit.ladder.ladder_branches`) across its
thickness (legs ``t_l``, bars ``h_p``, yoke ``t_y``, rail ``t_r``; with ``end_effects``
the Saint-Venant factor of the part's depth, as the U-magnet's), ``coil_air_i`` then from
``YL_i`` to ``YU_i`` (no eddy current in the iron encircles that air); statics are the
same.  docs/magnets.md, docs/validation_fem.md (the transient FEM).

All yokes of one section are identical and in parallel magnetically with their coils in
series: they are merged into one yoke branch of the summed cross-section whose coil has
the turns of one yoke (exact for identical yokes: ``psi = n phi_total``).  Formulas and
sources: docs/magnets.md.

``end_effects`` (``[magnet]`` key, default true, as for the other kinds) has no term to
remove here: the network is already the cross-section, 2-D over the section length.  Its
terms across the cut (along the track) would be the fringing at the sections' ends and at
the magnet's two ends; the bars and the rail run through from section to section, and the
magnet's two ends are neglected.  ``end_effects = false`` therefore builds the same
network (the key is accepted so that every kind can be set to its 2-D cut alike, e.g.
against the cross-section FEM of benchmarks/fem_guidance.py).  The legs' and yokes' depth
``yokes_per_section x yoke_width`` is a material cross-section of the cut, not an end term.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..circuit.elements import (
    AirGap,
    EddyCurrent,
    Element,
    FringePermeance,
    IronPath,
    LeakagePermeance,
)
from ..circuit.ladder import ladder_branches, saint_venant_factor
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

__all__ = ["build_guidance_magnet"]

MAGNET_SCHEMA = {
    "kind": Schema(str),
    "name": Schema(str, required=False, default="guidance magnet"),
    "section_length": Schema(float, unit="m"),
    "pole_bar_height": Schema(float, unit="m"),
    "pole_bar_thickness": Schema(float, unit="m"),
    "pole_bar_distance": Schema(float, unit="m"),
    "leg_length": Schema(float, unit="m"),
    "leg_thickness": Schema(float, unit="m"),
    "yokes_per_section": Schema(int, unit="-"),
    "yoke_width": Schema(float, unit="m"),
    "yoke_thickness": Schema(float, unit="m"),
    "coil_height": Schema(float, unit="m"),
    "coil_thickness": Schema(float, required=False, unit="m"),
    "turns_per_yoke": Schema(float, unit="-", whole=True),
    "resistance_per_yoke": Schema(float, unit="ohm"),
    "material": Schema(str),
    "resistivity": Schema(float, required=False, unit="ohm m"),
    "end_effects": Schema(bool, required=False, default=True),
    "flux_paths": Schema(str, required=False, default="paper"),
}
FLUX_PATHS = ("paper", "split")
CIRCUITS_SCHEMA = {"names": Schema(list)}
RAIL_SCHEMA = {
    "thickness": Schema(float, unit="m"),
    "height": Schema(float, unit="m"),
    "material": Schema(str),
    "resistivity": Schema(float, required=False, unit="ohm m"),
}


def build_guidance_magnet(params: Mapping[str, Any], materials: Mapping[str, Material],
                          options: ModelOptions) -> tuple[str, Network]:
    """Build a guidance magnet network from parsed parameters (see module docstring).

    Parameters
    ----------
    params : mapping
        The parsed parameter file (its ``magnet`` table and the tables this kind
        needs: ``circuits``, ``rail``).
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
    for table in ("circuits", "rail"):
        if table not in params:
            raise ParameterFileError(f"missing the [{table}] table")
    names = take(params["circuits"], CIRCUITS_SCHEMA, "circuits")["names"]
    if not names or not all(isinstance(n, str) and n for n in names) \
            or len(set(names)) != len(names):
        raise ParameterFileError(f"[circuits] names = {names!r}: expected unique non-empty "
                                 "strings, one per section (electric circuit) along the track")
    r = take(params["rail"], RAIL_SCHEMA, "rail")
    L, hp, tp = m["section_length"], m["pole_bar_height"], m["pole_bar_thickness"]
    dist, ll, tl = m["pole_bar_distance"], m["leg_length"], m["leg_thickness"]
    ny, wy, ty = m["yokes_per_section"], m["yoke_width"], m["yoke_thickness"]
    hc = m["coil_height"]
    window = dist - hp
    if window <= 0.0:
        raise ParameterFileError(f"[magnet] pole_bar_distance = {dist:g} m must exceed "
                                 f"pole_bar_height = {hp:g} m (the bars would overlap)")
    if ny * wy > L:
        raise ParameterFileError(f"[magnet] {ny} yokes of width {wy:g} m do not fit in a "
                                 f"section of length {L:g} m")
    if hc > dist - tl:
        raise ParameterFileError(f"[magnet] coil_height = {hc:g} m does not fit on the yoke "
                                 f"between the legs ({dist - tl:g} m)")
    if r["height"] < dist + hp:
        raise ParameterFileError(f"[rail] height = {r['height']:g} m must cover both pole bars "
                                 f"({dist + hp:g} m)")
    if m["flux_paths"] not in FLUX_PATHS:
        raise ParameterFileError(f"[magnet] flux_paths = {m['flux_paths']!r}: expected one of "
                                 f"{', '.join(map(repr, FLUX_PATHS))}")
    split = m["flux_paths"] == "split"
    tc = m["coil_thickness"]
    if split and tc is None:
        raise ParameterFileError("[magnet] flux_paths = \"split\" needs coil_thickness (m, the "
                                 "build of the coil's sides normal to the yoke)")
    if tc is not None and not 0.0 < tc < ll:
        raise ParameterFileError(f"[magnet] coil_thickness = {tc:g} m: the coil's front side "
                                 f"must fit between the yoke and the pole bars, 0 < coil_thickness"
                                 f" < leg_length = {ll:g} m")
    iron = resolve_material(m["material"], materials, "magnet")
    rail_mat = resolve_material(r["material"], materials, "rail")
    eddy = options.eddy_currents
    rho = resistivity(m["resistivity"], iron, "magnet") if eddy else 0.0
    rho_rail = resistivity(r["resistivity"], rail_mat, "rail") if eddy else 0.0

    face = L * hp
    # bar flanks above and below the face see the rail (it covers both bars); flank depth
    # = bar thickness.  The ends of the sections along the track do not fringe (the bars
    # continue), except at the two magnet ends, which are neglected (2-D cross-section):
    # there is no across-cut term, so m["end_effects"] (true or false) changes nothing.
    edges = ((L, tp), (L, tp)) if options.fringing else ()
    leg_area = ny * wy * tl
    yoke_area = ny * wy * ty
    leg_len = ll + 0.5 * (tp + ty)
    yoke_len = dist
    # "split": the yoke-leg corner (the t_y x t_l rectangle) as the conformal map of a
    # right-angled bend gives it (bend_reduction): each member runs along its outer edge to
    # the outer corner, less the bend's reduction of that member (equal widths: the corner
    # square counts 0.559 of a square, the centre lines' right angle 1, the mean quarter
    # circle used before 0.785)
    if split:
        yoke_len = dist + tl - 2.0 * bend_reduction(ty, tl)
    rail_len = dist + r["thickness"]
    # "split": where the bars' inner flanks' flux lands on the rail below the face: Roters'
    # tube from flank depth x lands x beside the face, and the centroid of their flux density
    # 1/(s + pi x/2) over the flank depth t_p is 0.31 / 0.35 / 0.39 t_p at s = 0.15 / 0.25 /
    # 0.5 t_p: t_p/3 (at most a quarter of the window: the rail's middle keeps a length)
    land = min(tp / 3.0, 0.25 * window)
    if split:
        # the rail in pieces (upper side; the lower mirrors it): the face's flux enters
        # over the face height in two strips of h_p/2, each at its middle (nodes R1, R2:
        # the staircase of the uniform entry, whose drop in linear iron is h_p/2 at full
        # flux like the ramp's; in saturation nearer the ramp's than one step), the outer
        # flank and the legs' top fringe above the face (RO, the bar's outer edge: their
        # flux crosses the whole face height), the inner flank below it at ``land`` (RF);
        # the rest runs to the mid-plane, no corner to turn: d - h_p - 2 land between RF_u
        # and RF_l
        rail_len = dist - hp - 2.0 * land
    rail_area = L * r["thickness"]
    # leakage between the pole bars across the window (parallel faces, flank depth t_p)
    # and between the legs (energy-equivalent coil height h_c/3 for the yoke part)
    g_leak = MU0 * L * tp / window + MU0 * ny * wy * (ll + hc / 3.0) / window
    if split:
        paths = _split_paths(L, hp, tp, dist, ll, tl, ny, wy, ty, hc, tc, m["end_effects"])
        g_leak = paths["bars"]

    ladder = eddy and options.eddy_model == "ladder"

    def with_eddy(els: list[Element], name: str, w: float, h: float, length: float,
                  rho_: float) -> tuple[Element, ...]:
        if eddy:
            els.append(EddyCurrent.solid_rectangular(name, w, h, length, rho_))
        return tuple(els)

    def part(branch: str, start: str, end: str, irons: list[IronPath], w: float, h: float,
             rho_: float, thickness: float, eddy_length: float | None = None) -> list[Branch]:
        """An iron part (``irons[0]``; a pole bar ``irons[1]`` in series) as branches: one
        lumped eddy element of the ``w x h`` section over the part's length, or
        (``eddy_model = "ladder"``) the slab ladder of the part across ``thickness`` and the
        bar's own ladder across its height ``h_p``.  ``eddy_length`` [m]: the length of
        conducting material the eddy currents see, where it differs from the magnetic
        length (the yoke-leg bends: the centre lines, which share out the corner's
        material; the bend's magnetic length is shorter)."""
        length = irons[0].length_m if eddy_length is None else eddy_length
        if not ladder:
            return [Branch(branch, start, end, with_eddy(
                list(irons), f"eddy_{branch}", w, h, length, rho_))]
        mid = f"{branch}:bar" if len(irons) > 1 else end
        out = slab(branch, start, mid, irons[0], thickness, w, rho_, length)
        if len(irons) > 1:
            out += slab(mid, mid, end, irons[1], hp, L, rho_)
        return out

    def slab(branch: str, start: str, end: str, iron: IronPath, thickness: float,
             depth: float, rho_: float, eddy_length: float | None = None) -> list[Branch]:
        """The slab ladder of one part across ``thickness``; with ``end_effects`` the
        Saint-Venant factor of its finite ``depth`` (docs/equations.md 1a), as the
        U-magnet's; the eddy conductances over ``eddy_length`` (default: the part's)."""
        factor = saint_venant_factor(thickness, depth) if m["end_effects"] else 1.0
        if eddy_length is not None:
            factor *= eddy_length / iron.length_m
        return ladder_branches(branch, start, end, iron, thickness_m=thickness,
                               resistivity_ohm_m=rho_, layers=options.eddy_layers, factor=factor)

    branches: list[Branch] = []
    circuits: list[Circuit] = []
    for i, cname in enumerate(names, start=1):
        g = f"g{i}"
        if split:
            # legs in two halves (node M at mid-length: the window's leakage beyond the coil
            # leaves there), their leakage to the other leg, the air behind the yoke (yoke
            # end to yoke end) and the legs' top fringe to the rail.  A leg runs along
            # its outer edge from the outer corner (less the bend's reduction) to the bar's
            # back, at the legs' section; the bar is a member of its own in series at the leg's end,
            # t_p at its section L h_p (the "paper" leg counts t_p/2 at the legs' smaller
            # section, which saturates first: at 6 mm / 80 A the FEM's line integral of H
            # through the bar is 82 A of the 12 kA, the "paper" leg's t_p/2 230 A)
            h = 0.5 * (ll + ty - bend_reduction(tl, ty))
            for side, a, b in (("u", f"YU{i}", f"U{i}"), ("l", f"L{i}", f"YL{i}")):
                mid = f"M{side.upper()}{i}"
                for j, (n0, n1) in enumerate(((a, mid), (mid, b))):
                    els = [IronPath(f"iron_leg_{side}_{i}_{j}", h, leg_area, iron)]
                    if j == (1 if side == "u" else 0):
                        els.append(IronPath(f"iron_bar_{side}_{i}", tp, L * hp, iron))
                    branches += part(f"leg_{side}_{i}_{j}", n0, n1, els, ny * wy, tl, rho, tl,
                                     eddy_length=0.5 * (ll + 0.5 * ty))
            if options.leakage:
                branches += [
                    Branch(f"leak_leg_{i}", f"MU{i}", f"ML{i}",
                           (LeakagePermeance(f"leak_leg_{i}", paths["legs"]),)),
                    # the window's tubes beside the coil's front side (within t_c of the
                    # yoke, a quarter of the window's permeance for tr-guidance) leave from
                    # the legs' yoke ends: in the field the window's flux leaving the yoke's
                    # front face is 15-19 % of it in linear iron, up to 65 % in deep
                    # saturation, where the legs' own drop lowers their potential
                    # (guidesat26, docs/validation_fem.md)
                    Branch(f"leak_coil_{i}", f"YU{i}", f"YL{i}",
                           (LeakagePermeance(f"leak_coil_{i}", paths["legs_coil"]),)),
                    Branch(f"back_{i}", f"YU{i}", f"YL{i}",
                           (LeakagePermeance(f"back_{i}", paths["back"]),))]
            if options.fringing:
                # the top fringe from the yoke-leg corner (YU, YL): in the field the corner's
                # top face sends 1.1-1.6 times the leg's top face's flux at every recorded
                # point (guidesat26, docs/validation_fem.md)
                for side, n0, n1 in (("u", f"YU{i}", f"ROU{i}"), ("l", f"ROL{i}", f"YL{i}")):
                    branches.append(Branch(f"top_{side}_{i}", n0, n1, (FringePermeance(
                        f"top_{side}_{i}", gap_input=g, width_m=paths["top_width"],
                        radius_m=tp + ll, inner_radius_m=tp),)))
                # the bars' flanks (depth t_p, along the section) to the rail beside the
                # face: the field of a right-angled pole edge over a plane (the conformal
                # law, as the TR09 split network's flanks), the outer flank landing above
                # the face (RO), the inner one below it (RF)
                for side, n0, n1 in (("u", f"U{i}", f"ROU{i}"), ("u", f"U{i}", f"RFU{i}"),
                                     ("l", f"ROL{i}", f"L{i}"), ("l", f"RFL{i}", f"L{i}")):
                    name = f"flank_{side}_{i}_{'o' if 'RO' in n0 + n1 else 'i'}"
                    branches.append(Branch(name, n0, n1, (FringePermeance(
                        name, gap_input=g, width_m=L, radius_m=tp, law="conformal"),)))
        branches += [] if split else part(
            f"leg_u_{i}", f"YU{i}", f"U{i}", [IronPath(f"iron_leg_u_{i}", leg_len, leg_area,
                                                       iron)], ny * wy, tl, rho, tl)
        # the rail: flux along its height, eddy currents across its thickness
        if split:
            # the face in two strips (outer: gap_u_i_1 to R1, inner: gap_u_i_2 to R2), its
            # flanks are branches of their own (above); the rail beside the face in pieces
            # RO -> R1 -> R2 -> RI (h_p/4, h_p/2, h_p/4), RI -> RF (land), and mirrored
            for k in (1, 2):
                branches += [
                    Branch(f"gap_u_{i}_{k}", f"U{i}", f"R{k}U{i}", (AirGap(
                        f"gap_u_{i}_{k}", gap_input=g, pole_area_m2=0.5 * face),)),
                    Branch(f"gap_l_{i}_{k}", f"R{k}L{i}", f"L{i}", (AirGap(
                        f"gap_l_{i}_{k}", gap_input=g, pole_area_m2=0.5 * face),))]
            pieces = (("o", "RO", "R1", 0.25 * hp), ("f", "R1", "R2", 0.5 * hp),
                      ("i", "R2", "RI", 0.25 * hp), ("b", "RI", "RF", land))
            for side in ("u", "l"):
                for tag, a, b, length in pieces:
                    name = f"rail_{i}_{side}{tag}"
                    ends = (f"{a}U{i}", f"{b}U{i}") if side == "u" else (f"{b}L{i}", f"{a}L{i}")
                    branches += part(name, *ends,
                                     [IronPath(f"iron_{name}", length, rail_area, rail_mat)],
                                     L, r["thickness"], rho_rail, r["thickness"])
        else:
            branches += [
                Branch(f"gap_u_{i}", f"U{i}", f"RU{i}", (
                    AirGap(f"gap_u_{i}", gap_input=g, pole_area_m2=face, fringe_edges=edges),)),
                Branch(f"gap_l_{i}", f"RL{i}", f"L{i}", (
                    AirGap(f"gap_l_{i}", gap_input=g, pole_area_m2=face, fringe_edges=edges),))]
        rail_ends = (f"RFU{i}", f"RFL{i}") if split else (f"RU{i}", f"RL{i}")
        branches += part(f"rail_{i}", *rail_ends,
                         [IronPath(f"iron_rail_{i}", rail_len, rail_area, rail_mat)],
                         L, r["thickness"], rho_rail, r["thickness"])
        branches += [] if split else part(
            f"leg_l_{i}", f"L{i}", f"YL{i}", [IronPath(f"iron_leg_l_{i}", leg_len, leg_area,
                                                       iron)], ny * wy, tl, rho, tl)
        branches += [
        ]
        yoke_iron = IronPath(f"iron_yoke_{i}", yoke_len, yoke_area, iron)
        coils = [Coil(f"yoke_{i}", m["turns_per_yoke"])]
        if split and options.leakage:
            # the air through the coil's cross-section beside the yoke, in parallel with its
            # iron and with the same turns (it sees the iron's own drop), the yoke's eddy
            # element in series with both (node EY), as the levitation magnet's coil_air;
            # with the ladder the air joins the yoke's ends directly (no eddy current in
            # the iron encircles that air flux) and the yoke is its ladder across t_y
            end = f"EY{i}" if eddy and not ladder else f"YU{i}"
            branches += [*(slab(f"yoke_{i}", f"YL{i}", end, yoke_iron, ty, ny * wy, rho, dist)
                           if ladder else [Branch(f"yoke_{i}", f"YL{i}", end, (yoke_iron,))]),
                         Branch(f"coil_air_{i}", f"YL{i}", end, (LeakagePermeance(
                             f"coil_air_{i}", paths["coil_air"]),))]
            if eddy and not ladder:
                branches.append(Branch(f"eddy_yoke_{i}", end, f"YU{i}", (
                    EddyCurrent.solid_rectangular(f"eddy_yoke_{i}", ny * wy, ty, dist, rho),)))
            # one winding on two parallel branches: its flux is the turn-weighted mean
            coils = [Coil(b, m["turns_per_yoke"], pole=f"yoke_{i}",
                          pole_turns=m["turns_per_yoke"]) for b in (f"yoke_{i}", f"coil_air_{i}")]
        else:
            branches += part(f"yoke_{i}", f"YL{i}", f"YU{i}", [yoke_iron], ny * wy, ty, rho, ty,
                             eddy_length=dist)
        if options.leakage:
            branches.append(Branch(f"leak_{i}", f"U{i}", f"L{i}",
                                   (LeakagePermeance(f"leak_{i}", g_leak),)))
        circuits.append(Circuit(cname, ny * m["resistance_per_yoke"], tuple(coils)))
        if i > 1:
            j = i - 1
            bar = L  # centre-to-centre distance of neighbouring sections
            branches += [
                Branch(f"bar_u_{j}_{i}", f"U{j}", f"U{i}",
                       (IronPath(f"iron_bar_u_{j}_{i}", bar, hp * tp, iron),)),
                Branch(f"bar_l_{j}_{i}", f"L{j}", f"L{i}",
                       (IronPath(f"iron_bar_l_{j}_{i}", bar, hp * tp, iron),)),
            ]
            # the rail beside the faces along the track ("split": beside each strip, half
            # the section each)
            for side in ("u", "l"):
                nodes = (f"R1{side.upper()}", f"R2{side.upper()}") if split \
                    else (f"R{side.upper()}",)
                for node in nodes:
                    name = f"rail_{side}_{j}_{i}" + (f"_{node[1]}" if split else "")
                    branches.append(Branch(name, f"{node}{j}", f"{node}{i}", (IronPath(
                        f"iron_{name}", bar, hp * r["thickness"] / len(nodes), rail_mat),)))
    return m["name"], Network(tuple(branches), tuple(circuits), name=m["name"])


def bend_reduction(w_own: float, w_other: float) -> float:
    """Reduction [m] of a member's outer-edge length at a right-angled bend into a member of
    width ``w_other`` [m], for a member of width ``w_own`` [m] (2-D, uniform permeability).

    The bend of two strips (widths ``a`` = ``w_own``, ``b`` = ``w_other``) is the image of
    the upper half plane under Schwarz-Christoffel's ``dz/dzeta = (b/pi) sqrt(zeta + a^2/b^2)
    / (sqrt(zeta - 1) zeta)`` (outer corner at ``zeta = 1``, inner corner at ``-a^2/b^2``,
    the strips at ``zeta -> 0`` and ``infinity``); the flux from one strip to the other has
    the potential ``ln|zeta|/pi`` per unit flux, so the bend's reluctance is that of the two
    strips along their outer edges up to the outer corner, each less a length

    ``c(a, b) = (a/pi) [2 ln 2 - ln(1 + (b/a)^2) + 2 (b/a) atan(b/a)]``

    (the integral in closed form).  Equal widths: ``c = (ln 2/pi + 1/2) w = 0.7206 w``, the
    corner square then counts ``2 - 2 x 0.7206 = 0.559`` of a square (the centre lines' right
    angle: 1, the mean quarter circle: pi/4).  docs/magnets.md, "Guidance magnet".
    """
    r = w_other / w_own
    return w_own / math.pi * (2.0 * math.log(2.0) - math.log1p(r * r) + 2.0 * r * math.atan(r))


def plate_flux(a: float, b: float, xi: float, n: int = 4096) -> float:
    """Flux [Wb per m depth, per mu0 and per ampere-turn] crossing the mid-plane behind a
    thin plate beyond the distance ``xi`` [m] from it.

    The plate (the yoke's back face) has height ``2 b`` [m]; its magnetic potential is
    ``+1/2`` above the coil (``y > a``, ``a`` [m] the coil's half height), ``-1/2`` below it
    and linear in between (a coil of one ampere-turn).  The exterior of the plate (a slit)
    is the exterior of the unit circle under Joukowski's map ``w = (b/2)(zeta + 1/zeta)``,
    the plate's potential there ``f(phi) = clip(b cos(phi)/a, -1, 1)/2``; the complex
    potential is Schwarz's integral ``W(zeta) = (1/2 pi) int f(phi) (zeta + e^{i phi}) /
    (zeta - e^{i phi}) dphi`` and the flux between the mid-plane's point ``zeta = i rho``
    (``xi = (b/2)(rho - 1/rho)``) and infinity is ``|Im W(i rho)|``.  Midpoint rule over
    ``n`` points (4096: converged to 1e-7 relative; the kinks of f limit it to second order).
    """
    phi = (np.arange(n) + 0.5) * (2.0 * math.pi / n)
    f = 0.5 * np.clip(b * np.cos(phi) / a, -1.0, 1.0)
    t = xi / b
    zeta = 1j * (t + math.sqrt(t * t + 1.0))
    e = np.exp(1j * phi)
    return float(abs(np.mean(f * (zeta + e) / (zeta - e)).imag))


def _split_paths(L: float, hp: float, tp: float, dist: float, ll: float, tl: float,
                 ny: int, wy: float, ty: float, hc: float, tc: float,
                 ends: bool) -> dict[str, float]:
    """Permeances [H] and widths [m] of the ``flux_paths = "split"`` air paths of one section.

    Depths: the bars run through the section (``L``); the legs, the yoke and its coil exist
    over the yokes' width ``yokes = n_y w_y`` only (the coil's sides add ``2 t_c`` per yoke
    behind the yoke).  ``ends = False`` (the 2-D cross-section, as the FEM) puts every path
    at the cut's depth ``L``.
    """
    ny_depth = L if not ends else ny * wy
    a, b = 0.5 * hc, 0.5 * (dist + tl)           # coil's and yoke's half heights
    back_depth = L if not ends else min(L, ny * (wy + 2.0 * tc))
    # the bars' inner faces across the window (parallel faces)
    bars = MU0 * L * tp / (dist - hp)
    # the legs' inner faces across the window between them; over the first t_c from the
    # yoke the coil's front side fills the window and a tube at xi links xi/t_c of the
    # turns: energy-equivalent length t_c/3 (as the paper's h_c/3); that part ("legs_coil")
    # leaves from the legs' yoke ends, the rest ("legs") from their middles
    legs = MU0 * ny_depth * (ll - tc) / (dist - tl)
    legs_coil = MU0 * ny_depth * (tc / 3.0) / (dist - tl)
    # behind the yoke: through the coil's back side (vertical tubes of length 2a linked
    # xi/t_c of the turns: energy-equivalent t_c/(3 2a)), and beyond it the field of the
    # yoke's back face seen as a thin plate of height 2b, its upper part at +NI/2 and its
    # lower part at -NI/2 (the coil's ramp between), the flux crossing the mid-plane
    # behind it beyond xi = t_c (plate_flux)
    back = MU0 * back_depth * (tc / (6.0 * a) + plate_flux(a, b, tc))
    # the air through the coil's cross-section beside the yoke (in parallel with the yoke,
    # with its turns): where the yoke's potential falls by D along its length, the air
    # beside it carries H = D/l, and a tube at x from the yoke links 1 - x/t_c of the
    # turns: linked width t_c/2 per coil side facing open air (the levitation magnet's
    # coil_air); the coil's sides run round the yoke (front and back over the cut's depth;
    # with end effects the whole perimeter 2 (w_y + t_y) of every yoke)
    area = L * tc if not ends else ny * (wy + ty) * tc
    coil_air = MU0 * area / dist
    return {"bars": bars, "legs": legs, "legs_coil": legs_coil, "back": back,
            "coil_air": coil_air,
            "top_width": ny_depth}


def guidance_magnet_range(params: Mapping[str, Any]) -> PlausibleRange:
    """Plausible inputs: gaps up to the pole-bar height, currents up to
    :data:`~maglevkit.magnets.base.MAX_CURRENT_DENSITY_A_PER_M2` in one yoke's coil.

    The coil's build cannot exceed the leg length between yoke and pole bar, so
    ``coil_height x leg_length`` bounds the coil's cross-section from above (and the
    current bound is generous).  ``coil_thickness`` (optional, for ``flux_paths =
    "split"``) is not used here, so the bound is the same with and without it."""
    m = params["magnet"]
    return PlausibleRange.from_geometry(
        gap_m=float(m["pole_bar_height"]), gap_basis="the pole-bar height",
        turns=float(m["turns_per_yoke"]),
        winding_area_m2=float(m["coil_height"]) * float(m["leg_length"]),
        winding="the coil of one yoke (coil_height x leg_length, an upper bound)")


register_kind("guidance_magnet", build_guidance_magnet, ("circuits", "rail"),
              guidance_magnet_range)
