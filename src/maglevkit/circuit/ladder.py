"""Diffusing eddy currents: nested flux tubes across a conducting slab (a Cauer ladder).

One eddy element per iron part (``EddyCurrent``) is a pure resistor for the coil at
``t = 0+``: a voltage step makes the current jump, and the skin dynamics of solid iron are
lost.  Here the iron part's cross-section is split into ``n`` nested flux tubes from the
surface inwards; the eddy currents flowing in the conductor between two tubes encircle the
flux of all the inner tubes, so each is an eddy element in series with the inner tubes::

    start --E_1--> m1 --tube_1--> end
                   m1 --E_2--> m2 --tube_2--> end
                               m2 ... --E_n--> mn --tube_n--> end

(``E_k``: ``V_m = G_k dPhi_k/dt`` with ``Phi_k`` the flux of tubes ``k..n``; ``tube_k``: the
iron law of the part on the area fraction ``a_k``).  For linear iron the magnetic
impedance is the Cauer form ``Z = s G_1 + 1/(P_1 + 1/(s G_2 + 1/(P_2 + ...)))`` of the
slab's ``Z = (z coth z)/P_0``, ``z^2 = s mu sigma b^2`` (docs/equations.md, section 1a).

Parameters from geometry and conductivity: ``P_k = a_k P_0``, ``G_k = w_k sigma l t b/(2 A)``
(slab of thickness ``t = 2 b``, total cross-section ``A``, length ``l``; ``A/t`` is the
depth of one slab or the total depth of a laminated stack of ``A/(t d)`` sheets), with
dimensionless ``a_k, w_k`` that depend only on ``n``: for ``n = 1`` the lumped element
(``a_1 = 1``, ``w_1 = 1/3``: ``G = sigma l t b/(6A) = t^2 l/(12 rho A)``), for ``n >= 2``
a least-squares fit of ``z coth z`` over ``omega tau`` in [1e-2, 1e5]
(``tools/fit_eddy_ladder.py``, table :data:`LADDER_COEFFICIENTS`).
"""

from __future__ import annotations

import math

from ..errors import ParameterError
from ..validation import renamed_keywords
from .elements import EddyCurrent, IronPath, rectangle_torsion_constant
from .network import Branch

__all__ = ["LADDER_COEFFICIENTS", "LADDER_BAND", "ladder_parameters", "ladder_branches",
           "EDDY_MODELS", "saint_venant_factor"]

#: Eddy-current models of the bundled magnets: one element per iron part, nested tubes,
#: or nested tubes with the rail split under and between the poles (U-magnet).
EDDY_MODELS = ("lumped", "ladder", "ladder_split")

#: Band of ``omega tau`` (``tau = mu sigma b^2``) over which the coefficients were fitted.
LADDER_BAND = (1e-2, 1e5)

#: ``n: ((a_1..a_n), (w_1..w_n))`` - tube area fractions from the surface inwards and eddy
#: weights; comments: the largest relative impedance error over :data:`LADDER_BAND`
#: (``tools/fit_eddy_ladder.py``).
LADDER_COEFFICIENTS: dict[int, tuple[tuple[float, ...], tuple[float, ...]]] = {
    1: ((1.0,), (1.0 / 3.0,)),                                  # lumped, exact DC loss
    2: ((0.03033105936, 0.9696689406),
        (0.005721682662, 0.1639259987)),                        # 1.3
    3: ((0.01043470407, 0.09168984827, 0.8978754477),
        (0.003261603507, 0.03013330242, 0.2778098902)),         # 0.52
    4: ((0.006554581594, 0.02994922422, 0.1523501963, 0.8111459979),
        (0.002294755198, 0.01377823143, 0.06711181626, 0.3429766232)),   # 0.24
    5: ((0.004996074169, 0.01593306821, 0.0548941922, 0.1957511233, 0.7284255421),
        (0.001774640323, 0.009003169128, 0.02927612737, 0.1034325294, 0.3686411093)),  # 0.11
    6: ((0.004085812674, 0.01077715307, 0.02834958341, 0.07894665431, 0.2216733199,
         0.6561674767),
        (0.001440684559, 0.006875355741, 0.01725862351, 0.04717439412, 0.1322181926,
         0.3705241882)),                                        # 0.051
    7: ((0.003457686573, 0.008290312847, 0.01802015226, 0.04182168134, 0.09902604822,
         0.2344512402, 0.5949328785),
        (0.001206807555, 0.005656444828, 0.01209801757, 0.02731846815, 0.06429183353,
         0.1524655073, 0.3599727891)),                          # 0.022
    8: ((0.002989370476, 0.006846710603, 0.01305634494, 0.02629183795, 0.05463857446,
         0.1143919761, 0.2382772815, 0.543507904),
        (0.001034124464, 0.004840664592, 0.009414916463, 0.01840864259, 0.03782998249,
         0.07903956338, 0.1653407545, 0.343666717)),            # 0.0088
}


@renamed_keywords(length="length_m", area="area_m2", thickness="thickness_m",
                  resistivity="resistivity_ohm_m")
def ladder_parameters(*, length_m: float, area_m2: float, thickness_m: float,
                      resistivity_ohm_m: float, layers: int,
                      factor: float = 1.0) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Tube areas [m^2] and eddy conductances [S] of a slab's ``layers``-tube ladder.

    Parameters
    ----------
    length_m : float
        Flux path length ``l`` [m] (deprecated keyword: ``length``).
    area_m2 : float
        Total iron cross-section ``A`` [m^2] (deprecated keyword: ``area``).
    thickness_m : float
        Slab (or sheet) thickness ``t`` across which the eddy currents diffuse [m]
        (deprecated keyword: ``thickness``).
    resistivity_ohm_m : float
        ``rho`` [ohm m] (deprecated keyword: ``resistivity``).
    layers : int
        Number of nested tubes ``n`` (1 ... 8; 1 is the lumped element).
    factor : float
        Scales every conductance (e.g. the Saint-Venant correction of a finite bar,
        ``J_rect / J_slab``).

    Raises
    ------
    ParameterError
        Non-positive geometry, ``layers`` outside 1 ... 8.
    """
    for key, v in (("length_m", length_m), ("area_m2", area_m2), ("thickness_m", thickness_m),
                   ("resistivity_ohm_m", resistivity_ohm_m), ("factor", factor)):
        if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                and v > 0.0):
            raise ParameterError(f"eddy ladder: {key} = {v!r} must be a finite number > 0")
    if isinstance(layers, bool) or not isinstance(layers, int) or layers not in LADDER_COEFFICIENTS:
        raise ParameterError(f"eddy ladder: layers = {layers!r}; allowed are the whole numbers "
                             f"{min(LADDER_COEFFICIENTS)} ... {max(LADDER_COEFFICIENTS)}")
    a, w = LADDER_COEFFICIENTS[layers]
    scale = factor * length_m * thickness_m * (0.5 * thickness_m) / (2.0 * resistivity_ohm_m * area_m2)
    return tuple(area_m2 * ak for ak in a), tuple(scale * wk for wk in w)


def saint_venant_factor(thickness_m: float, depth_m: float) -> float:
    """``J_rect / J_slab`` of a solid bar's ``thickness x depth`` section [-]: the finite
    depth's correction of its eddy conductances (the eddy currents close within the depth;
    docs/equations.md 1a, "Finite depth"), the ``factor`` of :func:`ladder_parameters`.

    Parameters
    ----------
    thickness_m : float
        Thickness across which the eddy currents diffuse [m].
    depth_m : float
        Depth of the section, along which they run [m].
    """
    return rectangle_torsion_constant(thickness_m, depth_m) / (depth_m * thickness_m**3 / 3.0)


@renamed_keywords(thickness="thickness_m", resistivity="resistivity_ohm_m")
def ladder_branches(name: str, start: str, end: str, iron: IronPath, *, thickness_m: float,
                    resistivity_ohm_m: float, layers: int, factor: float = 1.0) -> list[Branch]:
    """Branches of an iron part with diffusing eddy currents (nested tubes).

    The first branch is named ``name`` and carries the part's whole flux from ``start``
    (put a coil that encircles the part on it); it holds the outermost eddy element.
    Tube ``k`` is the branch ``f"{name}:tube{k}"`` with ``IronPath`` of ``iron``'s length
    and material on the area fraction ``a_k``; eddy element ``k >= 2`` is on
    ``f"{name}:eddy{k}"``.  Statics are those of ``iron`` exactly (parallel tubes of one
    material and length at one MMF carry one flux density).

    Parameters
    ----------
    name : str
        Name of the first branch (and prefix of the others and of the eddy elements).
    start, end : str
        Nodes the part joins [-]; flux flows from ``start`` to ``end``.
    iron : IronPath
        The part: its length [m], cross-section [m^2] and material are split into the
        tubes.
    thickness_m : float
        Thickness across which the eddy currents diffuse [m], > 0 (keyword only, like
        all that follow; deprecated keyword: ``thickness``).
    resistivity_ohm_m : float
        Electrical resistivity of the part [ohm m], > 0 (deprecated keyword:
        ``resistivity``).
    layers : int
        Number of nested tubes, 1 ... 8.
    factor : float, default 1.0
        Scales every eddy conductance, > 0 (see :func:`ladder_parameters`).

    Returns
    -------
    list of Branch
        ``2 layers`` branches, with ``layers - 1`` internal nodes ``f"{name}:n{k}"``.

    Raises
    ------
    ParameterError
        As :func:`ladder_parameters`.
    """
    areas, gs = ladder_parameters(length_m=iron.length_m, area_m2=iron.cross_section_m2,
                                  thickness_m=thickness_m, resistivity_ohm_m=resistivity_ohm_m,
                                  layers=layers, factor=factor)
    node = [f"{name}:n{k + 1}" for k in range(layers)]
    out = [Branch(name, start, node[0], (EddyCurrent(f"eddy_{name}", conductance_S=gs[0]),))]
    for k in range(layers):
        out.append(Branch(f"{name}:tube{k + 1}", node[k], end,
                          (IronPath(f"{iron.name}:tube{k + 1}", iron.length_m, areas[k],
                                    iron.material),)))
        if k + 1 < layers:
            out.append(Branch(f"{name}:eddy{k + 2}", node[k], node[k + 1],
                              (EddyCurrent(f"eddy_{name}:{k + 2}", conductance_S=gs[k + 1]),)))
    return out
