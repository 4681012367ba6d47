"""The main job end to end: design, certify, export to C, brake a car with the C observer in the loop, report.

Stages (``switchobs demo``, ``make demo``):

1. **rig** -- the built-in models abs-xbs3 (seed 000 eq. (7)) and abs-xbs4
   (eq. (20)) with the TU Delft rig of seed 000 Fig. 2 (``I = 1.2``,
   ``R = 0.3``, ``Fz = 2500``, ``gamma_b = 17.5``, ``c = 34``):
   ``a = R^2 Fz / I``, ``b = -R gamma_b / I``.
2. **design** -- symbolic gains for the spectra of seed 000 Sec. III-E / IV-D
   (``-beta1,-beta2,-beta2`` and ``-beta1,-beta1,-beta2,-beta2``, Theorem 1 of
   seed 004 for ``K_minus``), re-checked exactly (:meth:`GainDesign.verify`),
   evaluated at ``beta1 = beta2 = 100`` (``docs/observers.md``).
3. **certify** -- LMIs and dwell time re-checked in exact arithmetic
   (:func:`switchobs.certify.certify_model`), and the sampled observer that
   ships (one radau3 step per sample, certified for every step length,
   ``discrete`` section); the certificate is written to
   JSON and checked again from the file by :func:`switchobs.certify.verify_certificate`,
   the function behind ``switchobs verify``.
4. **codegen** -- C99 observers with the radau3 step (:func:`switchobs.codegen.generate_observer`),
   compiled, compared with the Python reference observers and timed.
5. **braking** -- the quarter car of seed 001 (2.1) on the Table I roads of
   seed 000, dry -> wet -> snow, five-phase ABS with wheel-acceleration
   tracking (21)-(22), the generated C 4D observer in the loop, fed by a
   60-ppr encoder with three-stage compensation
   (:func:`switchobs.loop.demo_braking`).
6. **report** -- ``report.md``, ``report.json`` and the figures.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._atomic import staged_directory
from .._json import JsonRecord, fields_from_json
from ..exceptions import SimulationError
from ._progress import Progress, Stage, check_prerequisites

if TYPE_CHECKING:       # the loop layer is imported when a stage needs it (its prerequisites are checked first)
    from ..loop import BrakingSummary, DemoSettings

__all__ = ["DEMO_BETAS", "DEMO_METHOD", "DEMO_MODELS", "DemoReport", "ModelResult", "run_demo", "STAGES"]

#: beta1 = beta2 = 100: the defaults docs/observers.md recommends for the quarter car at 1 ms.
DEMO_BETAS: Mapping[str, int] = {"beta1": 100, "beta2": 100}
#: The built-in models of the demo and their symbolic spectra (seed 000 Sec. III-E and IV-D).
DEMO_MODELS: tuple[tuple[str, str], ...] = (("abs-xbs3", "-beta1,-beta2,-beta2"),
                                           ("abs-xbs4", "-beta1,-beta1,-beta2,-beta2"))
#: The step of the generated C observers: 2-stage Radau IIA, certified for every step length h = |s| dt
#: (``switchobs certify --discrete radau3``); RK4 has no discrete certificate for these designs at any dt.
DEMO_METHOD = "radau3"
#: ``c = -c2 = 34`` of the rig in seed 000 (the value of the abs-xbs3 model file).
RIG_C = 34

STAGES: tuple[Stage, ...] = (
    Stage("rig", ("sympy", "switchobs.model", "switchobs.plants")),
    Stage("design", ("sympy", "switchobs.design")),
    Stage("certify", ("cvxpy", "clarabel", "switchobs.certify")),
    Stage("codegen", ("casadi", "switchobs.codegen", "switchobs.observers"), compiler=True),
    Stage("braking", ("numpy", "scipy", "switchobs.plants", "switchobs.sensors", "switchobs.observers",
                      "switchobs.loop")),
    Stage("report", ("matplotlib",)),
)


@dataclass(frozen=True)
class ModelResult(JsonRecord, error=SimulationError):
    """Design, certificate and C code of one model."""

    model: str
    spectrum: str
    K_plus_symbolic: tuple[str, ...]
    K_minus_symbolic: tuple[str, ...]
    exact_checks: Mapping[str, bool]
    K_plus: tuple[float, ...]
    K_minus: tuple[float, ...]
    method: str
    discrete: str
    certificate: str
    certified: bool
    verdict: str
    verified: bool
    verification: tuple[tuple[str, bool], ...]
    c_prefix: str = ""
    c_files: tuple[str, ...] = ()         # relative to the output directory
    c_run_ns: float = math.nan
    c_step_us: float = math.nan
    c_vs_python: float = math.nan

    def to_json(self) -> dict[str, Any]:
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["exact_checks"] = dict(self.exact_checks)
        out["verification"] = [list(v) for v in self.verification]
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in out.items()}

    def __str__(self) -> str:
        return (f"{self.model}: spectrum {{{self.spectrum}}}, K_plus = [{', '.join(f'{k:.6g}' for k in self.K_plus)}], "
                f"K_minus = [{', '.join(f'{k:.6g}' for k in self.K_minus)}]; exact checks "
                f"{'hold' if all(self.exact_checks.values()) else 'FAIL'}; certificate "
                f"{'verified' if self.verified else 'NOT verified'} ({self.certificate}); "
                f"C {self.c_prefix}: {self.c_run_ns:.0f} ns per step")


@dataclass(frozen=True)
class DemoReport(JsonRecord, error=SimulationError):
    """Everything the demo produced (``report.md`` is its readable form)."""

    out_dir: str
    settings: DemoSettings
    models: tuple[ModelResult, ...]
    braking: BrakingSummary
    files: tuple[str, ...]
    timings: Mapping[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Every exact check, certificate and re-verification holds, the car stopped (or ran its time) and no
        observer diverged (a non-finite RMS error over the run, as ``switchobs simulate`` fails a run)."""
        return (all(all(m.exact_checks.values()) and m.certified and m.verified for m in self.models)
                and self.braking.status in ("stopped", "duration") and not self.diverged)

    @property
    def diverged(self) -> tuple[str, ...]:
        """The estimators whose XBS error over the whole run is not finite."""
        return tuple(e.estimator for e in self.braking.errors
                     if e.segment == "whole run" and not math.isfinite(e.rms))

    def to_json(self) -> dict[str, Any]:
        return {"out_dir": self.out_dir, "ok": self.ok, "settings": self.settings.to_json(),
                "models": [m.to_json() for m in self.models], "braking": self.braking.to_json(),
                "files": list(self.files), "timings": dict(self.timings)}

    @classmethod
    def from_json(cls, data: Any) -> DemoReport:
        """The report of :meth:`to_json`.

        Raises
        ------
        SimulationError
            A missing key or a malformed part; the message names it.
        """
        from ..loop import BrakingSummary, DemoSettings  # the parts' types are imported only when needed (top)

        if not isinstance(data, Mapping):
            raise SimulationError(f"a demo report JSON must be an object, got {data!r:.80}")
        return fields_from_json(cls, data, error=SimulationError, what="demo report",
                                settings=DemoSettings.from_json(data.get("settings")),
                                braking=BrakingSummary.from_json(data.get("braking")))

    def __str__(self) -> str:
        lines = [f"switchobs demo ({'fast' if self.settings.fast else 'full'}): report in {self.out_dir}"]
        for m in self.models:
            lines.append(f"  {m.model}: exact checks {'ok' if all(m.exact_checks.values()) else 'FAILED'}; "
                         f"certificate {'verified' if m.verified else 'NOT verified'}: {m.verdict}; "
                         f"C step ({m.method}, sampled observer {'certified for every dt' if m.certified else 'NOT certified'}) "
                         f"{m.c_run_ns:.0f} ns")
        b = self.braking
        dist = "n/a" if b.braking_distance_m is None else f"{b.braking_distance_m:.1f} m"
        from ..plants import distance_label

        lines.append(f"  braking: {b.status}, {distance_label(b.stop_time_s is not None)} "
                     f"{b.stopping_distance_m:.1f} m, braking distance "
                     f"(Table 4.1 definition) {dist}")
        for e in b.errors:
            if e.segment == "whole run":
                lines.append(f"  XBS error, {e.estimator}: median {e.median:.3f}, RMS {e.rms:.3f}"
                             + ("" if math.isfinite(e.rms) else " (diverged)"))
        lines.append(f"  {'all checks hold' if self.ok else 'SOME CHECKS FAILED'}")
        return "\n".join(lines)


# ---------------------------------------------------------------------- stages
def _rig_models() -> dict[str, Any]:
    from ..model import builtin_model
    from ..plants import QuarterCar

    rig = QuarterCar.hoang2014()
    values = {"a": rig.a, "b": -rig.b}      # seed 000 writes b = -R gamma_b / I with +b u
    models = {}
    for name, _ in DEMO_MODELS:
        model = builtin_model(name)
        for key, value in values.items():
            stored = float(model.values[key])
            if not math.isclose(stored, value, rel_tol=1e-12):
                raise SimulationError(f"model {name}: stored {key} = {stored} differs from the rig's {value}")
        models[name] = model
    if float(models["abs-xbs3"].values["c"]) != RIG_C:
        raise SimulationError(f"abs-xbs3 stores c = {models['abs-xbs3'].values['c']}, the rig has c = {RIG_C}")
    return models


def _design(model: Any, spectrum: str) -> tuple[Any, dict[str, np.ndarray]]:
    from ..design import design

    d = design(model, spectrum)
    return d, d.numeric(dict(DEMO_BETAS))


def _exact_gains(d: Any) -> Any:
    """The design evaluated exactly at the rig values and the demo betas (a numeric GainDesign)."""
    return d.at({s.name: DEMO_BETAS[s.name] for s in d.design_symbols})


def _certify(model: Any, d: Any, out: Path) -> dict[str, Any]:
    from ..certify import certify_model, verify_certificate

    report = certify_model(model, gains=_exact_gains(d), discrete=DEMO_METHOD)
    path = out / f"certificate-{model.name}.json"
    report.write(path)
    check = verify_certificate(path)          # from the file, as `switchobs verify` does
    return {"path": path, "certified": report.certified and bool(report.discrete_certified),
            "verdict": report.text, "discrete": report.discrete.statement if report.discrete else "not certified",
            "verified": check.holds,
            "checks": tuple((c.name, c.holds) for c in check.checks)}


def _abs_like_rows(n: int) -> np.ndarray:
    """ABS-like signals (y, vx, u) at 1 kHz for timing and the C-vs-Python comparison."""
    t = np.arange(n) * 1e-3
    return np.column_stack([30.0 * np.sin(2 * np.pi * 6 * (t % 10)), 30.0 - 0.5 * (t % 10),
                            400.0 * np.cos(2 * np.pi * 6 * (t % 10))])


def _codegen(model: Any, d: Any, numeric: dict[str, np.ndarray], out: Path, settings: DemoSettings) -> dict[str, Any]:
    from ..codegen import compile_observer, generate_observer
    from ..observers import SwitchedObserver

    gen = generate_observer(model, d, values=dict(DEMO_BETAS), method=DEMO_METHOD,
                            command=f"switchobs demo (spectrum {dict(DEMO_MODELS)[model.name]}, beta1 = beta2 = 100)")
    target = out / "c" / gen.prefix
    target.mkdir(parents=True, exist_ok=True)
    gen.write(target)
    z2 = gen.state_names.index("z2")
    c_obs = compile_observer(gen, readout=lambda x, i=z2: np.asarray(x)[..., i])
    ref = SwitchedObserver(model, numeric["K_plus"], numeric["K_minus"], readout="z2", method=DEMO_METHOD)
    rows = _abs_like_rows(2000)
    x0 = np.zeros(model.n)
    x0[1] = 0.5
    c_traj, py_traj = c_obs.run(x0, rows, 1e-3), ref.run(x0, rows, 1e-3)
    diff = float(np.max(np.abs(c_traj - py_traj)) / max(np.max(np.abs(py_traj)), 1e-300))
    timing_rows = _abs_like_rows(settings.timing_steps)
    best = math.inf
    for _ in range(3):
        t0 = time.perf_counter()
        c_obs.run(x0, timing_rows, 1e-3)
        best = min(best, time.perf_counter() - t0)
    calls = 2000
    t0 = time.perf_counter()
    x = x0
    for row in rows[:calls]:
        x = c_obs.step(x, row, 1e-3)
    step_us = (time.perf_counter() - t0) / calls * 1e6
    return {"observer": c_obs, "prefix": gen.prefix,
            "files": tuple(str((target / name).relative_to(out)) for name in sorted(gen.files)),
            "run_ns": best / settings.timing_steps * 1e9, "step_us": step_us, "c_vs_python": diff}


# ---------------------------------------------------------------------- driver
def run_demo(out_dir: str | Path = "out/demo", *, fast: bool = False,
             progress: Progress | None = None) -> DemoReport:
    """Run the demo and write its report.

    Parameters
    ----------
    out_dir : path
        Created if needed (checked writable before any stage runs); the files appear in it only when
        the whole run succeeds, and none of them otherwise.  It receives ``report.md``, ``report.json``, the
        certificates, the generated C sources and the figures.
    fast : bool
        Shorter braking (ends shortly after the change to snow) and a shorter
        C timing: for CI.
    progress : Progress, optional
        Stage lines on stderr (default) or quiet (``Progress(6, stream=None)``).

    Returns
    -------
    DemoReport

    Raises
    ------
    PrerequisiteError
        Before anything runs, if a stage's package does not import or no C compiler is found.
    SwitchobsError
        If a stage fails on purpose (e.g. the compiler rejects the code).

    References
    ----------
    seed 000 eq. (7), (20), (21)-(22), Sec. III-E, IV-D, Figs. 2-4, Table I; seed 001 (2.1), Ch. 5-6;
    seed 004 Theorem 1.
    """
    progress = progress if progress is not None else Progress(len(STAGES))
    check_prerequisites(STAGES)
    from ..loop import DemoSettings, demo_braking, summarise_braking

    settings = DemoSettings.for_mode(fast)
    out = Path(out_dir)
    # Every file is written into a staging folder and moved into `out` only when the whole run succeeds;
    # the report names the files at their final place.
    with staged_directory(out, what="the demo output into") as work:
        with progress.stage("rig", "built-in models abs-xbs3, abs-xbs4 with the TU Delft rig of seed 000"):
            models = _rig_models()
        designs: dict[str, Any] = {}
        with progress.stage("design", "symbolic K+ / K- (Theorem 1), exact re-check"):
            for name, spectrum in DEMO_MODELS:
                designs[name] = _design(models[name], spectrum)
                progress.note(f"{name}: at beta1 = beta2 = 100, K+ = [{', '.join(f'{k:.6g}' for k in designs[name][1]['K_plus'])}]")
        certs: dict[str, dict[str, Any]] = {}
        with progress.stage("certify", "LMIs + exact re-check, certificate JSON re-verified from the file"):
            for name, _ in DEMO_MODELS:
                certs[name] = _certify(models[name], designs[name][0], work)
                progress.note(f"{name}: {'verified' if certs[name]['verified'] else 'NOT verified'}")
        code: dict[str, dict[str, Any]] = {}
        with progress.stage("codegen", "C99 observers, compiled, compared with Python, timed"):
            for name, _ in DEMO_MODELS:
                code[name] = _codegen(models[name], *designs[name], work, settings)
                progress.note(f"{name}: {code[name]['prefix']}, {code[name]['run_ns']:.0f} ns per step")
        with progress.stage("braking", "dry -> wet -> snow, encoder chain, C observer in the loop"):
            t0 = time.perf_counter()
            sc, result, record = demo_braking({n: c["observer"] for n, c in code.items()}, settings)
            braking = summarise_braking(sc, result, record, time.perf_counter() - t0)
            progress.note(f"{result.status}, {float(result.series['t'][-1]):.2f} s simulated, "
                          f"{record.events} encoder edges")
        model_results = tuple(
            ModelResult(model=name, spectrum=spectrum,
                        K_plus_symbolic=tuple(str(k) for k in designs[name][0].K_plus),
                        K_minus_symbolic=tuple(str(k) for k in designs[name][0].K_minus),
                        exact_checks=designs[name][0].verify(),
                        K_plus=tuple(float(k) for k in designs[name][1]["K_plus"]),
                        K_minus=tuple(float(k) for k in designs[name][1]["K_minus"]),
                        method=DEMO_METHOD, discrete=certs[name]["discrete"],
                        certificate=str(out / certs[name]["path"].name),
                        certified=certs[name]["certified"],
                        verdict=certs[name]["verdict"], verified=certs[name]["verified"],
                        verification=certs[name]["checks"], c_prefix=code[name]["prefix"], c_files=code[name]["files"],
                        c_run_ns=code[name]["run_ns"], c_step_us=code[name]["step_us"],
                        c_vs_python=code[name]["c_vs_python"])
            for name, spectrum in DEMO_MODELS)
        with progress.stage("report", "figures, report.md, report.json"):
            from .._figures import save_figure
            from ._plots import demo_figures

            figures = [out / save_figure(fig, work / name).name
                       for name, fig in demo_figures(sc, result, record).items()]
            report = DemoReport(out_dir=str(out), settings=settings, models=model_results, braking=braking,
                                files=tuple(sorted([*map(str, figures), str(out / "report.md"), str(out / "report.json"),
                                                    *(m.certificate for m in model_results),
                                                    *(str(out / f) for m in model_results for f in m.c_files)])),
                                timings=progress.summary())
            from ._markdown import demo_markdown

            (work / "report.json").write_text(json.dumps(report.to_json(), indent=2) + "\n", encoding="utf-8")
            (work / "report.md").write_text(demo_markdown(report), encoding="utf-8")
    return DemoReport(out_dir=report.out_dir, settings=settings, models=model_results, braking=braking,
                      files=report.files, timings=progress.summary())
