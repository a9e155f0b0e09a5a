"""In-place stepping of a magnet bank: the co-simulation loop without per-step objects.

:meth:`MagnetBank.step <maglevkit.reduced.bank.MagnetBank.step>` returns new immutable
state and output objects and copies its inputs and outputs, which at 100 circuits costs
about as much as the compiled arithmetic itself.  A :class:`BankStepper` binds the
compiled step to arrays it owns: the caller writes voltages, gaps and gap rates into the
stepper's input arrays (or passes them to :meth:`BankStepper.advance`), calls
:meth:`~BankStepper.advance`, and reads the currents and forces from the stepper's output
arrays.  Every array keeps its identity for the stepper's life, so a co-simulation may
bind them once.  The compiled step writes into scratch buffers that are copied into the
state and output arrays only when the step is good, so a step that fails (out of the
maps, non-finite) leaves the stepper at the last good step.  The numbers are the bank's
own: the same compiled function as :meth:`MagnetBank.step`, equal to it bit for bit.

Banks with detailed members or one gap input per pole have no compiled fast path; their
stepper runs :meth:`MagnetBank.step` behind the same interface.

In a bank with shielded-gap ladder members (``MagnetBank.motion_eddy``) the state carries
the shielding eddy currents ``I_e`` too (:attr:`BankStepper.eddy_currents_A`), bound and
committed with the rest; with three-state members (``MagnetBank.n_eddy_states == 2``) the
two eddy states of every circuit, stored as the kernel reads them (``I_e1`` of every
circuit, then ``I_e2``) and shown as an ``(n_circuits, 2)`` view.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from ..models.compiled import BoundCall
from ..models.inputs import check_step, per_name_values
from ..validation import renamed_keywords
from .core import substep_count

if TYPE_CHECKING:
    from .bank import BankState, MagnetBank

__all__ = ["BankStepper"]


def _readonly(a: np.ndarray) -> np.ndarray:
    v = a.view()
    v.flags.writeable = False
    return v


class BankStepper:
    """Advance a :class:`~maglevkit.reduced.bank.MagnetBank` step by step in place.

    Made by :meth:`MagnetBank.stepper <maglevkit.reduced.bank.MagnetBank.stepper>` (which
    compiles the bank's step for ``dt`` if that has not happened yet); one stepper per
    step length.  The input arrays (:attr:`voltages_V`, :attr:`gaps_m`,
    :attr:`gap_rates_m_per_s`) belong to the stepper and are written in place (assigning
    to the attribute copies into them); the output arrays are read-only views that always
    show the last good step.  All keep their identity, so they may be bound once.

    Parameters
    ----------
    bank : MagnetBank
        The bank to advance.
    state : BankState
        Start state of ``bank``.  The inputs start at its steady state: voltages
        ``R_el I`` [V], its gaps [m] and zero gap rates [m/s].
    dt_s : float
        Step length [s], finite and > 0 (fixed for the stepper's life; deprecated alias
        ``dt``).

    Raises
    ------
    InputError
        ``state`` not a state of ``bank``, or a bad ``dt_s``.

    Attributes
    ----------
    bank : MagnetBank
    dt_s : float
        Step length [s] (read-only).
    time_s : float
        Time of the current state [s]: the start time plus one ``dt_s`` per step, summed
        as :meth:`MagnetBank.step` sums it (so ``time_s == k * dt_s`` may be off in the
        last bits; count steps where exact times matter).

    Examples
    --------
    >>> import numpy as np
    >>> import maglevkit as mk
    >>> magnet = mk.load_magnet("u-magnet")
    >>> maps = mk.build_maps(magnet, gaps_m=np.linspace(0.006, 0.016, 6),
    ...                      currents_A=np.linspace(0, 60, 13), progress=False)
    >>> bank = mk.MagnetBank({f"m{k}": maps for k in range(4)}, compiled="never")
    >>> stepper = bank.stepper(bank.initial_state(gaps_m=0.010, currents_A=20.0), dt_s=1e-3)
    >>> force = stepper.circuit_force_N            # bound once, always the last step's
    >>> for k in range(10):
    ...     stepper.voltages_V[:] = bank.resistance_ohm * 21.0   # e.g. from a controller
    ...     stepper.gaps_m[:] = 0.010                             # e.g. from the mechanics
    ...     stepper.advance()
    >>> round(stepper.time_s, 6), force.shape, bool(force[0] == stepper.circuit_force_N[0])
    (0.01, (4,), True)
    """

    __slots__ = ("_bank", "_dt", "_time", "_fast", "_u", "_g", "_gd", "_il", "_coil",
                 "_force", "_member", "_pole", "_views", "_state_gaps", "_state",
                 "_buf", "_eval", "_res", "_n_bad", "_h", "_block", "_scratch", "_ie",
                 "_substeps")

    @renamed_keywords(dt="dt_s")
    def __init__(self, bank: MagnetBank, state: BankState, dt_s: float) -> None:
        bank.check_state(state)
        self._bank = bank
        self._dt = check_step(dt_s)
        self._substeps = substep_count(self._dt, bank.max_step_s)
        nc, ng = bank.n_circuits, bank.n_gaps
        out = bank.outputs(state)
        # steady-state voltages U = R_el I (I = I_L for reduced circuits in steady state)
        i_ss = np.where(np.isnan(state.inductor_currents_A), out.currents_A,
                        state.inductor_currents_A)
        self._u = bank.resistance_ohm * i_ss
        self._g = state.gaps_m.copy()
        self._gd = np.zeros(ng)
        self._time = float(state.time_s)
        self._fast = bank.compiled_fast_path
        # state and outputs in one block [I_L | I | F | member F | gaps of the state
        # (| I_e in a ladder bank)], so that a good step is committed by one copy of the
        # kernel's block of results
        nm = len(bank.member_names)
        eddy = state.eddy_currents_A
        # (two eddy states per circuit: column-major, the kernel's layout)
        self._block = np.concatenate([out.inductor_currents_A, out.currents_A,
                                      out.circuit_force_N, out.member_force_N, state.gaps_m]
                                     + ([] if eddy is None else [eddy.ravel(order="F")]))
        ng0 = 3 * nc + nm + ng
        b = self._block
        self._il, self._coil = b[:nc], b[nc:2 * nc]
        self._force, self._member = b[2 * nc:3 * nc], b[3 * nc:3 * nc + nm]
        self._state_gaps = b[3 * nc + nm:ng0]        # the gaps of the last good state
        self._ie = None if eddy is None else b[ng0:]  # a ladder bank's I_e
        assert out.pole_force_N is not None
        self._pole = out.pole_force_N.copy()
        self._views = tuple(_readonly(a) for a in (self._il, self._coil, self._force,
                                                   self._member)
                            + (() if self._ie is None else
                               (self._ie if eddy is None or eddy.ndim == 1
                                else self._ie.reshape(eddy.shape[1], nc).T,)))
        if not self._fast:
            self._state = state
            return
        kernel = bank.step_kernel(self._dt)
        self._h = np.array([self._dt])
        # the kernel reads the state and input arrays and writes scratch buffers (copied
        # into the state and output arrays only after a good step)
        args = [self._il, self._g, self._u, self._gd, self._h]
        self._scratch = r = np.zeros_like(self._block)       # the same layout as the block
        self._res = [r[:nc], r[nc:2 * nc], r[2 * nc:3 * nc], r[3 * nc:3 * nc + nm],
                     np.zeros(1), np.zeros(nc), np.zeros(nc), r[3 * nc + nm:ng0], np.zeros(nc)]
        if self._ie is not None:                  # input 5 and output 9: I_e
            args.append(self._ie)
            self._res.append(r[ng0:])
        self._buf = BoundCall(kernel, args=dict(enumerate(args)),    # keeps the arrays alive
                              res=dict(enumerate(self._res)))
        self._eval = self._buf.eval
        self._n_bad = self._res[4]

    # ------------------------------------------------------------------ inputs
    @property
    def bank(self) -> MagnetBank:
        """The bank this stepper advances."""
        return self._bank

    @property
    def dt_s(self) -> float:
        """Step length [s] (make a new stepper for another one)."""
        return self._dt

    @property
    def voltages_V(self) -> np.ndarray:
        """Circuit voltages [V] held over the next step (writable in place; assigning
        copies into it; initially the steady-state voltages ``R_el I`` of the start
        state).  Kept as written when a step fails."""
        return self._u

    @voltages_V.setter
    def voltages_V(self, value: Any) -> None:
        self._u[:] = self._convert(value, self._bank.circuit_names, "voltages", "V")

    @property
    def gaps_m(self) -> np.ndarray:
        """Gap inputs [m] at the start of the next step (writable in place; assigning
        copies into it).  Each good step moves them on by ``gap_rates * dt``; a failed
        step resets them to the gaps of the last good state."""
        return self._g

    @gaps_m.setter
    def gaps_m(self, value: Any) -> None:
        self._g[:] = self._convert(value, self._bank.gap_names, "gaps", "m")

    @property
    def gap_rates_m_per_s(self) -> np.ndarray:
        """Gap rates [m/s] over the next step (writable in place; assigning copies into
        it; initially 0; kept from step to step, unlike the ``gap_rates=0.0`` default
        of :meth:`MagnetBank.step`)."""
        return self._gd

    @gap_rates_m_per_s.setter
    def gap_rates_m_per_s(self, value: Any) -> None:
        self._gd[:] = self._convert(value, self._bank.gap_names, "gap_rates", "m/s")

    # ------------------------------------------------------------------ state and outputs
    @property
    def time_s(self) -> float:
        """Time of the current state [s]."""
        return self._time

    @property
    def inductor_currents_A(self) -> np.ndarray:
        """``I_L`` of every circuit [A] (read-only; NaN for detailed members)."""
        return self._views[0]

    @property
    def currents_A(self) -> np.ndarray:
        """Coil currents of the last step [A] (with its voltages; read-only)."""
        return self._views[1]

    @property
    def circuit_force_N(self) -> np.ndarray:
        """Force of every circuit [N], attraction positive (read-only)."""
        return self._views[2]

    @property
    def member_force_N(self) -> np.ndarray:
        """Total force of every member [N] (read-only)."""
        return self._views[3]

    @property
    def eddy_currents_A(self) -> np.ndarray | None:
        """The shielding eddy currents ``I_e`` [A] of a bank with ladder members
        (read-only; 0 in eq. 8 circuits, NaN for detailed members), else None: shape
        ``(n_circuits,)``, or ``(n_circuits, 2)`` (a view) with three-state members."""
        return self._views[4] if self._ie is not None else None

    @property
    def pole_force_N(self) -> np.ndarray:
        """Force per pole [N] (a reduced circuit's force shared equally by its poles;
        a new array)."""
        if self._fast:
            return self._bank.pole_forces(self._force)
        return self._pole.copy()

    @property
    def state(self) -> BankState:
        """The last good state as a :class:`BankState` (a copy; continue with
        :meth:`MagnetBank.step` or a new stepper)."""
        from .bank import BankState

        members = () if self._fast else self._state.member_states
        return BankState(self._time, self._il.copy(), self._state_gaps.copy(), members,
                         None if self._ie is None else self._views[4].copy())

    # ------------------------------------------------------------------ stepping
    def _convert(self, value: Any, names: tuple[str, ...], what: str, unit: str) -> np.ndarray:
        """One input as :meth:`_write_inputs` converts it (for the property setters)."""
        return per_name_values(value, names, what, unit, finite=not self._fast,
                               kind="gap input" if what.startswith("gap") else "circuit")

    def _write_inputs(self, voltages: Any, gaps: Any, gap_rates: Any) -> None:
        """Convert the given inputs, then write them (a refused one writes nothing).

        As :meth:`MagnetBank.step` converts: non-finite values pass on the fast path, where
        the kernel flags them and the step is diagnosed as ``step`` diagnoses it."""
        bank = self._bank
        finite = not self._fast
        u = None if voltages is None else per_name_values(
            voltages, bank.circuit_names, "voltages", "V", finite=finite)
        g = None if gaps is None else per_name_values(
            gaps, bank.gap_names, "gaps", "m", finite=finite, kind="gap input")
        gd = None if gap_rates is None else per_name_values(
            gap_rates, bank.gap_names, "gap_rates", "m/s", finite=finite, kind="gap input")
        if u is not None:
            self._u[:] = u
        if g is not None:
            self._g[:] = g
        if gd is not None:
            self._gd[:] = gd

    def set_step_length(self, dt_s: float) -> None:
        """Change the step length of the next steps to ``dt_s`` [s], which must take the
        RK4 sub-step count of this stepper's step (e.g. a time grid whose intervals differ
        in their last bits, as :meth:`MagnetBank.simulate` steps them).

        Parameters
        ----------
        dt_s : float
            Step length [s], finite and > 0.

        Raises
        ------
        InputError
            A bad ``dt_s``, or one that needs another sub-step count (make a new stepper
            with :meth:`MagnetBank.stepper` for it).
        """
        if dt_s == self._dt:
            return
        dt = dt_s if type(dt_s) is float and 0.0 < dt_s < math.inf else check_step(dt_s)
        n = substep_count(dt, self._bank.max_step_s)
        if n != self._substeps:
            raise InputError(f"set_step_length: dt_s = {dt!r} s takes {n} RK4 sub-steps, this "
                             f"stepper's step of {self._dt!r} s takes {self._substeps}; make a "
                             "new stepper (MagnetBank.stepper) for it")
        self._dt = dt
        if self._fast:
            self._h[0] = dt

    @renamed_keywords(voltages="voltages_V", gaps="gaps_m", gap_rates="gap_rates_m_per_s")
    def advance(self, voltages_V: Any = None, gaps_m: Any = None, gap_rates_m_per_s: Any = None) -> None:
        """Advance every circuit by :attr:`dt_s` (constant voltages, linearly moving gaps).

        The old keyword names ``voltages``, ``gaps``, ``gap_rates`` still work as deprecated
        aliases (a ``DeprecationWarning`` names the new one).

        Parameters
        ----------
        voltages_V : float or array (n_circuits,), optional
            Written into :attr:`voltages_V` first [V] (None: use what is there).
        gaps_m : float or array (n_gaps,), optional
            Written into :attr:`gaps_m` first [m] (None: continue from the last step's
            end gaps, or what the caller wrote there).
        gap_rates_m_per_s : float or array (n_gaps,), optional
            Written into :attr:`gap_rates_m_per_s` first [m/s] (None: keep them).

        All three are converted before any is written, so an argument that is refused
        changes nothing.

        Raises
        ------
        InputError, OutOfRangeError, SolverError
            As :meth:`MagnetBank.step` (the same checks and messages); the stepper then
            stays at the last good step: time, state and outputs unchanged, gap inputs
            reset to the state's gaps (voltages and gap rates stay as written).
        """
        voltages, gaps, gap_rates = voltages_V, gaps_m, gap_rates_m_per_s
        bank = self._bank
        if voltages is not None or gaps is not None or gap_rates is not None:
            self._write_inputs(voltages, gaps, gap_rates)
        t0 = self._time
        t1 = t0 + self._dt
        if not self._fast:
            from .bank import BankState

            st = self._state
            try:
                st, out = bank.step(BankState(st.time_s, st.inductor_currents_A,
                                              self._g.copy(), st.member_states,
                                              st.eddy_currents_A),
                                    self._dt, self._u.copy(), None, self._gd.copy(),
                                    pole_forces=True)
            except BaseException:
                self._g[:] = self._state_gaps
                raise
            assert out.pole_force_N is not None
            self._state = st
            self._il[:], self._coil[:] = out.inductor_currents_A, out.currents_A
            self._force[:], self._member[:] = out.circuit_force_N, out.member_force_N
            self._pole[:] = out.pole_force_N
            if self._ie is not None:
                assert st.eddy_currents_A is not None
                self._ie[:] = st.eddy_currents_A.ravel(order="F")
            self._g[:] = st.gaps_m
            self._state_gaps[:] = st.gaps_m
            self._time = st.time_s
            return
        self._eval()
        if self._n_bad[0]:
            r = self._res
            try:
                bank.raise_step_flags(r[8], gaps_m=self._g, gap_rates_m_per_s=self._gd,
                                      inductor_currents_A=self._il, voltages_V=self._u,
                                      current_min_A=r[5], current_max_A=r[6], start_s=t0,
                                      end_s=t1)
            except BaseException:
                self._g[:] = self._state_gaps
                raise
        self._block[:] = self._scratch
        self._g[:] = self._state_gaps
        self._time = t1

    # ------------------------------------------------------------------ copies
    def __copy__(self) -> BankStepper:
        """An independent stepper at the same state with the same inputs."""
        other = BankStepper(self._bank, self.state, self._dt)
        other._u[:], other._gd[:], other._g[:] = self._u, self._gd, self._g
        return other

    def __deepcopy__(self, memo: dict) -> BankStepper:
        return self.__copy__()

    def __reduce__(self) -> Any:
        raise InputError("a BankStepper holds bound compiled buffers and cannot be pickled; "
                         "pickle stepper.state and make a new one with bank.stepper(state, dt)")

    def __repr__(self) -> str:
        return (f"BankStepper({self._bank.n_circuits} circuits, dt={self._dt:g} s, "
                f"t={self._time:g} s, {'compiled buffers' if self._fast else 'bank.step'})")
