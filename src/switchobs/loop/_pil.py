"""Records for the processor-in-the-loop run of a generated observer, and its comparison with the Python reference.

:func:`braking_record` takes the signals an XBS observer is stepped with in a real braking simulation (the
held ``(y, vx, u)`` of :class:`ObserverXbsEstimator`, row by row with the step lengths), where ``y`` changes
sign with every ABS cycle and the road changes; one row is then replaced by a sensor dropout (``y`` NaN) so
that the record holds a refused step.  :func:`compare_with_reference` steps the Python reference observer
over the same rows (a refused row keeps the state, as the harness does) and compares it with a
:class:`switchobs.codegen.PilResult`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from .._json import JsonRecord, array_from_json, array_to_json
from ..exceptions import ObserverInputError, SimulationError
from ..plants import BrakingScenario, RoadChange, RoadSchedule, simulate
from ._adapter import ObserverXbsEstimator, SteppingObserver

__all__ = ["PilRecord", "braking_record", "reference_run", "reference_observer", "PilComparison", "compare_with_reference",
           "PIL_SCENARIO", "PIL_TOLERANCE"]

#: The braking of the record: dry asphalt, snow from 0.6 s, 60 km/h down to 10 km/h, five-phase ABS.
PIL_SCENARIO = BrakingScenario(RoadSchedule("dry-asphalt", [RoadChange("snow", at_time_s=0.6)]),
                               speed_m_s=60 / 3.6, duration_s=1.5, stop_speed_m_s=10 / 3.6)
#: Largest difference from the Python reference (double) per state entry, relative to the entry's largest
#: magnitude over the record: the tolerances of the C observer's runs against the reference (docs/codegen.md,
#: "Verification"): rounding in double; in float, the float build's own trajectory.
PIL_TOLERANCE = {"double": 1e-12, "float": 1e-4}


class _Recorder:
    """A stepping observer that records what it is stepped with (the first state, signals, step lengths)."""

    def __init__(self, observer: SteppingObserver):
        self.observer = observer
        self.x0: np.ndarray | None = None
        self.rows: list[tuple[float, ...]] = []
        self.dts: list[float] = []

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(self.observer.state_names)

    @property
    def signal_names(self) -> tuple[str, ...]:
        return tuple(self.observer.signal_names)

    def step(self, xhat: Any, signals: Any, dt: float) -> np.ndarray:
        if self.x0 is None:
            self.x0 = np.array(xhat, dtype=float)
        self.rows.append(tuple(float(v) for v in signals))
        self.dts.append(float(dt))
        return self.observer.step(xhat, signals, dt)

    def readout(self, xhat: Any) -> float:
        try:
            return float(self.observer.readout(xhat))
        except Exception:  # an observer without a readout: the record does not need one  # noqa: BLE001
            return 0.0


@dataclass(frozen=True)
class PilRecord(JsonRecord, error=SimulationError):
    """Rows of signals with their step lengths and the initial state, and what they come from.

    Attributes
    ----------
    rows : (N, NS) array
    dt : (N,) array
        Step length of every row [s].
    x0 : (NX,) array
    description : str
    """

    rows: np.ndarray
    dt: np.ndarray
    x0: np.ndarray
    description: str

    def to_json(self) -> dict[str, Any]:
        return {"rows": array_to_json(self.rows), "dt": array_to_json(self.dt), "x0": array_to_json(self.x0),
                "description": self.description}

    @classmethod
    def from_json(cls, data: Any) -> PilRecord:
        try:
            return cls(array_from_json(data["rows"]), array_from_json(data["dt"]), array_from_json(data["x0"]),
                       str(data["description"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise SimulationError(f"not a PilRecord JSON ({type(exc).__name__}: {exc})") from None

    def __eq__(self, other: object) -> bool:
        return isinstance(other, PilRecord) and self.description == other.description and all(
            np.array_equal(a, b, equal_nan=True) for a, b in ((self.rows, other.rows), (self.dt, other.dt),
                                                              (self.x0, other.x0)))

    __hash__ = None  # type: ignore[assignment]

    def __str__(self) -> str:
        return self.description


def braking_record(observer: SteppingObserver, *, scenario: BrakingScenario = PIL_SCENARIO,
                   initial_state: dict[str, float] | None = None, dropout_row: int | None = None) -> PilRecord:
    """The signals ``observer`` is stepped with in a braking simulation (beside the loop), with one dropout.

    Parameters
    ----------
    observer : SteppingObserver
        An observer with signals ``(y, vx, u)`` (the XBS models; its readout is not needed).
    scenario : BrakingScenario
        Default :data:`PIL_SCENARIO` (a road change at 0.6 s).
    initial_state : mapping, optional
        As for :class:`ObserverXbsEstimator`.
    dropout_row : int, optional
        The row whose ``y`` becomes NaN (a refused step, ``NONFINITE_SIGNAL``); default: the middle row.

    Raises
    ------
    SimulationError
        The simulation stopped before it stepped the observer, or the observer refused a step of it.
    """
    rec = _Recorder(observer)
    result = simulate(scenario, estimator=ObserverXbsEstimator(rec, initial_state=initial_state),
                      observer_in_loop=False)
    if result.status == "observer-failed" or rec.x0 is None:
        raise SimulationError(f"the braking run gives no record for this observer: {result.status} {result.message}")
    rows = np.array(rec.rows)
    k = rows.shape[0] // 2 if dropout_row is None else dropout_row
    rows[k, 0] = np.nan
    y = rows[:, 0]
    return PilRecord(rows, np.array(rec.dts), rec.x0,
                     f"{rows.shape[0]} steps of a braking simulation from {scenario.speed_m_s * 3.6:.0f} km/h, "
                     f"road change at {scenario.roads.changes[0].at_time_s:g} s, y > 0 in {int(np.sum(y > 0))} and "
                     f"y < 0 in {int(np.sum(y < 0))} rows, row {k} a sensor dropout (y NaN)")


def reference_run(observer: SteppingObserver, rows: npt.ArrayLike, dt: npt.ArrayLike,
                  x0: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """States and statuses of ``observer`` stepped row by row; a refused row keeps the state (its code)."""
    x = np.array(x0, dtype=float)
    states, statuses = [], []
    for sig, h in zip(np.asarray(rows, dtype=float), np.broadcast_to(np.asarray(dt, dtype=float), (len(rows),))):
        try:
            x = np.asarray(observer.step(x, sig, float(h)), dtype=float)
            statuses.append(0)
        except ObserverInputError as exc:
            statuses.append(int(exc.code))
        states.append(x.copy())
    return np.array(states), np.array(statuses, dtype=np.int32)


@dataclass(frozen=True)
class PilComparison(JsonRecord, error=SimulationError):
    """The target run against the host build (bit for bit) and the Python reference (within a tolerance).

    Attributes
    ----------
    rows, identical_rows : int
        Rows, and rows where the target's status and state equal the host build's bit for bit.
    status_equal : bool
        Target and Python reference refuse the same rows with the same codes.
    max_relative_error : float
        Largest difference from the reference per state entry, relative to the entry's largest magnitude.
    tolerance : float
        :data:`PIL_TOLERANCE` of the real type.
    """

    rows: int
    identical_rows: int
    status_equal: bool
    max_relative_error: float
    tolerance: float

    def to_json(self) -> dict[str, Any]:
        return {"rows": self.rows, "identical_rows": self.identical_rows, "status_equal": self.status_equal,
                "max_relative_error": self.max_relative_error, "tolerance": self.tolerance}

    @property
    def passed(self) -> bool:
        return self.identical_rows == self.rows and self.status_equal and self.max_relative_error <= self.tolerance

    def __str__(self) -> str:
        return (f"{self.identical_rows}/{self.rows} rows bit-identical to the host build; statuses "
                f"{'equal to' if self.status_equal else 'DIFFERENT from'} the Python reference's; largest difference "
                f"from it {self.max_relative_error:.2e} relative (tolerance {self.tolerance:g}): "
                f"{'PASSED' if self.passed else 'FAILED'}")


def compare_with_reference(result: Any, observer: SteppingObserver, rows: npt.ArrayLike, dt: npt.ArrayLike,
                           x0: npt.ArrayLike, *, tolerance: float | None = None) -> PilComparison:
    """Compare a :class:`switchobs.codegen.PilResult` with the Python reference stepped over the same rows."""
    ref, ref_status = reference_run(observer, rows, dt, x0)
    got = np.array(result.target_states)
    scale = np.maximum(np.nanmax(np.abs(ref), axis=0), np.finfo(float).tiny)
    err = float(np.nanmax(np.abs(got - ref) / scale)) if got.size else 0.0
    return PilComparison(rows=result.rows, identical_rows=result.identical_rows,
                         status_equal=bool(np.array_equal(ref_status, np.array(result.target_status))),
                         max_relative_error=err,
                         tolerance=PIL_TOLERANCE[result.real] if tolerance is None else tolerance)


def reference_observer(model: Any, generated: Any, *, unknown: tuple[str, ...] = ()) -> Any:
    """The Python reference observer of a generated one: its model, default parameters and gains, method and
    step bound (``unknown``: the adaptive observer's estimated parameters)."""
    from ..observers import AdaptiveSwitchedObserver, SwitchedObserver

    vals = dict(zip(generated.param_names, generated.default_params))
    params = {p: vals[p] for p in model.parameters if p in vals}
    K_plus = [vals[f"K_plus_{s}"] for s in model.states]
    K_minus = [vals[f"K_minus_{s}"] for s in model.states]
    common: dict[str, Any] = dict(params=params, method=generated.method, h_max=generated.h_max,
                                  max_substeps=generated.max_substeps)
    if unknown:
        Gamma = [[vals[f"Gamma_{u}_{v}"] for v in unknown] for u in unknown]
        return AdaptiveSwitchedObserver(model, K_plus, K_minus, unknown=unknown, Gamma=Gamma, **common)
    return SwitchedObserver(model, K_plus, K_minus, **common)
