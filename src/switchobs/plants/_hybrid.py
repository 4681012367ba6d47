"""Fixed-step RK4 with event location, on tuples of plain floats.

The hybrid simulations advance with classical Runge-Kutta steps; when a guard
changes sign within a step, the step is redone with the fraction ``θ`` of its
length that puts the guard on its switching surface (Illinois iteration on
``θ``, each trial a fresh RK4 step from the step's start).  Switching instants
are therefore resolved to ``time_tol`` instead of to the step size, which keeps
the limit cycles of the hybrid controllers independent of the step.
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["rk4_step", "locate_event"]

State = tuple[float, ...]
Rhs = Callable[[float, State], State]


def rk4_step(f: Rhs, t: float, y: State, h: float, k1: State) -> State:
    """One classical RK4 step of length ``h`` from ``(t, y)``, given ``k1 = f(t, y)``."""
    h2 = 0.5 * h
    k2 = f(t + h2, tuple(a + h2 * k for a, k in zip(y, k1)))
    k3 = f(t + h2, tuple(a + h2 * k for a, k in zip(y, k2)))
    k4 = f(t + h, tuple(a + h * k for a, k in zip(y, k3)))
    h6 = h / 6.0
    return tuple(a + h6 * (p + 2.0 * (q + r) + s) for a, p, q, r, s in zip(y, k1, k2, k3, k4))


def locate_event(f: Rhs, t: float, y: State, h: float, k1: State, guard: Callable[[float, State], float],
                 g_lo: float, g_hi: float, *, time_tol: float = 1e-10, max_iter: int = 60) -> float:
    """Fraction ``θ in (0, 1]`` of the step at which ``guard`` turns positive.

    Parameters
    ----------
    f, t, y, h, k1
        The step (as in :func:`rk4_step`).
    guard : callable
        ``guard(t, y) -> float``; evaluated on RK4 steps of length ``θ h``.
    g_lo, g_hi : float
        Guard at the start (``<= 0``) and at the end (``> 0``) of the step.

    Returns
    -------
    float
        The upper end of the final bracket, so that the guard is ``> 0`` there
        and the transition is taken on the far side of the surface; the bracket
        is narrower than ``time_tol`` seconds.
    """
    lo, hi = 0.0, 1.0
    side = 0
    for _ in range(max_iter):
        if (hi - lo) * h <= time_tol:
            break
        theta = hi - g_hi * (hi - lo) / (g_hi - g_lo)
        # keep the trial strictly inside the bracket so that it always shrinks
        span = hi - lo
        theta = min(max(theta, lo + 1e-3 * span), hi - 1e-3 * span)
        g = guard(t + theta * h, rk4_step(f, t, y, theta * h, k1))
        if g > 0.0:
            hi, g_hi = theta, g
            if side == 1:
                g_lo *= 0.5          # Illinois: the same end moved twice, halve the other's weight
            side = 1
        else:
            lo, g_lo = theta, g
            if side == -1:
                g_hi *= 0.5
            side = -1
    return hi
