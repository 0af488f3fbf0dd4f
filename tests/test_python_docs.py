"""The examples of docs/python.md run, in order, in one namespace, from the repository root,
and ``import certsolve`` stays cheap (no numpy, no solver code) until a name is used."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "python.md"


def code_blocks(text: str) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def test_docs_python_examples_run(monkeypatch, capsys):
    blocks = code_blocks(DOC.read_text())
    assert len(blocks) >= 8
    monkeypatch.chdir(ROOT)
    namespace: dict = {"__name__": "docs_python"}
    for i, block in enumerate(blocks):
        try:
            exec(compile(block, f"{DOC.name}[block {i}]", "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the message says which block
            pytest.fail(f"docs/python.md block {i} failed: {exc!r}\n{block}")
    assert "complete 2" in capsys.readouterr().out


def test_import_is_lazy_and_names_resolve():
    code = (
        "import sys, certsolve\n"
        "heavy = [m for m in sys.modules if m.split('.')[0] in ('numpy', 'scipy', 'pydantic')"
        " or m.startswith('certsolve.')]\n"
        "print(heavy)\n"
        "missing = [n for n in certsolve.__all__ if getattr(certsolve, n, None) is None]\n"
        "print(missing, certsolve.__version__)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    ).stdout.splitlines()
    assert out[0] == "[]"
    assert out[1].startswith("[] ")


def test_version_matches_pyproject():
    import tomllib

    import certsolve

    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert certsolve.__version__ == meta["project"]["version"]
    assert set(certsolve.__all__) <= set(dir(certsolve))
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        certsolve.nope  # noqa: B018
