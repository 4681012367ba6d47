"""Simulation evidence of issue 19: the seed's beta design against the synthesised pair on the demo braking with
the 60-ppr encoder, and the box certificate against a two-axle braking whose load varies inside the box."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from switchobs.experiments import encoder_comparison, two_axle_box_check

DOC = Path(__file__).resolve().parents[1] / "docs" / "certify.md"


@pytest.fixture(scope="module")
def comparison():
    return encoder_comparison()


@pytest.fixture(scope="module")
def box_run():
    return two_axle_box_check()


def test_docs_evidence_block_is_a_fresh_run(comparison, box_run):
    quoted = re.search(r"<!-- synthesis-evidence:start -->\n(.*?)\n<!-- synthesis-evidence:end -->",
                       DOC.read_text(encoding="utf-8"), re.S)
    assert quoted, "docs/certify.md lost its synthesis-evidence markers"
    assert quoted.group(1) == comparison.table() + "\n\n" + box_run.text(), \
        "docs/certify.md differs from a fresh run: paste switchobs.report.synthesis_evidence()"


def test_what_the_docs_say_about_the_comparison_holds(comparison):
    beta, lmi = comparison.labels
    segments = [s for s in comparison.settled[beta] if s != "whole run"]
    assert len(segments) == 3
    # "the beta design wins": lower settled error on every road, a noise floor about a third
    assert all(comparison.settled[beta][s] < comparison.settled[lmi][s] for s in segments)
    assert comparison.floor[beta] < 0.5 * comparison.floor[lmi]
    # "re-converges slightly better after the road changes"
    assert comparison.transient[lmi] < comparison.transient[beta]
    # "with the exact x2 both are an order of magnitude better"
    for label in comparison.labels:
        assert comparison.exact[label] < 0.1 * comparison.settled[label]["whole run"]


def test_two_axle_load_stays_in_the_certified_box_and_the_error_converges(box_run):
    lo, hi = box_run.a_range
    assert box_run.inside and 250 <= lo < box_run.a_static + 1e-6 and hi <= 450
    assert hi - lo > 100                      # the load really moves: tens of percent of a
    assert box_run.tau_D is not None and box_run.dwell_min >= box_run.tau_D
    assert box_run.error_end < 1e-6 * box_run.error_start
