"""A :class:`~certsolve.expr.system.System` compiled for batched interval work.

:class:`CompiledSystem` builds one shared DAG holding the equations, the extra
constraints and the symbolic Jacobian, and three level-grouped programs over it:

* ``hc4``  -- equations and constraints, for forward-backward contraction;
* ``f``    -- equations only, for rigorous evaluation at points (``f(c)`` in Newton);
* ``fj``   -- equations and Jacobian entries, for ``J(X)`` over boxes.

All methods take batches: boxes as ``(B, n)`` arrays of bounds, points as ``(B, n)``.
Everything in it is plain data (arrays, lists), so it pickles to worker processes.

**Chunks.**  A program call holds a ``(nodes, B)`` array per bound: a batch whose call
would hold more than :data:`CHUNK_ELEMENTS` node values per bound is evaluated in equal
chunks of boxes (:func:`_chunked`), so a large program (Hansen's mixed Jacobian stacked,
:mod:`.stacked`) runs at any batch size in bounded memory.  Every bound is computed from
its own box's values and rounded alone, whatever the size of the array it is in, so the
chunks give the floats of one call, and the domain test is per box.
"""

from __future__ import annotations

import copy
import math
from functools import cached_property

import numpy as np

from .graph import CompileTimeout, Graph, check_deadline
from .program import Program
from .stacked import StackedColumns
from .system import System

__all__ = ["CompileTimeout", "CompiledSystem"]

#: node values per bound array in one program call (16 MB): larger batches are evaluated
#: in chunks of boxes (module docstring).  Smaller chunks were slower in the search
#: (general-19 at 60 N, P1 within 6 cm of the pose, 2048 boxes a batch; CPU a box, the
#: same boxes): HC4 27-29 us at 2^21 and 2^20, 30-31 at 2^19, 36 at 2^18; partial Newton
#: 10-11, 11-12, 12-13, 13 (docs/fk-cost.md, "The last 10 %")
CHUNK_ELEMENTS = 1 << 21

#: the mixed Jacobian is evaluated as one stacked program, in chunks, while a chunk holds at
#: least this many boxes; a larger program, one column program per group (each in chunks).
#: general-19's (1,421 nodes; batches of ~1,700 boxes): interval Newton 29-30 -> 23-25 us
#: a box in the search, where batches past 737 boxes took one program per group and ``f``
#: at ``c`` (2,023 nodes and 153 groups in all, against 1,421 and 46)
STACK_MIN_BOXES = 16


def _chunked(fn, nodes: int, *boxes: np.ndarray) -> tuple:
    """``fn(*boxes)``, in equal chunks of rows when the batch holds more than
    :data:`CHUNK_ELEMENTS` values of ``nodes`` nodes: every output of ``fn`` (arrays with the
    boxes along axis 0) concatenated over the chunks."""
    B = boxes[0].shape[0]
    k = -(-B * nodes // CHUNK_ELEMENTS)
    if k <= 1:
        return fn(*boxes)
    size = -(-B // k)
    parts = [fn(*(a[i : i + size] for a in boxes)) for i in range(0, B, size)]
    return tuple(np.concatenate(p) for p in zip(*parts, strict=True))


def _group_key(groups) -> tuple[tuple[int, ...], ...]:
    """The variables of each group (boolean masks) as tuples: one ``nonzero`` for all."""
    rows, cols = np.nonzero(np.asarray(groups, dtype=bool))
    key: list[list[int]] = [[] for _ in range(len(groups))]
    for r, j in zip(rows.tolist(), cols.tolist()):
        key[r].append(j)
    return tuple(tuple(k) for k in key)


class CompiledSystem:
    def __init__(self, system: System, *, deadline: float | None = None):
        """``deadline`` (a :func:`time.monotonic` value): compiling past it raises
        :class:`~.graph.CompileTimeout` (checked per row of the Jacobian and per program)."""
        self.system = system
        self.n = n = system.n
        self.param_names = list(system.parameters)
        g = Graph(system.variables, self.param_names)
        self.eq_roots = [g.add_expr(e) for e in system.equations]
        self.cons_roots = [g.add_expr(c.expr) for c in system.constraints]
        jac = g.jacobian(self.eq_roots, deadline)
        check_deadline(deadline, "building the programs")
        self.graph = g
        self.jac_structure = np.array([[d is not None for d in row] for row in jac])

        hc4_out = self.eq_roots + self.cons_roots
        self.hc4 = Program(g, hc4_out)
        # the range each output must lie in (equations: 0); an expression that is both an
        # equation and a constraint (or two constraints) gets the intersection, once
        tlo = np.array([0.0] * n + [c.lo for c in system.constraints], dtype=np.float64)
        thi = np.array([0.0] * n + [c.hi for c in system.constraints], dtype=np.float64)
        self.hc4_out, inverse = np.unique(self.hc4.outputs, return_inverse=True)
        self.hc4_target_lo = np.full(self.hc4_out.size, -np.inf)
        self.hc4_target_hi = np.full(self.hc4_out.size, np.inf)
        np.fmax.at(self.hc4_target_lo, inverse, tlo)
        np.fmin.at(self.hc4_target_hi, inverse, thi)
        self.hc4_target_lo = self.hc4_target_lo[:, None]
        self.hc4_target_hi = self.hc4_target_hi[:, None]

        check_deadline(deadline, "building the programs")
        self.f = Program(g, self.eq_roots)
        jac_nodes = [d for row in jac for d in row if d is not None]
        check_deadline(deadline, "building the programs")
        self.fj = Program(g, self.eq_roots + jac_nodes)
        self._fj_f = self.fj.outputs[:n]
        self._fj_jac = self.fj.outputs[n:]
        self._jac_flat = np.flatnonzero(self.jac_structure.ravel())
        self._col_programs: dict = {}  # column subsets -> (Program, flat indices)
        self._mixed_programs: dict = {}  # groups of columns -> StackedColumns
        self.set_parameters(system.parameters)

    @cached_property
    def coupled(self) -> np.ndarray:
        """``(n,)`` variables whose Jacobian column depends on another variable: each is a
        factor of a product with another (``x y``, ``(1 - x) y``), or is otherwise coupled
        with one nonlinearly; a sign split pays on these (:func:`.solver.bisectors.split`).
        Computed on first use (``Solver.default``'s sign split asks; forward kinematics,
        with its own bisector, does not)."""
        out = np.zeros(self.n, dtype=np.bool_)
        nodes = self.fj.global_ids[self._fj_jac].tolist()  # the entries, row by row
        for node, j in zip(nodes, (self._jac_flat % self.n).tolist(), strict=True):
            if self.graph.depends[node] & ~(1 << j):
                out[j] = True
        return out

    # -- parameters -------------------------------------------------------------------------
    def set_parameters(self, values) -> None:
        """New parameter values: ``{name: value or (lo, hi)}`` (all names required)."""
        lo = np.empty(len(self.param_names))
        hi = np.empty(len(self.param_names))
        for i, name in enumerate(self.param_names):  # plain Python: called per tracking step
            if name not in values:
                raise KeyError(f"missing value for parameter {name!r}")
            v = values[name]
            if isinstance(v, (int, float, np.number)):
                a = b = float(v)
            else:
                a, b = (float(t) for t in v)
            if not (math.isfinite(a) and math.isfinite(b) and a <= b):
                raise ValueError(f"parameter {name!r} must be finite with lo <= hi")
            lo[i], hi[i] = a, b
        self.param_lo, self.param_hi = lo, hi
        self.param_mid = 0.5 * lo + 0.5 * hi
        self.system.parameters = {
            n: (float(a), float(b)) for n, a, b in zip(self.param_names, lo, hi)
        }

    def with_parameters(self, values) -> CompiledSystem:
        """This system with other parameter values (:meth:`set_parameters`), as a new object:
        the graph, the programs and the compiled column programs are shared, and neither this
        compiled system nor its :class:`System` changes."""
        out = copy.copy(self)
        out.system = copy.copy(self.system)
        out.set_parameters(values)
        return out

    # -- interval evaluation --------------------------------------------------------------
    def eval_f(self, lo, hi):
        """Enclosures of ``f`` over boxes: two ``(B, n)`` arrays."""
        return _chunked(self._eval_f, self.f.n_nodes, lo, hi)

    def _eval_f(self, lo, hi):
        LO, HI = self.f.eval_interval(lo, hi, self.param_lo, self.param_hi)
        return LO[self.f.outputs].T, HI[self.f.outputs].T

    def eval_f_at(self, x):
        """Rigorous enclosures of ``f`` at points ``x`` (degenerate boxes)."""
        return self.eval_f(x, x)

    def eval_fj(self, lo, hi, check_domain: bool = False):
        """Enclosures of ``f`` and of the Jacobian over boxes.

        Returns ``flo, fhi`` of shape ``(B, n)`` and ``jlo, jhi`` of shape ``(B, n, n)``;
        with ``check_domain`` also a ``(B,)`` mask of boxes on which ``f`` and ``J`` are
        defined everywhere (:meth:`Program.defined_mask`).
        """
        return _chunked(lambda lo, hi: self._eval_fj(lo, hi, check_domain), self.fj.n_nodes, lo, hi)

    def _eval_fj(self, lo, hi, check_domain: bool):
        B = lo.shape[0]
        LO, HI = self.fj.eval_interval(lo, hi, self.param_lo, self.param_hi)
        n = self.n
        jlo = np.zeros((B, n * n))
        jhi = np.zeros((B, n * n))
        jlo[:, self._jac_flat] = LO[self._fj_jac].T
        jhi[:, self._jac_flat] = HI[self._fj_jac].T
        out = (LO[self._fj_f].T, HI[self._fj_f].T, jlo.reshape(B, n, n), jhi.reshape(B, n, n))
        return (*out, self.fj.defined_mask(LO, HI)) if check_domain else out

    def _column_program(self, cols: tuple[int, ...]):
        """Program for ``f`` and the Jacobian columns ``cols`` only (built on first use)."""
        progs = self._col_programs
        if cols not in progs:
            n = self.n
            mask = np.zeros((n, n), dtype=bool)
            mask[:, list(cols)] = self.jac_structure[:, list(cols)]
            jac = []
            for i in range(n):
                for j in range(n):
                    if mask[i, j]:
                        d = self.graph.derivative(self.eq_roots[i], j)
                        assert d is not None  # mask is the Jacobian's structure
                        jac.append(d)
            prog = Program(self.graph, self.eq_roots + jac)
            progs[cols] = (prog, np.flatnonzero(mask.ravel()))
        return progs[cols]

    def eval_fj_columns(self, lo, hi, cols):
        """Enclosures of ``f`` and of the Jacobian *columns* ``cols`` over boxes.

        Returns ``flo, fhi`` ``(B, n)``, ``jlo, jhi`` ``(B, n, n)`` (other columns zero) and
        the ``(B,)`` mask of boxes on which every evaluated node is defined.  Cheaper than
        :meth:`eval_fj` when only a few columns are needed (mixed Jacobians).
        """
        cols = tuple(sorted(int(c) for c in cols))
        prog, flat = self._column_program(cols)
        return _chunked(lambda lo, hi: self._eval_columns(prog, flat, lo, hi), prog.n_nodes, lo, hi)

    def _eval_columns(self, prog: Program, flat: np.ndarray, lo, hi):
        B = lo.shape[0]
        LO, HI = prog.eval_interval(lo, hi, self.param_lo, self.param_hi)
        n = self.n
        jlo = np.zeros((B, n * n))
        jhi = np.zeros((B, n * n))
        out = prog.outputs
        jlo[:, flat] = LO[out[n:]].T
        jhi[:, flat] = HI[out[n:]].T
        return (
            LO[out[:n]].T,
            HI[out[:n]].T,
            jlo.reshape(B, n, n),
            jhi.reshape(B, n, n),
            prog.defined_mask(LO, HI),
        )

    def _mixed_program(self, groups: tuple[tuple[int, ...], ...]) -> StackedColumns:
        """The stacked program of Hansen's mixed Jacobian over ``groups`` (built on first use)."""
        if groups not in self._mixed_programs:
            self._mixed_programs[groups] = StackedColumns(
                self.graph, self.eq_roots, self.jac_structure, groups
            )
        return self._mixed_programs[groups]

    def prepare_mixed(self, groups) -> None:
        """Build the programs :meth:`eval_fj_mixed` uses for ``groups`` (at load time)."""
        self._mixed_program(_group_key(groups))

    def eval_fj_mixed(self, lo, hi, c, groups):
        """Hansen's mixed Jacobian: the columns of group ``k`` (boolean masks partitioning
        the variables) over the box that is ``[lo, hi]`` on groups ``1..k`` and ``c`` on the
        later ones.

        Returns ``jlo, jhi`` ``(B, n, n)`` and the ``(B,)`` mask of boxes on which ``f`` and
        those columns are defined and smooth (the last group's box is ``X`` itself).  Every
        group is evaluated in one stacked program (:mod:`.stacked`), in chunks of boxes; a
        program too large for :data:`STACK_MIN_BOXES` boxes a chunk, on a batch too large
        for one call, one column program per group (:meth:`eval_fj_columns`, built on
        first use): the same floats.
        """
        stacked = self._stacked(groups, lo.shape[0])
        if stacked is not None:
            return self._eval_stacked(stacked, lo, hi, c)[2:]
        return self._mixed_by_group(lo, hi, c, groups)

    def eval_f_mixed(self, lo, hi, c, groups):
        """``f(c)`` (rigorous, ``(B, n)`` bounds) and :meth:`eval_fj_mixed`, in the same
        calls of the stacked program (its copy of ``f`` at ``c``): the floats of
        :meth:`eval_f_at` and :meth:`eval_fj_mixed`.  Returns ``(flo, fhi, jlo, jhi,
        defined)``."""
        stacked = self._stacked(groups, lo.shape[0])
        if stacked is None:
            return (*self.eval_f_at(c), *self._mixed_by_group(lo, hi, c, groups))
        return self._eval_stacked(stacked, lo, hi, c)

    def _eval_stacked(self, stacked: StackedColumns, lo, hi, c):
        plo, phi = self.param_lo, self.param_hi
        return _chunked(
            lambda lo, hi, c: stacked.eval_with_f(lo, hi, c, plo, phi),
            stacked.program.n_nodes,
            lo,
            hi,
            c,
        )

    def _stacked(self, groups, boxes: int) -> StackedColumns | None:
        """The stacked program of the mixed Jacobian over ``groups`` if ``boxes`` boxes are
        evaluated in it: in one call of at most :data:`CHUNK_ELEMENTS` node values, or in
        chunks of at least :data:`STACK_MIN_BOXES` boxes; else ``None``."""
        stacked = self._mixed_program(_group_key(groups))
        nodes = stacked.program.n_nodes
        if boxes * nodes <= CHUNK_ELEMENTS or CHUNK_ELEMENTS // nodes >= STACK_MIN_BOXES:
            return stacked
        return None

    def _mixed_by_group(self, lo, hi, c, groups):
        """:meth:`eval_fj_mixed` one column program per group."""
        B, n = lo.shape
        mlo = np.zeros((B, n, n))
        mhi = np.zeros((B, n, n))
        defined = np.ones(B, dtype=bool)
        done = np.zeros(n, dtype=bool)
        for g in groups:
            done |= g
            blo = np.where(done, lo, c)
            bhi = np.where(done, hi, c)
            _, _, jlo, jhi, de = self.eval_fj_columns(blo, bhi, np.flatnonzero(g))
            mlo[:, :, g] = jlo[:, :, g]
            mhi[:, :, g] = jhi[:, :, g]
            defined &= de
        return mlo, mhi, defined

    def eval_constraints(self, lo, hi):
        """Enclosures of the constraint expressions over boxes: two ``(B, m)`` arrays."""
        return _chunked(self._eval_constraints, self.hc4.n_nodes, lo, hi)

    def _eval_constraints(self, lo, hi):
        LO, HI = self.hc4.eval_interval(lo, hi, self.param_lo, self.param_hi)
        out = self.hc4.outputs[self.n :]
        return LO[out].T, HI[out].T

    # -- float evaluation (approximate, for Newton iterations) ----------------------------
    def eval_f_float(self, x):
        V = self.f.eval_float(x, self.param_mid)
        return V[self.f.outputs].T

    def eval_fj_float(self, x):
        """Approximate ``f(x)`` ``(B, n)`` and ``J(x)`` ``(B, n, n)`` in floating point."""
        B = x.shape[0]
        V = self.fj.eval_float(x, self.param_mid)
        J = np.zeros((B, self.n * self.n))
        J[:, self._jac_flat] = V[self._fj_jac].T
        return V[self._fj_f].T, J.reshape(B, self.n, self.n)

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_scalar"] = None  # generated functions are rebuilt on demand (not picklable)
        return state

    # -- one box at a time (generated straight-line code, see :mod:`.scalar`) -------------
    def scalar(self):
        """``(f, fj)`` :class:`~.scalar.ScalarProgram` objects, built on first use."""
        if getattr(self, "_scalar", None) is None:
            from .scalar import ScalarProgram

            outs_f = self.f.global_ids[self.f.outputs].tolist()
            outs_fj = self.fj.global_ids[self.fj.outputs].tolist()
            self._scalar = (ScalarProgram(self.graph, outs_f), ScalarProgram(self.graph, outs_fj))
        return self._scalar

    def fj_box(self, lo, hi):
        """Enclosures of ``f`` and ``J`` over one box (1-D arrays in, numpy arrays out)."""
        _, sfj = self.scalar()
        flo, fhi = sfj.interval(
            lo.tolist(), hi.tolist(), self.param_lo.tolist(), self.param_hi.tolist()
        )
        n = self.n
        jlo = np.zeros(n * n)
        jhi = np.zeros(n * n)
        jlo[self._jac_flat] = flo[n:]
        jhi[self._jac_flat] = fhi[n:]
        return np.array(flo[:n]), np.array(fhi[:n]), jlo.reshape(n, n), jhi.reshape(n, n)

    def f_point(self, x):
        """Rigorous enclosure of ``f`` at one point."""
        sf, _ = self.scalar()
        xl = x.tolist()
        flo, fhi = sf.interval(xl, xl, self.param_lo.tolist(), self.param_hi.tolist())
        return np.array(flo), np.array(fhi)

    def fj_point_float(self, x):
        """Approximate ``f(x)`` and ``J(x)`` at one point (floats)."""
        _, sfj = self.scalar()
        v = sfj.floats(x.tolist(), self.param_mid.tolist())
        n = self.n
        J = np.zeros(n * n)
        J[self._jac_flat] = v[n:]
        return np.array(v[:n]), J.reshape(n, n)

    # -- HC4 -------------------------------------------------------------------------------
    def hc4_revise(self, lo, hi):
        """One forward-backward pass over all equations and constraints.

        Returns the narrowed boxes ``(lo, hi)`` and a mask of boxes proven empty.
        """
        return _chunked(self._hc4_revise, self.hc4.n_nodes, lo, hi)

    def _hc4_revise(self, lo, hi):
        p = self.hc4
        LO, HI = p.eval_interval(lo, hi, self.param_lo, self.param_hi)
        forward = (LO.copy(), HI.copy())
        out = self.hc4_out
        LO[out] = np.fmax(LO[out], self.hc4_target_lo)
        HI[out] = np.fmin(HI[out], self.hc4_target_hi)
        p.revise(LO, HI, forward)
        empty = np.any(~(LO <= HI), axis=0)
        n = self.n
        new_lo = np.fmax(LO[:n].T, lo)
        new_hi = np.fmin(HI[:n].T, hi)
        return new_lo, new_hi, empty
