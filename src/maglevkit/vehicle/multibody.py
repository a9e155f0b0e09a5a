"""A small planar multibody description: rigid bodies, spring-dampers, force points.

A vehicle part is written once as data - bodies, force elements and force points - and
:class:`PlanarMultibody` turns it into the linear equations of motion, as NumPy matrices and
as CasADi functions that every evaluation path (a compiled step, a reference loop, an
optimiser) shares.  :func:`derive_sympy` derives the same equations independently with
``sympy.physics.mechanics`` (Lagrange's method, exact rotations), and the tests compare both.

**Plane and coordinates.**  The motion lies in one plane with a horizontal coordinate ``y``
and a vertical coordinate ``z`` (positive **downward**, like every vertical displacement in
:mod:`maglevkit.vehicle`), and rotations ``phi`` about the axis normal to the plane.  For
the cross-section of a vehicle ``y`` is lateral (positive to the right looking forward),
``z`` vertical and ``phi`` the roll angle (``phi > 0`` lowers the right side).  Each body
has its centre of mass at ``(y_b, z_b)`` in the reference configuration and up to three
degrees of freedom, its displacements ``(y, z, phi)`` from there (``RigidBody.dofs`` picks
the free ones; the others are held at zero).

**Kinematics.**  A point with offset ``(d_y, d_z)`` from a body's centre of mass is at

    r = (y_b + y + d_y cos(phi) - d_z sin(phi),  z_b + z + d_y sin(phi) + d_z cos(phi))
      ~ (y_b + d_y + y - d_z phi,                  z_b + d_z + z + d_y phi)     |phi| << 1

**Small-angle linearisation.**  The equations are linearised at the reference
configuration ``q = q' = 0`` with zero point forces:

    M q'' + C q' + K q = B F + G a + Q_ext,

``M = diag(m, m, J)`` (exactly constant for planar rigid bodies about their centres of
mass), ``K = sum_e k_e g_e g_e^T`` and ``C = sum_e c_e g_e g_e^T`` with
``g_e = d(Delta_e)/dq``, ``B[:, p] = (d r_p/dq)^T e_p`` for force ``F_p`` acting along the
unit direction ``e_p`` at point ``p``, and ``G`` the generalised force of a uniform
acceleration field ``a = (a_y, a_z)`` acting on every mass (gravity ``(0, g)`` on a level
track; centrifugal and superelevation terms in a curve, see
:mod:`maglevkit.vehicle.crosssection`).  What the linearisation leaves out is of second
order in the angles (``|sin(phi) - phi| <= |phi|^3/6``, ``1 - cos(phi) <= phi^2/2``) or in
products of forces and angles: the roll stiffness of preloaded springs and of forces acting
at rotated points (``F_0 d phi``, the "pendulum" terms), which
:meth:`PlanarMultibody.preload_stiffness` adds about an operating point.  A spring-damper
acts along a direction fixed in the plane (its attachment points move by millimetres against element
lengths of decimetres), and its deflection is zero in the reference configuration (a
static preload is carried as part of the equilibrium ``q``).

**The heave-pitch model in this form.**  :class:`~maglevkit.vehicle.VehicleMechanics` is
the same kind of system in the vertical longitudinal plane: take ``y`` as the train
coordinate ``xi`` (bodies at ``(xi_b, 0)``), ``dofs=("z", "phi")`` with ``phi`` the pitch
angle (``phi > 0`` lowers the rear, as ``theta`` there), vertical spring-dampers for the air
springs and for the joints between car bodies, and vertical force points (direction
``-z``: magnet attraction upward) at the circuit or pole positions; its ``B`` is this
``-B``.  It is built on this class: ``VehicleMechanics.system`` is that description, and
its matrices are the ones here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..validation import real_number
from .zoh import exact_zoh_step, second_order_state_matrices

__all__ = ["RigidBody", "SpringDamper", "ForcePoint", "PlanarMultibody", "derive_sympy",
           "DOF_KINDS", "DIRECTIONS"]

DOF_KINDS = ("y", "z", "phi")
#: Unit vectors ``(e_y, e_z)`` of the allowed directions (``z`` positive downward).
DIRECTIONS: dict[str, tuple[float, float]] = {"+y": (1.0, 0.0), "-y": (-1.0, 0.0),
                                              "+z": (0.0, 1.0), "-z": (0.0, -1.0)}


@dataclass(frozen=True)
class RigidBody:
    """A rigid body of the plane.

    Parameters
    ----------
    name : str
        Unique label, e.g. ``"car_body"``.
    mass_kg : float
        Mass [kg], > 0.
    inertia_kg_m2 : float
        Moment of inertia about the centre of mass, normal to the plane [kg m^2], > 0.
    centre_m : tuple of float
        ``(y, z)`` of the centre of mass in the reference configuration [m] (``z`` down).
    dofs : tuple of str, default ("y", "z", "phi")
        The free degrees of freedom, a subset of ``("y", "z", "phi")`` in that order.
    """

    name: str
    mass_kg: float
    inertia_kg_m2: float
    centre_m: tuple[float, float]
    dofs: tuple[str, ...] = DOF_KINDS


@dataclass(frozen=True)
class SpringDamper:
    """A linear spring and a viscous damper in parallel along a fixed direction.

    Its deflection is ``Delta = e . (r_a - r_b) - (the same at q = 0)`` with ``e`` the unit
    vector of ``direction``; the element force ``k Delta + c Delta'`` acts on ``a`` along
    ``-e`` and on ``b`` along ``+e`` (a compressed vertical spring with ``a`` above ``b`` and
    ``e = +z`` pushes ``a`` up and ``b`` down).

    Parameters
    ----------
    name : str
        Label, e.g. ``"air_spring_left.z"``.
    body_a, body_b : str or None
        Names of the two bodies; None: the ground (fixed in the plane).
    point_a_m, point_b_m : tuple of float
        ``(y, z)`` of the attachment points in the reference configuration [m].
    direction : str
        ``"y"`` or ``"z"`` (``e = +y`` or ``+z``).
    stiffness_N_per_m : float
        Stiffness k [N/m], >= 0.
    damping_N_s_per_m : float
        Damping c [N s/m], >= 0.
    preload_N : float, default 0
        Static force ``f_0`` at zero deflection [N] (an air spring's pressure carrying its
        share of the weight): the element force is ``f_0 + k Delta + c Delta'``, its
        potential ``f_0 Delta + k Delta^2/2``.
    """

    name: str
    body_a: str | None
    point_a_m: tuple[float, float]
    body_b: str | None
    point_b_m: tuple[float, float]
    direction: str
    stiffness_N_per_m: float
    damping_N_s_per_m: float
    preload_N: float = 0.0


@dataclass(frozen=True)
class ForcePoint:
    """A point of a body where an external force of given direction acts (a magnet).

    A positive force ``F`` acts on the body along ``direction`` (a levitation magnet under
    the stator: ``"-z"``, attraction upward; a guidance magnet outboard of the left rail:
    ``"+y"``).  The air gap to the rail closes when the point moves along ``direction``:
    ``s = s_0 - e . (r - r_0)``.

    Parameters
    ----------
    name : str
        Label, e.g. ``"levitation_left"``.
    body : str
        Name of the body carrying the point.
    point_m : tuple of float
        ``(y, z)`` of the point in the reference configuration [m].
    direction : str
        ``"+y"``, ``"-y"``, ``"+z"`` or ``"-z"``.
    """

    name: str
    body: str
    point_m: tuple[float, float]
    direction: str


def _pair(value: Any, what: str) -> tuple[float, float]:
    try:
        a, b = value
    except (TypeError, ValueError):
        raise InputError(f"{what} = {value!r}: expected a (y, z) pair of numbers [m]") from None
    return real_number(a, f"{what}[0]", "m"), real_number(b, f"{what}[1]", "m")


class PlanarMultibody:
    """Linear equations of motion of planar rigid bodies (see the module docstring).

    Parameters
    ----------
    bodies : sequence of RigidBody
        The bodies, unique names; their free DOFs make ``q`` in body order.
    elements : sequence of SpringDamper
        Spring-dampers between bodies or between a body and the ground.
    force_points : sequence of ForcePoint
        Points where the forces ``F`` (one per point) act.

    Raises
    ------
    InputError
        Duplicate or unknown body names, a DOF or direction not allowed, non-positive
        masses or inertias, negative stiffness or damping, non-finite positions.

    Attributes
    ----------
    dof_names : tuple of str
        ``"<body>.<dof>"`` of every generalised coordinate.
    n_dof : int
        Number of generalised coordinates.
    M, C, K : ndarray (n_dof, n_dof)
        Mass [kg, kg m^2], damping and stiffness matrices.
    B : ndarray (n_dof, n_points)
        Generalised force of a unit force at each force point [-, m].
    G : ndarray (n_dof, 2)
        Generalised force of a unit acceleration field ``(a_y, a_z)`` [kg, kg m].
    gap_matrix : ndarray (n_points, n_dof)
        Change of each force point's air gap per unit ``q``: ``s - s_0 = gap_matrix q``.
    preload_N : ndarray (n_elements,)
        The elements' static forces ``f_0`` [N].
    Q_preload : ndarray (n_dof,)
        Their generalised force ``-sum_e f_0,e g_e`` [N, N m] (in every evaluation of
        ``Q``).
    """

    def __init__(self, bodies: Sequence[RigidBody], elements: Sequence[SpringDamper],
                 force_points: Sequence[ForcePoint]) -> None:
        self.bodies = tuple(bodies)
        self.elements = tuple(elements)
        self.force_points = tuple(force_points)
        names = [b.name for b in self.bodies]
        if not self.bodies or len(set(names)) != len(names):
            raise InputError(f"bodies = {names}: expected at least one body, unique names")
        self._index = {n: i for i, n in enumerate(names)}
        self._centre: list[tuple[float, float]] = []
        dof_names: list[str] = []
        self._cols: list[dict[str, int]] = []
        for b in self.bodies:
            real_number(b.mass_kg, f"body {b.name!r} mass_kg", "kg", positive=True)
            real_number(b.inertia_kg_m2, f"body {b.name!r} inertia_kg_m2", "kg m^2",
                        positive=True)
            self._centre.append(_pair(b.centre_m, f"body {b.name!r} centre_m"))
            if (not b.dofs or len(set(b.dofs)) != len(b.dofs)
                    or any(d not in DOF_KINDS for d in b.dofs)):
                raise InputError(f"body {b.name!r} dofs = {b.dofs!r}: expected distinct names "
                                 f"from {DOF_KINDS}")
            cols = {}
            for d in DOF_KINDS:
                if d in b.dofs:
                    cols[d] = len(dof_names)
                    dof_names.append(f"{b.name}.{d}")
            self._cols.append(cols)
        self.dof_names = tuple(dof_names)
        self.n_dof = len(dof_names)
        for e in self.elements:
            for body in (e.body_a, e.body_b):
                self._body(body, f"element {e.name!r}")
            _pair(e.point_a_m, f"element {e.name!r} point_a_m")
            _pair(e.point_b_m, f"element {e.name!r} point_b_m")
            if e.direction not in ("y", "z"):
                raise InputError(f"element {e.name!r} direction = {e.direction!r}: expected "
                                 "'y' or 'z'")
            real_number(e.stiffness_N_per_m, f"element {e.name!r} stiffness", "N/m",
                        nonnegative=True)
            real_number(e.damping_N_s_per_m, f"element {e.name!r} damping", "N s/m",
                        nonnegative=True)
            real_number(e.preload_N, f"element {e.name!r} preload_N", "N")
        for p in self.force_points:
            if p.body is None:
                raise InputError(f"force point {p.name!r}: body None; a force point needs a "
                                 "body")
            self._body(p.body, f"force point {p.name!r}")
            _pair(p.point_m, f"force point {p.name!r} point_m")
            if p.direction not in DIRECTIONS:
                raise InputError(f"force point {p.name!r} direction = {p.direction!r}: "
                                 f"expected one of {', '.join(DIRECTIONS)}")
        self._assemble()

    def _body(self, name: str | None, where: str) -> int | None:
        if name is None:
            return None
        if name not in self._index:
            raise InputError(f"{where}: body {name!r} is not one of {list(self._index)} "
                             "(or None for the ground)")
        return self._index[name]

    # ------------------------------------------------------------------ kinematics
    def point_jacobian(self, body: str | None, point_m: tuple[float, float]) -> np.ndarray:
        """``d r / dq`` of a body point at ``q = 0`` (small angles): (2, n_dof).

        Parameters
        ----------
        body : str or None
            Body name (None: the ground, a zero Jacobian).
        point_m : tuple of float
            ``(y, z)`` of the point in the reference configuration [m].

        Returns
        -------
        ndarray (2, n_dof)
            Rows ``y`` and ``z``: 1 in the body's own ``y``/``z`` column, ``-d_z`` and
            ``d_y`` [m] in its ``phi`` column (``(d_y, d_z)`` the offset from the centre).
        """
        jac = np.zeros((2, self.n_dof))
        b = self._body(body, "point_jacobian")
        if b is None:
            return jac
        py, pz = _pair(point_m, "point_m")
        dy, dz = py - self._centre[b][0], pz - self._centre[b][1]
        cols = self._cols[b]
        if "y" in cols:
            jac[0, cols["y"]] = 1.0
        if "z" in cols:
            jac[1, cols["z"]] = 1.0
        if "phi" in cols:
            jac[0, cols["phi"]] = -dz
            jac[1, cols["phi"]] = dy
        return jac

    def _assemble(self) -> None:
        n = self.n_dof
        self.M = np.zeros((n, n))
        self.G = np.zeros((n, 2))
        for b, body in enumerate(self.bodies):
            for d, c in self._cols[b].items():
                self.M[c, c] = body.inertia_kg_m2 if d == "phi" else body.mass_kg
                if d in ("y", "z"):
                    self.G[c, DOF_KINDS.index(d)] = body.mass_kg
        self.K = np.zeros((n, n))
        self.C = np.zeros((n, n))
        self.element_matrix = np.zeros((len(self.elements), n))
        for i, e in enumerate(self.elements):
            row = 0 if e.direction == "y" else 1
            g = (self.point_jacobian(e.body_a, e.point_a_m)[row]
                 - self.point_jacobian(e.body_b, e.point_b_m)[row])
            self.element_matrix[i] = g
            self.K += e.stiffness_N_per_m * np.outer(g, g)
            self.C += e.damping_N_s_per_m * np.outer(g, g)
        self.B = np.zeros((n, len(self.force_points)))
        for p, fp in enumerate(self.force_points):
            self.B[:, p] = np.asarray(DIRECTIONS[fp.direction]) @ self.point_jacobian(
                fp.body, fp.point_m)
        self.gap_matrix = -self.B.T.copy()
        self.stiffness_N_per_m = np.array([e.stiffness_N_per_m for e in self.elements])
        self.preload_N = np.array([e.preload_N for e in self.elements], dtype=float)
        # the preloads' generalised force: f_0 acts on a along -e and on b along +e
        self.Q_preload = -self.element_matrix.T @ self.preload_N

    # ------------------------------------------------------------------ NumPy
    def generalised_forces(self, q: Any, q_dot: Any, forces_N: Any, field_m_per_s2: Any,
                           external: Any = 0.0) -> np.ndarray:
        """``Q = -K q - C q' + B F + G a + Q_pre + Q_ext`` (NumPy; inputs not checked;
        ``Q_pre = -sum_e f_0,e g_e`` the elements' preloads, :attr:`Q_preload`).

        Parameters
        ----------
        q, q_dot : array_like (..., n_dof)
            Generalised displacements [m, rad] and velocities [m/s, rad/s].
        forces_N : array_like (..., n_points)
            Force at each force point along its direction [N].
        field_m_per_s2 : array_like (..., 2)
            Uniform acceleration field ``(a_y, a_z)`` on every mass [m/s^2].
        external : array_like (..., n_dof), default 0
            Further generalised forces [N, N m].

        Returns
        -------
        ndarray (..., n_dof)
            Generalised forces [N, N m].
        """
        return (-np.asarray(q) @ self.K.T - np.asarray(q_dot) @ self.C.T
                + np.asarray(forces_N) @ self.B.T + np.asarray(field_m_per_s2) @ self.G.T
                + self.Q_preload + external)

    def accelerations(self, q: Any, q_dot: Any, forces_N: Any, field_m_per_s2: Any,
                      external: Any = 0.0) -> np.ndarray:
        """``q'' = M^-1 Q`` (NumPy; the same law as :meth:`casadi_functions` ``"rhs"``).

        Parameters
        ----------
        q, q_dot : array_like (..., n_dof)
            Generalised displacements [m, rad] and velocities [m/s, rad/s].
        forces_N : array_like (..., n_points)
            Force at each force point along its direction [N].
        field_m_per_s2 : array_like (..., 2)
            Uniform acceleration field ``(a_y, a_z)`` [m/s^2].
        external : array_like (..., n_dof), default 0
            Further generalised forces [N, N m].

        Returns
        -------
        ndarray (..., n_dof)
            ``q''`` [m/s^2, rad/s^2].
        """
        return self.generalised_forces(q, q_dot, forces_N, field_m_per_s2, external) / np.diag(
            self.M)

    def element_deflections(self, q: Any) -> np.ndarray:
        """Deflection ``Delta_e`` of every spring-damper [m] (axis -1 over elements).

        Parameters
        ----------
        q : array_like (..., n_dof)
            Generalised displacements [m, rad].

        Returns
        -------
        ndarray (..., n_elements)
            Deflections [m] in the order of :attr:`elements`.
        """
        return np.asarray(q) @ self.element_matrix.T

    def energy_J(self, q: Any, q_dot: Any, field_m_per_s2: Any = (0.0, 0.0)) -> np.ndarray:
        """Kinetic plus potential energy, body by body and element by element (not from
        ``M`` and ``K``) [J].

        ``T = sum (m y'^2 + m z'^2 + J phi'^2)/2``, ``V = sum_e (f_0,e Delta_e + k_e
        Delta_e^2/2) - sum_b m_b a . (y_b, z_b)`` (preloads; the field's potential; gravity
        ``a = (0, g)``).

        Parameters
        ----------
        q, q_dot : array_like (..., n_dof)
            Generalised displacements [m, rad] and velocities [m/s, rad/s].
        field_m_per_s2 : array_like (2,), default (0, 0)
            Uniform acceleration field ``(a_y, a_z)`` [m/s^2].

        Returns
        -------
        ndarray (...)
            Energy [J].
        """
        q, qd = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        a = np.asarray(field_m_per_s2, dtype=float)
        kin = np.zeros(q.shape[:-1])
        defl = self.element_deflections(q)
        pot = 0.5 * (defl ** 2 @ self.stiffness_N_per_m) + defl @ self.preload_N
        for b, body in enumerate(self.bodies):
            for d, c in self._cols[b].items():
                if d == "phi":
                    kin = kin + 0.5 * body.inertia_kg_m2 * qd[..., c] ** 2
                else:
                    kin = kin + 0.5 * body.mass_kg * qd[..., c] ** 2
                    pot = pot - body.mass_kg * a[DOF_KINDS.index(d)] * q[..., c]
        return kin + pot

    def state_matrices(self, *, damping: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """``x' = A x + Bq Q`` with ``x = [q; q']`` and generalised forces ``Q``.

        Parameters
        ----------
        damping : bool, default True
            Include the dampers; False: the undamped system.

        Returns
        -------
        (A, Bq) : ndarray (2 n_dof, 2 n_dof), ndarray (2 n_dof, n_dof)
        """
        return second_order_state_matrices(self.M, self.K, self.C, damping=damping)

    def discretize(self, dt_s: float, *, damping: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Exact zero-order-hold step ``x+ = Ad x + Bd Q`` for generalised forces held over
        ``dt_s``: ``[Ad Bd] = expm([[A, Bq], [0, 0]] dt)`` of :meth:`state_matrices`.

        Parameters
        ----------
        dt_s : float
            Step [s], finite and > 0.
        damping : bool, default True
            Include the dampers.

        Returns
        -------
        (Ad, Bd) : ndarray (2 n_dof, 2 n_dof), ndarray (2 n_dof, n_dof)

        Raises
        ------
        InputError
            ``dt_s`` not a finite number > 0.
        """
        dt_s = real_number(dt_s, "dt_s", "s", positive=True)
        a, bq = self.state_matrices(damping=damping)
        return exact_zoh_step(a, bq, dt_s)

    def preload_stiffness(self, element_forces_N: Any, forces_N: Any) -> np.ndarray:
        """Stiffness of static preloads about an operating point with level bodies.

        Linearised at ``q = 0`` with the element forces ``f_e`` (``k Delta + preload``,
        positive as in :class:`SpringDamper`) and point forces ``F_p`` held, the exact
        rotation adds the "pendulum" terms the small-angle matrices leave out: a point
        ``r = c + R(phi) d`` has ``d^2 r/d phi^2 = -d`` at ``phi = 0``, so

            K_pre[phi_a, phi_a] -= f_e e.d_a,   K_pre[phi_b, phi_b] += f_e e.d_b,
            K_pre[phi, phi]     += F_p e_p.d_p       (d: offset from the centre of mass)

        (a support force pushing a body up from a point below its centre of mass lowers
        its roll stiffness by ``F h``).  The total stiffness about that operating point is
        ``K + K_pre`` (checked against :func:`derive_sympy` with the same preloads).

        Parameters
        ----------
        element_forces_N : array_like (n_elements,)
            Force of every spring-damper at the operating point [N].
        forces_N : array_like (n_points,)
            Force at every force point at the operating point [N].

        Returns
        -------
        ndarray (n_dof, n_dof)
            Diagonal in the ``phi`` coordinates [N m/rad].

        Raises
        ------
        InputError
            Wrong lengths or non-finite values.
        """
        fe = np.asarray(element_forces_N, dtype=float).ravel()
        fp = np.asarray(forces_N, dtype=float).ravel()
        if fe.shape != (len(self.elements),) or fp.shape != (len(self.force_points),) \
                or not (np.isfinite(fe).all() and np.isfinite(fp).all()):
            raise InputError(f"element_forces_N ({fe.size} values) and forces_N ({fp.size}) "
                             f"need one finite value per element ({len(self.elements)}) and "
                             f"per force point ({len(self.force_points)}) [N]")
        k = np.zeros((self.n_dof, self.n_dof))

        def add(body: str | None, point: tuple[float, float], unit: tuple[float, float],
                force: float) -> None:
            b = self._body(body, "preload_stiffness")
            if b is None or "phi" not in self._cols[b]:
                return
            c = self._cols[b]["phi"]
            d = (point[0] - self._centre[b][0], point[1] - self._centre[b][1])
            k[c, c] += force * (unit[0] * d[0] + unit[1] * d[1])

        for e, f in zip(self.elements, fe, strict=True):
            unit = (1.0, 0.0) if e.direction == "y" else (0.0, 1.0)
            add(e.body_a, e.point_a_m, unit, -f)
            add(e.body_b, e.point_b_m, unit, f)
        for p, f in zip(self.force_points, fp, strict=True):
            add(p.body, p.point_m, DIRECTIONS[p.direction], f)
        return k

    def natural_frequencies_Hz(self, stiffness: Any = None) -> np.ndarray:
        """Undamped natural frequencies ``sqrt(eig(M^-1 K))/(2 pi)``, ascending [Hz].

        Parameters
        ----------
        stiffness : array_like (n_dof, n_dof), optional
            The stiffness matrix to use (e.g. ``K + preload_stiffness(...)``); default
            :attr:`K`.

        Returns
        -------
        ndarray (n_dof,)
            Frequencies [Hz]; rigid-body modes (zero stiffness) give 0.
        """
        kk = self.K if stiffness is None else np.asarray(stiffness, dtype=float)
        m_half = 1.0 / np.sqrt(np.diag(self.M))
        ev = np.linalg.eigvalsh(m_half[:, None] * kk * m_half[None, :])
        return np.sqrt(np.clip(ev, 0.0, None)) / (2.0 * np.pi)

    # ------------------------------------------------------------------ CasADi
    def casadi_functions(self) -> dict[str, Any]:
        """The equations as CasADi functions, built from the same matrices as NumPy.

        Returns
        -------
        dict of str to casadi.Function
            ``"matrices"``: ``() -> (M, C, K, B, G)``;
            ``"generalised_forces"``: ``(q, q_dot, F, a, Q_ext) -> Q``;
            ``"rhs"``: ``(q, q_dot, F, a, Q_ext) -> q''``;
            ``"gaps"``: ``q -> s - s_0`` (air-gap change of every force point [m]).
            Units as :meth:`accelerations`.
        """
        import casadi as ca

        n, npt = self.n_dof, self.B.shape[1]
        q, qd = ca.SX.sym("q", n), ca.SX.sym("q_dot", n)
        f, a, qe = ca.SX.sym("F", npt), ca.SX.sym("a", 2), ca.SX.sym("Q_ext", n)
        gen = (-ca.mtimes(ca.DM(self.K), q) - ca.mtimes(ca.DM(self.C), qd)
               + ca.mtimes(ca.DM(self.B), f) + ca.mtimes(ca.DM(self.G), a)
               + ca.DM(self.Q_preload) + qe)
        minv = ca.DM(1.0 / np.diag(self.M))
        ins, names = [q, qd, f, a, qe], ["q", "q_dot", "F", "a", "Q_ext"]
        return {
            "matrices": ca.Function("multibody_matrices", [],
                                    [ca.DM(m) for m in (self.M, self.C, self.K, self.B,
                                                        self.G)],
                                    [], ["M", "C", "K", "B", "G"]),
            "generalised_forces": ca.Function("multibody_forces", ins, [gen], names, ["Q"]),
            "rhs": ca.Function("multibody_rhs", ins, [minv * gen], names, ["q_ddot"]),
            "gaps": ca.Function("multibody_gaps", [q],
                                [ca.mtimes(ca.DM(self.gap_matrix), q)], ["q"], ["ds"]),
        }


def derive_sympy(system: PlanarMultibody, *, element_forces_N: Any = None,
                 forces_N: Any = None) -> dict[str, np.ndarray]:
    """Derive ``system``'s linear equations independently with sympy.physics.mechanics.

    Lagrange's equations from ``T`` and ``V`` of the bodies with the **exact** rotation
    (body frames rotated about the plane's normal, points at their exact positions),
    ``V = sum k Delta^2/2`` with the exact deflection along each element's direction, the
    acceleration field as a force ``m a`` at every centre of mass, dampers and the point
    forces as forces at the exact points; then linearised at ``q = q' = 0`` and the
    point forces ``F = F_0``; each element may carry a preload force ``f_e`` at
    ``q = 0`` (potential ``f_e Delta + k Delta^2/2``).  With zero preloads and forces this
    is the small-angle system; otherwise ``K`` includes the preload stiffness
    (:meth:`PlanarMultibody.preload_stiffness`).

    Parameters
    ----------
    system : PlanarMultibody
        The model whose bodies, elements and force points are rederived.
    element_forces_N : array_like (n_elements,), optional
        Element forces ``f_e`` at ``q = 0`` [N] (default zero; keyword only).
    forces_N : array_like (n_points,), optional
        Point forces ``F_0`` of the operating point [N] (default zero; keyword only).

    Returns
    -------
    dict of str to ndarray
        ``M``, ``C``, ``K`` (n_dof, n_dof), ``B`` (n_dof, n_points), ``G`` (n_dof, 2) and
        ``mass_matrix_q`` (the exact mass matrix at a non-zero state).
    """
    import sympy as sp
    import sympy.physics.mechanics as me

    n = system.n_dof
    q = list(me.dynamicsymbols(f"q0:{n}")) if n > 1 else [me.dynamicsymbols("q0")]
    qd = [me.dynamicsymbols(f"q{i}", 1) for i in range(n)]
    N = me.ReferenceFrame("N")             # N.x: y (horizontal), N.z: z (down)
    O = me.Point("O")
    O.set_vel(N, 0)
    ay, az = sp.symbols("a_y a_z")
    forces: list[tuple[Any, Any]] = []
    frames: list[Any] = []
    cogs: list[Any] = []
    rigid = []
    for b, body in enumerate(system.bodies):
        cols = system._cols[b]

        def coord(d: str, cols: dict[str, int] = cols) -> Any:
            return q[cols[d]] if d in cols else sp.Integer(0)

        def rate(d: str, cols: dict[str, int] = cols) -> Any:
            return qd[cols[d]] if d in cols else sp.Integer(0)

        fr = N.orientnew(f"R{b}", "Axis", [-coord("phi"), N.y])   # R.x = cos N.x + sin N.z
        fr.set_ang_vel(N, -rate("phi") * N.y)
        yc, zc = system._centre[b]
        g = O.locatenew(f"G{b}", (sp.Float(yc) + coord("y")) * N.x
                        + (sp.Float(zc) + coord("z")) * N.z)
        g.set_vel(N, rate("y") * N.x + rate("z") * N.z)
        m = sp.Float(body.mass_kg)
        inertia = me.inertia(fr, 0, sp.Float(body.inertia_kg_m2), 0)
        rigid.append(me.RigidBody(f"body{b}", g, fr, m, (inertia, g)))
        frames.append(fr)
        cogs.append(g)
        forces.append((g, m * ay * N.x + m * az * N.z))

    def point(body: str | None, pm: tuple[float, float], name: str) -> Any:
        if body is None:
            pt = O.locatenew(name, sp.Float(pm[0]) * N.x + sp.Float(pm[1]) * N.z)
            pt.set_vel(N, 0)
            return pt
        b = system._index[body]
        dy, dz = pm[0] - system._centre[b][0], pm[1] - system._centre[b][1]
        pt = cogs[b].locatenew(name, sp.Float(dy) * frames[b].x + sp.Float(dz) * frames[b].z)
        pt.v2pt_theory(cogs[b], N, frames[b])
        return pt

    potential = sp.Integer(0)
    zero = {qq: 0 for qq in q}
    fe0 = (np.zeros(len(system.elements)) if element_forces_N is None
           else np.asarray(element_forces_N, dtype=float).ravel())
    fp0 = (np.zeros(len(system.force_points)) if forces_N is None
           else np.asarray(forces_N, dtype=float).ravel())
    for i, e in enumerate(system.elements):
        unit = N.x if e.direction == "y" else N.z
        pa, pb = point(e.body_a, e.point_a_m, f"A{i}"), point(e.body_b, e.point_b_m, f"B{i}")
        delta = (pa.pos_from(O) - pb.pos_from(O)).dot(unit)
        dev = delta - delta.subs(zero)
        potential += sp.Float(e.stiffness_N_per_m) * dev ** 2 / 2 + sp.Float(fe0[i]) * dev
        drate = (pa.vel(N) - pb.vel(N)).dot(unit)
        c = sp.Float(e.damping_N_s_per_m)
        forces.append((pa, -c * drate * unit))
        forces.append((pb, c * drate * unit))
    fsym = list(sp.symbols(f"F0:{len(system.force_points)}"))
    for p, fp in enumerate(system.force_points):
        ey, ez = DIRECTIONS[fp.direction]
        forces.append((point(fp.body, fp.point_m, f"P{p}"),
                       fsym[p] * (sp.Float(ey) * N.x + sp.Float(ez) * N.z)))
    lag = me.Lagrangian(N, *rigid) - potential
    lm = me.LagrangesMethod(lag, q, forcelist=forces, frame=N)
    lm.form_lagranges_equations()
    us = sp.symbols(f"u0:{n}")
    xs = sp.symbols(f"x0:{n}")
    fo = me.msubs(me.msubs(lm.forcing, dict(zip(qd, us, strict=True))),
                  dict(zip(q, xs, strict=True)))
    mm = me.msubs(lm.mass_matrix, dict(zip(q, xs, strict=True)))
    allv = (*xs, *us, *fsym, ay, az)

    base = {v: 0 for v in allv}
    base.update({f: float(f0) for f, f0 in zip(fsym, fp0, strict=True)})

    def column(var: Any) -> np.ndarray:
        e = fo.xreplace({v: b for v, b in base.items() if v is not var})
        return np.array(e.diff(var).xreplace({var: base[var]}), dtype=float).ravel()

    def block(vs: Sequence[Any]) -> np.ndarray:
        return np.column_stack([column(v) for v in vs]) if vs else np.zeros((n, 0))

    trial = {v: 0.05 * (i + 1) for i, v in enumerate(xs)}
    return {"M": np.array(mm.xreplace({v: 0 for v in xs}), dtype=float),
            "K": -block(xs), "C": -block(us), "B": block(fsym), "G": block([ay, az]),
            "mass_matrix_q": np.array(mm.xreplace(trial), dtype=float)}
