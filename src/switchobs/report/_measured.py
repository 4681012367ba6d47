"""The measured numbers of the layer pages (observers, certification, ABS), generated from runs.

Not the seed reproductions of ``docs/reproductions.md``: these are the numbers the pages quote about our own
observers, controllers and runs (decay rates of the switched error, the observers on the quarter car,
Assumption 1 on a braking run, the controllers' behaviour, the Table I fit and the Poincare map).  They are
sections of :mod:`switchobs.report._reproductions` (``switchobs reproduce`` writes them, its ``--check``
and ``tests/test_reproductions.py`` fail when a committed page differs from a fresh run).
"""

from __future__ import annotations

import math
import re

import numpy as np

from ..loop import DEFAULT_BETA, DEFAULT_GAMMA, default_method
from ..plants import D1_HOANG, D2_HOANG, FivePhaseABS, PoincareMap, SixPhaseABS, fit_exponential, road, scenario
from ..experiments import (POINCARE_KPS, POINCARE_SETTING, POINCARE_ZETAS, QUARTER_CAR_BETAS, QUARTER_CAR_OBSERVERS,
                           QUARTER_CAR_STEPS, TWO_PHASE_START, Runs)
from ._markdown import md_table
from ._repro_cells import ROLE, _fitted


#: The observer rates and half-cycle lengths in tau of the decay-rate table of docs/observers.md.
DECAY_BETAS = (5, 10, 20, 40, 60, 100, 150, 200, 300, 500)
DECAY_DTAUS = (0.03, 0.1)
#: Where the quarter-car error is scored: after the start-up transient and above the low-speed end [s], [m/s].
_SCORED_AFTER_S, _SCORED_ABOVE_M_S = 0.5, 5.0
#: Assumption 1 on aguado-sec34 (docs/certify.md): the PE window T0 and the regressor window T1 [s].
_TRAJECTORY_T0_S, _TRAJECTORY_T1_S = 0.2, 1.0


def _symmetric_switching_rate(A_plus: np.ndarray, A_minus: np.ndarray, dtau: float) -> float:
    """Decay rate in tau of the switched error under switching every ``dtau``:
    ``-log rho(exp(A_minus dtau) exp(A_plus dtau)) / (2 dtau)``."""
    from scipy.linalg import expm

    cycle = expm(A_minus * dtau) @ expm(A_plus * dtau)
    return -math.log(float(np.max(np.abs(np.linalg.eigvals(cycle))))) / (2.0 * dtau)


def _error_matrices(obs) -> tuple[np.ndarray, np.ndarray]:
    A, C = np.asarray(obs.A, dtype=float), np.asarray(obs.C, dtype=float).ravel()
    return A - np.outer(obs.K_plus, C), -A + np.outer(obs.K_minus, C)


def _decay_section(runs: Runs) -> list[str]:
    from ..observers import adaptive_xbs_observer, xbs3_observer, xbs4_observer

    build = {"abs-xbs3": lambda b: xbs3_observer(b, b), "abs-xbs4": lambda b: xbs4_observer(b, b),
             "abs-adaptive2": lambda b: adaptive_xbs_observer(b, [DEFAULT_GAMMA, DEFAULT_GAMMA])}
    rows = []
    for model, make in build.items():
        pairs = [_error_matrices(make(float(beta))) for beta in DECAY_BETAS]
        for dtau in DECAY_DTAUS:
            rows.append([f"{model}, $\\Delta\\tau = {dtau:g}$",
                         *(f"{_symmetric_switching_rate(Ap, Am, dtau):.1f}" for Ap, Am in pairs)])
    return [md_table([r"$\beta$ (all equal)", *map(str, DECAY_BETAS)], rows)]


def _scored(res) -> np.ndarray:
    s = res.series
    return (s["t"] > _SCORED_AFTER_S) & (s["vx"] > _SCORED_ABOVE_M_S)


def _quarter_car_rms(runs: Runs, dt: float, kind: str, gamma: float | None, beta: float) -> str:
    res = runs.quarter_car(dt, kind, gamma, beta)
    m = _scored(res)
    with np.errstate(over="ignore", invalid="ignore"):     # Gamma = 1e4 I at beta = 60 diverges at 1 ms
        rms = float(np.sqrt(np.mean((res.series["xbs_hat"][m] - res.series["xbs"][m]) ** 2)))
    return f"{rms:#.3g}" if math.isfinite(rms) and rms < 1e3 else "diverges"


def _quarter_car_section(runs: Runs) -> list[str]:
    dry = road("dry-asphalt")
    truth = runs.quarter_car(QUARTER_CAR_STEPS[0])
    xbs = truth.series["xbs"][_scored(truth)]
    head = ("Measured with `switchobs.plants.simulate` (five-phase ABS, dry asphalt of seed 001 Table 2.1, "
            f"25 m/s, observer in parallel, adapter with mean hold, each observer's default step: "
            f"{default_method('xbs3')} for xbs3 and xbs4, {default_method('adaptive')} for the adaptive one, which "
            "takes explicit steps only): RMS of $\\hat\\mu' - \\mu'$ for "
            f"$t > {_SCORED_AFTER_S:g}$ s and $v_x > {_SCORED_ABOVE_M_S:g}$ m/s (the true XBS ranges over "
            f"$[{xbs.min():.2f}, {xbs.max():.2f}]$, standard deviation {xbs.std():.2f}, there). The error is "
            "dominated by the simplification $(-a_x x_1 + x_2) \\simeq x_2$, $\\dot a_x \\simeq 0$ of the observer "
            "models, not by the discretisation (compare the two steps).")
    names = {("xbs3", None): f"xbs3 (road known, $c = {dry.c:g}$)", ("xbs4", None): "xbs4",
             ("adaptive", 1e4): "adaptive, $\\Gamma = 10^4 I$", ("adaptive", 1e3): "adaptive, $\\Gamma = 10^3 I$"}
    rows = []
    for dt in QUARTER_CAR_STEPS:
        for kind, gamma in QUARTER_CAR_OBSERVERS:
            name = names[kind, gamma] if dt == QUARTER_CAR_STEPS[0] else names[kind, gamma].split(" (")[0]
            rows.append([f"{dt * 1e3:g}", name,
                         *(_quarter_car_rms(runs, dt, kind, gamma, beta) for beta in QUARTER_CAR_BETAS)])
    lines = [head, "", md_table(["plant step [ms]", "observer", *(f"$\\beta = {b:g}$" for b in QUARTER_CAR_BETAS)],
                                rows)]
    lines += ["", "The scenarios' defaults (`switchobs.loop.DEFAULT_BETA`, `DEFAULT_GAMMA`): "
              f"$\\beta_1 = \\beta_2 = {DEFAULT_BETA['xbs3']:g}$ for xbs3, {DEFAULT_BETA['xbs4']:g} for xbs4, "
              f"$\\beta = {DEFAULT_BETA['adaptive']:g}$, $\\Gamma = 10^{{{round(math.log10(DEFAULT_GAMMA))}}} I$ "
              "for the adaptive observer, with a plant step of at most 1 ms."]
    return lines


def _trajectory_section(runs: Runs) -> list[str]:
    from ..certify import trajectory_conditions

    name = "aguado-sec34"
    # the observer runs beside the five-phase loop: the trajectory is the plant's, whatever its gains
    res, vehicle = runs.default_run(name), scenario(name).vehicle
    s = res.series
    t, y, vx, u = s["t"], s["x2"], s["vx"], s["u"]
    psi = np.zeros((len(t), 2, 2))
    psi[:, 0, 0], psi[:, 1, 0], psi[:, 1, 1] = y * y / vx, -(vehicle.b / vehicle.a) * u, y / vx
    rep = trajectory_conditions(t, y, window=_TRAJECTORY_T0_S, vx=vx, psi=psi, psi_window=_TRAJECTORY_T1_S)
    pe = rep.psi_pe_level
    return [md_table(["quantity", "value"], [
        [f"$\\tau$ after {rep.duration:g} s", f"{rep.tau_final:.2f}"],
        [f"$\\min \\int y^2$ over {_TRAJECTORY_T0_S:g} s windows", f"{rep.pe_level_y:.2f}"],
        [f"$\\min \\int s^2$ over {_TRAJECTORY_T0_S:g} s windows", f"{rep.pe_level_s:#.3g}"],
        ["zero crossings / smallest $\\lvert dy/dt\\rvert$",
         f"{len(rep.crossings)} / {rep.min_abs_slope:.0f} m/s³ "
         f"({'transversal' if rep.transversal else 'not transversal'})"],
        ["$T_D$ in $t$ / in $\\tau$", f"{rep.dwell_time_t:#.3g} s / {rep.dwell_time_tau:#.3g}"],
        [f"$\\min\\lambda_{{\\min}}\\int\\Psi^\\top\\Psi$ over {_TRAJECTORY_T1_S:g} s windows (Fig. 3.1)",
         f"{pe:#.3g} {'> 0 (PE)' if pe > 0 else '(not PE)'}"]])]


#: Seed 000 Table I: theta per road, as printed.
TABLE1_SEED = {"hoang-dry": (-0.53, 25.22, 7.2), "hoang-wet": (-0.36, 8.86, 24.0), "hoang-snow": (-0.05, 0.24, 14.0)}
#: What was chosen to match Table I: the fit's range and spacing (``fit_exponential``'s defaults).
TABLE1_FIT = "the range $[-1, 0]$ and its 101 slips were chosen to give these digits"


def _minus(text: str) -> str:
    """The typographic minus of the abs.md tables."""
    return text.replace("-", "−")


def _short(x: float) -> str:
    """Four significant digits, two below 1e-3 (``9.5e-8``, not ``9.462e-08``)."""
    text = f"{x:.4g}" if abs(x) >= 1e-3 else f"{x:.2g}"
    return re.sub(r"e([+-])0*(\d)", r"e\1\2", text).replace("e+", "e")


def _table1_section(runs: Runs) -> list[str]:
    lines = [f"Least squares on 101 equally spaced slips in $[-1,0]$, $d_1={D1_HOANG:g}$, $d_2={D2_HOANG:g}$ "
             "(`fit_exponential`):", ""]
    rows = []
    for name, seed in TABLE1_SEED.items():
        fit = fit_exponential(name)
        rows.append([name.removeprefix("hoang-"), _minus("(" + ", ".join(f"{x:.3f}" for x in fit.theta) + ")"),
                     _minus("(" + ", ".join(f"{x:g}" for x in seed) + ")"), f"{fit.residual_rms:.4f}",
                     _minus(f"{D1_HOANG * D2_HOANG * fit.theta[0]:.1f}"), _fitted(TABLE1_FIT)])
    return lines + [md_table(["road", "$\\theta$ ours", "$\\theta$ seed", "fit RMS", "$\\alpha_0=d_1d_2\\theta_0$",
                              ROLE], rows)]


def _poincare_section(runs: Runs) -> list[str]:
    dry = road("dry-asphalt")
    maps = {kp: PoincareMap.from_abs(kp=kp, c=dry.c, d=dry.d, **POINCARE_SETTING) for kp in POINCARE_KPS}
    zetas = ",".join(f"{z:g}" for z in POINCARE_ZETAS)
    symbols = {"z_ref": "z_{ref}", "chi_a": "\\chi_a", "chi_b": "\\chi_b"}
    lines = ["Dry asphalt, " + ", ".join(f"${symbols[k]}={v:g}$" for k, v in POINCARE_SETTING.items())
             + f" ($\\kappa={maps[POINCARE_KPS[0]].kappa:.3g}$):", ""]
    rows = []
    for kp, pm in maps.items():
        fp = pm.fixed_point()
        errors = [abs(pm(zeta) - runs.return_maps[kp, zeta]) / abs(runs.return_maps[kp, zeta])
                  for zeta in POINCARE_ZETAS]
        condition = "yes" if fp.alpha > fp.alpha_bound else ("no (yet stable)" if fp.stable else "no (unstable)")
        rows.append([f"{kp:g}", _minus(f"{fp.zeta:.6f}"), _short(fp.derivative), f"{fp.alpha_bound:.2f}",
                     condition, f"{max(errors):.2g}"])
    return lines + [md_table(["$k_p=\\alpha$", "$\\zeta^\\circ$", "$P'(\\zeta^\\circ)$", "bound", "condition",
                              f"largest relative error, analytic vs simulated map ($\\zeta={zetas}$)"], rows)]


def _continuous_section(runs: Runs) -> list[str]:
    """Seed 001 Figs. 4.1-4.2: the continuous law (4.2)-(4.3) against the two-phase ABS, adaptive observer
    beside the loop (``switchobs simulate --controller continuous --observer adaptive --parallel``)."""
    res = runs.continuous_law
    law = res["continuous"].scenario.controller
    cont, two = res["continuous"], res["two-phase"]
    m, a1 = cont.metrics, cont.metrics.assumption1
    s = cont.series
    two_err = np.abs(two.series["xbs_hat"] - two.series["xbs"])[two.series["t"] >= two.metrics.abs_activation_s]
    crossings = f"{a1.crossings} crossing" + ("" if a1.crossings == 1 else "s")
    xbs_end = float(s["xbs"][-1])
    return [f"**Continuous law, seed 001 Figs. 4.1–4.2.** On dry asphalt from 90 km/h with the adaptive observer "
            "beside the loop (`--controller continuous --observer adaptive --parallel`) the state-feedback law "
            f"settles the wheel near the optimum (mean friction {100 * m.efficiency:.1f} % of the peak) but $y=z_1$ "
            f"stops crossing zero ({crossings}), Assumption 1 {'holds' if a1.holds else 'fails'} (regressor PE "
            f"{a1.regressor_pe:.2g} vs {two.metrics.assumption1.regressor_pe:.2g} with the two-phase ABS), $\\tau$ "
            f"reaches only {a1.tau_final:.2f}, and the estimate settles on a wrong XBS (error "
            f"{abs(s['xbs_hat'][-1] - s['xbs'][-1]):.2f} at the end; with the two-phase ABS the median error after "
            f"its activation is {np.median(two_err):.2g}). On the non-simplified plant $z_1$ tends to "
            f"$a_x\\lambda\\approx{s['ax'][-1] * s['lambda'][-1]:.1f}$ m/s² rather than to 0 (the simplification "
            "$-a_xx_1+x_2\\approx x_2$ of (2.4)), so the XBS settles at "
            f"{_minus(f'{xbs_end:.2f}')} instead of 0 with $k_r={law.kr:g}$. An estimate "
            "that reaches $cz_2+d\\le0$ stops the run (`controller-singular`)."]


def _five_phase_section(runs: Runs) -> list[str]:
    """The printed Fig. 6.6 thresholds on the Table 2.1 characteristics, and our defaults."""
    fig66, ours = FivePhaseABS.fig66(), FivePhaseABS()
    res = runs.fig66_thresholds
    s = res.series
    k = int(np.argmin(s["lambda"]))
    mu_ratio = float(road("dry-asphalt").mu(s["lambda"][k])) / road("dry-asphalt").peak_friction
    return ["The thresholds printed in seed 001 Sec. 6.4 (" + ", ".join(f"{e:g}" for e in fig66.eps)
            + " m/s², `FivePhaseABS.fig66()`) were tuned there for dry concrete with encoder measurements; on the "
            "flat post-peak side of the Table 2.1 characteristics the hold between $-\\varepsilon_4$ and "
            f"$-\\varepsilon_5$ lets the slip run to ${s['lambda'][k]:.2f}$ (dry asphalt at 120 km/h, at "
            f"{s['t'][k]:.1f} s; the friction there is {100 * abs(mu_ratio):.0f} % of the peak, the run's mean "
            f"{100 * res.metrics.efficiency:.1f} %). Our defaults come from a random search followed by a local "
            "refinement maximising the worst friction utilisation over the five roads of Table 4.1 at 120 km/h: "
            "$\\varepsilon=(" + ",".join(f"{e:g}" for e in ours.eps) + ")$ m/s², "
            f"$u=({ours.u1:g},{ours.u3:g},{ours.u4:g})$ bar·m/s²."]


def _two_phase_start_section(runs: Runs) -> list[str]:
    """How the two-phase ABS of ``table41`` (no start-up safeguard) leaves its build-up on the flattest road."""
    name, speed = TWO_PHASE_START
    s = runs.two_phase_start.series
    k = int(np.flatnonzero(s["phase"] != 0)[0])
    slip, optimum = abs(float(s["lambda"][k])), abs(road(name).optimal_slip)
    text = (f"`table41` on the true XBS runs without the safeguard, as printed: at {speed:g} km/h on "
            f"{name.replace('-', ' ')} the build-up ends at {100 * slip:.0f} % slip after {s['t'][k]:.2f} s")
    if slip < optimum:
        later = np.flatnonzero(np.abs(s["lambda"][k:]) >= optimum)
        reach = f"{s['t'][k + later[0]] - s['t'][k]:.1f} s" if later.size else "the rest of the run"
        text += f", short of the {100 * optimum:.0f} % optimum, which the cycle then needs {reach} to reach."
    else:
        text += f", past the {100 * optimum:.0f} % optimum."
    return [text]


def _six_phase_section(runs: Runs) -> list[str]:
    """Our six-phase values and the friction utilisation they give on the roads of Table 2.1 at 120 km/h."""
    ours = SixPhaseABS()
    used = [res.metrics.efficiency for res in runs.six_phase_roads.values()]   # ice has no friction peak (c3 = 0)
    return [f"Ours: $-a={-ours.a_minus:g}$, $+a={ours.a_plus:g}$, $+A={ours.a_big:g}$ m/s², "
            f"$\\lambda_1={ours.slip_threshold:g}$, $u=({ours.u_release:g}, {ours.u_apply:g}, {ours.u_step:g})$ bar·m/s² "
            "(a grid search for the worst friction utilisation over the roads of Table 2.1 with a friction peak, all "
            "but ice, at 120 km/h that keeps "
            f"the full cycle on dry asphalt: {100 * min(used):.1f}–{100 * max(used):.1f} % of the peak friction)."]


#: (section name, page, section function) of this module, appended to the sections of ``switchobs reproduce``.
MEASURED_SECTIONS = (("observer_decay_rates", "docs/observers.md", _decay_section),
                     ("observer_quarter_car", "docs/observers.md", _quarter_car_section),
                     ("trajectory_conditions", "docs/certify.md", _trajectory_section),
                     ("five_phase_defaults", "docs/abs.md", _five_phase_section),
                     ("six_phase_defaults", "docs/abs.md", _six_phase_section),
                     ("two_phase_start", "docs/abs.md", _two_phase_start_section),
                     ("exponential_fit", "docs/abs.md", _table1_section),
                     ("continuous_law", "docs/abs.md", _continuous_section),
                     ("poincare_map", "docs/abs.md", _poincare_section))
