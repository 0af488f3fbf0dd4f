"""Level-grouped, batched evaluation of a DAG: interval values, float values, HC4-revise.

A :class:`Program` compiles the sub-DAG needed for some output nodes into *groups*: all
nodes with the same depth ("level", longest path from a leaf) and the same operation.
Nodes are renumbered so that every group writes one contiguous slice of the value arrays.
Evaluating a batch of ``B`` boxes then costs a handful of numpy calls per group, whatever
the batch size, and each call works on ``(group size, B)`` arrays.  This is what makes a
pure-Python solver fast: the number of Python-level steps depends on the depth of the
expressions, not on the number of nodes or boxes.

The forward pass merges groups further (:func:`_schedule`): independent groups of one
operation whose kernel is element by element and whose rounding does not depend on the
array size (``+``, ``-``, ``*``, ``+ c``, negation) are evaluated together, whatever their
level, in rows laid out so that each merged group is still one slice.  Every node gets the
same bits as level by level; the backward pass keeps the level groups (in HC4 the order of
the projections decides how much they contract).

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


#: operations whose forward kernel works element by element with a rounding rule that does
#: not depend on the array size (:mod:`certsolve.interval.inplace`, exact negation): groups of
#: them may be merged without changing a single bit of the result
_MERGEABLE = frozenset({"add", "sub", "mul", "cadd", "neg"})


def _schedule(units: list[list[int]], graph: Graph) -> list[list[int]]:
    """Forward order of the level groups ``units``, merging independent ones of one operation.

    List scheduling: repeatedly take the first group whose children are all computed and,
    if its operation is in :data:`_MERGEABLE`, every other ready group of that operation;
    they are evaluated together (one set of numpy calls).  Nodes of one batch never depend
    on each other, so each node gets exactly the value the level-by-level order gives it.
    """
    owner = {x: u for u, members in enumerate(units) for x in members}
    deps = [{owner[a] for x in members for a in graph.args[x] if a in owner} for members in units]
    done: set[int] = set()
    remaining = list(range(len(units)))
    batches = []
    while remaining:
        ready = [u for u in remaining if deps[u] <= done]
        op = graph.op[units[ready[0]][0]]
        if op in _MERGEABLE:
            batch = [u for u in ready if graph.op[units[u][0]] == op]
        else:
            batch = ready[:1]
        batches.append(batch)
        done.update(batch)
        remaining = [u for u in remaining if u not in done]
    return batches


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
        units: list[list[int]] = []  # the HC4 groups: runs of equal (level, op)
        for x in inner:
            if units and gkey(units[-1][0]) == gkey(x):
                units[-1].append(x)
            else:
                units.append([x])
        batches = _schedule(units, graph)
        order = list(range(n + npar)) + consts + [x for bt in batches for u in bt for x in units[u]]
        local = {g: i for i, g in enumerate(order)}
        self.global_ids = np.array(order, dtype=np.int64)
        self.n_nodes = len(order)
        self.param_slice = slice(n, n + npar)
        self.const_slice = slice(n + npar, n + npar + len(consts))
        self.const_lo = np.array([graph.param[c][0] for c in consts], dtype=np.float64)[:, None]
        self.const_hi = np.array([graph.param[c][1] for c in consts], dtype=np.float64)[:, None]
        self.const_mid = 0.5 * self.const_lo + 0.5 * self.const_hi
        self.outputs = np.array([local[o] for o in outputs], dtype=np.int64)

        def group(members: list[int]) -> Group:
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
            unique = len(set(kids.tolist())) == len(kids)  # (np.unique imports numpy.ma)
            la = () if unique else _layers(a)
            lb = () if unique or b is None else _layers(b)
            start = local[members[0]]
            return Group(op, start, start + len(members), a, b, param, unique, la, lb)

        #: backward (HC4) groups, by level: the order and grouping define what revise computes
        self.groups = [group(members) for members in units]
        #: forward groups: the same nodes, fewer numpy calls (see :func:`_schedule`)
        self.fwd_groups = [group([x for u in bt for x in units[u]]) for bt in batches]
        # groups whose operation is not smooth everywhere (domain restriction, poles, kinks)
        self._restricted = [g for g in self.fwd_groups if g.op in SMOOTH]
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
            for g in self.fwd_groups:
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
            for g in self.fwd_groups:
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
