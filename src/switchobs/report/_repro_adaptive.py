"""The adaptive-observer sections of ``docs/reproductions.md``: seed 001 Sec. 3.4 (the adaptive observer against
the augmented ones after the road changes, and what limits its re-convergence) and Sec. 3.6 (the two-axle
vehicle with the six-phase ABS and an adaptive observer per wheel), with the observers and measures of their
runs."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..loop import DEFAULT_BETA, DEFAULT_GAMMA, EstimatorSpec
from ..plants import BrakingResult, TwoAxleResult, road
from ..experiments import (SEC34_AUGMENTED_BETAS, SEC34_BETAS, SEC34_CHANGES, SEC34_FINE_H_MAX, SEC34_GAINS,
                           SEC34_GAMMAS, SEC34_H_MAX, SEC34_LARGE_GAMMA, SEC34_QUICK_S, SEC34_WINDOWS, SEC36_ACTIVATION,
                           SEC36_CROSSING_TOL_S, SEC36_FINE_STEP_S, SEC36_H_MAX, SEC36_OBSERVER, SEC36_WINDOW_S, Runs,
                           Traced, bosch_sequence, load_excursions, psi_excitation, quick_reapproach, reconverged,
                           sec36_late_excursions, sec36_settled, sec36_stays, segment_rms, upsilon_excitation)
from ._repro_cells import PREDICTED, ROLE, _fitted, _fmt_s, _row


# ---------------------------------------------------------------- Sec. 3.4


def _sec34_section(runs: Runs) -> list[str]:
    """Seed 001 Sec. 3.4: the adaptive observer against the augmented ones, and what limits its re-convergence."""
    chosen = runs.braking("aguado-sec34", EstimatorSpec("adaptive", **SEC34_GAINS))
    library = runs.braking("aguado-sec34", "adaptive")
    augmented = {(kind, beta): runs.braking("aguado-sec34", EstimatorSpec(kind, beta=beta))
                 for kind in ("xbs3", "xbs4") for beta in SEC34_AUGMENTED_BETAS}
    best = {kind: min(SEC34_AUGMENTED_BETAS, key=lambda b: augmented[kind, b].metrics.xbs_rms_error)
            for kind in ("xbs3", "xbs4")}
    betas_text = "$\\beta \\in \\{" + ", ".join(f"{b:g}" for b in SEC34_AUGMENTED_BETAS) + "\\}$"
    rows = [(f"adaptive (3.4), $\\beta = {SEC34_GAINS['beta']:g}$, $\\Gamma = {SEC34_GAINS['gamma']:g}\\,I$ "
             "(chosen by us, the scenario's)", chosen),
            (f"adaptive (3.4), $\\beta = {DEFAULT_BETA['adaptive']:g}$, $\\Gamma = {DEFAULT_GAMMA:g}\\,I$ "
             "(the library defaults)", library),
            (f"augmented 4D (seed 000 Sec. IV, the seed's comparison), $\\beta_1 = \\beta_2 = {best['xbs4']:g}$ "
             f"(lowest RMS of {betas_text})", augmented["xbs4", best["xbs4"]]),
            (f"augmented 3D (seed 000 Sec. III, knows the initial road's $c$), $\\beta_1 = \\beta_2 = "
             f"{best['xbs3']:g}$ (lowest RMS of {betas_text})", augmented["xbs3", best["xbs3"]])]
    roles = (_fitted("the gains were tuned on this run (the grid below) for the seed's ordering"), PREDICTED,
             _fitted("the rate with the lowest RMS on this run"), _fitted("the rate with the lowest RMS on this run"))
    aug_min = min(r.metrics.xbs_rms_error for r in augmented.values())
    ordered = chosen.metrics.xbs_rms_error < aug_min and quick_reapproach(chosen)
    lines = ["", "### Sec. 3.4: dry asphalt → wet asphalt → dry concrete", "",
             "*Seed:* with the switched adaptive observer (3.4) \"a quick convergence to zero of both the state and "
             "parameter estimation errors\" even after the abrupt transitions between the roads, and the adaptive "
             "observer does better than the augmented-state observer of seed 000 (its Sec. IV, the 4D observer), "
             "in transients and at steady state. The seed gives no gains.", "",
             _row("observer (`switchobs simulate aguado-sec34 --observer ...`)", "RMS XBS error",
                  "re-converged after → wet asphalt", "after → dry concrete", ROLE), _row(*["---"] * 5)]
    for (label, res), role in zip(rows, roles):
        lines.append(_row(label, f"{res.metrics.xbs_rms_error:.3f}", *(_fmt_s(reconverged(res, c)) for c in SEC34_CHANGES),
                          role))
    lines += ["", "Re-converged: the error stays within 10 % of the true XBS's peak-to-peak range on the segment. "
              f"{'**Reproduced**' if ordered else '**Not reproduced**'} for the XBS estimate at the chosen gains: the "
              "adaptive observer "
              f"{'re-converges' if quick_reapproach(chosen) else 'does NOT re-converge'} within {SEC34_QUICK_S:g} s after both "
              f"changes and its RMS error is {chosen.metrics.xbs_rms_error:.3f} against {aug_min:.3f}, the lowest of "
              f"the 3D and 4D observers at any of {betas_text}. Per segment (RMS XBS error):", "",
              _row("interval [s]", "adaptive, chosen", "adaptive, library defaults", "augmented 4D", "augmented 3D"),
              _row(*["---"] * 5)]
    segments = ((2.5, 3.0, "dry asphalt, before the change"), (3.0, 3.5, "first 0.5 s on wet asphalt"),
                (5.5, 6.0, "wet asphalt, 2.5 s after the change"), (6.0, 6.5, "first 0.5 s on dry concrete"),
                (9.5, 10.0, "dry concrete, 3.5 s after the change"))
    for a, b, label in segments:
        lines.append(_row(f"{a:g}–{b:g}, {label}", *(f"{segment_rms(r, a, b):.3f}" for _, r in rows)))
    lost = []
    for a, b, label in segments[::2]:
        ours, theirs = segment_rms(chosen, a, b), {n: segment_rms(r, a, b) for n, r in (("4D", rows[2][1]),
                                                                                         ("3D", rows[3][1]))}
        better = min(theirs, key=lambda n: theirs[n])
        if not ours < theirs[better]:
            lost.append(f"{label} ({better} {theirs[better]:.3f} against {ours:.3f})")
    lines += ["", "At steady state (the last 0.5 s on each road) the chosen adaptive observer has a lower error than "
              "both augmented observers " + ("on every road." if not lost else "except on " + "; ".join(lost) + ": "
                                             "the seed's \"better [...] at steady state\" holds only in part, because "
                                             "$\\hat c$ is not re-identified on wet asphalt (below).")]
    # the grid, sub-stepped so that no point is limited by the 1 kHz explicit step
    grid = {(b, g): runs.sec34(b, g) for b in SEC34_BETAS for g in SEC34_GAMMAS}
    lines += ["", f"The adaptive observer over $(\\beta, \\Gamma = \\gamma I)$, sub-stepped "
              f"(`adaptive_xbs_observer(..., h_max={SEC34_H_MAX:g})`): RMS error; re-converged after → wet asphalt, "
              "after → dry concrete [s] (– never):", "",
              _row("$\\beta$", *(f"$\\gamma = {g:g}$" for g in SEC34_GAMMAS)), _row(*["---"] * (1 + len(SEC34_GAMMAS)))]

    def cell(res: BrakingResult) -> str:
        times = ", ".join("–" if v is None else f"{v:.3f}" for v in (reconverged(res, c) for c in SEC34_CHANGES))
        return f"{res.metrics.xbs_rms_error:.3f}; {times}"
    for b in SEC34_BETAS:
        lines.append(_row(f"{b:g}", *(cell(grid[b, g].result) for g in SEC34_GAMMAS)))
    holds = [k for k, tr in grid.items() if quick_reapproach(tr.result) and tr.result.metrics.xbs_rms_error < aug_min]
    pick = min(holds, key=lambda k: grid[k].result.metrics.xbs_rms_error) if holds else None
    lines += ["", f"The seed's ordering (back in the band within {SEC34_QUICK_S:g} s after both changes, RMS below "
              f"{aug_min:.3f}) holds at {len(holds)} of {len(grid)} grid points"
              + (": " + ", ".join(f"$({b:g}, {g:g})$" for b, g in holds) if holds else "")
              + "; we chose " + ("the one with the lowest RMS error" if pick == (SEC34_GAINS["beta"], SEC34_GAINS["gamma"])
                                 else "gains that are NOT the grid's best") + "."]
    lines += _sec34_limits(runs, grid, library)
    lines += ["", "*Chosen by us:* the drum speed $25 - 1.96t$ m/s (the seed gives the deceleration), 25 ms road "
              "transitions, the five-phase ABS with its stall exit, the gains of the adaptive observer "
              f"($\\beta = {SEC34_GAINS['beta']:g}$, $\\Gamma = {SEC34_GAINS['gamma']:g}\\,I$: the grid point above, "
              "tuned on this run) and of the augmented ones (their lowest RMS over the rates tried), initial "
              "estimates $(\\hat c, \\hat d) = (20, 10)$; the seed gives none of them. "
              "`test_aguado2020_sec34_adaptive_reconverges_and_beats_the_augmented_observers_at_the_scenario_gains` "
              "and `test_aguado2020_sec34_the_road_change_not_the_step_limits_the_adaptive_observer` check this "
              "section.", ""]
    return lines


def _sec34_limits(runs: Runs, grid: dict[tuple[float, float], Traced], library: BrakingResult) -> list[str]:
    """What limits the adaptive observer's re-convergence after dry -> wet asphalt, measured."""
    wet, dry = road("wet-asphalt"), road("dry-asphalt")
    base = min(SEC34_BETAS)
    with np.errstate(over="ignore", invalid="ignore"):     # the run without sub-steps overflows on purpose
        plain = runs.braking("aguado-sec34", EstimatorSpec("adaptive", beta=base, gamma=3e4)).metrics.xbs_rms_error
    large = runs.sec34(base, SEC34_LARGE_GAMMA, SEC34_FINE_H_MAX).result
    fine = runs.sec34(base, max(SEC34_GAMMAS), SEC34_FINE_H_MAX).result
    coarse = grid[base, max(SEC34_GAMMAS)].result
    ref = grid[base, DEFAULT_GAMMA]
    s = ref.result.series
    spike = (s["t"] >= 3.0) & (s["t"] < 3.1)
    cycle = (s["t"] >= 4.0) & (s["t"] < 5.0)
    ratio = float(np.max(np.abs(ref.column("Upsilon_w1_c")[spike])) / np.mean(np.abs(ref.column("Upsilon_w1_c")[cycle])))
    count, peak, band, last = load_excursions(library, 3.025, 6.0, 3.5)
    phase, late = library.series["phase"], (library.series["t"] >= 3.5) & (library.series["t"] <= 6.0)
    cycles = int(np.count_nonzero((phase[1:] == 1) & (phase[:-1] != 1) & late[1:]))
    reidentified = [k for k, tr in grid.items() if abs(tr.at("c", 5.99) - wet.c) <= 0.1 * wet.c]
    chosen = grid.get((SEC34_GAINS["beta"], SEC34_GAINS["gamma"]))
    rising = all(np.all(np.diff([grid[b, g].result.metrics.xbs_rms_error for g in SEC34_GAMMAS if g >= DEFAULT_GAMMA]) > 0)
                 for b in SEC34_BETAS)
    kicks = [grid[base, g].at("c", 3.1) for g in SEC34_GAMMAS]
    wet_times = {k: reconverged(tr.result, SEC34_CHANGES[0]) for k, tr in grid.items()}
    fast = [k for k, v in wet_times.items() if v is not None and v <= SEC34_QUICK_S]
    slow = [v for v in wet_times.values() if v is None or v > SEC34_QUICK_S]
    lines = ["", "What limits the re-convergence after dry → wet asphalt, measured:", "",
             f"- **Not the step.** Without sub-steps $\\Gamma = 3\\cdot10^4 I$ still "
             f"{'blows up (RMS error above 1000)' if not plain < 1e3 else 'runs'} at $\\beta = {base:g}$; sub-stepped, "
             f"every grid point runs, the $\\gamma = {max(SEC34_GAMMAS):g}$ row gives the same RMS at $h_{{max}} = "
             f"{SEC34_FINE_H_MAX:g}$ ({fine.metrics.xbs_rms_error:.3f} against {coarse.metrics.xbs_rms_error:.3f}), "
             f"and $\\gamma = {SEC34_LARGE_GAMMA:g}$ ($h_{{max}} = {SEC34_FINE_H_MAX:g}$) gives RMS "
             f"{large.metrics.xbs_rms_error:.3f}, re-converged after → wet asphalt "
             f"{_fmt_s(reconverged(large, SEC34_CHANGES[0]))}. From $\\gamma = {DEFAULT_GAMMA:g}$ on, the RMS error "
             + ("grows with $\\gamma$ at every $\\beta$" if rising else "does NOT grow with $\\gamma$ at every $\\beta$")
             + ": a larger $\\Gamma$ does not buy a better estimate.",
             f"- **The road change kicks $\\hat\\theta$.** At $\\beta = {base:g}$, $\\hat c$ just before the "
             f"change and 0.1 s after it (dry {dry.c:.2f}, wet {wet.c:.2f}): "
             + ", ".join(f"$\\gamma = {g:g}$: {grid[base, g].at('c', 3.0):.1f} → {grid[base, g].at('c', 3.1):.1f}"
                         for g in SEC34_GAMMAS)
             + f" ({'growing' if kicks == sorted(kicks) else 'NOT growing'} with $\\gamma$). The XBS jumps at the "
             "change ($\\mu'$ of the new road at the same slip), which (3.2) with a "
             "constant $\\theta$ cannot represent, and the wheel acceleration swings to "
             f"{float(np.min(s['x2'][spike])):.0f} m/s² within 0.1 s, where the first row of $\\Upsilon$ is up to "
             f"{ratio:.0f} times its size on the wet ABS cycle: the gradient law (3.4b) attributes the jump to "
             "$\\theta$.",
             "- **Then the excitation of the ABS cycle sets the pace.** Smallest eigenvalue of "
             "$\\int \\Upsilon_1^\\top\\Upsilon_1\\,dt$ over 1 s ($\\Upsilon_1$, the row that drives "
             "(3.4b); $1/(\\gamma\\lambda_{min})$ is the slowest parameter time constant) and, for reference, of "
             "(3.7)'s $\\int\\Psi^\\top\\Psi\\,dt$:", "",
             _row("window", *(f"$\\lambda_{{min}}$, $\\beta = {b:g}$" for b in (base, SEC34_GAINS["beta"])),
                  f"$1/(\\gamma\\lambda_{{min}})$ at $\\gamma = {DEFAULT_GAMMA:g}$, $\\beta = {base:g}$",
                  "(3.7): $\\lambda_{min}$, $\\lambda_{max}$"), _row(*["---"] * 5)]
    weakest, spread = ("", math.inf), {}
    for label, a, b in SEC34_WINDOWS:
        ev = [upsilon_excitation(grid[beta, DEFAULT_GAMMA], a, b) for beta in (base, SEC34_GAINS["beta"])]
        weakest = min(weakest, (label, ev[0]), key=lambda p: p[1])
        psi = psi_excitation(ref.result, a, b)
        spread[label] = (psi[0] > 0.0, psi[1] / psi[0])
        lines.append(_row(f"{a:g}–{b:g} s, {label}", *(f"{v:.2g}" for v in ev), f"{1.0 / (DEFAULT_GAMMA * ev[0]):.1f} s",
                          f"{psi[0]:.2f}, {psi[1]:.0f}"))
    ratios = [r for _, r in spread.values()]
    lines += ["", f"(3.7) {'holds' if all(p for p, _ in spread.values()) else 'FAILS'} on every window, its weakest "
              f"direction {min(ratios):.0f}–{max(ratios):.0f} times weaker than its strongest. The ABS cycle on "
              f"{weakest[0]} excites the parameters least, and a larger $\\beta$ shrinks $\\Upsilon$: $\\hat c$ is "
              f"within 10 % of the wet road's $c$ at 5.99 s at {len(reidentified)} of {len(grid)} grid points"
              + "".join(f" $({b:g}, {g:g})$" for b, g in reidentified)
              + ". So the seed's quick convergence of $\\tilde\\theta$ after dry → wet asphalt is **not reproduced**, "
              "while that of the XBS estimate is"
              + ("." if chosen is None else
                 f": at the chosen gains the kick is small ($\\hat c$: {chosen.at('c', 3.0):.1f} → "
                 f"{chosen.at('c', 3.1):.1f}) and the XBS error stays in the band although $\\hat c$ stays off "
                 f"({chosen.at('c', 5.99):.1f} at 5.99 s)."),
              "- **The 10 % band turns small per-cycle excursions into seconds.** With the library defaults the error leaves the "
              f"10 % band ({band:.3f}) {count} times after 3.5 s, in {cycles} ABS cycles, by up to {peak:.3f}; "
              f"the last excursion ends at {last:.3f} s, hence the re-convergence "
              f"of {_fmt_s(reconverged(library, SEC34_CHANGES[0]))}. On the grid {len(fast)} points re-converge within "
             f"{SEC34_QUICK_S:g} s (" + ", ".join(f"$({b:g}, {g:g})$" for b, g in fast) + f"), the other {len(slow)} "
             + (f"take {min(v for v in slow if v is not None):.2f} s or more" if any(v is not None for v in slow) else "")
             + (" or never" if None in slow else "") + ": whether the per-cycle excursions stay under the band "
             "decides, not the decay of the error.",
              f"- **Not the initial estimates:** $(\\hat c, \\hat d)$ at 3.0 s is "
              f"({ref.at('c', 3.0):.1f}, {ref.at('d', 3.0):.1f}), dry asphalt's is ({dry.c:.1f}, {dry.d:.1f}): the start "
              "of the ABS identifies the first road whatever the initial estimates (tested)."]
    return lines


# ---------------------------------------------------------------- Sec. 3.6


def _sec36_section(runs: Runs) -> list[str]:
    est, true = runs.sec36["estimated"], runs.sec36["true"]
    sc = est.scenario
    m = est.metrics
    s = est.series
    t = s["t"]
    end = float(t[-1])
    changes = ((2.5, 5.0, "→ snow"), (5.0, end, "→ wet asphalt"))

    def activation(res: TwoAxleResult, k: str) -> float:
        return float(res.series["t"][np.argmax(res.series[f"phase_{k}"] > 0)])

    def sign_agreement(res: TwoAxleResult, k: str, floor: float = 0.0) -> float:
        """Share of the ABS time where the estimate has the true XBS's sign, counting only where
        |XBS| > ``floor`` × its peak-to-peak range (near 0 the sign says nothing about the tyre region)."""
        r = res.series
        on = r["t"] >= activation(res, k)
        xbs, hat = r[f"xbs_{k}"][on], r[f"xbs_hat_{k}"][on]
        keep = np.abs(xbs) > floor * np.ptp(xbs)
        return float(np.mean(np.sign(hat[keep]) == np.sign(xbs[keep])))

    def crossings_met(res: TwoAxleResult, k: str) -> tuple[float, float, int, int]:
        """Share of the true XBS's zero crossings with an estimated one within the tolerance, the median
        distance [s], and both counts."""
        r = res.series
        on = r["t"] >= activation(res, k)
        t_on = r["t"][on]

        def crossings(x: np.ndarray) -> np.ndarray:
            return t_on[1:][np.sign(x[1:]) != np.sign(x[:-1])]
        true_c, hat_c = crossings(r[f"xbs_{k}"][on]), crossings(r[f"xbs_hat_{k}"][on])
        dist = np.array([np.min(np.abs(hat_c - c)) for c in true_c])
        return float(np.mean(dist <= SEC36_CROSSING_TOL_S)), float(np.median(dist)), len(true_c), len(hat_c)

    def reapproach(res: TwoAxleResult, k: str, measure: Callable[..., float | None]) -> str:
        return ", ".join(f"{label}: {_fmt_s(measure(res, k, a, b))}" for a, b, label in changes)

    def excursions_stable(res: TwoAxleResult, k: str, a: float, b: float) -> float:
        """Share of the samples outside the band, from 0.5 s after the change on, where the true XBS > 0."""
        r = res.series
        sel = (r["t"] >= a) & (r["t"] <= b)
        band = 0.1 * float(np.ptp(r[f"xbs_{k}"][sel]))
        out = sel & (r["t"] > a + 0.5) & (np.abs(r[f"xbs_hat_{k}"] - r[f"xbs_{k}"]) > band)
        return float(np.mean(r[f"xbs_{k}"][out] > 0.0)) if np.any(out) else 1.0

    def initial_rms(res: TwoAxleResult, k: str) -> float:
        r = res.series
        a = activation(res, k)
        keep = (r["t"] >= a) & (r["t"] < a + 0.5)
        return float(np.sqrt(np.mean((r[f"xbs_hat_{k}"][keep] - r[f"xbs_{k}"][keep]) ** 2)))

    def pressure(a: float, b: float) -> str:
        keep = (t >= a) & (t < b)
        return " / ".join(f"{np.mean(s[f'P_{k}'][keep]):.0f}" for k in "fr")

    def c_hat(k: str, at: float) -> float:
        rows = runs.sec36_c_hat[k]
        return float(rows[np.searchsorted(rows[:, 0], at), 1])

    def c_hat_moves(k: str, a: float, b: float) -> tuple[float, float]:
        """Share of the total variation of wheel ``k``'s ``c_hat`` within ``[a, b)`` that happens where the true
        XBS > 0 (the stable side), and the share of the time spent there."""
        rows = runs.sec36_c_hat[k]
        tt, ch = rows[:, 0], rows[:, 1]
        keep = ((tt >= a) & (tt < b))[1:]
        stable = (np.interp(tt, t, s[f"xbs_{k}"]) > 0.0)[1:][keep]
        moved = np.abs(np.diff(ch))[keep]
        return float(moved[stable].sum() / moved.sum()), float(stable.mean())

    def load_rate_ratio(res: TwoAxleResult, k: str) -> float:
        """Over the first 0.5 s of ABS of wheel ``k`` (on the initial road): RMS of the term
        ``(R^2/J) dFz/dt mu`` of ``dx2/dt``, which (3.2) does not model, over that of the modelled
        ``a mu' x2 / vx``."""
        r = res.series
        a0 = activation(res, k)
        keep = (r["t"] >= a0) & (r["t"] < a0 + 0.5)
        gain = veh.radius_m ** 2 / veh.inertia_kg_m2
        unmodelled = gain * np.gradient(r[f"Fz_{k}"], r["t"]) * road(sc.roads.initial).mu_array(r[f"lambda_{k}"])
        modelled = gain * r[f"Fz_{k}"] * r[f"xbs_{k}"] * r[f"x2_{k}"] / r["vx"]
        return float(np.sqrt(np.mean(unmodelled[keep] ** 2) / np.mean(modelled[keep] ** 2)))

    def mean_load(k: str, a: float, b: float) -> float:
        return float(np.mean(s[f"Fz_{k}"][(t >= a) & (t < b)]))

    def releases(res: TwoAxleResult, k: str, a: float, b: float) -> int:
        """Releases (entries into phase 1) of wheel ``k`` within ``[a, b)``."""
        r = res.series
        ph, tt = r[f"phase_{k}"], r["t"]
        return int(np.count_nonzero((ph[1:] == 1) & (ph[:-1] != 1) & (tt[1:] >= a) & (tt[1:] < b)))

    static = runs.sec36["static-load"]
    veh = sc.vehicle
    load_error = np.abs(veh.static_loads[0] - veh.load_transfer * s["ax_meas"] - s["Fz_f"])
    seq = bosch_sequence(est, "f")
    text = "".join(map(str, seq))
    full = text.count("34567")
    cycles = text.count("3")
    diverged = runs.sec36["gamma-default"].metrics["front"]["xbs_rms_error"]
    rear_default = runs.sec36["gamma-default"].metrics["rear"]["xbs_rms_error"]
    fine = runs.sec36["gamma-default-fine"].metrics["front"]["xbs_rms_error"]
    substeps = runs.sec36["gamma-default-substeps"]
    sub = {a: substeps.metrics[a]["xbs_rms_error"] for a in ("front", "rear")}
    late_stable = [excursions_stable(est, k, a, b) for k in "fr" for a, b, _ in changes]
    half = runs.sec36["gamma-half"].metrics["front"]["xbs_rms_error"]

    def late(res: TwoAxleResult) -> list[str]:
        back = {(k, a): sec36_settled(res, k, a, b) for k in "fr" for a, b, _ in changes}
        return [f"{'front' if k == 'f' else 'rear'} {label[2:]} ({_fmt_s(back[k, a])})" for k in "fr"
                for a, _, label in changes if back[k, a] is None or back[k, a] > 0.5]

    late_est, late_static = late(est), late(static)
    strict_late = [(k, a, b, label) for k in "fr" for a, b, label in changes
                   if (sec36_stays(est, k, a, b) or math.inf) > 0.5]
    stretches = {(k, a): sec36_late_excursions(est, k, a, b) for k, a, b, _ in strict_late}
    snow = road("snow")
    snow_releases = {k: releases(est, k, 2.5, 5.0) for k in "fr"}
    c_moves = {k: c_hat_moves(k, 3.0, 5.0) for k in "fr"}
    met = {k: crossings_met(est, k) for k in "fr"}
    met_true = {k: crossings_met(true, k) for k in "fr"}
    away = {k: sign_agreement(est, k, 0.1) for k in "fr"}
    est_better = all(est.metrics[a]["xbs_rms_error"] <= 1.1 * true.metrics[a]["xbs_rms_error"]
                     for a in ("front", "rear"))
    front_better = initial_rms(est, "f") < initial_rms(est, "r")
    wet_rear = (mean_load("r", 5.0, end), veh.static_loads[1])
    lines = ["### Sec. 3.6: two-axle vehicle, six-phase ABS, adaptive observer", "",
             "*Seed:* 180 km/h, braking from 0.25 s, dry asphalt → snow (2.5 s) → wet asphalt (5 s) until 15 km/h; a "
             "six-phase ABS per wheel, the switched adaptive observer (3.4) per wheel fed by a Kalman speed estimate "
             "and an accelerometer with a 0.5 m/s² turn-on bias; its load-dependent $a$ computed on line from the "
             "loads (3.36) with the measured acceleration. *Ours:* `aguado_sec36()` "
             "(`SixPhaseABS`, the Bosch cycle of Sec. 2.2.3) with the adaptive observer per wheel, "
             f"$\\Gamma = {SEC36_OBSERVER.gamma:g}\\,I$, its $a = R^2F_z/J$ read each step from the load (3.36) "
             "computed with the measured $a_x$ (`adaptive_xbs_observer(..., load_signal=True)`, "
             "`xbs_estimator(..., load_signal=True)`; the vehicle feeds it through `plants.LoadInput`); the "
             "reference run of Fig. 3.18 reads the true $v_x$ and "
             f"$a_x$ (`speed_from_filter=False`, ideal accelerometer). Run: status {est.status}, {end:.2f} s, "
             f"stopping distance {m['stopping_distance_m']:.1f} m.", "",
             _row("item", "seed", "ours", "deviation", ROLE), _row(*["---"] * 5),
             _row("ABS takes over, front / rear", " / ".join(f"{SEC36_ACTIVATION[a]:.2f}" for a in ("front", "rear"))
                  + " s", " / ".join(f"{activation(est, k):.3f} s" for k in "fr"), "–",
                  _fitted(f"the driver's build-up rate, {sc.front.initial_rate_bar_s:g} bar/s, was chosen so that the "
                          "ABS takes over at these times")),
             _row("six-phase cycle (front wheel, Bosch numbers)", "1 2 3 4 5 6 7, then 3 4 5 6 7 (Sec. 2.2.3)",
                  " ".join(map(str, seq[:12])) + f" …; {full} of {cycles} releases followed by the full 4 5 6 7",
                  "–", PREDICTED),
             _row("mean speed error", "−18 % (underestimated)", f"{m['speed_error_mean_pct']:.1f} % (worst "
                  f"{m['speed_error_max_pct']:.1f} %)", f"{m['speed_error_mean_pct'] + 18.0:+.1f} points", PREDICTED),
             _row("front load from (3.36) with the measured $a_x$ (the observer's $a$)", "follows the real load "
                  "closely", f"largest error {np.max(load_error):.0f} N (= $\\Delta F_z$ × bias) on "
                  f"{m['front']['load_min_n']:.0f}–{m['front']['load_max_n']:.0f} N", "–", PREDICTED),
             _row("mean pressure front / rear [bar]: dry, snow, wet", "drastically reduced on snow (Fig. 3.16)",
                  f"{pressure(0.75, 2.5)}; {pressure(3.0, 5.0)}; {pressure(5.5, end)}", "–", PREDICTED),
             _row("XBS RMS error with the estimated signals", "\"reasonable approximation\" with the "
                  "estimated signals (Fig. 3.18)", ", ".join(f"{a} {est.metrics[a]['xbs_rms_error']:.2f} (true signals "
                                                              f"{true.metrics[a]['xbs_rms_error']:.2f}; static-load "
                                                              f"$a$ {static.metrics[a]['xbs_rms_error']:.2f})"
                                                              for a in ("front", "rear")), "–", PREDICTED),
             _row("zero crossings of the true XBS met by one of the estimate within "
                  f"{1e3 * SEC36_CROSSING_TOL_S:.0f} ms, front / rear", "zero crossings coincide (Fig. 3.18)",
                  " / ".join(f"{100 * met[k][0]:.0f} % of {met[k][2]} (median {1e3 * met[k][1]:.0f} ms; "
                             f"{met[k][3]} estimated crossings)" for k in "fr")
                  + "; true signals: " + " / ".join(f"{100 * met_true[k][0]:.0f} %" for k in "fr"), "–", PREDICTED),
             _row("sign of the estimate = sign of the true XBS, front / rear", "(the region of the tyre is "
                  "detected)", "where the true XBS is beyond ±10 % of its range: " + " / ".join(
                      f"{100 * away[k]:.1f} %" for k in "fr") + "; all the ABS time: "
                  + " / ".join(f"{100 * sign_agreement(est, k):.0f} %" for k in "fr") + " (true signals: "
                  + " / ".join(f"{100 * sign_agreement(true, k):.0f} %" for k in "fr") + ")", "–", PREDICTED),
             _row("re-approach after the road changes, front: error's "
                  f"{1e3 * SEC36_WINDOW_S:.0f} ms RMS back within the band; error stays within it",
                  "within 0.5 s (Fig. 3.19)", f"{reapproach(est, 'f', sec36_settled)}; stays: "
                  f"{reapproach(est, 'f', sec36_stays)}", "–", PREDICTED),
             _row("re-approach after the road changes, rear (same two measures)", "within 0.5 s",
                  f"{reapproach(est, 'r', sec36_settled)}; stays: {reapproach(est, 'r', sec36_stays)}", "–",
                  PREDICTED),
             _row("the same with the static-load $a$, front; rear", "(the seed updates $a$)",
                  f"{reapproach(static, 'f', sec36_settled)}; stays: {reapproach(static, 'f', sec36_stays)}; rear "
                  f"{reapproach(static, 'r', sec36_settled)}; stays: {reapproach(static, 'r', sec36_stays)}", "–",
                  PREDICTED),
             _row(f"estimate $\\hat c$ on snow (true $c = -c_2 = {snow.c:g}$), front / rear at 3, 4, 5 s", "–",
                  " / ".join(", ".join(f"{c_hat(k, at):.1f}" for at in (3.0, 4.0, 4.999)) for k in "fr"), "–", "–"),
             _row("first 0.5 s of ABS, RMS error front / rear", "front better than rear",
                  f"{initial_rms(est, 'f'):.2f} / {initial_rms(est, 'r'):.2f} (static-load $a$: "
                  f"{initial_rms(static, 'f'):.2f} / {initial_rms(static, 'r'):.2f})", "–", PREDICTED),
             "", "Re-approach, two readings of the seed's \"re-approach their true values within 0.5 s\": the "
             f"RMS of the error over the trailing {1e3 * SEC36_WINDOW_S:.0f} ms is back within 10 % of the true "
             "XBS's peak-to-peak range on the segment (what Fig. 3.19 shows: the perturbation has died out), and "
             "the stricter measure of Sec. 3.4, the error enters and stays within that band until the next change. "
             f"Reproduced: the six-phase cycle in the Bosch order, the speed underestimated on average "
             f"({m['speed_error_mean_pct']:.1f} % against −18 %: the filter is ours, the seed's [19] is not "
             "described), the loads of (3.36), the pressure cut on snow, an XBS estimate "
             f"{'as good with the estimated signals as' if est_better else 'worse with the estimated signals than'} "
             f"with the true ones, the front {'better' if front_better else 'NOT better'} than the rear in the first "
             "0.5 s; the re-approach in the first reading after "
             + ("every road change" if not late_est else f"the road changes except {', '.join(late_est)}")
             + (f" (with the static-load $a$: except {', '.join(late_static)}: the rear wheel, unloaded by the "
                f"load transfer, carries {wet_rear[0]:.0f} N on average on wet asphalt against its static "
                f"{wet_rear[1]:.0f} N, so a static $a$ is {100 * (wet_rear[1] / wet_rear[0] - 1):.0f} % too "
                "large there)" if late_static else "")
             + ". The on-line $a$ changes the RMS error of the whole run from "
             + " and ".join(f"{static.metrics[a]['xbs_rms_error']:.2f} to {est.metrics[a]['xbs_rms_error']:.2f} "
                            f"({a})" for a in ("front", "rear"))
             + f"; the rear's first 0.5 s of ABS is worse with it ({initial_rms(static, 'r'):.2f} → "
             f"{initial_rms(est, 'r'):.2f}; with $\\Gamma = 10^4\\,I$ sub-stepped "
             f"{initial_rms(substeps, 'r'):.2f}): there $\\dot x_2$ holds "
             "the term $-(R^2/J)\\dot F_z\\mu$ that (3.2) does not model (our load transfer follows $a_x$ "
             "instantly, without the pitch dynamics of the seed's vehicle model), with an RMS "
             f"{load_rate_ratio(est, 'r'):.2f} times that of the modelled $a\\mu'\\dot\\lambda$ on the rear "
             f"wheel ({load_rate_ratio(est, 'f'):.2f} on the front), and the observer reads it as an XBS error "
             "$\\propto 1/a$: the true, smaller rear $a$ magnifies it where the static one, "
             f"{veh.static_loads[1] / mean_load('r', activation(est, 'r'), activation(est, 'r') + 0.5):.1f} times "
             "too large there, shrank it"
             + "; the zero crossings: wherever the true XBS is beyond ±10 % of its range the estimate has its "
             f"sign (front {100 * away['f']:.1f} %, rear {100 * away['r']:.1f} % of that time): the signs differ "
             "where the wheel dwells near the friction peak (XBS ≈ 0), mostly the rear one, "
             "whose estimate chatters across 0 "
             f"({met['r'][3]} crossings against {met['r'][2]}), with the true signals as well. "
             + ("Reproduced in the strict reading as well." if not strict_late else
                "Not reproduced: the error staying within the band from 0.5 s after the change on: "
                + ", ".join(f"{'front' if k == 'f' else 'rear'} {label[2:]} "
                            f"({_fmt_s(sec36_stays(est, k, a, b))})" for k, a, b, label in strict_late)
                + ". After 0.5 s the samples outside the band "
                + ("all lie" if min(late_stable) == 1.0 else f"lie {100 * min(late_stable):.0f} % or more")
                + " on the stable side of the tyre (true XBS > 0), in "
                + "; ".join(f"{'front' if k == 'f' else 'rear'} {label[2:]}: "
                            + ", ".join(f"{t0:.2f}–{t1:.2f} s" for t0, t1 in stretches[k, a])
                            for k, a, _, label in strict_late)
                + ": each the recovery after a release (Bosch phases 6 → 7), where the XBS climbs from "
                f"$-c_3$ to its stable-side values within tens of ms (on snow $c = {snow.c:g}$, "
                f"{snow.c / road('dry-asphalt').c:.1f} times dry asphalt's). There the estimate grows at the rate "
                "$\\hat c$ in the rescaled time ($\\dot z_2 = s\\,(c z_2 + d)$), and $\\hat c$ has not "
                f"converged: after the change to snow it is {c_hat('f', 3.0):.0f} (front) and "
                f"{c_hat('r', 3.0):.0f} (rear) at 3 s, {c_hat('f', 4.999):.0f} and {c_hat('r', 4.999):.0f} at 5 s, "
                f"against {snow.c:g}. It moves almost only at those recoveries: from 3 s to 5 s, "
                f"{100 * c_moves['f'][0]:.0f} % (front) and {100 * c_moves['r'][0]:.0f} % (rear) of its total "
                f"change happen on the stable side, where the wheels spend {100 * c_moves['f'][1]:.0f} % and "
                f"{100 * c_moves['r'][1]:.0f} % of that time; in between, the wheel dwells on the flat deep-slip side, where $z_2 \\approx -c_3$ is "
                "constant and the data fix only $d/c$, and there are "
                f"{snow_releases['f']} (front) and {snow_releases['r']} (rear) releases on snow. What limits the strict reading is therefore the excitation of the adaptation "
                "on snow, not the gains or the load: a larger $\\Gamma$ does not remove it (the default "
                "$\\Gamma = 10^4\\,I$, sub-stepped as below, over the whole run: stays front "
                f"{reapproach(substeps, 'f', sec36_stays)}, rear {reapproach(substeps, 'r', sec36_stays)}; "
                f"RMS error front {_rms_text(sub['front'])}, rear {_rms_text(sub['rear'])}), so we keep "
                f"$\\Gamma = {SEC36_OBSERVER.gamma:g}\\,I$ without sub-steps.")
             + " With the default "
             "$\\Gamma = 10^4\\,I$ the front observer diverges within the first second at the loop's 1 ms step "
             f"(RMS error {_rms_text(diverged)}) and not at {1e3 * SEC36_FINE_STEP_S:g} ms (RMS error "
             f"{_rms_text(fine)}; ours, $\\Gamma = {SEC36_OBSERVER.gamma:g}\\,I$ at 1 ms: {_rms_text(half)}), nor at 1 ms with the "
             f"observer sub-stepped to $|s|\\,h \\le {SEC36_H_MAX:g}$ in rescaled time "
             "(`adaptive_xbs_observer(..., h_max=...)`): the explicit RK4 step of the adaptation is "
             "unstable once $\\Gamma\\,h$ is too large for the front wheel's gain $a = R^2F_z/J$, the largest of "
             f"our runs (the rear one stays bounded: RMS error {_rms_text(rear_default)}). The implicit `radau3` step cannot be used: the adaptive "
             "observer is not affine in its state ($\\hat\\theta$ multiplies $\\hat w$) and refuses it.", "",
             "*Chosen by us (the seed does not give them):* that the six-phase ABS is the Bosch cycle of Sec. 2.2.3, "
             "and all its values: " + str(sc.front) + "; rear thresholds × 0.6; the driver's build-up at "
             f"{sc.front.initial_rate_bar_s:g} bar/s (chosen so that the ABS takes over at the seed's times); its exits the description lacks "
             "(hold time-out, lock release, re-release, shortest release; see [ABS plants](abs.md)); "
             f"$\\Gamma = {SEC36_OBSERVER.gamma:g}\\,I$ and $\\beta = 100$; the vehicle (mass, geometry, brakes), the "
             "scalar Kalman speed filter and the accelerometer's random walk; the observer's coordinates "
             "$(w_1, a w_2)$ for the on-line $a$ (model `abs-adaptive2-load`: equal to (3.4) for a constant $a$; for "
             "a varying one it neglects $\\dot a z_2$, the seed's (3.4) with a varying $a$ would neglect "
             "$-c\\dot a z_1/a^2$) and $a$ held over a step at the mean of its two samples. Not modelled: "
             "suspension, pitch and tyre relaxation of the seed's full vehicle model [30].", "",
             "![two-axle vehicle of seed 001 Sec. 3.6](abs_sec36.png)", ""]
    return lines


def _rms_text(rms: float | None) -> str:
    return f"{rms:.2f}" if rms is not None and rms < 1e3 else "blows up"


