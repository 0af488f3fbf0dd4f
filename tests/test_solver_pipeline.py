"""The solver from parts: the batch protocol, the compositions (Sequence, FixPoint, Shave,
Inflate) and a Solver assembled from them.

* a Sequence runs its parts in order, each on what the previous one left, and stops when
  no box is left; a box proven empty stays empty (no later part sees it, nothing pushes
  it back or records it);
* a FixPoint sends back exactly the boxes that shrank as much as a bisection, and a search
  whose contractor halves a box at every round still stops;
* on the reference systems, no composition loses a solution: every reference point is in
  a certified solution's box or an undecided box;
* the recipe of ``docs/architecture.md`` (*Adding a contractor*): a custom part composed
  into the default pipeline runs, is named by the checkpoint fingerprint, and loses
  nothing.
"""

from __future__ import annotations

import inspect

import numpy as np
import pytest
from test_solver_contractors import NAMES, compiled, holds

from certsolve.expr import System, var
from certsolve.expr.compiled import CompiledSystem
from certsolve.solver import Solver, SolverLimits
from certsolve.solver.batch import Batch
from certsolve.solver.bisectors import SmearCurvatureMix, SmearSumRelative
from certsolve.solver.buffer import BoxStack
from certsolve.solver.certify import Certifier
from certsolve.solver.contractors import HC4, IntervalNewton
from certsolve.solver.pipeline import FixPoint, Inflate, Sequence, core, find, parts_of
from certsolve.solver.relaxation import PolytopeHull
from certsolve.solver.shaving import Shave


class Log:
    """A part that records the boxes it saw, then marks ``empty_rows`` of them empty (by
    their first coordinate, a label) and contracts nothing else."""

    def __init__(self, name: str, log: list, empty_labels=()):
        self.name, self.log, self.empty_labels = name, log, set(empty_labels)

    def apply(self, batch: Batch) -> None:
        labels = batch.lo[:, 0].tolist()
        self.log.append((self.name, labels))
        batch.empty |= np.isin(batch.lo[:, 0], list(self.empty_labels))

    def describe(self) -> str:
        return f"Log({self.name})"


class Halve:
    """Keeps the half of variable 0 that holds ``root`` (sound for a system whose only
    solution has ``x_0 = root``): the box halves at every call, for ever."""

    def __init__(self, root: float):
        self.root = root
        self.calls = 0

    def apply(self, batch: Batch) -> None:
        self.calls += 1
        lo, hi = batch.lo.copy(), batch.hi.copy()
        mid = 0.5 * (lo[:, 0] + hi[:, 0])
        left = self.root <= mid
        hi[left, 0] = mid[left]
        lo[~left, 0] = mid[~left]
        batch.lo, batch.hi = lo, hi

    def describe(self) -> str:
        return f"Halve({self.root!r})"


def _batch(labels, csys, **kw) -> Batch:
    lo = np.array([[float(k), 0.0] for k in labels])
    hi = lo + 1.0
    return Batch(lo, hi, csys=csys, eps=1e-8, **kw)


def _sqrt2() -> CompiledSystem:
    x, y = var("x"), var("y")
    dom = np.array([[0.0, 4.0], [0.0, 4.0]])
    return CompiledSystem(System(["x", "y"], dom, [x * x - 2, y - 1]))


def test_sequence_runs_its_parts_in_order_and_drops_empty_boxes():
    log: list = []
    seq = Sequence(Log("a", log, empty_labels=[1.0]), Log("b", log), Log("c", log, [0.0, 2.0]))
    batch = _batch([0, 1, 2], _sqrt2())
    seq.apply(batch)
    # b does not see the box a proved empty; after c nothing is left
    assert log == [("a", [0.0, 1.0, 2.0]), ("b", [0.0, 2.0]), ("c", [0.0, 2.0])]
    assert batch.size == 0
    log.clear()
    Sequence(Log("a", log, [0.0]), Log("b", log)).apply(_batch([0], _sqrt2()))
    assert log == [("a", [0.0])]  # no box left: b does not run
    assert seq.describe() == "Sequence(Log(a), Log(b), Log(c))"


def test_an_empty_box_stays_empty_through_a_fixpoint():
    """A box proven empty is neither pushed back nor kept, whatever its shrinking."""
    stack = BoxStack(2)
    log: list = []
    fix = FixPoint(Sequence(Log("a", log, [1.0]), Halve(root=0.25)))
    batch = _batch([0, 1, 2], _sqrt2(), stack=stack)
    fix.apply(batch)
    assert len(stack) == 0  # what goes back waits for the end of the round
    batch.flush()
    lo, _ = stack.snapshot()
    # every live box halved: both go back for another round, the empty one is gone
    assert sorted(lo[:, 0].tolist()) == [0.0, 2.0] and batch.size == 0


def test_a_fixpoint_sends_back_only_boxes_that_shrank_as_much_as_a_bisection():
    csys = _sqrt2()
    stack = BoxStack(2)

    class Shrink:
        def apply(self, batch):  # row 0 by half, row 1 by a quarter of its width
            lo, hi = batch.lo.copy(), batch.hi.copy()
            hi[:, 0] -= np.array([0.5, 0.25])[: batch.size]
            batch.lo, batch.hi = lo, hi

        def describe(self):
            return "Shrink()"

    batch = _batch([0, 1], csys, stack=stack)
    FixPoint(Shrink()).apply(batch)
    batch.flush()
    assert len(stack) == 1 and stack.snapshot()[0][0, 0] == 0.0
    assert batch.size == 1 and batch.lo[0, 0] == 1.0 and batch.hi[0, 0] == 1.75
    with pytest.raises(ValueError):
        FixPoint(Shrink(), gain=0.0)


def test_the_hull_fixpoint_counts_a_round_it_did_alone_by_the_variables_it_halved():
    """``since_round``: progress from the box as the round began.  Three of ten variables
    narrowed to 0.74 halve the volume (the plain rule sends the box back); done alone
    (the parts before left the box untouched), with ``significant=0.5`` they do not count,
    two narrowed to 0.4 still do, and after a part that narrowed the box the round's volume
    counts as before (ExtendedFreud-0100's hull did the first, alone, 903 rounds running)."""
    n = 10
    x = [var(f"x{i}") for i in range(n)]
    csys = CompiledSystem(System([f"x{i}" for i in range(n)], np.tile([0.0, 4.0], (n, 1)), x))

    class Narrow:
        def __init__(self, ratios, first=0):
            self.ratios, self.first = np.array(ratios), first

        def apply(self, batch):
            lo, hi = batch.lo.copy(), batch.hi.copy()
            v = slice(self.first, self.first + self.ratios.size)
            hi[:, v] = lo[:, v] + self.ratios * (hi[:, v] - lo[:, v])
            batch.lo, batch.hi = lo, hi

        def describe(self):
            return "Narrow()"

    def sent_back(ratios, significant, before=None):
        stack = BoxStack(n)
        batch = Batch(np.zeros((1, n)), np.full((1, n), 4.0), csys=csys, eps=1e-8, stack=stack)
        fix = FixPoint(Narrow(ratios), since_round=True, significant=significant)
        Sequence(*([before] if before else []), fix).apply(batch)
        batch.flush()
        assert len(stack) + batch.size == 1
        return len(stack) == 1

    assert sent_back([0.74] * 3, 1.0) and not sent_back([0.74] * 3, 0.5)
    assert sent_back([0.4] * 2, 0.5) and sent_back([0.4] * 2, 1.0)
    assert not sent_back([0.9] * 6, 1.0)  # 0.53 of the volume: less than a bisection
    # HC4 or Newton narrowed x9 to 0.8 first: the round's volume, 0.32, counts
    assert sent_back([0.74] * 3, 0.5, before=Narrow([0.8], first=9))
    assert not sent_back([0.9] * 3, 0.5, before=Narrow([0.8], first=9))  # 0.58
    fix = FixPoint(Narrow([0.5]), since_round=True, significant=0.5)
    assert "significant=0.5" in fix.describe()
    assert fix.replace(Narrow([0.5]), Narrow([0.5])).significant == 0.5
    with pytest.raises(ValueError):
        FixPoint(Narrow([0.5]), since_round=True, significant=0.0)
    with pytest.raises(ValueError):
        FixPoint(Narrow([0.5]), significant=0.5)  # only since the round began


def test_a_fixpoint_stops():
    """A contractor that halves the box at every round: the box goes round again while a
    variable wider than eps shrinks, then stops and is reported undecided -- with the
    solution in it."""
    x = var("x")
    csys = CompiledSystem(System(["x"], np.array([[0.0, 4.0]]), [x * x - 2]))
    halve = Halve(root=float(np.sqrt(2.0)))
    solver = Solver(
        csys,
        Sequence(FixPoint(halve)),
        Certifier(csys),
        SmearSumRelative(),
        limits=SolverLimits(eps=1e-6),
    )
    res = solver.solve(timeout=60)
    assert res.status == "complete" and not res.solutions
    assert 20 <= halve.calls <= 40  # ~log2(4 / 1e-6) rounds
    (und,) = res.undecided
    assert und.lo[0] <= np.sqrt(2.0) <= und.hi[0] and und.hi[0] - und.lo[0] <= 1e-6
    assert res.stats.bisections == 0  # every round was the fixpoint's, none a bisection


def _pipelines(csys: CompiledSystem):
    """Compositions of the parts, from the default one to a few without Newton."""
    hc4 = HC4(csys)
    newton = core(csys, hc4=hc4)
    return {
        "default": Solver.default(csys).contractor,
        "forward kinematics": Sequence(FixPoint(Sequence(*newton)), Inflate()),
        "no fixpoint": Sequence(*newton, Inflate()),
        "relaxation first": Sequence(
            FixPoint(Sequence(hc4, PolytopeHull(csys), newton[-1])),
            Inflate(),
            FixPoint(Shave(hc4, 3, count=None, n=csys.n)),
        ),
        "no Newton": Sequence(FixPoint(hc4), FixPoint(Shave(hc4, 4, count=2, n=csys.n))),
    }


PIPELINES = ["default", "forward kinematics", "no fixpoint", "relaxation first", "no Newton"]
#: without Newton, kin2-6r's 12 variables take ~20 s of HC4 and CID down to eps
SLOW = {("kin2-6r", "no Newton")}


@pytest.mark.parametrize(
    ("name", "pipeline"),
    [
        pytest.param(n, p, marks=[pytest.mark.slow] if (n, p) in SLOW else [])
        for n in NAMES
        for p in PIPELINES
    ],
)
def test_no_solution_is_lost_with_any_composition(name, pipeline):
    csys, pts = compiled(name)
    contractor = _pipelines(csys)[pipeline]
    eps = 1e-3 if pipeline == "no Newton" else 1e-8  # without Newton nothing is proven
    solver = Solver(
        csys, contractor, Certifier(csys), SmearCurvatureMix(), limits=SolverLimits(eps=eps)
    )
    res = solver.solve(timeout=120)
    assert res.status == "complete"
    for p in pts:
        inside = [s for s in res.solutions if holds(s.lo, s.hi, p)]
        inside += [u for u in res.undecided if holds(u.lo, u.hi, p)]
        assert inside, f"{name} with {pipeline}: reference point {p} lost"
    if pipeline != "no Newton":
        assert len(res.solutions) == len(pts)


def test_the_solver_is_assembled_from_at_most_eight_parts():
    assert len(inspect.signature(Solver).parameters) <= 8
    csys, _ = compiled("eco-6")
    default = Solver.default(csys)
    kinds = [type(p).__name__ for p in parts_of(default.contractor)]
    assert kinds == [
        "Sequence", "FixPoint", "Sequence", "HC4", "IntervalNewton", "FixPoint",
        "PolytopeHull", "Inflate", "FixPoint", "Shave",
    ]  # fmt: skip
    # the relaxation and CID are parts, not flags: the options leave them out
    lean = Solver.default(csys, relax=False, cid_slices=0)
    assert find(lean.contractor, PolytopeHull) is None and find(lean.contractor, Shave) is None
    assert default.fingerprint() != lean.fingerprint()
    assert default.contractor.describe() in default.fingerprint()


class CountedHC4:
    """The recipe's custom contractor: one HC4-revise pass (sound), counting its boxes."""

    def __init__(self, csys: CompiledSystem):
        self.csys = csys
        self.boxes = 0

    def apply(self, batch: Batch) -> None:
        self.boxes += batch.size
        batch.lo, batch.hi, empty = self.csys.hc4_revise(batch.lo, batch.hi)
        batch.empty |= empty

    def describe(self) -> str:
        return "CountedHC4()"


@pytest.mark.parametrize("name", ["eco-6", "kin2-6r"])
def test_adding_a_contractor_recipe(name):
    """docs/architecture.md, *Adding a contractor*: a class with ``apply`` and ``describe``,
    and one line where the pipeline is assembled.  It runs, the checkpoint fingerprint
    names it, and every solution is still found, each certified."""
    csys, pts = compiled(name)
    solver = Solver.default(csys)
    newton = find(solver.contractor, IntervalNewton)
    custom = CountedHC4(csys)
    solver.contractor = solver.contractor.replace(newton, Sequence(custom, newton))
    assert "CountedHC4()" in solver.fingerprint()
    res = solver.solve(timeout=300)
    assert custom.boxes > 0  # it ran
    assert res.status == "complete" and len(res.solutions) == len(pts)
    for p in pts:
        assert sum(holds(s.lo, s.hi, p) for s in res.solutions) == 1
