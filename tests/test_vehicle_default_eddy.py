"""Which reduced model the vehicles' magnets fly when nobody says (issue 26, switch26v;
docs/vehicle.md, "Which reduced model the magnets fly"): each magnet kind its magnet
file's ``[reduced] eddy_modes`` (``Magnet.default_eddy_modes``), an option or the
vehicle file's ``[magnets] eddy_modes`` winning; kinds that differ make a mixed bank,
whose compiled step must equal the NumPy loop and whose eq. 8 circuits carry no eddy
current; ``eddy_resistance_scale`` scales the network's resistances."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from maglevkit.magnets import load_magnet
from maglevkit.vehicle.irregularities import HarmonicProfile
from maglevkit.vehicle.simulation import Failure, VehicleModel
from maglevkit.vehicle.train import load_vehicle

from .test_vehicle_compiled import loops_agree

# compiled step and NumPy loop: the same arithmetic in another order (the bound of
# tests/test_vehicle_eddy_modes.py, measured there 5.4e-14)
RTOL = 1e-10


def test_heave_pitch_takes_each_magnet_files_default() -> None:
    """Unset everywhere: every kind flies its magnet file's default (the bundled TR09
    files: the 2-branch network); the option, the vehicle file's key and motion_eddy (the
    ladder, chosen explicitly) win over it; a per-kind mapping sets one kind."""
    train = load_vehicle()
    assert train.eddy_modes is None
    m = VehicleModel(train, rigid=True)
    own = {"standard": load_magnet(train.standard_magnet).default_eddy_modes,
           "bow": load_magnet(train.bow_magnet).default_eddy_modes}
    assert m.eddy_modes_of == own == {"standard": 2, "bow": 2}
    assert m.bank.eddy_modes == 2 and m.bank.n_eddy_states == 2 and not m.bank.motion_eddy
    assert VehicleModel(train, rigid=True, eddy_modes=0).bank.n_eddy_states == 0
    filed = VehicleModel(dataclasses.replace(train, eddy_modes=1), rigid=True)
    assert filed.eddy_modes_of == {"standard": 1, "bow": 1} and filed.bank.eddy_modes == 1
    # the option beats the file
    assert VehicleModel(dataclasses.replace(train, eddy_modes=1), rigid=True,
                        eddy_modes=0).bank.n_eddy_states == 0
    ladder = VehicleModel(train, rigid=True, motion_eddy=True)
    assert ladder.eddy_modes_of == {"standard": 0, "bow": 0} and ladder.bank.motion_eddy
    mixed = VehicleModel(train, rigid=True, eddy_modes={"bow": 0})
    assert mixed.eddy_modes_of == {"standard": 2, "bow": 0}


def test_heave_pitch_mixed_bank_compiled_equals_python() -> None:
    """Standard magnets on the network, bow magnets on eq. 8 (``eddy_modes={"bow": 0}``):
    the compiled step equals the NumPy loop (a 20 Hz wave, a failure); the bow circuits'
    eddy currents are exactly 0 throughout, the standard circuits' move; the record says
    which kind flies what."""
    m = VehicleModel(load_vehicle(), rigid=True, eddy_modes={"bow": 0})
    v = 400 / 3.6
    rc, _ = loops_agree(m, RTOL, speed_m_per_s=v, duration_s=0.2,
                        irregularity=HarmonicProfile(0.3e-3, v / 20.0),
                        failures=[Failure("s2m4/front", 0.1)])
    ds = rc.dataset
    bow = ds.magnet_of_circuit.isin(["s1m1", "s3m8"]).values
    assert bow.sum() == 6                        # two bow magnets of three circuits
    ie = ds.eddy_current.values                  # (time, circuit, eddy_state)
    assert np.all(ie[:, bow] == 0.0)
    assert float(np.abs(ie[:, ~bow]).max()) > 0.05     # measured ~1 A
    assert "eddy_modes = standard 2, bow 0" in ds.attrs["magnets"]
    assert "absent branches 0" in ds.eddy_current.attrs["long_name"]


def test_cross_section_takes_each_magnet_files_default() -> None:
    """The cross-section's levitation magnets take the TR09 file's network, the guidance
    magnets their own file's default; with kinds that differ the bank is mixed and its
    compiled block step equals the NumPy loop under a gust and a rail wave, the eq. 8
    kind's eddy currents exactly 0."""
    from maglevkit.vehicle.crossrun import CrossSectionModel, Crosswind

    model = CrossSectionModel()
    gui = load_magnet("tr-guidance").default_eddy_modes
    assert model.eddy_modes_of == {"levitation": 2, "guidance": gui}
    assert CrossSectionModel(eddy_modes=0).bank.n_eddy_states == 0
    assert CrossSectionModel(eddy_modes={"guidance": 1}).eddy_modes_of == {
        "levitation": 2, "guidance": 1}
    kw: dict[str, Any] = dict(speed_m_per_s=400 / 3.6, duration_s=0.3,
                              crosswind=Crosswind(5e3, rise_s=0.1, hold_s=0.1, start_s=0.05),
                              lateral=HarmonicProfile(0.2e-3, 100.0))
    ds = loops_agree(model, RTOL, **kw)[0].dataset
    lev, guid = ds.levitation_eddy_current.values, ds.guidance_eddy_current.values
    assert float(np.abs(lev).max()) > 0.05
    if gui == 0:
        assert np.all(guid == 0.0)
    else:
        assert float(np.abs(guid).max()) > 0.05


def test_eddy_resistance_scale_scales_the_network() -> None:
    """``eddy_resistance_scale`` multiplies every eddy resistance of the maps, the
    network's ``R_0`` and ``R_k`` included (an eddy path's resistance is proportional to
    the iron's resistivity), and leaves its inductances."""
    from maglevkit.reduced.current import eddy_network_parameters

    train = load_vehicle()
    base = VehicleModel(train, rigid=True)
    hot = VehicleModel(train, rigid=True, eddy_resistance_scale=1.5)
    assert hot.bank.eddy_modes == 2
    np.testing.assert_allclose(hot.bank.eddy_resistance_ohm,
                               1.5 * np.asarray(base.bank.eddy_resistance_ohm), rtol=1e-15)
    r = base.maps["standard"].dataset["resistance_ohm"].values
    a, _ = eddy_network_parameters(base.maps["standard"], 2, r)
    b, _ = eddy_network_parameters(hot.maps["standard"], 2, r)
    np.testing.assert_allclose(b["r_k"], 1.5 * a["r_k"], rtol=1e-15)
    np.testing.assert_array_equal(b["l_k"], a["l_k"])
    np.testing.assert_array_equal(b["l_ref"], a["l_ref"])
