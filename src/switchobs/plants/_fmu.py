"""The quarter car with its ABS controller as an FMI 3.0 co-simulation FMU (the plant for a loop with the observer's).

The FMU is the compiled braking loop of :func:`switchobs.plants.simulate` (``_closed_loop.c``, the same
integrator, road schedule and controller runtimes) behind the FMI 3.0 co-simulation interface
(``_plant_fmu.c``).  Its input is ``xbs_hat``, the XBS estimate that the controller reads where the scenario's
controller needs one (the two-phase ABS, the five-phase ABS with tracking); its outputs are the state
(``omega``, ``vx``, ``x``, ``P_b``), the measured ``x2`` (the observer's ``y``), ``u_mean`` (the mean brake
pressure rate over the last communication step, the observer's ``u``), ``dt`` (that step's length), ``lam``, ``mu``, the true ``xbs`` and
the controller's ``phase``; its fixed parameters are the loop's parameter vector (vehicle, actuator, the
controller's thresholds, the step ``DT``...), their start values the scenario's.  The road schedule is
compiled in.

A ``doStep(t, h)`` makes the loop's integrator steps up to ``t + h``: with ``h = DT`` above the low speed and
without a located event in the step, one step, the step of the run.  A step that ends early (a located event, a
road breakpoint, the shorter steps below the low speed) ends the ``doStep`` there when the master allowed an
early return (FMI 3.0 ``earlyReturnAllowed``), and ``dt`` is then the step's exact length: a master that steps
its observer by ``dt`` and starts the next step at ``lastSuccessfulTime`` makes the steps of the run, bit for
bit (``examples/fmu_closed_loop.py``).  The transitions after a step read the
estimate of that step, so the FMU makes those of the last step at the start of the next ``doStep``, after the
master has set ``xbs_hat`` (the order of the run: step, estimator, transitions).
"""

from __future__ import annotations

import os
from importlib import resources
from string import Template

from typing import TYPE_CHECKING

from ..exceptions import SimulationError
from ._compiled import _CH, _P, _defines, _parameters, compiled_support
from ._simulate import SERIES, BrakingScenario, _QuarterCar

if TYPE_CHECKING:
    from ..codegen import GeneratedFMU

__all__ = ["PLANT_OUTPUTS", "generate_plant_fmu"]

#: The plant FMU's Float64 outputs in value-reference order (name, description); then the Int32 ``phase``.
PLANT_OUTPUTS = (("omega", "wheel angular speed [rad/s]"), ("vx", "vehicle speed [m/s]"),
                 ("x", "distance travelled [m]"), ("P_b", "brake pressure [bar]"),
                 ("x2", "the wheel slip acceleration R domega/dt - ax, the observer's measured y [m/s^2]"),
                 ("u_mean", "mean brake pressure rate over the last communication step, the observer's u [bar/s]"),
                 ("dt", "the length of the last communication step: the sum of its integrator steps [s]"),
                 ("lam", "wheel slip"), ("mu", "tyre-road friction coefficient"),
                 ("xbs", "the true extended braking stiffness"))

_TEMPLATE = "_plant_fmu.c"
_LOG = (("logStatusError", "a call the FMU cannot serve, a cascade of phase changes"),)


def generate_plant_fmu(scenario: BrakingScenario, *, observer_in_loop: bool = True,
                       compiler: str | None = None, cache_dir: str | os.PathLike | None = None) -> GeneratedFMU:
    """The quarter car of ``scenario`` with its ABS controller as an FMI 3.0 co-simulation FMU.

    Parameters
    ----------
    scenario : BrakingScenario
        A braking the compiled loop runs (five- or two-phase ABS, no actuator delay).
    observer_in_loop : bool
        As :func:`simulate`: a controller that needs an XBS reads the input ``xbs_hat`` (default); otherwise
        the true XBS, and ``xbs_hat`` is unused.
    compiler, cache_dir
        As :func:`switchobs.codegen.compile_sources`.

    Returns
    -------
    GeneratedFMU
        Model identifier ``switchobs_quarter_car``; ``value_references`` names ``xbs_hat``, the parameters
        (the names of the loop's parameter vector: ``DT``, ``V0``, ``T_END``...), the outputs and ``phase``.

    Raises
    ------
    SimulationError
        A scenario the compiled loop does not run (its reason).
    CodegenError, PrerequisiteError
        As :func:`switchobs.codegen.generate_fmu`.

    Examples
    --------
    >>> from switchobs.plants import scenario
    >>> fmu = generate_plant_fmu(scenario("hoang-fig4"))
    >>> fmu.file_name, fmu.value_references["xbs_hat"], fmu.value_references["phase"] - fmu.value_references["x2"]
    ('switchobs_quarter_car.fmu', 1, 6)
    """
    # codegen needs casadi, which a base install lacks (as the compiled loop, _compiled.py)
    from ..codegen import FMUVariable, build_fmu, fmi3_common, fmi_headers, fmu_token

    if not isinstance(scenario, BrakingScenario):
        raise SimulationError(f"the plant FMU needs a BrakingScenario, got {type(scenario).__name__}")
    plant = _QuarterCar(scenario, None, observer_in_loop)
    # the estimator is the master's: the controller reads the input where simulate() reads an estimate
    plant.use_hat = bool(observer_in_loop and scenario.controller.uses_xbs)
    reason = compiled_support(plant, estimator=False)[1]
    if reason is not None:
        raise SimulationError(f"scenario {scenario.name!r} has no plant FMU: {reason}")
    params = _parameters(plant, None)
    params[_P.index("EST")] = 0.0
    identifier = "switchobs_quarter_car"
    changes = scenario.roads.changes
    roads = [v for c in changes for v in (1.0 if c.at_time_s is not None else 0.0,
                                            c.at_time_s if c.at_time_s is not None else c.at_position_m,
                                            c.duration_s, c.road.c1, c.road.c2, c.road.c3)]
    template = resources.files(__package__).joinpath(_TEMPLATE).read_text(encoding="utf-8")
    loop = resources.files(__package__).joinpath("_closed_loop.c").read_text(encoding="utf-8")
    source = _defines(None, len(SERIES), False) + loop
    shared = fmi3_common(template)
    token_texts = (source, template, shared, repr(params.tolist()), repr(roads))
    token = fmu_token(*token_texts)
    wrapper = Template(template).substitute(
        identifier=identifier, scenario=scenario.name, np=len(_P), no=len(PLANT_OUTPUTS), token=token,
        par_start=", ".join(repr(float(v)) for v in params),   # finite: repr is a C double literal
        roads=", ".join(repr(float(v)) for v in roads) or "0.0",
        n_roads_rows=max(len(roads), 1), n_roads=len(changes), fmi3_common=shared)
    # one translation unit: the loop's static functions, then the FMI functions
    variables = [FMUVariable("time", 0, "real", "independent", "continuous", description="simulation time"),
                 FMUVariable("xbs_hat", 1, "real", "input", "continuous", 0.0,
                             description="the XBS estimate the controller reads"
                             + ("" if plant.use_hat else " (unused: this controller reads the true XBS)"))]
    vr = 2
    for name, value in zip(_P, params):
        variables.append(FMUVariable(name, vr, "real", "parameter", "fixed", float(value), "exact",
                                     "parameter of the braking loop"))
        vr += 1
    for name, what in PLANT_OUTPUTS:
        variables.append(FMUVariable(name, vr, "real", "output", "discrete", initial="calculated",
                                     description=what))
        vr += 1
    variables.append(FMUVariable("phase", vr, "int", "output", "discrete", initial="calculated",
                                 description="the ABS controller's phase"))
    readme = (f"# {identifier}\n\nThe quarter car of scenario {scenario.name!r} with its "
              f"{type(scenario.controller).__name__} ABS, generated by switchobs (switchobs.plants."
              "generate_plant_fmu): the braking loop of switchobs simulate as an FMI 3.0 co-simulation FMU.\n"
              f"Road changes compiled in: {len(changes)} ({len(_CH)} values each).\n")
    return build_fmu(identifier, f"quarter car with ABS, scenario {scenario.name!r}", variables,
                     {f"{identifier}.c": source, **fmi_headers(3)}, f'#include "{identifier}.c"\n' + wrapper,
                     fmi_version=3, compiled=(), token=token, step_size=scenario.dt_s, log=_LOG, readme=readme,
                     compiler=compiler, cache_dir=cache_dir)
