"""The guideway parameter file (TOML, SI units, provenance tags like the magnet files).

::

    [guideway]
    span_length = 24.768          # m (pier spacing of single-span girders)
    mass_per_length = 7500.0      # kg/m
    bending_stiffness = 4.0e10    # N m^2
    damping_ratio = 0.01          # - (every mode)
    modes = 5                     # sine modes per span
    precamber = 2.7e-3            # m, built-in midspan camber (optional, default 0)
    [provenance]
    "guideway.span_length" = "[R] ..."

Unknown or missing keys and bad values raise :class:`~maglevkit.errors.ParameterFileError`.
The bundled file is ``guideway`` (``maglevkit/data/vehicle/guideway.toml``).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import ParameterError, ParameterFileError, PlausibilityWarning
from ..magnets.base import Schema, take
from ..parameter_files import bundled_files, parse_provenance, read_parameter_file
from ..validation import check_plausible
from .guideway import GUIDEWAY_PLAUSIBLE, BeamSpan, Guideway

__all__ = ["GuidewayData", "load_guideway", "parse_guideway", "bundled_guideways",
           "GUIDEWAY_SCHEMA", "GUIDEWAY_PLAUSIBLE"]

GUIDEWAY_SCHEMA = {
    "span_length": Schema(float, unit="m"),
    "mass_per_length": Schema(float, unit="kg/m"),
    "bending_stiffness": Schema(float, unit="N m^2"),
    "damping_ratio": Schema(float, unit="-", check="nonnegative"),
    "modes": Schema(int, unit="-"),
    "precamber": Schema(float, unit="m", check="nonnegative", required=False, default=0.0),
}



@dataclass(frozen=True)
class GuidewayData:
    """A parsed guideway file.

    Attributes
    ----------
    span : BeamSpan
        The girder (all spans identical).
    provenance : dict
        ``"guideway.key" -> tag/source``.
    source : str
        File path or bundled name.
    """

    span: BeamSpan
    provenance: Mapping[str, str] = field(default_factory=dict)
    source: str = ""

    def guideway(self, *, n_spans: int = 3, moving_boundary: bool = True, rigid: bool = False,
                 origin_m: float = 0.0) -> Guideway:
        """A :class:`Guideway` of these spans (see there for the options).

        Parameters
        ----------
        n_spans : int, default 3
            Number of integrated spans (>= 1): the moving window, or the whole guideway
            without the moving boundary.
        moving_boundary : bool, default True
            Recycle spans every load has left (an infinitely long guideway).
        rigid : bool, default False
            A rigid guideway (no deflection).
        origin_m : float, default 0.0
            Position of pier 0 [m].

        Returns
        -------
        Guideway

        Raises
        ------
        ParameterError
            ``n_spans`` not a whole number >= 1 or a non-finite ``origin_m``.
        InputError
            ``moving_boundary`` or ``rigid`` not True/False.
        """
        return Guideway(self.span, n_spans=n_spans, moving_boundary=moving_boundary, rigid=rigid,
                        origin_m=origin_m)


def parse_guideway(parameters: Mapping[str, Any], source: str = "parameters") -> GuidewayData:
    """Validate a parsed guideway TOML dictionary.

    Parameters
    ----------
    parameters : mapping
        The parsed file: a ``guideway`` table (keys ``span_length`` [m],
        ``mass_per_length`` [kg/m], ``bending_stiffness`` [N m^2], ``damping_ratio`` [-],
        ``modes``, optional ``precamber`` [m]: the girders' built-in midspan camber
        along the uniform-load line, default 0) and an optional ``provenance`` table.
    source : str, default "parameters"
        Label for error messages and :attr:`GuidewayData.source`.

    Returns
    -------
    GuidewayData

    Raises
    ------
    ParameterFileError
        Missing or unknown tables or keys, or invalid values.
    """
    if not isinstance(parameters, Mapping) or "guideway" not in parameters:
        raise ParameterFileError(f"{source}: missing the [guideway] table")
    unknown = sorted(set(parameters) - {"guideway", "provenance"})
    if unknown:
        raise ParameterFileError(f"{source}: unknown table(s) {unknown}; a guideway file may have: "
                                 "guideway, provenance")
    g = take(parameters["guideway"], GUIDEWAY_SCHEMA, "guideway")
    check_plausible({"guideway": g}, GUIDEWAY_PLAUSIBLE, source, stacklevel=3)
    try:
        with warnings.catch_warnings():   # the same ranges, warned above naming the file
            warnings.simplefilter("ignore", PlausibilityWarning)
            span = BeamSpan(g["span_length"], g["bending_stiffness"], g["mass_per_length"],
                            n_modes=g["modes"], damping_ratio=g["damping_ratio"],
                            precamber_m=g["precamber"])
    except ParameterError as exc:
        raise ParameterFileError(f"{source}: {exc}") from None
    prov = parse_provenance(parameters, ("guideway",), source)
    return GuidewayData(span, prov, source)


def bundled_guideways() -> list[str]:
    """Names of the guideway files shipped with maglevkit."""
    return bundled_files("vehicle", table="guideway")


def load_guideway(source: str | Path = "guideway") -> GuidewayData:
    """Load a guideway file by path or bundled name (default: the bundled ``guideway``).

    Parameters
    ----------
    source : str or Path, default "guideway"
        Path of a TOML file, or the name of a bundled file (:func:`bundled_guideways`).

    Returns
    -------
    GuidewayData

    Raises
    ------
    ParameterFileError
        Missing file, TOML syntax error, unknown/missing keys or invalid values.
    """
    params, label = read_parameter_file(source, what="guideway", folder="vehicle",
                                        table="guideway")
    return parse_guideway(params, label)
