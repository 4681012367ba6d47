"""The compiled-code cache loads nothing another user could have written (issue "Hostile input, round 2",
security item 2).

A library in the cache is code that runs in the user's process.  The cache is the user's own directory,
created 0700; a directory owned by someone else or writable by others is refused with one line; a library is
loaded only with the SHA-256 its manifest recorded under its source's key; the cache is bounded.
"""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from switchobs.codegen import _build, cache_directory, compile_sources, find_compiler, load_library
from switchobs.exceptions import CodegenError

pytestmark = pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX owners and modes")

SOURCE = {"probe.c": "int switchobs_probe(void) { return 42; }\n"}


def _cc() -> str:
    try:
        return find_compiler()
    except CodegenError:
        pytest.skip("no C compiler: the compiled-code cache is NOT checked")


def _build_probe(root: Path, text: str = SOURCE["probe.c"]) -> Path:
    return compile_sources({"probe.c": text}, ["probe.c"], "probe", cache_dir=root, host=False)


def test_default_cache_is_the_users_own_cache_directory_not_a_shared_temp_dir(monkeypatch, tmp_path):
    monkeypatch.delenv("SWITCHOBS_CODEGEN_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    if sys.platform.startswith("linux"):
        assert cache_directory() == tmp_path / "xdg" / "switchobs" / "codegen"
        monkeypatch.delenv("XDG_CACHE_HOME")
        monkeypatch.setenv("HOME", str(tmp_path / "home"))
        assert cache_directory() == tmp_path / "home" / ".cache" / "switchobs" / "codegen"
    assert "switchobs-codegen-" not in str(cache_directory())   # the predictable name of old


def test_the_cache_is_created_0700_and_a_library_loads_and_runs(tmp_path):
    _cc()
    root = tmp_path / "cache"
    lib = load_library(_build_probe(root))
    assert lib.switchobs_probe() == 42
    assert stat.S_IMODE(root.stat().st_mode) == 0o700


def test_a_world_writable_cache_directory_is_refused_with_one_line(tmp_path, capsys):
    _cc()
    root = tmp_path / "planted"
    root.mkdir(mode=0o777)
    os.chmod(root, 0o777)       # what another user who created the predictable name first would leave
    with pytest.raises(CodegenError, match=r"refusing the compiled-code cache .*writable by other users|"
                                           r"refusing the compiled-code cache .*may write it"):
        _build_probe(root)
    from switchobs.cli.main import main
    os.environ["SWITCHOBS_CODEGEN_CACHE"] = str(root)
    try:
        rc = main(["simulate", "--observer-impl", "c", "--duration", "0.05", "-q"])
    finally:
        del os.environ["SWITCHOBS_CODEGEN_CACHE"]
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "refusing the compiled-code cache" in err and str(root) in err


def test_a_cache_directory_of_another_user_is_refused(tmp_path):
    _cc()
    if os.geteuid() != 0:
        pytest.skip("creating a directory owned by another user needs root: that refusal is NOT checked here "
                    "(the mode refusal is, by the test above)")
    root = tmp_path / "foreign"
    root.mkdir(mode=0o700)
    os.chown(root, 65534, 65534)   # nobody
    with pytest.raises(CodegenError, match=r"owned by user id 65534"):
        _build_probe(root)


def test_a_cache_below_a_world_writable_directory_is_refused_but_a_sticky_tmp_is_fine(tmp_path):
    _cc()
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)        # anyone may rename our directory away and put theirs in its place
    with pytest.raises(CodegenError, match=r"above it is writable by other users"):
        _build_probe(shared / "cache")
    os.chmod(shared, 0o1777)       # sticky, as /tmp: only the owner renames its entries
    assert load_library(_build_probe(shared / "cache2")).switchobs_probe() == 42


def test_a_planted_library_without_its_manifest_is_never_loaded(tmp_path):
    cc = _cc()
    root = tmp_path / "cache"
    path = _build_probe(root)
    marker = tmp_path / "ran"
    evil = tmp_path / "evil.c"
    evil.write_text('#include <stdio.h>\n__attribute__((constructor)) static void planted(void) {\n'
                    f'    FILE *f = fopen("{marker}", "w"); if (f) fclose(f);\n}}\n'
                    "int switchobs_probe(void) { return 666; }\n")
    subprocess.run([cc, "-shared", "-fPIC", "-o", str(path), str(evil)], check=True)   # same name, same place
    rebuilt = _build_probe(root)
    assert rebuilt == path and load_library(rebuilt).switchobs_probe() == 42
    assert not marker.exists()
    # tampered manifest: the recorded digest no longer matches the file, so it is rebuilt again
    manifest = path.with_suffix(".json")
    manifest.write_text(manifest.read_text().replace('"sha256": "', '"sha256": "0'))
    assert not _build._verified(path, path.stem.rsplit("-", 1)[1])
    assert _build._verified(_build_probe(root), path.stem.rsplit("-", 1)[1])


def test_a_library_switchobs_did_not_build_is_not_loaded(tmp_path):
    cc = _cc()
    other = tmp_path / "other.so"
    (tmp_path / "o.c").write_text("int f(void) { return 1; }\n")
    subprocess.run([cc, "-shared", "-fPIC", "-o", str(other), str(tmp_path / "o.c")], check=True)
    with pytest.raises(CodegenError, match="not a library that switchobs built"):
        load_library(other)


def test_the_cache_is_bounded_least_recently_used_first(tmp_path, monkeypatch):
    _cc()
    monkeypatch.setattr(_build, "CACHE_MAX_LIBRARIES", 3)
    root = tmp_path / "cache"
    paths = [_build_probe(root, f"int switchobs_probe(void) {{ return {i}; }}\n") for i in range(6)]
    kept = sorted(root.glob("*.so"))
    assert len(kept) == 3 and set(kept) == set(paths[-3:])
    assert len(list(root.glob("*.json"))) == 3


def test_the_cache_bounds_in_the_codegen_page_are_the_constants():
    import re

    page = (Path(__file__).resolve().parents[1] / "docs" / "codegen.md").read_text("utf-8")
    page = " ".join(page.split())
    assert int(re.search(r"`CACHE_MAX_LIBRARIES` = (\d+)", page).group(1)) == _build.CACHE_MAX_LIBRARIES
    assert int(re.search(r"`CACHE_MAX_BYTES` = (\d+) MiB", page).group(1)) * 2**20 == _build.CACHE_MAX_BYTES
