"""Gap control: controllers behind one sampled-data interface and closed-loop co-simulation.

* :mod:`~maglevkit.control.interface`: :class:`Controller` (``reset``/``update``/
  ``diagnostics``) and :class:`Measurement`;
* :mod:`~maglevkit.control.cascade`: the flux-based cascade controller
  (:func:`design_gap_controller`, :class:`GapController`, :class:`CascadeController`);
* :mod:`~maglevkit.control.mpc`: offset-free nonlinear MPC on the reduced magnet model;
* :mod:`~maglevkit.control.observers`: the disturbance model and its extended Kalman filter;
* :mod:`~maglevkit.control.loop`: :func:`closed_loop` with a heave mass.
"""

from .cascade import CascadeController, GapController, damping_input, design_gap_controller
from .interface import Controller, Measurement
from .loop import ClosedLoopResult, closed_loop

__all__ = [
    "CascadeController",
    "ClosedLoopResult",
    "Controller",
    "GapController",
    "Measurement",
    "closed_loop",
    "damping_input",
    "design_gap_controller",
]
