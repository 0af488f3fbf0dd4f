"""The README's two commands work as written, CI runs its test command verbatim, and the
README and docs/ link only to files that exist."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
DOCS = sorted((ROOT / "docs").glob("*.md"))


def _commands() -> tuple[str, str]:
    """The quick start's command and the test command: the first two bash blocks."""
    blocks = re.findall(r"^```bash\n(.*?)^```", README, flags=re.S | re.M)
    return blocks[0].strip(), blocks[1].strip()


def test_readme_is_short():
    assert README.count("\n") <= 250


def test_quick_start_installs_the_core_and_runs_fk():
    quick, _ = _commands()
    install, run = (part.strip() for part in quick.split("&&"))
    assert install == "pip install -e ."  # no extra: fk needs none
    argv = shlex.split(run)
    assert argv[:2] == ["certsolve", "fk"]
    # the certsolve of this interpreter, whether or not its scripts are on PATH
    cmd = [sys.executable, "-m", "certsolve", *argv[1:]]
    out = subprocess.run(
        cmd, cwd=ROOT, capture_output=True, text=True, timeout=300, check=True
    ).stdout
    assert "complete: 1 certified pose(s), 0 undecided, 0 pending" in out


def test_ci_runs_the_readme_test_command():
    _, tests = _commands()
    assert tests == "pip install -e '.[dev]' && pytest"
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert f"({tests})" in ci


@pytest.mark.parametrize("page", [ROOT / "README.md", *DOCS], ids=lambda p: p.name)
def test_relative_links_point_to_files(page):
    links = re.findall(r"\]\(([^)\s]+)\)", page.read_text())
    local = [link.split("#")[0] for link in links if not re.match(r"[a-z]+:", link)]
    missing = [link for link in local if link and not (page.parent / link).exists()]
    assert not missing


def test_docs_index_lists_every_page():
    index = (ROOT / "docs" / "index.md").read_text()
    listed = set(re.findall(r"\]\(([\w.-]+\.md)\)", index))
    assert {p.name for p in DOCS} - {"index.md"} <= listed
