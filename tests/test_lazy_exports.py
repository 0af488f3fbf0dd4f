"""Packages that export their names lazily (certsolve.lazy) export exactly ``__all__``,
and every name resolves to the object of the module the table names."""

import importlib

import pytest


@pytest.mark.parametrize(
    "package", ["certsolve.kinematics", "certsolve.jobs", "certsolve.jobs.kinds"]
)
def test_every_exported_name_resolves(package):
    pkg = importlib.import_module(package)
    assert sorted(pkg.__all__) == sorted(pkg._WHERE) == dir(pkg)
    for name, module in pkg._WHERE.items():
        source = importlib.import_module(module, package)
        assert getattr(pkg, name) is getattr(source, name)
    with pytest.raises(AttributeError):
        pkg.no_such_name  # noqa: B018
