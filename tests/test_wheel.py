"""The README's user path from a built wheel: install it into a fresh virtual environment (base, and with the
codegen extra) and run its commands in a directory outside the repository.

The wheel is built from a copy of the tracked files (a clean checkout) with ``pip wheel --no-deps``, whose
isolated build takes setuptools from the package index.  The fresh environment sees the dependencies of
this test environment through a ``.pth`` line to links of its packages (so pip resolves the extras without
downloading them, ``--no-index``) but not its switchobs; a base install is the same environment with casadi
made unimportable.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: A module that stands for a package that is not installed.
_MISSING = 'raise ModuleNotFoundError("No module named {0!r}", name={0!r})\n'


def _user_path() -> tuple[list[str], list[str]]:
    """The README's user block: the ``pip`` lines and the ``switchobs`` lines (each as written)."""
    readme = (ROOT / "README.md").read_text("utf-8")
    block = re.search(r"^## Install as a user\n.*?```sh\n(.*?)```", readme, re.S | re.M)
    assert block, "README.md has no sh block under '## Install as a user'"
    lines = [line for line in block.group(1).splitlines() if line.strip()]
    pips = [line for line in lines if line.startswith("pip ")]
    commands = [line for line in lines if line.startswith("switchobs")]
    assert len(pips) == 2 and len(pips) + len(commands) == len(lines), lines
    return pips, commands


def _clean_env() -> dict[str, str]:
    """This process's environment without the path to the checkout's sources or this virtual environment."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}


def _run(argv: list[str], cwd: Path, env: dict[str, str] | None = None, timeout: float = 600) -> \
        subprocess.CompletedProcess:
    return subprocess.run(argv, cwd=cwd, env=_clean_env() if env is None else env, capture_output=True, text=True,
                          timeout=timeout)


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    git = shutil.which("git")
    if git is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout (or git is not installed): the wheel build is NOT checked")
    tracked = _run([git, "ls-files", "-z"], ROOT).stdout.split("\0")
    checkout = tmp_path_factory.mktemp("checkout")
    for name in filter(None, tracked):
        if (ROOT / name).is_file():
            (checkout / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, checkout / name)
    dist = tmp_path_factory.mktemp("dist")
    pip_line = _user_path()[0][0]
    assert shlex.split(pip_line, comments=True)[:4] == ["pip", "wheel", "--no-deps", "-w"]
    built = _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(dist), str(checkout)],
                 checkout)
    if built.returncode != 0:
        if "Could not find a version" in built.stderr or "Failed to establish" in built.stderr:
            pytest.skip(f"the build backend cannot be fetched from the package index: the wheel is NOT checked "
                        f"({built.stderr.strip().splitlines()[-1]})")
        pytest.fail(f"pip wheel failed: {built.stderr}")
    (found,) = dist.glob("switchobs-*.whl")
    return found


def _environment(tmp: Path, wheel: Path, install: str, *, extra: str) -> Path:
    """A fresh venv holding the wheel installed as the README says (``install`` is its pip line), with the
    ``extra`` its comment names ("base": no extra)."""
    casadi = extra != "base"
    venv = tmp / "venv"
    assert _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], tmp).returncode == 0
    python = venv / "bin" / "python"
    site = Path(_run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                     tmp).stdout.strip())
    # the dependencies of this environment, without its own switchobs (an editable install of the checkout)
    deps = tmp / "deps"
    deps.mkdir()
    for entry in Path(sysconfig.get_paths()["purelib"]).iterdir():
        if "switchobs" not in entry.name and entry.suffix != ".pth":
            (deps / entry.name).symlink_to(entry, target_is_directory=entry.is_dir())
    (site / "_deps.pth").write_text(f"{deps}\n", encoding="utf-8")
    if not casadi:
        (site / "casadi.py").write_text(_MISSING.format("casadi"), encoding="utf-8")
    words = shlex.split(install, comments=True)
    assert words[:4] == ["pip", "install", "--find-links", "dist"], words
    named = {"codegen": words[4], "base": "switchobs", "all": "switchobs[all]"}
    assert all(f'"{r}"' in install for r in named.values()), install   # the three the README names
    requirement = named[extra]
    done = _run([str(python), "-m", "pip", "install", "-q", "--no-index", "--find-links", str(wheel.parent),
                 requirement], tmp)
    assert done.returncode == 0, done.stderr
    return venv


@pytest.mark.slow
@pytest.mark.parametrize("extra", ["base", "codegen", "all"])
def test_the_readme_user_path_runs_from_an_installed_wheel(wheel, tmp_path, extra):
    pytest.importorskip("casadi")   # the codegen environment takes it from here
    pips, commands = _user_path()
    venv = _environment(tmp_path, wheel, pips[1], extra=extra)
    work = tmp_path / "work"       # outside the repository
    work.mkdir()
    env = _clean_env()
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    where = _run([str(venv / "bin" / "python"), "-c", "import switchobs; print(switchobs.__file__)"], work, env)
    assert where.stdout.startswith(str(venv)), where.stdout + where.stderr   # the wheel, not the checkout
    for line in commands:
        needs_codegen = "needs the codegen extra" in line
        words = shlex.split(line.split("#")[0])
        proc = _run([str(venv / "bin" / words[0]), *words[1:]], work, env)
        if needs_codegen and extra == "base":
            # one line naming the extra, exit 2
            assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
            assert 'pip install "switchobs[codegen]"' in proc.stderr
            continue
        assert proc.returncode == 0, f"{line}: {proc.stderr}"
    assert (work / "fig4.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and (work / "cert.json").is_file()
    assert (work / "c").is_dir() == (extra != "base")
    if extra == "all":   # what each extra brings is installed and imports in the user's environment
        found = _run([str(venv / "bin" / "python"), "-c", "import dask.distributed, fmpy, asammdf, pyarrow; "
                      "from importlib.metadata import requires; print(sorted(requires('switchobs')))"], work, env)
        assert found.returncode == 0, found.stderr
    # a repository command refuses in one line outside a checkout
    proc = _run([str(venv / "bin" / "switchobs"), "reproduce", "--check"], work, env)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "checkout" in proc.stderr


def test_without_casadi_simulate_and_the_encoder_chain_run(tmp_path):
    """A base install: the Python observers in the braking loop (compiled without casadi when a compiler is
    installed) and the encoder chain; only what generates C needs the codegen extra."""
    script = ("import sys; sys.modules['casadi'] = None\n"
              "from switchobs.cli.main import main\n"
              "codes = [main(['simulate', '--observer', 'xbs4', '--duration', '0.3', '-q']),\n"
              "         main(['encoder', '--duration', '1.5', '-q']),\n"
              "         main(['simulate', '--observer', 'xbs3', '--observer-impl', 'c', '--duration', '0.3'])]\n"
              "assert 'casadi' not in [m.split('.')[0] for m in sys.modules if sys.modules[m] is not None]\n"
              "print(codes)\n")
    env = {**_clean_env(), "PYTHONPATH": str(ROOT / "src")}
    proc = _run([sys.executable, "-c", script], tmp_path, env)
    assert proc.stdout.strip().splitlines()[-1] == "[0, 0, 2]", proc.stdout + proc.stderr
    assert 'pip install "switchobs[codegen]"' in proc.stderr and proc.stderr.count("\n") == 1
