"""Heave-pitch multibody model of the train: car bodies, levitation frames, air springs, joints.

Bodies (rigid, planar): per section one car body and ``n`` levitation frames, each with a
heave ``z`` (positive **downward**, like the guideway deflection) and a pitch ``theta``
about its centre of mass at train coordinate ``xi_b`` (``xi`` = distance behind the nose,
positive rearwards).  A body-fixed point at ``xi`` is displaced vertically by

    u(xi) = z_b + sin(theta_b) (xi - xi_b)            (exact, planar rotation)
          ~ z_b + theta_b (xi - xi_b)                  (small angles, |theta| << 1)

(``theta > 0`` lowers the rear).  Force elements: vertical air springs (stiffness ``k_s``,
damping ``c_s``) between a frame point and the car-body point above it; vertical
spring-dampers (``k_j``, ``c_j``) between the rear end of one car body and the front end of
the next; gravity at every centre of mass; the magnet forces ``F`` (attraction, acting
**upward** on the frame at the pole or circuit positions; equal and opposite on the
guideway).  With the small-angle kinematics the equations of motion are linear::

    M q'' + C q' + K q = Q_g - B F,      q = [z_1, theta_1, z_2, theta_2, ...]

    M = diag(m_b, J_b),   K = sum_e k_e g_e g_e^T,   C = sum_e c_e g_e g_e^T,
    g_e = d(Delta_e)/dq   (Delta_e = u_a(xi_e) - u_b(xi_e), the element's compression),
    Q_g = sum_b m_b g e_z,b,    B[:, p] = d u(xi_p)/dq of the frame carrying force p.

:class:`VehicleMechanics` describes the bodies, force elements and force points as a
:class:`~maglevkit.vehicle.multibody.PlanarMultibody` (the vertical plane: bodies at
``(xi_b, 0)`` with ``dofs = ("z", "phi")``, vertical spring-dampers, force points acting
along ``-z``), which composes ``M``, ``C``, ``K``, ``Q_g = G (0, g)`` and ``B`` (its ``-B``);
on top: the exact zero-order-hold discretisation, the static trim and a CasADi right-hand
side for optimisation.  :func:`derive_sympy` derives the same equations independently with
``sympy.physics.mechanics`` (Lagrange's equations from kinetic and potential energy with
the exact rotation, dampers and forces as generalised forces) and linearises them at
``q = 0``; the tests compare both.  The exact large-angle kinematics only add terms of
second order in ``theta`` (``|sin theta - theta| < theta^3/6``: < 1e-12 m over 25 m at the
mrad pitch angles of a levitating vehicle), which the linear model neglects.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..plant import STANDARD_GRAVITY
from ..validation import describe, real_array, real_number, renamed_keywords
from .train import TrainData
from .zoh import exact_zoh_step, second_order_state_matrices

__all__ = ["VehicleMechanics", "ForceElement", "derive_sympy"]


@dataclass(frozen=True)
class ForceElement:
    """A vertical spring-damper between body ``a`` at ``xi_a`` and body ``b`` at ``xi_b``.

    Its compression is ``Delta = u_a(xi_a) - u_b(xi_b)`` (``a`` above ``b``: the car body
    above a frame, or the front car body's rear end above the next one's front end);
    force ``k Delta + c Delta'`` pushes ``a`` up and ``b`` down.

    Parameters
    ----------
    name : str
        Label, e.g. ``"spring1.2"`` or ``"joint1"``.
    body_a, body_b : int
        Body indices (car bodies first, then frames; see
        :attr:`VehicleMechanics.body_names`).
    xi_a_m, xi_b_m : float
        Train coordinates of the attachment points [m] (distance behind the nose).
    stiffness_N_per_m : float
        Vertical stiffness k [N/m].
    damping_N_s_per_m : float
        Vertical damping c [N s/m].
    """

    name: str
    body_a: int
    xi_a_m: float
    body_b: int
    xi_b_m: float
    stiffness_N_per_m: float
    damping_N_s_per_m: float


@renamed_keywords(gravity="gravity_m_per_s2")
class VehicleMechanics:
    """The train's linear heave-pitch model (see the module docstring).

    Parameters
    ----------
    train : TrainData
        Masses, inertias, positions, air springs and joints of the train
        (from :func:`~maglevkit.vehicle.load_vehicle`).
    force_points_m : sequence of float
        Train coordinates ``xi`` [m] where magnet forces act (circuit centres or poles);
        finite, one per force point.
    force_frames : sequence of int
        Frame index (0-based, nose first) carrying each force point, in
        ``0 .. n_frames - 1``.
    gravity_m_per_s2 : float, default STANDARD_GRAVITY
        Gravitational acceleration g [m/s^2] (9.80665; not checked; keyword only).  The old
        name ``gravity`` is a deprecated alias (constructor keyword and attribute).

    Raises
    ------
    InputError
        ``train`` not a :class:`TrainData`, points and frames of different lengths or
        non-finite points, or a frame index out of range.

    Attributes
    ----------
    body_names : tuple of str
        ``"car1" ... , "frame1" ...`` (car bodies first, then frames).
    body_centres_m, body_mass_kg, body_inertia_kg_m2 : ndarray (n_bodies,)
        Centre of mass ``xi_b`` [m], mass [kg] and pitch inertia [kg m^2] of each body.
    elements : tuple of ForceElement
        Air springs (every frame, nose first) then the inter-car joints.
    M, C, K : ndarray (n_dof, n_dof)
        Mass [kg, kg m^2], damping and stiffness matrices.
    Q_gravity : ndarray (n_dof,)
        Generalised gravity force [N, N m].
    B : ndarray (n_dof, n_points)
        Generalised force of a unit upward magnet force at each force point (``-B F``
        enters the equations).
    system : PlanarMultibody
        The multibody description the matrices come from (bodies, air springs and
        joints as vertical spring-dampers, force points acting upward).
    """

    def __init__(self, train: TrainData, force_points_m: Sequence[float],
                 force_frames: Sequence[int], *,
                 gravity_m_per_s2: float = STANDARD_GRAVITY) -> None:
        if not isinstance(train, TrainData):
            raise InputError(f"train must be TrainData (from load_vehicle), got {type(train).__name__}")
        self.train = train
        ns, nf = train.n_sections, train.n_frames
        self.n_sections, self.n_frames = ns, nf
        self.body_names = tuple([f"car{k + 1}" for k in range(ns)]
                                + [f"frame{k + 1}" for k in range(nf)])
        self.body_centres_m = np.concatenate([train.section_centres_m, train.frame_centres_m])
        self.body_mass_kg = np.concatenate([np.full(ns, train.loaded_car_body_mass_kg),
                                            np.full(nf, train.frame_total_mass_kg)])
        self.body_inertia_kg_m2 = np.concatenate([np.full(ns, train.loaded_car_body_inertia_kg_m2),
                                                  np.full(nf, train.frame_total_inertia_kg_m2)])
        self.n_bodies = ns + nf
        self.n_dof = 2 * self.n_bodies
        self.gravity_m_per_s2 = float(gravity_m_per_s2)
        elements: list[ForceElement] = []
        for f in range(nf):
            car = int(train.frame_section[f])
            xc = float(train.frame_centres_m[f])
            for j, d in enumerate(train.spring_positions_m):
                elements.append(ForceElement(f"spring{f + 1}.{j + 1}", car, xc + d, ns + f, xc + d,
                                             train.spring_stiffness_N_per_m,
                                             train.spring_damping_N_s_per_m))
        for k in range(ns - 1):
            x = (k + 1) * train.section_length_m
            elements.append(ForceElement(f"joint{k + 1}", k, x, k + 1, x,
                                         train.joint_stiffness_N_per_m,
                                         train.joint_damping_N_s_per_m))
        self.elements = tuple(elements)
        pts = np.asarray(force_points_m, dtype=float).ravel()
        frames = np.asarray(force_frames, dtype=int).ravel()
        if pts.shape != frames.shape or not np.isfinite(pts).all():
            raise InputError("force_points_m and force_frames need one finite value each per point")
        if frames.size and (frames.min() < 0 or frames.max() >= nf):
            raise InputError(f"force_frames must be frame indices 0..{nf - 1}")
        self.force_points_m = pts
        self.force_bodies = ns + frames
        self._assemble()

    # ------------------------------------------------------------------ assembly
    def point_jacobian(self, body: int, xi_m: Any) -> np.ndarray:
        """``d u(xi) / dq`` of body points (small angles): (n_points, n_dof).

        Parameters
        ----------
        body : int
            Body index (car bodies first, then frames).
        xi_m : float or array_like
            Train coordinates of the points [m] (distance behind the nose; not checked).

        Returns
        -------
        ndarray (n_points, n_dof)
            1 in the body's heave column, ``xi - xi_b`` [m] in its pitch column.
        """
        x = np.atleast_1d(np.asarray(xi_m, dtype=float))
        name = self.body_names[body]     # the multibody description's z rows
        return np.array([self.system.point_jacobian(name, (float(xi), 0.0))[1] for xi in x]
                        ).reshape(x.size, self.n_dof)

    def _assemble(self) -> None:
        """The matrices from the multibody description (:class:`PlanarMultibody`): bodies
        at ``(xi_b, 0)`` with ``dofs = ("z", "phi")`` (``phi`` the pitch ``theta``),
        vertical spring-dampers, force points acting along ``-z`` (upward); ``B`` here
        is the multibody ``-B`` (``-B F`` enters the equations)."""
        from .multibody import ForcePoint, PlanarMultibody, RigidBody, SpringDamper

        names = self.body_names
        bodies = [RigidBody(names[b], float(self.body_mass_kg[b]),
                            float(self.body_inertia_kg_m2[b]),
                            (float(self.body_centres_m[b]), 0.0), ("z", "phi"))
                  for b in range(self.n_bodies)]
        springs = [SpringDamper(e.name, names[e.body_a], (e.xi_a_m, 0.0), names[e.body_b],
                                (e.xi_b_m, 0.0), "z", e.stiffness_N_per_m,
                                e.damping_N_s_per_m) for e in self.elements]
        points = [ForcePoint(f"point{p + 1}", names[int(body)], (float(x), 0.0), "-z")
                  for p, (body, x) in enumerate(zip(self.force_bodies, self.force_points_m,
                                                    strict=True))]
        system = PlanarMultibody(bodies, springs, points)
        self.system = system
        self.M, self.K, self.C = system.M, system.K, system.C
        self._element_g = system.element_matrix
        self.Q_gravity = system.G @ np.array([0.0, self.gravity_m_per_s2])
        self.B = -system.B

    # ------------------------------------------------------------------ use
    @property
    def dof_names(self) -> tuple[str, ...]:
        return tuple(f"{b}.{c}" for b in self.body_names for c in ("z", "theta"))

    def element_compressions(self, q: np.ndarray) -> np.ndarray:
        """Compression ``Delta_e`` of every force element [m] (axis -1 over elements).

        Parameters
        ----------
        q : array_like (..., n_dof)
            Generalised displacements ``[z_1, theta_1, ...]`` [m, rad].

        Returns
        -------
        ndarray (..., n_elements)
            Compressions [m], in the order of :attr:`elements`.
        """
        return np.asarray(q) @ self._element_g.T

    def energy_J(self, q: np.ndarray, q_dot: np.ndarray) -> np.ndarray:
        """Kinetic energy plus spring energy, ``sum m z'^2/2 + J theta'^2/2 + sum k Delta^2/2``,
        from the bodies and elements one by one (not from ``K``) [J].

        Gravity's potential is not included.

        Parameters
        ----------
        q : array_like (..., n_dof)
            Generalised displacements [m, rad].
        q_dot : array_like (..., n_dof)
            Generalised velocities [m/s, rad/s].

        Returns
        -------
        ndarray (...)
            Energy [J].
        """
        q, qd = np.asarray(q), np.asarray(q_dot)
        kin = 0.5 * (qd[..., 0::2] ** 2 @ self.body_mass_kg + qd[..., 1::2] ** 2
                     @ self.body_inertia_kg_m2)
        k = np.array([e.stiffness_N_per_m for e in self.elements])
        return kin + 0.5 * (self.element_compressions(q) ** 2 @ k)

    def state_matrices(self, *, damping: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """``x' = A x + Bq Q`` with ``x = [q; q']`` and generalised forces ``Q`` (n_dof).

        Parameters
        ----------
        damping : bool, default True
            Include the dampers (``-M^-1 C`` block); False: the undamped system.

        Returns
        -------
        (A, Bq) : ndarray (2 n_dof, 2 n_dof) and (2 n_dof, n_dof)
            ``Q`` in [N] (heave rows) and [N m] (pitch rows).
        """
        return second_order_state_matrices(self.M, self.K, self.C, damping=damping)

    def discretize(self, dt_s: float, *, damping: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Exact zero-order-hold discretisation ``x+ = Ad x + Bd Q`` for forces held over
        ``dt_s`` (matrix exponential of ``[[A, Bq], [0, 0]] dt``).

        Parameters
        ----------
        dt_s : float
            Step [s], finite and > 0.
        damping : bool, default True
            Include the dampers (as :meth:`state_matrices`).

        Returns
        -------
        (Ad, Bd) : ndarray (2 n_dof, 2 n_dof) and (2 n_dof, n_dof)

        Raises
        ------
        InputError
            ``dt_s`` not a finite real number > 0 (Python or NumPy floats and ints; not
            a bool).
        """
        dt_s = real_number(dt_s, "dt_s", "s", positive=True)
        a, bq = self.state_matrices(damping=damping)
        return exact_zoh_step(a, bq, dt_s)

    def accelerations(self, q: np.ndarray, q_dot: np.ndarray, forces_N: np.ndarray, *,
                      gravity_force: np.ndarray | None = None) -> np.ndarray:
        """``q''`` from the equations of motion (forces: upward magnet forces per point).

        Parameters
        ----------
        q : array_like (..., n_dof)
            Generalised displacements [m, rad].
        q_dot : array_like (..., n_dof)
            Generalised velocities [m/s, rad/s].
        forces_N : array_like (..., n_points)
            Upward (attractive) magnet force at each force point [N].
        gravity_force : array_like (..., n_dof), optional
            Generalised gravity ``Q_g`` [N, N m] in place of :attr:`Q_gravity` (e.g. with
            a payload step; keyword only).

        Returns
        -------
        ndarray (..., n_dof)
            ``q''`` [m/s^2, rad/s^2] (heave positive downward).  Inputs are not checked.
        """
        q_g = self.Q_gravity if gravity_force is None else np.asarray(gravity_force)
        rhs = (q_g - np.asarray(q) @ self.K.T - np.asarray(q_dot) @ self.C.T
               - np.asarray(forces_N) @ self.B.T)
        return rhs / np.diag(self.M)

    def casadi_rhs(self) -> Any:
        """The equations as a CasADi function ``(x, F) -> x'`` (``x = [q; q']``, ``F`` the
        upward magnet forces at the force points) for optimisation and linearisation."""
        import casadi as ca

        n = self.n_dof
        x = ca.SX.sym("x", 2 * n)
        f = ca.SX.sym("F", self.B.shape[1])
        q, qd = x[:n], x[n:]
        minv = ca.DM(1.0 / np.diag(self.M))
        qdd = minv * (ca.DM(self.Q_gravity) - ca.mtimes(ca.DM(self.K), q)
                      - ca.mtimes(ca.DM(self.C), qd) - ca.mtimes(ca.DM(self.B), f))
        return ca.Function("vehicle_mechanics", [x, f], [ca.vertcat(qd, qdd)], ["x", "F"], ["xdot"])

    def static_trim(self, pole_weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Standing equilibrium with every frame at its nominal position (``z = theta = 0``).

        The car bodies settle on the air springs (``K_cc q_c = Q_g,c``); each frame's load
        (its weight plus the air-spring forces) is shared among its force points by the
        least-squares distribution ``min sum F_p^2 / w_p`` subject to the frame's force and
        moment balance, with weights ``w_p`` (the number of poles a point stands for, so
        that equal poles carry equal forces).

        Parameters
        ----------
        pole_weights : array_like (n_points,)
            Weight ``w_p`` [-] of each force point, finite and > 0.

        Returns
        -------
        (q, forces_N) : ndarray (n_dof,), ndarray (n_points,)
            The equilibrium displacements and the upward force at every point [N].

        Raises
        ------
        InputError
            ``pole_weights`` not finite numbers > 0, one per force point; or a frame
            with fewer than two force points at different positions (its force and
            moment balance has no solution).
        """
        npts = self.B.shape[1]
        w = real_array(pole_weights, "pole_weights")
        if w.shape != (npts,) or not np.all(w > 0.0):
            raise InputError(f"pole_weights = {describe(pole_weights)}: expected {npts} "
                             "numbers > 0, one per force point")
        nc = 2 * self.n_sections
        cols_of = [np.flatnonzero(self.force_bodies == self.n_sections + f)
                   for f in range(self.n_frames)]
        for f, cols in enumerate(cols_of):
            xs = np.unique(self.force_points_m[cols])
            if xs.size < 2:
                raise InputError(f"static_trim: {self.body_names[self.n_sections + f]} has "
                                 f"force points at {xs.tolist()} m; each frame needs at "
                                 "least two force points at different positions "
                                 "(force_points_m, force_frames)")
        q = np.zeros(self.n_dof)
        q[:nc] = np.linalg.solve(self.K[:nc, :nc], self.Q_gravity[:nc])
        need = self.Q_gravity - self.K @ q            # = B F on the frame rows
        forces = np.zeros(npts)
        for f, cols in enumerate(cols_of):
            rows = slice(nc + 2 * f, nc + 2 * f + 2)
            a = self.B[rows, cols]
            lam = np.linalg.solve(a @ (w[cols, None] * a.T), need[rows])
            forces[cols] = w[cols] * (a.T @ lam)
        return q, forces


def derive_sympy(mech: VehicleMechanics) -> dict[str, np.ndarray]:
    """Derive the equations of ``mech``'s bodies and elements with sympy.physics.mechanics.

    Lagrange's equations from ``T = sum m z'^2/2 + J theta'^2/2`` (rigid bodies in a planar
    frame, exact rotation about the pitch axis), ``V = sum k Delta^2/2`` with the exact
    vertical displacement of the attachment points, gravity, dampers and magnet forces as
    point forces; then linearised at ``q = q' = 0``.

    Parameters
    ----------
    mech : VehicleMechanics
        The model whose bodies, elements and force points are rederived (slow for many
        bodies: symbolic differentiation).

    Returns
    -------
    dict with ``M``, ``C``, ``K`` (n_dof, n_dof), ``Q_gravity`` (n_dof,), ``B`` (n_dof,
    n_points) and ``mass_matrix_q`` (the mass matrix at a non-zero state, to show it does not
    depend on ``q``).
    """
    import sympy as sp
    import sympy.physics.mechanics as me

    n_b = mech.n_bodies
    q = me.dynamicsymbols(f"q0:{2 * n_b}")
    qd = [me.dynamicsymbols(f"q{i}", 1) for i in range(2 * n_b)]
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    frames, cogs, bodies = [], [], []
    g = sp.Float(mech.gravity_m_per_s2)
    forces: list[tuple[Any, Any]] = []
    for b in range(n_b):
        z, th = q[2 * b], q[2 * b + 1]
        fr = N.orientnew(f"B{b}", "Axis", [-th, N.y])      # body x axis: cos th N.x + sin th N.z
        fr.set_ang_vel(N, -qd[2 * b + 1] * N.y)
        p = O.locatenew(f"G{b}", sp.Float(mech.body_centres_m[b]) * N.x + z * N.z)
        p.set_vel(N, qd[2 * b] * N.z)
        inertia = me.inertia(fr, 0, sp.Float(mech.body_inertia_kg_m2[b]), 0)
        bodies.append(me.RigidBody(f"body{b}", p, fr, sp.Float(mech.body_mass_kg[b]),
                                   (inertia, p)))
        frames.append(fr)
        cogs.append(p)
        forces.append((p, sp.Float(mech.body_mass_kg[b]) * g * N.z))

    def point(body: int, xi: float, name: str) -> Any:
        pt = cogs[body].locatenew(name, sp.Float(xi - mech.body_centres_m[body]) * frames[body].x)
        pt.v2pt_theory(cogs[body], N, frames[body])
        return pt

    potential = sp.Integer(0)
    for i, e in enumerate(mech.elements):
        pa, pb = point(e.body_a, e.xi_a_m, f"A{i}"), point(e.body_b, e.xi_b_m, f"B{i}")
        delta = (pa.pos_from(O) - pb.pos_from(O)).dot(N.z)
        delta0 = delta.subs({qq: 0 for qq in q})
        potential += sp.Float(e.stiffness_N_per_m) * (delta - delta0) ** 2 / 2
        rate = (pa.vel(N) - pb.vel(N)).dot(N.z)
        c = sp.Float(e.damping_N_s_per_m)
        forces.append((pa, -c * rate * N.z))
        forces.append((pb, c * rate * N.z))
    fsym = sp.symbols(f"F0:{mech.force_points_m.size}")
    for p_i, (body, xi) in enumerate(zip(mech.force_bodies, mech.force_points_m, strict=True)):
        forces.append((point(int(body), float(xi), f"P{p_i}"), -fsym[p_i] * N.z))
    lag = me.Lagrangian(N, *bodies) - potential
    lm = me.LagrangesMethod(lag, q, forcelist=forces, frame=N)
    lm.form_lagranges_equations()
    mm = lm.mass_matrix
    fo = lm.forcing
    # plain symbols for q' and q (derivatives first), then the Jacobians at 0 one variable
    # at a time: every other variable set to 0 first keeps the expressions small
    us = sp.symbols(f"u0:{2 * n_b}")
    xs = sp.symbols(f"x0:{2 * n_b}")
    fo = me.msubs(me.msubs(fo, dict(zip(qd, us, strict=True))), dict(zip(q, xs, strict=True)))
    mm = me.msubs(mm, dict(zip(q, xs, strict=True)))
    allv = (*xs, *us, *fsym)

    def column(var: Any) -> np.ndarray:
        others = {v: 0 for v in allv if v is not var}
        e = fo.xreplace(others)
        return np.array(e.diff(var).xreplace({var: 0}), dtype=float).ravel()

    def num(expr: Any) -> np.ndarray:
        return np.array(expr.xreplace({v: 0 for v in allv}), dtype=float)

    k_mat = -np.column_stack([column(v) for v in xs])
    c_mat = -np.column_stack([column(v) for v in us])
    b_mat = (-np.column_stack([column(v) for v in fsym]) if fsym
             else np.zeros((2 * n_b, 0)))
    trial = {v: 0.01 * (i + 1) for i, v in enumerate(xs)}
    return {"M": num(mm), "C": c_mat, "K": k_mat, "Q_gravity": num(fo).ravel(), "B": b_mat,
            "mass_matrix_q": np.array(mm.xreplace(trial), dtype=float)}
