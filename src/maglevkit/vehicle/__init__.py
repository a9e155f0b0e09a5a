"""Mechanical models the magnets are coupled to, and what a vehicle run is judged by.

* :mod:`maglevkit.plant` (re-exported here): a rigid heave mass under one magnet and gravity
  (gap-control studies; below :mod:`maglevkit.control`, which uses it).
* :mod:`~maglevkit.vehicle.guideway`: simply supported Euler-Bernoulli spans in modal form,
  chained into a periodically pillared guideway with a moving system boundary.
* :mod:`~maglevkit.vehicle.irregularities`: deterministic and random guideway irregularities.
* :mod:`~maglevkit.vehicle.comfort`: ride comfort (ISO 2631-1 ``Wk`` and Sperling ``Wz``).
* :mod:`~maglevkit.vehicle.data`: the guideway parameter file.
* :mod:`~maglevkit.vehicle.train`: the vehicle (train) parameter file and its layout.
* :mod:`~maglevkit.vehicle.mechanics`: the train's heave-pitch multibody model.
* :mod:`~maglevkit.vehicle.multibody`: planar rigid bodies, spring-dampers and force
  points turned into linear equations of motion (NumPy, CasADi; checked by sympy).
* :mod:`~maglevkit.vehicle.crosssection`: the cross-section vehicle's mechanics (car
  body, levitation chassis, air springs, magnet force points; curves) and its file.
* :mod:`~maglevkit.vehicle.simulation`: vehicle runs (magnet bank, gap controllers,
  guideway, irregularities, failures).
* :mod:`~maglevkit.vehicle.crossrun`: cross-section runs (levitation and guidance magnets
  through the bank, gap controllers, curves, crosswind, irregularities, failures).
"""

from __future__ import annotations

from ..plant import STANDARD_GRAVITY, HeaveMass, HeaveState
from .comfort import (
    iso2631_weighted_rms,
    iso2631_wk,
    sperling_index,
    sperling_weighting,
)
from .crossrun import CrossSectionModel, CrossSectionRun, Crosswind, TransitionCurve
from .crosssection import (
    CrossSectionData,
    CrossSectionMechanics,
    load_cross_section,
    track_field_m_per_s2,
)
from .data import GuidewayData, load_guideway
from .guideway import BeamSpan, Guideway, GuidewayDeflection, GuidewayState
from .irregularities import (
    GermanTrackPSD,
    HarmonicProfile,
    JointSteps,
    PowerLawPSD,
    Profile,
    RandomProfile,
    SpanSag,
    TabulatedProfile,
)
from .mechanics import VehicleMechanics
from .multibody import ForcePoint, PlanarMultibody, RigidBody, SpringDamper
from .simulation import Failure, VehicleModel, VehicleRun, run_vehicle
from .train import TrainData, load_vehicle

__all__ = [
    "HeaveMass",
    "HeaveState",
    "STANDARD_GRAVITY",
    "BeamSpan",
    "Guideway",
    "GuidewayDeflection",
    "GuidewayState",
    "GuidewayData",
    "load_guideway",
    "Profile",
    "SpanSag",
    "JointSteps",
    "HarmonicProfile",
    "RandomProfile",
    "TabulatedProfile",
    "GermanTrackPSD",
    "PowerLawPSD",
    "iso2631_wk",
    "iso2631_weighted_rms",
    "sperling_weighting",
    "sperling_index",
    "TrainData",
    "load_vehicle",
    "VehicleMechanics",
    "PlanarMultibody",
    "RigidBody",
    "SpringDamper",
    "ForcePoint",
    "CrossSectionData",
    "CrossSectionMechanics",
    "load_cross_section",
    "track_field_m_per_s2",
    "CrossSectionModel",
    "CrossSectionRun",
    "Crosswind",
    "TransitionCurve",
    "VehicleModel",
    "VehicleRun",
    "Failure",
    "run_vehicle",
]
