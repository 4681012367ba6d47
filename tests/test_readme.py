"""The README's quick start works as written from the repository root and writes only under out/."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from switchobs.cli.main import main

ROOT = Path(__file__).resolve().parents[1]
ENTRY = ".venv/bin/switchobs"
OUTPUT_OPTIONS = ("--out", "--plot")


def _quick_start() -> list[list[str]]:
    readme = (ROOT / "README.md").read_text("utf-8")
    block = re.search(r"^## Quick start\n.*?```sh\n(.*?)```", readme, re.S | re.M)
    assert block, "README.md has no sh block under '## Quick start'"
    return [words for line in block.group(1).splitlines() if (words := shlex.split(line, comments=True))]


def test_the_quick_start_installs_first_and_writes_only_under_out():
    commands = _quick_start()
    assert commands[0] == ["make", "install"]
    assert commands[1] == ["mkdir", "-p", "out"]
    runs = commands[2:]
    assert runs and all(words[0] == ENTRY for words in runs)
    targets = [words[i + 1] for words in runs for i, w in enumerate(words[:-1]) if w in OUTPUT_OPTIONS]
    assert len(targets) >= 3 and all(t.startswith("out/") for t in targets), targets


@pytest.mark.slow
def test_the_quick_start_commands_run_from_the_repository_root(tmp_path, monkeypatch, capsys):
    # a fresh clone as far as the commands see it: the examples, and no out/ yet
    (tmp_path / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    for words in _quick_start()[1:]:
        if words[0] == "mkdir":
            Path(words[-1]).mkdir(parents=True, exist_ok=True)
            continue
        code = main(words[1:])
        out, err = capsys.readouterr()
        assert code == 0, f"{shlex.join(words)} exited {code}: {err}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["examples", "out"]
    written = sorted(str(p.relative_to(tmp_path / "out")) for p in (tmp_path / "out").rglob("*") if p.is_file())
    assert written == ["c/README.md", "c/switchobs_abs_xbs3.c", "c/switchobs_abs_xbs3.h", "c/switchobs_abs_xbs3_misra.md",
                       "cert.json", "fig4.png"]
    assert (tmp_path / "out" / "fig4.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_layer_table_names_every_command_and_every_layer():
    from switchobs.cli.main import COMMANDS

    readme = (ROOT / "README.md").read_text("utf-8")
    cli_row = next(line for line in readme.splitlines() if line.startswith("| cli |"))
    assert [c for c in COMMANDS if f"`switchobs {c}`" not in cli_row and f"`{c}`" not in cli_row] == []
    layers = sorted(p.name for p in (ROOT / "src" / "switchobs").iterdir() if (p / "__init__.py").is_file())
    assert [name for name in layers if f"`switchobs.{name}`" not in readme] == []


def test_the_missing_project_urls_are_answered_in_the_readme():
    """pyproject.toml names no project URL; the README says why (issue: package metadata)."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))["project"]
    readme = (ROOT / "README.md").read_text("utf-8")
    if "urls" in project:
        assert "no project URLs" not in readme, "the README says there are no project URLs, pyproject.toml has some"
    else:
        assert "The package metadata has no project URLs" in readme
