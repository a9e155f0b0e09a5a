"""Transrapid-type levitation magnet: a row of poles under the slotted long stator.

Standard magnets (two 6-pole half magnets, two circuits) and bow magnets (three
circuits) are the same builder; which pole feeds which circuit is a parameter.
Longitudinal cut (x along the track, poles hang under the stator, see docs/magnets.md)::

   S1l-S1-S1r --stator-- S2l-S2-S2r ...         stator yoke (laminated long-stator pack)
       ||     \\          ||   \\               ("split": nodes at the face edges too)
   teeth|slots window ...                       face teeth || their slots' air (T -> S),
       T1     W1r     W2l  T2                   the window's teeth and slots (W -> S)
        |                                       tooth tips
       gap                                      air gap of the face (H -> T)
        |   /  \\      |
        H1 fringe \\   H2 ...                    pole heads (pole face level)
        |         flank_j                       flank strips along the coil (C_j -> W)
      core_0      |
        C1_1 ==leak_pp_1== C2_1 ...             coil nodes along the core (K of them)
      core_1 ...
        K1 ---back--- K2 ---back--- K3 ...      pole back (solid)

``flux_paths = "paper"`` (default) is the former network: one core branch ``core_k`` with
the whole coil, the flank fringing in the gap branch, the grooves' bottom in series with the
gap, the window leakage ``leak_pp_k`` at the coil's energy-equivalent height ``h_c/3``.
``flux_paths = "split"`` (the paths a 2-D FEM led to, docs/validation_fem.md) is drawn
above.  Per pole k: the core split along its coil into ``coil_segments`` (K, default 3)
strips as the U-magnet's legs, ``core_k_j`` (K_k -> C_k_K ... C_k_1 -> H_k, each segment with the
turns of the coil it holds, saturable, eddy currents; the core ends at the pole back's
underside, as ``back_k`` already crosses the junction), beside each segment ``coil_air_k_j``
(the air through the coil's cross-section, in parallel with the iron and with its turns;
with eddy currents the segment's eddy element ``eddy_core_k_j`` follows both, through a node
``E_k_j``); ``gap_k`` (H_k -> T_k: air gap of the
face with Carter's coefficient of the stator slots and the recessed linear-generator
grooves as slots of the face) to the tooth tips, then ``teeth_k`` (T_k -> S_k: the saturable
stator teeth under the face) and in parallel ``slots_k`` (T_k -> S_k: the air of their
slots, the apparent tooth flux density of machine design);
per side ``x`` (``l``, ``r``) of the pole: ``fringe_k_x`` (H_k -> W_kx: the flank below
the coil facing that side) and ``flank_k_j_x`` (C_k_j -> W_kx: from each coil strip of the
flank below ``window/pi`` across the gap), both the pole edge's field over the stator
(conformal map, ``FringePermeance(law="conformal")``) and both landing on that
side's window teeth ``window_k_x`` (W_kx -> S_kx, with their slots' air
``window_slots_k_x``; ``across_k_x``, T_k -> W_kx: the slot at the face edge between the face's
teeth and that side's window teeth), and the stator yoke over the half face ``yoke_k_x`` (S_k -> S_kx,
``l_p/2``: the face teeth feed the yoke at the pole centre S_k, the window's teeth at the
face edge S_kx); ``leak_pb_k`` (H_k -> K_k: leakage around the coil back into the pole
back); the two end poles also ``end_k`` and ``under_k`` (K_k -> W_kx on the outer side:
Roters paths from the pole back's end face, beyond the coil's outer side, and from its
underside around the end, to the stator beyond the magnet).  Between neighbours:
``back_k`` (K_k -> K_k+1), ``stator_k`` (S_kr -> S_k+1,l: the yoke over the window,
``tau - l_p``), ``leak_pp_k`` (H_k -> H_k+1) and ``leak_pp_k_j`` (C_k_j -> C_k+1_j).
The paper's Fig. 3 flux paths map to:
nominal flux -> the face term ``A / s'``, LIG flux -> the grooves' Carter slot loss,
notch flux into the stator slots -> Carter's coefficient, leakage -> ``leak_pp``,
``leak_pb``, the flank strips.  All formulas, their sources and the 2-D FEM check that
shaped them: docs/magnets.md, docs/validation_fem.md.

End poles are built like the inner poles (same core, coil and turns); they differ only
in having one neighbour, so their outer flank leaks into the pole back (extra
``leak_pb`` length) instead of to a neighbour pole.

``end_effects`` (``[magnet]`` key, default true) keeps the terms that exist only because
the magnet has a finite width across the track: the fringing of the two pole-face edges
along the track (onto the stator's overhang) and the leakage around the coil's two
across-track sides into the pole back.  ``end_effects = false`` leaves them out: the
network is then a longitudinal cut of depth ``pole_width`` (the end poles' outer-side
leakage over that depth), the like-for-like partner of a 2-D field solution.  The
material cross-sections (stator yoke ``width``, pole back ``back_width``) and the lumped
eddy elements are unchanged.

Eddy currents: ``eddy_model = "lumped"`` (default) one solid-bar element per core segment
and pole-back segment (``EddyCurrent.solid_rectangular``); ``"ladder"`` each of them a
diffusing ladder of ``eddy_layers`` nested tubes (:mod:`maglevkit.circuit.ladder`) across
the slab of the longitudinal cut (a core across the pole length, the back across its
height), its conductances with the Saint-Venant factor of the finite width when
``end_effects`` is true (the 2-D slab when false), as the U-magnet's; the split network's
coil air then lies beside the tubes (outside the iron's eddy currents, no node ``E``).
Checked against a voltage-step transient 2-D FEM (docs/validation_fem.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import casadi as ca

from ..circuit.elements import (
    AirGap,
    EddyCurrent,
    Element,
    FringePermeance,
    IronPath,
    LeakagePermeance,
    symbolic,
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

__all__ = ["build_levitation_magnet", "levitation_network", "GeometryBranches", "pole_gap_names",
           "read_circuits"]

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
    "end_effects": Schema(bool, required=False, default=True),
    "flux_paths": Schema(str, required=False, default="paper"),
    "coil_segments": Schema(int, required=False, default=3, unit="-"),
}
FLUX_PATHS = ("paper", "split")
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
    """Gap input names ``("p01", "p02", ...)`` of a magnet with ``poles`` poles.

    Parameters
    ----------
    poles : int
        Number of poles.

    Returns
    -------
    tuple of str
    """
    return tuple(f"p{k:02d}" for k in range(1, poles + 1))


def read_circuits(raw: Any, poles: int) -> tuple[list[str], list[int]]:
    """Validate ``[circuits]``: names, and the 1-based circuit number of every pole.

    Parameters
    ----------
    raw : mapping
        The ``[circuits]`` table (``names``, ``assignment``).
    poles : int
        Number of poles.

    Returns
    -------
    tuple
        The circuit names and the circuit number (1-based) of every pole, in pole order.

    Raises
    ------
    ParameterFileError
        Bad names, an assignment of the wrong length or naming no circuit, an idle circuit.
    """
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
    names, assign = read_circuits(params["circuits"], poles)

    tau, lp, wp = m["pole_pitch"], m["pole_length"], m["pole_width"]
    hcore, hc, tc, hf = m["core_height"], m["coil_height"], m["coil_thickness"], m["coil_to_face"]
    ng, bg = m["lig_grooves"], m["lig_groove_width"]
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

    if m["flux_paths"] not in FLUX_PATHS:
        raise ParameterFileError(f"[magnet] flux_paths = {m['flux_paths']!r}: expected one of "
                                 f"{', '.join(map(repr, FLUX_PATHS))}")
    if m["flux_paths"] != "split" and "coil_segments" in params["magnet"]:
        raise ParameterFileError("[magnet] coil_segments applies to flux_paths = \"split\" "
                                 "only; remove it or set flux_paths = \"split\"")
    if m["flux_paths"] == "split" and not 1 <= m["coil_segments"] <= 12:
        raise ParameterFileError(f"[magnet] coil_segments = {m['coil_segments']}: allowed are "
                                 "1 ... 12 strips along the coil")
    core_mat = resolve_material(m["material"], materials, "magnet")
    stator_mat = resolve_material(st["material"], materials, "stator")
    net = levitation_network(m, st, names, assign, core_mat, stator_mat, options)
    return m["name"], net


class GeometryBranches:
    """The builder's comparisons of geometry values, for numbers and CasADi symbols.

    With numbers (a parameter file) each comparison is Python's own (``min``, ``max``,
    ``<``), so the network is the same as without this class.  With CasADi symbols (the
    design optimisation, :mod:`maglevkit.design`) a comparison cannot be decided on the
    expression: it is decided on the numbers the symbols take at the design point
    ``value`` evaluates at (the optimiser's start), and the condition that keeps the
    decision valid is recorded in :attr:`taken` as ``(label, expression)`` with
    ``expression >= 0`` while the decision holds.  The caller checks them at the optimum
    (and refuses, or re-decides there, when one changed sign): each side of a decision
    is a smooth function of the geometry, so the optimiser's derivatives are exact.

    Parameters
    ----------
    value : callable, optional
        ``expression -> float``: the value of a CasADi expression at the design point
        (required once a comparison involves a symbol).
    """

    def __init__(self, value: Callable[[Any], float] | None = None) -> None:
        self.value = value
        self.taken: list[tuple[str, Any]] = []

    def less(self, a: Any, b: Any, label: str) -> bool:
        """``a < b`` [same unit] (decided at the design point when symbolic; ``label``
        names the decision)."""
        if not (symbolic(a) or symbolic(b)):
            return bool(a < b)
        if self.value is None:
            raise ParameterFileError(f"geometry branch {label!r} depends on a symbolic value "
                                     "but no design point to decide it at was given")
        d = b - a
        yes = self.value(d) > 0.0
        self.taken.append((f"{label} ({'<' if yes else '>='})", d if yes else -d))
        return yes

    def minimum(self, a: Any, b: Any, label: str) -> Any:
        """``min(a, b)`` (Python's: ``a`` unless ``b < a``)."""
        return b if self.less(b, a, label) else a

    def maximum(self, a: Any, b: Any, label: str) -> Any:
        """``max(a, b)`` (Python's: ``a`` unless ``b > a``)."""
        return b if self.less(a, b, label) else a


def _log(x: Any) -> Any:
    return ca.log(x) if symbolic(x) else math.log(x)


def _hypot(a: Any, b: Any) -> Any:
    return ca.sqrt(a * a + b * b) if symbolic(a) or symbolic(b) else math.hypot(a, b)


def levitation_network(m: Mapping[str, Any], st: Mapping[str, Any], names: list[str],
                       assign: list[int], core_mat: Material, stator_mat: Material,
                       options: ModelOptions, decisions: GeometryBranches | None = None
                       ) -> Network:
    """The levitation magnet's network (module docstring): the one builder.

    :func:`build_levitation_magnet` calls it with the checked numbers of a parameter
    file; the design optimisation (:mod:`maglevkit.design`) with CasADi ``SX`` symbols for
    the geometry it varies (exact geometry derivatives).  The geometry checks of
    :func:`build_levitation_magnet` are then the optimiser's bounds and constraints, and
    the comparisons of geometry values inside the builder go through ``decisions``
    (:class:`GeometryBranches`: decided at the start design, checked at the optimum).

    Parameters
    ----------
    m : mapping
        The checked ``[magnet]`` table (:data:`MAGNET_SCHEMA`; lengths [m],
        ``turns_per_pole`` [-], ``resistance_per_pole`` [ohm]); geometry entries may be
        CasADi symbols.
    st : mapping
        The checked ``[stator]`` table (lengths [m]; numbers).
    names : list of str
        Circuit names.
    assign : list of int
        The 1-based circuit number of every pole.
    core_mat, stator_mat : Material
        The magnet's and the stator's iron.
    options : ModelOptions
        Physics switches.
    decisions : GeometryBranches, optional
        Decides the comparisons of geometry values (default: numbers only).

    Returns
    -------
    Network
    """
    br = GeometryBranches() if decisions is None else decisions
    poles = len(assign)
    gaps = pole_gap_names(poles)
    tau, lp, wp = m["pole_pitch"], m["pole_length"], m["pole_width"]
    hcore, hc, tc, hf = m["core_height"], m["coil_height"], m["coil_thickness"], m["coil_to_face"]
    hb, wb = m["back_height"], m["back_width"]
    ng, bg, dg = m["lig_grooves"], m["lig_groove_width"], m["lig_groove_depth"]
    window = tau - lp

    # ---- air gap of one pole: face teeth, LIG grooves, flanks; Carter for the stator slots
    # LIG grooves: deeper than half their width (the bundled files: 20 mm x 10 mm), their
    # flux enters through the side walls as into a slot: Carter's slot loss on the whole
    # face; shallow ones: the groove bottom in series with the gap
    split = m["flux_paths"] == "split"
    deep = split and dg >= 0.5 * bg
    face_area = (lp - (0 if deep else ng) * bg) * wp
    grooves = ((ng * bg * wp, dg),) if ng > 0 and not deep else ()
    face_slots = ((wp, bg),) * ng if deep else ()
    overhang = 0.5 * (st["width"] - wp)
    ends = m["end_effects"]       # across-track terms (a 2-D longitudinal cut has none)
    # fringing of the two flanks facing the neighbour poles: a branch of its own, whose
    # flux lands on the stator beside the pole face and rises in the teeth there (the
    # window's teeth), not in the teeth under the face; the along-track edges (end
    # effects) land on the overhang of the face's own teeth and stay in the gap branch
    edges: list[tuple[float, float]] = []
    if options.fringing and not split:
        edges += [(wp, hf), (wp, hf)]                         # flanks facing the neighbours
    if options.fringing and ends and br.less(0.0, overhang, "stator overhang beside the face"):
        r = br.minimum(hf, overhang, "end fringe radius: flank or stator edge")   # stator edge
        edges += [(lp, r), (lp, r)]
    teeth_share = 1.0 - st["slot_opening"] / st["slot_pitch"]
    tooth_area = lp * wp * teeth_share
    window_teeth = (tau - lp) * wp * teeth_share
    # "split": the air of the stator slots beside the teeth, in parallel with them (the
    # apparent tooth flux density of machine design: B_app = B_t + mu0 H_t A_slot/A_tooth),
    # a permeance mu0 A_slots / slot_depth over the slots' share of the footprint
    slot_share = 1.0 - teeth_share

    g_across = MU0 * wp * st["slot_depth"] / (2.0 * st["slot_opening"])

    def slot_air(name: str, footprint: float) -> LeakagePermeance:
        return LeakagePermeance(name, MU0 * footprint * wp * slot_share / st["slot_depth"])

    # the core runs from the face to the pole back's mid-line ("paper") or to the pole
    # back's underside ("split"): the back's branch runs from core centre to core centre
    # along the back's mid-line and so already crosses the junction of core and back;
    # the core's half back height counted it twice (2-D FEM, docs/validation_fem.md)
    core_len = hcore if split else hcore + 0.5 * hb
    stator_area = st["yoke_height"] * st["width"]
    # "split": the stator yoke carries a window's whole flux only between the face edges
    # of neighbouring poles (tau - l_p); over each half face (l_p/2) it runs in a branch of
    # its own from the pole centre, where the face teeth feed it, to the face edge, where
    # the window's teeth of that side do (2-D FEM: an end pole's flux all returns one way
    # and saturated the full-pitch branch, docs/validation_fem.md)
    yoke_split = split
    # the core split along the coil (as the U-magnet's legs): nodes C_j at the depths
    # y_j = h_f + (j - 1/2) h below the face, h = h_c/K; segments from the face up: tip
    # (to C_1), K - 1 coil strips, top (C_K to the pole back's mid-line); turns in
    # proportion to the coil they hold, so leakage can leave part-way along the winding
    nseg = m["coil_segments"] if split else 1
    h = hc / nseg
    y_nodes = [hf + (j + 0.5) * h for j in range(nseg)]
    seg_len = [y_nodes[0], *([h] * (nseg - 1)), core_len - y_nodes[-1]]
    seg_turns = [0.5 / nseg, *([1.0 / nseg] * (nseg - 1)), 0.5 / nseg]
    if not split:                          # "paper": one core branch with the whole coil
        seg_len, seg_turns = [core_len], [1.0]

    # ---- leakage estimates (Roters' method, docs/magnets.md)
    # neighbour poles: parallel faces across the window, flank below the coil (between the
    # heads) and one coil strip each (between the C_j): the MMF across the window falls
    # along the coil because the nodes see the turns below them (energy: h_c/3 as K -> oo)
    g_pp_face = MU0 * wp * hf / window
    g_pp_strip = MU0 * wp * h / window
    if not split:                          # energy-equivalent height h_c/3 of the coil
        g_pp_face = MU0 * wp * (hc / 3.0 + hf) / window
    # flanks facing the window, per coil strip [y - h/2, y + h/2]: the pole edge's field
    # (conformal map, FringePermeance law "conformal") across the gap to the stator, from
    # the flank heights where that is the shorter path: the tube from height y runs an arc
    # of pi y/2 before it crosses the gap, the path to the window's centre plane is
    # window/2 long, so the strips end at y = window/pi (the gap's own part is left out,
    # so the boundary does not move with the gap, docs/magnets.md); above it the window
    # leakage alone carries the flank's flux.  Both flanks of every pole (an end pole's
    # outer flank faces the stator beyond the magnet, with no window centre plane: strips
    # along the whole coil)
    reach = window / math.pi
    strips = [(y - 0.5 * h, br.minimum(y + 0.5 * h, reach,
                                       f"flank strip {j + 1}: top or window reach"))
              for j, y in enumerate(y_nodes)
              if br.less(y - 0.5 * h, reach, f"flank strip {j + 1} below the window "
                         "reach")] if split else []
    outer_strips = [(y - 0.5 * h, y + 0.5 * h) for y in y_nodes] if split else []
    # around the coil into the own pole back: half hollow cylinders around the coil's
    # cross-section (inner radius h_c/2, radial extent t_c) along the coil sides that do
    # not face a neighbour pole: both across-track sides, plus the outer side of an end pole
    # (without end effects only the end pole's outer side, over the cut's depth wp)
    side = lp + 2.0 * tc

    def g_pb(k: int) -> float:
        end_side = wp + 2.0 * tc if ends else wp
        length = 2.0 * side * ends + end_side * ((k == 0) + (k == poles - 1))
        return MU0 * length * _log(1.0 + tc / (0.5 * hc)) / math.pi

    rho = resistivity(m["resistivity"], core_mat, "magnet") if options.eddy_currents else 0.0
    # "ladder": each core segment and pole-back segment diffuses its eddy currents across
    # its section (nested tubes, circuit/ladder.py), the core across the pole length, the
    # back across its height: the slab of the 2-D cut, with end_effects the Saint-Venant
    # factor of the finite width (the loops close across the track), as the U-magnet's
    ladder = options.eddy_currents and options.eddy_model == "ladder"

    def ladder_factor(thickness: float, depth: float) -> float:
        return saint_venant_factor(thickness, depth) if ends else 1.0
    slots = {"slot_pitch_m": st["slot_pitch"], "slot_opening_m": st["slot_opening"]}

    def chain(k: int) -> list[str]:
        """Nodes of pole k's core from the face to the pole back."""
        inner = [f"C{k + 1}_{j + 1}" for j in range(nseg)] if split else []
        return [f"H{k + 1}", *inner, f"K{k + 1}"]

    # "split": the air beside the core, through the coil's own cross-section.  Where the
    # core's magnetic potential falls along its height by D (deep saturation), the flank's
    # potential falls with it (tangential H is continuous) and the window's air carries a
    # vertical field: with the window's centre plane at zero potential (neighbours of
    # opposite polarity) it is H_y = (D/l)(1 - x/a) at a distance x from the flank, a = half
    # the window (harmonic: V = D (y/l)(1 - x/a)).  The coil links a tube at x with the
    # share 1 - x/t_c of its turns, so the linked width per flank is
    # int_0^t_c (1 - x/a)(1 - x/t_c) dx = t_c/2 - t_c^2/(6 a); an end pole's outer flank
    # faces open air (no centre plane, a -> oo): t_c/2.  A branch parallel to each core
    # segment with that segment's turns sees exactly the iron's own drop (its MMF cancels
    # the coil's): flux mu0 w_p W D/l, linked like the core's (2-D FEM: the field's L is
    # 3.5 % above its cores' share at 10 mm / 100 A, docs/validation_fem.md)
    w_inner = 0.5 * tc - tc * tc / (6.0 * 0.5 * window)
    w_outer = 0.5 * tc

    def coil_air_width(k: int) -> float:
        """Linked air width [m] beside pole k's core, both flanks."""
        return sum(w_outer if end else w_inner for end in (k == 0, k == poles - 1))

    branches: list[Branch] = []
    coil_turns: list[list[tuple[str, float]]] = []
    for k in range(poles):
        p = gaps[k]
        nodes = chain(k)
        turns = []
        for j in range(len(seg_len)):
            name = f"core_{p}_{j}" if split else f"core_{p}"
            core_iron = IronPath(f"iron_{name}", seg_len[j], lp * wp, core_mat)
            core: list[Element] = [core_iron]
            eddy = (EddyCurrent.solid_rectangular(f"eddy_{name}", lp, wp, seg_len[j], rho),
                    ) if options.eddy_currents and not ladder else ()
            if ladder:
                # the coil air beside the core is outside the iron's eddy currents
                branches += ladder_branches(name, nodes[j + 1], nodes[j], core_iron,
                                            thickness_m=lp, resistivity_ohm_m=rho,
                                            layers=options.eddy_layers,
                                            factor=ladder_factor(lp, wp))
            # every segment carries the eddy currents of its own length
            if split and options.leakage:
                # the coil air in parallel with the iron only, the segment's eddy element in
                # series with both (node E): the air's flux follows the iron's drop, which
                # the lumped eddy element holds at a voltage step, so it is shielded with
                # the core (else the coil would link unshielded flux and the current-jump
                # admittance of paper eq. 8's R_ec would vanish)
                end = f"E{k + 1}_{j}" if eddy else nodes[j]
                air = f"coil_air_{p}_{j}"
                branches += [*([] if ladder else [Branch(name, nodes[j + 1], end, tuple(core))]),
                             Branch(air, nodes[j + 1], end, (LeakagePermeance(
                                 air, MU0 * wp * coil_air_width(k) / seg_len[j]),))]
                if eddy:
                    branches.append(Branch(f"eddy_{name}", end, nodes[j], eddy))
                turns += [(name, seg_turns[j]), (air, seg_turns[j])]
                continue
            if not ladder:
                branches.append(Branch(name, nodes[j + 1], nodes[j], (*core, *eddy)))
            turns.append((name, seg_turns[j]))
        coil_turns.append(turns)
        air_gap = AirGap(f"gap_{p}", gap_input=p, pole_area_m2=face_area, fringe_edges=tuple(edges),
                         recesses=grooves, face_slots=face_slots, **slots)
        teeth = IronPath(f"iron_teeth_{p}", st["slot_depth"], tooth_area, stator_mat)
        if split:
            # face -> tooth tips T_k, then the teeth under the face and their slots' air
            # in parallel up to the yoke
            branches += [Branch(f"gap_{p}", f"H{k + 1}", f"T{k + 1}", (air_gap,)),
                         Branch(f"teeth_{p}", f"T{k + 1}", f"S{k + 1}", (teeth,)),
                         Branch(f"slots_{p}", f"T{k + 1}", f"S{k + 1}",
                                (slot_air(f"slots_{p}", lp),))]
        else:
            branches.append(Branch(f"gap_{p}", f"H{k + 1}", f"S{k + 1}", (air_gap, teeth)))
        if yoke_split:
            for hand in ("l", "r"):
                branches.append(Branch(f"yoke_{p}_{hand}", f"S{k + 1}", f"S{k + 1}{hand}", (
                    IronPath(f"iron_yoke_{p}_{hand}", 0.5 * lp, stator_area, stator_mat),)))
        # the two windows beside the face ("split" with the yoke split at the face edges:
        # each side its own window teeth and landing node; else one node for both)
        hands = ("l", "r") if yoke_split else ("",)
        outer = {0: "l", poles - 1: "r"}.get(k) if yoke_split else None
        share = 1.0 / len(hands)
        for hand in hands:
            sfx, w_node = f"_{hand}" if hand else "", f"W{k + 1}{hand}"
            if split and (options.fringing or options.leakage):
                # the window's teeth beside the face carry what lands there (and their slots)
                branches += [Branch(f"window_{p}{sfx}", w_node, f"S{k + 1}{hand}", (
                    IronPath(f"iron_window_teeth_{p}{sfx}", st["slot_depth"],
                             share * window_teeth, stator_mat),)),
                    Branch(f"window_slots_{p}{sfx}", w_node, f"S{k + 1}{hand}",
                           (slot_air(f"window_slots_{p}{sfx}", share * (tau - lp)),))]
            if split and options.leakage:
                # across the slot at the face edge, from the face's teeth to that side's
                # window teeth (T_k -> W_kx): their potentials differ by the face teeth's
                # drop at the tips and by ~nothing at the roots, both joining the yoke, so
                # the slot (opening b, depth d) carries mu0 w_p dV d/(2b): deep in
                # saturation the increment spreads into the less loaded teeth beside the
                # face (2-D FEM, docs/validation_fem.md)
                branches.append(Branch(f"across_{p}{sfx}", f"T{k + 1}", w_node, (
                    LeakagePermeance(f"across_{p}{sfx}", g_across),)))
            if split and options.fringing:
                branches.append(Branch(f"fringe_{p}{sfx}", f"H{k + 1}", w_node, (
                    FringePermeance(f"fringe_{p}{sfx}", gap_input=p, width_m=2.0 * share * wp,
                                    radius_m=hf, law="conformal", **slots),)))
            if options.leakage:
                # an end pole's outer flank has no neighbour and no window centre plane:
                # its strips run along the whole coil
                use = outer_strips if hand and hand == outer else strips
                for j, (y0, y1) in enumerate(use):
                    name = f"flank_{p}_{j + 1}{sfx}"
                    branches.append(Branch(name, nodes[j + 1], w_node, (
                        FringePermeance(name, gap_input=p, width_m=2.0 * share * wp, radius_m=y1,
                                        inner_radius_m=y0, law="conformal", **slots),)))
        if outer and options.leakage:
            # end pole: the back's end face, beyond the coil's outer side, to the stator
            # beyond the magnet (Roters' quarter circles centred on the face's outer edge,
            # from the depth where they clear the coil's corner to the back's underside)
            r0 = br.maximum(hcore, _hypot(hf + hc, tc), "end face: core or coil corner")
            branches.append(Branch(f"end_{p}", f"K{k + 1}", f"W{k + 1}{outer}", (
                FringePermeance(f"end_{p}", gap_input=p, width_m=wp, radius_m=hcore + hb,
                                inner_radius_m=r0, **slots),)))
        if outer and options.leakage:
            # end pole: the pole back's underside, from its end to the window centre (the
            # part node K_k stands for, u <= l_p/2 + tau/2), around the end to the stator
            # beyond: a half circle of radius u about the back's bottom corner, then straight
            # up beside the end (depth D = core_height + back_height) and across the gap,
            # length pi u + D + s': (mu0 w_p/pi) ln((s' + D + pi u)/(s' + D)), i.e. the
            # fringe form of width w_p/2 between radii 2D/pi and 2D/pi + 2u
            r_d = 2.0 * (hcore + hb) / math.pi
            branches.append(Branch(f"under_{p}", f"K{k + 1}", f"W{k + 1}{outer}", (
                FringePermeance(f"under_{p}", gap_input=p, width_m=0.5 * wp,
                                radius_m=r_d + lp + tau, inner_radius_m=r_d, **slots),)))
        if options.leakage:
            if ends or k in (0, poles - 1):       # g_pb > 0: a coil side not facing a pole
                branches.append(Branch(f"leak_pb_{p}", f"H{k + 1}", f"K{k + 1}",
                                       (LeakagePermeance(f"leak_pb_{p}", g_pb(k)),)))
    for k in range(poles - 1):
        q = f"{gaps[k]}_{gaps[k + 1]}"
        back_iron = IronPath(f"iron_back_{q}", tau, hb * wb, core_mat)
        back: list[Element] = [back_iron]
        if ladder:
            branches += ladder_branches(f"back_{q}", f"K{k + 1}", f"K{k + 2}", back_iron,
                                        thickness_m=hb, resistivity_ohm_m=rho,
                                        layers=options.eddy_layers,
                                        factor=ladder_factor(hb, wb))
            back = []
        elif options.eddy_currents:
            back.append(EddyCurrent.solid_rectangular(f"eddy_back_{q}", hb, wb, tau, rho))
        if back:
            branches.append(Branch(f"back_{q}", f"K{k + 1}", f"K{k + 2}", tuple(back)))
        if yoke_split:
            branches.append(Branch(f"stator_{q}", f"S{k + 1}r", f"S{k + 2}l",
                                   (IronPath(f"iron_stator_{q}", tau - lp, stator_area,
                                             stator_mat),)))
        else:
            branches.append(Branch(f"stator_{q}", f"S{k + 1}", f"S{k + 2}",
                                   (IronPath(f"iron_stator_{q}", tau, stator_area, stator_mat),)))
        if options.leakage:
            branches.append(Branch(f"leak_pp_{q}", f"H{k + 1}", f"H{k + 2}",
                                   (LeakagePermeance(f"leak_pp_{q}", g_pp_face),)))
            for j in range(nseg if split else 0):
                branches.append(Branch(f"leak_pp_{q}_{j + 1}", chain(k)[j + 1],
                                       chain(k + 1)[j + 1],
                                       (LeakagePermeance(f"leak_pp_{q}_{j + 1}", g_pp_strip),)))

    # Alternating polarity: pole 1 drives flux up (towards the stator), pole 2 down, ...
    circuits = []
    n = m["turns_per_pole"]
    for i, cname in enumerate(names):
        # the coil-air branches carry the turns of the core segment they run beside: the
        # pole's winding has n turns (pole_turns), not the sum over parallel branches
        coils = tuple(Coil(seg, n * share, 1 if k % 2 == 0 else -1,
                           pole=gaps[k] if split else None, pole_turns=n if split else None)
                      for k in range(poles) if assign[k] == i + 1 for seg, share in coil_turns[k])
        npoles = sum(1 for a in assign if a == i + 1)
        circuits.append(Circuit(cname, m["resistance_per_pole"] * npoles, coils))
    return Network(tuple(branches), tuple(circuits), name=m["name"])


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
