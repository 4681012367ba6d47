"""Switched observers built from any switchobs model (seed 000 eq. (8)-(9), seed 001 eq. (3.4), seed 004)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt
import sympy as sp

from .._validate import adaptation_gain, round_down, signal_matrix, substep_bound
from ..design import GainDesign
from ..exceptions import DimensionError, FreeSymbolError, ModelError, SimulationError
from ..model import Model, numeric, parse_expression, rational_value
from ..spec import REFERENCE_STATUSES, ObserverSpec, default_method
from ._engine import Kernel, _ArrayPrinter, check_free

__all__ = ["SwitchedObserver", "AdaptiveSwitchedObserver"]

ArrayLike = npt.ArrayLike


def _gain(K: Any, n: int, what: str) -> np.ndarray:
    """A gain column as n floats: numbers, a numpy array or a numeric sympy matrix."""
    if isinstance(K, sp.MatrixBase):
        K = numeric(K, what=what)
    try:
        arr = np.asarray(K, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(f"{what} must be {n} numbers, got {K!r}") from None
    if arr.shape not in ((n,), (n, 1), (1, n)):
        raise DimensionError(f"{what} has the wrong shape; expected ({n},) instead of {arr.shape}")
    arr = arr.reshape(n)
    if not np.isfinite(arr).all():
        raise SimulationError(f"{what} = {arr.tolist()} has a non-finite entry")
    return arr


def _parameter_values(model: Model, params: Mapping[str, Any] | None,
                      keep: Sequence[str]) -> dict[str, sp.Rational]:
    """Exact values of every parameter but ``keep`` (``params`` override the model's ``values``)."""
    values = {k: v for k, v in model.values.items() if k not in keep}
    for key, val in (params or {}).items():
        if key in keep:
            raise ModelError(f"parameter {key!r} is estimated by the adaptive observer; do not give it a value")
        values[key] = rational_value(val, what=f"params[{key!r}]")
    model.with_values(values)  # validates the names and the declared signs
    return values


class _Observer:
    """Common machinery: input conversion, step / derivative / run, readout."""

    _kernel: Kernel
    _readout_fn: Any
    _readout_text: str | None

    def __init__(self, model: Model, K_plus: Any, K_minus: Any, *, params: Mapping[str, Any] | None,
                 method: str, readout: str | None, unknown: Sequence[str], Gamma: Any, h_max: Any = None,
                 max_substeps: int | None = None):
        bound = substep_bound(h_max, max_substeps, error=SimulationError)
        unknown = tuple(unknown)
        values = _parameter_values(model, params, unknown)
        if isinstance(K_plus, GainDesign):
            if K_minus is not None:
                raise SimulationError("a GainDesign holds both gains; do not give K_minus with it")
            K_plus, K_minus = K_plus.gains_for(model, values)
        elif K_minus is None:
            raise SimulationError("K_minus is missing: give both gains, or a GainDesign as K_plus")
        n = model.n
        G = adaptation_gain(Gamma, unknown, error=SimulationError) if unknown else np.zeros((0, 0))
        spec = ObserverSpec(model, tuple(_gain(K_plus, n, "K_plus").tolist()),
                            tuple(_gain(K_minus, n, "K_minus").tolist()), values=values, unknown=unknown,
                            Gamma=tuple(map(tuple, G.tolist())))
        missing = [p for p in spec.known_parameters if p not in values]
        if missing:
            raise FreeSymbolError(f"model {model.name!r}: the parameter(s) {missing} have no value; "
                                  f"give them with params={{{missing[0]!r}: ...}}")
        self._build(spec, method, readout, bound)

    def _build(self, spec: ObserverSpec, method: str, readout: str | None, bound: tuple[Any, int] | None) -> None:
        """Everything but the validation of the user's arguments: what an unpickled observer runs."""
        #: Certified bound on |s| dt (exact) and the sub-step limit, as given (None: one step per dt).
        self.h_max, self.max_substeps = bound if bound is not None else (None, None)
        self._kernel = (Kernel(spec, method) if bound is None else
                        Kernel(spec, method, h_max=round_down(bound[0], error=SimulationError),
                               max_substeps=bound[1]))
        self.model = spec.model
        self.values = {k: float(v) for k, v in spec.values.items()}
        self.unknown = spec.unknown
        lowered = self._kernel.lowered
        self.K_plus, self.K_minus, self.Gamma = lowered.K_plus, lowered.K_minus, lowered.Gamma
        self.A, self.C = lowered.A, lowered.C
        self._readout_text = readout
        self._readout_fn = self._compile_readout(readout, spec.values) if readout is not None else None

    @classmethod
    def _from_spec(cls, spec: ObserverSpec, method: str, readout: str | None,
                   bound: tuple[Any, int] | None = None) -> "_Observer":
        obs = cls.__new__(cls)
        obs._build(spec, method, readout, bound)
        return obs

    def __reduce__(self):
        """Pickle as the spec (plain data): the unpickled observer regenerates its step source."""
        bound = None if self.h_max is None else (self.h_max, self.max_substeps)
        return (type(self)._from_spec, (self.spec, self.method, self._readout_text, bound))

    @property
    def spec(self) -> ObserverSpec:
        """The observer contract this observer runs (also what :func:`switchobs.codegen.generate_observer` translates)."""
        return self._kernel.spec

    # ------------------------------------------------------------------ info
    @property
    def method(self) -> str:
        """One of :data:`switchobs.spec.METHODS`."""
        return self._kernel.method

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the observer state entries, in order (the C ``xhat`` layout)."""
        return self._kernel.spec.state_names

    @property
    def signal_names(self) -> tuple[str, ...]:
        """Names of the signals, in order: y, external signals, inputs (``Model.signals``)."""
        return self._kernel.spec.signal_names

    @property
    def size(self) -> int:
        """Length of the observer state."""
        return self._kernel.spec.size

    @property
    def source(self) -> str:
        """The generated Python source of the step (for inspection and for mirroring in C)."""
        return self._kernel.source

    # ------------------------------------------------------------------ numerics
    def step(self, xhat: ArrayLike, signals: ArrayLike, dt: float) -> np.ndarray:
        """Advance the observer state by one step of ``dt`` seconds, signals held constant.

        Parameters
        ----------
        xhat : array_like, shape (size,)
            Current observer state (layout :attr:`state_names`).
        signals : array_like, shape (len(signal_names),)
            ``y``, the external signals, the inputs, held over the step (zero-order hold).
        dt : float
            Step in seconds, finite and > 0.

        Returns
        -------
        numpy.ndarray
            The new state; ``xhat`` is not modified.

        Raises
        ------
        ObserverInputError
            With ``.code`` one of :class:`~switchobs.spec.StepStatus` (checked in that order).
        DimensionError
            If ``xhat`` or ``signals`` has the wrong length.
        """
        k = self._kernel
        x = k.floats(xhat, self.state_names, "xhat")
        sig = k.floats(signals, self.signal_names, "signals")
        return np.array(k.step(x, sig, dt))

    def derivative(self, xhat: ArrayLike, signals: ArrayLike) -> np.ndarray:
        """The continuous-time right-hand side ``dxhat/dt`` at ``xhat`` and ``signals``.

        Raises the same errors as :meth:`step` (except for ``dt``).
        """
        k = self._kernel
        return np.array(k.derivative(k.floats(xhat, self.state_names, "xhat"),
                                     k.floats(signals, self.signal_names, "signals")))

    def run(self, xhat0: ArrayLike, signal_rows: ArrayLike, dt: float) -> np.ndarray:
        """Step through a whole record of signals; the same arithmetic as repeated :meth:`step`.

        Parameters
        ----------
        xhat0 : array_like, shape (size,)
        signal_rows : array_like, shape (k, len(signal_names))
            One row of signals per step.
        dt : float

        Returns
        -------
        numpy.ndarray, shape (k, size)
            Row ``i`` is the state after consuming row ``i`` of the signals
            (the layout of the C ``<prefix>_run`` trajectory; ``xhat0`` is not included).

        Raises
        ------
        ObserverInputError
            The error :meth:`step` would raise at the first failing row; the message names the row.
        """
        k = self._kernel
        x0 = k.floats(xhat0, self.state_names, "xhat0")
        rows = signal_matrix(signal_rows, self.signal_names)
        return k.run(x0, rows, dt)

    # ------------------------------------------------------------------ readout
    def _compile_readout(self, text: str, values: Mapping[str, sp.Rational]):
        states = {name: sp.Symbol(f"x{i}", real=True) for i, name in enumerate(self.state_names)}
        names = {**{p: self.model.symbols[p] for p in self.model.parameters}, **states}
        expr = parse_expression(text, names, what="readout").xreplace(
            {self.model.symbols[k]: v for k, v in values.items()})
        check_free(expr, set(states.values()), "readout", self.model)
        self._readout_code = _ArrayPrinter().doprint(expr)
        args = ", ".join(f"x{i}" for i in range(self.size))
        namespace: dict = {"numpy": np}
        exec(f"def readout({args}):\n    return {self._readout_code}\n", namespace)
        return namespace["readout"]

    @property
    def readout_code(self) -> str | None:
        """The readout as the printed expression it evaluates, in ``x0, x1, ...`` (the states in order), if any."""
        return self._readout_code if self._readout_fn is not None else None

    @property
    def readout_expression(self) -> str | None:
        """The readout (e.g. the XBS estimate ``"z2"``) in terms of :attr:`state_names`, if any."""
        return self._readout_text

    def readout(self, xhat: ArrayLike) -> float | np.ndarray:
        """Evaluate the readout on one state (a float) or on a trajectory ``(k, size)`` (an array)."""
        if self._readout_fn is None:
            raise SimulationError("this observer has no readout; build it with readout='<expression in "
                                  f"{', '.join(self.state_names)}>'")
        arr = np.asarray(xhat, dtype=float)
        if arr.shape[-1:] != (self.size,) or arr.ndim > 2:
            raise DimensionError(f"readout expects a state of length {self.size} or a (k, {self.size}) "
                                 f"trajectory, got shape {arr.shape}")
        out = self._readout_fn(*(arr[..., i] for i in range(self.size))) + np.zeros(arr.shape[:-1])
        return float(out) if arr.ndim == 1 else out

    # ------------------------------------------------------------------ python-control
    def to_nlsys(self, *, name: str | None = None):
        """The observer as a python-control ``NonlinearIOSystem``, for ``control.interconnect``.

        The system is the continuous-time observer ODE (:meth:`derivative`; seed 000 eq. (8)-(9), seed 001
        eq. (3.4) for the adaptive observer): inputs :attr:`signal_names` (``y``, the external signals, the
        inputs ``u``), states :attr:`state_names`, outputs the estimate ``<state>_hat`` and, for a switched
        observer of a model with an ``[original]`` table (``switchobs transform``), the original coordinates
        ``<name>_hat = phi^-1(xhat)``.  python-control integrates it with its own solver (``solve_ivp``), not
        with :attr:`method`: it agrees with :meth:`run` up to the discretisation error of the steps.

        Parameters
        ----------
        name : str, optional
            System name (default ``<model>-observer``).

        Returns
        -------
        control.NonlinearIOSystem

        Raises
        ------
        ObserverInputError
            During a simulation, at signals the observer refuses (e.g. ``vx <= 0`` of abs-xbs3).

        Examples
        --------
        >>> from switchobs.observers import xbs3_observer
        >>> sys = xbs3_observer(60.0, 60.0).to_nlsys()
        >>> sys.input_labels, sys.output_labels
        (['y', 'vx', 'u'], ['z1_hat', 'z2_hat', 'z3_hat'])
        """
        import control

        outputs = [f"{s}_hat" for s in self.state_names]
        original = self.model.original if not self.unknown else ()
        if original:
            symbols = [self.model.symbols[n] for n in (*self.model.states, *self.signal_names)]
            values = {self.model.symbols[k]: v for k, v in self.values.items() if k in self.model.symbols}
            inverse = sp.lambdify(symbols, [e.xreplace(values) for _, e in original], "math")
            outputs += [f"{k}_hat" for k, _ in original]
        n = len(self.model.states)

        def update(t, x, u, params):   # noqa: ARG001 - time-invariant, no python-control parameters
            return self.derivative(x, u)

        def output(t, x, u, params):   # noqa: ARG001
            if not original:
                return np.array(x, dtype=float)
            return np.concatenate([x, inverse(*x[:n], *u)])

        return control.nlsys(update, output, inputs=list(self.signal_names), outputs=outputs,
                             states=list(self.state_names), name=name or f"{self.model.name}-observer")

    # ------------------------------------------------------------------ output
    def to_json(self) -> dict[str, Any]:
        """Plain-JSON description (model, gains, discretisation, layouts, error codes)."""
        return {
            "kind": type(self).__name__,
            "model": self.model.name,
            "method": self.method,
            "state_names": list(self.state_names),
            "signal_names": list(self.signal_names),
            "parameters": dict(self.values),
            "K_plus": self.K_plus.tolist(),
            "K_minus": self.K_minus.tolist(),
            "unknown": list(self.unknown),
            "Gamma": self.Gamma.tolist(),
            "readout": self._readout_text,
            "h_max": None if self.h_max is None else str(self.h_max),
            "max_substeps": self.max_substeps,
            "error_codes": {c.name: int(c) for c in REFERENCE_STATUSES},
            "spec": self.spec.to_json(),
        }

    @classmethod
    def from_json(cls, data: Any) -> "_Observer":
        """The observer of :meth:`to_json`, rebuilt from its ``spec`` (model, gains and values exact), its
        method, readout and sub-step bound, as an unpickled observer is.

        Raises
        ------
        SimulationError
            Another observer class, or no ``spec``.
        ModelError
            A spec the model rejects.
        """
        if not isinstance(data, Mapping) or data.get("kind") != cls.__name__ or "spec" not in data:
            raise SimulationError(f"a {cls.__name__} JSON needs kind {cls.__name__!r} and its 'spec' "
                                  f"({cls.__name__}.to_json writes them), got {data!r:.80}")
        bound = None if data.get("h_max") is None else (Fraction(data["h_max"]), int(data["max_substeps"]))
        return cls._from_spec(ObserverSpec.from_json(data["spec"]), str(data["method"]), data.get("readout"), bound)

    def __str__(self) -> str:
        lines = [f"{type(self).__name__} of model {self.model.name!r} ({self.method}, ZOH signals "
                 f"{', '.join(self.signal_names)})",
                 f"  state: {', '.join(self.state_names)}",
                 f"  K_plus  = {np.array2string(self.K_plus, precision=6)}",
                 f"  K_minus = {np.array2string(self.K_minus, precision=6)}"]
        if self.unknown:
            lines.append(f"  estimated: {', '.join(self.unknown)}, Gamma = {self.Gamma.tolist()}")
        if self._readout_text:
            lines.append(f"  readout: {self._readout_text}")
        if self.h_max is not None:
            lines.append(f"  sub-steps: |s|*dt <= h_max = {self.h_max} per step, at most {self.max_substeps}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.model.name} {self.method} n={self.size}>"




class SwitchedObserver(_Observer):
    """The switched observer of a model ``dz/dt = s(y,t)(A z + d(y)) + b(y) u``, ``y = C z``.

    .. math::

        \\dot{\\hat z} = s(y)\\,\\bigl(A\\hat z + d(y) + K(y)\\,(y - C\\hat z)\\bigr) + b(y)\\,u,
        \\qquad K = K_+ \\text{ if } s > 0,\\; K_- \\text{ otherwise},

    so that in the rescaled time ``tau = ∫|s| dt`` the error ``e = z - zhat``
    obeys ``de/dtau = A_plus e`` (s > 0) or ``A_minus e`` (s < 0), with
    ``A_plus = A - K_plus C`` and ``A_minus = -A + K_minus C``.  The correction
    ``s K(s) (y - C zhat)`` is continuous through ``s = 0`` (it vanishes there
    from both sides), as ``k_i(z1) z1 (z1 - zhat1)`` in seed 000.

    Parameters
    ----------
    model : Model
        Any switchobs model (built-in or TOML).  Parameters take the model's
        :attr:`~switchobs.model.Model.values` unless overridden by ``params``;
        none may be left free.
    K_plus, K_minus : GainDesign, or array_like or sympy.Matrix of length n
        The design (``design_gains(model, spectrum)``, evaluated at the
        observer's parameter values; its design symbols need values, e.g.
        with :meth:`GainDesign.at`) with ``K_minus`` omitted, or two numeric gains.
    params : mapping, optional
        Parameter values overriding the model's (numbers or fraction strings).
    method : {"radau3", "midpoint", "rk4", "euler"}, optional
        One step per ``dt`` with the signals held constant: 2-stage Radau IIA
        (the default, :func:`switchobs.spec.default_method`) or the implicit
        midpoint rule (``x + dt D(Z)^-1 F(Z) f(x)``, ``Z = dt (s A - g C)``;
        both certified for every step length by
        ``switchobs.certify.discrete_certificate``), classic RK4 or forward
        Euler (no step bound is a certificate for them: n >= 3 for rk4,
        n >= 2 for euler).  The implicit methods take n <= 12
        (:data:`switchobs.spec.IMPLICIT_MAX_N`); above, the default is rk4 (bound it with ``h_max``).
    readout : str, optional
        An expression in the state names and parameters evaluated by
        :meth:`readout` (e.g. ``"z2"``, the XBS estimate of abs-xbs3).
    h_max : number, Fraction or str, optional
        Certified bound on the step ``h = |s| dt`` in the rescaled time (e.g.
        the ``h_max`` of a discrete certificate): a step with ``|s| dt`` above
        it (rounded down to a double) is split into ``ceil(|s| dt / h_max)``
        sub-steps of ``dt / n``, signals held -- the arithmetic of the generated
        C with ``--h-max``.  None (default): one step per ``dt``.
    max_substeps : int, optional
        Most sub-steps per step (default 64, only with ``h_max``); a step
        needing more is refused with ``ErrorCode.SUBSTEP_LIMIT``.

    Raises
    ------
    FreeSymbolError
        A parameter has no value.
    ModelError
        The time scaling depends on ``t`` explicitly.
    DimensionError, SimulationError
        Gains of the wrong length or not finite; unknown ``method``.

    References
    ----------
    seed 000 eq. (8)-(9) and (13); seed 004 (observer and Theorem 1).

    Examples
    --------
    >>> from switchobs.design import design
    >>> from switchobs.model import builtin_model
    >>> model = builtin_model("abs-xbs3")
    >>> g = design(model, "-beta1,-beta2,-beta2").at({"beta1": 10, "beta2": 20})
    >>> obs = SwitchedObserver(model, g, readout="z2")
    >>> obs.signal_names
    ('y', 'vx', 'u')
    >>> x = obs.step([0.0, 0.5, 0.0], [10.0, 20.0, 0.0], 1e-3)
    >>> x.round(6).tolist()
    [0.36948, 0.412037, -0.10469]
    >>> round(obs.readout(x), 6)
    0.412037
    """

    def __init__(self, model: Model, K_plus: GainDesign | Any, K_minus: Any = None, *,
                 params: Mapping[str, Any] | None = None, method: str | None = None, readout: str | None = None,
                 h_max: Any = None, max_substeps: int | None = None):
        method = default_method(model.n) if method is None else method
        super().__init__(model, K_plus, K_minus, params=params, method=method, readout=readout,
                         unknown=(), Gamma=None, h_max=h_max, max_substeps=max_substeps)


class AdaptiveSwitchedObserver(_Observer):
    """The switched adaptive observer of seed 001 eq. (3.4), for any model linear in the unknowns.

    With ``theta`` the parameters named in ``unknown`` (which may appear only
    in ``d(y)`` and ``b(y)``, linearly), ``s d(y) + b(y) u = c(y, u) + Psi(y, u) theta``
    and (seed 001 eq. (3.4a)-(3.4c), with ``K(t, y) = s K'(y)`` of (3.8) and the
    switched ``K'`` of (3.15))::

        dw/dt      = s A w + c + Psi theta_hat + (s K(s) + Upsilon Gamma Upsilon' C') (y - C w)
        dtheta/dt  = Gamma Upsilon' C' (y - C w)
        dUpsilon/dt = (s A - s K(s) C) Upsilon + Psi

    The state is ``(w, theta_hat, Upsilon)`` with ``Upsilon`` (n x p) stored
    row-major (:attr:`state_names`).  For abs-adaptive2, ``Psi`` is the matrix
    of seed 001 eq. (3.3).

    Parameters
    ----------
    model : Model
    K_plus, K_minus : GainDesign, or array_like of length n
        A design (``K_minus`` omitted), or the gains ``K'`` for ``y > 0`` and ``y < 0`` (seed 001 (3.15); (3.20)
        asks ``k1- = -k1+ > ... `` see :func:`adaptive_xbs_observer`).
    unknown : sequence of str
        Parameters to estimate (``("c", "d")`` for abs-adaptive2).
    Gamma : array_like, p x p (or its diagonal)
        Symmetric positive definite adaptation gain.
    method : {"rk4", "euler"}
        The explicit step methods only: the right-hand side multiplies the
        estimates (``Upsilon theta_hat``), it is not affine in the state, so the
        certified implicit steps of :class:`SwitchedObserver` do not apply and
        the default stays classic RK4 (bound the step with ``h_max``).
    params, readout, h_max, max_substeps
        As for :class:`SwitchedObserver`; ``readout`` may use the estimated
        parameters by name (they denote the estimates).

    Raises
    ------
    ModelError
        An unknown parameter appears in A, C or s, or not linearly.
    SimulationError, DimensionError
        Gamma not symmetric positive definite, wrong shapes.

    References
    ----------
    seed 001 eq. (3.2)-(3.5), (3.8), (3.15), (3.20), Propositions 1-2.
    """

    def __init__(self, model: Model, K_plus: GainDesign | Any, K_minus: Any = None, *, unknown: Sequence[str],
                 Gamma: Any, params: Mapping[str, Any] | None = None, method: str = "rk4",
                 readout: str | None = None, h_max: Any = None, max_substeps: int | None = None):
        if isinstance(unknown, str) or not unknown:
            raise ModelError(f"unknown must be a non-empty list of parameter names, got {unknown!r}")
        super().__init__(model, K_plus, K_minus, params=params, method=method, readout=readout,
                         unknown=unknown, Gamma=Gamma, h_max=h_max, max_substeps=max_substeps)
