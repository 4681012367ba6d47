"""Numeric observers of large dimension: certify / verify round trips and the CLI chain (issue 12)."""

from __future__ import annotations

import copy
import json
import signal
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import pytest

from switchobs.certify import certify_model, verify_certificate
from switchobs.codegen import find_compiler
from switchobs.model import Model

POLES = ("-2", "-3", "-5/2", "-7/2")


def chain(n: int) -> dict:
    """First-order lags ``x_i' = -d_i x_i + x_(i+1)`` seen through ``y = x_1`` (as in benchmarks/numeric_scaling.py)."""
    lags = ("1", "3/2", "2", "5/2")
    A = [["0"] * n for _ in range(n)]
    for i in range(n):
        A[i][i] = f"-{lags[i % 4]}"
        if i < n - 1:
            A[i][i + 1] = "1"
    return {"name": f"chain-{n}", "states": [f"x{i + 1}" for i in range(n)], "output": "y", "A": A,
            "C": ["1"] + ["0"] * (n - 1), "time_scale": "y"}


def spectrum(n: int) -> str:
    return ",".join(POLES[i % 4] for i in range(n))


def _hespanha(doc: dict) -> dict:
    return next(c for c in doc["certificates"] if c["kind"] == "hespanha")


@pytest.mark.slow
@pytest.mark.parametrize("n", [16, 32])
def test_certify_verify_round_trip_and_tampering_at_size(n):
    report = certify_model(Model.from_dict(chain(n)), spectrum=spectrum(n), dwell=False)
    assert report.certified and report.verification.holds
    assert report.verdict.dwell_time == "any"
    assert report.hespanha.method == "exact P of the gain design"
    doc = json.loads(json.dumps(report.document))
    assert verify_certificate(doc).holds
    # a P entry nudged off the design's exact value breaks the Lyapunov inequality
    bad = copy.deepcopy(doc)
    P = _hespanha(bad)["P"]
    P[n - 1][n - 1] = str(Fraction(P[n - 1][n - 1]) * Fraction(1, 2))
    P[0][0] = str(Fraction(P[0][0]) * Fraction(1, 2))
    assert not verify_certificate(bad).holds
    # an error matrix that does not come from the observer's gains
    bad = copy.deepcopy(doc)
    bad["family"]["matrices"][0][n - 1][0] = str(Fraction(bad["family"]["matrices"][0][n - 1][0]) + 1)
    checks = {c.name: c for c in verify_certificate(bad).checks}
    assert not checks["observer"].holds
    # the claimed verdict must be the one the certificates imply
    bad = copy.deepcopy(doc)
    bad["verdict"]["arbitrary_switching"] = "UGES"
    assert not verify_certificate(bad).holds


def chain_file(n: int, folder: Path) -> Path:
    """The chain model of size n as a TOML model file, as a user would write it."""
    data = chain(n)
    rows = ",\n     ".join("[" + ", ".join(f'"{x}"' for x in row) + "]" for row in data["A"])
    model = folder / "chain.toml"
    model.write_text(f'name = "chain-{n}"\nstates = {json.dumps(data["states"])}\noutput = "y"\nA = [{rows}]\n'
                     f'C = {json.dumps(data["C"])}\ntime_scale = "y"\n', encoding="utf-8")
    return model


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "switchobs", *args], capture_output=True, text=True, cwd=str(cwd),
                          timeout=900)


@pytest.mark.slow
def test_a_32_state_model_goes_through_design_certify_verify_codegen_compile(tmp_path):
    n = 32
    model = chain_file(n, tmp_path)
    design = _cli("design", str(model), "--spectrum", spectrum(n), "--json", cwd=tmp_path)
    assert design.returncode == 0, design.stderr
    assert all(json.loads(design.stdout)["verified"].values())
    cert = tmp_path / "cert.json"
    certify = _cli("certify", str(model), "--spectrum", spectrum(n), "--no-dwell", "--out", str(cert), cwd=tmp_path)
    assert certify.returncode == 0, certify.stderr
    assert "Traceback" not in certify.stderr
    verify = _cli("verify", str(cert), cwd=tmp_path)
    assert verify.returncode == 0 and "certificate holds exactly" in verify.stdout
    out = tmp_path / "c"
    codegen = _cli("codegen", str(model), "--spectrum", spectrum(n), "--out", str(out), cwd=tmp_path)
    assert codegen.returncode == 0, codegen.stderr
    source = next(out.glob("*.c"))
    obj = tmp_path / "observer.o"
    cc = subprocess.run([find_compiler(), "-std=c99", "-O1", "-Wall", "-Wextra", "-pedantic", "-Werror", "-c",
                         str(source), "-o", str(obj)], capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr
    assert obj.stat().st_size > 0


@pytest.mark.slow
def test_ctrl_c_stops_certify_with_130_and_no_certificate(tmp_path):
    n = 16
    model = chain_file(n, tmp_path)
    cert = tmp_path / "cert.json"
    # --verbose: into a pipe, the progress notes are lines only when asked for; --dwell: the Geromel-Colaneri
    # bisection runs for minutes at n = 16, so the signal finds it at work
    proc = subprocess.Popen([sys.executable, "-m", "switchobs", "--verbose", "certify", str(model), "--spectrum",
                             spectrum(n), "--dwell", "--out", str(cert)], stderr=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    first = proc.stderr.readline()          # the first progress line: the command is at work
    assert first.startswith("switchobs certify: [")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130
    assert err.strip().splitlines()[-1] == "switchobs certify: interrupted"
    assert "Traceback" not in err
    assert list(tmp_path.iterdir()) == [model]


@pytest.mark.parametrize("multiplicity", [2, 3, 4])
def test_a_repeated_pole_is_printed_as_the_exact_pole_not_its_rounding_scatter(multiplicity):
    # the eigenvalues of a k-fold pole scatter by eps**(1/k) in floating point (differently on every BLAS);
    # the printed spectrum takes the square-free factor of the exact characteristic polynomial instead
    from switchobs.certify import as_family

    n = multiplicity + 1
    M = [[Fraction(-100) if i == j else Fraction(1) if j == i + 1 else Fraction(0) for j in range(n)]
         for i in range(n)]
    M[-1][-1] = Fraction(-7, 3)   # one simple pole beside the Jordan block
    text = as_family([M, M]).spectra()["A_1"]
    assert text == "[" + ", ".join(["-100"] * multiplicity + ["-2.33333"]) + "]"
