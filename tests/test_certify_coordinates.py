"""Certificates in the observer normal form's coordinates (seed 004 'Observer normal form' and Theorem 1).

A dense model with 6-digit decimal entries has gains ``K = T^-1 k`` of thousands of digits in its own
coordinates; ``certify`` then states the observer and the family in ``z = T x``.  These tests check that the
two statements are the same observer (same gains, same verdict), that the checker holds the similarity to
account, and that the doubles shown for the model's gains are the exact ones rounded.
"""

from __future__ import annotations

import json
import tomllib
from fractions import Fraction

import numpy as np
import pytest

from switchobs.certify import ObserverSection, certify_model, verify_certificate
from switchobs.design import NORMAL_FORM_DIGITS
from switchobs.design import design_gains, normal_form_design
from switchobs.design._normal_form import flint_matrix, rational_coordinates
from switchobs.exact import (add, fraction_matrix, lyapunov_form, matmul, nonsingular, solve, solve_float, to_fraction,
                             transpose)
from switchobs.model import Model

N = 12


def dense_model(n: int = N, seed: int = 3) -> tuple[Model, str]:
    """A dense random observable model and a spread spectrum, every number with 6 significant digits."""
    text, poles = dense_text(n, seed)
    return Model.from_dict(tomllib.loads(text), source="dense test model"), poles


def dense_text(n: int = N, seed: int = 3) -> tuple[str, str]:
    """The model file of :func:`dense_model` and its spectrum."""
    rng = np.random.default_rng(seed)
    six = lambda x: f"{float(f'{x:.6g}'):.6g}"  # noqa: E731
    G = rng.normal(size=(n, n)) / np.sqrt(n) - 0.5 * np.eye(n)
    rows = ", ".join("[" + ", ".join(f'"{six(x)}"' for x in row) + "]" for row in G)
    C = ", ".join(f'"{six(x)}"' for x in rng.normal(size=n))
    states = ", ".join(f'"x{i + 1}"' for i in range(n))
    text = f'name = "dense-{n}"\nstates = [{states}]\noutput = "y"\nA = [{rows}]\nC = [{C}]\ntime_scale = "y"\n'
    poles = ",".join(six(-1 - k / (n - 1)) for k in range(n))
    return text, poles


@pytest.fixture(scope="module")
def dense() -> tuple[Model, str]:
    return dense_model()


@pytest.fixture(scope="module")
def report(dense):
    model, poles = dense
    return certify_model(model, spectrum=poles)


def test_observer_coordinates_are_the_normal_form_seed004(dense):
    model, _ = dense
    A, C = fraction_matrix(model.A), fraction_matrix(model.C)
    c, _, T = rational_coordinates(flint_matrix(model.A), flint_matrix(model.C))
    a, T = [-to_fraction(x) for x in c[1:]], fraction_matrix(T.tolist())
    n = len(A)
    A_nf = [[a[i] if j == 0 else Fraction(1 if j == i + 1 else 0) for j in range(n)] for i in range(n)]
    assert matmul(T, A) == matmul(A_nf, T)
    assert T[0] == C[0]
    assert nonsingular(T)


def test_normal_form_design_is_theorem1_of_the_model_design_seed004(dense):
    model, poles = dense
    nf = normal_form_design(model, poles)
    e1 = [[Fraction(1)] + [Fraction(0)] * (N - 1)]
    for Ap in (nf.A_plus, nf.A_minus):  # A_p' P + P A_p = -e1 e1' on both sides (Theorem 1)
        assert add(lyapunov_form(Ap, nf.P), matmul(transpose(e1), e1)) == [[0] * N for _ in range(N)]
    exact = design_gains(model, poles)  # the same gains as the model-coordinate design, exactly
    T = nf.T
    assert matmul(T, fraction_matrix([[k] for k in exact.K_plus])) == [[k] for k in nf.k_plus]
    assert matmul(T, fraction_matrix([[k] for k in exact.K_minus])) == [[k] for k in nf.k_minus]
    K_plus, K_minus = nf.gains()
    assert np.array_equal(K_plus, [float(to_fraction(k)) for k in exact.K_plus])
    assert np.array_equal(K_minus, [float(to_fraction(k)) for k in exact.K_minus])


def test_dense_decimal_certificate_is_stated_in_normal_form_coordinates(report):
    observer = report.document["observer"]
    assert "T" in observer
    assert max(len(x) for row in observer["T"] for x in row) > NORMAL_FORM_DIGITS
    assert report.verification.holds and report.certified
    assert report.verdict.dwell_time == "any"


def test_both_coordinates_give_the_same_verdict_seed004_theorem1(dense, report):
    model, poles = dense
    in_model = certify_model(model, gains=design_gains(model, poles))
    assert "T" not in in_model.document["observer"]
    assert in_model.verdict == report.verdict


def test_displayed_model_gains_are_the_exact_gains_rounded(dense, report):
    model, poles = dense
    exact = design_gains(model, poles)
    K_plus, K_minus = ObserverSection.from_json(report.document["observer"]).model_gains()
    assert K_plus == [float(to_fraction(k)) for k in exact.K_plus]
    assert K_minus == [float(to_fraction(k)) for k in exact.K_minus]


def _tampered(document: dict, edit) -> dict:
    doc = json.loads(json.dumps(document))
    edit(doc["observer"])
    return doc


@pytest.mark.parametrize("what, edit, detail", [
    ("one entry of T", lambda o: o["T"][3].__setitem__(2, str(Fraction(o["T"][3][2]) + 1)), "differs"),
    ("one gain", lambda o: o["K_plus"].__setitem__(1, str(Fraction(o["K_plus"][1]) * 2)), "differs"),
    ("a singular T", lambda o: o.__setitem__("T", [o["T"][0]] * len(o["T"])), "singular"),
])
def test_checker_refuses_a_broken_similarity(report, what, edit, detail):
    result = verify_certificate(_tampered(report.document, edit))
    failed = [c for c in result.checks if not c.holds]
    assert not result.holds, what
    assert failed[0].name == "observer" and detail in failed[0].detail


def test_certificates_without_coordinates_keep_their_form():
    section = ObserverSection([["1"]], [["1"]], ["2"], ["3"])
    assert "T" not in section.to_json()
    assert section.model_gains() is None


def test_flint_rationals_convert_exactly():
    flint = pytest.importorskip("flint")
    big = flint.fmpq(10**60 + 1, 3**70)
    assert to_fraction(big) == Fraction(10**60 + 1, 3**70)


def test_solve_float_is_the_exact_solution_rounded_on_an_ill_conditioned_matrix():
    n = 12  # the Hilbert matrix: condition number about 1e16, beyond what a float solve gets right
    H = [[Fraction(1, i + j + 1) for j in range(n)] for i in range(n)]
    b = [[Fraction(k + 1)] for k in range(n)]
    exact = solve(H, b)
    assert solve_float(H, b) == [[float(x[0])] for x in exact]
    assert np.max(np.abs(np.linalg.solve(np.array(H, dtype=float), np.array(b, dtype=float)).ravel()
                         - [float(x[0]) for x in exact])) > 0  # the float solve is not the exact one


def test_cli_shows_the_model_gains_of_a_normal_form_certificate(tmp_path, capsys):
    from switchobs.cli.main import main

    text, poles = dense_text()
    path = tmp_path / "dense.toml"
    path.write_text(text, encoding="utf-8")
    assert main(["certify", str(path), "--spectrum", poles, "--out", str(tmp_path / "c.json")]) == 0
    out = capsys.readouterr().out
    K_plus, _ = ObserverSection.from_json(json.loads((tmp_path / "c.json").read_text())["observer"]).model_gains()
    assert f"K_plus  = [{K_plus[0]:.6g}, " in out
    assert "normal form's coordinates z = T x" in out
    assert main(["verify", str(tmp_path / "c.json")]) == 0


def test_docs_state_the_coordinates_threshold():
    from pathlib import Path

    text = " ".join((Path(__file__).resolve().parents[1] / "docs" / "certify.md").read_text().split())
    assert f"`NORMAL_FORM_DIGITS` = {NORMAL_FORM_DIGITS} digits" in text


def test_normal_form_statement_only_where_the_model_coordinates_are_long(dense):
    from switchobs.design import normal_form_statement
    from switchobs.model import builtin_model

    model, poles = dense
    assert normal_form_statement(model, poles) is not None
    xbs3 = builtin_model("abs-xbs3")
    assert normal_form_statement(xbs3.with_values({}).numeric(), "-10,-20,-20") is None  # short T: model's own
    assert normal_form_statement(model, ",".join(["-beta"] * N)) is None  # design symbols: the symbolic design


def test_normal_form_design_recheck_catches_a_wrong_T(dense):
    import dataclasses

    model, poles = dense
    nf = normal_form_design(model, poles)
    assert all(nf.verify().values())
    T = [row[:] for row in nf.T]
    T[2][5] += 1
    broken = dataclasses.replace(nf, T=T).verify()
    assert broken["similarity"] is False and broken["lyapunov_plus"] is True


def test_cli_design_of_a_dense_model_states_the_normal_form(tmp_path, dense, capsys):
    from switchobs.cli.main import main

    text, poles = dense_text()
    path = tmp_path / "dense.toml"
    path.write_text(text, encoding="utf-8")
    assert main(["design", str(path), "--spectrum", poles, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["coordinates"].startswith("observer normal form") and all(data["verified"].values())
    model, _ = dense
    exact = design_gains(model, poles)
    assert data["K_plus"] == [float(to_fraction(k)) for k in exact.K_plus]
    assert data["k_plus"] == [str(x) for x in normal_form_design(model, poles).k_plus]
    assert main(["design", str(path), "--spectrum", poles]) == 0
    assert "in its observer normal form's coordinates z = T x" in capsys.readouterr().out


def test_normal_form_design_reprs_stay_short(dense):
    model, poles = dense
    nf = normal_form_design(model, poles)
    assert len(repr(nf)) < 120 and len(nf._repr_markdown_()) < 200 * N


def test_model_coordinates_are_the_long_statement_of_a_dense_design(dense):
    # docs/design.md: the model's gains grow like n^2 times the data's digits, T's entries like n
    model, poles = dense
    nf = normal_form_design(model, poles)
    in_model = max(len(str(k)) for k in design_gains(model, poles).K_plus)
    in_z = max(len(str(x)) for row in nf.T for x in row + [nf.k_plus[0]])
    assert in_model > N / 2 * in_z


def test_codegen_of_a_dense_model_writes_the_exact_gains_doubles(tmp_path, monkeypatch):
    import switchobs.design._design as designs
    from switchobs.cli.main import main
    from switchobs.codegen import generate_observer

    monkeypatch.setattr(designs, "NORMAL_FORM_DIGITS", 10)  # a small model through the dense path: quick C
    text, poles = dense_text(5)
    model = Model.from_dict(tomllib.loads(text), source="dense test model")
    assert designs.normal_form_statement(model, poles) is not None
    path = tmp_path / "dense.toml"
    path.write_text(text, encoding="utf-8")
    assert main(["codegen", str(path), "--spectrum", poles, "--out", str(tmp_path / "c")]) == 0
    via_exact = generate_observer(model, design_gains(model, poles))  # the model-coordinate design's doubles
    assert via_exact.default_params == generate_observer(model, normal_form_design(model, poles).gains()).default_params
    written = (tmp_path / "c" / f"{via_exact.prefix}.c").read_text()
    assert written.split("\n", 3)[3] == via_exact.source.split("\n", 3)[3]  # the same C past the command line


def test_normal_form_coordinates_are_O_nf_inverse_O_by_their_definition_seed004(dense):
    import sympy as sp

    model, _ = dense  # T = O_nf^-1 O solved in sympy from the definitions, not by the Toeplitz product
    A, C = sp.Matrix(model.A), sp.Matrix(model.C)
    design = normal_form_design(model, ",".join(["-1"] * N))
    A_nf = sp.Matrix(N, N, lambda i, j: sp.Rational(design.a[i]) if j == 0 else int(j == i + 1))

    def observability(M: sp.Matrix, row: sp.Matrix) -> sp.Matrix:
        rows = [row]
        for _ in range(N - 1):
            rows.append(rows[-1] * M)
        return sp.Matrix.vstack(*rows)

    T = observability(A_nf, sp.Matrix([[1] + [0] * (N - 1)])).LUsolve(observability(A, C))
    assert design.T == fraction_matrix(T)
    assert list(design.a) == [-to_fraction(c) for c in sp.Matrix(A).charpoly().all_coeffs()[1:]]


@pytest.mark.parametrize("seed", range(6))
def test_nonsingular_agrees_with_the_fraction_determinant(seed):
    import sympy as sp

    rng = np.random.default_rng(seed)
    n = 7
    M = [[Fraction(int(rng.integers(-9, 10)), int(rng.integers(1, 5))) for _ in range(n)] for _ in range(n)]
    if seed % 2:  # a dependent row, scaled by a prime's multiple: singular however the residues fall
        M[3] = [2 * x + 3 * y for x, y in zip(M[0], M[1])]
    det = sp.Matrix([[sp.Rational(x.numerator, x.denominator) for x in row] for row in M]).det()
    assert nonsingular(M) == (det != 0)
