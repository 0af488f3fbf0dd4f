"""Package layout (everything else is in pyproject.toml): the ``certsolve*`` packages, and
the ``api/`` folder installed inside the namespace as ``certsolve.api`` -- no top-level
``api`` module, which could collide with another on a user's path -- with the web page's
files (``api/static``: HTML, script, style sheet) as package data."""

from setuptools import find_namespace_packages, setup

CORE = find_namespace_packages(include=["certsolve", "certsolve.*"])
API = ["certsolve." + p for p in find_namespace_packages(include=["api", "api.*"])]

setup(
    packages=CORE + API,
    package_dir={"certsolve.api": "api"},
    package_data={"certsolve.api.static": ["*.html", "*.js", "*.css"]},
)
