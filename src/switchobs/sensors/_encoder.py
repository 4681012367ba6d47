"""Imperfect incremental encoder: tooth edges, transition noise, eccentricity, timer clock.

Seed 001, Section 5.3: the actual transition locations are the nominal ones
plus a differential nonlinearity, (5.6), fixed per edge and/or drawn afresh at
every event (the revolution-to-revolution scatter of Fig. 5.3), and the code
track is seen through the eccentricity law (5.7) (small-angle form (5.8)).  An edge
fires when the code-track angle seen by the pick-off sensor reaches a
transition location; the electronic control unit only counts edges, so it
assigns each event the *nominal* angle of its edge.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord
from ..exceptions import SimulationError
from ._trajectory import AngleTrajectory
from ._validate import check_int, check_positive, check_range

__all__ = ["Encoder", "EncoderEvents", "MAX_PPR"]

Array = npt.NDArray[np.float64]

_MAX_ECCENTRICITY = 0.1
#: Most teeth per revolution: ABS tone wheels have 40-100, optical encoders up to some 10 000.
MAX_PPR = 100_000


@dataclass(frozen=True)
class Encoder:
    """An incremental wheel encoder with its manufacturing and mounting imperfections.

    Parameters
    ----------
    ppr : int
        Pulses (teeth) per revolution ``N`` (48-60 on ABS wheels), at least 2.
    dnl_cycles : float
        Differential nonlinearity bound ``eps`` of (5.6), in encoder cycles
        (one cycle is ``2 pi / N``): every edge ``i`` gets a fixed error
        ``delta_i ~ U[-eps, eps]``.  Real sensors: 0.002-0.05 cycles (seed 001,
        Section 6.1).  With ``jitter_cycles`` it must stay below 1/4 cycle with
        ``both_edges`` (1/2 otherwise) so that edges keep their order.
    eccentricity : float
        Ratio ``e / r`` of code-track eccentricity to code-track radius, in
        ``[0, 0.1]`` (0.05-0.25 mm on a few-cm track in practice).
    eccentricity_phase_rad : float
        Offset angle ``phi`` of (5.7).
    both_edges : bool
        Use rising and falling edges (``2N`` events per revolution, 50 % duty
        cycle) instead of rising edges only (the seed's test rig).
    clock_hz : float or None
        Frequency of the capture timer; time stamps are floored to its ticks.
        ``None`` keeps the exact crossing times.
    seed : int
        Seed of ``numpy.random.default_rng`` drawing the ``delta_i``.
    exact_arcsin : bool
        Use the exact eccentricity law (5.7) rather than its small-angle form (5.8).
    jitter_cycles : float
        Bound of a transition error ``U[-eps_j, eps_j]`` (encoder cycles) drawn
        afresh for every event: the stochastic part of (5.6), the scatter of
        the dots around each tooth's mean in seed 001 Fig. 5.3.  It is not
        periodic in the angle, so no harmonic compensation removes it.

    Raises
    ------
    SimulationError
        For ``ppr`` outside ``[2, MAX_PPR]``, a negative ``dnl_cycles`` or ``jitter_cycles`` or too large a
        sum of the two, ``eccentricity`` outside ``[0, 0.1]`` or a non-positive ``clock_hz``.

    References
    ----------
    Seed 001, (5.6)-(5.8) and Section 6.3 (rising edge of one channel).

    Examples
    --------
    >>> from switchobs.sensors import Encoder, constant_speed
    >>> ev = Encoder(ppr=60).events(constant_speed(1020, 0.1))
    >>> len(ev)  # 1020 rpm for 0.1 s is 1.7 revolutions of 60 teeth
    102
    """

    ppr: int = 60
    dnl_cycles: float = 0.0
    eccentricity: float = 0.0
    eccentricity_phase_rad: float = 0.0
    both_edges: bool = False
    clock_hz: float | None = None
    seed: int = 0
    exact_arcsin: bool = True
    jitter_cycles: float = 0.0
    _transitions: Array = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if check_int(self.ppr, "ppr (pulses per revolution)", minimum=2) > MAX_PPR:
            raise SimulationError(f"ppr = {self.ppr} lies above {MAX_PPR}, more teeth than any wheel encoder has")
        limit = 0.25 if self.both_edges else 0.5
        dnl = check_positive(self.dnl_cycles, "dnl_cycles", allow_zero=True)
        jitter = check_positive(self.jitter_cycles, "jitter_cycles", allow_zero=True)
        if dnl + jitter >= limit:
            raise SimulationError(
                f"dnl_cycles + jitter_cycles = {dnl + jitter:g} must stay below {limit:g} cycle so that consecutive "
                f"edges keep their order")
        check_range(self.eccentricity, "eccentricity (e/r)", 0.0, _MAX_ECCENTRICITY)
        check_range(self.eccentricity_phase_rad, "eccentricity_phase_rad", -1e6, 1e6)
        if self.clock_hz is not None:
            check_positive(self.clock_hz, "clock_hz")
        check_int(self.seed, "seed", minimum=0)
        rng = np.random.default_rng(self.seed)
        delta = rng.uniform(-self.dnl_rad, self.dnl_rad, self.n_edges) if self.dnl_rad > 0 else np.zeros(self.n_edges)
        object.__setattr__(self, "_transitions", self.nominal_angles() + delta)

    @property
    def n_edges(self) -> int:
        """Events per revolution: ``N`` (rising edges) or ``2N`` (both edges)."""
        return self.ppr * (2 if self.both_edges else 1)

    @property
    def dnl_rad(self) -> float:
        """The bound ``eps`` of (5.6) in radians."""
        return self.dnl_cycles * 2.0 * math.pi / self.ppr

    def nominal_angles(self) -> Array:
        """``theta_i^nom = (i - 1) 2 pi / N`` for the edges of one revolution (seed 001, Section 5.3.1)."""
        return np.arange(self.n_edges) * (2.0 * math.pi / self.n_edges)

    def transition_angles(self) -> Array:
        """Actual transition locations ``theta_i^act = theta_i^nom + delta_i`` on the code track, (5.6)."""
        return self._transitions.copy()

    def measured_angle(self, theta_r: npt.ArrayLike) -> Array:
        """Code-track angle ``theta_m`` seen at rotation angle ``theta_r``: (5.7), or (5.8) if not exact."""
        th = np.asarray(theta_r, dtype=float)
        s = self.eccentricity * np.sin(th + self.eccentricity_phase_rad)
        return th + (np.arcsin(s) if self.exact_arcsin else s)

    def rotation_angles(self) -> Array:
        """Rotation angles ``theta_r`` at which each edge of revolution 0 fires (without ``jitter_cycles``).

        Inverts ``measured_angle`` (strictly increasing since ``e/r <= 0.1``) by Newton's method.
        """
        return self._rotation(self._transitions)

    def _rotation(self, target: Array) -> Array:
        """``measured_angle`` inverted at the code-track angles ``target`` (Newton's method)."""
        th = target.copy()
        rho, phi = self.eccentricity, self.eccentricity_phase_rad
        for _ in range(50):
            s = rho * np.sin(th + phi)
            c = rho * np.cos(th + phi)
            slope = 1.0 + (c / np.sqrt(1.0 - s * s) if self.exact_arcsin else c)
            step = (self.measured_angle(th) - target) / slope
            th -= step
            if np.max(np.abs(step)) <= 8.0 * np.finfo(float).eps * (1.0 + np.max(np.abs(th))):
                break
        return th

    def events(self, trajectory: AngleTrajectory) -> EncoderEvents:
        """The encoder events produced while the wheel follows ``trajectory``.

        Edges are located by exact root finding on the continuous angle (see
        :meth:`AngleTrajectory.crossing_times`), then time-stamped by the timer.

        Returns
        -------
        EncoderEvents

        Raises
        ------
        SimulationError
            If the timer is so coarse that two edges share one tick, or the wheel reverses.
        """
        base = self.rotation_angles()
        two_pi = 2.0 * math.pi
        th0, th1 = (float(v) for v in trajectory.theta(np.array([trajectory.t_start, trajectory.t_end])))
        k0 = math.floor((th0 - base[-1]) / two_pi) - 1
        k1 = math.ceil((th1 - base[0]) / two_pi) + 1
        revs = np.arange(k0, k1 + 1)
        if self.jitter_cycles > 0:
            # a fresh code-track error per event; (5.7) is 2 pi-periodic, so revolution 0 is inverted
            width = self.jitter_cycles * 2.0 * math.pi / self.ppr
            jitter = np.random.default_rng([self.seed, 1]).uniform(-width, width, (revs.size, self.n_edges))
            base = self._rotation((self._transitions[None, :] + jitter).ravel()).reshape(revs.size, self.n_edges)
        levels = (base + two_pi * revs[:, None]).ravel()
        edge = np.tile(np.arange(self.n_edges), revs.size)
        rev = np.repeat(revs, self.n_edges)
        keep = (levels > th0) & (levels <= th1)
        levels, edge, rev = levels[keep], edge[keep], rev[keep]
        exact = trajectory.crossing_times(levels)
        if self.clock_hz is None:
            stamps = exact.copy()
        else:
            stamps = np.floor(exact * self.clock_hz) / self.clock_hz
            clash = np.flatnonzero(np.diff(stamps) <= 0.0)
            if clash.size:
                i = int(clash[0])
                raise SimulationError(
                    f"clock_hz = {self.clock_hz:g} is too coarse: edges {i} and {i + 1} share the tick "
                    f"t = {stamps[i]:.9g} s; raise clock_hz")
        nominal = self.nominal_angles()[edge] + two_pi * rev
        return EncoderEvents(times=stamps, angles=nominal, exact_times=exact, true_angles=levels,
                             edge_index=edge, encoder=self)


@dataclass(frozen=True, eq=False)
class EncoderEvents(JsonRecord, error=SimulationError):
    """Time-stamped encoder events.

    Attributes
    ----------
    times : ndarray
        Time stamps (s) from the capture timer (strictly increasing).
    angles : ndarray
        Angle the control unit assigns to each event: the nominal location of
        the edge plus whole revolutions (it cannot see ``delta_i`` nor the eccentricity).
    exact_times : ndarray
        Exact crossing times before clock quantisation.
    true_angles : ndarray
        True rotation angle ``theta_r`` at each crossing.
    edge_index : ndarray of int
        Which edge of the revolution fired (``0 .. n_edges - 1``).
    encoder : Encoder
        The encoder that produced the events.
    """

    times: Array
    angles: Array
    exact_times: Array
    true_angles: Array
    edge_index: npt.NDArray[np.int_]
    encoder: Encoder

    def __len__(self) -> int:
        return int(self.times.size)

    def angle_error(self) -> Array:
        """``angles - true_angles``: the position error the imperfections put on each event."""
        return self.angles - self.true_angles

    def to_json(self, *, arrays: bool = False) -> dict[str, Any]:
        """Summary as plain JSON types (with the event arrays if ``arrays``)."""
        enc = {k: v for k, v in asdict(self.encoder).items() if not k.startswith("_")}
        out: dict[str, Any] = {
            "encoder": enc,
            "count": len(self),
            "t_first_s": float(self.times[0]) if len(self) else None,
            "t_last_s": float(self.times[-1]) if len(self) else None,
            "max_angle_error_rad": float(np.max(np.abs(self.angle_error()))) if len(self) else 0.0,
        }
        if arrays:
            out.update(times=self.times.tolist(), angles=self.angles.tolist(),
                       exact_times=self.exact_times.tolist(), true_angles=self.true_angles.tolist(),
                       edge_index=self.edge_index.tolist())
        return out

    def __str__(self) -> str:
        e = self.encoder
        if not len(self):
            return f"EncoderEvents: none ({e.ppr} ppr)"
        return (f"EncoderEvents: {len(self)} events from a {e.ppr}-ppr encoder "
                f"({'both edges' if e.both_edges else 'rising edges'}), "
                f"t in [{self.times[0]:.6g}, {self.times[-1]:.6g}] s, "
                f"max angle error {np.max(np.abs(self.angle_error())):.3g} rad")
