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
    #: the rows of ``a`` and ``b`` as a slice where they are consecutive (a view to read, a
    #: block to write: no index array to walk), else ``a`` and ``b`` themselves
    ra: slice | np.ndarray | None = None
    rb: slice | np.ndarray | None = None


def _rows(idx: np.ndarray | None) -> slice | np.ndarray | None:
    """``idx`` as a slice when it is ``k, k + 1, ...``, else ``idx``."""
    if idx is None or not len(idx):
        return idx
    first = int(idx[0])
    if np.array_equal(idx, np.arange(first, first + len(idx))):
        return slice(first, first + len(idx))
    return idx


def _layers(idx: np.ndarray) -> tuple:
    """Split positions of ``idx`` into layers where each node id occurs at most once.

    Layer ``r`` holds, in increasing position, the ``r``-th occurrence of every id (the rank
    of a position among the equal ids before it, from a stable sort)."""
    if len(set(idx.tolist())) == len(idx):  # the common case: one layer (or none)
        return ((np.arange(len(idx)), idx),) if len(idx) else ()
    by_id = np.argsort(idx, kind="stable")
    ids = idx[by_id]
    starts = np.zeros(len(ids), dtype=np.int64)  # where the run of each id starts
    starts[1:] = np.where(ids[1:] != ids[:-1], np.arange(1, len(ids)), 0)
    rank = np.empty(len(idx), dtype=np.int64)
    rank[by_id] = np.arange(len(ids)) - np.maximum.accumulate(starts)
    by_rank = np.argsort(rank, kind="stable")  # layer by layer, positions increasing
    stops = np.cumsum(np.bincount(rank)).tolist()
    layers = (by_rank[a:b] for a, b in zip([0, *stops[:-1]], stops))
    return tuple((pos, idx[pos]) for pos in layers)


def _levels(has_args: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Depth of every node: 0 for a leaf, else ``1 + max`` over its children (positions
    ``a``, ``b``; ``b = a`` for a unary node, anything for a leaf).  A fixpoint of whole-array
    steps, one per level: after step ``d`` every node of depth ``<= d`` has its depth."""
    level = np.zeros(len(a), dtype=np.int64)
    while True:
        new = np.where(has_args, 1 + np.maximum(level[a], level[b]), 0)
        if np.array_equal(new, level):
            return level
        level = new


#: operations whose forward kernel works element by element with a rounding rule that does
#: not depend on the array size (:mod:`certsolve.interval.inplace`, exact negation): groups of
#: them may be merged without changing a single bit of the result
_MERGEABLE = frozenset({"add", "sub", "mul", "cadd", "neg"})


def _schedule(deps: list[set[int]], ops: list[str]) -> list[list[int]]:
    """Forward order of the level groups, merging independent ones of one operation.

    ``deps[u]``: the groups whose nodes group ``u``'s children are; ``ops[u]``: its operation.
    List scheduling: repeatedly take the first group whose children are all computed and,
    if its operation is in :data:`_MERGEABLE`, every other ready group of that operation;
    they are evaluated together (one set of numpy calls).  Nodes of one batch never depend
    on each other, so each node gets exactly the value the level-by-level order gives it.
    """
    done: set[int] = set()
    remaining = list(range(len(deps)))
    batches = []
    while remaining:
        ready = [u for u in remaining if deps[u] <= done]
        op = ops[ready[0]]
        if op in _MERGEABLE:
            batch = [u for u in ready if ops[u] == op]
        else:
            batch = ready[:1]
        batches.append(batch)
        done.update(batch)
        remaining = [u for u in remaining if u not in done]
    return batches


class Program:
    """Batched evaluator for the sub-DAG of ``graph`` that computes ``outputs``."""

    def __init__(self, graph: Graph, outputs: Sequence[int]):
        """Compile: the needed nodes sorted by (level, operation, power, id), cut into runs
        of equal (level, operation, power) -- the HC4 groups --, then scheduled forward
        (:func:`_schedule`).  Whole-array steps over the nodes; Python loops only over the
        groups (and a list per node to read the graph's tables)."""
        n = len(graph.variables)
        npar = len(graph.parameters)
        self.n_vars = n
        self.n_params = npar
        outputs = [int(o) for o in outputs]
        # every variable and parameter has a row, used or not; ids are topologically ordered
        ids = np.array(sorted(set(range(n + npar)) | set(graph.ancestors(outputs))), dtype=np.int64)
        gops = [graph.op[x] for x in ids.tolist()]
        gargs = [graph.args[x] for x in ids.tolist()]
        code = {name: i for i, name in enumerate(sorted(set(gops)))}  # ordered as the names
        opc = np.array([code[o] for o in gops], dtype=np.int64)
        arity = np.array([len(t) for t in gargs], dtype=np.int64)
        first = np.array([t[0] if t else x for x, t in zip(ids.tolist(), gargs)], dtype=np.int64)
        second = np.array(
            [t[1] if len(t) > 1 else f for t, f in zip(gargs, first.tolist())], dtype=np.int64
        )
        a_pos = np.searchsorted(ids, first)  # children as positions in ``ids``
        b_pos = np.searchsorted(ids, second)
        level = _levels(arity > 0, a_pos, b_pos)
        power = np.zeros(len(ids))
        pow_at = [i for i, o in enumerate(gops) if o == "pow"]
        power[pow_at] = [graph.param[int(ids[i])] for i in pow_at]

        consts = np.flatnonzero(np.array([o == "const" for o in gops], dtype=bool))
        inner = np.flatnonzero(level > 0)
        inner = inner[np.lexsort((ids[inner], power[inner], opc[inner], level[inner]))]
        key = np.stack([level[inner], opc[inner], power[inner]])  # a group: one key
        cut = np.flatnonzero(np.any(key[:, 1:] != key[:, :-1], axis=0)) + 1
        units = np.split(inner, cut) if len(inner) else []  # the HC4 groups (positions)
        owner = np.full(len(ids), -1, dtype=np.int64)
        for u, members in enumerate(units):
            owner[members] = u
        unit_of = owner[inner]
        kids = np.concatenate([owner[a_pos[inner]], owner[b_pos[inner]]])
        pairs = (np.concatenate([unit_of, unit_of]) * len(units) + kids)[kids >= 0]
        deps: list[set[int]] = [set() for _ in units]
        for pair in set(pairs.tolist()):
            deps[pair // len(units)].add(pair % len(units))
        unit_ops = [gops[int(m[0])] for m in units]
        batches = _schedule(deps, unit_ops)

        order = np.concatenate(
            [np.arange(n + npar), consts, *[units[u] for bt in batches for u in bt]]
        ).astype(np.int64)
        local = np.empty(len(ids), dtype=np.int64)  # position in ``ids`` -> local row
        local[order] = np.arange(len(order))
        self.global_ids = ids[order]
        self.n_nodes = len(order)
        self.param_slice = slice(n, n + npar)
        self.const_slice = slice(n + npar, n + npar + len(consts))
        cvals = [graph.param[int(ids[c])] for c in consts]
        self.const_lo = np.array([v[0] for v in cvals], dtype=np.float64)[:, None]
        self.const_hi = np.array([v[1] for v in cvals], dtype=np.float64)[:, None]
        self.const_mid = 0.5 * self.const_lo + 0.5 * self.const_hi
        self.outputs = local[np.searchsorted(ids, np.array(outputs, dtype=np.int64))]

        def group(members: np.ndarray) -> Group:
            lead = int(members[0])
            op = gops[lead]
            a = local[a_pos[members]]
            b = local[b_pos[members]] if arity[lead] == 2 else None
            param: np.ndarray | int | None
            if op in ("cadd", "cmul"):
                values = [graph.param[x] for x in ids[members].tolist()]
                param = np.array(values, dtype=np.float64)[:, None]
            elif op == "pow":
                param = int(graph.param[int(ids[lead])])
            else:
                param = None
            kids = (a if b is None else np.concatenate([a, b])).tolist()
            unique = len(set(kids)) == len(kids)  # (np.unique imports numpy.ma)
            la = () if unique else _layers(a)
            lb = () if unique or b is None else _layers(b)
            start = int(local[lead])
            return Group(
                op, start, start + len(members), a, b, param, unique, la, lb, _rows(a), _rows(b)
            )

        #: backward (HC4) groups, by level: the order and grouping define what revise computes
        self.groups = [group(members) for members in units]
        #: forward groups: the same nodes, fewer numpy calls (see :func:`_schedule`)
        self.fwd_groups = [group(np.concatenate([units[u] for u in bt])) for bt in batches]
        # groups whose operation is not smooth everywhere (domain restriction, poles, kinks)
        self._restricted = [g for g in self.fwd_groups if g.op in SMOOTH]
        self.n_levels = 1 + int(level.max(initial=0))

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
                # the children's rows are read in place where consecutive (the kernels
                # never write their operands, and a group never feeds itself)
                into = _FWD_INTO.get(g.op)
                if into is not None:
                    b_lo = None if g.rb is None else LO[g.rb]
                    b_hi = None if g.rb is None else HI[g.rb]
                    into(
                        LO[g.ra], HI[g.ra], b_lo, b_hi, g.param,
                        LO[g.start : g.stop], HI[g.start : g.stop],
                    )  # fmt: skip
                    continue
                if g.rb is None:
                    rlo, rhi = _FWD[g.op](LO[g.ra], HI[g.ra], None, None, g.param)
                else:
                    rlo, rhi = _FWD[g.op](LO[g.ra], HI[g.ra], LO[g.rb], HI[g.rb], g.param)
                LO[g.start : g.stop] = rlo
                HI[g.start : g.stop] = rhi
        return LO, HI

    def defined_mask(
        self, LO: np.ndarray, HI: np.ndarray, skip: np.ndarray | None = None
    ) -> np.ndarray:
        """Boxes on which every node is defined, continuous and differentiable everywhere.

        The tests are :data:`.ops.SMOOTH` (``sqrt`` of a non-negative argument, ``log`` of a
        positive one, no divisor or negative power over 0, no pole of ``tan``, no kink of
        ``abs``/``min``/``max``, ...).  Certification requires this: the Krawczyk and Newton
        theorems need ``f`` continuously differentiable on the whole box.  ``skip``: a mask
        of the local rows whose test is left out.
        """
        ok = np.ones(LO.shape[1], dtype=bool)
        for g in self._restricted:
            b_lo = None if g.b is None else LO[g.b]
            b_hi = None if g.b is None else HI[g.b]
            z = slice(g.start, g.stop)
            test = SMOOTH[g.op](LO[g.a], HI[g.a], b_lo, b_hi, LO[z], HI[z], g.param)
            if skip is not None and skip[z].any():
                test = test | skip[z, None]
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
                V[g.start : g.stop] = _FLT[g.op](
                    V[g.ra], None if g.rb is None else V[g.rb], g.param
                )
        return V

    def revise(
        self,
        LO: np.ndarray,
        HI: np.ndarray,
        forward: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> None:
        """Backward pass of HC4, in place, on forward values whose outputs were narrowed.

        ``forward``: the values of the forward pass, before the outputs were narrowed.  A
        group whose nodes all still hold them, in every box, is skipped: a node ``z = x ∘ y``
        whose enclosure was not narrowed encloses ``x ∘ y`` over the children's forward
        enclosures, which hold their present ones, so the inverse image of ``z`` holds the
        children and the projection ``x ∩ ...`` gives ``x`` back (the bounds of every
        projection are rounded outward).  Skipping it changes no bound and saves its numpy
        calls: 35-47 % of the groups' projections on Trigexp1-024 and BroydenBanded-014
        searches, 10 % on Kin1.  (A NaN is never equal: such a group is projected.)
        """
        flo, fhi = forward if forward is not None else (None, None)
        with np.errstate(all="ignore"):
            for g in reversed(self.groups):
                bwd = _BWD.get(g.op)
                if bwd is None:
                    continue
                zlo = LO[g.start : g.stop]
                zhi = HI[g.start : g.stop]
                if flo is not None and fhi is not None:
                    z = slice(g.start, g.stop)
                    if not ((zlo != flo[z]).any() or (zhi != fhi[z]).any()):
                        continue
                # distinct children: their rows read in place where consecutive (a
                # projection may return an operand as it is; no write meets another's rows)
                a, b = (g.ra, g.rb) if g.unique_children else (g.a, g.b)
                if b is None:
                    nxlo, nxhi = bwd(zlo, zhi, LO[a], HI[a], None, None, g.param)
                    self._write(LO, HI, a, nxlo, nxhi, g.unique_children, g.layers_a)
                else:
                    nxlo, nxhi, nylo, nyhi = bwd(zlo, zhi, LO[a], HI[a], LO[b], HI[b], g.param)
                    self._write(LO, HI, a, nxlo, nxhi, g.unique_children, g.layers_a)
                    self._write(LO, HI, b, nylo, nyhi, g.unique_children, g.layers_b)

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
