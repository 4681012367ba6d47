"""The XBS observers of the seeds as instances of the generic ones, with beta-parametrised gains."""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..design import GainDesign, design_gains
from ..exceptions import ModelError, SpectrumError
from ..model import builtin_model
from ..spec import DEFAULT_METHOD
from ._observer import AdaptiveSwitchedObserver, SwitchedObserver

__all__ = ["xbs3_observer", "xbs4_observer", "adaptive_xbs_observer", "xbs_gains"]

#: Target spectra of ``A_plus`` (and, by Theorem 1 of seed 004, of ``A_minus``) per built-in XBS model.
_SPECTRA = {
    "abs-xbs3": ("-beta1,-beta2,-beta2", ("beta1", "beta2")),          # seed 000 Sec. III-E
    "abs-xbs4": ("-beta1,-beta1,-beta2,-beta2", ("beta1", "beta2")),   # seed 000 Sec. IV-D
    "abs-adaptive2": ("-beta,-beta", ("beta",)),                        # seed 001 (3.20), double pole
    "abs-adaptive2-load": ("-beta,-beta", ("beta",)),                   # the same in (w1, a w2)
}


@functools.lru_cache(maxsize=None)
def _symbolic_design(model_name: str) -> GainDesign:
    return design_gains(builtin_model(model_name), _SPECTRA[model_name][0])


def _positive(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise SpectrumError(f"{name} = {value!r} is not a number") from None
    if not math.isfinite(v) or v <= 0.0:
        raise SpectrumError(f"{name} = {value!r} must be finite and > 0: the error dynamics have the "
                            f"eigenvalue -{name}, which must be stable")
    return v


def xbs_gains(model_name: str, betas: Mapping[str, float], *,
              params: Mapping[str, Any] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Numeric ``(K_plus, K_minus)`` of a built-in XBS model for the given betas.

    The gains come from :func:`switchobs.design.design_gains` with the spectra of
    the seeds: ``{-beta1, -beta2, -beta2}`` for abs-xbs3 (seed 000 Sec. III-E),
    ``{-beta1, -beta1, -beta2, -beta2}`` for abs-xbs4 (Sec. IV-D) and
    ``{-beta, -beta}`` for abs-adaptive2 (a double pole; then
    ``k1- = -k1+`` and ``k2- = k2+`` as seed 001 eq. (3.20) asks).  They equal
    the seeds' closed formulas (checked in the tests).

    Parameters
    ----------
    model_name : {"abs-xbs3", "abs-xbs4", "abs-adaptive2", "abs-adaptive2-load"}
    betas : mapping
        ``beta1``, ``beta2`` (or ``beta`` for abs-adaptive2 and abs-adaptive2-load), all > 0.
    params : mapping, optional
        Model parameter values overriding the built-in ones (e.g. ``{"c": 24}``).

    Raises
    ------
    SpectrumError
        A beta is missing, not finite or not positive.
    """
    gains = _xbs_design(model_name, betas, params)
    return gains.gains_for(gains.model)


def _xbs_design(model_name: str, betas: Mapping[str, Any], params: Mapping[str, Any] | None) -> GainDesign:
    """The seeds' design of a built-in XBS model, evaluated exactly at the betas and the parameter values."""
    if model_name not in _SPECTRA:
        raise SpectrumError(f"no XBS gain formula for model {model_name!r}; use one of {sorted(_SPECTRA)} "
                            "or switchobs.design.design_gains for other models")
    _, names = _SPECTRA[model_name]
    unexpected = sorted(set(betas) - set(names))
    if unexpected:
        raise SpectrumError(f"model {model_name!r} takes {list(names)}, not {unexpected}")
    missing = [n for n in names if n not in betas]
    if missing:
        raise SpectrumError(f"model {model_name!r} needs {list(names)}; missing {missing}")
    values: dict[str, Any] = {n: _positive(n, betas[n]) for n in names}
    values.update(params or {})
    return _symbolic_design(model_name).at(values)


def xbs3_observer(beta1: float, beta2: float, *, params: Mapping[str, Any] | None = None,
                  method: str = DEFAULT_METHOD, h_max: Any = None, max_substeps: int | None = None) -> SwitchedObserver:
    """The 3D known-road XBS observer of seed 000 eq. (8)-(9) on model abs-xbs3.

    State ``(z1, z2, z3)`` = (wheel-acceleration offset x2, XBS mu', -c2 c3);
    signals ``(y, vx, u)`` with ``y = x2`` [m/s^2], ``vx`` [m/s], ``u = dP_b/dt``
    [bar/s].  The error has the spectrum ``{-beta1, -beta2, -beta2}`` in the
    rescaled time for both signs of ``y`` (seed 000 Sec. III-E).  Readout: ``z2``.

    Parameters
    ----------
    beta1, beta2 : float
        Positive; the rates of the error in ``tau = ∫|y|/vx dt``.
    params : mapping, optional
        Overrides of ``a = R^2 Fz / I``, ``b = -R gamma_b / I``, ``c = -c2`` (the
        built-in values are the TU Delft rig of seed 000 Fig. 2).
    method : {"radau3", "midpoint", "rk4", "euler"}
        The step method (default radau3, certified for every step length; see :class:`SwitchedObserver`).
    h_max, max_substeps
        Sub-stepping of a step with ``|s| dt`` above ``h_max`` (see :class:`SwitchedObserver`); default none.

    Examples
    --------
    >>> obs = xbs3_observer(10.0, 20.0)
    >>> obs.K_plus.round(4).tolist()
    [84.0, -19.4987, -21.3333]
    """
    gains = _xbs_design("abs-xbs3", {"beta1": beta1, "beta2": beta2}, params)
    return SwitchedObserver(builtin_model("abs-xbs3"), gains, params=params, method=method, readout="z2", h_max=h_max,
                            max_substeps=max_substeps)


def xbs4_observer(beta1: float, beta2: float, *, params: Mapping[str, Any] | None = None,
                  method: str = DEFAULT_METHOD, h_max: Any = None, max_substeps: int | None = None) -> SwitchedObserver:
    """The 4D unknown-road XBS observer of seed 000 Sec. IV on model abs-xbs4.

    State ``(z1, z2, z3, z4)`` = (x2, mu', mu'', alpha0); the error has two
    double eigenvalues ``-beta1``, ``-beta2`` (seed 000 Sec. IV-D).  Readout: ``z2``.
    The parameters are those of :func:`xbs3_observer` (without ``c``).

    Examples
    --------
    >>> xbs4_observer(10.0, 20.0).K_plus.round(3).tolist()
    [134.0, -53.717, -3221.504, -213.333]
    """
    gains = _xbs_design("abs-xbs4", {"beta1": beta1, "beta2": beta2}, params)
    return SwitchedObserver(builtin_model("abs-xbs4"), gains, params=params, method=method, readout="z2", h_max=h_max,
                            max_substeps=max_substeps)


def adaptive_xbs_observer(beta: float, Gamma: Any, *, params: Mapping[str, Any] | None = None,
                          method: str = "rk4", h_max: Any = None, max_substeps: int | None = None,
                          load_signal: bool = False) -> AdaptiveSwitchedObserver:
    """The switched adaptive XBS observer of seed 001 eq. (3.4) on model abs-adaptive2.

    Estimates ``w = (w1, w2)`` with ``w1 = z1``, ``w2 = z2 + (c/a) z1`` and
    ``theta = (c, d) = (-c2, -c2 c3)``; the XBS readout is
    ``z2_hat = w2_hat - (c_hat / a) w1_hat``.  Gains ``K'`` of (3.15) with
    ``k1+ = 2 beta``, ``k2+ = -beta^2 / a``, ``k1- = -k1+``, ``k2- = k2+``
    (conditions (3.20); ``A_plus`` and ``A_minus`` both have the double
    eigenvalue ``-beta``).

    Parameters
    ----------
    beta : float
        Positive.
    Gamma : array_like, 2 x 2 or its diagonal
        Symmetric positive definite adaptation gain for ``(c, d)``.
    params : mapping, optional
        Overrides of ``a`` and ``b`` (``c`` and ``d`` are estimated).
    method : {"rk4", "euler"}
        The adaptive observer is not affine in its state: the implicit (certified) methods are refused, so the
        default stays rk4.
    h_max, max_substeps
        Bound on the step in rescaled time ``|s| dt`` and the sub-step limit, as for
        :class:`AdaptiveSwitchedObserver`: the explicit step of the adaptation is unstable when
        ``Gamma`` times that step is too large (seed 001 Sec. 3.6 at 1 kHz with ``Gamma = 1e4 I``).
    load_signal : bool
        ``True``: ``a = R^2 Fz / J`` is not a parameter but a measured signal, read each step (seed 001
        Sec. 3.6 computes it on line from the loads (3.36)).  The observer is then the same (3.4) on
        model abs-adaptive2-load, in the coordinates ``(w1, v2) = (w1, a w2)`` where ``a`` enters only
        the regressor (``Psi[1][d] = s a``) and the gains are ``a``-free (``k2 = -beta^2``); signals
        ``(y, vx, a, u)``; the readout ``v2 - c*w1`` is ``a`` times the XBS (divide by the step's ``a``,
        as :class:`switchobs.loop.LoadXbsEstimator` does).  For a constant ``a`` its estimates equal
        the default observer's up to rounding.

    Examples
    --------
    >>> obs = adaptive_xbs_observer(100.0, [5e3, 5e3], params={"b": 4.0}, load_signal=True)
    >>> obs.signal_names
    ('y', 'vx', 'a', 'u')
    >>> x = obs.step([-3.0, 190 * 0.4, 20.0, 10.0, 0.01, -0.02, 190 * 0.03, 190 * 0.5], [-3.2, 30.0, 190.0, 150.0],
    ...              1e-3)
    >>> round(obs.readout(x) / 190.0, 9)   # the XBS estimate; the default observer's with a = 190 is the same
    0.711595288
    """
    name = "abs-adaptive2-load" if load_signal else "abs-adaptive2"
    if load_signal and params is not None and "a" in params:
        raise ModelError(f"with load_signal=True the load a is a signal, read each step; drop params['a'] = "
                              f"{params['a']!r}")
    gains = _xbs_design(name, {"beta": beta}, params)
    return AdaptiveSwitchedObserver(builtin_model(name), gains, unknown=("c", "d"), Gamma=Gamma, params=params,
                                    method=method, readout="v2 - c*w1" if load_signal else "w2 - c*w1/a",
                                    h_max=h_max, max_substeps=max_substeps)
