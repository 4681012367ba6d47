"""The numeric engine shared by every switchobs observer: validation, the step methods, run loops.

All observers of this package integrate a right-hand side of the form
(signals ``sig`` held constant over a step, zero-order hold)::

    s      = s(sig)                                   time scaling, once per step
    g      = s * (K_plus if s > 0 else K_minus)       continuous through s = 0
    c      = s d(y) + b(y) u        (theta-free part)  once per step
    Psi    = d/dtheta (s d + b u)                      once per step (adaptive only)
    e      = y - C w
    r      = Upsilon' C'            q = Gamma r        (adaptive only)
    w'     = s (A w) + c + Psi theta + (g + Upsilon q) e
    theta' = q e
    Upsilon' = s (A Upsilon) - g r' + Psi

With no unknown parameters (``p = 0``) this is the switched observer
``dzhat/dt = s (A zhat + d + K (y - C zhat)) + b u`` (seed 000 eq. (8)-(9),
seed 004); with ``p > 0`` it is the switched adaptive observer of seed 001
eq. (3.4), (3.8), (3.15).

The observer comes as an :class:`~switchobs.spec.ObserverSpec` (the contract the
generated C is translated from too): its affine split ``c``, ``Psi`` is lowered
here to the signal symbols ``S0, S1, ...`` with the parameter values substituted.
The right-hand side is turned into straight-line Python source once (sympy's
code printers, as ``lambdify`` does, with the gains and matrices as float
literals and zeros skipped), so that a step costs a few microseconds of pure
float arithmetic.  ``run`` evaluates the per-step quantities (``s``, ``g``,
``c``, ``Psi``) for all rows at once with NumPy and then executes the very same
stage code as ``step`` in a loop; for rational models the two agree bit for
bit.

With a step bound ``h_max`` (a double, already rounded down from the
certified rational), a step whose ``|s| dt`` in rescaled time exceeds it is
split into ``n = ceil(|s| dt / h_max)`` sub-steps of ``dt / n`` with the same
held signals, with the very float operations of the generated C
(``switchobs.codegen``), so that both choose the same ``n`` and agree bit for
bit; more than ``max_substeps`` is refused (``SUBSTEP_LIMIT``).

The implicit methods ("midpoint", "radau3"; switched observer only, ``p = 0``)
use that the held-signal right-hand side is affine, ``f = J x + c`` with
``J = s A - g C``: one step is ``x + dt D(Z)^-1 F(Z) f(x)``, ``Z = dt J``,
straight-line Python recorded from :func:`switchobs.spec.implicit_increment`
(the function the C translation evaluates on casadi SX).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.pycode import PythonCodePrinter

from .._validate import DEFAULT_MAX_SUBSTEPS, named_vector
from ..exceptions import FreeSymbolError, ModelError, ObserverInputError, SimulationError
from ..model import Model, numeric
from ..spec import (METHODS, SCALE, STEP_METHODS, ObserverSpec, StepStatus, affine_jacobian, implicit_increment,
                    require_explicit)

__all__ = ["ErrorCode", "METHODS", "Kernel", "check_free"]

#: The observers' name of the step status codes (the one enum of :mod:`switchobs.spec`).
ErrorCode = StepStatus


# --------------------------------------------------------------------------- printing
def _pow(printer, expr: sp.Pow, sqrt: str, power: str) -> str:
    """Powers as C would evaluate them: small integer powers as products, so math and numpy agree."""
    base, ex = expr.base, expr.exp
    b = printer.parenthesize(base, 1000)  # always parenthesise the base
    if ex == sp.Rational(1, 2):
        return f"{sqrt}({printer._print(base)})"
    if ex == sp.Rational(-1, 2):
        return f"(1/{sqrt}({printer._print(base)}))"
    if ex.is_Integer:
        k = int(ex)
        if k == -1:
            return f"(1/{b})"
        if 2 <= abs(k) <= 4:
            prod = "*".join([b] * abs(k))
            return f"({prod})" if k > 0 else f"(1/({prod}))"
    return f"{power}({printer._print(base)}, {printer._print(ex)})"


class _MathPrinter(PythonCodePrinter):
    def __init__(self) -> None:
        super().__init__({"fully_qualified_modules": True})

    def _print_Pow(self, expr, rational=False):  # noqa: D102 - printer hook
        return _pow(self, expr, "math.sqrt", "math.pow")


class _ArrayPrinter(NumPyPrinter):
    def _print_Pow(self, expr, rational=False):  # noqa: D102 - printer hook
        return _pow(self, expr, "numpy.sqrt", "numpy.power")


def _lit(value: float) -> str:
    """A float literal that round-trips exactly."""
    return repr(float(value))


def _lin(terms: Sequence[tuple[float, str]]) -> str:
    """``sum(coef * name)`` with zero terms dropped and unit coefficients folded; '' if empty."""
    out: list[str] = []
    for coef, name in terms:
        if coef == 0.0:
            continue
        if coef == 1.0:
            piece = name
        elif coef == -1.0:
            piece = f"-{name}"
        else:
            piece = f"{_lit(coef)}*{name}"
        if out and piece.startswith("-"):
            out.append(f"- {piece[1:]}")
        elif out:
            out.append(f"+ {piece}")
        else:
            out.append(piece)
    return " ".join(out)


def _sum(parts: Sequence[str]) -> str:
    parts = [p for p in parts if p]
    return " + ".join(parts) if parts else "0.0"


# --------------------------------------------------------------------------- lowering
@dataclass(frozen=True)
class _Lowered:
    """An :class:`ObserverSpec` in numbers: floats, and expressions in ``S0, S1, ...`` (signals) and ``s``."""

    A: np.ndarray                      # n x n
    C: np.ndarray                      # n
    K_plus: np.ndarray                 # n
    K_minus: np.ndarray                # n
    time_scale: sp.Expr                # in S0..
    drift: tuple[sp.Expr, ...]         # c_i, in S0.. and s
    regressor: tuple[tuple[sp.Expr, ...], ...]  # Psi_ij (n x p), in S0.. and s
    Gamma: np.ndarray                  # p x p (0 x 0 without unknowns)
    n_signals: int

    @property
    def n(self) -> int:
        return len(self.C)

    @property
    def p(self) -> int:
        return self.Gamma.shape[0]

    @property
    def size(self) -> int:
        return self.n + self.p + self.n * self.p


SIGNAL = "S"


def signal_symbols(count: int) -> tuple[sp.Symbol, ...]:
    return tuple(sp.Symbol(f"{SIGNAL}{i}", real=True) for i in range(count))


def check_free(expr: sp.Basic, allowed: set, what: str, model: Model) -> None:
    """Refuse ``t`` and any symbol outside ``allowed`` in an expression the observer evaluates."""
    t = model.symbols["t"]
    if t in expr.free_symbols:
        raise ModelError(f"{what} of model {model.name!r} depends on t explicitly; the observers hold the "
                         "signals constant over a step and take no time argument (neither does the C API): "
                         "make time an external signal instead")
    free = sorted(str(s) for s in expr.free_symbols - allowed)
    if free:
        raise FreeSymbolError(f"{what} of model {model.name!r} still depends on {free}; give their values "
                              f"(e.g. params={{{free[0]!r}: ...}})")


def _lower(spec: ObserverSpec) -> _Lowered:
    """Substitute the spec's parameter values and name the signals ``S0, S1, ...``."""
    model = spec.model
    subs = {model.symbols[k]: v for k, v in spec.values.items()}
    sig_syms = [model.symbols[name] for name in model.signals]
    S = signal_symbols(len(sig_syms))
    to_S = dict(zip(sig_syms, S))
    time_scale = model.time_scale.subs(subs)
    check_free(time_scale, set(sig_syms), "time_scale", model)
    allowed = set(sig_syms) | {SCALE}
    drift = [c.subs(subs) for c in spec.drift]
    regressor = [[q.subs(subs) for q in row] for row in spec.regressor]
    for i in range(spec.n):
        for expr in (drift[i], *regressor[i]):
            check_free(expr, allowed, f"d or b (row {i + 1})", model)
    return _Lowered(A=numeric(model.A, subs, what=f"A of model {model.name!r}"),
                    C=numeric(model.C, subs, what=f"C of model {model.name!r}").reshape(spec.n),
                    K_plus=np.array(spec.K_plus, dtype=float), K_minus=np.array(spec.K_minus, dtype=float),
                    time_scale=time_scale.xreplace(to_S), drift=tuple(c.xreplace(to_S) for c in drift),
                    regressor=tuple(tuple(q.xreplace(to_S) for q in row) for row in regressor),
                    Gamma=np.array(spec.Gamma, dtype=float).reshape(spec.p, spec.p), n_signals=len(S))


class _Source:
    """Generates the Python source of the kernel functions from a lowered spec."""

    def __init__(self, spec: _Lowered):
        self.spec = spec
        n, p = spec.n, spec.p
        self.x = [f"x{k}" for k in range(spec.size)]
        self.sig = [f"{SIGNAL}{i}" for i in range(spec.n_signals)]
        self.g = [f"g{i}" for i in range(n)]
        self.c = [f"c{i}" if spec.drift[i] != 0 else "" for i in range(n)]
        self.psi = [[f"q{i}_{j}" if spec.regressor[i][j] != 0 else "" for j in range(p)] for i in range(n)]

    # per-step quantities -------------------------------------------------------
    def prelude_names(self) -> list[str]:
        """The per-step quantities, in the order ``prelude`` returns them and ``loop`` unpacks them."""
        names = ["s", *self.g, *[c for c in self.c if c]]
        names += [q for row in self.psi for q in row if q]
        return names

    def math_prelude(self, indent: str) -> list[str]:
        """Lines computing g, c, Psi from ``s`` and the signals (pure Python floats)."""
        spec, pr = self.spec, _MathPrinter()
        lines = [f"{indent}if s > 0.0:"]
        lines += [f"{indent}    {g} = s*{_lit(k)}" for g, k in zip(self.g, spec.K_plus)]
        lines += [f"{indent}else:"]
        lines += [f"{indent}    {g} = s*{_lit(k)}" for g, k in zip(self.g, spec.K_minus)]
        for i, c in enumerate(self.c):
            if c:
                lines.append(f"{indent}{c} = {pr.doprint(spec.drift[i])}")
        for i, row in enumerate(self.psi):
            for j, q in enumerate(row):
                if q:
                    lines.append(f"{indent}{q} = {pr.doprint(spec.regressor[i][j])}")
        return lines

    def array_prelude(self, indent: str) -> list[str]:
        """The same quantities for all rows at once (NumPy, elementwise the same operations)."""
        spec, pr = self.spec, _ArrayPrinter()
        lines = [f"{indent}s = {pr.doprint(spec.time_scale)} + zero"]
        lines += [f"{indent}{g} = numpy.where(s > 0.0, s*{_lit(kp)}, s*{_lit(km)})"
                  for g, kp, km in zip(self.g, spec.K_plus, spec.K_minus)]
        for i, c in enumerate(self.c):
            if c:
                lines.append(f"{indent}{c} = {pr.doprint(spec.drift[i])} + zero")
        for i, row in enumerate(self.psi):
            for j, q in enumerate(row):
                if q:
                    lines.append(f"{indent}{q} = {pr.doprint(spec.regressor[i][j])} + zero")
        return lines

    # one evaluation of the right-hand side ------------------------------------
    def stage(self, xin: Sequence[str], kout: Sequence[str], indent: str) -> list[str]:
        """Lines computing the derivatives ``kout`` at the state ``xin``."""
        spec = self.spec
        n, p = spec.n, spec.p
        w = xin[:n]
        th = xin[n:n + p]
        U = [[xin[n + p + i * p + j] for j in range(p)] for i in range(n)]  # Upsilon, row-major
        lines = [f"{indent}e = {self.sig[0]} - ({_lin(list(zip(spec.C, w))) or '0.0'})"]
        for j in range(p):
            lines.append(f"{indent}r{j} = {_lin([(spec.C[i], U[i][j]) for i in range(n)]) or '0.0'}")
        for j in range(p):
            lines.append(f"{indent}m{j} = {_lin([(spec.Gamma[j, l], f'r{l}') for l in range(p)]) or '0.0'}")
        for i in range(n):
            Aw = _lin([(spec.A[i, j], w[j]) for j in range(n)])
            parts = [f"s*({Aw})" if Aw else "", self.c[i]]
            parts += [f"{self.psi[i][j]}*{th[j]}" for j in range(p) if self.psi[i][j]]
            gain = _sum([self.g[i], *[f"{U[i][j]}*m{j}" for j in range(p)]])
            parts.append(f"({gain})*e" if p else f"{self.g[i]}*e")
            lines.append(f"{indent}{kout[i]} = {_sum(parts)}")
        for j in range(p):
            lines.append(f"{indent}{kout[n + j]} = m{j}*e")
        for i in range(n):
            for j in range(p):
                AU = _lin([(spec.A[i, k], U[k][j]) for k in range(n)])
                parts = [f"s*({AU})" if AU else "", f"-{self.g[i]}*r{j}"]
                if self.psi[i][j]:
                    parts.append(self.psi[i][j])
                lines.append(f"{indent}{kout[n + p + i * p + j]} = {_sum(parts).replace('+ -', '- ')}")
        return lines

    def advance(self, method: str, indent: str) -> tuple[list[str], list[str]]:
        """Lines advancing ``x0..`` by one step of ``dt`` into ``y0..``; returns (lines, new names)."""
        N = self.spec.size
        x = self.x
        new = [f"y{k}" for k in range(N)]
        k1 = [f"k1_{k}" for k in range(N)]
        lines = self.stage(x, k1, indent)
        if method == "euler":
            lines += [f"{indent}{new[k]} = {x[k]} + dt*{k1[k]}" for k in range(N)]
            return lines, new
        if not STEP_METHODS[method].explicit:
            return lines + self.implicit(method, k1, new, indent), new
        k2, k3, k4 = ([f"k{j}_{k}" for k in range(N)] for j in (2, 3, 4))
        t = [f"t{k}" for k in range(N)]
        lines += [f"{indent}{t[k]} = {x[k]} + h*{k1[k]}" for k in range(N)]
        lines += self.stage(t, k2, indent)
        lines += [f"{indent}{t[k]} = {x[k]} + h*{k2[k]}" for k in range(N)]
        lines += self.stage(t, k3, indent)
        lines += [f"{indent}{t[k]} = {x[k]} + dt*{k3[k]}" for k in range(N)]
        lines += self.stage(t, k4, indent)
        lines += [f"{indent}{new[k]} = {x[k]} + dt6*({k1[k]} + 2.0*{k2[k]} + 2.0*{k3[k]} + {k4[k]})"
                  for k in range(N)]
        return lines, new

    def implicit(self, method: str, f: Sequence[str], new: Sequence[str], indent: str) -> list[str]:
        """Lines of ``new = x + dt D(Z)^-1 F(Z) f`` (NaN where ``D(Z)`` is singular), straight-line.

        They are the operations of :func:`switchobs.spec.implicit_increment` on ``J = s A - g C`` (the
        function the C translation evaluates on casadi SX), recorded by running it on :class:`_Recorder`
        scalars, so that a step is plain float arithmetic and cannot raise.
        """
        spec, lines = self.spec, []
        leaf = lambda name: _Recorder(name, lines)  # noqa: E731
        A = [[None if a == 0.0 else float(a) for a in row] for row in spec.A]
        C = [None if c == 0.0 else float(c) for c in spec.C]
        J = affine_jacobian(A, C, leaf("s"), [leaf(g) for g in self.g])
        inc, det = implicit_increment(STEP_METHODS[method], J, [leaf(k) for k in f], leaf("dt"), _Recorder.safe)
        out = [f"{indent}{line}" for line in lines]
        floor = STEP_METHODS[method].det_floor(spec.size)  # the C step's DET_MIN: the same refusal
        out.append(f"{indent}ok = abs({_operand(det)}) >= {floor!r} and math.isfinite({_operand(det)})")
        out += [f"{indent}{new[k]} = {self.x[k]} + dt*{_operand(inc[k])} if ok else math.nan"
                for k in range(spec.size)]
        return out

    def module(self, method: str) -> str:
        spec = self.spec
        N = spec.size
        xs, sigs = ", ".join(self.x), ", ".join(self.sig)
        pr = _MathPrinter()
        steps = "    h = 0.5*dt\n    dt6 = dt/6.0\n" if method == "rk4" else ""
        adv, new = self.advance(method, "    ")
        adv_loop, _ = self.advance(method, "        ")
        deriv = self.stage(self.x, [f"d{k}" for k in range(N)], "    ")
        pre = ", ".join(self.prelude_names())
        src = [
            f"def scale({sigs}):",
            f"    return {pr.doprint(spec.time_scale)}",
            "",
            f"def advance(x, sig, s, dt):",
            f"    {xs}, = x",
            f"    {sigs}, = sig",
            *self.math_prelude("    "),
            steps.rstrip("\n"),
            *adv,
            f"    return ({', '.join(new)},)",
            "",
            f"def derivative(x, sig, s):",
            f"    {xs}, = x",
            f"    {sigs}, = sig",
            *self.math_prelude("    "),
            *deriv,
            f"    return ({', '.join(f'd{k}' for k in range(N))},)",
            "",
            f"def prelude({sigs}):",
            "    zero = numpy.zeros_like(S0)",
            *self.array_prelude("    "),
            f"    return [{pre}]",
            "",
            f"def loop(x, columns, dt):",
            f"    {xs}, = x",
            steps.rstrip("\n"),
            "    out = []",
            "    push = out.append",
            f"    for {sigs}, {pre} in zip(*columns):",
            *adv_loop,
            f"        {xs} = {', '.join(new)}",
            f"        push(({xs},))",
            "    return out",
        ]
        return "\n".join(line for line in src if line != "") + "\n"


def _operand(value) -> str:
    """A recorded temporary by name, a constant as a literal that round-trips exactly."""
    return value.name if isinstance(value, _Recorder) else f"({_lit(value)})"


class _Recorder:
    """A scalar that writes every operation on it as a line ``_tK = a op b`` of straight-line Python."""

    def __init__(self, name: str, lines: list[str]):
        self.name, self.lines = name, lines

    def _op(self, template: str, *args) -> _Recorder:
        name = f"_t{len(self.lines)}"
        self.lines.append(f"{name} = {template.format(*map(_operand, args))}")
        return _Recorder(name, self.lines)

    def __add__(self, other): return self._op("{} + {}", self, other)  # noqa: E704
    def __radd__(self, other): return self._op("{} + {}", other, self)  # noqa: E704
    def __sub__(self, other): return self._op("{} - {}", self, other)  # noqa: E704
    def __rsub__(self, other): return self._op("{} - {}", other, self)  # noqa: E704
    def __mul__(self, other): return self._op("{}*{}", self, other)  # noqa: E704
    def __rmul__(self, other): return self._op("{}*{}", other, self)  # noqa: E704
    def __truediv__(self, other): return self._op("{}/{}", self, other)  # noqa: E704
    def __rtruediv__(self, other): return self._op("{}/{}", other, self)  # noqa: E704
    def __neg__(self): return self._op("-{}", self)  # noqa: E704

    @staticmethod
    def safe(det):
        """``det`` where it is nonzero, else 1 (the solve divides by it)."""
        if isinstance(det, _Recorder):
            return det._op("{0} if {0} != 0.0 else 1.0", det)
        return det if det != 0.0 else 1.0


# --------------------------------------------------------------------------- kernel
_NONFINITE = ("the step produced a non-finite state (overflow, or a domain error in d(y), b(y)); "
              "reduce dt or check the signals")


class Kernel:
    """Compiled step / derivative / run of one observer, with the input checks of :class:`ErrorCode`.

    ``h_max`` (a positive double or None) and ``max_substeps`` bound the step in rescaled time (see the
    module docstring).
    """

    def __init__(self, spec: ObserverSpec, method: str, *, h_max: float | None = None,
                 max_substeps: int = DEFAULT_MAX_SUBSTEPS):
        if method not in METHODS:
            raise SimulationError(f"unknown discretisation method {method!r}; choose one of {list(METHODS)}")
        if spec.p:
            require_explicit(method, "the adaptive observer's right-hand side", SimulationError)
        self.spec = spec
        self.method = method
        self.lowered = _lower(spec)
        self.source = _Source(self.lowered).module(method)
        namespace: dict = {"math": math, "numpy": np}
        exec(compile(self.source, f"<switchobs observer kernel ({method})>", "exec"), namespace)
        self._scale = namespace["scale"]
        self._advance = namespace["advance"]
        self._derivative = namespace["derivative"]
        self._prelude = namespace["prelude"]
        self._loop = namespace["loop"]
        self._signed = tuple((i, sg) for i, sg in enumerate(spec.signal_signs) if sg)
        self.h_max = h_max
        self.max_substeps = max_substeps

    # -------------------------------------------------------------- checks
    def _fail(self, code: ErrorCode, detail: str, row: int | None = None) -> ObserverInputError:
        where = f"row {row}: " if row is not None else ""
        return ObserverInputError(f"observer step refused ({code.name}, code {int(code)}): {where}{detail}", int(code))

    @staticmethod
    def floats(values, names: Sequence[str], what: str) -> list[float]:
        """``values`` as a list of Python floats, one per name (DimensionError otherwise)."""
        return named_vector(values, names, what).tolist()

    def check_dt(self, dt) -> float:
        try:
            dt_f = float(dt)
        except (TypeError, ValueError):
            raise self._fail(ErrorCode.BAD_DT, f"dt = {dt!r} is not a number") from None
        if not math.isfinite(dt_f) or dt_f <= 0.0:
            raise self._fail(ErrorCode.BAD_DT, f"dt = {dt_f!r} must be finite and > 0 (seconds)")
        return dt_f

    def check_state(self, x: list[float]) -> None:
        for name, v in zip(self.spec.state_names, x):
            if not math.isfinite(v):
                raise self._fail(ErrorCode.NONFINITE_STATE, f"state {name} = {v!r} is not finite; "
                                 "reset the observer")

    def check_signals(self, sig: list[float], row: int | None = None) -> float:
        """Codes 3 and 4 for one row of signals; returns the time scaling s."""
        names = self.spec.signal_names
        for name, v in zip(names, sig):
            if not math.isfinite(v):
                raise self._fail(ErrorCode.NONFINITE_SIGNAL, f"signal {name} = {v!r} is not finite", row)
        for i, sign in self._signed:
            if sig[i] * sign <= 0.0:
                want = "> 0" if sign > 0 else "< 0"
                raise self._fail(ErrorCode.UNDEFINED_TIME_SCALE, f"signal {names[i]} = {sig[i]!r} must be {want} "
                                 "(the time scaling is undefined there)", row)
        try:
            s = float(self._scale(*sig))
        except (ArithmeticError, ValueError):
            s = math.nan
        if not math.isfinite(s):
            raise self._fail(ErrorCode.UNDEFINED_TIME_SCALE, f"time scaling s = {s!r} is not finite at "
                             + ", ".join(f"{k} = {v!r}" for k, v in zip(names, sig)), row)
        return s

    def substeps(self, s: float, dt: float, row: int | None = None) -> int:
        """Sub-steps of a step of ``dt`` at the time scaling ``s`` (1 without ``h_max``); SUBSTEP_LIMIT beyond."""
        if self.h_max is None:
            return 1
        a = abs(s) * dt  # the same float operations as the generated C, so that both choose the same n
        if a <= self.h_max:
            return 1
        q = a / self.h_max
        if not q <= self.max_substeps:
            raise self._fail(ErrorCode.SUBSTEP_LIMIT, f"|s|*dt = {a!r} needs {q:.6g} sub-steps of h_max = "
                             f"{self.h_max!r}, more than max_substeps = {self.max_substeps}; reduce dt or raise "
                             "max_substeps", row)
        return math.ceil(q)

    def _substepped(self, x: list[float], sig: list[float], s: float, dt: float, n: int):
        h = dt / n
        for _ in range(n):
            x = self._advance(x, sig, s, h)
        return x

    def _result(self, fn, *args) -> list[float]:
        try:
            out = fn(*args)
        except (ArithmeticError, ValueError):  # math domain errors, division by zero, overflow in math.exp
            out = (math.nan,)
        if not all(map(math.isfinite, out)):
            raise self._fail(ErrorCode.NONFINITE_RESULT, _NONFINITE)
        return list(out)

    # -------------------------------------------------------------- numerics
    def step(self, x: list[float], sig: list[float], dt: float) -> list[float]:
        """One step on already-converted floats (checks in :class:`ErrorCode` order)."""
        dt = self.check_dt(dt)
        self.check_state(x)
        s = self.check_signals(sig)
        n = self.substeps(s, dt)
        if n == 1:
            return self._result(self._advance, x, sig, s, dt)
        return self._result(self._substepped, x, sig, s, dt, n)

    def derivative(self, x: list[float], sig: list[float]) -> list[float]:
        self.check_state(x)
        s = self.check_signals(sig)
        return self._result(self._derivative, x, sig, s)

    def run(self, x0: list[float], rows: np.ndarray, dt: float) -> np.ndarray:
        """Step through ``rows`` (k x n_signals); the states after each step, shape (k, N).

        Raises the error ``step`` would raise at the first failing row (the
        message names the row).
        """
        dt = self.check_dt(dt)
        self.check_state(x0)
        k = rows.shape[0]
        if k == 0:
            return np.empty((0, self.spec.size))
        cols = [rows[:, i] for i in range(rows.shape[1])]
        with np.errstate(all="ignore"):
            pre = [np.asarray(v, dtype=float) for v in self._prelude(*cols)]
        bad = ~np.isfinite(rows).all(axis=1) | ~np.isfinite(pre[0])
        for i, sign in self._signed:
            bad |= ~(rows[:, i] * sign > 0.0)
        stiff = np.zeros(k, dtype=bool)
        if self.h_max is not None:
            with np.errstate(all="ignore"):
                a = np.abs(pre[0]) * dt
                stiff = ~(a <= self.h_max)
                bad |= stiff & ~(a / self.h_max <= self.max_substeps)
        valid = int(np.argmax(bad)) if bad.any() else k
        lists = [c[:valid].tolist() for c in cols] + [c[:valid].tolist() for c in pre]
        # The loop only adds and multiplies floats, so it cannot raise; overflow shows up as inf/nan.
        traj = np.empty((valid, self.spec.size))
        start = 0
        for i in [*np.flatnonzero(stiff[:valid]).tolist(), valid]:  # stretches of one step each, then a stiff row
            if i > start:
                traj[start:i] = self._loop(x0, [c[start:i] for c in lists], dt)
                x0 = traj[i - 1].tolist()
            if i < valid:
                s = float(pre[0][i])
                try:
                    traj[i] = self._substepped(x0, rows[i].tolist(), s, dt, self.substeps(s, dt, i))
                except (ArithmeticError, ValueError):
                    traj[i] = math.nan
                x0 = traj[i].tolist()
            start = i + 1
        finite = np.isfinite(traj).all(axis=1)
        if not finite.all():
            raise self._fail(ErrorCode.NONFINITE_RESULT, _NONFINITE, int(np.argmin(finite)))
        if valid < k:
            self.check_signals(rows[valid].tolist(), valid)
            self.substeps(float(pre[0][valid]), dt, valid)
            # numpy found s non-finite where math did not (never seen; refuse rather than skip rows)
            raise self._fail(ErrorCode.UNDEFINED_TIME_SCALE, "time scaling is not finite", valid)
        return traj
