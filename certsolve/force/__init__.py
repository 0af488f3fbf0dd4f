"""Force indexes of wire-driven parallel robots (Krut, Company, Pierrot 2004, and beyond).

* :mod:`.polytope`   -- the operational force polytope; hyperplane shifting (default)
* :mod:`.krut`       -- the paper's six steps (reference algorithm, small m and n)
* :mod:`.section`    -- exact force section of the wrench polytope (vertices + Qhull)
* :mod:`.loads`      -- external wrench (gravity) and the bias point of the ball
* :mod:`.isotropic`  -- the maximum isotropic force at a pose and over many poses
* :mod:`.ellipse`    -- the largest centred ellipse / ellipsoid (section IV-C)
* :mod:`.maps`       -- the index over a grid of positions
* :mod:`.enclosure`  -- interval enclosures of the index test over boxes (proofs)
* :mod:`.meanvalue`  -- slope (mean-value) interval arithmetic used by the proofs
* :mod:`.certified`  -- certified workspace ``{f_min ≥ f_req}``: paving by bisection
* :mod:`.picture`    -- the force picture at one pose (Fig. 4): polygons, circle, ellipse
* :mod:`.plots`      -- heat maps, pavings and force pictures (matplotlib)
* :mod:`.wedge`      -- facet candidates: generalised cross products

Layering: this package imports :mod:`certsolve.interval`, :mod:`certsolve.robot`, and the
search driver of :mod:`certsolve.solver` (for the certified paving).

Entry points: :func:`isotropic_force`, :func:`isotropic_map`, :func:`certified_workspace`.
"""

from .certified import CertifiedWorkspace, PavingStep, certified_workspace
from .ellipse import CentredEllipsoid, largest_centred_ellipsoid
from .isotropic import IsotropicForceResult, isotropic_force, isotropic_values
from .krut import krut_polytope
from .loads import external_wrench
from .maps import IsotropicMap, isotropic_map
from .picture import ForcePicture, force_picture
from .polytope import ForcePolytope, hyperplane_shifting
from .section import force_section

__all__ = [
    "CentredEllipsoid",
    "CertifiedWorkspace",
    "ForcePicture",
    "ForcePolytope",
    "IsotropicForceResult",
    "IsotropicMap",
    "PavingStep",
    "certified_workspace",
    "external_wrench",
    "force_picture",
    "force_section",
    "hyperplane_shifting",
    "isotropic_force",
    "isotropic_map",
    "isotropic_values",
    "krut_polytope",
    "largest_centred_ellipsoid",
]
