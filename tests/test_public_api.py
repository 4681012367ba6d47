"""The top-level public API resolves to the sub-packages' objects and the layers stay ordered."""

import ast
import pathlib

import pytest

import switchobs

from switchobs._layers import FLOORS, RANK, layer_map

LAYERS = [name for floor in FLOORS for name in floor]


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


def _imports(path: pathlib.Path) -> set[str]:
    """The modules of switchobs that ``path`` imports, at run time or for type checking only
    (``if TYPE_CHECKING:`` blocks count: a type-only import back is still a definition in the wrong file)."""
    package = ["switchobs", *path.relative_to(pathlib.Path(switchobs.__file__).parent).parent.parts]
    tree = ast.parse(path.read_text())
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join([*base, *(node.module.split(".") if node.module else [])])
            if module.startswith("switchobs"):
                out.add(module)
                out.update(f"{module}.{a.name}" for a in node.names)
    return out


def test_type_only_imports_are_seen():
    """An import under ``if TYPE_CHECKING:`` is an edge of the graph the circle test walks."""
    path = pathlib.Path(switchobs.__file__).parent / "plants" / "_metrics.py"
    source = path.read_text()
    assert "if TYPE_CHECKING:" in source
    assert "switchobs.plants._plant.BrakingScenario" in _imports(path)


def test_no_circle_of_imports_inside_a_room():
    """Each file of a room imports its room's files one way: a circle means a definition sits in the wrong file."""
    root = pathlib.Path(switchobs.__file__).parent
    for layer in LAYERS:
        files = {".".join(["switchobs", *p.relative_to(root).with_suffix("").parts]): p
                 for p in (root / layer).rglob("_*.py") if p.name != "__init__.py"}
        graph = {m: {t for t in _imports(p) if t in files and t != m} for m, p in files.items()}
        state: dict[str, int] = {}

        def visit(m: str, trail: list[str]) -> None:
            state[m] = 1
            for t in graph[m]:
                if state.get(t) == 1:
                    pytest.fail(f"import circle in {layer}: {' -> '.join(trail[trail.index(t):] + [t])}")
                if t not in state:
                    visit(t, trail + [t])
            state[m] = 2

        for m in sorted(files):
            if m not in state:
                visit(m, [m])


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


def test_the_layer_map_of_the_developer_page_is_drawn_from_the_code():
    page = (pathlib.Path(__file__).resolve().parents[1] / "docs" / "developer.md").read_text("utf-8")
    block = page.split("<!-- begin generated: layer map -->\n", 1)[1].split("\n<!-- end generated: layer map -->", 1)[0]
    assert block.strip("\n").splitlines() == layer_map()


def test_every_package_is_on_a_floor():
    root = pathlib.Path(switchobs.__file__).parent
    packages = sorted(p.parent.name for p in root.glob("*/__init__.py"))
    assert packages == sorted(LAYERS)
