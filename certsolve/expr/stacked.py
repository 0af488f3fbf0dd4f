"""Hansen's mixed Jacobian as one program: the column sub-DAGs of every group, stacked.

For groups ``G_1 .. G_K`` of variables (a partition), a box ``X`` and a point ``c`` in it,
Hansen's mixed Jacobian takes the columns of ``G_k`` over the box ``X_k`` that is ``X`` on
``G_1 .. G_k`` and ``c`` on the later groups (:class:`~certsolve.solver.contractors.
IntervalNewton` says why that is sound).  Each ``k`` needs ``f`` and the columns of ``G_k``
over a box of its own: evaluated one group at a time, that is one program call per group,
``K`` times the numpy calls of one program (``K = n`` with one variable per group).

:class:`StackedColumns` copies the ``K`` column sub-DAGs into one graph, copy ``k`` over
variables of its own (:meth:`.graph.Graph.copy_nodes`): a box of ``K n`` variables whose
block ``k`` is ``X_k``.  One :class:`~.program.Program` evaluates them all, the nodes of one
(level, operation) of every copy in one group: about the numpy calls of one copy, for the
same elementwise work as the ``K`` programs.

Each copy applies the same operations to the same inputs as group ``k``'s own program
(:meth:`.compiled.CompiledSystem.eval_fj_columns`), and every bound is rounded one ulp out
whatever the size of the arrays (:func:`certsolve.interval.rounding.up`), so the two give
the same floats.  Copy ``k`` holds the nodes of its columns only; ``f`` itself, which the
column programs evaluate over every ``X_k`` for their domain test, is in the last copy
alone, over ``X_K`` (``X`` itself: the groups partition the variables), which holds every
``X_k``.  The enclosures are inclusion-isotone (a bound is a monotone function of the
operands' bounds, then rounded outward), so ``f`` passes the test over ``X_k`` wherever it
passes over ``X_K``; and the ``n`` copies of ``f`` of a dense or banded system had cost
most of the program's elements for nothing (Trigexp1-024: 9,940 nodes, 2,094 without
them, the copy at ``c`` included).

One more copy, of ``f`` alone over the point ``c``, gives Newton's ``f(c)`` in the same
call (:meth:`StackedColumns.eval_with_f`): the floats of ``f``'s own program at ``c``, for
no numpy call of its own.  It is left out of the domain test, which stays that of the
``K`` copies.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .graph import Graph
from .program import Program

__all__ = ["StackedColumns"]


class StackedColumns:
    """``f`` and the columns of each group over its own box, in one :class:`Program`."""

    def __init__(
        self,
        graph: Graph,
        eq_roots: Sequence[int],
        structure: np.ndarray,
        groups: Sequence[Sequence[int]],
    ):
        n = len(graph.variables)
        K = len(groups)
        names = [f"{v}@{k}" for k in range(K + 1) for v in graph.variables]  # K: f at c
        stacked = Graph(names, graph.parameters)
        outputs: list[int] = []
        jac_out: list[int] = []  # positions in outputs of the Jacobian entries
        flat: list[int] = []  # their places in the flattened (n, n) Jacobian
        done = np.zeros((K + 1, n), dtype=bool)  # copy K: every variable at c
        tested: set[int] = set()  # the nodes of the K copies (the domain test)
        for k, cols in enumerate(groups):
            done[k:K, list(cols)] = True
            entries = [(i, j) for i in range(n) for j in cols if structure[i, j]]
            derivs = [graph.derivative(eq_roots[i], j) for i, j in entries]
            # f itself only in the last copy, over X (see the class docstring)
            f_roots = eq_roots if k == K - 1 else []
            roots = [*f_roots, *(d for d in derivs if d is not None)]
            mapped = stacked.copy_nodes(graph, roots, var_offset=k * n)
            tested.update(mapped.values())
            outputs += [mapped[r] for r in f_roots]
            for (i, j), d in zip(entries, derivs):
                assert d is not None  # entries follow the Jacobian's structure
                jac_out.append(len(outputs))
                outputs.append(mapped[d])
                flat.append(i * n + j)
        at_c = stacked.copy_nodes(graph, eq_roots, var_offset=K * n)
        f_out = len(outputs)
        outputs += [at_c[r] for r in eq_roots]
        self.n = n
        self.program = Program(stacked, outputs)
        self._jac_rows = self.program.outputs[jac_out]
        self._f_rows = self.program.outputs[f_out:]
        self._flat = np.array(flat, dtype=np.int64)
        #: ``done[k]``: the variables that span ``X`` in copy ``k``'s box (the others: ``c``)
        self.done = done
        #: local rows of the nodes only the copy at ``c`` has (no domain test)
        self._untested = ~np.isin(self.program.global_ids, np.array(sorted(tested)))

    def eval(self, lo, hi, c, plo, phi):
        """``(jlo, jhi, defined)``: the mixed Jacobian ``(B, n, n)`` (zero off the
        structure) and the boxes on which every node of every copy is defined and smooth
        (:meth:`.program.Program.defined_mask`)."""
        return self.eval_with_f(lo, hi, c, plo, phi)[2:]

    def eval_with_f(self, lo, hi, c, plo, phi):
        """``(flo, fhi, jlo, jhi, defined)``: :meth:`eval` and the enclosure of ``f(c)``
        ``(B, n)`` from the copy at ``c``."""
        B, n = lo.shape
        blo = np.where(self.done, lo[:, None, :], c[:, None, :]).reshape(B, -1)
        bhi = np.where(self.done, hi[:, None, :], c[:, None, :]).reshape(B, -1)
        LO, HI = self.program.eval_interval(blo, bhi, plo, phi)
        jlo = np.zeros((B, n * n))
        jhi = np.zeros((B, n * n))
        jlo[:, self._flat] = LO[self._jac_rows].T
        jhi[:, self._flat] = HI[self._jac_rows].T
        defined = self.program.defined_mask(LO, HI, skip=self._untested)
        f = self._f_rows
        return LO[f].T, HI[f].T, jlo.reshape(B, n, n), jhi.reshape(B, n, n), defined
