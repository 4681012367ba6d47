"""The documentation site builds in strict mode and says what the code does."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import yaml

from switchobs.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _nav_pages(nav) -> list[str]:
    pages = []
    for item in nav:
        value = next(iter(item.values())) if isinstance(item, dict) else item
        pages += _nav_pages(value) if isinstance(value, list) else [value]
    return pages


@pytest.mark.slow
def test_mkdocs_builds_in_strict_mode(tmp_path):
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                          cwd=str(ROOT), capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "WARNING" not in proc.stderr
    for page in ("index.html", "guide/index.html", "model-format/index.html", "reproductions/index.html",
                 "benchmarks/index.html", "theory/abs-xbs3/index.html", "theory/normal-form-3/index.html"):
        assert (tmp_path / "site" / page).is_file(), page
    # the generated theory reaches the site with its math for MathJax
    assert "arithmatex" in (tmp_path / "site" / "theory" / "abs-xbs4" / "index.html").read_text("utf-8")


def test_every_page_is_in_the_navigation_and_every_nav_entry_exists():
    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text("utf-8"))
    nav = _nav_pages(config["nav"])
    pages = sorted(str(p.relative_to(DOCS)) for p in DOCS.glob("*.md"))
    theory = sorted(f"theory/{p.name}" for p in (ROOT / "theory").glob("*.md"))
    assert sorted(nav) == sorted(pages + theory)


def test_images_referenced_by_the_docs_exist():
    for page in DOCS.glob("*.md"):
        for target in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", page.read_text("utf-8")):
            assert (DOCS / target).is_file(), f"{page.name} shows {target}, which does not exist"


def test_benchmark_tables_are_those_of_the_layer_pages():
    text = (DOCS / "benchmarks.md").read_text("utf-8")
    sections = re.split(r"\n## ", text)[1:]
    checked = 0
    for section in sections:
        source = re.search(r"From \[([\w.-]+\.md)\]", section)
        if source is None:
            continue
        page = (DOCS / source.group(1)).read_text("utf-8")
        table_lines = [ln for ln in section.splitlines() if "|" in ln and not ln.startswith("`")]
        assert table_lines, section[:40]
        for line in table_lines:
            assert line in page, f"benchmarks.md line not on {source.group(1)}: {line}"
            checked += 1
    assert checked > 50


def test_model_format_example_is_the_example_model_file():
    doc = (DOCS / "model-format.md").read_text("utf-8")
    block = re.search(r"```toml\n(.*?)```", doc, re.S).group(1)
    assert block == (ROOT / "examples" / "my_model.toml").read_text("utf-8")
    data = tomllib.loads(block)
    documented = set(re.findall(r"^\| `(\w+)`", doc, re.M))
    for keys in re.findall(r"^\| (`\w+`(?:, `\w+`)+) \|", doc, re.M):
        documented |= set(re.findall(r"`(\w+)`", keys))
    assert set(data) <= documented


@pytest.mark.slow
def test_python_api_example_of_the_guide_runs(tmp_path, monkeypatch):
    guide = (DOCS / "guide.md").read_text("utf-8")
    blocks = re.findall(r"```python\n(.*?)```", guide, re.S)
    assert blocks
    monkeypatch.chdir(tmp_path)
    for code in blocks:
        namespace: dict = {}
        exec(compile(code, "guide.md", "exec"), namespace)   # noqa: S102 - our own documentation
    assert namespace["x"].shape == (3,)


@pytest.mark.parametrize("command", [
    'switchobs design abs-adaptive2 --spectrum "-beta,-beta"',
    'switchobs classify "[[-1,2],[-3,-4]]" "[[-2,0],[1,-1]]"',
    "switchobs theory --check",
])
def test_cli_output_shown_in_the_guide_is_what_the_command_prints(command, capsys, monkeypatch):
    guide = (DOCS / "guide.md").read_text("utf-8")
    block = re.search(r"^\$ " + re.escape(command) + r"\n(.*?)(?=\n\$ |\n```)", guide, re.S | re.M)
    assert block, f"the guide has no output of `{command}`"
    monkeypatch.chdir(ROOT)
    assert main(shlex.split(command)[1:]) == 0
    assert capsys.readouterr().out.rstrip("\n") == block.group(1).rstrip("\n")


def test_tests_cited_by_the_reproductions_page_exist():
    cited = set(re.findall(r"`(test_\w+)`", (DOCS / "reproductions.md").read_text("utf-8")))
    assert len(cited) > 8
    defined = set()
    for path in (ROOT / "tests").glob("test_*.py"):
        defined |= set(re.findall(r"^def (test_\w+)", path.read_text("utf-8"), re.M))
    assert cited <= defined, sorted(cited - defined)
