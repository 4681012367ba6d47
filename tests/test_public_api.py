"""The top-level public API resolves to the sub-packages' objects and the layers stay ordered."""

import ast
import pathlib

import pytest

import switchobs

LAYERS = ["model", "transform", "design", "spec", "certify", "codegen", "observers", "plants", "sensors", "loop", "sweep",
          "logs", "report", "cli"]
# spec is the observer contract shared by the Python engine and the C translator; observers are generic (model,
# design, spec); plants hold the physics and the hybrid integrator; sensors use the plants' vehicle, roads and
# integrator; the loop wires observers and sensors to the plants; sweeps run the loop over families of cases;
# logs read and write measurement files for the loop's replay
RANK = {"model": 0, "transform": 1, "design": 1, "spec": 2, "certify": 2, "codegen": 3, "observers": 4, "plants": 5,
        "sensors": 6, "loop": 7, "sweep": 8, "logs": 8, "report": 8, "cli": 9}


@pytest.mark.parametrize("name", switchobs.__all__)
def test_every_exported_name_resolves(name):
    assert getattr(switchobs, name) is not None


def test_unknown_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        switchobs.nope  # noqa: B018


@pytest.mark.parametrize("first", ["import switchobs", "import switchobs.design", "from switchobs import design_gains",
                                   "from switchobs.design import design", "import switchobs.observers"])
def test_switchobs_design_is_the_subpackage_in_every_import_order(first):
    """`switchobs.design` never turns into the design function, whatever was imported before."""
    import subprocess
    import sys

    code = (f"{first}\nimport types\nimport switchobs\nfrom switchobs import design\n"
            "assert isinstance(design, types.ModuleType), design\n"
            "assert switchobs.design is design\n"
            "assert switchobs.design_gains is design.design_gains is design.design\n"
            "assert 'design' in dir(switchobs)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("layer", [name for name in LAYERS if name != "cli"])
def test_lower_layers_never_import_higher_ones(layer):
    root = pathlib.Path(switchobs.__file__).parent / layer
    if not root.exists():
        pytest.fail(f"layer {layer} is missing")
    for path in root.rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            target = None
            if isinstance(node, ast.ImportFrom) and node.module:
                if node.level == 2:
                    target = node.module.split(".")[0]
                elif node.level == 0 and node.module.startswith("switchobs."):
                    target = node.module.split(".")[1]
            if target in RANK:
                assert RANK[target] <= RANK[layer], f"{path} imports the higher layer {target}"


def test_a_broken_dependency_disables_only_its_commands(tmp_path):
    """A casadi that fails to import must not crash `switchobs design` (which does not need it)."""
    import os
    import subprocess
    import sys

    fake = tmp_path / "casadi"
    fake.mkdir()
    (fake / "__init__.py").write_text("raise ImportError('broken casadi')\n")
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    ok = subprocess.run([sys.executable, "-m", "switchobs", "design", "abs-xbs3", "--spectrum=-1,-2,-3"],
                        capture_output=True, text=True, env=env, timeout=120)
    assert ok.returncode == 0, ok.stderr
    broken = subprocess.run([sys.executable, "-m", "switchobs", "codegen", "abs-xbs3", "--out", str(tmp_path / "c")],
                            capture_output=True, text=True, env=env, timeout=120)
    assert broken.returncode == 2 and "Traceback" not in broken.stderr
    assert "command 'codegen' cannot run" in broken.stderr and "broken casadi" in broken.stderr
