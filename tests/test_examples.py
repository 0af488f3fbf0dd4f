"""Every script in ``examples/`` runs to the end (slow: a few minutes in all).

The scripts are run as the READMEs say (``python examples/<dir>/<script>.py`` from the
repository root) on a copy of ``examples/``, so the figures and files they write do not
touch the repository.  ``examples/robots/generate.py`` is deterministic: the robot files it
writes must be the bundled ones, byte for byte.
"""

from __future__ import annotations

import filecmp
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SCRIPTS = sorted(p.relative_to(ROOT) for p in (ROOT / "examples").rglob("*.py"))


def test_there_are_example_scripts():
    assert Path("examples/robots/generate.py") in SCRIPTS
    assert len(SCRIPTS) >= 5


@pytest.mark.slow
@pytest.mark.parametrize("script", SCRIPTS, ids=str)
def test_example_script_runs(script, tmp_path):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    proc = subprocess.run(
        [sys.executable, str(script)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=3600,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    if script == Path("examples/robots/generate.py"):
        made = sorted(p.name for p in (tmp_path / "examples" / "robots").glob("*.json"))
        assert made
        _, mismatch, errors = filecmp.cmpfiles(
            ROOT / "examples" / "robots", tmp_path / "examples" / "robots", made, shallow=False
        )
        assert not mismatch and not errors, (mismatch, errors)
