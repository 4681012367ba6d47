"""The target experiments of docs/codegen.md "On the target": the generated C built and run on the emulated
Cortex-M targets, and proved free of run-time errors by Frama-C EVA.

Sizes, worst-case stack and instructions per step are measured, not estimated: the observer of the
processor-in-the-loop tests is built with each target's flags (``switchobs.codegen.TARGETS``) and stepped
over the braking record of ``switchobs.loop.braking_record`` on ``qemu-system-arm`` and on the host
(:func:`target_runs`).  The proof runs EVA on the ranged build of each observer (:func:`proved_observer`, the
declared ranges below are ours).  :mod:`switchobs.report` renders both (``switchobs reproduce``).
"""

from __future__ import annotations

import collections
import shutil
import subprocess
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..loop import braking_record, compare_with_reference

if TYPE_CHECKING:
    from ..codegen import GeneratedObserver
    from ..model import Model

__all__ = ["XBS3_RANGES", "STATE_SIGNAL_RANGES", "PROOF_ROWS", "TARGET_ROWS", "division_model", "parameter_ranges",
           "proved_observer", "TargetRun", "target_runs", "proof_runs", "qemu_version"]

#: Declared ranges of abs-xbs3 (ours): wheel acceleration offset and XBS states, speed 1-70 m/s, 0.01-10 ms
#: steps, every parameter within about a factor 2 of its default (poles at -100).  docs/codegen.md shows them.
XBS3_RANGES = {"z1": (-200, 200), "z2": (-100, 100), "z3": (-1e5, 1e5), "y": (-200, 200), "vx": (1, 70),
               "u": (-1e4, 1e4), "dt": (1e-5, 1e-2), "a": (100, 300), "b": (-8, -2), "c": (17, 68),
               "K_plus_z1": (167, 668), "K_plus_z2": (-441, -110), "K_plus_z3": (-10667, -2666),
               "K_minus_z1": (-532, -133), "K_minus_z2": (-224, -55), "K_minus_z3": (2666, 10667)}

#: The states and signals of the other observers, ours: the XBS states and signals as for abs-xbs3; the
#: adaptive observer's (c, d) beyond what the braking record of the processor-in-the-loop tests reaches (|c|, |d|
#: < 112) and its sensitivities Upsilon within 1 (the record: < 0.71; within 10, EVA's intervals of the float
#: rk4 stages grow past FLT_MAX: 2 alarms, none in double); the super-twisting observer's wheel angle in rad,
#: speed in rad/s and injection, a known acceleration up to 1e4 rad/s^2; the vehicle-speed observer's speed in
#: m/s (up to 90, our quarter car starts at 36) and injection.  The parameters: within a factor 2 of
#: their defaults (:func:`parameter_ranges`).
STATE_SIGNAL_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    "abs-xbs4": {"z1": (-200, 200), "z2": (-100, 100), "z3": (-1e5, 1e5), "z4": (-1e5, 1e5), "y": (-200, 200),
                 "vx": (1, 70), "u": (-1e4, 1e4), "dt": (1e-5, 1e-2)},
    "abs-adaptive2": {"w1": (-200, 200), "w2": (-200, 200), "c": (-200, 200), "d": (-200, 200),
                      **{f"Upsilon_{w}_{p}": (-1, 1) for w in ("w1", "w2") for p in ("c", "d")},
                      "y": (-200, 200), "vx": (1, 70), "u": (-1e4, 1e4), "dt": (1e-5, 1e-2)},
    # d(y) = (0, k/y, log(y + 2)), b(y) = (b, 1/vx, 1/(y - 1) + y^(3/2)): the divisors y, vx and y - 1 are kept
    # from 0 by the declared ranges of y and vx (y > 1 is the range that makes the proof)
    "user": {"z1": (-200, 200), "z2": (-1e3, 1e3), "z3": (-1e5, 1e5), "y": (1.5, 200), "vx": (1, 70),
             "u": (-1e4, 1e4), "dt": (1e-5, 1e-2)},
    "super-twisting": {"x1_hat": (-1e5, 1e5), "x2_hat": (-1e3, 1e3), "z2": (-1e5, 1e5), "x1": (-1e5, 1e5),
                       "f1": (-1e4, 1e4), "dt": (1e-5, 1e-2)},
    "vehicle-speed": {"x3_hat": (-10, 100), "z3": (-100, 100), "x3": (0, 90), "dt": (1e-5, 1e-2)},
}

#: (observer, method, real, h_max) of the proof table: the observers of the table above, the adaptive and the
#: super-twisting observers, the user model that divides by signals.
PROOF_ROWS = (("abs-xbs3", "radau3", "float", None), ("abs-xbs3", "radau3", "double", None),
              ("abs-xbs4", "radau3", "float", None), ("abs-xbs4", "radau3", "double", None),
              ("abs-adaptive2", "rk4", "float", None), ("user", "radau3", "double", None),
              ("super-twisting", "euler", "float", None), ("vehicle-speed", "euler", "float", None))


def parameter_ranges(gen: GeneratedObserver) -> dict[str, tuple[float, float]]:
    """Every parameter within a factor 2 of its default (a zero default: within +-1)."""
    return {n: (-1.0, 1.0) if v == 0 else (min(v / 2, 2 * v), max(v / 2, 2 * v))
            for n, v in zip(gen.param_names, gen.default_params)}


def division_model() -> Model:
    """A user model whose d(y) and b(y) divide by the signals y and vx and by y - 1 (ours: the wheel model of
    examples/my_model.toml with d = (0, k/y, log(y + 2)), b = (b, 1/vx, 1/(y - 1) + y^(3/2)))."""
    from ..model import Model

    return Model.from_dict({
        "name": "my-wheel-div", "description": "3D XBS-like wheel model whose d(y) and b(y) divide by signals",
        "states": ["z1", "z2", "z3"], "output": "y", "A": [["0", "-a", "0"], ["0", "c", "1"], ["0", "0", "0"]],
        "C": ["1", "0", "0"], "d": ["0", "k/y", "log(y + 2)"], "b": ["b", "1/vx", "1/(y - 1) + y^(3/2)"],
        "time_scale": "y/vx", "parameters": ["a", "b", "c", "k"], "external": ["vx"], "inputs": ["u"],
        "positive": ["a", "vx"], "negative": ["b"],
        "values": {"a": "187.5", "b": "-4.375", "c": "24", "k": "0.01"}})


def proved_observer(name: str, method: str, real: str, h_max: str | None = None,
                    ranges: dict[str, tuple[float, float]] | None = None) -> GeneratedObserver:
    """The observer ``name`` generated with a declared range of every input (``ranges`` on top of ours).

    ``name``: abs-xbs3 (poles at -100, :data:`XBS3_RANGES`), abs-xbs4 (-10, -10, -20, -20), abs-adaptive2
    (-15, -15, ``Gamma = diag(50, 20)``), ``user`` (:func:`division_model`, gains (1, 2, 3), (-1, 2, 3)) or
    ``super-twisting`` (``lam = 400``, ``alpha = 2000``) or ``vehicle-speed`` (``beta = 26.4``, twice the
    eta = 13.2 m/s^2 of M'Sirdi et al. 2008 Theorem 3 on our quarter car).
    """
    from ..codegen import generate_observer, generate_super_twisting, generate_vehicle_speed
    from ..design import design
    from ..model import builtin_model

    def make(rng: dict[str, tuple[float, float]]) -> GeneratedObserver:
        options: dict = {"real": real, "ranges": rng}
        if name == "super-twisting":
            return generate_super_twisting(400.0, 2000.0, **options)
        if name == "vehicle-speed":
            return generate_vehicle_speed(26.4, **options)
        options.update(method=method, h_max=h_max)
        if name == "user":
            return generate_observer(division_model(), ([1.0, 2.0, 3.0], [-1.0, 2.0, 3.0]), **options)
        m = builtin_model(name)
        if name == "abs-adaptive2":
            return generate_observer(m, design(m, "-15,-15"), unknown=["c", "d"], Gamma=[50.0, 20.0], **options)
        return generate_observer(m, design(m, "-100,-100,-100" if name == "abs-xbs3" else "-10,-10,-20,-20"),
                                 **options)

    if name == "abs-xbs3":
        return make({**XBS3_RANGES, **(ranges or {})})
    base = {**STATE_SIGNAL_RANGES[name], **(ranges or {})}
    return make({**parameter_ranges(make(base)), **base})

#: (model, method, beta1, beta2, real, target) of the rows: the observers of tests/test_codegen_target.py.
TARGET_ROWS = (("abs-xbs3", "radau3", 100.0, 100.0, "float", "cortex-m4f"),
        ("abs-xbs3", "radau3", 100.0, 100.0, "double", "cortex-m7"),
        ("abs-xbs4", "radau3", 10.0, 20.0, "float", "cortex-m4f"),
        ("abs-xbs4", "radau3", 10.0, 20.0, "double", "cortex-m7"))


@dataclass(frozen=True)
class TargetRun:
    """One row of :data:`TARGET_ROWS` built and run on its target: the footprint (``TargetFootprint``), the
    processor-in-the-loop result (``PilResult``), its comparison with the Python reference, the record's
    description and the MISRA findings by category (cppcheck's misra addon on the generated files)."""

    model: str
    method: str
    real: str
    target: str
    footprint: Any
    pil: Any
    reference: Any
    record: str
    misra: dict[str, int]


def target_runs() -> tuple[TargetRun, ...]:
    """Every row of :data:`TARGET_ROWS` measured (needs arm-none-eabi-gcc with newlib, qemu-system-arm and
    cppcheck)."""
    from ..codegen import CObserver, measure_footprint, run_pil   # casadi: not for `reproduce --help`
    from ..codegen._misra import CATEGORY, misra_findings
    from ..observers import xbs3_observer, xbs4_observer

    cppcheck = shutil.which("cppcheck")
    if cppcheck is None:
        raise RuntimeError("cppcheck is not installed: the MISRA column of 'On the target' cannot be made "
                           "(as root on Debian: make cc-tools)")
    make = {"abs-xbs3": xbs3_observer, "abs-xbs4": xbs4_observer}
    out = []
    for model, method, b1, b2, real, target in TARGET_ROWS:
        ref = make[model](b1, b2, method=method)
        rec = braking_record(ref, initial_state={"z2": 0.5})
        gen = CObserver.like(ref, real=real).generated
        pil = run_pil(gen, target, rec.rows, rec.dt, rec.x0)
        kinds = collections.Counter(CATEGORY.get(rule, "other") for _, _, rule in
                                    misra_findings(cppcheck, gen.prefix, gen.files))
        out.append(TargetRun(model, method, real, target, measure_footprint(gen, target), pil,
                             compare_with_reference(pil, ref, rec.rows, rec.dt, rec.x0), rec.description,
                             dict(kinds)))
    return tuple(out)


def qemu_version() -> str:
    """The first line of ``qemu-system-arm --version``."""
    return subprocess.run([str(shutil.which("qemu-system-arm")), "--version"], capture_output=True, text=True,
                          check=False).stdout.splitlines()[0]


def proof_runs() -> tuple[tuple[GeneratedObserver, Any], ...]:
    """``(observer, ProofResult)`` of every row of :data:`PROOF_ROWS` (needs frama-c)."""
    from ..codegen import prove  # casadi: not for `reproduce --help`

    return tuple((gen, prove(gen)) for gen in (proved_observer(*row) for row in PROOF_ROWS))
