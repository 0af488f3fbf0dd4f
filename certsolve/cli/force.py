"""Placeholder: sub-commands of this module are being written (see certsolve/cli/__init__.py)."""


def register(sub) -> None:
    """Add this module's sub-commands to the parser (none yet)."""
