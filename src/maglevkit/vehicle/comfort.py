"""Ride comfort of vertical acceleration: ISO 2631-1 ``Wk`` weighted RMS and Sperling ``Wz``.

ISO 2631-1:1997, Annex A (parameters as in ISO 8041): the weighting ``Wk`` (vertical,
seated/standing/recumbent) is the product of four analogue filters, ``s = j 2 pi f``::

    band-limiting high pass   H_h = s^2 / (s^2 + w1 s / Q1 + w1^2)
    band-limiting low pass    H_l = w2^2 / (s^2 + w2 s / Q2 + w2^2)
    a-v transition            H_t = (1 + s / w3) / (1 + s / (Q4 w4) + s^2 / w4^2)
    upward step               H_s = (w5/w6)^2 (1 + s / (Q5 w5) + s^2 / w5^2)
                                              / (1 + s / (Q6 w6) + s^2 / w6^2)

with ``w_i = 2 pi f_i``: f1 = 0.4 Hz, f2 = 100 Hz, Q1 = Q2 = 1/sqrt(2), f3 = f4 = 12.5 Hz,
Q4 = 0.63, f5 = 2.37 Hz, Q5 = 0.91, f6 = 3.35 Hz, Q6 = 0.91 (gain K = 1).

Sperling's ride comfort index for vertical vibration (Sperling and Betzhold 1956; in the
filter form of e.g. Garg and Dukkipati, Dynamics of Railway Vehicle Systems, 1984, and
Forstberg, Ride comfort and motion sickness in tilting trains, KTH/VTI 2000)::

    B(f) = 0.588 sqrt((1.911 f^2 + (0.25 f^2)^2)
                      / ((1 - 0.277 f^2)^2 + (1.563 f - 0.0368 f^3)^2))      (f in Hz)
    Wz   = (sum_i (a_i B(f_i))^3)^(1/10)     for sinusoids of amplitude a_i [cm/s^2]
         = (100 sqrt(2) a_B)^0.3             with a_B the B-weighted RMS [m/s^2]

``B`` is the magnitude of the rational filter
``0.588 p (1.3824 + 0.25 p) / (1 + 1.563 p + 0.277 p^2 + 0.0368 p^3)``, ``p = j f``.
We evaluate a whole record with the RMS form (the "second power, 6.67th root" form, which
for one sine equals Sperling's amplitude form exactly and does not depend on the spectral
resolution).  Sperling's original amplitude formula with his frequency factor ``F(f)`` is
:func:`sperling_sine_index`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import InputError
from ..validation import real_array, real_number, renamed_keywords

__all__ = [
    "WD_PARAMETERS",
    "WK_PARAMETERS",
    "iso2631_wd",
    "iso2631_wk",
    "lateral_comfort_indices",
    "iso2631_wk_sections",
    "iso2631_weighted_rms",
    "comfort_indices",
    "sperling_weighting",
    "sperling_index",
    "sperling_sine_index",
]

WK_PARAMETERS = {"f1": 0.4, "Q1": 1 / math.sqrt(2), "f2": 100.0, "Q2": 1 / math.sqrt(2),
                 "f3": 12.5, "f4": 12.5, "Q4": 0.63, "f5": 2.37, "Q5": 0.91, "f6": 3.35,
                 "Q6": 0.91, "K": 1.0}
"""ISO 2631-1:1997 Table A.1 / ISO 8041 parameters of the ``Wk`` weighting [Hz, -]."""

WD_PARAMETERS = {"f1": 0.4, "Q1": 1 / math.sqrt(2), "f2": 100.0, "Q2": 1 / math.sqrt(2),
                 "f3": 2.0, "f4": 2.0, "Q4": 0.63, "K": 1.0}
"""ISO 2631-1:1997 Table A.1 / ISO 8041 parameters of the ``Wd`` weighting (horizontal
acceleration, seated, standing, recumbent): the band limits of ``Wk``, an a-v transition
at 2 Hz and no upward step [Hz, -]."""

SPERLING_LATERAL_FACTOR = 0.737 / 0.588
"""Sperling's horizontal weighting is the vertical one with 0.737 in place of 0.588
(Sperling's frequency factor ``F_y = 1.25 F_z``; Garg and Dukkipati 1984)."""

SPERLING_SCALE = (100.0 * math.sqrt(2.0)) ** 0.3
"""``Wz = SPERLING_SCALE a_B^0.3`` with the B-weighted RMS ``a_B`` in m/s^2 (about 4.42)."""


def _sections(p: dict[str, float]) -> list[tuple[np.ndarray, np.ndarray]]:
    """The analogue sections of an ISO 2631-1 weighting with parameters ``p`` (``Wk``,
    ``Wd``) as ``(b, a)`` polynomials in ``s`` [rad/s] (descending powers): high pass, low
    pass, a-v transition and, where ``p`` has ``f5`` and ``f6``, the upward step."""
    w1, w2, w3, w4 = (2 * math.pi * p[k] for k in ("f1", "f2", "f3", "f4"))
    sections = [
        (np.array([1.0, 0.0, 0.0]), np.array([1.0, w1 / p["Q1"], w1 * w1])),
        (np.array([w2 * w2]), np.array([1.0, w2 / p["Q2"], w2 * w2])),
        (np.array([1.0 / w3, 1.0]), np.array([1.0 / w4 ** 2, 1.0 / (p["Q4"] * w4), 1.0])),
    ]
    if "f5" in p:
        w5, w6 = 2 * math.pi * p["f5"], 2 * math.pi * p["f6"]
        sections.append((np.array([1.0 / w5 ** 2, 1.0 / (p["Q5"] * w5), 1.0]) * (w5 / w6) ** 2,
                         np.array([1.0 / w6 ** 2, 1.0 / (p["Q6"] * w6), 1.0])))
    return sections


def iso2631_wk_sections() -> list[tuple[np.ndarray, np.ndarray]]:
    """The four analogue sections of ``Wk`` as ``(b, a)`` polynomials in ``s`` [rad/s]
    (descending powers): high pass, low pass, a-v transition, upward step."""
    return _sections(WK_PARAMETERS)


def _response(p: dict[str, float], frequency_Hz: Any) -> np.ndarray:
    """``K`` times the product of the sections of ``p`` at ``s = j 2 pi f``."""
    s = 2j * math.pi * _freqs(frequency_Hz)
    h = np.ones_like(s)
    for b, a in _sections(p):
        h = h * np.polyval(b, s) / np.polyval(a, s)
    return p["K"] * h


def _freqs(frequency_Hz: Any) -> np.ndarray:
    f = real_array(frequency_Hz, "frequencies", "Hz")
    if (f < 0).any():
        raise InputError("frequencies must be finite and >= 0 Hz")
    return f


def iso2631_wk(frequency_Hz: Any) -> np.ndarray:
    """Complex frequency response of ``Wk`` at frequencies [Hz] (``|Wk|`` is the weighting
    factor of ISO 2631-1 Table 3).

    Parameters
    ----------
    frequency_Hz : float or array_like
        Frequencies f [Hz], finite and >= 0.

    Returns
    -------
    ndarray of complex
        ``Wk(j 2 pi f)`` [-], same shape as ``frequency_Hz`` (0 at f = 0).

    Raises
    ------
    InputError
        Frequencies that are not finite real numbers >= 0.
    """
    return _response(WK_PARAMETERS, frequency_Hz)


def iso2631_wd(frequency_Hz: Any) -> np.ndarray:
    """Complex frequency response of ``Wd`` (ISO 2631-1, horizontal) at frequencies [Hz]::

        Wd = H_h H_l H_t,   H_t = (1 + s/w3) / (1 + s/(Q4 w4) + s^2/w4^2),  f3 = f4 = 2 Hz

    with the band-limiting ``H_h``, ``H_l`` of ``Wk`` (:data:`WD_PARAMETERS`).

    Parameters
    ----------
    frequency_Hz : float or array_like
        Frequencies f [Hz], finite and >= 0.

    Returns
    -------
    ndarray of complex
        ``Wd(j 2 pi f)`` [-], same shape as ``frequency_Hz`` (0 at f = 0).

    Raises
    ------
    InputError
        Frequencies that are not finite real numbers >= 0.
    """
    return _response(WD_PARAMETERS, frequency_Hz)


@renamed_keywords(acceleration="acceleration_m_per_s2")
def lateral_comfort_indices(acceleration_m_per_s2: Any, sample_rate_Hz: float
                            ) -> tuple[np.ndarray, np.ndarray]:
    """ISO 2631-1 ``Wd``-weighted RMS [m/s^2] and Sperling's lateral ``Wz`` [-] of every
    column of a lateral acceleration record, one FFT per record (as
    :func:`comfort_indices` with the horizontal weightings: ``Wd`` and ``B_y =
    SPERLING_LATERAL_FACTOR B``).

    Old keyword names (``acceleration``) are deprecated aliases for one release.

    Parameters
    ----------
    acceleration_m_per_s2 : array_like (n, m)
        Lateral accelerations [m/s^2], n >= 8 samples of m records, finite.
    sample_rate_Hz : float
        Sampling rate [Hz], > 0.

    Returns
    -------
    (a_wd, wz) : ndarray (m,), ndarray (m,)
        Weighted RMS [m/s^2] and Sperling index [-] per record.

    Raises
    ------
    InputError
        A record that is not finite (n, m) with n >= 8, or a bad sampling rate.
    """
    return _indices(acceleration_m_per_s2, sample_rate_Hz, iso2631_wd, SPERLING_LATERAL_FACTOR)


def sperling_weighting(frequency_Hz: Any) -> np.ndarray:
    """Sperling's vertical comfort weighting ``B(f)`` [-] at frequencies [Hz].

    Parameters
    ----------
    frequency_Hz : float or array_like
        Frequencies f [Hz], finite and >= 0.

    Returns
    -------
    ndarray
        ``B(f)`` [-], same shape as ``frequency_Hz`` (0 at f = 0).

    Raises
    ------
    InputError
        Frequencies that are not finite real numbers >= 0.
    """
    f = _freqs(frequency_Hz)
    return 0.588 * np.sqrt((1.911 * f ** 2 + (0.25 * f ** 2) ** 2)
                           / ((1 - 0.277 * f ** 2) ** 2 + (1.563 * f - 0.0368 * f ** 3) ** 2))


def _signal(acceleration: Any, sample_rate_Hz: float) -> tuple[np.ndarray, float]:
    a = real_array(acceleration, "acceleration", "m/s^2")
    if a.ndim != 1 or a.size < 8:
        raise InputError("acceleration must be a finite 1-D record of at least 8 samples [m/s^2]")
    return a, real_number(sample_rate_Hz, "sample_rate_Hz", "Hz", positive=True)


def _weighted_rms(spectrum: np.ndarray, n: int, magnitude: np.ndarray) -> np.ndarray:
    """RMS of the records ``irfft(spectrum * magnitude, n)`` (columns of ``spectrum``, the
    ``rfft`` of ``n`` samples along axis 0), by Parseval:
    ``mean(y^2) = sum_k c_k |Y_k|^2 / n^2`` with ``c_k = 2`` except ``c_0 = 1`` and, for
    even ``n``, ``c_(n/2) = 1`` (no inverse transform; the same sum to rounding)."""
    c = np.full(spectrum.shape[0], 2.0)
    c[0] = 1.0
    if n % 2 == 0:
        c[-1] = 1.0
    mag = np.asarray(magnitude, dtype=float).reshape((-1,) + (1,) * (spectrum.ndim - 1))
    power = np.abs(spectrum * mag) ** 2
    return np.sqrt(np.tensordot(c, power, axes=(0, 0)) / float(n) ** 2)


@renamed_keywords(acceleration="acceleration_m_per_s2")
def comfort_indices(acceleration_m_per_s2: Any, sample_rate_Hz: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """ISO 2631-1 ``a_w`` [m/s^2] (frequency domain) and Sperling's ``Wz`` [-] of every
    column of ``acceleration_m_per_s2`` (n samples, m records) [m/s^2], one FFT per record:
    :func:`iso2631_weighted_rms` and :func:`sperling_index` of each column (the old keyword
    ``acceleration`` is a deprecated alias for one release)."""
    return _indices(acceleration_m_per_s2, sample_rate_Hz, iso2631_wk, 1.0)


def _indices(acceleration: Any, sample_rate_Hz: float, iso_weighting: Any,
             sperling_factor: float) -> tuple[np.ndarray, np.ndarray]:
    """ISO-weighted RMS [m/s^2] (``|iso_weighting(f)|``) and Sperling ``Wz`` [-] (weighting
    ``sperling_factor B(f)``) of every column of ``acceleration``, one FFT per record."""
    a = real_array(acceleration, "acceleration", "m/s^2")
    if a.ndim != 2 or a.shape[0] < 8:
        raise InputError("acceleration must be finite (n samples, m records), n >= 8 [m/s^2]")
    fs = real_number(sample_rate_Hz, "sample_rate_Hz", "Hz", positive=True)
    spec = np.fft.rfft(a, axis=0)
    f = np.fft.rfftfreq(a.shape[0], 1.0 / fs)
    aw = _weighted_rms(spec, a.shape[0], np.abs(iso_weighting(f)))
    b = sperling_factor * sperling_weighting(f)
    return aw, SPERLING_SCALE * _weighted_rms(spec, a.shape[0], b) ** 0.3


@renamed_keywords(acceleration="acceleration_m_per_s2")
def iso2631_weighted_rms(acceleration_m_per_s2: Any, sample_rate_Hz: float, *,
                         method: str = "fft") -> float:
    """ISO 2631-1 frequency-weighted RMS ``a_w`` [m/s^2] of a vertical acceleration record.

    Old keyword names (``acceleration``) are deprecated aliases for one release.

    Parameters
    ----------
    acceleration_m_per_s2 : array_like (n,)
        Vertical acceleration [m/s^2], equally sampled.
    sample_rate_Hz : float
        Sampling rate [Hz], > 0.
    method : {"fft", "filter"}, default "fft"
        "fft": the record's spectrum times ``|Wk(f)|`` (zero phase; the record is treated
        as periodic); "filter": the four sections, bilinear-transformed, run causally
        over the record (as a measuring instrument would; start-up transient included).
    """
    a, fs = _signal(acceleration_m_per_s2, sample_rate_Hz)
    if method == "fft":
        return float(comfort_indices(a[:, None], fs)[0][0])
    if method == "filter":
        import scipy.signal  # lazily: 0.6 s to import, only this method needs it

        y = a
        for b, den in iso2631_wk_sections():
            bz, az = scipy.signal.bilinear(b, den, fs)
            y = scipy.signal.lfilter(bz, az, y)
        y = WK_PARAMETERS["K"] * y
    else:
        raise InputError(f"method = {method!r}; allowed: 'fft', 'filter'")
    return float(np.sqrt(np.mean(y ** 2)))


@renamed_keywords(acceleration="acceleration_m_per_s2")
def sperling_index(acceleration_m_per_s2: Any, sample_rate_Hz: float) -> float:
    """Sperling's ride comfort index ``Wz`` [-] of a vertical acceleration record [m/s^2]:
    ``Wz = (100 sqrt(2) a_B)^0.3`` with the B-weighted RMS ``a_B`` (frequency domain).

    Rough scale (Sperling): 1 just noticeable, 2 clearly noticeable, 2.5 more
    pronounced but not unpleasant, 3 strong, irregular but tolerable, 3.25 very irregular,
    3.5 extremely irregular, unpleasant, 4 extremely unpleasant.

    Old keyword names (``acceleration``) are deprecated aliases for one release.

    Parameters
    ----------
    acceleration_m_per_s2 : array_like (n,)
        Vertical acceleration [m/s^2], equally sampled, finite, at least 8 samples.  The
        record is weighted in the frequency domain (treated as periodic).
    sample_rate_Hz : float
        Sampling rate [Hz], > 0.

    Returns
    -------
    float
        ``Wz`` [-].

    Raises
    ------
    InputError
        A record that is not a finite 1-D array of >= 8 samples, or a sampling rate that
        is not finite and > 0.
    """
    a, fs = _signal(acceleration_m_per_s2, sample_rate_Hz)
    return float(comfort_indices(a[:, None], fs)[1][0])


def sperling_sine_index(amplitude_m_per_s2: Any, frequency_Hz: Any) -> np.ndarray:
    """Sperling's original formula for one sinusoid, ``Wz = 0.896 (a^3 F(f) / f)^(1/10)``.

    ``a`` is the acceleration amplitude in cm/s^2 (converted from the m/s^2 given here);
    the vertical frequency factor is ``F = 0.325 f^2`` (0.5-5.9 Hz), ``400 / f^2``
    (5.9-20 Hz), ``1`` (above 20 Hz).  Defined for 0.5 Hz <= f.

    Parameters
    ----------
    amplitude_m_per_s2 : float or array_like
        Acceleration amplitude [m/s^2] (its magnitude is used).
    frequency_Hz : float or array_like
        Frequency [Hz], >= 0.5; broadcast against the amplitude.

    Returns
    -------
    ndarray
        ``Wz`` [-].

    Raises
    ------
    InputError
        Non-finite values, or a frequency below 0.5 Hz.
    """
    a = real_array(amplitude_m_per_s2, "amplitude_m_per_s2", "m/s^2") * 100.0
    f = _freqs(frequency_Hz)
    if (f < 0.5).any():
        raise InputError("Sperling's frequency factor is defined from 0.5 Hz up")
    ff = np.where(f < 5.9, 0.325 * f ** 2, np.where(f < 20.0, 400.0 / f ** 2, 1.0))
    return 0.896 * (np.abs(a) ** 3 * ff / f) ** 0.1
