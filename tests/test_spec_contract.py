"""One observer contract (switchobs.spec) for the Python reference and the generated C; pickling of both."""

import pickle

import numpy as np
import pytest
import sympy as sp

from switchobs import codegen, observers, spec
from switchobs.codegen import CObserver, compile_observer, generate_observer
from switchobs.exceptions import ModelError
from switchobs.model import Model, builtin_model
from switchobs.observers import AdaptiveSwitchedObserver, SwitchedObserver, adaptive_xbs_observer, xbs3_observer
from switchobs.spec import SCALE, ObserverSpec, StepStatus

PRODUCT = {
    "name": "product", "states": ["x1", "x2"], "A": [["0", "1"], ["0", "0"]], "C": ["1", "0"],
    "time_scale": "y", "d": ["q*r*y", "q*y"], "parameters": ["q", "r"], "values": {"q": "2", "r": "3"},
}


def test_one_status_enum_and_one_methods_tuple():
    assert codegen.StepStatus is observers.ErrorCode is StepStatus
    assert codegen.METHODS is observers.METHODS is spec.METHODS == ("rk4", "euler", "midpoint", "radau3")
    assert [s.name for s in StepStatus][-5:] == ["BAD_PARAM", "BAD_ARGUMENT", "SUBSTEP_LIMIT", "STATE_RANGE",
                                                "SIGNAL_RANGE"] and len(StepStatus) == 11


def test_seed001_eq33_affine_split_of_abs_adaptive2():
    """c + Psi theta = s d + b u, split once: Psi is the regressor of seed 001 eq. (3.3)."""
    m = builtin_model("abs-adaptive2")
    sp_ = ObserverSpec(m, (1.0, 2.0), (3.0, 4.0), values=dict(m.values), unknown=("c", "d"), Gamma=((1.0, 0.0),
                                                                                                     (0.0, 1.0)))
    theta = [m.symbols["c"], m.symbols["d"]]
    full = [SCALE * m.d[i] + sum((m.b[i, j] * m.symbols[u] for j, u in enumerate(m.inputs)), sp.Integer(0))
            for i in range(m.n)]
    for i in range(m.n):
        rebuilt = sp_.drift[i] + sum(q * t for q, t in zip(sp_.regressor[i], theta))
        assert sp.expand(rebuilt - full[i]) == 0
        assert not (sp_.drift[i].free_symbols & set(theta))
    assert sp_.state_names == ("w1", "w2", "c", "d", "Upsilon_w1_c", "Upsilon_w1_d", "Upsilon_w2_c", "Upsilon_w2_d")
    assert sp_.signal_names == ("y", "vx", "u") and sp_.signal_signs == (0, 1, 0)


def test_product_of_unknowns_is_refused_by_the_spec_for_python_and_c_alike():
    """A theta1 theta2 term used to pass codegen's test and fail later in to_casadi with a misleading message."""
    m = Model.from_dict(PRODUCT)
    with pytest.raises(ModelError, match=r"not linear in q and r \(term q\*r\*y of d\[1\]\)"):
        ObserverSpec(m, (1.0, 1.0), (1.0, 1.0), values={}, unknown=("q", "r"), Gamma=((1.0, 0.0), (0.0, 1.0)))
    with pytest.raises(ModelError, match=r"not linear in q and r \(term q\*r\*y of d\[1\]\)"):
        AdaptiveSwitchedObserver(m, [1.0, 1.0], [1.0, 1.0], unknown=("q", "r"), Gamma=[1.0, 1.0])
    with pytest.raises(ModelError, match=r"not linear in q and r \(term q\*r\*y of d\[1\]\)"):
        generate_observer(m, ([1.0, 1.0], [1.0, 1.0]), unknown=("q", "r"), Gamma=[1.0, 1.0])
    # one unknown at a time is linear: the other is a known parameter
    assert ObserverSpec(m, (1.0, 1.0), (1.0, 1.0), unknown=("q",), Gamma=((1.0,),)).regressor[0][0] != 0


def test_square_of_an_unknown_is_refused_naming_the_term():
    m = Model.from_dict({**PRODUCT, "d": ["q^2*y + r", "0"]})
    with pytest.raises(ModelError, match=r"not linear in q \(term q\*\*2\*y of d\[1\]\)"):
        ObserverSpec(m, (1.0, 1.0), (1.0, 1.0), unknown=("q", "r"), Gamma=((1.0, 0.0), (0.0, 1.0)))


def test_the_observers_run_their_spec():
    obs = xbs3_observer(10.0, 20.0)
    assert isinstance(obs.spec, ObserverSpec)
    assert obs.spec.K_plus == tuple(obs.K_plus.tolist()) and obs.spec.state_names == obs.state_names


ROWS = np.column_stack([np.linspace(-3.0, 5.0, 40), np.full(40, 20.0), np.linspace(0.0, 50.0, 40)])


@pytest.mark.parametrize("make", [lambda: xbs3_observer(10.0, 20.0, method="euler"),
                                  lambda: adaptive_xbs_observer(30.0, [5.0, 7.0])],
                         ids=["switched", "adaptive"])
def test_python_observers_pickle_and_step_identically(make):
    obs = make()
    back = pickle.loads(pickle.dumps(obs))
    assert type(back) is type(obs) and back.method == obs.method and back.spec == obs.spec
    x0 = np.zeros(obs.size)
    x0[1] = 0.5
    np.testing.assert_array_equal(back.step(x0, ROWS[3], 1e-3), obs.step(x0, ROWS[3], 1e-3))
    traj = obs.run(x0, ROWS, 1e-3)
    np.testing.assert_array_equal(back.run(x0, ROWS, 1e-3), traj)
    np.testing.assert_array_equal(back.readout(traj), obs.readout(traj))
    assert back.to_json() == obs.to_json()


def test_c_observer_pickles_and_steps_identically():
    ref = SwitchedObserver(builtin_model("abs-xbs3"), [84.0, -19.5, -21.3], [-44.0, -19.5, 21.3], readout="z2")
    c_obs = CObserver.like(ref).with_params({"c": 24.0})
    back = pickle.loads(pickle.dumps(c_obs))
    assert back.generated == c_obs.generated and back.params.tolist() == c_obs.params.tolist()
    x0 = np.array([0.0, 0.5, 0.0])
    np.testing.assert_array_equal(back.step(x0, ROWS[3], 1e-3), c_obs.step(x0, ROWS[3], 1e-3))
    traj = c_obs.run(x0, ROWS, 1e-3)
    np.testing.assert_array_equal(back.run(x0, ROWS, 1e-3), traj)
    np.testing.assert_array_equal(back.readout(traj), c_obs.readout(traj))
    unpicklable = compile_observer(c_obs.generated, readout=lambda x: x[..., 1])
    with pytest.raises((pickle.PicklingError, AttributeError)):
        pickle.dumps(unpicklable)
