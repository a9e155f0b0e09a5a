"""In-place stepping of a magnet bank: the co-simulation loop without per-step objects.

:meth:`MagnetBank.step <maglevkit.models.bank.MagnetBank.step>` returns new immutable
state and output objects and copies its inputs and outputs, which at 100 circuits costs
about as much as the compiled arithmetic itself.  A :class:`BankStepper` binds the
compiled step to arrays it owns: the caller writes voltages, gaps and gap rates into the
stepper's input arrays (or passes them to :meth:`BankStepper.advance`), calls
:meth:`~BankStepper.advance`, and reads the currents and forces from the stepper's output
arrays.  Two sets of state and output arrays alternate, so a step never overwrites its
own inputs and a step that fails (out of the maps, non-finite) leaves the stepper at the
last good step.  The numbers are the bank's own: the same compiled function as
:meth:`MagnetBank.step`, equal to it bit for bit.

Banks with detailed members or one gap input per pole have no compiled fast path; their
stepper runs :meth:`MagnetBank.step` behind the same interface.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError
from .inputs import check_step

if TYPE_CHECKING:
    from .bank import BankState, MagnetBank

__all__ = ["BankStepper"]


def _readonly(a: np.ndarray) -> np.ndarray:
    v = a.view()
    v.flags.writeable = False
    return v


class _Buffers:
    """One bound evaluation of the compiled step: reads state set ``c``, writes set
    ``1 - c`` (``res`` as :class:`~maglevkit.models.bank._StepCall`, for the diagnosis)."""

    def __init__(self, f: Any, args: list[np.ndarray], res: list[np.ndarray]) -> None:
        buf, self.eval = f.buffer()
        self.buf = buf                   # keeps the bound buffer alive
        self.args, self.res = args, res
        for i, a in enumerate(args):
            buf.set_arg(i, memoryview(a))  # type: ignore[arg-type]
        for i, r in enumerate(res):
            buf.set_res(i, memoryview(r))  # type: ignore[arg-type]


class BankStepper:
    """Advance a :class:`~maglevkit.models.bank.MagnetBank` step by step in place.

    Made by :meth:`MagnetBank.stepper <maglevkit.models.bank.MagnetBank.stepper>`; one
    stepper per step length.  The input arrays belong to the stepper and are written in
    place; the output arrays are read-only views of the stepper's buffers, valid until
    the next :meth:`advance` (copy them to keep them).

    Attributes
    ----------
    bank : MagnetBank
    dt_s : float
        Step length [s].
    voltages_V : ndarray (n_circuits,)
        Circuit voltages [V] held over the next step (writable; initially the
        steady-state voltages ``R_el I_L`` of the start state).
    gap_rates_m_per_s : ndarray (n_gaps,)
        Gap rates [m/s] over the next step (writable; initially 0).

    Examples
    --------
    >>> import numpy as np
    >>> import maglevkit as mk
    >>> magnet = mk.load_magnet("u-magnet")
    >>> maps = mk.build_maps(magnet, gaps=np.linspace(0.006, 0.016, 6),
    ...                      currents=np.linspace(0, 60, 13), progress=False)
    >>> bank = mk.MagnetBank({f"m{k}": maps for k in range(4)}, compiled="never")
    >>> stepper = bank.stepper(bank.initial_state(gaps=0.010, currents=20.0), dt=1e-3)
    >>> for k in range(10):
    ...     stepper.voltages_V[:] = bank.resistance_ohm * 21.0   # e.g. from a controller
    ...     stepper.gaps_m[:] = 0.010                             # e.g. from the mechanics
    ...     stepper.advance()
    >>> round(stepper.time_s, 6), stepper.circuit_force_N.shape
    (0.01, (4,))
    """

    def __init__(self, bank: MagnetBank, state: BankState, dt: float) -> None:
        from .bank import BankState

        if type(state) is not BankState or state.gaps_m.shape != (bank.n_gaps,):
            raise InputError("state must be a BankState of this bank (from initial_state or "
                             "step)")
        self.bank = bank
        self.dt_s = check_step(dt)
        nc, ng = bank.n_circuits, bank.n_gaps
        out = bank.outputs(state)
        self.voltages_V = bank.resistance_ohm * np.where(
            np.isnan(state.inductor_currents_A), 0.0, state.inductor_currents_A)
        self.gap_rates_m_per_s = np.zeros(ng)
        self._time = float(state.time_s)
        self._fast = bank._fast
        if not self._fast:
            self._state = state
            self._gaps = state.gaps_m.copy()
            self._out = [_readonly(a) for a in (out.inductor_currents_A.copy(),
                                                out.currents_A.copy(),
                                                out.circuit_force_N.copy(),
                                                out.member_force_N.copy())]
            assert out.pole_force_N is not None
            self._pole_force = out.pole_force_N
            return
        nm = len(bank.member_names)
        call = bank._kernel(self.dt_s)
        # state set c: I_L, s; outputs of the step that produced it: coil, F, member F
        il = [state.inductor_currents_A.copy(), np.zeros(nc)]
        s = [state.gaps_m.copy(), np.zeros(nc)]
        coil = [out.currents_A.copy(), np.zeros(nc)]
        force = [out.circuit_force_N.copy(), np.zeros(nc)]
        member = [out.member_force_N.copy(), np.zeros(nm)]
        h = self._h = np.array([self.dt_s])
        n_bad, lo, hi = np.zeros(1), np.zeros(nc), np.zeros(nc)
        self._sets = [_Buffers(call.f, [il[c], s[c], self.voltages_V, self.gap_rates_m_per_s, h],
                               [il[1 - c], coil[1 - c], force[1 - c], member[1 - c], n_bad,
                                lo, hi, s[1 - c]])
                      for c in (0, 1)]
        self._n_bad = n_bad
        self._il, self._s = il, s
        self._views = [[_readonly(a[c]) for a in (il, coil, force, member)] for c in (0, 1)]
        self._c = 0

    # ------------------------------------------------------------------ state and outputs
    @property
    def time_s(self) -> float:
        """Time of the current state [s]."""
        return self._time

    @property
    def gaps_m(self) -> np.ndarray:
        """Gap inputs [m] at the start of the next step (writable; each :meth:`advance`
        moves them on by ``gap_rates * dt``)."""
        return self._s[self._c] if self._fast else self._gaps

    @property
    def inductor_currents_A(self) -> np.ndarray:
        """``I_L`` of every circuit [A] (read-only; NaN for detailed members)."""
        return (self._views[self._c] if self._fast else self._out)[0]

    @property
    def currents_A(self) -> np.ndarray:
        """Coil currents of the last step [A] (with its voltages; read-only)."""
        return (self._views[self._c] if self._fast else self._out)[1]

    @property
    def circuit_force_N(self) -> np.ndarray:
        """Force of every circuit [N], attraction positive (read-only)."""
        return (self._views[self._c] if self._fast else self._out)[2]

    @property
    def member_force_N(self) -> np.ndarray:
        """Total force of every member [N] (read-only)."""
        return (self._views[self._c] if self._fast else self._out)[3]

    @property
    def pole_force_N(self) -> np.ndarray:
        """Force per pole [N] (a reduced circuit's force shared equally by its poles;
        computed on request, a new array)."""
        if self._fast:
            return self.bank._share @ self.circuit_force_N
        return self._pole_force.copy()

    @property
    def state(self) -> BankState:
        """The current state as a :class:`BankState` (a copy; continue with
        :meth:`MagnetBank.step` or a new stepper)."""
        from .bank import BankState

        if not self._fast:
            st = self._state
            return BankState(st.time_s, st.inductor_currents_A.copy(), self._gaps.copy(),
                             st.member_states)
        c = self._c
        return BankState(self._time, self._il[c].copy(), self._s[c].copy(), ())

    # ------------------------------------------------------------------ stepping
    def _set(self, target: np.ndarray, value: Any, names: tuple[str, ...], what: str,
             unit: str) -> None:
        if type(value) is np.ndarray and value.shape == target.shape and value.dtype == float:
            target[:] = value
        else:
            target[:] = self.bank._vector(value, names, what, unit)

    def _set_step_length(self, dt: float) -> None:
        """Change the step length to ``dt`` [s] with the same RK4 sub-step count (for
        :meth:`MagnetBank.simulate` on grids whose intervals differ in the last bits)."""
        self.dt_s = dt
        self._h[0] = dt

    def advance(self, voltages: Any = None, gaps: Any = None, gap_rates: Any = None) -> None:
        """Advance every circuit by :attr:`dt_s` (constant voltages, linearly moving gaps).

        Parameters
        ----------
        voltages : float or array (n_circuits,), optional
            Written into :attr:`voltages_V` first [V] (None: use what is there).
        gaps : float or array (n_gaps,), optional
            Written into :attr:`gaps_m` first [m] (None: continue from the last step's
            end gaps, or what the caller wrote there).
        gap_rates : float or array (n_gaps,), optional
            Written into :attr:`gap_rates_m_per_s` first [m/s].

        Raises
        ------
        InputError, OutOfRangeError, SolverError
            As :meth:`MagnetBank.step` (the same checks, the same messages); the stepper
            then stays at the state before the step.
        """
        bank = self.bank
        if voltages is not None:
            self._set(self.voltages_V, voltages, bank.circuit_names, "voltages", "V")
        if gaps is not None:
            self._set(self.gaps_m, gaps, bank.gap_names, "gaps", "m")
        if gap_rates is not None:
            self._set(self.gap_rates_m_per_s, gap_rates, bank.gap_names, "gap_rates", "m/s")
        t0 = self._time
        if not self._fast:
            st = self._state
            from .bank import BankState

            st = BankState(st.time_s, st.inductor_currents_A, self._gaps.copy(),
                           st.member_states)
            st, out = bank.step(st, self.dt_s, self.voltages_V.copy(), self._gaps.copy(),
                                self.gap_rates_m_per_s.copy(), pole_forces=True)
            assert out.pole_force_N is not None
            self._state, self._pole_force = st, out.pole_force_N
            self._gaps[:] = st.gaps_m
            self._out = [_readonly(a) for a in (out.inductor_currents_A, out.currents_A,
                                                out.circuit_force_N, out.member_force_N)]
            self._time = st.time_s
            return
        c = self._c
        b = self._sets[c]
        b.eval()
        t1 = t0 + self.dt_s
        if self._n_bad[0]:
            a = b.args
            bank._diagnose(a[1], a[3], a[0], a[2], b.res[0], b, t0, t1)  # type: ignore[arg-type]
        self._c = 1 - c
        self._time = t1

    def __repr__(self) -> str:
        return (f"BankStepper({self.bank.n_circuits} circuits, dt={self.dt_s:g} s, "
                f"t={self._time:g} s, {'compiled buffers' if self._fast else 'bank.step'})")
