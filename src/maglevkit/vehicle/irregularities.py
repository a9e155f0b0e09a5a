"""Guideway irregularities: vertical deviations of the stator underside from its nominal line.

Sign convention: positive downward, like the guideway deflection ``w``; a positive
irregularity under a levitation magnet closes its gap just as a deflection does.
Every profile gives its elevation ``r(x)`` [m] and slope ``dr/dx`` [m/m] at any positions,
so that a magnet at ``x_m(t)`` moving at ``v`` sees ``r(x_m)`` and the rate ``v dr/dx``.

Deterministic profiles
    :class:`SpanSag` (span-periodic sag or camber between the piers), :class:`JointSteps`
    (steps at the stator-pack joints, every 1.032 m on the Transrapid), and
    :class:`HarmonicProfile` (a sinusoid, e.g. of the stator-pack or pole pitch).
Random profiles
    :class:`RandomProfile`: a seeded sum of cosines with amplitudes from a one-sided PSD
    (:class:`GermanTrackPSD`, :class:`PowerLawPSD` or any callable), reproducible and
    evaluable anywhere.  :meth:`Profile.tabulate` samples any profile once for fast
    interpolation in a simulation loop.

Profiles add: ``SpanSag(...) + JointSteps(...) + RandomProfile(...)``.  Formulas and
sources: ``docs/vehicle.md``.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError, OutOfRangeError, ParameterError
from ..validation import real_array, real_number, renamed_keywords, whole_number

__all__ = [
    "Profile",
    "SumProfile",
    "SpanSag",
    "JointSteps",
    "HarmonicProfile",
    "RandomProfile",
    "TabulatedProfile",
    "GermanTrackPSD",
    "PowerLawPSD",
    "STATOR_PACK_LENGTH_M",
]

STATOR_PACK_LENGTH_M = 1.032
"""Transrapid long-stator pack length [m]: 12 slots of 86 mm = 4 pole pitches of 258 mm
(widely quoted, [R]); 24 packs make one 24.768 m span."""


def _x(position_m: Any) -> np.ndarray:
    return real_array(position_m, "positions", "m")


def _finite(name: str, value: Any, unit: str, *, positive: bool = False) -> float:
    return real_number(value, name, unit, positive=positive, error=ParameterError)


def _seed(value: Any, what: str = "seed") -> int:
    try:
        return whole_number(value, what, minimum=0)
    except InputError as exc:
        raise ParameterError(str(exc)) from None


def _band(omega_min: Any, omega_max: Any, *, zero_ok: bool) -> tuple[float, float]:
    """A band ``[omega_min, omega_max]`` [rad/m] of a PSD integral, checked (InputError)."""
    lo = real_number(omega_min, "omega_min", "rad/m", nonnegative=zero_ok, positive=not zero_ok)
    hi = real_number(omega_max, "omega_max", "rad/m", positive=True)
    if not hi > lo:
        raise InputError(f"omega_max = {hi:g} rad/m must be > omega_min = {lo:g} rad/m (a "
                         "reversed or empty band)")
    return lo, hi


class Profile:
    """Base class: an irregularity profile ``r(x)`` [m], positive downward."""

    def elevation_m(self, position_m: Any) -> np.ndarray:  # pragma: no cover - abstract
        """Irregularity ``r(x)`` [m] at positions [m], positive downward.

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``r(x)`` [m], same shape as ``position_m``.
        """
        raise NotImplementedError

    def slope(self, position_m: Any) -> np.ndarray:  # pragma: no cover - abstract
        """``dr/dx`` [m/m] at positions [m] (steps contribute nothing: a jump has no rate).

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``dr/dx`` [m/m], same shape as ``position_m``.
        """
        raise NotImplementedError

    def on_paths(self, positions_m: np.ndarray, *, start_m: np.ndarray, step_m: float
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Elevation [m] and slope [-] at ``positions_m`` (n_steps, n_points), points
        that move at a constant speed: ``positions_m[k, j] = start_m[j] + k step_m`` (up
        to rounding).  The default evaluates :meth:`elevation_m` and :meth:`slope` at
        ``positions_m``; profiles with a faster way for such paths override it.

        Parameters
        ----------
        positions_m : array_like (n_steps, n_points)
            Positions [m] of the points at every step.
        start_m : array_like (n_points,)
            Position of each point at step 0 [m] (keyword only; used by the overrides).
        step_m : float
            Distance travelled per step [m] (speed times time step; keyword only).

        Returns
        -------
        (elevation_m, slope) : ndarray (n_steps, n_points) each
            ``r`` [m] and ``dr/dx`` [m/m].
        """
        x = np.asarray(positions_m, dtype=float)
        return (np.asarray(self.elevation_m(x.ravel())).reshape(x.shape),
                np.asarray(self.slope(x.ravel())).reshape(x.shape))

    def __call__(self, position_m: Any) -> np.ndarray:
        return self.elevation_m(position_m)

    def __add__(self, other: Profile) -> SumProfile:
        if not isinstance(other, Profile):
            return NotImplemented
        return SumProfile((self, other))

    def tabulate(self, start_m: float, stop_m: float, step_m: float) -> TabulatedProfile:
        """Sample this profile on ``[start_m, stop_m]`` every ``step_m`` for fast lookup
        (cubic Hermite interpolation of elevation and slope).

        For smooth profiles only: the interpolation rounds off steps (:class:`JointSteps`,
        the kinks of :class:`SpanSag` at the piers); evaluate those directly (cheap).

        Parameters
        ----------
        start_m, stop_m : float
            First and last position of the table [m], finite, ``stop_m > start_m``.
        step_m : float
            Sample spacing [m], > 0.  The table runs on to the first sample at or beyond
            ``stop_m``.

        Returns
        -------
        TabulatedProfile
            Positions outside the table raise :class:`~maglevkit.errors.OutOfRangeError`.

        Raises
        ------
        ParameterError
            Non-finite bounds, ``step_m <= 0`` or ``stop_m <= start_m``.
        """
        a, b = _finite("start_m", start_m, "m"), _finite("stop_m", stop_m, "m")
        h = _finite("step_m", step_m, "m", positive=True)
        if b <= a:
            raise ParameterError(f"stop_m = {b} m must be > start_m = {a} m")
        n = int(math.ceil((b - a) / h)) + 1
        x = a + h * np.arange(n)
        return TabulatedProfile(x, self.elevation_m(x), self.slope(x))


@dataclass(frozen=True, eq=False)
class SumProfile(Profile):
    """The sum of several profiles (what ``profile_a + profile_b`` gives).

    Parameters
    ----------
    parts : tuple of Profile
        The summed profiles.
    """

    parts: tuple[Profile, ...]

    def elevation_m(self, position_m: Any) -> np.ndarray:
        """Sum of the parts' elevations [m].

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``r(x)`` [m], same shape as ``position_m``.
        """
        x = _x(position_m)
        return sum((p.elevation_m(x) for p in self.parts), np.zeros_like(x))

    def slope(self, position_m: Any) -> np.ndarray:
        """Sum of the parts' slopes [m/m].

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``dr/dx`` [m/m], same shape as ``position_m``.
        """
        x = _x(position_m)
        return sum((p.slope(x) for p in self.parts), np.zeros_like(x))

    def on_paths(self, positions_m: np.ndarray, *, start_m: np.ndarray, step_m: float
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Sum of the parts' :meth:`Profile.on_paths` (each part's fast path).

        Parameters
        ----------
        positions_m : array_like (n_steps, n_points)
            Positions [m] of the points at every step.
        start_m : array_like (n_points,)
            Position of each point at step 0 [m].
        step_m : float
            Distance travelled per step [m].

        Returns
        -------
        (elevation_m, slope) : ndarray (n_steps, n_points) each
            ``r`` [m] and ``dr/dx`` [m/m].
        """
        x = np.asarray(positions_m, dtype=float)
        r, rx = np.zeros_like(x), np.zeros_like(x)
        for p in self.parts:
            a, b = p.on_paths(x, start_m=start_m, step_m=step_m)
            r += a
            rx += b
        return r, rx

    def __add__(self, other: Profile) -> SumProfile:
        if not isinstance(other, Profile):
            return NotImplemented
        return SumProfile((*self.parts, other))


@dataclass(frozen=True, eq=False)
class SpanSag(Profile):
    """Span-periodic sag (amplitude > 0) or camber (< 0) between the piers.

    ``shape="uniform_load"``: the static deflection line of a simply supported beam under
    a uniform load, scaled to ``amplitude_m`` at midspan,
    ``r = A (16/5) (xi - 2 xi^3 + xi^4)``, ``xi = (x - x0)/L mod 1``;
    ``shape="half_sine"``: ``r = A sin(pi xi)``.  Both vanish at the piers, with a kink
    there (single-span girders rotate independently at their bearings).

    Parameters
    ----------
    amplitude_m : float
        Midspan value [m].
    span_length_m : float
        Pier spacing [m] (> 0).
    origin_m : float
        Position of a pier [m].
    shape : {"uniform_load", "half_sine"}
        Deflection line between the piers (default ``"uniform_load"``).

    Raises
    ------
    ParameterError
        Non-finite values, ``span_length_m <= 0`` or an unknown ``shape``.
    """

    amplitude_m: float
    span_length_m: float
    origin_m: float = 0.0
    shape: str = "uniform_load"

    def __post_init__(self) -> None:
        _finite("amplitude_m", self.amplitude_m, "m")
        _finite("span_length_m", self.span_length_m, "m", positive=True)
        _finite("origin_m", self.origin_m, "m")
        if self.shape not in ("uniform_load", "half_sine"):
            raise ParameterError(f"shape = {self.shape!r}; allowed: 'uniform_load', 'half_sine'")

    def _xi(self, position_m: Any) -> np.ndarray:
        # u - floor(u) equals np.mod(u, 1.0) bit for bit (both round the exact u - floor(u)
        # once) at a fraction of its cost (np.mod's fmod per element)
        u = (_x(position_m) - self.origin_m) / self.span_length_m
        return u - np.floor(u)

    def _value(self, xi: np.ndarray) -> np.ndarray:
        if self.shape == "half_sine":
            return self.amplitude_m * np.sin(math.pi * xi)
        return (self.amplitude_m * 3.2) * (xi * (1.0 + xi * xi * (xi - 2.0)))

    def _slope(self, xi: np.ndarray) -> np.ndarray:
        if self.shape == "half_sine":
            return (self.amplitude_m * math.pi / self.span_length_m) * np.cos(math.pi * xi)
        return (self.amplitude_m * 3.2 / self.span_length_m) * (1.0 + xi * xi * (4.0 * xi - 6.0))

    def elevation_m(self, position_m: Any) -> np.ndarray:
        """Sag ``r(x)`` [m] at positions [m], positive downward (0 at the piers).

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite; any position (the profile repeats
            every ``span_length_m`` from ``origin_m``).

        Returns
        -------
        ndarray
            ``r(x)`` [m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        """
        return self._value(self._xi(position_m))

    def slope(self, position_m: Any) -> np.ndarray:
        """``dr/dx`` [m/m] at positions [m].

        At a pier (``xi = 0``) the slope is that of the span starting there (the right-hand
        side of the kink).

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``dr/dx`` [m/m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        """
        return self._slope(self._xi(position_m))

    def on_paths(self, positions_m: np.ndarray, *, start_m: np.ndarray, step_m: float
                 ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`elevation_m` and :meth:`slope` at ``positions_m`` (the span coordinate
        computed once for both).

        Parameters
        ----------
        positions_m : array_like (n_steps, n_points)
            Positions [m] of the points at every step.
        start_m : array_like (n_points,)
            Position of each point at step 0 [m] (not needed here: the sag is evaluated
            where the points are).
        step_m : float
            Distance travelled per step [m] (not needed here).

        Returns
        -------
        (elevation_m, slope) : ndarray (n_steps, n_points) each
            ``r`` [m] and ``dr/dx`` [m/m].
        """
        x = np.asarray(positions_m, dtype=float)
        xi = self._xi(x.ravel()).reshape(x.shape)
        return self._value(xi), self._slope(xi)


@dataclass(frozen=True, eq=False)
class JointSteps(Profile):
    """Steps at the stator-pack joints: pack ``n`` (on ``[x0 + n p, x0 + (n+1) p)``) is
    offset by ``h_n``.

    ``pattern="alternating"``: ``h_n = +-step_m/2`` alternately, a step of ``step_m`` at
    every joint; ``pattern="random"``: ``h_n`` uniform in ``[-step_m/2, step_m/2]``, seeded
    (reproducible; pack ``n`` always gets the same offset, whatever is evaluated first).

    Parameters
    ----------
    step_m : float
        Step height (alternating) or the range of offsets (random) [m] (>= 0).
    pitch_m : float
        Pack length [m]; default the Transrapid's 1.032 m.
    origin_m : float
        Position of a joint [m].
    pattern : {"alternating", "random"}
        How the pack offsets alternate (default ``"alternating"``).
    seed : int
        Seed of the random offsets (whole number >= 0; default 0).

    Raises
    ------
    ParameterError
        Non-finite values, ``step_m < 0``, ``pitch_m <= 0``, an unknown ``pattern`` or a
        bad seed.
    """

    step_m: float
    pitch_m: float = STATOR_PACK_LENGTH_M
    origin_m: float = 0.0
    pattern: str = "alternating"
    seed: int = 0

    def __post_init__(self) -> None:
        if _finite("step_m", self.step_m, "m") < 0:
            raise ParameterError(f"step_m = {self.step_m!r} m must be >= 0")
        _finite("pitch_m", self.pitch_m, "m", positive=True)
        _finite("origin_m", self.origin_m, "m")
        if self.pattern not in ("alternating", "random"):
            raise ParameterError(f"pattern = {self.pattern!r}; allowed: 'alternating', 'random'")
        object.__setattr__(self, "seed", _seed(self.seed))

    def pack_index(self, position_m: Any) -> np.ndarray:
        """Index ``n`` of the stator pack at each position.

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray of int64
            ``floor((x - origin_m) / pitch_m)``, same shape as ``position_m``.
        """
        return np.floor((_x(position_m) - self.origin_m) / self.pitch_m).astype(np.int64)

    def elevation_m(self, position_m: Any) -> np.ndarray:
        """Irregularity ``r(x)`` [m] at positions [m], positive downward.

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``r(x)`` [m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        """
        n = self.pack_index(position_m)
        if self.pattern == "alternating":
            return np.where(n % 2 == 0, 0.5, -0.5) * self.step_m
        # a counter-based hash of (seed, n): the same offset for pack n in any evaluation
        u = _hash_uniform(self.seed, n)
        return (u - 0.5) * self.step_m

    def slope(self, position_m: Any) -> np.ndarray:
        """``dr/dx`` [m/m] at positions [m]: zero (a step has no rate).

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``dr/dx`` [m/m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        """
        return np.zeros_like(_x(position_m))


def _hash_uniform(seed: int, n: np.ndarray) -> np.ndarray:
    """Uniform [0, 1) numbers from integers (SplitMix64 finaliser), reproducible per index."""
    with np.errstate(over="ignore"):
        z = (n.astype(np.uint64) + np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15)
             + np.uint64(0x632BE59BD9B4E019))
        z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
        z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
        z = z ^ (z >> np.uint64(31))
    return (z >> np.uint64(11)).astype(np.float64) / float(2 ** 53)


@dataclass(frozen=True, eq=False)
class HarmonicProfile(Profile):
    """``r = A sin(2 pi (x - x0) / lambda)``: e.g. the stator-pack (1.032 m) or pole-pitch
    (0.258 m) periodicity.

    Parameters
    ----------
    amplitude_m : float
        Amplitude A [m] (finite; negative flips the sign).
    wavelength_m : float
        Wavelength lambda [m], > 0; default the stator-pack length 1.032 m.
    origin_m : float
        Position x0 of a zero crossing with positive slope [m] (default 0).

    Raises
    ------
    ParameterError
        Non-finite values or ``wavelength_m <= 0``.
    """

    amplitude_m: float
    wavelength_m: float = STATOR_PACK_LENGTH_M
    origin_m: float = 0.0

    def __post_init__(self) -> None:
        _finite("amplitude_m", self.amplitude_m, "m")
        _finite("wavelength_m", self.wavelength_m, "m", positive=True)
        _finite("origin_m", self.origin_m, "m")

    def elevation_m(self, position_m: Any) -> np.ndarray:
        """Irregularity ``r(x)`` [m] at positions [m], positive downward.

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``r(x)`` [m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        """
        k = 2 * math.pi / self.wavelength_m
        return self.amplitude_m * np.sin(k * (_x(position_m) - self.origin_m))

    def slope(self, position_m: Any) -> np.ndarray:
        """``dr/dx`` [m/m] at positions [m].

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``dr/dx`` [m/m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        """
        k = 2 * math.pi / self.wavelength_m
        return self.amplitude_m * k * np.cos(k * (_x(position_m) - self.origin_m))


# ----------------------------------------------------------------------------- PSDs
@dataclass(frozen=True)
class GermanTrackPSD:
    """One-sided vertical-profile PSD of the form used for German high-speed track::

        S(Omega) = A_v Omega_c^2 / ((Omega^2 + Omega_r^2) (Omega^2 + Omega_c^2))

    in m^2/(rad/m), ``Omega`` the spatial angular frequency [rad/m].  The defaults are the
    widely quoted "low irregularity" values ``A_v = 4.032e-7 m rad``,
    ``Omega_c = 0.8246 rad/m``, ``Omega_r = 0.0206 rad/m`` (high irregularity:
    ``A_v = 1.080e-6``) for *railway* track (e.g. Zhai, Vehicle-Track Coupled Dynamics,
    2020; Lei, High Speed Railway Track Dynamics, 2017); a maglev guideway is smoother at
    long and rougher at short wavelengths (Shi et al., J. Zhejiang Univ. Sci. A 15 (2014)
    385-394), so scale ``A_v`` to the case.

    Parameters
    ----------
    A_v_m_rad : float
        Roughness coefficient ``A_v`` [m rad], > 0.
    omega_c_rad_per_m : float
        Cut-off spatial frequency ``Omega_c`` [rad/m], > 0.
    omega_r_rad_per_m : float
        Second corner spatial frequency ``Omega_r`` [rad/m], > 0 and different from
        ``omega_c_rad_per_m``.

    Raises
    ------
    ParameterError
        Values not finite and > 0, or ``omega_r_rad_per_m == omega_c_rad_per_m``.
    """

    A_v_m_rad: float = 4.032e-7
    omega_c_rad_per_m: float = 0.8246
    omega_r_rad_per_m: float = 0.0206

    def __post_init__(self) -> None:
        _finite("A_v_m_rad", self.A_v_m_rad, "m rad", positive=True)
        _finite("omega_c_rad_per_m", self.omega_c_rad_per_m, "rad/m", positive=True)
        _finite("omega_r_rad_per_m", self.omega_r_rad_per_m, "rad/m", positive=True)
        if self.omega_r_rad_per_m == self.omega_c_rad_per_m:
            raise ParameterError("omega_r_rad_per_m must differ from omega_c_rad_per_m")

    def __call__(self, omega_rad_per_m: Any) -> np.ndarray:
        w2 = np.asarray(omega_rad_per_m, dtype=float) ** 2
        c, r = self.omega_c_rad_per_m, self.omega_r_rad_per_m
        return self.A_v_m_rad * c * c / ((w2 + r * r) * (w2 + c * c))

    @renamed_keywords(omega_min="omega_min_rad_per_m", omega_max="omega_max_rad_per_m")
    def variance_m2(self, omega_min_rad_per_m: float, omega_max_rad_per_m: float) -> float:
        """Exact ``int S dOmega`` over ``[omega_min, omega_max]`` [m^2] (partial fractions).

        Old keyword names (``omega_min``, ``omega_max``) are deprecated aliases for one
        release.

        Parameters
        ----------
        omega_min_rad_per_m, omega_max_rad_per_m : float
            Band of spatial angular frequencies [rad/m], finite,
            ``0 <= omega_min < omega_max``.

        Returns
        -------
        float
            Variance [m^2] of the profile components in the band.

        Raises
        ------
        InputError
            A band that is not finite, starts below 0, or is reversed or empty.
        """
        omega_min_rad_per_m, omega_max_rad_per_m = _band(omega_min_rad_per_m, omega_max_rad_per_m,
                                                         zero_ok=True)
        c, r = self.omega_c_rad_per_m, self.omega_r_rad_per_m

        def prim(w: float) -> float:
            return (math.atan(w / r) / r - math.atan(w / c) / c) * c * c / (c * c - r * r)

        return self.A_v_m_rad * (prim(omega_max_rad_per_m) - prim(omega_min_rad_per_m))


@dataclass(frozen=True)
class PowerLawPSD:
    """One-sided power-law PSD ``S(Omega) = S0 (Omega / Omega0)^(-n)`` [m^2/(rad/m)].

    Parameters
    ----------
    S0_m2_per_rad_per_m : float
        PSD ``S0`` at the reference frequency [m^2/(rad/m)], > 0.
    exponent : float
        Exponent n [-] (finite; default 2).
    omega0_rad_per_m : float
        Reference spatial frequency ``Omega0`` [rad/m], > 0 (default 1).

    Raises
    ------
    ParameterError
        ``S0_m2_per_rad_per_m`` or ``omega0_rad_per_m`` not finite and > 0, or a
        non-finite ``exponent``.
    """

    S0_m2_per_rad_per_m: float
    exponent: float = 2.0
    omega0_rad_per_m: float = 1.0

    def __post_init__(self) -> None:
        _finite("S0_m2_per_rad_per_m", self.S0_m2_per_rad_per_m, "m^2/(rad/m)", positive=True)
        _finite("exponent", self.exponent, "")
        _finite("omega0_rad_per_m", self.omega0_rad_per_m, "rad/m", positive=True)

    def __call__(self, omega_rad_per_m: Any) -> np.ndarray:
        w = np.asarray(omega_rad_per_m, dtype=float)
        return self.S0_m2_per_rad_per_m * (w / self.omega0_rad_per_m) ** (-self.exponent)

    @renamed_keywords(omega_min="omega_min_rad_per_m", omega_max="omega_max_rad_per_m")
    def variance_m2(self, omega_min_rad_per_m: float, omega_max_rad_per_m: float) -> float:
        """Exact ``int S dOmega`` over ``[omega_min, omega_max]`` [m^2].

        Old keyword names (``omega_min``, ``omega_max``) are deprecated aliases for one
        release.

        Parameters
        ----------
        omega_min_rad_per_m, omega_max_rad_per_m : float
            Band of spatial angular frequencies [rad/m], finite,
            ``0 <= omega_min < omega_max``; ``omega_min = 0`` only for ``exponent < 1``
            (the integral diverges at 0 otherwise).

        Returns
        -------
        float
            Variance [m^2] of the profile components in the band.

        Raises
        ------
        InputError
            A band that is not finite, starts below 0, or is reversed or empty; or
            ``omega_min = 0`` with ``exponent >= 1``.
        """
        omega_min_rad_per_m, omega_max_rad_per_m = _band(omega_min_rad_per_m, omega_max_rad_per_m,
                                                         zero_ok=True)
        s0, n, w0 = self.S0_m2_per_rad_per_m, self.exponent, self.omega0_rad_per_m
        if omega_min_rad_per_m == 0.0 and n >= 1.0:
            raise InputError(f"omega_min = 0 rad/m: the variance of a power law with "
                             f"exponent = {n:g} >= 1 diverges at 0; allowed: omega_min > 0 "
                             "(or an exponent < 1)")
        if n == 1.0:
            return s0 * w0 * math.log(omega_max_rad_per_m / omega_min_rad_per_m)
        return s0 * w0 ** n * (omega_max_rad_per_m ** (1 - n) - omega_min_rad_per_m ** (1 - n)) / (1 - n)


@dataclass(frozen=True, eq=False)
class RandomProfile(Profile):
    """A random profile from a one-sided PSD by a seeded sum of cosines::

        r(x) = sum_k a_k cos(Omega_k x + phi_k),   a_k = sqrt(2 P_k),
        P_k = int_{bin k} S(Omega) dOmega

    over ``n_components`` equal bins of ``[omega_min, omega_max]``; ``Omega_k`` uniformly
    jittered within the middle half of bin ``k`` (so the profile does not repeat after
    ``2 pi / dOmega``) and phases ``phi_k`` uniform in ``[0, 2 pi)``, both from
    ``numpy.random.default_rng(seed)`` (spectral representation, Shinozuka and Deodatis,
    Appl. Mech. Rev. 44 (1991) 191-204).  The bin powers ``P_k`` are 5-point
    Gauss-Legendre integrals of ``S``, so the profile's spatial variance
    ``sum_k a_k^2 / 2`` equals ``int S dOmega`` over the band.

    Parameters
    ----------
    psd : callable
        One-sided PSD ``S(Omega)`` [m^2/(rad/m)] of ``Omega`` [rad/m].
    omega_min_rad_per_m, omega_max_rad_per_m : float
        Band [rad/m] (wavelengths ``2 pi / Omega``); 0 < min < max.
    n_components : int
        Number of cosines (>= 1).
    seed : int
        Seed (>= 0): the same seed gives the same profile.
    """

    psd: Callable[[np.ndarray], np.ndarray]
    omega_min_rad_per_m: float
    omega_max_rad_per_m: float
    n_components: int = 1000
    seed: int = 0
    omega_rad_per_m: np.ndarray = field(init=False, repr=False)
    amplitude_m: np.ndarray = field(init=False, repr=False)
    phase_rad: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        lo = _finite("omega_min_rad_per_m", self.omega_min_rad_per_m, "rad/m", positive=True)
        hi = _finite("omega_max_rad_per_m", self.omega_max_rad_per_m, "rad/m", positive=True)
        if hi <= lo:
            raise ParameterError(f"omega_max_rad_per_m = {hi} must be > omega_min_rad_per_m = {lo}")
        n = _seed(self.n_components, "n_components")
        if n < 1:
            raise ParameterError(f"n_components = {n!r}: must be a whole number >= 1")
        object.__setattr__(self, "n_components", n)
        object.__setattr__(self, "seed", _seed(self.seed))
        if not callable(self.psd):
            raise ParameterError("psd must be a callable S(Omega) [m^2/(rad/m)]")
        rng = np.random.default_rng(self.seed)
        d = (hi - lo) / n
        om = lo + d * (np.arange(n) + 0.5 + 0.5 * (rng.random(n) - 0.5))
        phase = 2 * math.pi * rng.random(n)
        # power of each bin: 5-point Gauss-Legendre of S over the bin (exact to ~1e-10
        # for smooth spectra), so the variance is the band integral whatever the jitter
        g, gw = np.polynomial.legendre.leggauss(5)
        nodes = lo + d * (np.arange(n)[:, None] + 0.5 + 0.5 * g[None, :])
        s = np.asarray(self.psd(nodes.ravel()), dtype=float)
        if s.shape != (nodes.size,) or not np.isfinite(s).all() or (s < 0).any():
            raise ParameterError("psd must return finite values >= 0, one per frequency")
        power = 0.5 * d * (s.reshape(nodes.shape) @ gw)
        for name, v in (("omega_rad_per_m", om), ("amplitude_m", np.sqrt(2 * power)),
                        ("phase_rad", phase)):
            v.setflags(write=False)
            object.__setattr__(self, name, v)

    @property
    def bin_width_rad_per_m(self) -> float:
        return (self.omega_max_rad_per_m - self.omega_min_rad_per_m) / self.n_components

    @property
    def variance_m2(self) -> float:
        """Exact spatial variance of the profile, ``sum_k a_k^2 / 2`` [m^2]."""
        return float(0.5 * np.sum(self.amplitude_m ** 2))

    def _sum(self, position_m: Any, derivative: bool) -> np.ndarray:
        x = _x(position_m)
        flat = x.ravel()
        out = np.empty_like(flat)
        chunk = max(1, 2 ** 22 // self.n_components)
        for i in range(0, flat.size, chunk):
            arg = np.multiply.outer(flat[i:i + chunk], self.omega_rad_per_m) + self.phase_rad
            if derivative:
                out[i:i + chunk] = -(np.sin(arg) @ (self.amplitude_m * self.omega_rad_per_m))
            else:
                out[i:i + chunk] = np.cos(arg) @ self.amplitude_m
        return out.reshape(x.shape)

    def elevation_m(self, position_m: Any) -> np.ndarray:
        """Irregularity ``r(x)`` [m] at positions [m], positive downward.

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``r(x)`` [m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        """
        return self._sum(position_m, False)

    def slope(self, position_m: Any) -> np.ndarray:
        """``dr/dx`` [m/m] at positions [m].

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``dr/dx`` [m/m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        """
        return self._sum(position_m, True)

    def on_paths(self, positions_m: np.ndarray, *, start_m: np.ndarray, step_m: float
                 ) -> tuple[np.ndarray, np.ndarray]:
        """The profile on paths ``start_m[j] + k step_m``, synthesised once along the track.

        All points travel the same track at the same speed, so the sum of cosines is
        evaluated once on a uniform track grid of spacing ``step_m / q`` (``q`` the
        smallest whole number giving a spacing <= :meth:`track_spacing_m`) with its first
        :data:`TRACK_HERMITE_ORDER` derivatives, and each point's elevation and slope are
        two-point Hermite interpolants of degree ``2 M - 1`` between its grid neighbours
        (``M`` = :data:`TRACK_HERMITE_ORDER` conditions at each end; a point keeps its
        place between the nodes along the whole path, so its weights are computed once).
        The remainder ``h^(2M) / (4^M (2M)!) max|r^(2M)|``, bounded by
        ``sum_k a_k Omega_k^(2M)``, is kept below :data:`TRACK_TOLERANCE` of the profile's
        RMS elevation (and of the RMS slope for the slope).  Cost: (track length /
        spacing) x ``n_components`` x ``(M + 1)`` products instead of
        ``n_steps x n_points x n_components x 2`` complex ones on the points' own paths;
        where that is not cheaper (few points, very slow runs) and for ``step_m <= 0``,
        the sums are taken on the paths themselves (:meth:`_on_paths_phasors`); positions
        further off ``start_m + k step_m`` than their rounding are evaluated where they are
        (:meth:`elevation_m`, :meth:`slope`).

        Parameters
        ----------
        positions_m : array_like (n_steps, n_points)
            Positions [m] of the points at every step, ideally
            ``start_m[j] + k step_m``.  Other shapes, or paths that do not match
            ``start_m`` and ``step_m``, are evaluated point by point (the base method).
        start_m : array_like (n_points,)
            Position of each point at step 0 [m] (keyword only).
        step_m : float
            Distance travelled per step [m] (speed times time step; keyword only); 0 for a
            standing train.

        Returns
        -------
        (elevation_m, slope) : ndarray (n_steps, n_points) each
            ``r`` [m] and ``dr/dx`` [m/m].
        """
        x = np.asarray(positions_m, dtype=float)
        start = np.asarray(start_m, dtype=float).ravel()
        if x.ndim != 2 or x.shape[1] != start.size:
            return super().on_paths(x, start_m=start_m, step_m=step_m)
        step = float(step_m)
        n_steps, n_pts = x.shape
        if n_steps == 0 or n_pts == 0:
            return np.zeros(x.shape), np.zeros(x.shape)
        if step == 0.0 and np.array_equal(x, np.broadcast_to(start, x.shape)):
            r0, rx0 = self._on_paths_phasors(start[None, :], start, 0.0)
            return (np.repeat(r0, n_steps, axis=0), np.repeat(rx0, n_steps, axis=0))
        m = TRACK_HERMITE_ORDER
        h_max = self.track_spacing_m()
        q = max(1, math.ceil(step / h_max))
        hg = step / q
        g0 = float(start.min())
        u = (start - g0) / hg if step > 0 else np.zeros(n_pts)
        i0 = np.floor(u).astype(np.int64)
        n_grid = int(i0.max()) + q * (n_steps - 1) + 2
        # the positions' rounding off the ideal paths (~1e-13 m from ``x0 + v t``) is
        # corrected to first order in the elevation below; positions further off are not
        # such paths: evaluated where they are
        delta = x - (start[None, :] + np.arange(n_steps, dtype=float)[:, None] * step)
        if float(np.max(np.abs(delta), initial=0.0)) > _on_path_tolerance_m(x):
            return super().on_paths(x, start_m=start_m, step_m=step_m)
        if not (step > 0 and n_grid * (m + 1) < 2 * x.size):
            return self._on_paths_phasors(x, start, step)
        cols = self._track_table(g0, hg, n_grid, m + 1)           # h^p r^(p), p = 0..m
        t = np.clip(u - i0, 0.0, 1.0)
        w = _hermite_weights(t, m)                                  # (n_pts, 2 m)
        r = np.empty(x.shape)
        rx = np.empty(x.shape)
        stop = q * (n_steps - 1) + 1
        for j in range(n_pts):
            a = cols[i0[j]:i0[j] + stop:q]
            b = cols[i0[j] + 1:i0[j] + 1 + stop:q]
            r[:, j] = a[:, :m] @ w[j, :m] + b[:, :m] @ w[j, m:]
            rx[:, j] = (a[:, 1:] @ w[j, :m] + b[:, 1:] @ w[j, m:]) / hg
        r += rx * delta             # first order; the slope's r'' delta is < 1e-11 r''
        return r, rx

    def track_spacing_m(self) -> float:
        """Largest track-grid spacing [m] of :meth:`on_paths` whose Hermite remainder bound
        stays below :data:`TRACK_TOLERANCE` of the RMS elevation and of the RMS slope."""
        m = TRACK_HERMITE_ORDER
        a, om = self.amplitude_m, self.omega_rad_per_m
        c = 4.0 ** m * math.factorial(2 * m) * TRACK_TOLERANCE
        rms = math.sqrt(0.5 * float(np.sum(a ** 2)))
        rms_slope = math.sqrt(0.5 * float(np.sum((a * om) ** 2)))
        hs = []
        for scale, weight in ((rms, a * om ** (2 * m)), (rms_slope, a * om ** (2 * m + 1))):
            bound = float(np.sum(weight))
            if scale > 0 and bound > 0:
                hs.append((c * scale / bound) ** (1.0 / (2 * m)))
        return min(hs) if hs else math.inf

    def _track_table(self, g0: float, h: float, n: int, n_cols: int) -> np.ndarray:
        """``(h d/dx)^p r`` at ``g0 + i h``, ``i < n``, ``p < n_cols`` (n, n_cols).

        By phasors in blocks of ``B ~ sqrt(n)`` nodes, in real arithmetic: with
        ``theta_bk = Omega_k x_b + phi_k`` at the block starts ``x_b`` and
        ``a_k (i h Omega_k)^p exp(i theta_bk) = A + i B``, the block's column ``p`` is
        ``cos(Omega n h) A^T - sin(Omega n h) B^T`` (two real matrix products per column
        for all blocks, ``(h Omega)^p`` applied to the ``(B, K)`` factors).  The phasors
        ``exp(i Omega n h)``, ``n < B``, and ``exp(i Omega B h b)``, ``b < n / B``, are
        products of at most ``log2`` of their count directly evaluated powers
        (:func:`_phasor_powers`): ~``4 log2(n) K`` sines and cosines instead of
        ``~4 sqrt(n) K``."""
        om, amp, ph = self.omega_rad_per_m, self.amplitude_m, self.phase_rad
        block = int(min(256, max(16, math.isqrt(n))))
        n_blocks = -(-n // block)
        w_in = _phasor_powers(h * om, block)                                     # (B, K)
        wc, ws = w_in.real, w_in.imag
        z = amp * _phasor_powers(h * block * om, n_blocks) * np.exp(1j * (g0 * om + ph))
        ca_, sa_ = np.ascontiguousarray(z.real.T), np.ascontiguousarray(z.imag.T)  # (K, nb)
        out = np.empty((n_blocks, block, n_cols))
        hom = h * om
        for p in range(n_cols):                   # times i^p (h Omega)^p
            fac = hom ** p
            if p % 2 == 0:                        # Re(W z) = wc ca - ws sa
                col = (wc * fac) @ ca_ - (ws * fac) @ sa_
            else:                                 # Im(W z) = wc sa + ws ca
                col = (wc * fac) @ sa_ + (ws * fac) @ ca_
            out[:, :, p] = -col.T if p % 4 in (1, 2) else col.T
        return out.reshape(-1, n_cols)[:n]

    def _on_paths_phasors(self, x: np.ndarray, start: np.ndarray, step: float
                          ) -> tuple[np.ndarray, np.ndarray]:
        """The sums on each point's own path by phasors: with
        ``z_jk = a_k exp(i (Omega_k x_j + phi_k))`` at the start of a block of ``B`` steps,
        the block's elevations are ``Re(W z)`` and slopes ``-Im(W (Omega z))``, with
        ``W[n, k] = exp(i Omega_k n step_m)`` computed once.  Mathematically the same sum
        as :meth:`elevation_m`; the phase differs by rounding only (|Omega x| eps)."""
        n_steps = x.shape[0]
        om, amp, ph = self.omega_rad_per_m, self.amplitude_m, self.phase_rad
        block = max(1, min(n_steps, 256))
        w = np.exp(1j * np.multiply.outer(np.arange(block) * float(step), om))   # (B, K)
        r = np.empty(x.shape)
        rx = np.empty(x.shape)
        for n0 in range(0, n_steps, block):
            nb = min(block, n_steps - n0)
            x0 = start + n0 * float(step)
            z = amp * np.exp(1j * (np.multiply.outer(x0, om) + ph))                    # (m, K)
            out = w[:nb] @ np.concatenate([z, z * om], axis=0).T                        # (nb, 2m)
            r[n0:n0 + nb] = out[:, :start.size].real
            rx[n0:n0 + nb] = -out[:, start.size:].imag
        return r, rx


def _phasor_powers(angle_rad: np.ndarray, n: int) -> np.ndarray:
    """``exp(i j angle)`` for ``j = 0 ... n - 1`` (n, K), by doubling: rows ``[m, 2 m)``
    are rows ``[0, m)`` times ``exp(i m angle)``, evaluated directly for ``m = 1, 2, 4,
    ...``.  Row ``j`` is a product of ``popcount(j) <= log2(n)`` directly evaluated
    phasors, so its rounding is a few ulp (against ``|j angle| eps`` of the phase when
    ``exp(i j angle)`` is evaluated at the rounded ``j angle``); ``2 K log2(n)`` sines
    and cosines instead of ``2 K n``.

    Parameters
    ----------
    angle_rad : ndarray (K,)
        The angle step of each column [rad].
    n : int
        Rows [1], >= 1.

    Returns
    -------
    ndarray of complex (n, K)
    """
    ang = np.asarray(angle_rad, dtype=float)
    out = np.empty((n, ang.size), dtype=complex)
    out[0] = 1.0
    m = 1
    while m < n:
        take = min(m, n - m)
        np.multiply(out[:take], np.exp(1j * (m * ang)), out=out[m:m + take])
        m += take
    return out


TRACK_HERMITE_ORDER = 6
"""Conditions at each grid node (the value and 5 derivatives) of the Hermite interpolation
of :meth:`RandomProfile.on_paths` (degree 11)."""

def _on_path_tolerance_m(x: np.ndarray) -> float:
    """How far [m] positions may be from ``start_m + k step_m`` for
    :meth:`RandomProfile.on_paths` to take them as on those paths: 1e-12 m plus 16 units
    of rounding of the largest position (a run's ``x0 + v t`` is a few units off them,
    1e-13 m at 400 m, 1.5e-11 m at 33 km); the elevation is corrected by
    ``slope x offset``, the slope's error ``r'' offset`` stays below the phases' own
    rounding ``|Omega x| eps``."""
    return 1e-12 + 16.0 * float(np.finfo(float).eps) * float(np.max(np.abs(x), initial=0.0))

TRACK_TOLERANCE = 1e-13
"""Bound of the interpolation error of :meth:`RandomProfile.on_paths`, relative to the
profile's RMS elevation (slope): far below the phase rounding of the sums themselves
(``|Omega x| eps`` ~ 5e-13 rad at 400 m)."""


@functools.lru_cache(maxsize=4)
def _hermite_basis(m: int) -> np.ndarray:
    """Coefficients (in powers of ``t``, one column per condition) of the two-point Hermite
    basis of degree ``2 m - 1`` on ``[0, 1]``: conditions ``p(t)^(p)`` at 0, then at 1."""
    n = 2 * m
    a = np.zeros((n, n))
    for p in range(m):
        a[p, p] = math.factorial(p)
        for j in range(p, n):
            a[m + p, j] = math.factorial(j) / math.factorial(j - p)
    basis = np.linalg.solve(a, np.eye(n))
    basis.setflags(write=False)
    return basis


def _hermite_weights(t: np.ndarray, m: int) -> np.ndarray:
    """Weights (len(t), 2 m) of the conditions ``h^p r^(p)`` at the left, then the right
    node, for the points at ``t`` in [0, 1] between them."""
    return (t[:, None] ** np.arange(2 * m)[None, :]) @ _hermite_basis(m)


@dataclass(frozen=True, eq=False)
class TabulatedProfile(Profile):
    """A profile sampled at increasing positions, cubic-Hermite interpolated (elevation
    and slope given at the samples); positions outside the table raise.

    Parameters
    ----------
    position_m : array_like (n,)
        Sample positions [m], finite, strictly increasing, n >= 2.
    values_m : array_like (n,)
        Irregularity ``r`` at the samples [m].
    slopes : array_like (n,)
        ``dr/dx`` at the samples [m/m].

    Raises
    ------
    ParameterError
        Arrays not 1-D and equally long (>= 2), non-finite values, or positions not
        strictly increasing.
    """

    position_m: np.ndarray
    values_m: np.ndarray
    slopes: np.ndarray
    _interp: Any = field(init=False, repr=False)

    def __post_init__(self) -> None:
        x, v, s = (np.asarray(a, dtype=float) for a in (self.position_m, self.values_m,
                                                        self.slopes))
        if x.ndim != 1 or x.size < 2 or v.shape != x.shape or s.shape != x.shape:
            raise ParameterError("position_m, values_m and slopes must be 1-D, equally long (>= 2)")
        if not (np.isfinite(x).all() and np.isfinite(v).all() and np.isfinite(s).all()):
            raise ParameterError("tabulated profile values must be finite")
        if (np.diff(x) <= 0).any():
            raise ParameterError("position_m must be strictly increasing")
        import scipy.interpolate

        object.__setattr__(self, "_interp", scipy.interpolate.CubicHermiteSpline(x, v, s))

    def _check(self, position_m: Any) -> np.ndarray:
        x = _x(position_m)
        lo, hi = float(self.position_m[0]), float(self.position_m[-1])
        if x.size and (x.min() < lo or x.max() > hi):
            raise OutOfRangeError(f"positions {float(x.min()):.6g} ... {float(x.max()):.6g} m leave "
                                  f"the tabulated range {lo:.6g} ... {hi:.6g} m")
        return x

    def elevation_m(self, position_m: Any) -> np.ndarray:
        """Irregularity ``r(x)`` [m] at positions [m], positive downward.

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``r(x)`` [m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        OutOfRangeError
            A position outside the tabulated range.
        """
        return np.asarray(self._interp(self._check(position_m)), dtype=float)

    def slope(self, position_m: Any) -> np.ndarray:
        """``dr/dx`` [m/m] at positions [m].

        Parameters
        ----------
        position_m : float or array_like
            Positions along the guideway [m], finite.

        Returns
        -------
        ndarray
            ``dr/dx`` [m/m], same shape as ``position_m``.

        Raises
        ------
        InputError
            Positions that are not finite real numbers.
        OutOfRangeError
            A position outside the tabulated range.
        """
        return np.asarray(self._interp(self._check(position_m), 1), dtype=float)
