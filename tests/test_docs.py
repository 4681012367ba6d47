"""The documentation site builds in strict mode and says what the code does."""

from __future__ import annotations

import importlib
import os
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import yaml

from switchobs._layers import FLOORS
from switchobs.cli.main import COMMANDS, main

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
RESULTS = ROOT / "benchmarks" / "results"
BENCH_BLOCK = re.compile(r"<!-- bench:([\w-]+) -->\n(.*?)<!-- /bench:\1 -->", re.S)
TABLE = re.compile(r"^(\|.*\|)\n(\|[-:| ]+\|)\n((?:\|.*\|\n)+)", re.M)


def _nav_pages(nav) -> list[str]:
    pages = []
    for item in nav:
        value = next(iter(item.values())) if isinstance(item, dict) else item
        pages += _nav_pages(value) if isinstance(value, list) else [value]
    return pages


#: Loaded first by the docs build (PYTHONPATH): any network connection fails, as on an offline machine.
NO_NETWORK = """
import socket

def _offline(*args, **kwargs):
    raise OSError("the docs test builds offline: no network connection allowed")

socket.socket.connect = socket.socket.connect_ex = _offline
socket.create_connection = socket.getaddrinfo = _offline
"""
REMOTE = re.compile(r"<(?:script|link)\b[^>]*\b(?:src|href)=\"((?:https?:)?//[^\"]+)\"")
#: The packages the API pages render, one page each (docs/api/<name>.md): every layer but the CLI, and the exceptions.
LAYERS = tuple(name for floor in FLOORS for name in floor if name != "cli") + ("exceptions",)
#: A Sphinx role as the docstrings write it; the API pages show cross-references instead (docs/_hooks/roles.py).
ROLE = re.compile(r":(?:func|meth|class|data|attr|mod|exc|obj|const):`")


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built once, strict, with the network cut off."""
    tmp = tmp_path_factory.mktemp("docs")
    (tmp / "sitecustomize.py").write_text(NO_NETWORK, encoding="utf-8")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(tmp), os.environ.get("PYTHONPATH")]))}
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp / "site")],
                          cwd=str(ROOT), capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "WARNING" not in proc.stderr
    return tmp / "site"


def test_the_docs_build_cannot_reach_the_network(tmp_path):
    (tmp_path / "sitecustomize.py").write_text(NO_NETWORK, encoding="utf-8")
    probe = "import urllib.request; urllib.request.urlopen('http://127.0.0.1:9/', timeout=2)"
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(tmp_path)}, timeout=60)
    assert proc.returncode != 0 and "no network connection allowed" in proc.stderr


@pytest.mark.slow
def test_mkdocs_builds_in_strict_mode(site):
    for page in ("index.html", "guide.html", "model-format.html", "reproductions.html",
                 "benchmarks.html", "theory/abs-xbs3.html", "theory/normal-form-3.html",
                 "api/index.html", "api/codegen.html"):
        assert (site / page).is_file(), page
    # the generated theory reaches the site with its math for MathJax
    assert "arithmatex" in (site / "theory" / "abs-xbs4.html").read_text("utf-8")


@pytest.mark.slow
def test_the_site_loads_no_script_or_style_from_outside_and_serves_mathjax_itself(site):
    pages = sorted(site.rglob("*.html"))
    assert len(pages) > 15
    for page in pages:
        remote = REMOTE.findall(page.read_text("utf-8"))
        assert not remote, f"{page.relative_to(site)} loads {remote}"
    theory = (site / "theory" / "abs-xbs4.html").read_text("utf-8")
    assert '<script src="../javascripts/mathjax/tex-svg.js"></script>' in theory
    mathjax = site / "javascripts" / "mathjax" / "tex-svg.js"
    assert mathjax.stat().st_size > 1_000_000 and b'VERSION="3.' in mathjax.read_bytes()  # MathJax 3
    assert "Apache License" in (site / "javascripts" / "mathjax" / "LICENSE").read_text("utf-8")


@pytest.mark.slow
def test_the_site_browses_from_the_file_system(site):
    """use_directory_urls is off: every link, script, style and image of every page names a file of the site (what a
    browser opens from file://, where a directory does not show its index.html)."""
    reference = re.compile(r'\b(?:href|src)="([^"#?]+)[^"]*"')
    checked = 0
    for page in sorted(p for p in site.rglob("*.html") if p.name != "404.html"):  # 404: a server's page only
        for target in reference.findall(page.read_text("utf-8")):
            if re.match(r"(?:[a-z]+:|//)", target):   # mailto:, data:, an external address: not a file of the site
                continue
            path = (page.parent / target).resolve()
            assert path.is_file(), f"{page.relative_to(site)} links to {target}, which is not a file of the site"
            checked += 1
    assert checked > 1000


@pytest.mark.slow
def test_the_api_reference_documents_every_public_name_from_its_docstring(site):
    for layer in LAYERS:
        html = (site / "api" / f"{layer}.html").read_text("utf-8")
        ids = set(re.findall(r'id="(switchobs\.[\w.]+)"', html))
        names = importlib.import_module(f"switchobs.{layer}").__all__
        missing = [name for name in names if f"switchobs.{layer}.{name}" not in ids]
        assert not missing, f"the API page of switchobs.{layer} lacks {missing}"
    # rendered from the numpydoc sections, not pasted as text
    from switchobs.design import design_gains

    html = (site / "api" / "design.html").read_text("utf-8")
    assert design_gains.__doc__.split("\n")[0].strip() in html
    assert "Parameters:" in html and "Raises:" in html


@pytest.mark.slow
def test_the_api_pages_are_one_per_layer_and_show_cross_references_not_roles(site):
    assert sorted(p.stem for p in (DOCS / "api").glob("*.md")) == sorted([*LAYERS, "index"])
    links = 0
    for layer in LAYERS:
        html = (site / "api" / f"{layer}.html").read_text("utf-8")
        roles = ROLE.findall(html)
        assert not roles, f"the API page of switchobs.{layer} shows {len(roles)} raw Sphinx roles"
        prose = re.sub(r"<(code|pre)\b[^>]*>.*?</\1>", "", html, flags=re.S)   # a constant's value is code
        seeds = SEED_NUMBER.findall(prose)
        assert not seeds, f"the API page of switchobs.{layer} cites {seeds[0]!r}, not the paper's author and year"
        links += html.count('class="autorefs autorefs-internal"')
    assert links > 500
    # prove's docstring says :func:`proof_record`: a link to where the codegen page renders it
    codegen = (site / "api" / "codegen.html").read_text("utf-8")
    assert 'href="#switchobs.codegen.proof_record"' in codegen
    # a role naming another layer's object links across pages (ParameterBox lives in model, certify re-exports it)
    assert 'href="model.html#switchobs.model.ParameterBox' in (site / "api" / "certify.html").read_text("utf-8")


#: An internal seed number; the pages cite the papers by author and year (Hoang et al. 2014, ...).
SEED_NUMBER = re.compile(r"\b[Ss]eeds?[ -]00[0-9]")


def test_the_pages_cite_the_papers_by_author_and_year():
    """No page names a paper by its seed number: not the hand-written text, not the generated sections and pages
    (``switchobs reproduce``, ``switchobs theory``), not the command output shown.

    Only the benchmark blocks are left out: each is ``benchmarks/results/<script>.md`` copied whole (checked by
    ``test_benchmark_blocks_are_the_generated_results``), the record of a measurement, whose text changes only
    with a new one (``make bench``; ``benchmarks/_harness.publish`` cites by author and year).
    """
    bench = re.compile(r"<!-- bench:([\w-]+) -->.*?<!-- /bench:\1 -->", re.S)
    pages = [ROOT / "README.md", *DOCS.glob("*.md"), *DOCS.glob("api/*.md"), *(ROOT / "theory").glob("*.md")]
    assert any(p.name == "reproductions.md" for p in pages) and any(p.parent.name == "theory" for p in pages)
    for page in pages:
        found = SEED_NUMBER.findall(bench.sub("", page.read_text("utf-8")))
        assert not found, f"{page.relative_to(ROOT)} cites {found[0]!r}: cite the paper by author and year"


@pytest.mark.parametrize("command", [None, *COMMANDS])
def test_the_help_of_every_command_cites_no_seed_number(command, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--help"] if command is None else [command, "--help"])
    assert exit_.value.code == 0
    help_text = " ".join(capsys.readouterr().out.split())   # argparse wraps "seed" and "000" onto two lines
    assert "usage: switchobs" in help_text
    found = SEED_NUMBER.findall(help_text)
    assert not found, f"switchobs {command or ''} --help cites {found[0]!r}: cite the paper by author and year"


def test_the_generated_c_and_its_files_cite_the_papers_by_author_and_year():
    """Every file of the generated observers (header, source, README, MISRA record, the A2L), for each kind:
    no seed number; the papers by author and year in ASCII, the equation numbers kept."""
    from switchobs.codegen import generate_a2l, generate_observer, generate_super_twisting, generate_vehicle_speed
    from switchobs.design import design
    from switchobs.model import builtin_model

    def switched(name, spectrum, **kw):
        model = builtin_model(name)
        return generate_observer(model, design(model, spectrum), **kw)

    gens = [switched("abs-xbs3", "-100,-100,-100"), switched("abs-xbs4", "-10,-10,-20,-20"),
            switched("abs-adaptive2", "-15,-15", unknown=["c", "d"], Gamma=[50.0, 20.0], method="rk4"),
            generate_super_twisting(10.0, 20.0), generate_vehicle_speed(5.0)]
    cited = {"abs-xbs3": "Hoang et al. 2014 eq. (8)-(9), Pasillas-Lepine",
             "abs-xbs4": "Hoang et al. 2014 eq. (20)", "abs-adaptive2": "Aguado-Rojas 2020 eq. (3.4)",
             "super-twisting": "M'Sirdi et al. 2008 eq. (8)-(9)", "vehicle-speed": "M'Sirdi et al. 2008 eq. (15)"}
    for gen in gens:
        files = {**gen.files, f"{gen.prefix}.a2l": generate_a2l(gen)}
        for name, text in files.items():
            found = SEED_NUMBER.findall(" ".join(text.split()))
            assert not found, f"{gen.model_name}: the generated {name} cites {found[0]!r}"
        assert cited[gen.model_name] in gen.header + gen.readme, gen.model_name
        assert (gen.header + gen.source).isascii(), gen.model_name   # the source character set of C


def test_every_page_is_in_the_navigation_and_every_nav_entry_exists():
    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text("utf-8"))
    nav = _nav_pages(config["nav"])
    pages = sorted(str(p.relative_to(DOCS)) for p in [*DOCS.glob("*.md"), *DOCS.glob("api/*.md")])
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


def test_benchmark_blocks_are_the_generated_results():
    shown: dict[str, set[str]] = {}
    for page in DOCS.glob("*.md"):
        for name, body in BENCH_BLOCK.findall(page.read_text("utf-8")):
            result = RESULTS / f"{name}.md"
            assert result.is_file(), f"{page.name} shows benchmarks/results/{name}.md, which does not exist"
            assert body == result.read_text("utf-8"), \
                f"{page.name}: the {name} block is not benchmarks/results/{name}.md; run benchmarks/render_docs.py"
            shown.setdefault(name, set()).add(page.name)
    results = {p.stem for p in RESULTS.glob("*.md")}
    assert {"design_scaling", "certify_scaling", "codegen_step", "observer_step", "abs_sim",
            "encoder_chain"} <= results
    assert results <= {p.stem for p in (ROOT / "benchmarks").glob("*.py")}
    for name in results:  # on the overview and on its layer's page
        assert "benchmarks.md" in shown.get(name, set()) and len(shown[name]) >= 2, name


def test_benchmark_results_name_their_script_machine_load_and_statistics():
    for path in RESULTS.glob("*.md"):
        text = path.read_text("utf-8")
        first = text.splitlines()[0]
        assert first.startswith(f"Generated by `benchmarks/{path.stem}.py` (`make bench`) on "), path.name
        assert "machine: " in first and "load average" in first, path.name
        if path.stem == "target":  # instructions counted by qemu: exact, the same on every run (no spread)
            assert "exact counts (one run each)" in text, path.name
        elif path.stem == "numeric_inputs":  # commands of minutes at n = 64, on a shared machine: one run each
            assert "CPU time" in text and "each run once" in text, path.name
        else:
            assert "CPU time" in text and "median [min–max]" in text, path.name
        tables = TABLE.findall(text)
        assert tables, f"{path.name} holds no markdown table"
        for header, rule, rows in tables:
            width = header.count("|")
            assert rule.count("|") == width, path.name
            assert all(row.count("|") >= width for row in rows.splitlines()), path.name


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
