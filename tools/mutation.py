#!/usr/bin/env python3
"""Mutation check of maglevkit's physics core (issue 16): do the tests catch small errors?

Each mutation is a deliberate small error -- a factor 1.05, a sign flip, an index shift --
given as ``(file, exact source snippet, replacement)``.  For every mutation the script

1. copies ``src``, ``tests``, ``benchmarks``, ``docs``, ``README.md`` and ``pyproject.toml``
   of this repository into a temporary directory (once) and checks that ``import maglevkit``
   there loads the copy (``PYTHONPATH`` = the copy's ``src``), not the installed package;
2. replaces the snippet in the copy (it must occur exactly once; a snippet that is not found,
   e.g. because the code was rewritten, is reported as ``NOT APPLIED`` and the spec below
   needs updating, not the code);
3. runs the mutation's selected tests there (``pytest -x``, slow ones included when named)
   and reports ``KILLED`` (a test failed: named in the table), ``SURVIVED`` (all passed),
   ``TIMEOUT`` or ``ERROR`` (pytest could not run: collection or usage error);
4. restores the file.

Before the mutations the union of all selected tests runs once on the unmodified copy
(baseline): a failing baseline would make every mutation look killed, so it aborts.

A mutation listed with ``equivalent="reason"`` is one whose survival is expected because it
does not change the physics (the reason says why); its survival is reported as
``EQUIVALENT``.  Exit status: 0 if no mutation survived (NOT APPLIED does not fail the run,
it is listed), 1 otherwise, 2 if the baseline fails.

Usage::

    python tools/mutation.py               # all mutations (make mutation)
    python tools/mutation.py --list        # the list, no runs
    python tools/mutation.py -k eq8        # mutations whose name contains "eq8"
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COPY = ("src", "tests", "benchmarks", "docs", "README.md", "pyproject.toml")


@dataclass(frozen=True)
class Mutation:
    name: str
    file: str                 # relative to the repository root
    snippet: str              # exact source text (must occur exactly once)
    replacement: str
    tests: tuple[str, ...]    # pytest node ids (relative to the repository root)
    equivalent: str | None = None


EL = "src/maglevkit/circuit/elements.py"
ASM = "src/maglevkit/circuit/assembly.py"
NET = "src/maglevkit/circuit/network.py"
STA = "src/maglevkit/models/statics.py"
FLX = "src/maglevkit/models/flux.py"
CUR = "src/maglevkit/reduced/current.py"
EXP = "src/maglevkit/models/experiments.py"
PAR = "src/maglevkit/reduction/parameters.py"
MAP = "src/maglevkit/reduction/maps.py"
TRA = "src/maglevkit/reduction/transient.py"
VEH = "src/maglevkit/plant.py"
GW = "src/maglevkit/vehicle/guideway.py"
SIM = "src/maglevkit/vehicle/simulation.py"
KER = "src/maglevkit/vehicle/stepkernel.py"
MB = "src/maglevkit/vehicle/multibody.py"
MEC = "src/maglevkit/vehicle/mechanics.py"
TRN = "src/maglevkit/vehicle/train.py"
IRR = "src/maglevkit/vehicle/irregularities.py"
CMF = "src/maglevkit/vehicle/comfort.py"
OBS = "src/maglevkit/control/observers.py"
MOD = "src/maglevkit/control/model.py"
MPC = "src/maglevkit/control/mpc.py"

T_STA = "tests/test_statics.py"
T_EL = "tests/test_elements.py"
T_FL = "tests/test_flux_linear.py"
T_FP = "tests/test_flux_physics.py"
T_RED = "tests/test_reduction.py"
T_RT = "tests/test_reduction_transient.py"
T_LEV = "tests/test_magnets_levitation.py"
T_GW = "tests/test_guideway.py"
T_SV = "tests/test_strength_vehicle.py"

MUTATIONS: tuple[Mutation, ...] = (
    # ------------------------------------------------------------------ element laws
    Mutation("iron law x1.05", EL,
             "return self.length_m * self.material.field_strength(flux_Wb / self.cross_section_m2)",
             "return 1.05 * self.length_m * self.material.field_strength(flux_Wb / self.cross_section_m2)",
             (f"{T_STA}::test_constant_mu_iron_is_series_reluctances",
              f"{T_STA}::test_single_saturable_loop_against_a_scalar_root_solve")),
    Mutation("iron law B index (A -> 1.05 A)", EL,
             "return self.length_m * self.material.field_strength(flux_Wb / self.cross_section_m2)",
             "return self.length_m * self.material.field_strength(flux_Wb / (1.05 * self.cross_section_m2))",
             (f"{T_STA}::test_single_saturable_loop_against_a_scalar_root_solve",)),
    Mutation("air-gap permeance x1.05", EL,
             "g = self._add_fringe(self.pole_area_m2 / s, s)",
             "g = self._add_fringe(1.05 * self.pole_area_m2 / s, s)",
             (f"{T_STA}::test_ideal_iron_matches_textbook",)),
    Mutation("fringing quarter circle -> half circle", EL,
             "_log(1.0 + math.pi * r / (2.0 * s))",
             "_log(1.0 + math.pi * r / s)",
             (f"{T_EL}::test_air_gap_fringe_edge_is_the_quarter_circle_tube_to_a_plane",)),
    Mutation("recess depth sign flip", EL,
             "g = g + a / (s + d)",
             "g = g + a / (s - d)",
             (f"{T_LEV}::test_lig_grooves_matter",)),
    Mutation("Carter gamma x1.05", EL,
             "    return gamma * gap\n",
             "    return 1.05 * gamma * gap\n",
             (f"{T_LEV}::test_carter_coefficient_against_hand_computation",)),
    Mutation("gap leakage pi r/s -> pi r/(2 s)", EL,
             "_log(1.0 + math.pi * self.radius_m / gap_m)",
             "_log(1.0 + math.pi * self.radius_m / (2.0 * gap_m))",
             (f"{T_EL}::test_gap_leakage_around_poles_is_the_modelica_formula",)),
    Mutation("linear element energy x1/1.05", EL,
             "return flux_Wb * flux_Wb / (2.0 * self.permeance(gap_m))",
             "return flux_Wb * flux_Wb / (2.1 * self.permeance(gap_m))",
             (f"{T_STA}::test_ideal_iron_matches_textbook",)),
    Mutation("solid-bar eddy conductance x1.05", EL,
             "return cls(name, torsion * length_m / (4.0 * resistivity_ohm_m * area * area))",
             "return cls(name, 1.05 * torsion * length_m / (4.0 * resistivity_ohm_m * area * area))",
             (f"{T_FP}::test_solid_bar_eddy_conductance_limits",)),
    Mutation("laminated eddy conductance x1.05", EL,
             "sheet_thickness_m**2 * length_m / (12.0 * resistivity_ohm_m * area_m2)",
             "sheet_thickness_m**2 * length_m / (11.4 * resistivity_ohm_m * area_m2)",
             (f"{T_FP}::test_laminated_eddy_conductance",)),
    Mutation("torsion series 192 -> 190", EL,
             "192.0 / math.pi**5",
             "190.0 / math.pi**5",
             (f"{T_FP}::test_solid_bar_eddy_conductance_limits",)),
    Mutation("quarter-cylinder leakage 0.52 -> 0.546", EL,
             "return cls(name, 0.52 * MU0 * length_m)",
             "return cls(name, 0.546 * MU0 * length_m)",
             (f"{T_EL}::test_roters_leakage_shapes",)),
    # ------------------------------------------------------------------ assembly, network
    Mutation("loop law MMF sign flip", ASM,
             "residual = ca.mtimes(ca.DM(C), mmf - ca.mtimes(ca.DM(N), I))",
             "residual = ca.mtimes(ca.DM(C), mmf + ca.mtimes(ca.DM(N), I))",
             (f"{T_STA}::test_ideal_iron_matches_textbook",)),
    Mutation("flux linkage psi x1.05", ASM,
             "psi = ca.mtimes(ca.DM(N.T), phi)",
             "psi = 1.05 * ca.mtimes(ca.DM(N.T), phi)",
             (f"{T_STA}::test_ideal_iron_matches_textbook",)),
    Mutation("force x1.05", ASM,
             "force_b = ca.gradient(w_gap, s)",
             "force_b = 1.05 * ca.gradient(w_gap, s)",
             (f"{T_STA}::test_ideal_iron_matches_textbook",)),
    Mutation("turns matrix polarity dropped", NET,
             "n[idx[coil.branch], k] += coil.polarity * coil.turns",
             "n[idx[coil.branch], k] += coil.turns",
             (f"{T_LEV}::test_half_magnet_carries_section_share",
              f"{T_LEV}::test_coupling_of_the_two_circuits_is_small")),
    Mutation("resistance x1.05", NET,
             "return np.array([c.resistance_ohm for c in self.circuits], dtype=float)",
             "return 1.05 * np.array([c.resistance_ohm for c in self.circuits], dtype=float)",
             (f"{T_FL}::test_rl_step_response_matches_exponential",)),
    Mutation("eddy conductances x1.05 (network)", NET,
             "return np.array([sum(e.eddy_conductance for e in b.elements) for b in self.branches])",
             "return 1.05 * np.array([sum(e.eddy_conductance for e in b.elements) "
             "for b in self.branches])",
             (f"{T_FL}::test_one_eddy_element_first_order_with_jump",)),
    Mutation("pole flux matrix (eta) x1.05", NET,
             "w[idx[coil.branch], k] += coil.polarity * coil.turns / totals[coil.pole or coil.branch]",
             "w[idx[coil.branch], k] += 1.05 * coil.polarity * coil.turns / totals[coil.pole or "
             "coil.branch]",
             ("tests/test_flux_interface.py::test_eta_is_sum_of_pole_core_fluxes",)),
    Mutation("loop matrix: tree path sign flip", NET,
             "for path, sign in ((pa, 1.0), (pb, -1.0)):",
             "for path, sign in ((pa, -1.0), (pb, 1.0)):",
             (f"{T_STA}::test_ideal_iron_matches_textbook",)),
    # ------------------------------------------------------------------ statics, force
    Mutation("dx/dI sign flip (inductance)", STA,
             "dx_dI = -ca.solve(Jm, dIm)",
             "dx_dI = ca.solve(Jm, dIm)",
             (f"{T_STA}::test_ideal_iron_matches_textbook",)),
    Mutation("dF/ds: implicit term sign flip", STA,
             "dfds + ca.mtimes(dfdx, dx_ds)]",
             "dfds - ca.mtimes(dfdx, dx_ds)]",
             (f"{T_STA}::test_force_gap_derivative_against_finite_differences",)),
    Mutation("dpsi/ds x1.05", STA,
             "ca.mtimes(NC, dx_ds),",
             "1.05 * ca.mtimes(NC, dx_ds),",
             (f"{T_STA}::test_reciprocity_and_inductance_against_finite_differences",)),
    Mutation("co-energy sign of W", STA,
             "return float(sol.currents_A @ sol.flux_linkage_Wb) - w",
             "return float(sol.currents_A @ sol.flux_linkage_Wb) + w",
             (f"{T_STA}::test_coenergy_force_matches_finite_difference_of_coenergy",)),
    Mutation("eq. 6 factor (mu_r-1)/mu_r -> mu_r/(mu_r+1)", STA,
             "factor = (mu - 1.0) / mu",
             "factor = mu / (mu + 1.0)",
             (f"{T_STA}::test_constant_mu_iron_is_series_reluctances",)),
    # ------------------------------------------------------------------ eddy law (flux DAE)
    Mutation("eddy law G_ec x1.05 in the DAE", FLX,
             "M = np.vstack((C @ np.diag(G) @ C.T, a_psi))",
             "M = np.vstack((1.05 * C @ np.diag(G) @ C.T, a_psi))",
             (f"{T_FL}::test_one_eddy_element_first_order_with_jump",)),
    Mutation("eddy loss x1.05 (energy bookkeeping)", FLX,
             "ca.dot(g_e * phidot_e, phidot_e)",
             "1.05 * ca.dot(g_e * phidot_e, phidot_e)",
             (f"{T_FP}::test_energy_balance_moving_gap_saturation_eddy",)),
    Mutation("circuit law R I sign flip", FLX,
             "hv = ca.vertcat(-eq.residual, U - R * I)",
             "hv = ca.vertcat(-eq.residual, U + R * I)",
             (f"{T_FL}::test_rl_step_response_matches_exponential",)),
    Mutation("mechanical power sign flip", FLX,
             "-ca.dot(force, rate))",
             "ca.dot(force, rate))",
             (f"{T_FP}::test_energy_balance_large_gap_motion",)),
    # ------------------------------------------------------------------ eq. 8 (current model)
    Mutation("eq8 dL/ds term x1.05", CUR,
             "return ((u - r_el * i_l) / a - dl_ds * i_l * gap_rate) / ltilde",
             "return ((u - r_el * i_l) / a - 1.05 * dl_ds * i_l * gap_rate) / ltilde",
             (f"{T_RED}::test_current_model_virtual_control_law_isolates_dl_ds",
              "tests/test_compare.py::test_u_magnet_with_eddy_currents_and_saturation")),
    Mutation("eq8 R_ec x1.05 (model)", "src/maglevkit/reduced/core.py",
             "r_ec = np.asarray(maps.dataset[var].values, dtype=float)",
             "r_ec = 1.05 * np.asarray(maps.dataset[var].values, dtype=float)",
             (f"{T_RT}::test_default_eddy_resistance_against_an_independent_tail_fit",)),
    Mutation("eq8 a = 1 + R_el/R_ec -> 1 + 1.05 R_el/R_ec", "src/maglevkit/reduced/core.py",
             "return 1.0 + np.where(np.isinf(r_ec), 0.0, r_el / np.where(np.isinf(r_ec), 1.0, r_ec))",
             "return 1.0 + np.where(np.isinf(r_ec), 0.0, 1.05 * r_el / np.where(np.isinf(r_ec), 1.0, "
             "r_ec))",
             (f"{T_RT}::test_default_eddy_resistance_against_an_independent_tail_fit",)),
    Mutation("eq8 resistive term sign flip", CUR,
             "return ((u - r_el * i_l) / a - dl_ds",
             "return ((u + r_el * i_l) / a - dl_ds",
             (f"{T_RED}::test_current_model_step_response_is_the_rl_law",)),
    Mutation("eq8 coil current output x1.05", CUR,
             "return (u - (u - r_el * i_l) / a) / r_el",
             "return 1.05 * (u - (u - r_el * i_l) / a) / r_el",
             (f"{T_RED}::test_current_model_step_response_is_the_rl_law",)),
    # ------------------------------------------------------------------ R_ec identification
    Mutation("R_ec jump: -R_el -> +R_el", PAR,
             "out[j] = 1.0 / yjj - r_el",
             "out[j] = 1.0 / yjj + r_el",
             (f"{T_RT}::test_eddy_resistance_of_one_loop_is_n2_over_g",)),
    Mutation("R_ec jump admittance dr/dI x1.05", PAR,
             "dh_dz = np.block([[-drdx, -drdi],",
             "dh_dz = np.block([[-drdx, -1.05 * drdi],",
             (f"{T_RT}::test_eddy_resistance_of_one_loop_is_n2_over_g",)),
    Mutation("R_ec fit x1.05 (maps)", MAP,
             "out[j] = R[j] * di_inf / jump - R[j]",
             "out[j] = 1.05 * (R[j] * di_inf / jump - R[j])",
             (f"{T_RT}::test_default_eddy_resistance_against_an_independent_tail_fit",)),
    Mutation("R_ec fit: step formula x1.05", EXP,
             "r_ec = math.inf if jump <= 0.0 else r_par * di_inf / jump - r_par",
             "r_ec = math.inf if jump <= 0.0 else 1.05 * (r_par * di_inf / jump - r_par)",
             (f"{T_RT}::test_default_eddy_resistance_of_one_loop_is_n2_over_g",)),
    Mutation("L~ from step: (1 - jump) -> (1 + jump)", EXP,
             "inductance_H=tau * r_par * (1.0 - max(jump, 0.0) / di_inf)",
             "inductance_H=tau * r_par * (1.0 + max(jump, 0.0) / di_inf)",
             (f"{T_FP}::test_inductance_with_eddies_has_jump_and_same_l_tilde",)),
    # ------------------------------------------------------------------ map building
    Mutation("maps dpsi/ds: circuit index shift", MAP,
             "dpsi_ds[j] = sol.dpsi_dgap_Wb_per_m[:, j, idx].sum(axis=-1)",
             "dpsi_ds[j] = sol.dpsi_dgap_Wb_per_m[:, (j + 1) % nc, idx].sum(axis=-1)",
             (f"{T_RED}::test_tr09_maps_satisfy_eq9_reciprocity_per_circuit",)),
    Mutation("maps force: one pole dropped", MAP,
             "force[j] = sol.pole_force_N[:, idx].sum(axis=-1)",
             "force[j] = sol.pole_force_N[:, idx[:-1]].sum(axis=-1)",
             (f"{T_RED}::test_maps_of_the_ideal_magnet_are_the_closed_forms",)),
    Mutation("maps dL/ds at I = 0: 2h -> h", MAP,
             "d = (l0[0, j] - l0[1, j]) / (2 * h)",
             "d = (l0[0, j] - l0[1, j]) / h",
             (f"{T_RED}::test_maps_of_the_ideal_magnet_are_the_closed_forms",)),
    Mutation("maps L~: self -> row sum (adds mutual)", MAP,
             "ltilde = np.diagonal(sol.differential_inductance_H, axis1=-2, axis2=-1).T",
             "ltilde = sol.differential_inductance_H.sum(axis=-1).T",
             (f"{T_RED}::test_tr09_maps_satisfy_eq9_reciprocity_per_circuit",)),
    Mutation("transient dL/ds from the ramp x1.05", TRA,
             "lt[j], dl[j], rec[j] = step.inductance_H, ramp.dL_ds_H_per_m, step.eddy_resistance_ohm",
             "lt[j], dl[j], rec[j] = step.inductance_H, 1.05 * ramp.dL_ds_H_per_m, "
             "step.eddy_resistance_ohm",
             (f"{T_RT}::test_transient_and_statics_maps_agree",)),
    # ------------------------------------------------------------------ vehicle (heave mass)
    Mutation("heave: 0.5 a dt^2 -> a dt^2", VEH,
             "state.gap_m + state.gap_rate_m_per_s * dt + 0.5 * a * dt * dt",
             "state.gap_m + state.gap_rate_m_per_s * dt + a * dt * dt",
             ("tests/test_control.py::test_heave_mass_free_fall_is_exact",)),
    Mutation("heave: magnet force x1.05", VEH,
             "return self.gravity_m_per_s2 + (external_force_N - magnet_force_N) / self.mass_kg",
             "return self.gravity_m_per_s2 + (external_force_N - 1.05 * magnet_force_N) / "
             "self.mass_kg",
             ("tests/test_control.py::test_gap_controller_levitates_and_tracks_a_reference",)),
    # ------------------------------------------------------------------ magnet bank
    Mutation("bank: bicubic cell coefficients t^p scaled by h^(p+1)", "src/maglevkit/reduced/tables.py",
             "return c * (h ** np.arange(4)).reshape((4,) + (1,) * (c.ndim - 1))",
             "return c * (h ** np.arange(1, 5)).reshape((4,) + (1,) * (c.ndim - 1))",
             ("tests/test_bank.py::test_bicubic_table_equals_casadi_bspline",)),
    Mutation("bank: cell coefficient index shift (q -> q + 1 in w)", "src/maglevkit/reduced/tables.py",
             "g = [_power_sum([c[j * nk + pp * (d + 1) + q] for pp in range(d + 1)], tp)",
             "g = [_power_sum([c[j * nk + pp * (d + 1) + min(q + 1, d)] for pp in range(d + 1)], tp)",
             ("tests/test_current_tables.py::test_kernel_lookup_equals_the_cell_table_reference",)),
    Mutation("bank: RK4 stage gap at the sub-step start instead of its middle",
             "src/maglevkit/reduced/bank.py",
             "cell_mid = self._gap_cell(sk + sd * (hs / 2), p)",
             "cell_mid = self._gap_cell(sk, p)",
             ("tests/test_bank.py::test_moving_gap_converges_with_rk4_order",)),
    Mutation("bank: range flag of the current's upper bound dropped", "src/maglevkit/reduced/bank.py",
             "any_of(lo < p[11], hi > p[12])",
             "any_of(lo < p[11])",
             ("tests/test_bank.py::test_range_checked_before_integrating_names_member_and_range",)),
    Mutation("bank stepper: the kernel's flag count not checked",
             "src/maglevkit/reduced/stepper.py",
             "        if self._n_bad[0]:\n",
             "        if False:\n",
             ("tests/test_bank_stepper.py::test_failed_step_leaves_the_stepper_at_the_last_good_step",)),
    Mutation("bank stepper: the end gaps not carried on to the next step",
             "src/maglevkit/reduced/stepper.py",
             "        self._block[:] = self._scratch\n        self._g[:] = self._state_gaps\n",
             "        self._block[:] = self._scratch\n",
             ("tests/test_bank_stepper.py::test_stepper_equals_step_bit_for_bit",)),
    # ------------------------------------------------------------------ SIMD lanes (bank kernel)
    Mutation("lanes: 4x4 transpose, high halves swapped (0x31 -> 0x20 for coefficient 2)",
             "src/maglevkit/reduced/lanes.py",
             'f"{c2} = (vd)_mm256_permute2f128_pd(u0, u2, 0x31); "',
             'f"{c2} = (vd)_mm256_permute2f128_pd(u0, u2, 0x20); "',
             ("tests/test_lanes.py::test_bank_lanes_equal_casadi_code_and_virtual_machine",)),
    Mutation("lanes: fast gather accepts an index one past the table",
             "src/maglevkit/reduced/lanes.py",
             'f"if (b == (double) ib && ib + {lo} >= 0 && ib + {hi} < {tsize}) {{ "',
             'f"if (b == (double) ib && ib + {lo} >= 0 && ib + {hi} <= {tsize}) {{ "',
             ("tests/test_lanes.py::test_lane_kernel_equals_casadi_bit_for_bit",)),
    Mutation("lanes: vector fmin without the NaN rule", "src/maglevkit/reduced/lanes.py",
             'ca.OP_FMIN: "SEL(({a} <= {b}) | ({b} != {b}), {a}, {b})"',
             'ca.OP_FMIN: "SEL(({a} <= {b}), {a}, {b})"',
             ("tests/test_lanes.py::test_lane_kernel_equals_casadi_bit_for_bit",)),
    Mutation("lanes: element selection off by one", "src/maglevkit/reduced/lanes.py",
             'work[outs[0]] = [src_el[j] if j >= 0 else "(0.0)" for j in nz]',
             'work[outs[0]] = [src_el[min(j + 1, len(src_el) - 1)] if j >= 0 else "(0.0)" for j in nz]',
             ("tests/test_lanes.py::test_lane_kernel_equals_casadi_bit_for_bit",)),
    # ------------------------------------------------------------------ chopper bound (plant)
    Mutation("chopper: bound -R_ec I_L with the sign lost", "src/maglevkit/plant.py",
             "low = -eddy_resistance_ohm * inductor_current_A",
             "low = eddy_resistance_ohm * inductor_current_A",
             ("tests/test_chopper.py::test_bound_makes_the_coil_current_non_negative_and_leaves_allowed_commands",)),
    # ------------------------------------------------------------------ guideway (spans)
    Mutation("guideway: modal mass m L/2 x1.05", GW,
             "return 0.5 * self.mass_per_length_kg_per_m * self.length_m",
             "return 0.525 * self.mass_per_length_kg_per_m * self.length_m",
             (f"{T_GW}::test_static_point_load_matches_beam_formula",)),
    Mutation("guideway: modal stiffness EI x1.05 in omega_j", GW,
             "omega = k ** 2 * math.sqrt(self.bending_stiffness_N_m2 / self.mass_per_length_kg_per_m)",
             "omega = k ** 2 * math.sqrt(1.05 * self.bending_stiffness_N_m2 "
             "/ self.mass_per_length_kg_per_m)",
             (f"{T_GW}::test_natural_frequencies_match_finite_difference_beam",)),
    Mutation("guideway: mode shape sin(j pi x/L) index shift j -> j + 1", GW,
             "k = np.arange(1, self.n_modes + 1) * math.pi / self.length_m",
             "k = np.arange(2, self.n_modes + 2) * math.pi / self.length_m",
             (f"{T_GW}::test_natural_frequencies_match_finite_difference_beam",)),
    Mutation("exact ZOH step (guideway, mechanics, multibody): input matrix over dt/2",
             "src/maglevkit/vehicle/zoh.py",
             "aug[:n2, n2:] = b * dt_s",
             "aug[:n2, n2:] = b * dt_s / 2",
             (f"{T_GW}::test_damped_moving_force_matches_closed_form",
              f"{T_SV}::test_mechanics_zoh_step_matches_an_ode_solver_with_held_forces",
              "tests/test_zoh.py::test_first_order_lag_and_undamped_oscillator_closed_forms")),
    Mutation("guideway: recycled span's displacements not reset", GW,
             "        q[rows] = 0.0\n",
             "",
             (f"{T_GW}::test_recycled_span_is_reset_and_window_too_short_is_refused",)),
    # ------------------------------------------------------------------ vehicle run loop
    # the step's laws are written once (stepkernel.build_vehicle_parts); the NumPy
    # reference loop evaluates the same parts, so a mutation there reaches both loops and
    # the loops' equality test cannot see it: the strength tests on the reference loop do
    Mutation("vehicle step: moving-load term v dw/dx sign flip", KER,
             "[w, w_t + v * w_x, mid]",
             "[w, w_t - v * w_x, mid]",
             (f"{T_SV}::test_gap_rate_is_the_time_derivative_of_the_gap",)),
    Mutation("vehicle step: irregularity rate v dr/dx sign flip", KER,
             "velocity - w_rate - v * rx",
             "velocity - w_rate + v * rx",
             (f"{T_SV}::test_gap_rate_is_the_time_derivative_of_the_gap",)),
    Mutation("vehicle step: recycled ring-buffer span not reset", GW,
             "% self.n_spans] = 0.0",
             "% self.n_spans] = 1.0",
             (f"{T_SV}::test_guideway_replay_over_recycled_spans",
              "tests/test_vehicle_framework.py::"
              "test_window_schedule_equals_advancing_the_guideway_step_by_step")),
    Mutation("vehicle step: guideway loads at the step end, not mid-step", KER,
             "half = 0.5 * v * dt",
             "half = v * dt",
             ("tests/test_vehicle.py::test_guideway_in_the_loop_matches_guideway_step",)),
    Mutation("vehicle step: deflection enters the gap with the wrong sign", KER,
             "return s0 + ca.mtimes(bt, q) - w - r,",
             "return s0 + ca.mtimes(bt, q) + w - r,",
             (f"{T_SV}::test_recorded_gap_is_the_kinematic_gap",)),
    Mutation("vehicle step: guideway load not equal and opposite (sign)", KER,
             "loads = ca.vertcat(*[sn_m[j] * f_bar for j in range(nm)])",
             "loads = ca.vertcat(*[-sn_m[j] * f_bar for j in range(nm)])",
             ("tests/test_vehicle.py::test_guideway_in_the_loop_matches_guideway_step",)),
    Mutation("vehicle: floor acceleration pitch lever arm sign", SIM,
             "+ qdd_all[:, 1:2 * secs:2, None] * floor[None, None, :] * tr.section_length_m)",
             "- qdd_all[:, 1:2 * secs:2, None] * floor[None, None, :] * tr.section_length_m)",
             (f"{T_SV}::test_floor_acceleration_is_the_second_derivative_of_the_floor",)),
    Mutation("vehicle: comfort record's mean not removed", SIM,
             "comfort_indices(a - a.mean(axis=0), 1.0 / dt)",
             "comfort_indices(a, 1.0 / dt)",
             (f"{T_SV}::test_floor_acceleration_is_the_second_derivative_of_the_floor",),
             equivalent="both weightings vanish at 0 Hz (Wk has the s^2 high pass, Sperling's "
                        "B(0) = 0), so the record's mean is multiplied by 0 in either case"),
    Mutation("vehicle: integral projection lever arm sign (xi_f - xi)", SIM,
             "a = np.column_stack([np.ones(cols.size), self.circuit_xi_m[cols] - centres[f]])",
             "a = np.column_stack([np.ones(cols.size), centres[f] - self.circuit_xi_m[cols]])",
             ("tests/test_vehicle.py::test_levitates_standing_on_elastic_guideway",),
             equivalent="the projector A (A^T A)^-1 A^T depends only on the column space of A; "
                        "(1, xi - xi_f) and (1, xi_f - xi) span the same space"),
    # ------------------------------------------------------------------ mechanics, train
    Mutation("mechanics: air-spring stiffness x1.05", MEC,
             "train.spring_stiffness_N_per_m,",
             "1.05 * train.spring_stiffness_N_per_m,",
             (f"{T_SV}::test_car_bodies_sink_by_weight_over_air_spring_stiffness",)),
    Mutation("mechanics: frame pitch lever arm sign (xi_b - xi)", MB,
             "jac[1, cols[\"phi\"]] = dy",
             "jac[1, cols[\"phi\"]] = -dy",
             ("tests/test_vehicle.py::test_mechanics_against_sympy_lagrange_small_train",)),
    Mutation("mechanics: gravity sign", MEC,
             "self.Q_gravity = system.G @ np.array([0.0, self.gravity_m_per_s2])",
             "self.Q_gravity = system.G @ np.array([0.0, -self.gravity_m_per_s2])",
             ("tests/test_vehicle.py::test_mechanics_against_sympy_lagrange_small_train",)),
    Mutation("train: magnets' pitch offsets not centred on the frame", TRN,
             "offsets = (np.arange(per) + 0.5) * lm - 0.5 * per * lm",
             "offsets = np.arange(per) * lm - 0.5 * per * lm",
             (f"{T_SV}::test_frame_and_car_body_inertia_by_the_parallel_axis_theorem",)),
    # ------------------------------------------------------------------ irregularities, comfort
    Mutation("irregularity: bin power x2 (two-sided PSD read as one-sided)", IRR,
             "power = 0.5 * d * (s.reshape(nodes.shape) @ gw)",
             "power = d * (s.reshape(nodes.shape) @ gw)",
             ("tests/test_irregularities.py::test_variance_equals_integral_of_psd",)),
    Mutation("irregularity: random phases over [0, pi) instead of [0, 2 pi)", IRR,
             "phase = 2 * math.pi * rng.random(n)",
             "phase = math.pi * rng.random(n)",
             (f"{T_SV}::test_random_profile_ensemble_is_zero_mean_and_stationary",)),
    Mutation("irregularity: seed ignored", IRR,
             "rng = np.random.default_rng(self.seed)",
             "rng = np.random.default_rng(0)",
             ("tests/test_irregularities.py::test_random_profile_is_reproducible",)),
    Mutation("comfort: Wk upward-step corner f5 2.37 -> 2.5 Hz", CMF,
             '"f5": 2.37',
             '"f5": 2.5',
             ("tests/test_comfort.py::test_wk_matches_iso_table",)),
    Mutation("comfort: Sperling exponent 0.3 -> 1/3", CMF,
             "return aw, SPERLING_SCALE * _weighted_rms(spec, a.shape[0], b) ** 0.3",
             "return aw, SPERLING_SCALE * _weighted_rms(spec, a.shape[0], b) ** (1 / 3)",
             ("tests/test_comfort.py::test_sperling_index_of_a_sine",)),
    # ------------------------------------------------------------------ MPC, observer, model
    Mutation("EKF: Joseph covariance update I + K H", OBS,
             "IKH = ca.DM.eye(nz) - K @ H",
             "IKH = ca.DM.eye(nz) + K @ H",
             (f"{T_SV}::test_ekf_step_is_the_textbook_kalman_step",)),
    Mutation("EKF: process noise dropped from the prediction", OBS,
             "Pp = Az @ P @ Az.T + Qm",
             "Pp = Az @ P @ Az.T",
             (f"{T_SV}::test_ekf_step_is_the_textbook_kalman_step",)),
    Mutation("MPC model: voltage disturbance enters with the wrong sign", MOD,
             'ueff = u + self.disturbance(d, "voltage")\n        rhs, coil, force, eddy = [], [], 0, []',
             'ueff = u - self.disturbance(d, "voltage")\n        rhs, coil, force, eddy = [], [], 0, []',
             (f"{T_SV}::test_target_is_an_equilibrium_with_the_reference_as_measured_gap",)),
    Mutation("MPC model: force disturbance sign", MOD,
             'acc = self.gravity + (self.disturbance(d, "force") - force) / self.mass_kg',
             'acc = self.gravity + (-self.disturbance(d, "force") - force) / self.mass_kg',
             (f"{T_SV}::test_target_is_an_equilibrium_with_the_reference_as_measured_gap",)),
    Mutation("MPC target: gap-sensor offset added instead of subtracted", MOD,
             's = gap_m - float(dd.get("gap_sensor", np.zeros(1))[0])',
             's = gap_m + float(dd.get("gap_sensor", np.zeros(1))[0])',
             (f"{T_SV}::test_target_is_an_equilibrium_with_the_reference_as_measured_gap",)),
    Mutation("the one RK4 (reduced core): third stage from k1", "src/maglevkit/reduced/core.py",
             "k3 = mid(x + hs / 2 * k2)",
             "k3 = mid(x + hs / 2 * k1)",
             ("tests/test_reduced_core.py::test_rk4_substep_order_four",)),
    Mutation("MPC: upper voltage bound x1.05", MPC,
             "ubw[k * blk + nx:k * blk + nx + nu] = self._ulim / self._su",
             "ubw[k * blk + nx:k * blk + nx + nu] = 1.05 * self._ulim / self._su",
             (f"{T_SV}::test_mpc_inputs_saturate_exactly_at_the_voltage_limit",)),
    Mutation("MPC: terminal cost from the Riccati equation with R x1.05", MPC,
             'self._P = scipy.linalg.solve_discrete_are(lin["A"], lin["B"], self._Q, self._R)',
             'self._P = scipy.linalg.solve_discrete_are(lin["A"], lin["B"], self._Q, '
             '1.05 * self._R)',
             (f"{T_SV}::test_one_interval_mpc_is_the_lqr_of_the_linearisation",)),
)


@dataclass
class Outcome:
    mutation: Mutation
    status: str
    seconds: float
    detail: str


def _copy_tree(dest: Path) -> None:
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", ".pytest_cache", "*.egg-info")
    for name in COPY:
        src = ROOT / name
        if src.is_dir():
            shutil.copytree(src, dest / name, ignore=ignore)
        elif src.is_file():
            shutil.copy2(src, dest / name)


def _env(copy: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(copy / "src") + os.pathsep + str(copy)
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    env.setdefault("MPLBACKEND", "Agg")
    return env


def _pytest(copy: Path, tests: tuple[str, ...], timeout: float) -> tuple[int | None, str, float]:
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
           "-o", "addopts=--strict-markers", "--no-header", "-rfE", *tests]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, cwd=copy, env=_env(copy), capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired as exc:
        out = (exc.stdout or b"").decode() if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        return None, out, time.perf_counter() - t0
    return proc.returncode, proc.stdout + proc.stderr, time.perf_counter() - t0


def _first_failure(output: str) -> str:
    m = re.search(r"^FAILED (\S+)", output, flags=re.M)
    if m:
        return m.group(1)
    m = re.search(r"^ERROR (\S+)", output, flags=re.M)   # a fixture (set-up) failed
    return f"{m.group(1)} (error in set-up)" if m else ""


def _check_import(copy: Path) -> None:
    out = subprocess.run([sys.executable, "-c", "import maglevkit; print(maglevkit.__file__)"],
                         cwd=copy, env=_env(copy), capture_output=True, text=True, check=True)
    path = Path(out.stdout.strip()).resolve()
    if copy.resolve() not in path.parents:
        raise SystemExit(f"mutation: `import maglevkit` in the copy loads {path}, not the copy "
                         f"under {copy}; refusing to run (mutations would not be tested)")


def run(mutations: list[Mutation], *, timeout: float, baseline: bool) -> list[Outcome]:
    outcomes: list[Outcome] = []
    with tempfile.TemporaryDirectory(prefix="maglevkit-mutation-") as tmp:
        copy = Path(tmp)
        _copy_tree(copy)
        _check_import(copy)
        if baseline:
            union = tuple(dict.fromkeys(t for m in mutations for t in m.tests))
            print(f"baseline: {len(union)} selected tests on the unmodified copy ...", flush=True)
            rc, out, sec = _pytest(copy, union, timeout * 3)
            if rc != 0:
                print(out[-4000:])
                print(f"mutation: the baseline fails (exit {rc}); fix the tests first")
                raise SystemExit(2)
            print(f"baseline passed in {sec:.0f} s", flush=True)
        for k, m in enumerate(mutations, 1):
            target = copy / m.file
            original = target.read_text()
            count = original.count(m.snippet)
            if count != 1:
                why = "snippet not found" if count == 0 else f"snippet found {count} times"
                outcomes.append(Outcome(m, "NOT APPLIED", 0.0, why))
                print(f"[{k}/{len(mutations)}] {m.name}: NOT APPLIED ({why})", flush=True)
                continue
            target.write_text(original.replace(m.snippet, m.replacement))
            try:
                rc, out, sec = _pytest(copy, m.tests, timeout)
            finally:
                target.write_text(original)
            if rc is None:
                status, detail = "TIMEOUT", f"> {timeout:.0f} s"
            elif rc == 0:
                status = "EQUIVALENT" if m.equivalent else "SURVIVED"
                detail = m.equivalent or "all selected tests passed"
            elif rc == 1:
                status, detail = "KILLED", _first_failure(out) or "a test failed"
            else:
                status, detail = "ERROR", f"pytest exit {rc}: " + out.strip().splitlines()[-1][:120]
            outcomes.append(Outcome(m, status, sec, detail))
            print(f"[{k}/{len(mutations)}] {m.name}: {status} ({sec:.0f} s) {detail}", flush=True)
    return outcomes


def table(outcomes: list[Outcome]) -> str:
    lines = ["| # | mutation | file | result | time [s] | killed by / note |",
             "|---|---|---|---|---|---|"]
    for k, o in enumerate(outcomes, 1):
        f = o.mutation.file.removeprefix("src/maglevkit/")
        lines.append(f"| {k} | {o.mutation.name} | {f} | {o.status} | {o.seconds:.0f} | "
                     f"{o.detail} |")
    counts: dict[str, int] = {}
    for o in outcomes:
        counts[o.status] = counts.get(o.status, 0) + 1
    lines.append("")
    lines.append("summary: " + ", ".join(f"{v} {k.lower()}" for k, v in sorted(counts.items())))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-k", dest="select", default="", help="run mutations whose name contains this")
    ap.add_argument("--list", action="store_true", help="list the mutations and exit")
    ap.add_argument("--timeout", type=float, default=600.0, help="per mutation [s] (default 600)")
    ap.add_argument("--no-baseline", action="store_true", help="skip the unmodified baseline run")
    ap.add_argument("--report", type=Path, help="also write the table to this file")
    args = ap.parse_args(argv)
    chosen = [m for m in MUTATIONS if args.select.lower() in m.name.lower()]
    if args.list:
        for m in chosen:
            print(f"{m.name}  [{m.file}]  -> {', '.join(m.tests)}")
        return 0
    if not chosen:
        print(f"no mutation matches {args.select!r}")
        return 2
    outcomes = run(chosen, timeout=args.timeout, baseline=not args.no_baseline)
    text = table(outcomes)
    print()
    print(text)
    if args.report:
        args.report.write_text(text + "\n")
    return 1 if any(o.status in ("SURVIVED", "ERROR") for o in outcomes) else 0


if __name__ == "__main__":
    sys.exit(main())
