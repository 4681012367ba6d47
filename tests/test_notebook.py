"""Notebook representations and JSON round trips of the result classes (issue 16, item 2)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
import sympy as sp

from switchobs.certify import (DualCertificate, DwellTimeResult, LyapunovResult, PlanarClassification,
                              VerificationReport, certify, classify_planar, dwell_time, strict_common_lyapunov)
from switchobs.design import GainDesign, design_gains
from switchobs.exceptions import CertificateError, ModelError, SimulationError
from switchobs.model import Model, builtin_model
from switchobs.plants import (BrakingResult, BrakingScenario, PrescribedSpeed, RoadChange, RoadSchedule, TwoAxleScenario,
                              Table41Result, TwoAxleResult, TwoPhaseABS, simulate, simulate_two_axle, table41)
from switchobs.sensors import ChainResult, ChainSettings, Encoder, compare_estimators, constant_speed


def _through_json(x, **kw):
    """``x.to_json()`` as a JSON file would give it back."""
    return json.loads(json.dumps(x.to_json(**kw)))


@pytest.mark.parametrize("name", ["abs-xbs3", "abs-xbs4", "abs-adaptive2"])
def test_model_json_round_trip_and_markdown(name):
    m = builtin_model(name)
    assert Model.from_json(_through_json(m)) == m
    md = m._repr_markdown_()
    assert f"**Model `{name}`**" in md and sp.latex(m.A) in md and "$$" in md
    assert repr(m).startswith(f"<Model {name!r}: n={m.n}") and "\n" not in repr(m)


def test_design_json_round_trip_recomputes_and_refuses_a_tampered_file():
    for d in (design_gains(builtin_model("abs-xbs3"), "-beta1,-beta2,-beta2"),
              design_gains(builtin_model("abs-xbs3").numeric(), K_plus="84,-7312/375,-64/3",
                           K_minus="-16,-512/375,64/3")):
        assert GainDesign.from_json(_through_json(d)) == d
    data = _through_json(d)
    data["P"][0][0] = "1"
    with pytest.raises(ModelError, match="stored P"):
        GainDesign.from_json(data)
    with pytest.raises(ModelError, match="model_definition"):
        GainDesign.from_json({k: v for k, v in data.items() if k != "model_definition"})


def test_design_repr_is_short_and_markdown_has_the_latex_matrices():
    d = design_gains(builtin_model("abs-xbs3"), "-beta1,-beta2,-beta2")
    assert repr(d) == "<GainDesign for model 'abs-xbs3': n=3, theorem1, spectrum [-beta1, -beta2, -beta2]>"
    md = d._repr_markdown_()
    assert sp.latex(d.P) in md and sp.latex(d.A_plus) in md and r"\beta_{1}" in md
    big = design_gains(Model.from_dict({"name": "chain6", "states": [f"z{i}" for i in range(1, 7)],
                                        "A": np.diag(np.ones(5), 1), "C": np.eye(6)[0], "time_scale": "y"}),
                       -np.arange(1, 7))
    assert len(repr(big)) < 100 and "P =" not in big._repr_markdown_()


def test_certification_report_markdown_repr_numpy_and_json_parts():
    rep = certify([[[-1, -1], [1, 0]], [[-1, 1], [-1, 0]]], output=[[1, 0]], dwell=False)
    md = rep._repr_markdown_()
    assert "| Hespanha non-strict P | certified |" in md and f"**verdict**: {rep.text}" in md
    assert "\n" not in repr(rep) and "certified=True" in repr(rep)
    arrays = rep.to_numpy()
    assert set(arrays) == {"A_1", "A_2", "P"} and arrays["P"].shape == (2, 2)
    for M in (arrays["A_1"], arrays["A_2"]):  # the certified P: A' P + P A <= 0
        assert np.linalg.eigvalsh(M.T @ arrays["P"] + arrays["P"] @ M).max() <= 1e-9
    assert VerificationReport.from_json(_through_json(rep.verification)) == rep.verification
    planar = classify_planar([["-0.1", -1], [2, "-0.1"]], [["-0.1", -2], [1, "-0.1"]])
    assert PlanarClassification.from_json(_through_json(planar)) == planar
    with pytest.raises(CertificateError, match="planar"):
        PlanarClassification.from_json({"case": "iv"})


def test_lyapunov_dual_and_dwell_results_round_trip_through_json():
    """A result read back from its JSON writes the same JSON, with the exact matrices and the solver record."""
    no_cqlf = strict_common_lyapunov([[[-1, 0], [10, -1]], [[-1, 10], [0, -1]]])
    assert not no_cqlf.certified and no_cqlf.dual is not None and no_cqlf.dual.certified
    back = LyapunovResult.from_json(_through_json(no_cqlf))
    assert back.to_json() == no_cqlf.to_json()
    assert (back.family.names, back.family.exact, back.solver, back.dual) == (
        no_cqlf.family.names, no_cqlf.family.exact, no_cqlf.solver, no_cqlf.dual)
    assert DualCertificate.from_json(_through_json(no_cqlf.dual)) == no_cqlf.dual
    dwell = dwell_time([[[-1, 0], [10, -1]], [[-1, 10], [0, -1]]])
    again = DwellTimeResult.from_json(_through_json(dwell))
    assert again.to_json() == dwell.to_json() and (again.tau_D, again.P) == (dwell.tau_D, dwell.P)
    with pytest.raises(CertificateError, match="dwell-time result"):
        DwellTimeResult.from_json({k: v for k, v in dwell.to_json().items() if k != "family"})

def test_simulation_results_markdown_numpy_and_json_round_trip():
    res = simulate(BrakingScenario("dry-asphalt", speed_m_s=15.0, duration_s=0.2))
    md = res._repr_markdown_()
    assert f"status: **{res.status}**" in md and "| `initial_speed_m_s` | 15 |" in md
    assert "\n" not in repr(res) and len(repr(res)) < 150
    table = res.to_numpy()
    np.testing.assert_array_equal(table["vx"], res.series["vx"])
    back = BrakingResult.from_json(_through_json(res, include_series=True))
    assert back.to_json(include_series=True) == res.to_json(include_series=True)
    assert (back.scenario, back.metrics, back.events, back.steps) == (res.scenario, res.metrics, res.events, res.steps)
    for name, arr in res.series.items():
        np.testing.assert_array_equal(back.series[name], arr)
    with pytest.raises(SimulationError, match="include_series"):
        BrakingResult.from_json(res.to_json())
    with pytest.raises(SimulationError, match="controller named"):
        BrakingScenario.from_json({**res.scenario.to_json(), "controller": {"name": "bang-bang"}})
    two = replace(res.scenario, controller=TwoPhaseABS(), speed_profile=PrescribedSpeed(),
                  roads=RoadSchedule("dry-asphalt", [RoadChange("wet-asphalt", at_time_s=0.1)]))
    assert BrakingScenario.from_json(json.loads(json.dumps(two.to_json()))) == two
    comparison = compare_estimators(constant_speed(1020.0, 0.5), Encoder(ppr=60, seed=1),
                                    settings=ChainSettings(warmup_s=0.1), estimators=("tsa",))
    chain = comparison.results[0]
    back = ChainResult.from_json(_through_json(chain, arrays=True))
    for field in ("t", "omega", "alpha", "omega_true", "alpha_true"):
        np.testing.assert_array_equal(getattr(back, field), getattr(chain, field))
    assert back.summary() == chain.summary() and back.settings == chain.settings
    with pytest.raises(SimulationError, match="arrays"):
        ChainResult.from_json(chain.to_json())


def test_table41_and_two_axle_markdown_show_the_numbers_of_their_text():
    table = table41(roads=("dry-asphalt",), speeds_kmh=(60.0,))
    row = table.rows[0]
    md = table._repr_markdown_()
    assert r"$v_x(0)^2 / (2 g \bar\mu)$" in md
    assert f"| 60 | dry-asphalt | {row.five_phase_m:.2f} ({row.seed_five_phase_m:.2f}) |" in md
    assert f"**{table.two_phase_always_shorter}**" in md
    assert Table41Result.from_json(json.loads(json.dumps(table.to_json()))) == table
    with pytest.raises(SimulationError, match="Table 4.1 row"):
        Table41Result.from_json({**table.to_json(), "rows": [{"road": "dry-asphalt"}]})
    run = simulate_two_axle(TwoAxleScenario("dry-asphalt", speed_m_s=10.0, duration_s=0.5))
    back = TwoAxleResult.from_json(json.loads(json.dumps(run.to_json(include_series=True))))
    assert back.to_json(include_series=True) == run.to_json(include_series=True)
    assert (back.scenario, back.metrics, back.events) == (run.scenario, run.metrics, run.events)
    for name, arr in run.series.items():
        np.testing.assert_array_equal(back.series[name], arr)
    with pytest.raises(SimulationError, match="front"):
        TwoAxleScenario.from_json({**run.scenario.to_json(), "front": None})
    md = run._repr_markdown_()
    m = run.metrics
    assert run.status == "duration"  # 0.5 s from 36 km/h: the run did not stop, so no "stopping distance"
    for r, words in ((run, "distance travelled"), (replace(run, status="stopped"), "stopping distance")):
        line = f"{words} {m['stopping_distance_m']:.2f} m"
        assert f"status: **{r.status}**; {line}" in r._repr_markdown_() and f"status: {r.status}; {line}" in str(r)
    assert f"| front | {m['front']['load_min_n']:.0f}–{m['front']['load_max_n']:.0f} | {m['front']['abs_cycles']} |" in md
    assert "$(\\hat v_x - v_x)/v_x$" in md
