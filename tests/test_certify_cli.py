"""certify / verify / classify commands and certificate tampering (issue 3, items 5, 7 and 8)."""

import copy
import json
from fractions import Fraction

import pytest
from _docs_blocks import assert_page_says

from switchobs.certify import certify_model, verify_certificate
from switchobs.cli.main import main
from switchobs.exceptions import CertificateError
from switchobs.model import builtin_model


@pytest.fixture(scope="module")
def xbs3_report():
    """abs-xbs3 on the TU Delft rig (a = 187.5, c = 34, seed 000 Fig. 2), beta1 = 10, beta2 = 20."""
    return certify_model(builtin_model("abs-xbs3"), spectrum="-10,-20,-20", dwell=True)


def test_hoang2014_xbs3_certificate_verdict(xbs3_report):
    rep = xbs3_report
    assert rep.certified and rep.verification.holds
    assert rep.verdict.to_json() == {"arbitrary_switching": "UGS", "dwell_time": "any", "strict_cqlf": "none",
                                     "common_lyapunov": "exists"}
    kinds = [c["kind"] for c in rep.document["certificates"]]
    assert kinds == ["hespanha", "singular-sum", "dwell-time"]
    assert rep.document["observer"]["K_plus"] == ["84", "-7312/375", "-64/3"]   # seed 000 Sec. III-E
    assert rep.document["observer"]["K_minus"] == ["-16", "-512/375", "64/3"]
    # the first row of the full runs in docs/certify.md is this run
    assert_page_says("certify.md", f"| abs-xbs3 | 10, 20 | certified (design P) | - | none (singular sum) | "
                                   f"{float(rep.dwell.tau_D):.4g} | any | holds |")


def _tampered(doc, edit):
    d = copy.deepcopy(doc)
    edit(d)
    return verify_certificate(d)


def _cert(d, kind):
    return next(c for c in d["certificates"] if c["kind"] == kind)


def test_interval_arithmetic_verifies_and_rejects_like_the_exact_check(xbs3_report, tmp_path, capsys):
    assert xbs3_report.document["provenance"]["arithmetic"] == "exact"
    rep = verify_certificate(xbs3_report.document, arithmetic="interval")
    assert rep.holds and rep.arithmetic == "interval" and "interval arithmetic" in str(rep)
    bad = copy.deepcopy(xbs3_report.document)
    _cert(bad, "hespanha")["P"][0][0] = "-1"
    rep = verify_certificate(bad, arithmetic="interval")
    assert not rep.holds and "P > 0 fails" in next(c.detail for c in rep.checks if c.name == "hespanha")
    path = tmp_path / "cert.json"
    xbs3_report.write(path)
    assert main(["verify", str(path), "--arithmetic", "interval"]) == 0
    assert "\ncertificate holds (interval arithmetic" in capsys.readouterr().out


def test_dwell_time_runs_by_default_only_where_it_can_change_the_verdict():
    xbs3 = certify_model(builtin_model("abs-xbs3"), spectrum="-10,-20,-20")      # Hespanha: every dwell time
    assert xbs3.dwell is None and xbs3.verdict.dwell_time == "any"
    off = certify_model(builtin_model("abs-adaptive2"), K_plus="8,-2/25", K_minus="-3,-1/25")   # no common P
    assert not off.hespanha.certified and off.dwell is not None and off.dwell.certified
    # without a common P the LMI dual is tried too: it excludes every common P, more than the singular sum
    assert off.strict.dual.kind == "no-common-lyapunov" and off.verdict.common_lyapunov == "none"
    with pytest.raises(CertificateError, match="dwell must be 'auto', True or False"):
        certify_model(builtin_model("abs-xbs3"), spectrum="-10,-20,-20", dwell="always")


def test_tampered_P_breaks_the_named_inequality(xbs3_report):
    def edit(d):
        _cert(d, "hespanha")["P"][2][2] = "1/100"

    rep = _tampered(xbs3_report.document, edit)
    assert not rep.holds
    bad = {c.name: c.detail for c in rep.checks if not c.holds}
    assert bad["hespanha"].startswith("A_plus' P + P A_plus + C_plus' C_plus <= 0 fails")
    assert "verdict" in bad  # the verdict no longer follows from what holds


def test_tampered_output_breaks_observability(xbs3_report):
    def edit(d):
        c = _cert(d, "hespanha")
        c["C"] = [[["0", "0", "0"]], [["0", "0", "0"]]]

    rep = _tampered(xbs3_report.document, edit)
    detail = next(c.detail for c in rep.checks if c.name == "hespanha")
    assert not rep.holds and detail == "(A_plus, C_plus) is not observable: the observable subspace has dimension 0 < 3"


def test_tampered_family_or_gain_is_caught(xbs3_report):
    def edit_family(d):
        d["family"]["matrices"][1][0][0] = "-17"

    def edit_gain(d):
        d["observer"]["K_minus"][0] = "-17"

    rep = _tampered(xbs3_report.document, edit_family)
    bad = {c.name: c.detail for c in rep.checks if not c.holds}
    assert "A_minus in the family differs from -A + K_minus C" in bad["observer"]
    assert not _tampered(xbs3_report.document, edit_gain).holds


def test_tampered_dual_and_dwell_time_and_verdict(xbs3_report):
    def edit_dual(d):
        _cert(d, "singular-sum")["v"] = ["1", "0", "0"]   # (A_plus + A_minus) e1 = K_minus - K_plus != 0

    def edit_dwell(d):
        c = _cert(d, "dwell-time")
        c["tau_D"] = str(Fraction(c["tau_D"]) / 10)

    def edit_verdict(d):
        d["verdict"]["arbitrary_switching"] = "UGES"

    r = _tampered(xbs3_report.document, edit_dual)
    assert not r.holds and "entry 1 is nonzero" in next(c.detail for c in r.checks if c.name == "singular-sum")
    r = _tampered(xbs3_report.document, edit_dwell)
    assert not r.holds and "tau_D" in next(c.detail for c in r.checks if c.name == "dwell-time")
    r = _tampered(xbs3_report.document, edit_verdict)
    assert not r.holds and [c.name for c in r.checks if not c.holds] == ["verdict"]


@pytest.mark.parametrize("edit, match", [
    (lambda d: d.update(format="other"), "not a switchobs certificate"),
    (lambda d: d["certificates"].append({"kind": "magic"}), "unknown certificate kind 'magic'"),
    (lambda d: d["family"]["matrices"][0][0].__setitem__(0, "nan"), "not a finite number"),
    (lambda d: d["family"]["matrices"][0].pop(), "A_plus is not square"),
])
def test_malformed_certificates_raise(xbs3_report, edit, match):
    d = copy.deepcopy(xbs3_report.document)
    edit(d)
    with pytest.raises(CertificateError, match=match):
        verify_certificate(d)


def test_cli_certify_writes_a_certificate_verify_accepts(tmp_path, capsys):
    out = tmp_path / "cert.json"
    rc = main(["certify", "abs-xbs3", "--param", "a=187.5", "--param", "c=34", "--spectrum=-40,-60,-60",
               "--no-dwell", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0 and "Hespanha non-strict P" in text and "verdict: uniformly exponentially stable" in text
    assert main(["verify", str(out)]) == 0
    assert "certificate holds exactly" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    _cert(doc, "hespanha")["P"][0][0] = "-1"
    out.write_text(json.dumps(doc))
    assert main(["verify", str(out)]) == 1
    assert "hespanha: FAILS - P > 0 fails" in capsys.readouterr().out


def test_cli_certify_toml_model_with_non_theorem1_gains(tmp_path, capsys):
    """seed 001 eq. (3.16) with K_minus off Proposition 1's choice: BBM case (i), dwell time only."""
    toml = tmp_path / "planar.toml"
    toml.write_text('name = "planar"\nstates = ["w1", "w2"]\nA = [["0", "-a"], ["0", "0"]]\nC = ["1", "0"]\n'
                    'time_scale = "y/vx"\nparameters = ["a"]\nexternal = ["vx"]\npositive = ["a", "vx"]\n'
                    '[values]\na = "375/2"\n')
    out = tmp_path / "c.json"
    rc = main(["certify", str(toml), "--gains-plus", "8,-2/25", "--gains-minus", "-3,-1/25", "--json",
               "--out", str(out)])
    data = json.loads(capsys.readouterr().out)
    assert rc == 0 and data["hespanha"]["certified"] is False
    assert data["dwell_time"]["certified"] and data["planar"]["case"] == "i"
    assert data["verdict"]["arbitrary_switching"] == "unbounded"
    assert data["verdict"]["common_lyapunov"] == "none"
    assert data["verdict"]["dwell_time"] == data["dwell_time"]["tau_D"]
    assert main(["verify", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["holds"] is True


def test_cli_certify_bad_input_one_line(capsys):
    rc = main(["certify", "abs-xbs3", "--gains-plus", "84,-7312/375,-64/3", "--gains-minus", "1,1,1"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    assert err.startswith("switchobs certify: error: A_minus is not Hurwitz: its spectrum is [")
    assert main(["certify", "abs-xbs3"]) == 2
    assert "give either a spectrum" in capsys.readouterr().err
    assert main(["certify", "abs-xbs3", "--spectrum=-beta1,-2,-3"]) == 2
    err = capsys.readouterr().err
    assert "beta1" in err and err.count("--param NAME=VALUE") == 1    # the CLI adds its hint once
    assert main(["certify", "abs-xbs3", "--param", "a=nan", "--spectrum=-1,-2,-3"]) == 2
    assert "not a finite number" in capsys.readouterr().err


def test_cli_verify_malformed_file(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["verify", str(bad)]) == 2
    assert "is not valid JSON" in capsys.readouterr().err
    assert main(["verify", str(tmp_path / "missing.json")]) == 2


@pytest.mark.parametrize("A1, A2, case", [
    ("[[-1,-100],[10,-1]]", "[[-1,10],[-100,-1]]", "i"),
    ("[[-8,-187.5],[0.08,0]]", "[[-8,187.5],[-0.08,0]]", "ii"),
    ("[[-1,2],[-3,-4]]", "[[-0.1,-2],[1,-0.1]]", "iii"),
    ("[[-0.1,-1],[2,-0.1]]", "[[-0.1,-2],[1,-0.1]]", "iv"),
])
def test_cli_classify_json(A1, A2, case, capsys):
    assert main(["classify", A1, A2, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["case"] == case and isinstance(data["verdict"], str) and data["verdict"]


def test_cli_classify_bad_matrices(capsys):
    assert main(["classify", "[[1,2],[3]]", "[[-1,0],[0,-1]]"]) == 2
    assert "not rectangular" in capsys.readouterr().err
    assert main(["classify", "[[-1,0],[0,-1]]", "[[1,0],[0,1]]"]) == 2
    assert "A2 is not Hurwitz" in capsys.readouterr().err
    assert main(["classify", "[[-1,0],[0,-1]]", "oops"]) == 2
    assert "is not a list of rows" in capsys.readouterr().err


def test_schema_round_trip_keeps_the_json_and_types_the_verdict(xbs3_report):
    """One schema for producers and checker: reading and writing a certificate gives the same JSON."""
    from switchobs.certify import (ArbitrarySwitching, CertificateDocument, CertificateKind, Existence,
                                   ObserverSection)

    doc = CertificateDocument.from_json(xbs3_report.document)
    assert json.dumps(doc.to_json()) == json.dumps(xbs3_report.document)
    assert [c.kind for c in doc.certificates] == [CertificateKind.HESPANHA, CertificateKind.SINGULAR_SUM,
                                                  CertificateKind.DWELL_TIME]
    assert doc.verdict == xbs3_report.verdict
    assert xbs3_report.verdict.arbitrary_switching is ArbitrarySwitching.UGS
    assert xbs3_report.verdict.strict_cqlf == "none" and xbs3_report.verdict.strict_cqlf is Existence.NONE
    assert isinstance(doc.sections["observer"], ObserverSection)


def test_a_new_optional_section_is_one_class(xbs3_report, monkeypatch):
    """A later section (e.g. the sampled observer's `discrete` data) plugs into writing, reading and checking."""
    import dataclasses
    from typing import ClassVar

    from switchobs.certify import CertificateDocument, Check
    from switchobs.certify import _schema

    @dataclasses.dataclass(frozen=True)
    class Discrete:
        KEY: ClassVar[str] = "discrete"
        h_max: str

        def to_json(self):
            return {"h_max": self.h_max}

        @classmethod
        def from_json(cls, data):
            return cls(data["h_max"])

        def check(self, names, matrices):
            return Check("discrete", self.h_max == "1/100", f"h_max = {self.h_max}")

    monkeypatch.setattr(_schema, "SECTIONS", dict(_schema.SECTIONS))
    _schema.document_section(Discrete)
    doc = dict(xbs3_report.document, discrete={"h_max": "1/100"})
    back = CertificateDocument.from_json(doc)
    assert back.sections["discrete"] == Discrete("1/100")
    assert list(back.to_json()) == ["format", "version", "family", "observer", "discrete", "certificates",
                                    "verdict", "provenance"]
    assert verify_certificate(doc).holds
    bad = verify_certificate(dict(doc, discrete={"h_max": "1"}))
    assert not bad.holds and [c.name for c in bad.checks if not c.holds] == ["discrete"]


def test_a_verdict_outside_the_schema_is_malformed(xbs3_report):
    d = copy.deepcopy(xbs3_report.document)
    d["verdict"]["strict_cqlf"] = "maybe"
    with pytest.raises(CertificateError, match="verdict strict_cqlf is 'maybe'"):
        verify_certificate(d)
