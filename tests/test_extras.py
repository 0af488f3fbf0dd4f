"""Optional extras: the core works without them, and a feature used without its extra says
which one to install.  Missing packages are simulated in a child interpreter by setting
``sys.modules[name] = None`` (import then fails as if the package were absent)."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "examples/robots"


def run_without(missing: list[str], argv: list[str]) -> subprocess.CompletedProcess:
    code = (
        "import sys\n"
        f"for name in {missing!r}:\n"
        "    sys.modules[name] = None\n"
        "from certsolve.cli import main\n"
        f"sys.exit(main({argv!r}))\n"
    )
    return subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120
    )


def test_serve_without_the_service_extra():
    out = run_without(["fastapi", "uvicorn"], ["serve", "--port", "0", "--workers", "0"])
    assert out.returncode == 2, out.stderr
    assert out.stderr == (
        "error: the service needs the 'service' extra: pip install 'certsolve[service]'\n"
    )


@pytest.mark.parametrize(
    "argv",
    [
        ["isotropic", str(ROBOTS / "krut-3.json"), "--grid", "0,1,0,1,3,3", "--plot", "m.png"],
        ["workspace", str(ROBOTS / "krut-3.json"), "--min-force", "100", "--box",
         "-10,10,-10,10", "--eps", "5", "--plot", "p.png"],
        ["ik", str(ROBOTS / "planar.json"), "--pose", "85,65,3", "--sweep", "1=0.1:2:5",
         "--plot", "s.png"],
        ["design", str(ROOT / "examples/design/krut3-spec.json"), "--plot", "d.png"],
    ],
)  # fmt: skip
def test_plot_without_the_plot_extra(argv, tmp_path):
    argv[-1] = str(tmp_path / argv[-1])
    out = run_without(["matplotlib"], argv)
    assert out.returncode == 2, out.stderr
    assert out.stderr == "error: --plot needs the 'plot' extra: pip install 'certsolve[plot]'\n"
    assert not Path(argv[-1]).exists()


def test_core_commands_need_no_extra():
    missing = ["fastapi", "uvicorn", "matplotlib", "httpx"]
    out = run_without(missing, ["solve", "examples/systems/circle-line.mbx"])
    assert out.returncode == 0 and "complete, 2 solution(s)" in out.stdout, out.stderr
    out = run_without(missing, ["fk", str(ROBOTS / "planar.json"), "--u", "0.5,0.5,0.5,0.5"])
    assert out.returncode == 0 and "1 certified pose(s)" in out.stdout, out.stderr


def test_importing_the_api_without_the_extra():
    code = (
        "import sys\nsys.modules['fastapi'] = None\n"
        "try:\n    import certsolve.api\nexcept ImportError as exc:\n    print(exc)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == (
        "certsolve.api needs the 'service' extra: pip install 'certsolve[service]'"
    )


def test_api_installs_inside_the_namespace(tmp_path):
    """``certsolve.api`` imports from anywhere; no top-level ``api`` module is installed."""
    code = (
        "import importlib.util, certsolve.api\n"
        "print(certsolve.api.__name__, importlib.util.find_spec('api') is None)"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True)
    assert out.stdout.split() == ["certsolve.api", "True"], out.stderr
