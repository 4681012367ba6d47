"""Terminal output and notebook reprs shorten long exact rationals, and say so; the results stay exact.

A float entry (python-control's ``-2.1``) is the 52-bit fraction ``-4728779608739021/2251799813685248``,
and a design on a 6-digit decimal spectrum has gains of 100-digit fractions; printed in full they made a
wall of digits (and a 66 kB notebook repr at n = 12).
"""

from __future__ import annotations

import json
import re
from fractions import Fraction

import control
import numpy as np
import pytest

from switchobs._display import MAX_EXACT_CHARS, ROUNDED_NOTE
from switchobs.cli.main import main
from switchobs.design import design_gains
from switchobs.model import Model

LONG_RATIONAL = re.compile(r"-?\d+/\d+")


def _float_model(n: int) -> Model:
    rng = np.random.default_rng(n)
    A = np.diag(np.ones(n - 1), 1) - np.diag(rng.uniform(0.5, 2.5, n))
    C = np.zeros((1, n))
    C[0, 0] = 1.0
    return Model.from_statespace(control.ss(A, np.zeros((n, 1)), C, 0), time_scale="y")


def _longest_rational(text: str) -> int:
    return max((len(m) for m in LONG_RATIONAL.findall(text)), default=0)


def test_design_text_and_reprs_of_a_float_model_shorten_its_binary_fractions_and_say_so():
    model = _float_model(12)
    design = design_gains(model, ",".join(str(-1 - k / 7) for k in range(12)))
    text = str(design)
    assert _longest_rational(text) <= MAX_EXACT_CHARS and ROUNDED_NOTE in text
    assert len(model._repr_markdown_()) < 5000 and _longest_rational(model._repr_markdown_()) <= MAX_EXACT_CHARS
    assert _longest_rational(design._repr_markdown_()) <= MAX_EXACT_CHARS
    # the result itself keeps every digit
    assert any(len(str(k)) > MAX_EXACT_CHARS for k in design.K_minus)


def test_a_short_design_is_printed_exactly_without_the_note():
    model = Model.from_statespace(control.ss([[-1, 1], [0, -2]], [[0], [0]], [[1, 0]], 0), time_scale="y")
    design = design_gains(model, "-3,-4")
    assert ROUNDED_NOTE not in str(design)


@pytest.fixture(scope="module")
def chain_file(tmp_path_factory):
    n = 8
    A = [["0"] * n for _ in range(n)]
    for i in range(n):
        A[i][i] = "-" + ["1", "3/2", "2", "5/2"][i % 4]
        if i + 1 < n:
            A[i][i + 1] = "1"
    path = tmp_path_factory.mktemp("chain") / "chain8.toml"
    rows = ", ".join("[" + ", ".join(f'"{x}"' for x in row) + "]" for row in A)
    states = ", ".join(f'"x{i + 1}"' for i in range(n))
    C = ", ".join(['"1"'] + ['"0"'] * (n - 1))
    path.write_text(f'name = "chain8"\nstates = [{states}]\nA = [{rows}]\nC = [{C}]\ntime_scale = "y"\n', "utf-8")
    return path, ",".join(f"{-(1 + k / 7):.6g}" for k in range(n))


def test_certify_prints_long_gains_to_six_digits_and_exact_with_the_flag(chain_file, capsys):
    path, spectrum = chain_file
    assert main(["certify", str(path), f"--spectrum={spectrum}", "--no-dwell"]) == 0
    short = capsys.readouterr().out
    gains_short = [line for line in short.splitlines() if line.lstrip().startswith("K_")]
    assert ROUNDED_NOTE in short and _longest_rational("\n".join(gains_short)) <= MAX_EXACT_CHARS
    assert main(["certify", str(path), f"--spectrum={spectrum}", "--no-dwell", "--exact"]) == 0
    exact = capsys.readouterr().out
    assert ROUNDED_NOTE not in exact
    assert main(["certify", str(path), f"--spectrum={spectrum}", "--no-dwell", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    K_plus = doc["certificate"]["observer"]["K_plus"]
    assert f"  K_plus  = [{', '.join(K_plus)}]" in exact
    assert any(len(k) > MAX_EXACT_CHARS for k in K_plus)
    # each shortened gain is the exact one to 6 significant digits
    shown = re.search(r"K_plus  = \[(.*)\]", short).group(1).split(", ")
    for text, value in zip(shown, K_plus):
        assert float(text) == pytest.approx(float(Fraction(value)), rel=1e-5)
