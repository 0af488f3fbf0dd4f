"""Job kinds: for each, the pydantic model of its request and the function that runs it.

A job request is ``{"kind": ..., "robot": {...} | "system": "...", "params": {...},
"limits": {...}}``; the same models validate HTTP bodies, lines of ``certsolve batch``
files, the ``certsolve submit`` command line and the options of the ``certsolve solve /
fk / ik / isotropic / workspace`` commands.  One module per kind (params model, job model,
runner, and its quick synchronous call if it has one); :mod:`.base` holds what they share,
including the one check of parameters against the robot.

==================  ==============================================  =========================
kind (module)       library call                                    input
==================  ==============================================  =========================
solve               ``certsolve.solver.solve``                      ``system`` (Minibex text)
fk                  ``certsolve.kinematics.forward_kinematics``     ``robot``
ik                  ``certsolve.kinematics.inverse_kinematics``     ``robot``
ik-sweep            ``certsolve.kinematics.ik_sweep.ik_sweep``      ``robot``
isotropic-map       ``certsolve.force.isotropic_map``               ``robot``
workspace           ``certsolve.force.certified_workspace``         ``robot``
design              ``certsolve.force.design.design``               ``robot``
==================  ==============================================  =========================

The quick calls (``QUICK_CALLS``: ``ik``, ``isotropic``, ``fk/track``) live in the module
of their kind, with their cost estimate (:class:`.base.QuickCall`).

Each kind is an operation (:class:`.base.Kind`): its params model, the cheap check
against the robot (:meth:`.base.Params.check_robot`) and ``run(params, input, ctx)``,
which every front end calls (the worker, the quick calls, ``certsolve batch``, the
command line).  ``run`` imports its library module inside the function (the command
line's start-up stays cheap); a build without one of them still serves the others, and
such jobs fail with "kind X is not available in this build".
The hidden kind ``sleep`` (test settings only) sleeps, reports progress and can crash.

Names are imported on first use (:mod:`certsolve.lazy`): the command line imports one
kind's module (``certsolve.jobs.kinds.fk``) without the others.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...lazy import lazy_exports

if TYPE_CHECKING:
    from .base import (
        Job,
        JobLimits,
        Kind,
        KindUnavailable,
        Params,
        QuickCall,
        Request,
        RunContext,
    )
    from .design import DesignJob, DesignParameter, DesignParams
    from .fk import FkJob, FkParams, TrackCall, TrackParams, call_track
    from .ik import IkCall, IkJob, IkParams, run_ik
    from .ik_sweep import IkSweepJob, IkSweepParams
    from .isotropic_map import (
        MAX_GRID_POINTS,
        MAX_GRID_SIDE,
        IsotropicCall,
        IsotropicMapJob,
        IsotropicMapParams,
        PoseParams,
        call_isotropic,
    )
    from .registry import KINDS, QUICK_CALLS, job_request_type, public_kinds, request_adapter
    from .sleep import SleepJob, SleepParams
    from .solve import MAX_SYSTEM_CHARS, MAX_VARIABLES, SolveJob, SolveParams
    from .workspace import WorkspaceJob, WorkspaceParams

_WHERE = {
    "KINDS": ".registry",
    "QUICK_CALLS": ".registry",
    "job_request_type": ".registry",
    "public_kinds": ".registry",
    "request_adapter": ".registry",
    "Job": ".base",
    "JobLimits": ".base",
    "Kind": ".base",
    "KindUnavailable": ".base",
    "Params": ".base",
    "QuickCall": ".base",
    "Request": ".base",
    "RunContext": ".base",
    "DesignJob": ".design",
    "DesignParameter": ".design",
    "DesignParams": ".design",
    "IkSweepJob": ".ik_sweep",
    "IkSweepParams": ".ik_sweep",
    "FkJob": ".fk",
    "FkParams": ".fk",
    "TrackCall": ".fk",
    "TrackParams": ".fk",
    "call_track": ".fk",
    "IkCall": ".ik",
    "IkJob": ".ik",
    "IkParams": ".ik",
    "run_ik": ".ik",
    "MAX_GRID_POINTS": ".isotropic_map",
    "MAX_GRID_SIDE": ".isotropic_map",
    "IsotropicCall": ".isotropic_map",
    "IsotropicMapJob": ".isotropic_map",
    "IsotropicMapParams": ".isotropic_map",
    "PoseParams": ".isotropic_map",
    "call_isotropic": ".isotropic_map",
    "SleepJob": ".sleep",
    "SleepParams": ".sleep",
    "MAX_SYSTEM_CHARS": ".solve",
    "MAX_VARIABLES": ".solve",
    "SolveJob": ".solve",
    "SolveParams": ".solve",
    "WorkspaceJob": ".workspace",
    "WorkspaceParams": ".workspace",
}

__getattr__, __dir__ = lazy_exports(__name__, _WHERE)

__all__ = [
    "DesignJob",
    "DesignParameter",
    "DesignParams",
    "FkJob",
    "FkParams",
    "IkCall",
    "IkJob",
    "IkParams",
    "IkSweepJob",
    "IkSweepParams",
    "IsotropicCall",
    "IsotropicMapJob",
    "IsotropicMapParams",
    "Job",
    "JobLimits",
    "KINDS",
    "Kind",
    "KindUnavailable",
    "MAX_GRID_POINTS",
    "MAX_GRID_SIDE",
    "MAX_SYSTEM_CHARS",
    "MAX_VARIABLES",
    "Params",
    "PoseParams",
    "QUICK_CALLS",
    "QuickCall",
    "Request",
    "RunContext",
    "SleepJob",
    "SleepParams",
    "SolveJob",
    "SolveParams",
    "TrackCall",
    "TrackParams",
    "WorkspaceJob",
    "WorkspaceParams",
    "call_isotropic",
    "call_track",
    "job_request_type",
    "run_ik",
    "public_kinds",
    "request_adapter",
]
