"""The sampled observer's certificate in the user's units: step bound, sample rate and, for the ABS, vehicle speed.

With the time scaling ``s = y / vx`` (the XBS models of seed 000 (7), seed
001 (2.6)) one observer step of ``dt`` seconds is a step of
``h = |y| dt / vx`` in the rescaled time, so a certified ``h <= h_max`` reads
``vx >= |y|max / (rate * h_max)``.  The table of ``docs/certify.md`` is
:func:`sampled_observer_table`; a test compares it with a fresh run.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import sympy as sp

from ..exceptions import DimensionError

__all__ = ["speed_signal", "speed_table", "sampled_lines", "sampled_observer_table", "ABS_ACCEL_MAX", "ABS_RATE_HZ",
           "ABS_SPEED_MIN"]

#: The ABS operating envelope the issue names: |x2| <= 150 m/s^2, a 1 kHz observer, speeds down to 1 m/s.
ABS_ACCEL_MAX = 150.0
ABS_RATE_HZ = 1000.0
ABS_SPEED_MIN = 1.0


def speed_signal(model: Any) -> str | None:
    """The external signal ``v`` when the time scaling is ``y / v`` (the ABS models), else None."""
    y = model.symbols[model.output]
    for name in model.external:
        if sp.simplify(model.time_scale - y / model.symbols[name]) == 0:
            return name
    return None


def speed_table(h_bound: float | None, *, accel_max: float, rate_hz: float, speed_min: float) -> tuple[float, float]:
    """ABS units: ``(lowest speed certified at rate_hz for |x2| <= accel_max, rate needed down to speed_min)``.

    With ``s = x2 / vx`` the step length is ``h = |x2| dt / vx``; ``h <= h_bound``
    holds for ``vx >= accel_max / (rate_hz h_bound)`` and, at ``speed_min``,
    for ``rate >= accel_max / (speed_min h_bound)``.  ``h_bound = None``
    (every step) gives ``(0, 0)``.
    """
    if h_bound is None:
        return 0.0, 0.0
    if not math.isfinite(h_bound) or h_bound <= 0:
        raise DimensionError(f"h_bound must be a positive number, got {h_bound!r}")
    return accel_max / (rate_hz * h_bound), accel_max / (speed_min * h_bound)


def _bound(cert: Any) -> tuple[float | None, bool]:
    """``(h bound, certified)``: the certified ``h_max`` (None = every step) or, if not certified, ``h_rho``."""
    if cert.certified:
        return (None if cert.h_max is None else float(cert.h_max)), True
    return cert.h_rho, False


def sampled_lines(model: Any, cert: Any, *, rate_hz: float = ABS_RATE_HZ, accel_max: float = ABS_ACCEL_MAX,
                  speed_min: float = ABS_SPEED_MIN) -> list[str]:
    """What the discrete certificate means at ``rate_hz``, and in vehicle speed for an ABS model."""
    h, certified = _bound(cert)
    lines = []
    if certified and h is None:
        lines.append("  at any sample rate: certified for every |s(y,t)|*dt (every speed for the ABS models)")
        return lines
    what = "certified" if certified else "per-mode spectral bound only (NOT certified)"
    if h is None:
        lines.append(f"  no step bound: {what}")
        return lines
    lines.append(f"  at {rate_hz:g} Hz: {what} while |s(y,t)| <= {h * rate_hz:.4g}")
    v = speed_signal(model)
    if v is not None:
        low, rate = speed_table(h, accel_max=accel_max, rate_hz=rate_hz, speed_min=speed_min)
        lines.append(f"  ABS ({model.output} up to {accel_max:g}): {what} for {v} >= {low:.3g} m/s at {rate_hz:g} Hz; "
                     f"down to {speed_min:g} m/s needs {rate:.4g} Hz")
    return lines


def sampled_observer_table(models: Sequence[tuple[str, str]], *, beta: int = 100,
                           methods: Sequence[str] = ("euler", "rk4", "midpoint", "radau3")) -> str:
    """Markdown table: per model and step method, the discrete verdict, ``h_max``, ``h_rho`` and the ABS speeds.

    ``models`` are ``(name, spectrum)`` with the spectrum in ``beta1, beta2``
    (the demo's designs), evaluated at ``beta1 = beta2 = beta``.
    """
    from ..certify import certify_model
    from ..certify import discrete_certificate
    from ..design import design_gains
    from ..model import builtin_model

    rows = ["| model | method | verdict | certified h_max | per-mode h_rho | lowest speed at 1 kHz, "
            "x2 up to 150 m/s² | rate for 1 m/s |",
            "|---|---|---|---|---|---|---|"]
    for name, spectrum in models:
        model = builtin_model(name)
        d = design_gains(model, spectrum)
        values = {**dict(model.values), **{s.name: beta for s in d.design_symbols}}
        rep = certify_model(model, gains=d.at(values), dwell=False)
        P = (rep.hespanha if rep.hespanha.certified else rep.strict).P
        Ap, Am = rep.family.exact
        C = [[str(c) for c in model.C]]
        for method in methods:
            cert = discrete_certificate(Ap, Am, C, P, method=method)
            h, certified = _bound(cert)
            rho = "∞ (A-stable)" if cert.h_rho is None else f"{cert.h_rho:.4f}"
            if certified and h is None:
                speed, rate, hmax = "any > 0", "any", "∞ (every step)"
            else:
                low, need = speed_table(h, accel_max=ABS_ACCEL_MAX, rate_hz=ABS_RATE_HZ, speed_min=ABS_SPEED_MIN)
                speed, rate = f"{low:.2f} m/s", f"{need / 1000:.2f} kHz"
                hmax = f"{h:.4g}" if certified else "none"
                if not certified:  # h is the per-mode bound h_rho: stability of each mode alone
                    speed, rate = f"none certified (per mode: {speed})", f"none certified (per mode: {rate})"
            verdict = cert.verdict.value + (" (strict)" if cert.strict else "")
            rows.append(f"| {name} | {method} | {verdict} | {hmax} | {rho} | {speed} | {rate} |")
    return "\n".join(rows)
