"""Level-grouped, batched evaluation of a DAG: interval values, float values, HC4-revise.

A :class:`Program` compiles the sub-DAG needed for some output nodes into *groups*: all
nodes with the same depth ("level", longest path from a leaf) and the same operation.
Nodes are renumbered so that every group writes one contiguous slice of the value arrays.
Evaluating a batch of ``B`` boxes then costs a handful of numpy calls per group, whatever
the batch size, and each call works on ``(group size, B)`` arrays.  This is what makes a
pure-Python solver fast: the number of Python-level steps depends on the depth of the
expressions, not on the number of nodes or boxes.

Value arrays have shape ``(n_nodes, B)``: row ``i`` holds node ``i`` (local numbering) for
every box.  Variables occupy rows ``0 .. n_vars-1``, parameters the next ``n_params`` rows.

:meth:`Program.revise` is the backward half of HC4 (Benhamou et al. 1999): given the
forward values with the outputs intersected with their targets, it walks the groups from
the top down and narrows every child with the inverse image of its parent
(:mod:`certsolve.interval.projections`).  A node shared by several parents is intersected
with the projection from each (``ufunc.at`` when a group touches the same child twice).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..interval import inplace as IP
from .graph import Graph
from .ops import BACKWARD as _BWD
from .ops import FLOAT as _FLT
from .ops import FORWARD as _FWD
from .ops import SMOOTH

__all__ = ["Program"]


# forward ops writing into the node rows (fewer temporaries, see interval.inplace):
# (xlo, xhi, ylo, yhi, param, out_lo, out_hi)
_FWD_INTO = {
    "add": lambda a, b, c, d, p, o, q: IP.add_into(a, b, c, d, o, q),
    "sub": lambda a, b, c, d, p, o, q: IP.sub_into(a, b, c, d, o, q),
    "mul": lambda a, b, c, d, p, o, q: IP.mul_into(a, b, c, d, o, q),
    "cadd": lambda a, b, c, d, p, o, q: IP.shift_into(a, b, p, o, q),
}


@dataclass(frozen=True)
class Group:
    """Nodes ``start:stop`` (local numbering) computed by one ``op`` from children ``a``, ``b``."""

    op: str
    start: int
    stop: int
    a: np.ndarray
    b: np.ndarray | None
    param: object  # column array (k, 1) for cadd/cmul, int for pow, else None
    unique_children: bool  # no child index repeated within the group (direct write-back)
    #: when children repeat: for each operand, layers (positions, node ids) in which every
    #: node id occurs at most once, so the intersection is written with plain fancy indexing
    layers_a: tuple = ()
    layers_b: tuple = ()


def _layers(idx: np.ndarray) -> tuple:
    """Split positions of ``idx`` into layers where each node id occurs at most once."""
    count: dict[int, int] = {}
    rank = np.empty(len(idx), dtype=np.int64)
    for p, v in enumerate(idx.tolist()):
        rank[p] = count.get(v, 0)
        count[v] = rank[p] + 1
    out = []
    for r in range(int(rank.max()) + 1 if len(idx) else 0):
        pos = np.flatnonzero(rank == r)
        out.append((pos, idx[pos]))
    return tuple(out)


class Program:
    """Batched evaluator for the sub-DAG of ``graph`` that computes ``outputs``."""

    def __init__(self, graph: Graph, outputs: Sequence[int]):
        n = len(graph.variables)
        npar = len(graph.parameters)
        self.n_vars = n
        self.n_params = npar
        outputs = [int(o) for o in outputs]
        # every variable and parameter has a row, used or not
        needed = set(range(n + npar)) | set(graph.ancestors(outputs))
        level: dict[int, int] = {}
        for x in sorted(needed):  # ids are topologically ordered
            args = graph.args[x]
            level[x] = 0 if not args else 1 + max(level[a] for a in args)
        consts = sorted(x for x in needed if graph.op[x] == "const")

        def gkey(x):
            op = graph.op[x]
            p = graph.param[x] if op == "pow" else None
            return (level[x], op, p if p is not None else 0)

        inner = sorted((x for x in needed if level[x] > 0), key=lambda x: (gkey(x), x))
        order = list(range(n + npar)) + consts + inner
        local = {g: i for i, g in enumerate(order)}
        self.global_ids = np.array(order, dtype=np.int64)
        self.n_nodes = len(order)
        self.param_slice = slice(n, n + npar)
        self.const_slice = slice(n + npar, n + npar + len(consts))
        self.const_lo = np.array([graph.param[c][0] for c in consts], dtype=np.float64)[:, None]
        self.const_hi = np.array([graph.param[c][1] for c in consts], dtype=np.float64)[:, None]
        self.const_mid = 0.5 * self.const_lo + 0.5 * self.const_hi
        self.outputs = np.array([local[o] for o in outputs], dtype=np.int64)

        groups: list[Group] = []
        i = n + npar + len(consts)
        while i < len(order):
            key = gkey(order[i])
            j = i
            while j < len(order) and gkey(order[j]) == key:
                j += 1
            members = order[i:j]
            op = graph.op[members[0]]
            a = np.array([local[graph.args[m][0]] for m in members], dtype=np.int64)
            b = None
            if len(graph.args[members[0]]) == 2:
                b = np.array([local[graph.args[m][1]] for m in members], dtype=np.int64)
            param: np.ndarray | int | None
            if op in ("cadd", "cmul"):
                param = np.array([graph.param[m] for m in members], dtype=np.float64)[:, None]
            elif op == "pow":
                param = int(graph.param[members[0]])
            else:
                param = None
            kids = a if b is None else np.concatenate([a, b])
            unique = len(np.unique(kids)) == len(kids)
            la = () if unique else _layers(a)
            lb = () if unique or b is None else _layers(b)
            groups.append(Group(op, i, j, a, b, param, unique, la, lb))
            i = j
        self.groups = groups
        # groups whose operation is not smooth everywhere (domain restriction, poles, kinks)
        self._restricted = [g for g in groups if g.op in SMOOTH]
        self.n_levels = 1 + max([level[x] for x in needed], default=0)

    # -- evaluation ------------------------------------------------------------------------
    def eval_interval(
        self, lo: np.ndarray, hi: np.ndarray, plo=None, phi=None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Interval values of every node for a batch of boxes ``lo, hi`` of shape ``(B, n)``.

        ``plo, phi`` are the parameter values (shape ``(p,)``, same for every box).
        Returns ``(LO, HI)`` of shape ``(n_nodes, B)``.
        """
        B = lo.shape[0]
        LO = np.empty((self.n_nodes, B))
        HI = np.empty((self.n_nodes, B))
        n = self.n_vars
        LO[:n] = lo.T
        HI[:n] = hi.T
        if self.n_params:
            LO[self.param_slice] = np.asarray(plo, dtype=float)[:, None]
            HI[self.param_slice] = np.asarray(phi, dtype=float)[:, None]
        LO[self.const_slice] = self.const_lo
        HI[self.const_slice] = self.const_hi
        with np.errstate(all="ignore"):
            for g in self.groups:
                into = _FWD_INTO.get(g.op)
                if into is not None:
                    b_lo = None if g.b is None else LO[g.b]
                    b_hi = None if g.b is None else HI[g.b]
                    into(
                        LO[g.a], HI[g.a], b_lo, b_hi, g.param,
                        LO[g.start : g.stop], HI[g.start : g.stop],
                    )  # fmt: skip
                    continue
                if g.b is None:
                    rlo, rhi = _FWD[g.op](LO[g.a], HI[g.a], None, None, g.param)
                else:
                    rlo, rhi = _FWD[g.op](LO[g.a], HI[g.a], LO[g.b], HI[g.b], g.param)
                LO[g.start : g.stop] = rlo
                HI[g.start : g.stop] = rhi
        return LO, HI

    def defined_mask(self, LO: np.ndarray, HI: np.ndarray) -> np.ndarray:
        """Boxes on which every node is defined, continuous and differentiable everywhere.

        The tests are :data:`.ops.SMOOTH` (``sqrt`` of a non-negative argument, ``log`` of a
        positive one, no divisor or negative power over 0, no pole of ``tan``, no kink of
        ``abs``/``min``/``max``, ...).  Certification requires this: the Krawczyk and Newton
        theorems need ``f`` continuously differentiable on the whole box.
        """
        ok = np.ones(LO.shape[1], dtype=bool)
        for g in self._restricted:
            b_lo = None if g.b is None else LO[g.b]
            b_hi = None if g.b is None else HI[g.b]
            z = slice(g.start, g.stop)
            test = SMOOTH[g.op](LO[g.a], HI[g.a], b_lo, b_hi, LO[z], HI[z], g.param)
            ok &= np.all(test, axis=0)
        return ok

    def eval_float(self, x: np.ndarray, pv=None) -> np.ndarray:
        """Float values of every node at points ``x`` of shape ``(B, n)``; ``(n_nodes, B)``.

        ``pv`` holds (approximate) parameter values, shape ``(p,)``.
        """
        V = np.empty((self.n_nodes, x.shape[0]))
        V[: self.n_vars] = x.T
        if self.n_params:
            V[self.param_slice] = np.asarray(pv, dtype=float)[:, None]
        V[self.const_slice] = self.const_mid
        with np.errstate(all="ignore"):
            for g in self.groups:
                V[g.start : g.stop] = _FLT[g.op](V[g.a], None if g.b is None else V[g.b], g.param)
        return V

    def revise(self, LO: np.ndarray, HI: np.ndarray) -> None:
        """Backward pass of HC4, in place, on forward values whose outputs were narrowed."""
        with np.errstate(all="ignore"):
            for g in reversed(self.groups):
                bwd = _BWD.get(g.op)
                if bwd is None:
                    continue
                zlo = LO[g.start : g.stop]
                zhi = HI[g.start : g.stop]
                if g.b is None:
                    nxlo, nxhi = bwd(zlo, zhi, LO[g.a], HI[g.a], None, None, g.param)
                    self._write(LO, HI, g.a, nxlo, nxhi, g.unique_children, g.layers_a)
                else:
                    nxlo, nxhi, nylo, nyhi = bwd(
                        zlo, zhi, LO[g.a], HI[g.a], LO[g.b], HI[g.b], g.param
                    )
                    self._write(LO, HI, g.a, nxlo, nxhi, g.unique_children, g.layers_a)
                    self._write(LO, HI, g.b, nylo, nyhi, g.unique_children, g.layers_b)

    @staticmethod
    def _write(LO, HI, idx, lo, hi, unique: bool, layers) -> None:
        """Intersect children with their projections (each projection already ⊆ the child)."""
        if unique:
            LO[idx] = lo
            HI[idx] = hi
            return
        # a node may occur several times: intersect layer by layer (ids unique in a layer);
        # fmax/fmin ignore a NaN bound, which only comes from an empty operand
        for pos, ids in layers:
            LO[ids] = np.fmax(LO[ids], lo[pos])
            HI[ids] = np.fmin(HI[ids], hi[pos])
