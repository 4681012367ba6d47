"""Exact translation of a switchobs model and its gains into casadi SX expressions.

The observer right-hand side (seed 000 eq. (8)-(9), seed 004) is

    dzhat/dt = s(y) (A zhat + d(y) + K(y) (y - C zhat)) + b(y) u,
    K = K_plus where s > 0, K_minus otherwise,

written, like the Python reference observers, as ``s (A zhat) + c + g e`` with
``c = s d(y) + b(y) u``, ``e = y - C zhat`` and ``g = s K(s)`` chosen with
``if_else(s > 0, s K_plus, s K_minus)``: both branches vanish at ``s = 0``, so
the correction ``g e`` is continuous there (seed 000, remark after eq. (9))
and each branch is evaluated exactly, without ``K_minus + (K_plus - K_minus)``
rounding.  The switched adaptive observer of seed 001 eq. (3.4), (3.8),
(3.15) adds ``theta`` and ``Upsilon`` to the state.

Both observers are translated from an :class:`~switchobs.spec.ObserverSpec`,
the contract the Python reference observers consume too (the affine split
``c + Psi theta = s d + b u`` and its linearity test live there).  Every
model parameter and every gain stays a runtime parameter (an entry of the
``params`` vector of the generated C).  Besides the equations, the
translation returns the *guards* of the spec: the conditions under which the
right-hand side is defined (denominators nonzero, logarithm arguments
positive, even roots non-negative, declared signs respected), each tagged
with the status code the generated step returns when it fails.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import casadi as ca
import sympy as sp

from ..exceptions import CodegenError
from ..model import Model
from ..spec import (METHODS, SCALE, STEP_METHODS, Guard, ObserverSpec, StepStatus, affine_jacobian,
                    implicit_increment)

__all__ = ["Translation", "to_casadi", "translate_original", "translate_switched", "translate_adaptive",
           "translate_super_twisting", "translate_vehicle_speed"]

#: Guard kinds and the C comparison that holds when the guard is satisfied (NaN fails every one); ``{zero}`` is
#: the literal 0 of the C real type (MISRA C:2012 rule 10.4: no int operand beside a real one).
GUARD_TESTS: Mapping[str, str] = {
    "positive": "{g} > {zero}",
    "negative": "{g} < {zero}",
    "nonzero": "({g} < {zero}) || ({g} > {zero})",
    "nonnegative": "{g} >= {zero}",
}

_FUNCTIONS: Mapping[type, Callable[[ca.SX], ca.SX]] = {
    sp.exp: ca.exp,
    sp.log: ca.log,
    sp.sin: ca.sin,
    sp.cos: ca.cos,
    sp.tan: ca.tan,
    sp.tanh: ca.tanh,
    sp.atan: ca.atan,
    sp.Abs: ca.fabs,
    sp.sign: ca.sign,
}


#: The methods of a right-hand side that is not affine in the state (the adaptive observer).
EXPLICIT = tuple(m for m in METHODS if STEP_METHODS[m].explicit)


def _power(base: ca.SX, exponent: sp.Expr) -> ca.SX:
    """Powers as the Python reference evaluates them: small integer powers as products, halves as sqrt."""
    if exponent == sp.Rational(1, 2):
        return ca.sqrt(base)
    if exponent == sp.Rational(-1, 2):
        return 1 / ca.sqrt(base)
    if exponent.is_Integer:
        k = int(exponent)
        if k == -1:
            return 1 / base
        if 2 <= abs(k) <= 4:
            prod = base
            for _ in range(abs(k) - 1):
                prod = prod * base
            return prod if k > 0 else 1 / prod
    return ca.power(base, float(exponent))


def to_casadi(expr: sp.Expr, env: Mapping[sp.Symbol, ca.SX], *, what: str = "expression") -> ca.SX:
    """Translate a sympy expression into casadi SX, node by node.

    Parameters
    ----------
    expr : sympy.Expr
        Built from the model's whitelisted functions (see ``switchobs.model.EXPRESSION_FUNCTIONS``).
    env : mapping Symbol -> casadi.SX
        The casadi scalar of every free symbol.
    what : str
        Name used in error messages.

    Raises
    ------
    CodegenError
        For a symbol missing from ``env`` or a construct C cannot evaluate (complex numbers, ...).
    """
    def walk(e: sp.Basic) -> ca.SX:
        if e.is_Symbol:
            if e not in env:
                raise CodegenError(f"{what} uses {e.name!r}, which is not a state, signal or parameter of the "
                                   "generated observer (an explicit time t cannot be evaluated by the C step: "
                                   "pass the time-varying quantity as an external signal)")
            return env[e]
        if e.is_Rational or e.is_Float:
            return ca.SX(float(e))
        if e in (sp.pi, sp.E):
            return ca.SX(float(e))
        if e.is_Add:
            terms = [walk(a) for a in e.args]
            total = terms[0]
            for t in terms[1:]:
                total = total + t
            return total
        if e.is_Mul:
            num, den = [], []
            for factor in e.args:
                if factor.is_Pow and factor.exp.is_Rational and factor.exp < 0 and factor.exp != -sp.Rational(1, 2):
                    den.append(sp.Pow(factor.base, -factor.exp))
                elif factor.is_Rational and factor.q != 1:
                    num.append(sp.Integer(factor.p))
                    den.append(sp.Integer(factor.q))
                else:
                    num.append(factor)
            sign = 1
            if num and num[0] == -1:
                sign, num = -1, num[1:]
            top = _product([walk(f) for f in num]) if num else ca.SX(1.0)
            out = top / _product([walk(f) for f in den]) if den else top
            return -out if sign < 0 else out
        if e.is_Pow:
            return _power(walk(e.base), e.exp)
        for fn, cfn in _FUNCTIONS.items():
            if isinstance(e, fn):
                return cfn(walk(e.args[0]))
        raise CodegenError(f"{what}: cannot generate C for {sp.sstr(e)!r} ({type(e).__name__}); "
                           "only real arithmetic and the model's expression functions are supported")

    return walk(sp.sympify(expr))


def _product(factors: Sequence[ca.SX]) -> ca.SX:
    out = factors[0]
    for f in factors[1:]:
        out = out * f
    return out


@dataclass(frozen=True)
class Translation:
    """The casadi graph of one observer and the names of its C interface.

    Attributes
    ----------
    x, signals, params, dt : casadi.SX
        Symbolic inputs of the step (state, signals ``(y, external..., inputs...)``, parameters, step).
    rhs : callable or None
        ``rhs(x) -> dx/dt`` at the same signals and parameters (casadi SX column);
        None when ``advance`` gives the step directly.
    scale : casadi.SX
        The time scaling ``s`` as an expression of the signals and parameters.
    s : casadi.SX or None
        The symbol standing for ``s`` in ``rhs`` and ``advance``: the step
        kernel takes the checked value of ``scale`` as an input, so ``s`` is
        computed (and divided) once per step.
    guards : tuple of (Guard, casadi.SX)
        The conditions with their casadi expression.
    state_names, signal_names, param_names : tuple of str
    default_params : tuple of float
    advance : callable, optional
        ``advance(method) -> x_next`` replacing the generic RK4 / Euler step of ``rhs``.
    methods : tuple of str
        The discretisations this observer admits.
    implicit : callable, optional
        ``implicit(method) -> (numerators, det)`` for an implicit method: ``det D(Z) D(Z)^-1 F(Z) f(x)``
        (the cofactor solve before its one division) and ``det D(Z)``; the step checks ``|det|`` against
        ``StepMethod.det_floor`` (below it or not finite: ``NONFINITE_RESULT``) and then steps
        ``x + dt (numerators / det)``, so that the division is visibly by a number away from zero.
    """

    x: ca.SX
    signals: ca.SX
    params: ca.SX
    dt: ca.SX
    rhs: Callable[[ca.SX], ca.SX] | None
    scale: ca.SX
    guards: tuple[tuple[Guard, ca.SX], ...]
    state_names: tuple[str, ...]
    signal_names: tuple[str, ...]
    param_names: tuple[str, ...]
    default_params: tuple[float, ...]
    advance: Callable[[str], ca.SX] | None = None
    methods: tuple[str, ...] = METHODS
    s: ca.SX | None = None
    implicit: Callable[[str], tuple[ca.SX, ca.SX]] | None = None


def _environment(model: Model, extra_params: Sequence[str]) -> tuple[ca.SX, ca.SX, ca.SX, dict, dict]:
    sig = ca.SX.sym("signals", len(model.signals))
    names = (*model.parameters, *extra_params)
    par = ca.SX.sym("params", len(names))
    env = {model.symbols[name]: sig[i] for i, name in enumerate(model.signals)}
    env.update({model.symbols[name]: par[i] for i, name in enumerate(model.parameters)})
    index = {name: i for i, name in enumerate(names)}
    dt = ca.SX.sym("dt")
    return sig, par, dt, env, index


def _affine_parts(spec: ObserverSpec, env: Mapping[sp.Symbol, ca.SX]):
    """``s``, ``A``, ``C`` and the spec's ``c`` and ``Psi``, as casadi.

    ``s`` is returned twice: as a symbol (used in ``c`` and ``Psi``) and as
    its expression.  ``A``, ``C``, ``c`` and ``Psi`` keep structural zeros as
    ``None`` so that no term is generated for them, as in the reference.
    """
    model = spec.model
    s_expr = to_casadi(model.time_scale, env, what="time_scale")
    s = ca.SX.sym("s")
    n = model.n
    A = [[None if model.A[i, j] == 0 else to_casadi(model.A[i, j], env, what=f"A[{i + 1}][{j + 1}]")
          for j in range(n)] for i in range(n)]
    C = [None if model.C[j] == 0 else to_casadi(model.C[j], env, what=f"C[{j + 1}]") for j in range(n)]
    # A dummy for s, as the symbol sorts among the model's symbols: it fixes the order of the products.
    s_sym = sp.Dummy("s")
    env_s = {**env, s_sym: s}
    c = [None if ci == 0 else to_casadi(ci.xreplace({SCALE: s_sym}), env_s, what=f"s*d[{i + 1}] + b u")
         for i, ci in enumerate(spec.drift)]
    psi = [[None if q == 0 else to_casadi(q.xreplace({SCALE: s_sym}), env_s, what="regressor Psi") for q in row]
           for row in spec.regressor]
    return s, s_expr, A, C, c, psi


def _lin(coeffs: Sequence[ca.SX | None], xs: Sequence[ca.SX]) -> ca.SX | None:
    total = None
    for a, x in zip(coeffs, xs):
        if a is None:
            continue
        term = a * x
        total = term if total is None else total + term
    return total


def _sum(parts: Sequence[ca.SX | None]) -> ca.SX:
    parts = [p for p in parts if p is not None]
    if not parts:
        return ca.SX(0.0)
    total = parts[0]
    for p in parts[1:]:
        total = total + p
    return total


def _guards(spec: ObserverSpec, env: Mapping[sp.Symbol, ca.SX]) -> tuple[tuple[Guard, ca.SX], ...]:
    return tuple((g, to_casadi(g.expr, env, what=f"guard {g.expr}")) for g in spec.guards())


def _check_no_time(model: Model) -> None:
    t = model.symbols.get("t")
    if t is not None and t in model.time_scale.free_symbols:
        raise CodegenError(f"time_scale s = {model.time_scale} depends on the time t explicitly; the generated "
                           "step has no clock: declare the time-varying quantity as an external signal")


def _gain_parameters(spec: ObserverSpec, par: ca.SX, index: Mapping[str, int], s: ca.SX) -> list[ca.SX]:
    """``g = if_else(s > 0, s K_plus, s K_minus)`` per state, the gains being runtime parameters."""
    return [ca.if_else(s > 0, s * par[index[f"K_plus_{z}"]], s * par[index[f"K_minus_{z}"]])
            for z in spec.model.states]


def _gain_names(spec: ObserverSpec) -> list[str]:
    return [f"K_plus_{z}" for z in spec.model.states] + [f"K_minus_{z}" for z in spec.model.states]


def translate_original(model: Model, tr: Translation) -> ca.SX:
    """``x = phi^{-1}(xhat)`` (the model's ``[original]`` table) in the step's state, signals and parameters."""
    env = {model.symbols[name]: tr.signals[i] for i, name in enumerate(model.signals)}
    env.update({model.symbols[name]: tr.params[i] for i, name in enumerate(model.parameters)})
    env.update({model.symbols[name]: tr.x[i] for i, name in enumerate(model.states)})
    return ca.vertcat(*[to_casadi(e, env, what=f"original {name}") for name, e in model.original])


def translate_switched(spec: ObserverSpec) -> Translation:
    """The switched observer of seed 000 eq. (8)-(9) / seed 004 as casadi SX.

    Parameters
    ----------
    spec : ObserverSpec
        Without unknowns.  Its gains are the defaults of the runtime
        parameters ``K_plus_<state>``, ``K_minus_<state>``; its ``values``
        those of the model parameters (every parameter needs one).
    """
    model = spec.model
    _check_no_time(model)
    n = model.n
    sig, par, dt, env, index = _environment(model, _gain_names(spec))
    x = ca.SX.sym("x", n)
    s, s_expr, A, C, c, _ = _affine_parts(spec, env)
    y = sig[0]
    g = _gain_parameters(spec, par, index, s)

    def rhs(w: ca.SX) -> ca.SX:
        ws = [w[j] for j in range(n)]
        e = y - _sum([_lin(C, ws)])
        rows = []
        for i in range(n):
            Aw = _lin(A[i], ws)
            rows.append(_sum([None if Aw is None else s * Aw, c[i], g[i] * e]))
        return ca.vertcat(*rows)

    def implicit(method: str) -> tuple[ca.SX, ca.SX]:
        """The undivided solve of one implicit step of the affine ``f(w) = J w + c``, ``J = s A - g C``."""
        f = rhs(x)
        # safe = 1: the solve's one division is left to the step, after its check of det (see _generate)
        num, det = implicit_increment(STEP_METHODS[method], affine_jacobian(A, C, s, g), [f[i] for i in range(n)],
                                      dt, lambda d: ca.SX(1))
        return ca.vertcat(*num), det

    values = [float(spec.values[name]) for name in model.parameters] + list(spec.K_plus) + list(spec.K_minus)
    return Translation(x=x, signals=sig, params=par, dt=dt, rhs=rhs, scale=s_expr, s=s, guards=_guards(spec, env),
                       state_names=spec.state_names, signal_names=spec.signal_names,
                       param_names=tuple(index), default_params=tuple(values), implicit=implicit)


def translate_adaptive(spec: ObserverSpec) -> Translation:
    """The switched adaptive observer of seed 001 eq. (3.4), (3.8), (3.15) as casadi SX.

    With ``g = s K(s)``, ``e = y - C w``, ``r = Upsilon' C'``, ``q = Gamma r``::

        w'       = s (A w) + c + Psi theta + (g + Upsilon q) e      (3.4a)
        theta'   = q e                                              (3.4b)
        Upsilon' = s (A Upsilon) - g r' + Psi                       (3.4c)

    where ``c`` and ``Psi`` are the spec's affine split.  The state is
    ``(w, theta, Upsilon row-major)`` (:attr:`ObserverSpec.state_names`).
    ``Gamma`` entries are runtime parameters ``Gamma_<unknown>_<unknown>``;
    the unknown parameters leave the parameter vector (they are states).
    """
    model, unknown = spec.model, spec.unknown
    _check_no_time(model)
    n, p = model.n, spec.p
    gamma_names = [f"Gamma_{a}_{b}" for a in unknown for b in unknown]
    sig, par, dt, env, index = _environment(spec.known_model, [*_gain_names(spec), *gamma_names])
    N = spec.size
    x = ca.SX.sym("x", N)
    s, s_expr, A, C, c, psi = _affine_parts(spec, env)
    y = sig[0]
    g = _gain_parameters(spec, par, index, s)
    G = [[par[index[f"Gamma_{a}_{b}"]] for b in unknown] for a in unknown]

    def rhs(v: ca.SX) -> ca.SX:
        w = [v[i] for i in range(n)]
        th = [v[n + j] for j in range(p)]
        U = [[v[n + p + i * p + j] for j in range(p)] for i in range(n)]
        e = y - _sum([_lin(C, w)])
        r = [_sum([_lin(C, [U[i][j] for i in range(n)])]) for j in range(p)]
        m = [_sum([_lin(G[j], r)]) for j in range(p)]
        rows = []
        for i in range(n):
            Aw = _lin(A[i], w)
            parts = [None if Aw is None else s * Aw, c[i]]
            parts += [psi[i][j] * th[j] for j in range(p) if psi[i][j] is not None]
            gain = _sum([g[i], *[U[i][j] * m[j] for j in range(p)]]) if p else g[i]
            parts.append(gain * e)
            rows.append(_sum(parts))
        rows += [m[j] * e for j in range(p)]
        for i in range(n):
            for j in range(p):
                AU = _lin(A[i], [U[k][j] for k in range(n)])
                rows.append(_sum([None if AU is None else s * AU, -(g[i] * r[j]), psi[i][j]]))
        return ca.vertcat(*rows)

    flat_gamma = [float(spec.Gamma[i][j]) for i in range(p) for j in range(p)]
    values = ([float(spec.values[name]) for name in spec.known_parameters] + list(spec.K_plus)
              + list(spec.K_minus) + flat_gamma)
    return Translation(x=x, signals=sig, params=par, dt=dt, rhs=rhs, scale=s_expr, s=s, guards=_guards(spec, env),
                       state_names=spec.state_names, signal_names=spec.signal_names, param_names=tuple(index),
                       default_params=tuple(values), methods=EXPLICIT)


def translate_super_twisting(lam: float, alpha: float) -> Translation:
    """The super-twisting observer of seed 003 eq. (8)-(9) with its Euler scheme (13), as casadi SX.

    Signals ``(x1, f1)``: the measured angle and the known part of the
    acceleration; parameters ``(lam, alpha)``; state ``(x1_hat, x2_hat, z2)``
    where ``z2 = alpha sign(x1 - x1_hat)`` is the injection used over the last
    step (an output, not integrated), so that the equivalent output injection
    (seed 003 eq. (20)) is available from the state::

        e = x1 - x1_hat,  z1 = lam |e|^(1/2) sign(e),  z2 = alpha sign(e)
        x1_hat+ = x1_hat + dt (x2_hat + z1),  x2_hat+ = x2_hat + dt (f1 + z2)

    Only forward Euler is admitted: (13) is the seed's discretisation, and the
    stages of RK4 would straddle the discontinuity of ``sign``.
    """
    sig = ca.SX.sym("signals", 2)
    par = ca.SX.sym("params", 2)
    dt = ca.SX.sym("dt")
    x = ca.SX.sym("x", 3)
    e = sig[0] - x[0]
    sgn = ca.sign(e)
    z1 = par[0] * ca.sqrt(ca.fabs(e)) * sgn
    z2 = par[1] * sgn

    def advance(method: str) -> ca.SX:  # noqa: ARG001 - only "euler" is admitted
        return ca.vertcat(x[0] + dt * (x[1] + z1), x[1] + dt * (sig[1] + z2), z2)

    lam_s, alpha_s = sp.Symbol("lam", positive=True), sp.Symbol("alpha", positive=True)
    guards = tuple((Guard(sym, "positive", StepStatus.BAD_PARAM, f"gain {sym.name} of seed 003 (9) must be > 0"),
                    par[i]) for i, sym in enumerate((lam_s, alpha_s)))
    return Translation(x=x, signals=sig, params=par, dt=dt, rhs=None, scale=ca.SX(1.0), guards=guards,
                       state_names=("x1_hat", "x2_hat", "z2"), signal_names=("x1", "f1"),
                       param_names=("lam", "alpha"), default_params=(float(lam), float(alpha)),
                       advance=advance, methods=("euler",))


def translate_vehicle_speed(beta: float) -> Translation:
    """The sliding-mode observer of the vehicle speed of seed 003 eq. (15), explicit Euler, as casadi SX.

    Signal ``x3``: the measured speed; parameter ``beta``; state ``(x3_hat, z3)`` where ``z3 = beta sign(x3 -
    x3_hat)`` is the injection used over the last step (an output, as ``z2`` of
    :func:`translate_super_twisting`), whose low-pass filtered value is ``xi2`` (seed 003 eq. (21))::

        z3 = beta sign(x3 - x3_hat),   x3_hat+ = x3_hat + dt z3

    Only forward Euler is admitted, for the reason given in :func:`translate_super_twisting`.
    """
    sig = ca.SX.sym("signals", 1)
    par = ca.SX.sym("params", 1)
    dt = ca.SX.sym("dt")
    x = ca.SX.sym("x", 2)
    z3 = par[0] * ca.sign(sig[0] - x[0])

    def advance(method: str) -> ca.SX:  # noqa: ARG001 - only "euler" is admitted
        return ca.vertcat(x[0] + dt * z3, z3)

    guards = ((Guard(sp.Symbol("beta", positive=True), "positive", StepStatus.BAD_PARAM,
                     "gain beta of seed 003 (15) must be > 0"), par[0]),)
    return Translation(x=x, signals=sig, params=par, dt=dt, rhs=None, scale=ca.SX(1.0), guards=guards,
                       state_names=("x3_hat", "z3"), signal_names=("x3",), param_names=("beta",),
                       default_params=(float(beta),), advance=advance, methods=("euler",))
