"""Issue 24 (first slice): the planar multibody description and the cross-section vehicle's
mechanics, each checked against an independent reference: a hand derivation, a
sympy.physics.mechanics derivation, energy conservation, closed-form eigenfrequencies of
the equivalent two-mass oscillators, and the closed-form force balance in a curve."""

from __future__ import annotations

import copy
import math
import re
import sys
import warnings
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.integrate

import maglevkit as mk
from maglevkit.vehicle.crosssection import (
    CrossSectionMechanics,
    bundled_cross_sections,
    load_cross_section,
    parse_cross_section,
    track_field_m_per_s2,
)
from maglevkit.vehicle.multibody import (
    ForcePoint,
    PlanarMultibody,
    RigidBody,
    SpringDamper,
    derive_sympy,
)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

G0 = 9.80665
ROOT = Path(__file__).resolve().parent.parent


def _params() -> dict[str, Any]:
    text = (resources.files("maglevkit") / "data" / "vehicle" / "tr09-cross-section.toml"
            ).read_text()
    return tomllib.loads(text)


def _two_mass_Hz(m1: float, m2: float, k1: float, k2: float) -> np.ndarray:
    """Closed form of m1 x1'' + k1 (x1 - x2) = 0, m2 x2'' + k1 (x2 - x1) + k2 x2 = 0."""
    s = k1 / m1 + (k1 + k2) / m2
    root = math.sqrt(s * s - 4.0 * k1 * k2 / (m1 * m2))
    return np.sqrt([(s - root) / 2.0, (s + root) / 2.0]) / (2.0 * math.pi)


# ------------------------------------------------------------------ the generic multibody
def test_one_body_against_a_hand_derivation_and_sympy() -> None:
    """One body on two vertical springs at +-b and one lateral spring at height offset h,
    a vertical (upward) force at lateral offset p: matrices written by hand."""
    m, j, zc, b, h, p = 800.0, 300.0, -0.4, 0.9, 0.35, 0.6
    ky, kz, cy, cz = 4.0e4, 9.0e4, 700.0, 1300.0
    body = RigidBody("b", m, j, (0.0, zc))
    elements = [SpringDamper("l", "b", (-b, zc), None, (-b, zc), "z", kz, cz),
                SpringDamper("r", "b", (b, zc), None, (b, zc), "z", kz, cz),
                SpringDamper("lat", "b", (0.2, zc + h), None, (0.2, zc + h), "y", ky, cy)]
    points = [ForcePoint("up", "b", (p, zc + 0.1), "-z")]
    sysm = PlanarMultibody([body], elements, points)
    # by hand, q = (y, z, phi), small angles: a point (dy, dz) moves by (y - dz phi,
    # z + dy phi); the lateral spring's deflection y - h phi, the vertical ones z -+ b phi;
    # an upward force at dy = p: generalised force (0, -F, -p F)
    hand = {
        "M": np.diag([m, m, j]),
        "K": np.array([[ky, 0.0, -ky * h], [0.0, 2 * kz, 0.0],
                       [-ky * h, 0.0, ky * h * h + 2 * kz * b * b]]),
        "C": np.array([[cy, 0.0, -cy * h], [0.0, 2 * cz, 0.0],
                       [-cy * h, 0.0, cy * h * h + 2 * cz * b * b]]),
        "B": np.array([[0.0], [-1.0], [-p]]),
        "G": np.array([[m, 0.0], [0.0, m], [0.0, 0.0]]),
    }
    ref = derive_sympy(sysm)
    for key, want in hand.items():
        # sums of products of numbers up to 1e5: rounding, 1e-12 of the largest entry
        tol = 1e-12 * np.abs(want).max()
        np.testing.assert_allclose(ref[key], want, rtol=0, atol=tol, err_msg=f"sympy {key}")
        np.testing.assert_allclose(getattr(sysm, key), want, rtol=0, atol=tol, err_msg=key)
    # planar rigid bodies: the exact mass matrix about the centre of mass is constant
    np.testing.assert_allclose(ref["mass_matrix_q"], hand["M"], rtol=1e-14)


def test_preload_stiffness_against_a_hand_derivation_and_sympy() -> None:
    """A body on two preloaded vertical springs at (+-b, h below the centre) and an
    upward force F at hp below the centre: the exact rotation adds -2 f h - F hp to the
    roll stiffness (an inverted pendulum), on top of 2 k b^2."""
    m, j, zc, b, h, hp, k, f, force = 900.0, 350.0, -0.5, 0.8, 0.4, 0.25, 6e4, 3e3, 2.5e3
    sysm = PlanarMultibody(
        [RigidBody("b", m, j, (0.0, zc))],
        [SpringDamper("l", "b", (-b, zc + h), None, (-b, zc + h), "z", k, 0.0),
         SpringDamper("r", "b", (b, zc + h), None, (b, zc + h), "z", k, 0.0)],
        [ForcePoint("up", "b", (0.3, zc + hp), "-z")])
    k_pre = sysm.preload_stiffness([f, f], [force])
    hand = np.diag([0.0, 2 * k, 2 * k * b * b - 2 * f * h - force * hp])
    # 1e-12 of the largest entry: rounding
    np.testing.assert_allclose(sysm.K + k_pre, hand, rtol=0, atol=1e-12 * hand.max())
    ref = derive_sympy(sysm, element_forces_N=[f, f], forces_N=[force])
    np.testing.assert_allclose(ref["K"], hand, rtol=0, atol=1e-12 * hand.max())
    with pytest.raises(mk.InputError, match="one finite value per element"):
        sysm.preload_stiffness([f], [force])


def test_multibody_refuses_bad_descriptions() -> None:
    body = RigidBody("b", 1.0, 1.0, (0.0, 0.0))
    with pytest.raises(mk.InputError, match="unique names"):
        PlanarMultibody([body, body], [], [])
    with pytest.raises(mk.InputError, match=r"mass_kg \[kg\] = -1.0: must be > 0"):
        PlanarMultibody([RigidBody("b", -1.0, 1.0, (0.0, 0.0))], [], [])
    with pytest.raises(mk.InputError, match="dofs = .*expected distinct names from"):
        PlanarMultibody([RigidBody("b", 1.0, 1.0, (0.0, 0.0), ("x",))], [], [])
    with pytest.raises(mk.InputError, match="body 'c' is not one of"):
        PlanarMultibody([body], [SpringDamper("e", "c", (0, 0), None, (0, 0), "z", 1, 0)], [])
    with pytest.raises(mk.InputError, match="direction = 'x': expected 'y' or 'z'"):
        PlanarMultibody([body], [SpringDamper("e", "b", (0, 0), None, (0, 0), "x", 1, 0)], [])
    with pytest.raises(mk.InputError, match="direction = 'up': expected one of"):
        PlanarMultibody([body], [], [ForcePoint("p", "b", (0, 0), "up")])
    with pytest.raises(mk.InputError, match=r"point_m = 3: expected a \(y, z\) pair"):
        PlanarMultibody([body], [], [ForcePoint("p", "b", 3, "+y")])  # type: ignore[arg-type]


# ------------------------------------------------------------------ the cross-section
def test_cross_section_matrices_against_sympy() -> None:
    mech = CrossSectionMechanics(load_cross_section())
    s = mech.system
    assert s.dof_names == ("car_body.y", "car_body.z", "car_body.phi", "chassis.y",
                           "chassis.z", "chassis.phi")
    ref = derive_sympy(s)
    for key in ("M", "K", "C", "B", "G"):
        # rounding of sums of products of ~1e5 numbers: 1e-12 of the largest entry
        np.testing.assert_allclose(getattr(s, key), ref[key], rtol=0,
                                   atol=1e-12 * np.abs(ref[key]).max(), err_msg=key)
    np.testing.assert_allclose(ref["mass_matrix_q"], s.M, rtol=1e-14)
    np.testing.assert_array_equal(s.K, s.K.T)
    # about the trim in a curve: the air springs' and magnets' static forces add the
    # preload stiffness; sympy with the same element and point forces agrees
    a = track_field_m_per_s2(450 / 3.6, 4000.0, math.radians(12.0))
    q, forces = mech.static_trim(a, guidance_bias_N=2e4)
    fe = s.stiffness_N_per_m * s.element_deflections(q) + s.preload_N
    ref = derive_sympy(s, element_forces_N=fe, forces_N=forces)
    k_lin = mech.linearised_stiffness(a, guidance_bias_N=2e4)
    np.testing.assert_allclose(k_lin, ref["K"], rtol=0, atol=1e-12 * np.abs(ref["K"]).max())
    # the car body's pendulum term lowers its roll stiffness by about m a_z h (h = 0.95 m)
    i = s.dof_names.index("car_body.phi")
    d = load_cross_section()
    drop = s.K[i, i] - k_lin[i, i]
    assert drop == pytest.approx(d.loaded_car_body_mass_kg * a[1]
                                 * (d.spring_z_m - d.car_body_centre_z_m), rel=1e-12)


def test_casadi_functions_equal_numpy() -> None:
    s = CrossSectionMechanics(load_cross_section()).system
    fn = s.casadi_functions()
    rng = np.random.default_rng(5)
    q, qd = rng.normal(0, 1e-2, 6), rng.normal(0, 1e-1, 6)
    f, a, qe = rng.normal(0, 4e4, 4), np.array([0.3, G0]), rng.normal(0, 1e3, 6)
    want = s.accelerations(q, qd, f, a, qe)
    got = np.asarray(fn["rhs"](q, qd, f, a, qe)).ravel()
    # the same matrices in the same order of operations up to summation order: 1e-13 rel.
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13 * np.abs(want).max())
    np.testing.assert_allclose(np.asarray(fn["gaps"](q)).ravel(), s.gap_matrix @ q, rtol=1e-14)
    mats = fn["matrices"]()
    for key in ("M", "C", "K", "B", "G"):
        np.testing.assert_array_equal(np.asarray(mats[key]), getattr(s, key), err_msg=key)
    # gaps: the guidance magnets sit outboard of the rails, so a chassis moving right
    # closes the left guidance gap and opens the right one; moving down opens both
    # levitation gaps
    ds = s.gap_matrix @ np.array([0, 0, 0, 1e-3, 0, 0])
    np.testing.assert_allclose(ds, [0, 0, -1e-3, 1e-3], atol=1e-18)
    ds = s.gap_matrix @ np.array([0, 0, 0, 0, 1e-3, 0])
    np.testing.assert_allclose(ds, [1e-3, 1e-3, 0, 0], atol=1e-18)


def test_energy_conserved_without_damping() -> None:
    """Air springs and magnets as undamped springs, gravity on: kinetic + spring + gravity
    potential (body by body, element by element) is conserved by DOP853; with the
    dampers it falls."""
    mech = CrossSectionMechanics(load_cross_section())
    s = mech.with_magnet_springs(2.0e6, 1.5e6)
    n = s.n_dof
    a = np.array([0.0, G0])
    rng = np.random.default_rng(11)
    q0, qd0 = rng.normal(0, 3e-3, n), rng.normal(0, 3e-2, n)
    minv = 1.0 / np.diag(s.M)

    def rhs(_t: float, x: np.ndarray) -> np.ndarray:
        return np.concatenate([x[n:], minv * (s.G @ a + s.Q_preload - s.K @ x[:n])])

    sol = scipy.integrate.solve_ivp(rhs, (0, 10.0), np.concatenate([q0, qd0]), method="DOP853",
                                    rtol=1e-11, atol=1e-14, t_eval=np.linspace(0, 10, 501))
    e = s.energy_J(sol.y[:n].T, sol.y[n:].T, a)
    scale = float(np.max(np.abs(s.energy_J(sol.y[:n].T, np.zeros_like(sol.y[n:].T), a))))
    # measured drift 1.6e-12 of the largest potential over 10 s (~50 periods of the
    # slowest mode); bound 1e-8
    assert np.abs(e - e[0]).max() < 1e-8 * scale
    damped = mech.with_magnet_springs(2.0e6, 1.5e6, levitation_damping_N_s_per_m=3e3,
                                      guidance_damping_N_s_per_m=3e3)
    a_mat, _ = damped.state_matrices()
    q_eq = np.linalg.solve(damped.K, damped.G @ a + damped.Q_preload)
    x0 = np.concatenate([q0 + q_eq, qd0])
    sol = scipy.integrate.solve_ivp(lambda _t, x: a_mat @ x + np.concatenate(
        [np.zeros(n), minv * (damped.G @ a + damped.Q_preload)]), (0, 10.0), x0,
        method="DOP853", rtol=1e-10,
        atol=1e-14)
    e_eq = float(damped.energy_J(q_eq, np.zeros(n), a))
    e_end = float(damped.energy_J(sol.y[:n, -1], sol.y[n:, -1], a))
    assert e_end - e_eq < 0.2 * (float(damped.energy_J(x0[:n], x0[n:], a)) - e_eq)


def test_eigenfrequencies_against_the_two_mass_oscillators() -> None:
    """With every lateral element at the height of both centres of mass, lateral,
    vertical and roll motion decouple into three two-mass oscillators with closed-form
    frequencies (car body on the air springs, chassis on the magnets)."""
    p = _params()
    h = -0.3
    p["car_body"]["centre_z"] = p["chassis"]["centre_z"] = p["air_spring"]["z"] = h
    p["guidance"]["z"] = h
    data = parse_cross_section(p)
    kl, kg = 2.0e6, 1.5e6
    s = CrossSectionMechanics(data).with_magnet_springs(kl, kg)
    m1, m2 = data.loaded_car_body_mass_kg, data.chassis_mass_kg
    j1, j2 = data.car_body_roll_inertia_kg_m2, data.chassis_roll_inertia_kg_m2
    ky, kz = data.spring_lateral_stiffness_N_per_m, data.spring_vertical_stiffness_N_per_m
    ys, yl = data.spring_y_m, data.levitation_y_m
    want = np.sort(np.concatenate([
        _two_mass_Hz(m1, m2, 2 * ky, 2 * kg),                        # lateral
        _two_mass_Hz(m1, m2, 2 * kz, 2 * kl),                        # vertical
        _two_mass_Hz(j1, j2, 2 * kz * ys ** 2, 2 * kl * yl ** 2)]))  # roll
    # eigenvalues of a 6x6 symmetric matrix: rounding, 1e-10 relative
    np.testing.assert_allclose(s.natural_frequencies_Hz(), want, rtol=1e-10)
    # the lateral car-body mode of the bundled vehicle is near the file's ~0.8 Hz design
    # aim (the estimate behind air_spring.lateral_stiffness) once roll couples in
    f_bundled = CrossSectionMechanics(load_cross_section()).with_magnet_springs(
        kl, kg).natural_frequencies_Hz()
    assert 0.4 < f_bundled[0] < 0.9


def test_static_equilibrium_straight_level_track() -> None:
    data = load_cross_section()
    mech = CrossSectionMechanics(data)
    weight = data.total_mass_kg * G0
    a = track_field_m_per_s2(400 / 3.6)
    np.testing.assert_allclose(a, [0.0, G0], rtol=0, atol=1e-15)
    q, f = mech.static_trim(a, guidance_bias_N=1.5e4)
    names = mech.system.dof_names
    # symmetric vehicle: centred and level (exact zeros up to rounding of the solve)
    for d in ("car_body.y", "car_body.phi"):
        assert abs(q[names.index(d)]) < 1e-14
    # the air springs' preload (m g / 2 each) carries the car body at its design position:
    # no sag m g / (2 k_z) (243 mm on the linear stiffness); each spring's force, from
    # its deflection and preload, is half the loaded car body's weight
    assert abs(q[names.index("car_body.z")]) < 1e-15
    s0 = mech.system
    spring = s0.stiffness_N_per_m * s0.element_deflections(q) + s0.preload_N
    half = 0.5 * data.loaded_car_body_mass_kg * G0
    for k, e in enumerate(s0.elements):
        want = half if e.direction == "z" else 0.0
        assert spring[k] == pytest.approx(want, rel=1e-12, abs=1e-9)
    # levitation left = right, together the weight; guidance both at the bias
    assert f[0] == pytest.approx(f[1], rel=1e-12)
    assert f[0] + f[1] == pytest.approx(weight, rel=1e-12)
    np.testing.assert_allclose(f[2:], [1.5e4, 1.5e4], rtol=1e-12)
    # the free suspension (magnets as springs) settles centred too
    s = mech.with_magnet_springs(2.0e6, 1.5e6)
    q_free = np.linalg.solve(s.K, s.G @ a + s.Q_preload)
    for d in ("car_body.y", "car_body.phi", "chassis.y", "chassis.phi"):
        assert abs(q_free[names.index(d)]) < 1e-15


@pytest.mark.parametrize("speed_kmh", [200.0, 450.0])
def test_quasi_steady_curve_force_balance(speed_kmh: float) -> None:
    """R = 4000 m, 12 deg superelevation: balancing speed 328.7 km/h.  The net lateral
    guidance force = m v^2/R cos(c) - m g sin(c) for the masses carried (closed form,
    written out here), below and above the balancing speed."""
    data = load_cross_section()
    mech = CrossSectionMechanics(data)
    r, c, v = 4000.0, math.radians(12.0), speed_kmh / 3.6
    v_bal = math.sqrt(G0 * r * math.tan(c))
    assert (v - v_bal) * (speed_kmh - 328.7) > 0
    m = data.loaded_car_body_mass_kg + data.chassis_mass_kg
    lateral = m * v * v / r * math.cos(c) - m * G0 * math.sin(c)
    normal = m * v * v / r * math.sin(c) + m * G0 * math.cos(c)
    a = track_field_m_per_s2(v, r, c)
    q, f = mech.static_trim(a, guidance_bias_N=2.0e4)
    # guidance left pulls +y, right pulls -y: the net inward (-y) force is F_r - F_l
    net = f[3] - f[2]
    assert np.sign(net) == np.sign(v - v_bal)
    # the 1 % criterion of the issue; measured agreement 1e-15 (same linear balance)
    assert net == pytest.approx(lateral, rel=1e-2)
    assert f[0] + f[1] == pytest.approx(normal, rel=1e-2)
    assert f[2] + f[3] == pytest.approx(4.0e4, rel=1e-12)
    # through the free suspension instead (magnets as springs, element by element): the
    # guidance springs' forces, from their deflections, balance the same load
    s = mech.with_magnet_springs(2.0e6, 1.5e6)
    q_free = np.linalg.solve(s.K, s.G @ a + s.Q_preload)
    defl = s.element_deflections(q_free)
    k = np.array([e.stiffness_N_per_m for e in s.elements])
    force = dict(zip([e.name for e in s.elements], k * defl, strict=True))
    # element force k Delta acts on the chassis along -e (e = +y): net -y force is the sum
    assert force["magnet_guidance_left"] + force["magnet_guidance_right"] == pytest.approx(
        lateral, rel=1e-2)
    # the car body leans out of the curve above the balancing speed: outward (+y) shift
    assert np.sign(q[mech.system.dof_names.index("car_body.y")]) == np.sign(v - v_bal)


def test_track_field_refuses_bad_input() -> None:
    with pytest.raises(mk.InputError, match=r"curve_radius_m = 0.5 m: \|R\| must be >= 1 m"):
        track_field_m_per_s2(10.0, 0.5)
    with pytest.raises(mk.InputError, match=r"superelevation_rad = 12.0 rad: must be in"):
        track_field_m_per_s2(10.0, 4000.0, 12.0)
    with pytest.raises(mk.InputError, match="speed_m_per_s"):
        track_field_m_per_s2("fast")  # type: ignore[arg-type]
    with pytest.raises(mk.InputError, match="field_m_per_s2"):
        CrossSectionMechanics(load_cross_section()).static_trim([1.0])


# ------------------------------------------------------------------ the file
def test_bundled_file_loads_and_its_masses_follow_the_published_total() -> None:
    assert bundled_cross_sections() == ["tr09-cross-section"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")              # complete provenance: no warning
        data = load_cross_section()
    # [D] car_body.mass = 170 t / (3 x 8) - chassis.mass, to the 0.1 kg written
    assert data.car_body_mass_kg + data.chassis_mass_kg == pytest.approx(
        data.slice_share_kg, abs=0.05)
    assert data.slice_share_kg == pytest.approx(170000.0 / 24)
    assert data.provenance["cross_section.empty_train_mass"].startswith("[P]")


@pytest.mark.parametrize("edit, message", [
    (lambda p: p["car_body"].update(mass=-5083.3), r"\[car_body\] mass = -5083.3"),
    (lambda p: p["guidance"].update(y=1.0), r"\[guidance\] y = 1.0 m must be outboard"),
    (lambda p: p["chassis"].pop("mass"), r"\[chassis\]: missing required key 'mass' \[kg\]"),
    (lambda p: p["chassis"].update(mas=1.0), r"unknown key\(s\) \['mas'\]"),
    (lambda p: p.pop("guidance"), r"missing the \[guidance\] table"),
    (lambda p: p.update(magnet={}), r"unknown table\(s\) \['magnet'\]"),
    (lambda p: p["air_spring"].update(lateral_damping=-1.0), "must be >= 0"),
])
def test_bad_files_name_the_key_value_and_what_is_allowed(edit: Any, message: str) -> None:
    p = copy.deepcopy(_params())
    edit(p)
    with pytest.raises(mk.ParameterFileError, match=message):
        parse_cross_section(p)


@pytest.mark.parametrize("edit, message", [
    (lambda p: p["car_body"].update(mass=5.0833),
     r"\[car_body\] mass = 5.0833 kg is below the plausible range 50 \.\.\. 100000 kg .*"
     r"typed in t \(tonnes\) instead of kg"),
    (lambda p: p["air_spring"].update(y=1100.0),
     r"\[air_spring\] y = 1100.0 m is above the plausible range .* typed in mm instead of m"),
])
def test_implausible_values_warn_as_every_file_kind(edit: Any, message: str) -> None:
    """A unit slip in the cross-section file warns through the one check (as the magnet,
    vehicle and guideway files) and the value is used as given; it no longer refuses."""
    p = copy.deepcopy(_params())
    edit(p)
    with pytest.warns(mk.PlausibilityWarning, match=message):
        parse_cross_section(p)


def test_missing_provenance_warns() -> None:
    p = copy.deepcopy(_params())
    del p["provenance"]["chassis.mass"]
    p["provenance"]["guidance.z"] = "estimate"
    with pytest.warns(mk.ProvenanceWarning) as rec:
        parse_cross_section(p)
    text = " ".join(str(w.message) for w in rec)
    assert "no entry for chassis.mass" in text and "guidance.z do not start with" in text


def test_loader_fails_like_the_other_loaders(tmp_path: Path) -> None:
    with pytest.raises(mk.InputError, match="expected a bundled cross-section name"):
        load_cross_section(None)  # type: ignore[arg-type]
    with pytest.raises(mk.ParameterFileError, match="bundled cross-sections: tr09-cross-section"):
        load_cross_section("nonesuch")


def test_sources_page_lists_every_value_with_its_tag() -> None:
    text = (ROOT / "docs" / "sources.md").read_text()
    m = re.search(r"^### `vehicle/tr09-cross-section`\n(.*?)(?=^#|\Z)", text,
                  flags=re.S | re.M)
    assert m, "docs/sources.md has no section for vehicle/tr09-cross-section"
    rows = {}
    for line in m.group(1).splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 3 and cells[0].startswith("`"):
            rows[cells[0].strip("`")] = (cells[1], cells[2])
    data = _params()
    assert set(rows) == set(data["provenance"])
    for key, note in data["provenance"].items():
        table, k = key.split(".")
        value, tag = rows[key]
        assert tag == note[:3], key
        v = data[table][k]
        shown = value if value.startswith('"') else value.split(" ")[0]
        assert shown == (f'"{v}"' if isinstance(v, str) else repr(v)), key


def test_the_heave_pitch_train_is_expressible_in_the_planar_description() -> None:
    """The module docstring's recipe: the bundled heave-pitch train's bodies, air springs,
    joints and magnet points as a PlanarMultibody in the longitudinal plane (train
    coordinate as y, dofs z and pitch) give today's composed matrices."""
    from maglevkit.vehicle import VehicleMechanics, load_vehicle

    train = load_vehicle()
    slots = train.magnet_slots()
    mech = VehicleMechanics(train, [s.centre_m for s in slots], [s.frame for s in slots])
    bodies = [RigidBody(name, float(m), float(j), (float(x), 0.0), ("z", "phi"))
              for name, m, j, x in zip(mech.body_names, mech.body_mass_kg,
                                       mech.body_inertia_kg_m2, mech.body_centres_m,
                                       strict=True)]
    names = mech.body_names
    elements = [SpringDamper(e.name, names[e.body_a], (e.xi_a_m, 0.0), names[e.body_b],
                             (e.xi_b_m, 0.0), "z", e.stiffness_N_per_m, e.damping_N_s_per_m)
                for e in mech.elements]
    points = [ForcePoint(f"p{i}", names[int(b)], (float(x), 0.0), "-z")
              for i, (b, x) in enumerate(zip(mech.force_bodies, mech.force_points_m,
                                             strict=True))]
    planar = PlanarMultibody(bodies, elements, points)
    assert planar.dof_names == tuple(n.replace("theta", "phi") for n in mech.dof_names)
    for mine, theirs in ((planar.M, mech.M), (planar.K, mech.K), (planar.C, mech.C),
                         (planar.B, -mech.B), (planar.G[:, 1] * G0, mech.Q_gravity)):
        # the same sums in a different order: 1e-12 of the largest entry
        np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-12 * np.abs(theirs).max())
