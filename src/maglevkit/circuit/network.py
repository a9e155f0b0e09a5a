"""Topology of the equivalent magnetic circuit and its electric circuits.

A :class:`Network` is a set of :class:`Branch` es between named nodes; each branch is a
series chain of elements.  Electric :class:`Circuit` s put coils (``theta = n I``, paper
eq. 2) on branches, in series with a resistance and a voltage source.

The network is solved in loop fluxes: with a loop matrix ``C`` (loops x branches, a basis
of the closed flux paths: the fundamental loops of a spanning tree, or short loops for large
networks, :attr:`Network.loop_matrix`) the branch fluxes ``phi = C^T x`` satisfy
Kirchhoff's node law identically, and Kirchhoff's loop law reads
``C (V_m(phi, s) - N I) = 0`` with the branch-by-circuit turns matrix ``N``.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from ..errors import ParameterError, TopologyError
from ..validation import flag, renamed_keywords
from .elements import EddyCurrent, Element, IronPath

__all__ = ["Branch", "Coil", "Circuit", "Network", "SHORT_LOOP_SIZE"]

#: Networks with more loops than this are solved in a basis of short loops
#: (:attr:`Network.loop_matrix`); smaller ones in the fundamental loops of a spanning tree.
#: Either basis gives the same solutions (the loop laws of a basis imply those of every
#: loop), but not the same rounding or integrator error control, so the networks whose
#: results are recorded (the lumped TR09, guidance and U-magnet networks, 7-36 loops; the
#: U-magnet's ladder n = 4: 59) keep theirs.  The short loops matter for the large ones: TR09
#: split 253 loops, the U-magnet grid 110, its ladder 506, the air-cell grid 1385
#: (docs/decisions.md, splitfast).
SHORT_LOOP_SIZE = 100


@dataclass(frozen=True)
class Branch:
    """A branch of the magnetic network: elements in series from ``start`` to ``end``.

    Parameters
    ----------
    name : str
        Unique branch name.
    start, end : str
        Node names; positive flux flows from ``start`` to ``end``.
    elements : tuple of Element
        The series elements (may be empty only if a coil sits on the branch and the
        loop it closes contains some reluctance).
    """

    name: str
    start: str
    end: str
    elements: tuple[Element, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "elements", tuple(self.elements))
        for key in ("name", "start", "end"):
            v = getattr(self, key)
            if not isinstance(v, str) or not v:
                raise TopologyError(f"branch {self.name!r}: {key} must be a non-empty string")
        if self.start == self.end:
            raise TopologyError(f"branch {self.name!r} starts and ends at node {self.start!r}; "
                                "a branch must join two different nodes")
        for el in self.elements:
            if not isinstance(el, Element):
                raise TopologyError(f"branch {self.name!r}: {el!r} is not an Element")

    @property
    def area(self) -> float | None:
        """Smallest cross-section of the branch's iron/gap elements [m^2] (None if none)."""
        areas = [a for a in (el.area for el in self.elements) if a is not None]
        return min(areas) if areas else None


@dataclass(frozen=True)
class Coil:
    """A coil of ``turns`` windings on ``branch``.

    Its MMF ``turns * I`` drives flux from the branch's start node to its end node
    when ``polarity = +1`` (and the other way for ``-1``).

    A pole winding distributed over several branches (a leg split into segments, so
    that leakage can leave it part-way up the coil) is given as several coils with the
    same ``pole`` name; the pole's flux (paper eq. 5, ``eta``) is then the turn-weighted
    mean of its segments' fluxes, ``psi_pole / n_pole``.  Default: one pole per coil.

    ``pole_turns`` is ``n_pole`` when the pole's coils are not all in series along one
    path, e.g. a leg modelled as parallel columns of iron cells, each column carrying the
    MMF of the turns it passes (then the coils' turns add up to a multiple of the winding's
    turns); default: the sum of the turns of the coils with the same ``pole`` name.

    Parameters
    ----------
    branch : str
        Name of the branch the coil sits on (checked by :class:`Network`).
    turns : float
        Number of turns [-], finite and > 0 (need not be whole: a lumped share).
    polarity : {1, -1}
        Direction of the coil's MMF relative to the branch (default +1).
    pole : str, optional
        Name of the pole winding the coil belongs to (default: a pole of its own).
    pole_turns : float, optional
        Turns ``n_pole`` of the pole winding [-], > 0; only with ``pole``.

    Raises
    ------
    ParameterError
        ``turns`` or ``pole_turns`` not a finite number > 0, ``polarity`` not +1 or -1,
        an empty ``pole`` name, or ``pole_turns`` without ``pole``.
    """

    branch: str
    turns: float
    polarity: int = 1
    pole: str | None = None
    pole_turns: float | None = None

    def __post_init__(self) -> None:
        if self.pole is not None and (not isinstance(self.pole, str) or not self.pole):
            raise ParameterError(f"coil on branch {self.branch!r}: pole must be a non-empty "
                                 "name or None")
        if not (isinstance(self.turns, (int, float)) and not isinstance(self.turns, bool)
                and math.isfinite(self.turns) and self.turns > 0):
            raise ParameterError(f"coil on branch {self.branch!r}: turns = {self.turns!r} must be > 0")
        if isinstance(self.polarity, bool) or self.polarity not in (1, -1):
            raise ParameterError(f"coil on branch {self.branch!r}: polarity must be +1 or -1")
        if self.pole_turns is not None:
            if self.pole is None:
                raise ParameterError(f"coil on branch {self.branch!r}: pole_turns needs a pole "
                                     "name (the winding the coil belongs to)")
            pt = self.pole_turns
            if not (isinstance(pt, (int, float)) and not isinstance(pt, bool)
                    and math.isfinite(pt) and pt > 0):
                raise ParameterError(f"coil on branch {self.branch!r}: pole_turns = {pt!r} "
                                     "must be a finite number > 0")


@renamed_keywords(resistance="resistance_ohm")
@dataclass(frozen=True)
class Circuit:
    """An electric circuit: coils in series with a resistance and a voltage input.

    The old field name ``resistance`` still works as a deprecated alias (keyword and
    read-only attribute; a ``DeprecationWarning`` names ``resistance_ohm``).

    Parameters
    ----------
    name : str
        Unique circuit name (also the name of its current and voltage).
    resistance_ohm : float
        Total ohmic resistance R_el [ohm] (> 0).
    coils : tuple of Coil
        At least one coil.
    """

    name: str
    resistance_ohm: float
    coils: tuple[Coil, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "coils", tuple(self.coils))
        if not isinstance(self.name, str) or not self.name:
            raise TopologyError("a circuit needs a non-empty name")
        r = self.resistance_ohm
        if not (isinstance(r, (int, float)) and not isinstance(r, bool)
                and math.isfinite(r) and r > 0):
            raise ParameterError(f"circuit {self.name!r}: resistance_ohm = {r!r} "
                                 "must be a finite number > 0")
        if not self.coils:
            raise TopologyError(f"circuit {self.name!r} has no coils; every circuit must drive "
                                "at least one coil")

    @property
    def turns(self) -> float:
        """Total number of turns of the circuit's coils."""
        return float(sum(c.turns for c in self.coils))


@dataclass(frozen=True)
class Network:
    """Equivalent magnetic circuit with its electric circuits.

    Parameters
    ----------
    branches : sequence of Branch
        The magnetic branches (at least one); nodes are named by the branches.
    circuits : sequence of Circuit
        The electric circuits (at least one), each driving coils on the branches.
    name : str, default "network"
        Name used in messages and reports.

    Raises
    ------
    TopologyError
        Not sequences of :class:`Branch` / :class:`Circuit`, no branches or circuits,
        duplicate branch, element or circuit names, a coil on a missing branch or two
        coils of one circuit on one branch, a disconnected network, no closed flux
        path, or a coil branch on no loop.

    Notes
    -----
    Validates on construction: unique names, known nodes, connectedness, at least
    one closed flux path, coils on existing branches, at most one coil per circuit
    and branch.

    Attributes
    ----------
    cache : dict
        Objects derived from this (immutable) network once and reused: its equations, the
        statics solver, flux-model DAEs, map runs; keyed by the module that derives them
        (e.g. ``"equations"``, ``("flux_dae", ...)``).  Not part of equality, the repr or
        a pickle (a worker process derives them again).
    """

    branches: tuple[Branch, ...]
    circuits: tuple[Circuit, ...]
    name: str = "network"
    cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for key, cls in (("branches", Branch), ("circuits", Circuit)):
            items = getattr(self, key)
            if isinstance(items, (str, bytes, cls)) or not hasattr(items, "__iter__"):
                raise TopologyError(f"network {key} must be a sequence of {cls.__name__} "
                                    f"objects, got {type(items).__name__}")
            items = tuple(items)
            for item in items:
                if not isinstance(item, cls):
                    raise TopologyError(f"network {key}: {item!r} is not a {cls.__name__}")
            object.__setattr__(self, key, items)
        if not self.branches:
            raise TopologyError("the network has no branches")
        if not self.circuits:
            raise TopologyError("the network has no electric circuit; add at least one Circuit")
        _unique("branch", [b.name for b in self.branches])
        _unique("element", [e.name for b in self.branches for e in b.elements])
        _unique("circuit", [c.name for c in self.circuits])
        names = {b.name for b in self.branches}
        seen: set[tuple[str, str]] = set()
        for c in self.circuits:
            for coil in c.coils:
                if coil.branch not in names:
                    raise TopologyError(
                        f"circuit {c.name!r}: coil on branch {coil.branch!r}, which does not exist; "
                        f"branches are: {', '.join(sorted(names))}"
                    )
                if (c.name, coil.branch) in seen:
                    raise TopologyError(f"circuit {c.name!r} has two coils on branch "
                                        f"{coil.branch!r}; merge them into one")
                seen.add((c.name, coil.branch))
        self._check_connected()
        if self.n_loops == 0:
            raise TopologyError("the network has no closed flux path (it is a tree); flux needs "
                                "a loop through the coils")
        coil_branches = {coil.branch for c in self.circuits for coil in c.coils}
        loops = self.loop_matrix
        idx = {n: i for i, n in enumerate(self.branch_names)}
        for b in coil_branches:
            if not np.any(loops[:, idx[b]]):
                raise TopologyError(f"coil branch {b!r} lies on no closed loop (a dangling branch); "
                                    "its coil could not drive any flux")

    def __getstate__(self) -> dict:
        # Compiled CasADi functions stay behind: a worker process rebuilds them lazily.
        state = dict(self.__dict__)
        state["cache"] = {}
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)

    # ------------------------------------------------------------------ topology
    @property
    def branch_names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.branches)

    @property
    def circuit_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.circuits)

    @property
    def nodes(self) -> tuple[str, ...]:
        out: dict[str, None] = {}
        for b in self.branches:
            out.setdefault(b.start)
            out.setdefault(b.end)
        return tuple(out)

    @property
    def gap_names(self) -> tuple[str, ...]:
        """Names of the gap inputs, in order of first appearance."""
        out: dict[str, None] = {}
        for b in self.branches:
            for e in b.elements:
                if e.gap is not None:
                    out.setdefault(e.gap)
        return tuple(out)

    @property
    def n_loops(self) -> int:
        return len(self.branches) - len(self.nodes) + 1

    def _check_connected(self) -> None:
        parent = {n: n for n in self.nodes}

        def find(a: str) -> str:
            while parent[a] != a:
                parent[a] = parent[parent[a]]
                a = parent[a]
            return a

        for b in self.branches:
            parent[find(b.start)] = find(b.end)
        groups: dict[str, list[str]] = {}
        for n in self.nodes:
            groups.setdefault(find(n), []).append(n)
        if len(groups) > 1:
            parts = sorted((sorted(g) for g in groups.values()), key=len)
            raise TopologyError(
                f"the network is disconnected: {len(groups)} separate parts, e.g. nodes "
                f"{parts[0]} are not joined to {parts[-1][:5]}; every node must be reachable"
            )

    @property
    def incidence_matrix(self) -> np.ndarray:
        """Node-by-branch incidence (+1 leaving the node, -1 entering)."""
        nodes = {n: i for i, n in enumerate(self.nodes)}
        a = np.zeros((len(nodes), len(self.branches)))
        for j, b in enumerate(self.branches):
            a[nodes[b.start], j] = 1.0
            a[nodes[b.end], j] = -1.0
        return a

    @cached_property
    def loop_matrix(self) -> np.ndarray:
        """Loop matrix ``C`` (loops x branches): a basis of the network's closed flux paths,
        one row per loop, entries +-1 (the branch along or against the loop) and 0.

        Networks of up to :data:`SHORT_LOOP_SIZE` loops take the fundamental loops of a BFS
        spanning tree (as every earlier version did, so their results stay the same);
        larger ones a basis of short loops (:meth:`_short_loops`), whose loop Jacobian
        ``C diag(dV_m/dphi) C^T`` has a fraction of the nonzeros: on the TR09 split
        network (253 loops) 1537 instead of 23455 (docs/decisions.md, splitfast).
        """
        fundamental = self._fundamental_loops()
        if fundamental.shape[0] <= SHORT_LOOP_SIZE:
            return fundamental
        return self._short_loops(fundamental)

    def _short_loops(self, fundamental: np.ndarray) -> np.ndarray:
        """A loop basis of short loops: for every branch the shortest loop through it (a
        shortest path in branch count between its nodes that avoids it, BFS), taken
        shortest first (ties in branch order) where independent of the loops taken, then
        the ``fundamental`` loops where still needed.

        Independence is tested over GF(2) (loops as sets of branches, exact integer
        arithmetic): rows independent mod 2 have a square minor with an odd, hence nonzero,
        determinant, so they are independent over the reals too; the fundamental loops
        span the loop space mod 2 as well, so the result always has their number of rows.
        """
        index = {n: i for i, n in enumerate(self.nodes)}
        ends = [(index[b.start], index[b.end]) for b in self.branches]
        nb = len(ends)
        adj: list[list[tuple[int, int]]] = [[] for _ in index]
        for j, (a, b) in enumerate(ends):
            adj[a].append((j, b))
            adj[b].append((j, a))

        def shortest_loop(j: int) -> np.ndarray | None:
            start, end = ends[j]
            prev: dict[int, tuple[int, int] | None] = {end: None}
            queue = deque((end,))
            while queue and start not in prev:
                n = queue.popleft()
                for k, m in adj[n]:
                    if k != j and m not in prev:
                        prev[m] = (k, n)
                        queue.append(m)
            if start not in prev:
                return None                   # a branch on no loop (a bridge)
            row = np.zeros(nb)
            row[j] = 1.0                      # along branch j, back from its end to its start
            n = start
            step = prev[n]
            while step is not None:
                k, before = step              # branch k walked from node `before` to `n`
                row[k] = 1.0 if ends[k] == (before, n) else -1.0
                n = before
                step = prev[n]
            return row

        found = [row for row in map(shortest_loop, range(nb)) if row is not None]
        found.sort(key=np.count_nonzero)      # stable: ties stay in branch order
        pivots: dict[int, int] = {}           # leading branch -> reduced loop (bit set)
        rows: list[np.ndarray] = []
        for row in (*found, *fundamental):
            bits = sum(1 << int(k) for k in np.flatnonzero(row))
            while bits:
                lead = bits.bit_length() - 1
                if lead not in pivots:
                    pivots[lead] = bits
                    rows.append(row)
                    break
                bits ^= pivots[lead]
            if len(rows) == fundamental.shape[0]:
                break
        return np.array(rows).reshape(len(rows), nb)

    def _fundamental_loops(self) -> np.ndarray:
        """Fundamental loop matrix (loops x branches) from a BFS spanning tree."""
        nodes = self.nodes
        adj: dict[str, list[tuple[int, str]]] = {n: [] for n in nodes}
        for j, b in enumerate(self.branches):
            adj[b.start].append((j, b.end))
            adj[b.end].append((j, b.start))
        root = nodes[0]
        parent_branch: dict[str, int | None] = {root: None}
        parent_node: dict[str, str | None] = {root: None}
        order = [root]
        for n in order:
            for j, m in adj[n]:
                if m not in parent_branch:
                    parent_branch[m] = j
                    parent_node[m] = n
                    order.append(m)
        tree = {j for j in parent_branch.values() if j is not None}

        def path_to_root(n: str) -> list[str]:
            out = [n]
            while parent_node[out[-1]] is not None:
                out.append(parent_node[out[-1]])  # type: ignore[arg-type]
            return out

        rows = []
        for j, b in enumerate(self.branches):
            if j in tree:
                continue
            row = np.zeros(len(self.branches))
            row[j] = 1.0
            # Close the loop: from b.end back to b.start through the tree.
            pa, pb = path_to_root(b.end), path_to_root(b.start)
            common = set(pa) & set(pb)
            for path, sign in ((pa, 1.0), (pb, -1.0)):
                for node in path:
                    if node in common:
                        break
                    k = parent_branch[node]
                    assert k is not None
                    br = self.branches[k]
                    # walking from `node` towards its parent: along the branch if it starts at node
                    along = 1.0 if br.start == node else -1.0
                    row[k] += sign * along
            rows.append(row)
        return np.array(rows).reshape(len(rows), len(self.branches))

    @property
    def turns_matrix(self) -> np.ndarray:
        """``N`` (branches x circuits): signed turns, so that ``theta = N I`` and ``psi = N^T phi``."""
        idx = {n: i for i, n in enumerate(self.branch_names)}
        n = np.zeros((len(self.branches), len(self.circuits)))
        for k, c in enumerate(self.circuits):
            for coil in c.coils:
                n[idx[coil.branch], k] += coil.polarity * coil.turns
        return n

    @property
    def pole_flux_matrix(self) -> np.ndarray:
        """``W`` (branches x circuits) with ``eta = W^T phi``: the sum of the pole fluxes of
        each circuit (paper eq. 5), a pole's flux being ``psi_pole / n_pole`` over the coils
        that share its ``pole`` name (one coil: just its branch flux, signed; ``n_pole`` is
        the coils' ``pole_turns`` where given)."""
        idx = {n: i for i, n in enumerate(self.branch_names)}
        w = np.zeros((len(self.branches), len(self.circuits)))
        for k, c in enumerate(self.circuits):
            totals: dict[str, float] = {}
            for coil in c.coils:
                key = coil.pole or coil.branch
                totals[key] = totals.get(key, 0.0) + coil.turns
            for coil in c.coils:
                if coil.pole_turns is not None:
                    totals[coil.pole or coil.branch] = coil.pole_turns
            for coil in c.coils:
                w[idx[coil.branch], k] += coil.polarity * coil.turns / totals[coil.pole or coil.branch]
        return w

    @property
    def resistances(self) -> np.ndarray:
        """Circuit resistances R_el [ohm]."""
        return np.array([c.resistance_ohm for c in self.circuits], dtype=float)

    @property
    def eddy_conductances(self) -> np.ndarray:
        """Per-branch sum of eddy-current conductances ``G_ec`` [S]."""
        return np.array([sum(e.eddy_conductance for e in b.elements) for b in self.branches])

    @property
    def branch_areas(self) -> np.ndarray:
        """Per-branch reporting cross-section [m^2] (NaN where none is defined)."""
        return np.array([np.nan if b.area is None else b.area for b in self.branches])

    @property
    def has_eddy_currents(self) -> bool:
        return bool(np.any(self.eddy_conductances > 0.0))

    # ------------------------------------------------------------------ variants
    def with_options(self, *, saturation: bool = True, eddy_currents: bool = True) -> Network:
        """A copy with saturation (iron nonlinearity) and/or eddy currents switched off.

        ``saturation=False`` replaces every iron material by its initial permeability
        (``Material.linearized``); ``eddy_currents=False`` removes the eddy elements.

        Parameters
        ----------
        saturation : bool, default True
            Keep the iron materials' nonlinear laws (keyword only).
        eddy_currents : bool, default True
            Keep the eddy-current elements (keyword only).

        Returns
        -------
        Network
            ``self`` when both are True, else a new network (same name and circuits).

        Raises
        ------
        InputError
            ``saturation`` or ``eddy_currents`` not True or False.
        """
        saturation = flag(saturation, "saturation")
        eddy_currents = flag(eddy_currents, "eddy_currents")
        if saturation and eddy_currents:
            return self

        def convert(el: Element) -> Element | None:
            if not eddy_currents and isinstance(el, EddyCurrent):
                return None
            if not saturation and isinstance(el, IronPath):
                return replace(el, material=el.material.linearized())
            if not saturation and callable(getattr(el, "linearized", None)):
                return el.linearized()  # type: ignore[attr-defined, no-any-return]
            return el

        branches = []
        for b in self.branches:
            els = tuple(e for e in (convert(x) for x in b.elements) if e is not None)
            branches.append(replace(b, elements=els))
        return Network(tuple(branches), self.circuits, name=self.name)

    def element(self, name: str) -> Element:
        """The element called ``name`` (in any branch).

        Parameters
        ----------
        name : str
            Element name.

        Returns
        -------
        Element

        Raises
        ------
        KeyError
            No element of that name.
        """
        for b in self.branches:
            for e in b.elements:
                if e.name == name:
                    return e
        raise KeyError(f"no element named {name!r} in network {self.name!r}")

    def branch(self, name: str) -> Branch:
        """The branch called ``name``.

        Parameters
        ----------
        name : str
            Branch name (:attr:`branch_names`).

        Returns
        -------
        Branch

        Raises
        ------
        KeyError
            No branch of that name (the message lists the branches).
        """
        for b in self.branches:
            if b.name == name:
                return b
        raise KeyError(f"no branch named {name!r} in network {self.name!r}; "
                       f"branches are: {', '.join(self.branch_names)}")


def _unique(kind: str, names: Sequence[str] | Iterable[str]) -> None:
    seen: set[str] = set()
    for n in names:
        if n in seen:
            raise TopologyError(f"duplicate {kind} name {n!r}; {kind} names must be unique")
        seen.add(n)
