"""The command line starts cheaply: structure, not timing (timings: benchmarks/startup_bench.py).

``import certsolve.cli`` and ``certsolve --help`` import no command module, and a forward
kinematics run imports none of the optional or heavy packages it does not use.  The lazy
command table still gives each command its full parser.
"""

import argparse
import gc
import json
import subprocess
import sys
from pathlib import Path

import pytest

from certsolve.cli import COMMANDS, build_parser

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("scipy", "matplotlib", "fastapi", "uvicorn", "rich")


def imported_after(code: str) -> set[str]:
    """Top-level packages in ``sys.modules`` after running ``code`` in a fresh interpreter."""
    probe = (
        "import sys, json, contextlib, io\n"
        + code
        + "\nprint(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))"
    )
    out = subprocess.run(
        [sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    return set(json.loads(out.stdout.splitlines()[-1]))


def test_import_cli_is_light():
    mods = imported_after("import certsolve.cli")
    assert not mods & {*HEAVY, "numpy", "pydantic"}, mods & {*HEAVY, "numpy", "pydantic"}


def test_help_imports_no_command():
    code = (
        "from certsolve.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        main(['--help'])\n    except SystemExit:\n        pass"
    )
    mods = imported_after(code)
    assert not mods & {*HEAVY, "numpy"}, mods & {*HEAVY, "numpy"}


def test_fk_run_imports_only_what_it_uses():
    code = (
        "from certsolve.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['fk', 'examples/robots/planar.json', '--u', '0.5,0.5,0.5,0.5',"
        " '--tau-max', '10']) == 0"
    )
    mods = imported_after(code)
    assert "numpy" in mods  # it did run
    assert not mods & {*HEAVY, "dask", "distributed"}, mods & {*HEAVY, "dask", "distributed"}


def _options(parser: argparse.ArgumentParser, name: str) -> dict[str, object]:
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return {a.dest: a.default for a in sub.choices[name]._actions}


@pytest.mark.parametrize("name", [c.name for c in COMMANDS])
def test_lazy_parser_has_every_option(name):
    """The parser built for one command equals that command's part of the full parser."""
    full = build_parser()
    lazy = build_parser([name])
    assert _options(lazy, name) == _options(full, name)
    assert len(_options(lazy, name)) > 1  # more than -h: the module registered it


def test_command_help_shows_defaults(capsys):
    from certsolve.cli import main

    with pytest.raises(SystemExit):
        main(["fk", "--help"])
    out = capsys.readouterr().out
    assert "--tau-max" in out and "--half-width" in out and "(default: 1e-08)" in out


@pytest.mark.parametrize("given", [None, "3"])
def test_the_command_runs_with_one_blas_thread_unless_the_user_sets_it(monkeypatch, capsys, given):
    """``main()`` as the process's command sets ``OPENBLAS_NUM_THREADS`` to
    :data:`certsolve.cli.BLAS_THREADS` before a command imports numpy, and keeps a user's."""
    import os

    from certsolve import cli

    if given is None:
        monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    else:
        monkeypatch.setenv("OPENBLAS_NUM_THREADS", given)
    monkeypatch.setattr("sys.argv", ["certsolve", "schema", "robot"])
    try:
        assert cli.main() == 0
    finally:
        gc.unfreeze()  # main() as the process's command froze what was loaded
    assert os.environ["OPENBLAS_NUM_THREADS"] == (given or cli.BLAS_THREADS)
    assert capsys.readouterr().out.lstrip().startswith("{")


GC_STATE = "print(json.dumps([gc.isenabled(), gc.get_freeze_count()]))"


def test_the_command_loads_its_modules_without_the_collector_then_freezes_them():
    """``main()`` as the process's command: the collector is on again after the command's
    modules loaded, and what they hold is frozen (not walked by later collections)."""
    code = (
        "import gc, json, sys\n"
        "sys.argv = ['certsolve', 'solve', 'examples/systems/circle-line.mbx', '--json']\n"
        "from certsolve.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()) as out:\n"
        "    assert main() == 0\n"
        "assert json.loads(out.getvalue())['status'] == 'complete'\n" + GC_STATE
    )
    enabled, frozen = _probe(code)
    assert enabled
    assert frozen > 10_000  # numpy's and the solver's objects, not a handful


def test_a_caller_of_main_keeps_its_collector():
    """``main(argv)`` (a caller's process: a test, a script) leaves the collector as it is."""
    code = (
        "import gc, json\n"
        "from certsolve.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    assert main(['solve', 'examples/systems/circle-line.mbx', '--json']) == 0\n" + GC_STATE
    )
    assert _probe(code) == [True, 0]


def _probe(code: str):
    """The last line of ``code``'s output in a fresh interpreter, as JSON."""
    out = subprocess.run(
        [sys.executable, "-c", "import contextlib, io\n" + code],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.splitlines()[-1])
