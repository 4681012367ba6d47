"""Generation of the C observer: discretisation, C API, header, README.

The observer ODE is discretised with one step of classic fourth-order
Runge-Kutta, the signals (y, external signals, inputs) held constant over the
step (zero-order hold), or with forward Euler on request:

    h = dt/2, k1 = f(x), k2 = f(x + h k1), k3 = f(x + h k2), k4 = f(x + dt k3),
    x+ = x + dt/6 (k1 + 2 k2 + 2 k3 + k4)

With the signals held, the observer is an affine ODE with constant
coefficients over the step, so RK4 is the fourth-order Taylor polynomial of
its exact flow: error O(dt^5) per step, stable for ``|s| dt |lambda| < 2.78``
on the real axis (Euler: first order, ``< 2``), a fixed count of operations,
no iteration and no allocation -- what a brake ECU wants -- and the same
scheme as the Python reference observers, so that the two agree to rounding.

The implicit midpoint rule and 2-stage Radau IIA (switched observer only, whose
held-signal right-hand side ``f = J x + c``, ``J = s A - g C``, is affine) step
``x+ = x + dt D(Z)^-1 F(Z) f(x)``, ``Z = dt J`` (``switchobs.spec.implicit_increment``
on casadi SX: cofactors, one division by ``det D(Z)`` made safe); the kernel
returns ``det D(Z)`` after the new state and the step refuses ``|det D(Z)| <
DET_FLOOR`` or a non-finite one (``NONFINITE_RESULT``).  With declared ranges the
kernel returns ``det D(Z)`` and the undivided solve, and the step divides after
that check (the proved build, :mod:`switchobs.codegen._proof`).  They keep the design's Lyapunov function decreasing at
every step length, so they need no step bound.

With a certified step bound ``h_max`` (in the rescaled time ``tau = ∫|s| dt``,
where the signals-held step is ``h = |s| dt``), a step whose ``|s| dt``
exceeds ``H_MAX`` is split into ``n = ceil(|s| dt / H_MAX)`` sub-steps of
``dt / n`` with the same held signals (at most ``MAX_SUBSTEPS``, else the
status ``SUBSTEP_LIMIT``), so that every step the C takes is one the discrete
certificate covers.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import casadi as ca
import numpy as np
import sympy as sp

from ..design import GainDesign
from .._validate import adaptation_gain, round_down, substep_bound
from ..exceptions import CodegenError, DimensionError, ModelError
from ..model import Model, numeric, rational_value
from ..spec import (METHODS, STATUS_TEXT, STEP_METHODS, Guard, ObserverSpec, StepStatus,
                    default_method, require_explicit)
from ._emit import CFunction, float_literal, kernel
from ._observer import GeneratedObserver
from ._readme import readme
from ._text import c_comment
from ._translate import (GUARD_TESTS, Translation, translate_adaptive, translate_original, translate_super_twisting,
                         translate_vehicle_speed,
                         translate_switched)

__all__ = ["GeneratedObserver", "generate_observer", "generate_super_twisting", "generate_vehicle_speed",
           "default_prefix", "REALS", "METHODS"]

REALS = ("double", "float")
#: The macro that switches on the branch hints of every generated file (clang only; MISRA C:2012 rule 1.2).
BRANCH_HINTS = "SWITCHOBS_BRANCH_HINTS"

#: Per method: the discretisation as the header states it, the step's name in the source comment.
_SCHEMES = {
    "rk4": ("classic RK4", "RK4"),
    "euler": ("forward Euler", "Euler"),
    "midpoint": ("implicit midpoint rule, x+ = x + dt (I - Z/2)^-1 f(x) with Z = dt J, J = s A - g C "
                 "(1-stage Gauss, order 2, A-stable)", "implicit midpoint"),
    "radau3": ("2-stage Radau IIA, x+ = x + dt (I - 2Z/3 + Z^2/6)^-1 (I - Z/6) f(x) with Z = dt J, J = s A - g C "
               "(order 3, L-stable)", "Radau IIA"),
}

_C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if inline int long "
    "register restrict return short signed sizeof static struct switch typedef union unsigned void volatile "
    "while _Bool _Complex _Imaginary".split())


def default_prefix(model_name: str) -> str:
    """``switchobs_<model>`` with every run of characters that are not C identifier characters turned into one
    ``_`` (casadi's function names allow no ``__`` and no trailing ``_``: ``"café x"`` gives ``switchobs_caf_x``)."""
    return ("switchobs_" + re.sub(r"[^A-Za-z0-9]+", "_", model_name)).rstrip("_")


def _check_options(real: str, method: str) -> None:
    if real not in REALS:
        raise CodegenError(f"real must be one of {list(REALS)}, got {real!r}")
    if method not in METHODS:
        raise CodegenError(f"method must be one of {list(METHODS)}, got {method!r}")


def _check_prefix(prefix: str) -> str:
    # the C function names are the prefix and a suffix such as "_kernel": casadi refuses "__" in them
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9]*(_[A-Za-z0-9]+)*", prefix or ""):
        raise CodegenError(f"prefix {prefix!r} is not a C identifier of the generated API (a letter, then letters, "
                           "digits or single '_' between them)")
    if prefix in _C_KEYWORDS:
        raise CodegenError(f"prefix {prefix!r} is a C keyword; choose another with --prefix")
    return prefix


def _macro_names(kind: str, names: Sequence[str]) -> list[str]:
    upper = [n.upper() for n in names]
    clash = sorted({u for u in upper if upper.count(u) > 1})
    if clash:
        dup = [n for n in names if n.upper() in clash]
        raise CodegenError(f"the {kind} names {dup} give the same C macro name(s) {clash}; rename them in the model")
    return upper


# ----------------------------------------------------------------------------- inputs
def _gains(model: Model, gains: Any, values: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(gains, GainDesign):
        return gains.gains_for(model, values)
    try:
        Kp, Km = gains
    except (TypeError, ValueError):
        raise CodegenError("gains must be a GainDesign or a pair (K_plus, K_minus) of number sequences, "
                           f"got {type(gains).__name__}") from None
    out = []
    for name, K in (("K_plus", Kp), ("K_minus", Km)):
        if isinstance(K, sp.MatrixBase):
            arr = numeric(K, values, what=name).reshape(-1)
        else:
            try:
                arr = np.asarray(K, dtype=float).reshape(-1)
            except (TypeError, ValueError):
                raise DimensionError(f"{name} must be {model.n} numbers, got {K!r}") from None
        if arr.shape != (model.n,):
            raise DimensionError(f"{name} has {arr.size} entries but model {model.name!r} has dimension {model.n}")
        if not np.all(np.isfinite(arr)):
            raise CodegenError(f"{name} = {arr.tolist()} is not finite")
        out.append(arr)
    return out[0], out[1]


def _defaults(model: Model, values: Mapping[str, Any], extra_names: Sequence[str]) -> dict[str, sp.Rational]:
    """Default of every model parameter: the model's values, overridden by ``values``."""
    unknown = sorted(set(values) - set(model.parameters) - set(extra_names))
    if unknown:
        raise ModelError(f"values given for {unknown}, which are neither parameters of model {model.name!r} "
                         f"({list(model.parameters)}) nor design symbols ({list(extra_names)})")
    overrides = {k: v for k, v in values.items() if k in model.parameters}
    model.with_values(overrides)  # validates the overrides (finite numbers, declared signs)
    merged = {**model.values, **{k: rational_value(v, what=k) for k, v in overrides.items()}}
    missing = [p for p in model.parameters if p not in merged]
    if missing:
        raise ModelError(f"parameter(s) {missing} of model {model.name!r} have no value; every parameter is a "
                         "runtime parameter of the C observer and needs a default value")
    return {p: merged[p] for p in model.parameters}


# ----------------------------------------------------------------------------- assembly
def _step_expression(tr: Translation, method: str, *, split: bool = False) -> ca.SX:
    """The step ``x_next``; for an implicit method ``(x_next, det D(Z))``, or with ``split`` (the proved
    build) ``(det D(Z), numerators)``: the undivided solve, which the step divides after its check of ``det``.

    Without ranges the division stays in the kernel, by ``det`` where it is nonzero (else by 1), and the
    step refuses ``|det| < DET_FLOOR``: divided outside, abs-xbs4's radau3 step was 1.1-1.15x slower with
    gcc 12 -O2, and the floor tested in the kernel too (``if_else(|det| >= DET_FLOOR, det, 1)``) 1.08x
    slower on abs-xbs3 float (``benchmarks/_codegen_against.py``); the step refuses those steps anyway.
    """
    if tr.advance is not None:
        return tr.advance(method)
    if not STEP_METHODS[method].explicit:
        num, det = tr.implicit(method)
        if split:
            return ca.vertcat(det, num)
        return ca.vertcat(tr.x + tr.dt * (num * (1.0 / ca.if_else(det != 0, det, 1))), det)
    x, dt = tr.x, tr.dt
    k1 = tr.rhs(x)
    if method == "euler":
        return x + dt * k1
    h = 0.5 * dt
    dt6 = dt / 6.0
    k2 = tr.rhs(x + h * k1)
    k3 = tr.rhs(x + h * k2)
    k4 = tr.rhs(x + dt * k3)
    return x + dt6 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def _guard_value(guard: Guard, expr: ca.SX, tr: Translation, index: int, real: str,
                 prefix: str, P: str) -> tuple[str, CFunction | None]:
    """C expression of the guard value; a kernel when it is more than one signal or parameter."""
    if guard.expr.is_Symbol:
        name = guard.expr.name
        if name in tr.param_names:
            return f"par[{P}_P_{name.upper()}]", None
        if name in tr.signal_names:
            return f"sig[{P}_S_{name.upper()}]", None
    k = kernel(f"{prefix}_guard{index}", [("sig", tr.signals), ("par", tr.params)], expr, real=real, prefix=prefix)
    return "g", k


@dataclass(frozen=True)
class _Info:
    """What the files say about the observer besides its numbers."""

    name: str
    description: str
    equations: tuple[str, ...]
    signal_roles: tuple[str, ...]
    references: Mapping[str, str]


def _model_info(model: Model, kind: str) -> _Info:
    s = model.time_scale
    if kind == "adaptive":
        eq = ("switched adaptive observer (seed 001 eq. (3.4)): with g = s K(s), e = y - C w, r = Upsilon' C',",
              "q = Gamma r:  w' = s A w + c + Psi theta + (g + Upsilon q) e,  theta' = q e,",
              f"Upsilon' = s A Upsilon - g r' + Psi,  where c + Psi theta = s d + b u,  s = {s}.")
    else:
        eq = (f"dzhat/dt = s (A zhat + d(y) + K (y - C zhat)) + b(y) u,  s = {s},",
              "K = K_plus where s > 0, K_minus otherwise (the correction s K e is continuous at s = 0).")
    y = sum((c * model.symbols[z] for c, z in zip(model.C, model.states)), sp.Integer(0))
    roles = [f"measured output {model.output} = {sp.sstr(y)}"]
    for name in model.external:
        sym = model.symbols[name]
        roles.append("external signal" + (" (> 0)" if sym.is_positive else " (< 0)" if sym.is_negative else ""))
    roles += ["input"] * len(model.inputs)
    return _Info(name=model.name, description=model.description or "user model", equations=eq,
                 signal_roles=tuple(roles), references=dict(model.references))


def _substep_check(tr: Translation, real: str, prefix: str, P: str) -> list[str]:
    """C lines choosing the sub-steps: ``a = |s| dt`` (the step in tau), ``n``, ``h = dt / n``.

    The non-stiff path costs a multiplication and two comparisons (bound, sub-step loop); the Python
    reference (``switchobs.observers``) makes the same float operations
    (``a <= H_MAX``, else ``n = ceil(a / H_MAX)``), so both choose the same ``n``.
    """
    f = "f" if real == "float" else ""
    scale = f"fabs{f}(s)" if not tr.scale.is_constant() else float_literal(abs(float(tr.scale)), real)
    return [f"    a = {scale} * dt;  /* this step in the rescaled time tau */",
            f"    if (!(a <= {P}_H_MAX)) {{",
            f"        {prefix}_real q = a / {P}_H_MAX;",
            _refuse(P, f"!(q <= ({prefix}_real){P}_MAX_SUBSTEPS)", "SUBSTEP_LIMIT", indent="        "),
            f"        n = (int32_t)ceil{f}(q);",
            f"        h = dt / ({prefix}_real)n;",
            "    }"]


def _refuse(P: str, test: str, status: str, comment: str | None = None, indent: str = "    ", *,
            hint: bool = True) -> str:
    """``if (test) { return <P>_ERR_<status>; }``, braced (MISRA C:2012 rule 15.6); ``hint``: the test is
    marked unlikely (``<P>_UNLIKELY``, the checks of the step)."""
    note = "" if comment is None else f"  /* {c_comment(comment)} */"
    cond = f"{P}_UNLIKELY({test})" if hint else test
    return f"{indent}if ({cond}) {{\n{indent}    return {P}_ERR_{status};{note}\n{indent}}}"


def _check_ranges(ranges: Mapping[str, Any] | None, tr: Translation, real: str) -> dict[str, tuple[float, float]]:
    """The declared ranges by name (states, signals, parameters, ``dt``), each ``[lo, hi]`` as ``real`` rounds it.

    A range is a pair of finite numbers ``lo < hi`` (``dt``: ``lo > 0``) of a name of the observer.
    """
    out: dict[str, tuple[float, float]] = {}
    known = (*tr.state_names, *tr.signal_names, *tr.param_names, "dt")
    dtype = np.float32 if real == "float" else np.float64
    for name, value in (ranges or {}).items():
        if name not in known:
            raise CodegenError(f"range of {name!r}: not a state, signal or parameter of the observer, nor dt "
                               f"(names: {', '.join(known)})")
        try:
            lo, hi = (float(v) for v in value)
        except (TypeError, ValueError):
            raise CodegenError(f"range of {name!r} must be two numbers lo, hi, got {value!r}") from None
        lo_c, hi_c = float(dtype(lo)), float(dtype(hi))
        if not (np.isfinite(lo_c) and np.isfinite(hi_c) and lo_c < hi_c):
            raise CodegenError(f"range of {name!r} = [{lo!r}, {hi!r}] must be finite numbers lo < hi in {real}")
        if name == "dt" and not lo_c > 0.0:
            raise CodegenError(f"range of dt = [{lo!r}, {hi!r}] must have lo > 0 (seconds)")
        out[name] = (lo_c, hi_c)
    return out


def _assemble(tr: Translation, *, info: _Info, kind: str, real: str, method: str, prefix: str,
              command: str | None, bound: tuple[Fraction, int] | None = None,
              certificate: str | None = None,
              original: tuple[tuple[str, ...], ca.SX] | None = None,
              ranges: Mapping[str, Any] | None = None) -> GeneratedObserver:
    if kind == "adaptive":
        require_explicit(method, "the adaptive observer's right-hand side", CodegenError)
    if method not in tr.methods:
        raise CodegenError(f"the {kind} observer admits only method {list(tr.methods)}, got {method!r}")
    # every text of the user's that the files print passes the one gate, here
    info = _Info(name=c_comment(info.name), description=c_comment(info.description),
                 equations=tuple(map(c_comment, info.equations)), signal_roles=tuple(map(c_comment, info.signal_roles)),
                 references={c_comment(k): c_comment(v) for k, v in info.references.items()})
    command = None if command is None else c_comment(command)
    certificate = None if certificate is None else c_comment(certificate)
    P = prefix.upper()
    x_macros = _macro_names("state", tr.state_names)
    s_macros = _macro_names("signal", tr.signal_names)
    p_macros = _macro_names("parameter", tr.param_names)
    rng = _check_ranges(ranges, tr, real)
    det_floor = None if STEP_METHODS[method].explicit else STEP_METHODS[method].det_floor(len(tr.state_names))
    step_expr = _step_expression(tr, method, split=bool(rng))
    inputs = [("x", tr.x), ("sig", tr.signals), ("par", tr.params), ("dt", tr.dt)]
    if tr.s is not None and tr.scale.is_constant():  # a constant time scaling needs no check: fold it in
        step_expr = ca.substitute(step_expr, tr.s, tr.scale)
    elif tr.s is not None:
        inputs.append(("s", tr.s))
    step_k = kernel(f"{prefix}_kernel", inputs, step_expr, real=real, prefix=prefix, scalars=("dt", "s"))
    kernels = [step_k]
    if tr.scale.is_constant():
        scale_check: list[str] = []
    else:
        scale_k = kernel(f"{prefix}_scale", [("sig", tr.signals), ("par", tr.params)], tr.scale, real=real,
                         prefix=prefix)
        kernels.append(scale_k)
        scale_check = ["    " + scale_k.call("&s", sig="sig", par="par"),
                       _refuse(P, "!isfinite(s)", "UNDEFINED_TIME_SCALE", "s must be finite")]
    h_max_c = None
    if bound is not None:
        # after s is known and before the domain of d and b: the order of the Python reference's checks
        scale_check += _substep_check(tr, real, prefix, P)
        h_max_c = round_down(bound[0], real, error=CodegenError)
    checks: list[str] = []
    param_checks: list[str] = []  # the original coordinates use the parameters too: the same sign checks
    scale_done = False
    for i, (guard, expr) in enumerate(tr.guards):
        if guard.status != StepStatus.UNDEFINED_TIME_SCALE and guard.status != StepStatus.BAD_PARAM \
                and not scale_done:
            checks += scale_check
            scale_done = True
        value, k = _guard_value(guard, expr, tr, i, real, prefix, P)
        if k is not None:
            kernels.append(k)
            checks.append("    " + k.call("&g", sig="sig", par="par"))
        test = GUARD_TESTS[guard.kind].format(g=value, zero=float_literal(0.0, real))
        checks.append(_refuse(P, f"!({test})", guard.status.name, guard.reason))
        if guard.status == StepStatus.BAD_PARAM:
            param_checks += checks[-2:] if k is not None else checks[-1:]
    if not scale_done:
        checks += scale_check

    full = step_expr if tr.s is None else ca.substitute(step_expr, tr.s, tr.scale)
    x_next = full[:len(tr.state_names)]
    if not STEP_METHODS[method].explicit and rng:  # the step's division, after its check of det
        x_next = tr.x + tr.dt * (full[1:] * (1.0 / full[0]))
    step_fn = ca.Function(f"{prefix}_step", [tr.x, tr.signals, tr.params, tr.dt], [x_next],
                          ["x", "signals", "params", "dt"], ["x_next"])
    # kernel temporaries, the state _run holds and the new state, s, one guard value
    stack_reals = max(k.temporaries for k in kernels) + 2 * len(tr.state_names) + 2
    if not STEP_METHODS[method].explicit:  # det D(Z) after the solve
        stack_reals += 1
    if bound is not None:  # the sub-step's input state, a, q, h
        stack_reals += len(tr.state_names) + 3
    original_names = () if original is None else original[0]
    original_k = None if original is None else kernel(
        f"{prefix}_original_kernel", [("x", tr.x), ("sig", tr.signals), ("par", tr.params)], original[1], real=real,
        prefix=prefix)
    text_args = dict(tr=tr, info=info, kind=kind, real=real, method=method, prefix=prefix, P=P,
                     original_names=original_names, o_macros=_macro_names("original state", original_names),
                     x_macros=x_macros, s_macros=s_macros, p_macros=p_macros, command=command,
                     temporaries=step_k.temporaries, stack_reals=stack_reals, bound=bound, h_max_c=h_max_c,
                     certificate=certificate, ranges=rng, det_floor=det_floor)
    header = _header(**text_args)
    source = _source(kernels=kernels, checks=checks, original_k=original_k, param_checks=param_checks, **text_args)
    gen = GeneratedObserver(
        prefix=prefix, real=real, method=method, kind=kind, model_name=info.name, state_names=tr.state_names,
        signal_names=tr.signal_names, param_names=tr.param_names, default_params=tr.default_params,
        guards=tuple(g for g, _ in tr.guards), temporaries=step_k.temporaries, stack_reals=stack_reals,
        header=header, source=source, readme="", casadi_version=ca.__version__, description=info.description,
        equations=info.equations, signal_roles=info.signal_roles, references=dict(info.references),
        h_max=None if bound is None else bound[0], h_max_c=h_max_c, max_substeps=None if bound is None else bound[1],
        certificate=certificate, original_names=tuple(original_names), ranges=rng, det_floor=det_floor,
        step_function=step_fn)
    return dataclasses.replace(gen, readme=readme(gen, command=command))


def generate_observer(model: Model, gains: GainDesign | tuple[Sequence[float], Sequence[float]], *,
                      values: Mapping[str, Any] | None = None, real: str = "double", method: str | None = None,
                      prefix: str | None = None, unknown: Sequence[str] = (),
                      Gamma: Sequence[Sequence[float]] | np.ndarray | None = None,
                      h_max: float | Fraction | str | None = None, max_substeps: int | None = None,
                      certificate: str | None = None, command: str | None = None,
                      ranges: Mapping[str, tuple[float, float]] | None = None) -> GeneratedObserver:
    """Generate the C observer of a model and its gain pair.

    Parameters
    ----------
    model : Model
        Any built-in or TOML model; every parameter stays a runtime parameter.
    gains : GainDesign or (K_plus, K_minus)
        The designed gains (``switchobs.design.design``) or two sequences of
        ``n`` numbers.  They become the runtime parameters ``K_plus_<state>``
        and ``K_minus_<state>`` with these defaults.
    values : mapping, optional
        Values of design symbols (``beta1``...) and overrides of the model's
        parameter values (defaults of the runtime parameters).
    real : {"double", "float"}
    method : {"radau3", "midpoint", "rk4", "euler"}, optional
        2-stage Radau IIA, the implicit midpoint rule, classic RK4 or forward Euler, signals held over the step.
        The implicit methods (switched observer only) solve ``D(Z) v = F(Z) f(x)``, ``Z = dt J``, by
        cofactors; a singular ``D(Z)`` returns ``NONFINITE_RESULT``.  They keep the design's continuous
        Lyapunov matrix decreasing at every step length (``switchobs.certify.discrete_certificate``).
        Default :func:`switchobs.spec.default_method`: radau3; rk4 with ``unknown`` (the adaptive observer
        takes the explicit methods only) and for more than ``IMPLICIT_MAX_N`` states.
    prefix : str, optional
        C prefix; default ``switchobs_<model>`` (:func:`default_prefix`).
    unknown : sequence of str, optional
        Parameters estimated online: generates the switched adaptive observer
        of seed 001 eq. (3.4) with state ``(w, theta_hat, Upsilon)``.
    Gamma : (p, p) array or its diagonal, optional
        Adaptation gain of (3.4b), symmetric positive definite, required with
        ``unknown``; its entries are runtime parameters ``Gamma_<u>_<v>``.
    h_max : number, Fraction or str, optional
        Certified bound on the step ``h = |s| dt`` in rescaled time (e.g. the
        ``h_max`` of a discrete certificate).  The step splits ``dt`` into
        ``ceil(|s| dt / H_MAX)`` sub-steps when ``|s| dt > H_MAX``, where
        ``<PREFIX>_H_MAX`` is ``h_max`` rounded *down* to ``real``.  None (the
        default): one step per ``dt``, no bound.
    max_substeps : int, optional
        ``<PREFIX>_MAX_SUBSTEPS`` (default 64, only with ``h_max``): a step
        needing more returns ``SUBSTEP_LIMIT`` with the state unchanged; it
        bounds the worst-case time of one step.
    certificate : str, optional
        Statement of a discrete certificate proved for this design and method, recorded in the files.
    command : str, optional
        Command line recorded in the files' comments.
    ranges : mapping name -> (lo, hi), optional
        Declared ranges of states, signals, parameters and ``dt`` (name ``dt``, seconds), on top of the
        model's ``[ranges]`` (:attr:`switchobs.model.Model.ranges`): the step refuses a
        value outside its range (``STATE_RANGE``, also for a new state outside it, ``SIGNAL_RANGE``,
        ``BAD_PARAM``, ``BAD_DT``).  With a range for every one of them the step is proved free of run-time
        errors by Frama-C EVA (:func:`switchobs.codegen.prove`, driver ``<prefix>_proof.c``).

    Returns
    -------
    GeneratedObserver

    Raises
    ------
    CodegenError
        Unsupported expression, bad prefix, clashing C names, explicit time dependence, a malformed range.
    ModelError, FreeSymbolError, DimensionError
        Missing parameter values or design symbols, wrong gain sizes.

    References
    ----------
    seed 000 eq. (8)-(9) (observer), Sec. III-E and IV-D (gains); seed 001
    eq. (3.4), (3.8), (3.15) (adaptive observer); seed 004 (time rescaling).

    Examples
    --------
    >>> from switchobs.model import builtin_model
    >>> from switchobs.design import design
    >>> m = builtin_model("abs-xbs3")
    >>> gen = generate_observer(m, design(m, "-40,-60,-60"))
    >>> gen.prefix, gen.nx, gen.ns, gen.np
    ('switchobs_abs_xbs3', 3, 3, 9)
    """
    unknown = tuple(unknown)
    if method is None:
        method = default_method(model.n, affine=not unknown)
    _check_options(real, method)
    prefix = _check_prefix(default_prefix(model.name) if prefix is None else prefix)
    bound = substep_bound(h_max, max_substeps, error=CodegenError)
    values = dict(values or {})
    design_syms = [s.name for s in gains.design_symbols] if isinstance(gains, GainDesign) else []
    defaults = _defaults(model, values, design_syms)
    num_values = {**{k: v for k, v in values.items() if k not in model.parameters},
                  **{k: float(v) for k, v in defaults.items()}}
    Kp, Km = _gains(model, gains, num_values)
    if unknown:
        G = tuple(map(tuple, adaptation_gain(Gamma, unknown, error=CodegenError).tolist()))
    elif Gamma is not None:
        raise CodegenError("Gamma is only used by the adaptive observer; give the unknown parameters too")
    else:
        G = ()
    spec = ObserverSpec(model, tuple(map(float, Kp)), tuple(map(float, Km)), values=defaults, unknown=unknown,
                        Gamma=G)
    original = None
    if unknown:
        tr = translate_adaptive(spec)
        kind = "adaptive"
    else:
        tr = translate_switched(spec)
        kind = "switched"
        if model.original:
            original = (tuple(name for name, _ in model.original), translate_original(model, tr))
    return _assemble(tr, info=_model_info(model, kind), kind=kind, real=real, method=method, prefix=prefix,
                     command=command, bound=bound, certificate=certificate, original=original,
                     ranges={**model.ranges, **(ranges or {})})


def generate_super_twisting(lam: float, alpha: float, *, real: str = "double",
                            prefix: str = "switchobs_super_twisting", command: str | None = None,
                            ranges: Mapping[str, tuple[float, float]] | None = None) -> GeneratedObserver:
    """Generate the C super-twisting observer of seed 003 eq. (8)-(9), Euler scheme (13).

    Parameters
    ----------
    lam, alpha : float
        Gains of (9) (e.g. from ``switchobs.sensors.super_twisting_gains``, rule (12)); positive.
        They are runtime parameters ``lam`` and ``alpha``.
    real : {"double", "float"}
    prefix : str
    ranges : mapping name -> (lo, hi), optional
        Declared ranges of the states, signals, ``lam``, ``alpha`` and ``dt``, as for
        :func:`generate_observer`: with a range for every one of them the step is proved free of run-time errors.

    Returns
    -------
    GeneratedObserver
        Signals ``(x1, f1)`` (measured angle, known acceleration), state
        ``(x1_hat, x2_hat, z2)`` with ``z2`` the injection of the last step.

    References
    ----------
    seed 003 eq. (8), (9), (12), (13), (20).
    """
    _check_options(real, "euler")
    prefix = _check_prefix(prefix)
    for name, v in (("lam", lam), ("alpha", alpha)):
        if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
            raise CodegenError(f"{name} = {v!r} must be a finite number > 0 (seed 003 eq. (9))")
    info = _Info(name="super-twisting", description="wheel angle and speed from an angle sensor (seed 003)",
                 equations=("super-twisting observer (seed 003 eq. (8)-(9)), Euler scheme (13): e = x1 - x1_hat,",
                            "x1_hat' = x2_hat + lam |e|^(1/2) sign(e),  x2_hat' = f1 + alpha sign(e);",
                            "state entry z2 = alpha sign(e) is the injection of the last step (seed 003 eq. (20))."),
                 signal_roles=("measured angle x1 (rad)", "known acceleration f1 (rad/s^2)"),
                 references={"observer": "seed 003 eq. (8)-(9)", "discretisation": "seed 003 eq. (13)",
                             "gains": "seed 003 eq. (12)"})
    return _assemble(translate_super_twisting(lam, alpha), info=info, kind="super-twisting", real=real,
                     method="euler", prefix=prefix, command=command, ranges=ranges)


def generate_vehicle_speed(beta: float, *, real: str = "double", prefix: str = "switchobs_vehicle_speed",
                           command: str | None = None,
                           ranges: Mapping[str, tuple[float, float]] | None = None) -> GeneratedObserver:
    """Generate the C sliding-mode observer of the vehicle speed of seed 003 eq. (15), explicit Euler.

    Parameters
    ----------
    beta : float
        Gain of (15) (e.g. from ``switchobs.sensors.vehicle_speed_gain``, Theorem 3: ``beta > eta``); positive.
        A runtime parameter ``beta``.
    real : {"double", "float"}
    prefix : str
    ranges : mapping name -> (lo, hi), optional
        Declared ranges of the states, the signal, ``beta`` and ``dt``, as for :func:`generate_observer`.

    Returns
    -------
    GeneratedObserver
        Signal ``(x3,)`` (measured speed), state ``(x3_hat, z3)`` with ``z3`` the injection of the last step.

    References
    ----------
    seed 003 eq. (14)-(17), (21), Theorem 3.
    """
    _check_options(real, "euler")
    prefix = _check_prefix(prefix)
    if not (isinstance(beta, (int, float)) and np.isfinite(beta) and beta > 0):
        raise CodegenError(f"beta = {beta!r} must be a finite number > 0 (seed 003 eq. (15))")
    info = _Info(name="vehicle-speed", description="vehicle speed and its injection from a speed sensor (seed 003)",
                 equations=("sliding-mode observer of the vehicle speed (seed 003 eq. (15)), forward Euler:",
                            "x3_hat' = z3 = beta sign(x3 - x3_hat);",
                            "state entry z3 is the injection of the last step (seed 003 eq. (21))."),
                 signal_roles=("measured vehicle speed x3 (m/s)",),
                 references={"observer": "seed 003 eq. (15)", "gain": "seed 003 Theorem 3"})
    return _assemble(translate_vehicle_speed(beta), info=info, kind="vehicle-speed", real=real,
                     method="euler", prefix=prefix, command=command, ranges=ranges)


# ----------------------------------------------------------------------------- text
def _header(*, tr: Translation, info: _Info, kind: str, real: str, method: str, prefix: str, P: str,
            x_macros: Sequence[str], s_macros: Sequence[str], p_macros: Sequence[str], command: str | None,
            temporaries: int, stack_reals: int, bound: tuple[Fraction, int] | None, h_max_c: float | None,
            certificate: str | None, original_names: Sequence[str], o_macros: Sequence[str],
            ranges: Mapping[str, tuple[float, float]], det_floor: float | None) -> str:
    guard = f"{P}_H"
    rt = f"{prefix}_real"
    scheme = _SCHEMES[method][0] + ", signals held over the step (zero-order hold)"
    lines = [
        f"/* {prefix}.h -- generated by switchobs with casadi {ca.__version__}; do not edit.",
        f" * Model {info.name!r}: {info.description}.",
        *[f" * {e}" for e in info.equations],
        f" * Discretisation: {scheme}.  Real type: {real}.",
        " * No heap allocation, no global mutable state: re-entrant and thread-safe.",
    ]
    if certificate:
        lines.append(f" * Discrete certificate (switchobs.certify.discrete_certificate, exact): {certificate}.")
    if command:
        lines.append(f" * Regenerate with: {command}")
    lines += [" */", f"#ifndef {guard}", f"#define {guard}", "", "#include <stdint.h>", "",
              "#ifdef __cplusplus", 'extern "C" {', "#endif", "",
              f"#define {P}_NX {len(tr.state_names)}  /* observer state size */",
              f"#define {P}_NS {len(tr.signal_names)}  /* signals per step: y, external signals, inputs */",
              f"#define {P}_NP {len(tr.param_names)}  /* runtime parameters */",
              f"#define {P}_SZ_W {temporaries}  /* scalar temporaries of the step kernel (casadi sz_w) */",
              f"#define {P}_STACK_REALS {stack_reals}  /* bound on the {real}s one step keeps on the stack */"]
    if bound is not None:
        lines += ["",
                  f"/* Certified step: the discrete certificate holds for every step h = |s|*dt in tau up to",
                  f" * h_max = {bound[0]} (exact).  H_MAX is h_max rounded DOWN to {real}, so that no step",
                  " * exceeds the certified bound; a step with |s|*dt > H_MAX is split into ceil(|s|*dt / H_MAX)",
                  " * sub-steps of dt / n with the signals held; more than MAX_SUBSTEPS: ERR_SUBSTEP_LIMIT. */",
                  f"#define {P}_H_MAX {float_literal(h_max_c, real)}",
                  f"#define {P}_MAX_SUBSTEPS {bound[1]}  /* worst case: this many kernel evaluations per step */"]
    if det_floor is not None:
        lines += ["", "/* The step refuses |det D(Z)| below this (ERR_NONFINITE_RESULT), before its one division:",
                  " * half the least |det D(Z)| of a Z = dt J with J Hurwitz (switchobs.spec.StepMethod.det_floor). */",
                  f"#define {P}_DET_FLOOR {float_literal(det_floor, real)}"]
    if ranges:
        lines += ["", "/* Declared ranges [MIN, MAX]: the step refuses a value outside (state, also the new state:",
                  " * ERR_STATE_RANGE; signal: ERR_SIGNAL_RANGE; parameter: ERR_BAD_PARAM; dt: ERR_BAD_DT). */"]
        for key, names, macros in (("X", tr.state_names, x_macros), ("S", tr.signal_names, s_macros),
                                   ("P", tr.param_names, p_macros), (None, ("dt",), ("DT",))):
            for name, m in zip(names, macros):
                if name in ranges:
                    macro = f"{P}_{key}_{m}" if key else f"{P}_{m}"
                    lines += [f"#define {macro}_MIN {float_literal(ranges[name][0], real)}",
                              f"#define {macro}_MAX {float_literal(ranges[name][1], real)}"]
    lines += ["", "/* Observer state (xhat), in the model's coordinates. */"]
    lines += [f"#define {P}_X_{m} {i}" for i, m in enumerate(x_macros)]
    lines += ["", "/* Signals, one row per step. */"]
    lines += [f"#define {P}_S_{m} {i}  /* {role} */" for i, (m, role) in
              enumerate(zip(s_macros, info.signal_roles))]
    if original_names:
        lines += ["", f"/* Original coordinates x = phi^-1(xhat) of the system file ({prefix}_original). */",
                  f"#define {P}_NO {len(original_names)}"]
        lines += [f"#define {P}_O_{m} {i}" for i, m in enumerate(o_macros)]
    lines += ["", "/* Parameters (index into params; default in <prefix>_default_params). */"]
    lines += [f"#define {P}_P_{m} {i}  /* default {float_literal(v, 'double')} */"
              for i, (m, v) in enumerate(zip(p_macros, tr.default_params))]
    lines += ["", "/* Status codes of _step, _run and _run_dt (xhat is unchanged by a failed step). */"]
    lines += [f"#define {P}_{'OK' if s == StepStatus.OK else 'ERR_' + s.name} {int(s)}  /* {STATUS_TEXT[s]} */"
              for s in StepStatus]
    lines += [
        "",
        f"/* The real type of every real of the API (MISRA C:2012 Dir 4.6: no basic numerical type). */",
        f"typedef {real} {prefix}_real;",
        "",
        f"/* The model values and designed gains used at generation. */",
        f"extern const {rt} {prefix}_default_params[{P}_NP];",
        "",
        f"/* Advance xhat[{P}_NX] in place by one step of dt seconds with signals[{P}_NS] held;",
        f" * params[{P}_NP] may be NULL for the defaults.  Returns {P}_OK or an error code. */",
        f"int32_t {prefix}_step({rt} *xhat, const {rt} *signals, const {rt} *params, {rt} dt);",
        "",
        f"/* n_steps steps through the rows of signals (row-major, {P}_NS per row), writing each new",
        f" * state to trajectory (row-major, {P}_NX per row; may be NULL).  On error, returns the code of",
        " * the first failing step k: xhat holds the state after the k steps that succeeded and rows",
        " * 0..k-1 of trajectory are written.  xhat and signals are never NULL (BAD_ARGUMENT); n_steps = 0",
        " * changes nothing and checks what needs no row: dt (BAD_DT" + (", also outside its range" if "dt" in ranges
                                                                          else "")
        + "), then xhat (NONFINITE_STATE" + (", then STATE_RANGE" if any(n in ranges for n in tr.state_names)
                                             else "") + "). */",
        f"int32_t {prefix}_run({rt} *xhat, const {rt} *signals, int32_t n_steps, const {rt} *params,",
        f"    {rt} dt, {rt} *trajectory);",
        "",
        f"/* As _run, row k a step of dt[k] seconds (dt: n_steps entries; irregular sampling).  A dt[k] that is",
        f" * not finite or <= 0 fails step k with {P}_ERR_BAD_DT; dt may be NULL only when n_steps is 0, which",
        " * checks xhat alone. */",
        f"int32_t {prefix}_run_dt({rt} *xhat, const {rt} *signals, int32_t n_steps, const {rt} *params,",
        f"    const {rt} *dt, {rt} *trajectory);",
        "",
        *([] if not original_names else [
            f"/* The estimate in the original coordinates: x[{P}_NO] = phi^-1(xhat[{P}_NX]), with the step's",
            f" * signals[{P}_NS] (phi^-1 may use the external signals); params may be NULL.  Returns {P}_OK, or",
            f" * an error code with x unchanged: NULL pointers, non-finite inputs, a parameter of the wrong sign, or",
            f" * {P}_ERR_NONFINITE_RESULT where phi^-1 is undefined (log of a non-positive number, ...). */",
            f"int32_t {prefix}_original(const {rt} *xhat, const {rt} *signals, const {rt} *params, {rt} *x);",
            ""]),
        "/* A static description of a status code. */",
        f"const char *{prefix}_status_message(int32_t status);",
        "", "#ifdef __cplusplus", "}", "#endif", "", f"#endif /* {guard} */", ""]
    return "\n".join(lines)


def _unrolled(template: str, count: int, indent: str, sep: str) -> str:
    """``template`` for indices 0..count-1 joined by ``sep``, four to a line.

    The checks and copies of one row are written out, not looped: a loop over the state in the body of
    ``_run`` made abs-xbs4's ``_run`` 1.2x slower with gcc 12 -O2 (``benchmarks/codegen_step.py``).
    """
    return _joined([template.format(i=i) for i in range(count)], indent, sep)


def _joined(items: Sequence[str], indent: str, sep: str) -> str:
    """``items`` joined by ``sep``, four to a line."""
    return f"{sep.rstrip()}\n{indent}".join(sep.join(items[j:j + 4]) for j in range(0, len(items), 4))


def _range_test(var: str, names: Sequence[str], macros: Sequence[str], key: str, ranges: Mapping[str, Any],
                P: str, indent: str) -> str | None:
    """C condition true when an entry ``var[i]`` with a declared range is outside it (or NaN); None: no range."""
    items = [f"(!(({var}[{i}] >= {P}_{key}_{m}_MIN) && ({var}[{i}] <= {P}_{key}_{m}_MAX)))"
             for i, (n, m) in enumerate(zip(names, macros)) if n in ranges]
    return _joined(items, indent, " || ") if items else None


def _source(*, tr: Translation, info: _Info, kind: str, real: str, method: str, prefix: str, P: str,
            kernels: Sequence[CFunction], checks: Sequence[str], command: str | None,
            bound: tuple[Fraction, int] | None, original_k: CFunction | None, param_checks: Sequence[str],
            ranges: Mapping[str, tuple[float, float]], x_macros: Sequence[str], s_macros: Sequence[str],
            p_macros: Sequence[str], **_: Any) -> str:
    nx = f"{P}_NX"
    rt = f"{prefix}_real"
    n_x, n_s = len(tr.state_names), len(tr.signal_names)
    used = "\n".join(k.body for k in (*kernels, *([original_k] if original_k else [])))
    helpers = []
    zero, one = float_literal(0.0, real), float_literal(1.0, real)
    if f"{prefix}_sq(" in used:
        helpers.append(f"static {rt} {prefix}_sq({rt} v) {{ return v * v; }}")
    if f"{prefix}_sign(" in used:
        helpers.append(f"static {rt} {prefix}_sign({rt} v) {{ return (v < {zero}) ? -{one} : "
                       f"((v > {zero}) ? {one} : v); }}")
    defaults = ",\n".join(f"    {float_literal(v, real)}  /* {n} */" for n, v in zip(tr.param_names,
                                                                                       tr.default_params))
    status_cases = "\n".join(f"    case {int(s)}:\n        message = \"{STATUS_TEXT[s]}\";\n        break;"
                             for s in StepStatus)
    call = kernels[0].call
    state_in = _range_test("x", tr.state_names, x_macros, "X", ranges, P, "        ")
    signal_in = _range_test("sig", tr.signal_names, s_macros, "S", ranges, P, "        ")
    param_in = _range_test("par", tr.param_names, p_macros, "P", ranges, P, "        ")

    # a declared dt range (DT_MIN > 0) is checked in every step, not skipped with valid: the proof then sees
    # the bound of dt where it is used, without the relation between valid and dt
    dt_check = (f"!((dt >= {P}_DT_MIN) && (dt <= {P}_DT_MAX))" if "dt" in ranges
                else f"(!valid) && ((!(dt > {zero})) || (!isfinite(dt)))")
    implicit = not STEP_METHODS[method].explicit
    f = "f" if real == "float" else ""
    state_out = _range_test("next", tr.state_names, x_macros, "X", ranges, P, "        ")

    def singular(x: str, dt: str, indent: str) -> list[str]:
        """The implicit kernel's det D(Z) checked against DET_FLOOR.  In the ranged build the kernel wrote det
        D(Z) and the undivided solve after it: the one division, 1 / det, is then taken as 1 / |det| with det's
        sign (the same bits), its divisor visibly at least DET_FLOOR, and the step is x + dt (solve * (1 / det)),
        the operations of the Python reference (switchobs.spec.implicit_increment)."""
        if not implicit:
            return []
        if not ranges:  # the kernel divided by det where it is nonzero (else by 1): refuse |det| < DET_FLOOR
            return [_refuse(P, f"(!(fabs{f}(next[{nx}]) >= {P}_DET_FLOOR)) || (!isfinite(next[{nx}]))",
                            "NONFINITE_RESULT", "D(Z) singular, or J not Hurwitz", indent)]
        return [f"{indent}det = next[0];  /* det D(Z), then the undivided solve */",
                f"{indent}inv = fabs{f}(det);",
                _refuse(P, f"(!(inv >= {P}_DET_FLOOR)) || (!isfinite(inv))", "NONFINITE_RESULT",
                        "D(Z) singular, or J not Hurwitz", indent),
                f"{indent}inv = (det < {zero}) ? ((-{one}) / inv) : ({one} / inv);",
                *(f"{indent}next[{i}] = {x}[{i}] + ({dt} * (next[{i + 1}] * inv));" for i in range(n_x))]

    size = f"{nx} + 1" if implicit else nx
    if bound is None:
        stepping = ["    " + call("next", x="x", sig="sig", par="par", dt="dt", s="s"), *singular("x", "dt", "    ")]
    else:
        # one call of the kernel, so that compilers inline it as in the step without sub-steps (two calls,
        # the first from x, kept it out of line with gcc 12 -O2: 1.2x slower non-stiff steps of abs-xbs3).
        # The loop's bound is the constant MAX_SUBSTEPS, so compilers and proof tools see that it runs at least
        # once and writes next (over j < n, gcc 12 -O2 warns that next may be used uninitialized).
        stepping = [f"    for (int32_t i = 0; i < {nx}; ++i) {{",
                    "        cur[i] = x[i];",
                    "    }",
                    f"    for (int32_t j = 1; j <= {P}_MAX_SUBSTEPS; ++j) {{  /* sub-step j of n <= MAX_SUBSTEPS, "
                    "signals held */",
                    "        " + call("next", x="cur", sig="sig", par="par", dt="h", s="s"),
                    *singular("cur", "h", "        "),
                    "        if (j >= n) {",
                    "            break;",
                    "        }",
                    # ranged (proved) build: a sub-step's state stays in the declared box, so that the next
                    # sub-step starts from a state the proof covers (the loop needs no global argument)
                    *([] if state_out is None else [
                        _refuse(P, _unrolled('(!isfinite(next[{i}]))', n_x, '            ', ' || '),
                                "NONFINITE_RESULT", indent="        "),
                        _refuse(P, state_out, "STATE_RANGE", indent="        ")]),
                    f"        for (int32_t i = 0; i < {nx}; ++i) {{",
                    "            cur[i] = next[i];",
                    "        }",
                    "    }"]
    body = [
        f"/* {prefix}.c -- generated by switchobs with casadi {ca.__version__}; do not edit.",
        f" * Kernels: casadi C of the {_SCHEMES[method][1]} step, post-processed for {real}.",
        f" * MISRA C:2012: the remaining advisory findings and why are in {prefix}_misra.md.",
        " */",
        f'#include "{prefix}.h"',
        "",
        "#include <math.h>",
        "#include <stdbool.h>",
        "#include <stddef.h>",
        "",
        "#if defined(__FAST_MATH__) || (defined(__FINITE_MATH_ONLY__) && __FINITE_MATH_ONLY__)",
        f'#error "{prefix}.c must not be compiled with -ffast-math or -ffinite-math-only: they let the compiler '
        'assume that no value is NaN or infinite and delete the checks that refuse NaN and infinite inputs '
        '(a NaN speed would then return OK with a NaN state)"',
        "#endif",
        "",
        *_branch_hints(P),
        "",
        *helpers,
        "" if helpers else None,
        f"const {rt} {prefix}_default_params[{P}_NP] = {{\n{defaults}\n}};",
        "",
        used,
        "/* All checks of one step, then the step into next; nothing is written unless every check passes.",
        " * valid: dt and par are already known to pass their checks (see _rows), which are then skipped. */",
        f"static int32_t {prefix}_advance(const {rt} *x, const {rt} *sig, const {rt} *par, {rt} dt, "
        f"{rt} *next, bool valid)",
        "{",
        f"    {rt} g;" if any("&g" in c for c in checks) else None,
        f"    {rt} s;" if any("&s" in c for c in checks) else None,
        *([] if bound is None else [f"    {rt} cur[{nx}];", f"    {rt} a;", f"    {rt} h = dt;",
                                    "    int32_t n = 1;"]),
        *([f"    {rt} det;", f"    {rt} inv;"] if implicit and ranges else []),
        _refuse(P, dt_check, "BAD_DT"),
        _refuse(P, _unrolled('(!isfinite(x[{i}]))', n_x, '        ', ' || '), "NONFINITE_STATE"),
        None if state_in is None else _refuse(P, state_in, "STATE_RANGE"),
        _refuse(P, _unrolled('(!isfinite(sig[{i}]))', n_s, '        ', ' || '), "NONFINITE_SIGNAL"),
        None if signal_in is None else _refuse(P, signal_in, "SIGNAL_RANGE"),
        "    if (!valid) {",
        f"        for (int32_t i = 0; i < {P}_NP; ++i) {{",
        _refuse(P, "!isfinite(par[i])", "BAD_PARAM", indent="            "),
        "        }",
        "    }",
        None if param_in is None else _refuse(P, param_in, "BAD_PARAM", "a declared parameter range"),
        *checks,
        *stepping,
        _refuse(P, _unrolled('(!isfinite(next[{i}]))', n_x, '        ', ' || '), "NONFINITE_RESULT"),
        None if state_out is None else _refuse(P, state_out, "STATE_RANGE", "the new state leaves its range"),
        f"    return {P}_OK;",
        "}",
        "",
        "/* The rows of _step, _run and _run_dt: row k a step of dts[k] seconds, or of dt when dts is NULL.",
        " * _advance has this one caller, so compilers inline it into the loop (a loop of its own for _run_dt,",
        " * a second caller, made _run up to 1.15x slower with gcc 12 -O2).  Six pointers and integers and a",
        " * real, which the System V x86-64 ABI passes in registers: a seventh integer would be pushed, and",
        " * gcc -fstack-usage reports the callers' frames as dynamic. */",
        f"static int32_t {prefix}_rows({rt} *xhat, const {rt} *signals, int32_t n_steps, const {rt} *params,",
        f"    {rt} dt, const {rt} *dts, {rt} *trajectory)",
        "{",
        f"    {rt} cur[{nx}];",
        # with ranges (the proved build) next starts initialised: that a row's state is written exactly when
        # _advance returns 0 is a relation between paths the proof would otherwise have to keep apart
        # (every element written out: a partial initialiser breaks MISRA C:2012 rule 9.3)
        f"    {rt} next[{size}]{' = {' + ', '.join([zero] * (n_x + implicit)) + '}' if ranges else ''};",
        "    /* one loop for both: row k reads h[hk], hk stepped by stride, 0 for a fixed dt (stepped:",
        "     * faster than indexing h with k * stride with gcc 12 -O2) */",
        f"    const {rt} *h = &dt;",
        f"    const {rt} *par = {prefix}_default_params;",
        "    size_t stride = 0u;",
        "    size_t hk = 0u;",
        f"    int32_t status = {P}_OK;",
        "    bool valid;",
        _refuse(P, "(xhat == NULL) || (signals == NULL) || (n_steps < 0)", "BAD_ARGUMENT", hint=False),
        "    /* no row: the state check of a step, which needs none (as the Python reference and CObserver) */",
        "    if (n_steps == 0) {",
        f"        for (int32_t i = 0; i < {nx}; ++i) {{",
        _refuse(P, "!isfinite(xhat[i])", "NONFINITE_STATE", indent="            ", hint=False),
        "        }",
        None if state_in is None else _refuse(P, _range_test("xhat", tr.state_names, x_macros, "X", ranges, P,
                                                             "            "), "STATE_RANGE", indent="        ",
                                              hint=False),
        "    }",
        "    if (dts != NULL) {",
        "        h = dts;",
        "        stride = 1u;",
        "    }",
        "    if (params != NULL) {",
        "        par = params;",
        "    }",
        "    /* the step lengths and params are checked once here.  If one fails, every row checks them again",
        "     * in _step's order, so a failing row reports exactly the status that _step reports. */",
        f"    valid = {_unrolled('isfinite(par[{i}])', len(tr.param_names), '        ', ' && ')};",
        "    for (int32_t k = 0; valid && (k < ((stride > 0u) ? n_steps : 1)); ++k) {",
        f"        valid = (h[k] > {zero}) && isfinite(h[k])"
        + (f" && (h[k] >= {P}_DT_MIN) && (h[k] <= {P}_DT_MAX);" if "dt" in ranges else ";"),
        "    }",
        "    /* the state is carried in a local array, which no store to trajectory can alias, and written to xhat",
        "     * once at the end; the copies in the loop are written out (measured fastest with gcc 12 -O2) */",
        f"    for (int32_t i = 0; i < {nx}; ++i) {{",
        "        cur[i] = xhat[i];",
        "    }",
        "    /* k is an int32_t like n_steps, its row offset a size_t (a size_t k made gcc 12 -O2's _step 1.04x",
        "     * slower on abs-xbs4) */",
        "    for (int32_t k = 0; k < n_steps; ++k) {",
        f"        status = {prefix}_advance(cur, &signals[(size_t)k * (size_t){P}_NS], par, h[hk], next, valid);",
        f"        if (status != {P}_OK) {{",
        "            break;",
        "        }",
        f"        {_unrolled('cur[{i}] = next[{i}];', n_x, '        ', ' ')}",
        "        if (trajectory != NULL) {",
        f"            {rt} *row = &trajectory[(size_t)k * (size_t){nx}];",
        f"            {_unrolled('row[{i}] = next[{i}];', n_x, '            ', ' ')}",
        "        }",
        "        hk += stride;",
        "    }",
        f"    for (int32_t i = 0; i < {nx}; ++i) {{",
        "        xhat[i] = cur[i];",
        "    }",
        "    return status;",
        "}",
        "",
        f"int32_t {prefix}_run({rt} *xhat, const {rt} *signals, int32_t n_steps, const {rt} *params,",
        f"    {rt} dt, {rt} *trajectory)",
        "{",
        "    /* no row: dt is checked before the state, in _step's order"
        + (" (within its declared range, as a step checks it) */" if "dt" in ranges else " */"),
        _refuse(P, "(n_steps == 0) && (xhat != NULL) && (signals != NULL) && "
                + (f"!((dt >= {P}_DT_MIN) && (dt <= {P}_DT_MAX))" if "dt" in ranges
                   else f"!((dt > {zero}) && isfinite(dt))"), "BAD_DT", hint=False),
        f"    return {prefix}_rows(xhat, signals, n_steps, params, dt, NULL, trajectory);",
        "}",
        "",
        f"int32_t {prefix}_run_dt({rt} *xhat, const {rt} *signals, int32_t n_steps, const {rt} *params,",
        f"    const {rt} *dt, {rt} *trajectory)",
        "{",
        f"    int32_t status = {P}_ERR_BAD_ARGUMENT;",
        "    if ((dt != NULL) || (n_steps <= 0)) {",
        f"        status = {prefix}_rows(xhat, signals, n_steps, params, {zero}, dt, trajectory);",
        "    }",
        "    return status;",
        "}",
        "",
        "/* One row of _run. */",
        f"int32_t {prefix}_step({rt} *xhat, const {rt} *signals, const {rt} *params, {rt} dt)",
        "{",
        f"    return {prefix}_rows(xhat, signals, 1, params, dt, NULL, NULL);",
        "}",
        "",
        *_original_function(original_k, param_checks, real=real, prefix=prefix, P=P),
        f"const char *{prefix}_status_message(int32_t status)",
        "{",
        "    const char *message;",
        "    switch (status) {",
        status_cases,
        "    default:",
        "        message = \"unknown status code\";",
        "        break;",
        "    }",
        "    return message;",
        "}",
        "",
    ]
    return "\n".join(line for line in body if line is not None)


def _branch_hints(P: str) -> list[str]:
    """The macro that marks a refusal unlikely: the condition itself unless the integrator asks for the hint.

    ``__builtin_expect`` is a language extension (MISRA C:2012 rule 1.2), so the file uses it only when
    compiled with ``-DSWITCHOBS_BRANCH_HINTS`` by clang (:data:`BRANCH_HINTS`).
    """
    return [
        f"/* {P}_UNLIKELY(c) is c.  Compiled by clang with -D{BRANCH_HINTS}, it also tells the compiler that",
        " * the refusals are rare (__builtin_expect: a language extension, MISRA C:2012 rule 1.2, so off unless",
        " * asked for).  Told so, clang 14 -O2 inlines the kernel into the step: it judges the call cold behind a",
        " * dozen checks and keeps it out of line (1.2-1.4x slower steps).  gcc 12 -O2 inlines it anyway and lays",
        " * the step out worse with the hint (abs-xbs4's step 1.15x slower), so gcc is never told. */",
        f"#if defined({BRANCH_HINTS}) && defined(__clang__)",
        # the comparison keeps the if's condition boolean (rule 14.4); with (c) ? 1L : 0L as the argument
        # instead of !!(c), clang 14 lost the hint in abs-xbs4's _run (1.22x slower)
        f"#define {P}_UNLIKELY(c) (__builtin_expect(!!(c), 0) != 0)",
        "#else",
        f"#define {P}_UNLIKELY(c) (c)",
        "#endif",
    ]


def _original_function(original_k: CFunction | None, param_checks: Sequence[str], *, real: str, prefix: str,
                       P: str) -> list[str | None]:
    """``<prefix>_original``: the checks of the step's inputs and parameters, phi^-1, then its finiteness."""
    if original_k is None:
        return []
    rt = f"{prefix}_real"
    return [
        f"int32_t {prefix}_original(const {rt} *xhat, const {rt} *signals, const {rt} *params, {rt} *x)",
        "{",
        f"    {rt} out[{P}_NO];",
        f"    {rt} g;" if any("&g" in c for c in param_checks) else None,
        f"    const {rt} *sig = signals;",
        f"    const {rt} *par = {prefix}_default_params;",
        _refuse(P, "(xhat == NULL) || (signals == NULL) || (x == NULL)", "BAD_ARGUMENT", hint=False),
        "    if (params != NULL) {",
        "        par = params;",
        "    }",
        *(line for name, array, status in (("NX", "xhat", "NONFINITE_STATE"), ("NS", "sig", "NONFINITE_SIGNAL"),
                                           ("NP", "par", "BAD_PARAM"))
          for line in (f"    for (int32_t i = 0; i < {P}_{name}; ++i) {{",
                       _refuse(P, f"!isfinite({array}[i])", status, indent="        ", hint=False), "    }")),
        *param_checks,
        "    " + original_k.call("out", x="xhat", sig="sig", par="par"),
        f"    for (int32_t i = 0; i < {P}_NO; ++i) {{",
        _refuse(P, "!isfinite(out[i])", "NONFINITE_RESULT", "phi^-1 undefined here", indent="        ",
                hint=False),
        "    }",
        f"    for (int32_t i = 0; i < {P}_NO; ++i) {{",
        "        x[i] = out[i];",
        "    }",
        f"    return {P}_OK;",
        "}",
        "",
    ]
