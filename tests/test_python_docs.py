"""The examples of docs/python.md run, in order, in one namespace, from the repository root;
what each prints is the output shown under it (a ```text block), to the digits shown; and
``import certsolve`` stays cheap (no numpy, no solver code) until a name is used."""

from __future__ import annotations

import contextlib
import io
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "python.md"
# a python block, and the text block right under it: what the block prints
BLOCK = re.compile(r"^```python\n(.*?)^```\n(?:[ \t]*\n)*(?:^```text\n(.*?)^```$)?", re.S | re.M)
NUMBER = r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?"
TOKEN = re.compile(rf"\.\.\.|{NUMBER}|\S")
WILDCARD = "..."  # in a shown output: one number that varies from machine to machine


def code_blocks(text: str) -> list[tuple[str, str | None]]:
    """The python blocks of the page, each with the output shown under it (None: none)."""
    return [(code, out or None) for code, out in BLOCK.findall(text)]


def _tolerance(shown: str) -> float:
    """One unit of the last decimal shown (a value next to a rounding edge may print one
    unit off); 0 for an integer."""
    mantissa, _, exponent = shown.lower().partition("e")
    if "." not in mantissa:
        return 0.0
    return 1.001 * 10.0 ** (int(exponent or 0) - len(mantissa.partition(".")[2]))


def same_output(printed: str, shown: str) -> bool:
    """``printed`` reads as ``shown``: the same words and signs (white space aside), and
    numbers equal to the digits shown (to one unit of the last) -- so neither numpy's
    column padding nor a rounding far below the digits shown matters, while any other
    change of a number does."""
    got, want = TOKEN.findall(printed), TOKEN.findall(shown)
    if len(got) != len(want):
        return False
    for g, w in zip(got, want, strict=True):
        if w == WILDCARD:
            if not re.fullmatch(NUMBER, g):
                return False
        elif re.fullmatch(NUMBER, w) and re.fullmatch(NUMBER, g):
            if abs(float(g) - float(w)) > _tolerance(w):
                return False
        elif g != w:
            return False
    return True


def test_same_output_reads_numbers_to_the_digits_shown():
    assert same_output("[0.70710678 -0.5]\nok", "[0.7071068  -0.5] ok")
    assert same_output("max_boxes 3892", "max_boxes ...")
    assert not same_output("max_boxes x", "max_boxes ...")
    assert same_output("[0.7072 -0.5]", "[0.7071 -0.5]")
    assert not same_output("[0.7073 -0.5]", "[0.7071 -0.5]")
    assert not same_output("complete 3", "complete 2")
    assert not same_output("complete 2 0", "complete 2")
    assert not same_output("timeout 2", "complete 2")


def test_docs_python_examples_print_what_is_shown(monkeypatch):
    blocks = code_blocks(DOC.read_text())
    assert len(blocks) >= 8
    monkeypatch.chdir(ROOT)
    namespace: dict = {"__name__": "docs_python"}
    for i, (block, shown) in enumerate(blocks):
        out = io.StringIO()
        try:
            with contextlib.redirect_stdout(out):
                exec(compile(block, f"{DOC.name}[block {i}]", "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the message says which block
            pytest.fail(f"docs/python.md block {i} failed: {exc!r}\n{block}")
        printed = out.getvalue()
        if shown is None:
            assert not printed, f"block {i} prints, and the page shows no output:\n{printed}"
        else:
            assert same_output(printed, shown), f"block {i} printed\n{printed}\nnot\n{shown}"


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
