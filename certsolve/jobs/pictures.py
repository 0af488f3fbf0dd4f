"""Pictures of finished jobs, drawn once and kept as PNG files in the data directory.

A picture is a function of a job's request and its final result only, so it never goes
stale: it is drawn on first request and kept in ``DATA_DIR/pictures/<STYLE>/<job id>/``.
``STYLE`` names the drawing code's version; a release that draws differently changes it,
and the old files are simply no longer read.

==============  ===============  =============================================================
kind            picture          drawn by
==============  ===============  =============================================================
``fk``          ``pose-<k>``     :func:`certsolve.kinematics.plots.plot_pose`: certified pose k
                                 (0-based, the order of ``result.solutions``)
``fk``          ``poses``        :func:`certsolve.kinematics.plots.plot_poses`: all overlaid
``isotropic-map`` ``map``        :func:`certsolve.force.plots.plot_map` (Krut's Figs. 9, 10)
``workspace``   ``paving``       :func:`certsolve.force.plots.plot_paving`
``trajectory``  ``path``         :func:`certsolve.kinematics.plots.plot_trajectory`: pose and
                                 tensions along the path, the lost step marked
==============  ===============  =============================================================

A job that has not finished, or finished without a result, has no picture yet
(:class:`~.service.NoResult`); a picture its kind does not have, or a pose index past the
last pose, is :class:`NoPicture`; without matplotlib, :class:`~certsolve.extras.MissingExtra`.
A result that stops short (an incomplete search, a cancelled job's partial result, boxes cut
by the service's ``max_result_items``) is drawn with that said in the title.

matplotlib's ``pyplot`` keeps global state and is not thread-safe, so one :class:`Pictures`
draws one picture at a time (a lock); a file is written under a temporary name and renamed,
so a reader never sees half of one.
"""

from __future__ import annotations

import json
import os
import tempfile
import threading
from pathlib import Path
from typing import Any

from ..extras import require
from ..solver.search import SearchStatus
from .service import NoResult, NoSuchJob
from .store import JobStore

__all__ = ["PICTURES", "STYLE", "NoPicture", "Pictures"]

STYLE = "v1"

# kind -> names of its pictures ("pose" stands for pose-<k>)
PICTURES: dict[str, tuple[str, ...]] = {
    "fk": ("pose", "poses"),
    "isotropic-map": ("map",),
    "workspace": ("paving",),
    "trajectory": ("path",),
}


class NoPicture(LookupError):
    """The job exists but has no such picture (another kind, or no such pose)."""


class Pictures:
    """The pictures of the jobs of one store, cached under ``directory``."""

    def __init__(self, store: JobStore, directory: str | os.PathLike):
        self.store = store
        self.directory = Path(directory) / STYLE
        self._lock = threading.Lock()

    def png(self, job_id: str, name: str, index: int | None = None) -> Path:
        """The PNG file of picture ``name`` (``index``: the pose of ``pose``), drawn if new."""
        row = self.store.get(job_id, result=False)
        if row is None:
            raise NoSuchJob(f"no job {job_id}")
        names = PICTURES.get(row.kind, ())
        if name not in names:
            raise NoPicture(f"job {job_id} is a {row.kind} job, which has no {name} picture")
        if not row.status.final:
            raise NoResult(f"job {job_id} is {row.status}: its pictures come when it is done")
        stem = name if index is None else f"{name}-{int(index)}"
        path = self.directory / job_id / f"{stem}.png"
        if path.exists():
            return path
        full = self.store.get(job_id, result=True, request=True)
        if full is None or full.result is None:
            why = f": {row.error}" if row.error else ""
            raise NoResult(f"job {job_id} is {row.status} and has no result{why}")
        request, result = json.loads(full.request or "{}"), json.loads(full.result)
        if name == "pose":
            count = len(result.get("solutions") or [])
            if index is None or not 0 <= index < count:
                raise NoPicture(f"job {job_id} has {count} pose(s): no pose {index} (0-based)")
        require("plot", "a picture")
        with self._lock:
            if not path.exists():
                try:
                    _write(path, lambda out: _DRAW[name](request, result, index, out))
                except ValueError as exc:  # a result stored without what the picture needs
                    raise NoPicture(f"job {job_id}: its result cannot be drawn ({exc})") from None
        return path


def _write(path: Path, draw) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".draw-", suffix=".png")
    os.close(fd)
    try:
        draw(Path(tmp))
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


# -- from stored JSON to the library's objects ---------------------------------------------------
def _robot(request: dict[str, Any]):
    from ..kinematics.fk import with_tau_max
    from ..robot.model import Robot

    robot = Robot.load(request["robot"])
    return with_tau_max(robot, (request.get("params") or {}).get("tau_max"))


def _fk_pose(d: dict[str, Any]):
    import numpy as np

    from ..kinematics.fk import FKPose

    return FKPose(
        position=np.asarray(d["position"], dtype=float),
        rotation=np.asarray(d["rotation"], dtype=float),
        platform_points=np.asarray(d["platform_points"], dtype=float),
        rho=np.asarray(d["rho"], dtype=float),
        tau=np.asarray(d["tau"], dtype=float),
        box=d.get("box", []),
        variables=d.get("variables", []),
        certificate=d.get("certificate", "unique"),
        verified=d.get("verified"),
    )


def _search_note(result: dict[str, Any]) -> str:
    """What a search result leaves open, or "" when it is complete."""
    parts = []
    if result.get("status") != SearchStatus.COMPLETE:
        parts.append(f"search {result.get('status')}")
    for key in ("undecided", "pending"):
        n = (result.get("truncated") or {}).get(key, len(result.get(key) or []))
        if n:
            parts.append(f"{n} {key} box(es)")
    return "; ".join(parts)


def _truncation_note(result: dict[str, Any]) -> str:
    cut = result.get("truncated") or {}
    if not cut:
        return ""
    lists = ", ".join(f"{k} ({n})" for k, n in cut.items())
    return f"only part of a long list is stored: {lists}"


def _draw_pose(request, result, index, out: Path) -> None:
    from ..kinematics.plots import plot_pose

    poses = result["solutions"]
    plot_pose(_robot(request), _fk_pose(poses[index]), out, number=(index + 1, len(poses)))


def _draw_poses(request, result, index, out: Path) -> None:
    from ..kinematics.plots import plot_poses

    robot = _robot(request)
    poses = [_fk_pose(p) for p in result.get("solutions") or []]
    title = f"{robot.name}: {len(poses)} certified pose(s)"
    note = "; ".join(n for n in (_search_note(result), _truncation_note(result)) if n)
    if note:
        title += f"\nnot every pose is known: {note}"
    plot_poses(robot, poses, out, title=title)


def _draw_map(request, result, index, out: Path) -> None:
    from ..force.maps import IsotropicMap
    from ..force.plots import plot_map

    plot_map(IsotropicMap.from_dict(result, _robot(request).A), out)


def _draw_paving(request, result, index, out: Path) -> None:
    from ..force.certified import CertifiedWorkspace
    from ..force.plots import plot_paving

    robot = _robot(request)
    ws = CertifiedWorkspace.from_dict(result)
    title = None
    note = _truncation_note(result)
    if note:
        counts = ", ".join(f"{k} {n}" for k, n in (result.get("counts") or {}).items())
        head = f"{ws.robot}: f_min ≥ {ws.min_force:g} N [{ws.status}]; boxes: {counts}"
        title = head + "\n" + note.replace("_boxes", "")
    plot_paving(ws, out, title=title, anchors=robot.A)


def _draw_path(request, result, index, out: Path) -> None:
    from ..kinematics.plots import plot_trajectory

    robot = _robot(request)
    title = None
    note = _truncation_note(result)
    if note:
        title = f"{robot.name}: {result.get('status')}, lost at {result.get('lost_at')}\n{note}"
    plot_trajectory(result, out, tau_limits=(robot.tau_min, robot.tau_max), title=title)


_DRAW = {
    "pose": _draw_pose,
    "poses": _draw_poses,
    "map": _draw_map,
    "paving": _draw_paving,
    "path": _draw_path,
}
