"""Each certificate entry is checked once per ``certify``: the candidate check is the independent check."""

import collections

import pytest

import switchobs.certify._verify as verifier
from switchobs.certify import certify_model, verify_certificate
from switchobs.model import load_model


@pytest.fixture
def eliminations(monkeypatch):
    """Counts the verifier's definiteness decisions (every entry check is made of them)."""
    calls = collections.Counter()
    for name in ("definiteness", "_defin"):
        def wrap(*args, _decide=getattr(verifier, name), _name=name, **kwargs):
            calls[_name] += 1
            return _decide(*args, **kwargs)
        monkeypatch.setattr(verifier, name, wrap)
    return calls


@pytest.mark.parametrize("dwell", [False, True])
def test_certify_checks_every_entry_of_its_document_once(eliminations, dwell):
    report = certify_model(load_model("abs-xbs3"), spectrum="-10,-20,-20", dwell=dwell)
    kinds = [c["kind"] for c in report.document["certificates"]]
    assert report.verification.holds and "hespanha" in kinds and ("dwell-time" in kinds) == dwell
    during_certify = sum(eliminations.values())
    # the verifier alone, outside certify, decides every entry of the same document afresh
    eliminations.clear()
    assert verify_certificate(report.document).holds
    alone = sum(eliminations.values())
    assert alone > 0
    # certify decided its candidates with the verifier's checks and verified its document: the same count,
    # not twice it (the design's P, the dwell-time P_p and the exponential enclosures are eliminated once)
    assert during_certify == alone
