"""Every script in examples/ runs (fast mode), checks what it claims and writes its plot."""

from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
#: script -> the plot(s) it writes
EXPECTED = {
    "design_my_model.py": ["design_my_model.png", "my_model_certificate.json"],
    "hoang2014_fig3_fig4.py": ["hoang2014_fig3.png", "hoang2014_fig4.png"],
    "aguado_table41.py": ["aguado_table41.png"],
    "aguado_table61.py": ["aguado_table61.png"],
    "poincare_two_phase.py": ["poincare_two_phase.png"],
    "noise_decay_front.py": ["noise_decay_front.png"],
    "python_control_notebook.py": ["python_control_notebook.png"],
    "c_observer.py": ["c_observer.png", "c_observer/observer_demo", "c_observer/switchobs_abs_xbs4.h"],
    "fmu_closed_loop.py": ["switchobs_quarter_car.fmu", "switchobs_abs_xbs4.fmu"],
}


def test_every_example_script_is_covered():
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(EXPECTED)


@pytest.mark.parametrize("script", sorted(EXPECTED))
def test_examples_say_what_they_reproduce_and_use_only_the_public_api(script):
    tree = ast.parse((EXAMPLES / script).read_text("utf-8"))
    doc = ast.get_docstring(tree)
    assert doc and "Reproduces:" in doc and "SWITCHOBS_FAST" in doc
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("switchobs"):
            assert not any(part.startswith("_") for part in node.module.split(".")), node.module
            assert not any(alias.name.startswith("_") for alias in node.names)
    assert any(isinstance(n, ast.Assert) for n in ast.walk(tree)), "an example must check what it claims"


@pytest.mark.slow
@pytest.mark.parametrize("script", sorted(EXPECTED))
def test_example_runs_in_fast_mode(script, tmp_path):
    if script == "c_observer.py" and shutil.which("make") is None:
        pytest.fail("the C example needs `make` (install build-essential)")
    env = {**os.environ, "SWITCHOBS_FAST": "1", "MPLBACKEND": "Agg"}
    proc = subprocess.run([sys.executable, str(EXAMPLES / script), str(tmp_path)], capture_output=True, text=True,
                          env=env, cwd=str(tmp_path), timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    assert "written to" in proc.stdout
    for name in EXPECTED[script]:
        assert (tmp_path / name).is_file() and (tmp_path / name).stat().st_size > 0, name


def test_example_model_file_loads_and_is_documented():
    from switchobs.model import load_model

    model = load_model(EXAMPLES / "my_model.toml")
    assert model.name == "my-wheel" and model.n == 3
    assert str(model.d[1]) == "k*y"
