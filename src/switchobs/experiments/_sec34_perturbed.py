"""Seed 001 Sec. 3.4, the perturbed scenario (Figs. 3.6-3.9): the observers read the wheel acceleration offset
through an eccentric wheel-speed sensor, whose periodic error grows with the square of the wheel speed.

The seed perturbs "the measurement of the wheel acceleration offset [...] by periodic (in one mechanical
revolution) oscillations caused by imperfections in the wheel-speed sensors (see Section 5.3)".  Its Sec. 5.3
models the code track seen through the eccentricity law (5.7)-(5.8), ``theta_m = theta + f(theta)`` with ``f``
of period one revolution (:meth:`switchobs.sensors.Encoder.measured_angle`).  Differentiating the measured
angle twice gives the acceleration the sensor reports,

    d²theta_m/dt² = alpha (1 + f'(theta)) + omega² f''(theta),

so the measured offset is ``x2 + R (alpha f'(theta) + omega² f''(theta))``: periodic in the angle, with an
amplitude ``R omega² e/r`` that falls with the square of the speed, as the seed says ("because the perturbation
is velocity-dependent, its amplitude decreases as the vehicle velocity is reduced").  The brake controller reads
the exact offset (chosen by us: the seed does not say, and so the braking is the ideal scenario's and only the
observers' input differs).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..exceptions import SimulationError
from ..loop import EstimatorSpec, xbs_estimator
from ..plants import BrakingResult, replay_updates, scenario, simulate
from ..sensors import TABLE61_ENCODER, Encoder
from ._adaptive import SEC34_AUGMENTED_BETAS, SEC34_GAINS

__all__ = ["SEC34_PERTURBED_ENCODER", "SEC34_PERTURBED_OBSERVERS", "Sec34Perturbed", "eccentric_x2",
           "sec34_perturbed"]

Array = npt.NDArray[np.float64]

#: The wheel-speed sensor of the perturbed scenario: the eccentricity of our Table 6.1 encoder (fitted to the
#: seed's Table 6.1, ``switchobs.experiments.fit_table61_encoder``) alone, one harmonic per revolution; the seed
#: gives the perturbation only as its Fig. 3.6.
SEC34_PERTURBED_ENCODER = Encoder(ppr=TABLE61_ENCODER.ppr, eccentricity=TABLE61_ENCODER.eccentricity)

#: The observers compared on it: the adaptive observer (3.4) at the scenario's gains and the augmented-state
#: (4D) observer of seed 000 Sec. IV at the rates of the ideal comparison (the seed gives no gains).
SEC34_PERTURBED_OBSERVERS: Mapping[str, EstimatorSpec] = {
    "adaptive": EstimatorSpec("adaptive", **SEC34_GAINS),
    **{f"xbs4, beta = {b:g}": EstimatorSpec("xbs4", beta=b) for b in SEC34_AUGMENTED_BETAS}}

#: Step of the central differences of the sensor's angle error f over one revolution [rad]: the truncation error
#: of f'' is h² f''''/12, 1e-7 of its amplitude, the rounding error eps/h², 1e-10 rad.
_DIFF_STEP_RAD = 1e-3


def eccentric_x2(result: BrakingResult, encoder: Encoder) -> Array:
    """The wheel acceleration offset of ``result`` as read through the angle law of ``encoder`` (module notes).

    Parameters
    ----------
    result : BrakingResult
        A run with the columns ``t``, ``omega``, ``omega_dot`` and ``x2``; the wheel angle is the trapezoidal
        integral of ``omega`` from 0.
    encoder : Encoder
        Its :meth:`~switchobs.sensors.Encoder.measured_angle` is the sensor's angle law (5.7)-(5.8).

    Returns
    -------
    ndarray
        ``x2 + R (omega_dot f'(theta) + omega² f''(theta))`` at the run's samples [m/s²].
    """
    s = result.series
    t, om = s["t"], s["omega"]
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (om[1:] + om[:-1]) * np.diff(t))])
    phi = np.mod(theta, 2.0 * math.pi)        # f is periodic: differentiate it on one revolution, not at 500 rad
    h = _DIFF_STEP_RAD

    def f(a: Array) -> Array:
        return encoder.measured_angle(a) - a

    f1 = (f(phi + h) - f(phi - h)) / (2.0 * h)
    f2 = (f(phi + h) - 2.0 * f(phi) + f(phi - h)) / (h * h)
    return s["x2"] + result.scenario.vehicle.radius_m * (s["omega_dot"] * f1 + om * om * f2)


@dataclass(frozen=True)
class Sec34Perturbed:
    """The Sec. 3.4 braking with each observer fed the exact and the perturbed offset.

    Attributes
    ----------
    result : BrakingResult
        The braking (the controller reads the exact ``x2``).
    x2_measured : ndarray
        The perturbed offset the observers read in the perturbed runs.
    estimates : mapping of str to (ndarray, ndarray)
        Per observer of :data:`SEC34_PERTURBED_OBSERVERS`, the XBS estimates at the run's samples fed with the
        exact ``x2`` (the ideal scenario) and with ``x2_measured``.
    """

    result: BrakingResult
    x2_measured: Array
    estimates: Mapping[str, tuple[Array, Array]]

    def _window(self, a: float, b: float) -> npt.NDArray[np.bool_]:
        t = self.result.series["t"]
        return (t >= a) & (t < b)

    def rms(self, label: str, perturbed: bool, a: float, b: float) -> float:
        """RMS of the XBS estimation error of observer ``label`` over ``[a, b)`` [s]."""
        s, keep = self.result.series, self._window(a, b)
        est = self.estimates[label][1 if perturbed else 0]
        return float(np.sqrt(np.mean((est[keep] - s["xbs"][keep]) ** 2)))

    def effect(self, label: str, a: float, b: float) -> float:
        """RMS over ``[a, b)`` of what the perturbation changes in the estimate (perturbed minus ideal)."""
        keep = self._window(a, b)
        ideal, perturbed = self.estimates[label]
        return float(np.sqrt(np.mean((perturbed[keep] - ideal[keep]) ** 2)))

    def amplitude(self, a: float, b: float) -> float:
        """Largest ``|x2_measured - x2|`` over ``[a, b)`` [m/s²]."""
        keep = self._window(a, b)
        return float(np.max(np.abs(self.x2_measured[keep] - self.result.series["x2"][keep])))

    def speed(self, a: float, b: float) -> float:
        """Mean vehicle speed over ``[a, b)`` [m/s]."""
        return float(np.mean(self.result.series["vx"][self._window(a, b)]))


def sec34_perturbed(encoder: Encoder = SEC34_PERTURBED_ENCODER,
                    observers: Mapping[str, EstimatorSpec] = SEC34_PERTURBED_OBSERVERS) -> Sec34Perturbed:
    """Seed 001 Sec. 3.4's braking (``aguado-sec34``) with each observer fed the exact offset and the one read
    through ``encoder`` (:func:`eccentric_x2`), as the simulation loop feeds it (:func:`replay_updates`).

    Raises
    ------
    SimulationError
        An observer refuses a step of the perturbed run (the run's message).
    """
    sc = scenario("aguado-sec34")
    result = simulate(sc)
    s = result.series
    dt = np.concatenate([[0.0], np.diff(s["t"])])
    # the loop hands the estimator the step's mean pressure rate
    u = np.concatenate([[0.0], np.diff(s["P_b"]) / np.where(dt[1:] > 0.0, dt[1:], 1.0)])
    measured = eccentric_x2(result, encoder)
    estimates = {}
    for label, spec in observers.items():
        pair = []
        for y in (s["x2"], measured):
            est, failed, message = replay_updates(xbs_estimator(spec, sc.vehicle, sc.roads.initial),
                                                  s["t"], y, s["vx"], u, dt)
            if failed is not None:
                raise SimulationError(f"Sec. 3.4 perturbed scenario, observer {label}: {message}")
            pair.append(est)
        estimates[label] = (pair[0], pair[1])
    return Sec34Perturbed(result, measured, estimates)
