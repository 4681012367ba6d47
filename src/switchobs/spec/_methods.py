"""The step methods of the observers, by stability function, and the one implicit step of an affine ODE.

With the signals held over a step the observer's right-hand side is affine in
its state, ``f(x) = J x + c`` (switched observer: ``J = s A - g C``), and one
step of a Runge-Kutta method with stability function ``R = N / D`` is exactly

    x+ = x + dt D(Z)^-1 F(Z) f(x),      Z = dt J,      F(z) = (N(z) - D(z)) / z,

(for ``R(z) = 1 + z F(z) / D(z)``, the affine flow's step).  The explicit
methods have ``D = 1`` and are evaluated stage by stage; for the implicit
ones (midpoint, radau3) :func:`implicit_increment` evaluates the formula with
one linear solve by cofactors.  It is written once, over any scalar type with
``+ - * /`` (Python floats for the reference observers, casadi SX for the
generated C), so both make the same operations in the same order, and it
divides exactly once, by ``det D(Z)`` made safe (a zero determinant is
replaced by 1 and reported, never divided by).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from ..exceptions import ModelError

__all__ = ["StepMethod", "STEP_METHODS", "METHODS", "DEFAULT_METHOD", "CERTIFIED_METHODS", "IMPLICIT_MAX_N",
           "implicit_increment", "affine_jacobian", "require_explicit", "uncertified_note", "default_method"]

#: Largest state dimension of an implicit step: the cofactor solve shares minors over subsets of rows, so its
#: size grows like 2^n (n = 12: 1.5 s to generate, 0.14 MB of C; n = 16: 21 s, 0.33 MB).
IMPLICIT_MAX_N = 12


@dataclass(frozen=True)
class StepMethod:
    """A one-step method through its stability function ``R(z) = N(z) / D(z)`` (coefficients from ``z^0``).

    For the observer's held-signal right-hand side ``f(x) = J x + c`` (affine
    in the state) one step is ``x+ = x + dt D(Z)^-1 F(Z) f(x)`` with
    ``Z = dt J`` and ``F(z) = (N(z) - D(z)) / z``; for an explicit method
    ``D = 1``.
    """

    name: str
    numerator: tuple[Fraction, ...]
    denominator: tuple[Fraction, ...]
    order: int
    description: str

    def __post_init__(self) -> None:
        if self.numerator[0] != self.denominator[0]:
            raise ModelError(f"step method {self.name}: R(0) = N(0) / D(0) must be 1")

    @property
    def explicit(self) -> bool:
        return len(self.denominator) == 1

    @property
    def increment(self) -> tuple[Fraction, ...]:
        """Coefficients of ``F(z) = (N(z) - D(z)) / z``."""
        size = max(len(self.numerator), len(self.denominator))
        num = list(self.numerator) + [Fraction(0)] * (size - len(self.numerator))
        den = list(self.denominator) + [Fraction(0)] * (size - len(self.denominator))
        diff = [a - b for a, b in zip(num, den)]
        while len(diff) > 2 and diff[-1] == 0:
            diff.pop()
        return tuple(diff[1:])

    def det_floor(self, n: int) -> float:
        """Half the least ``|det D(Z)|`` of an ``n x n`` ``Z`` whose eigenvalues have real part ``<= 0``.

        ``det D(Z)`` is the product of ``D(lambda_i)`` over the eigenvalues of ``Z``, and for ``Re z <= 0``
        ``|D(z)| = |d_m| prod_k |z - r_k| >= |d_m| prod_k Re r_k`` (the roots ``r_k`` of ``D`` have positive
        real part): 1 for the midpoint rule, 2/3 for 2-stage Radau IIA, so ``(2/3)^n`` there.  A step whose
        ``|det D(Z)|`` is below half that bound (``Z = dt J`` with ``J`` not Hurwitz: runtime gains of
        another design) is refused, so the one division of the solve is by a number bounded away from
        zero, which any analyser sees locally.  1 for an explicit method (``D = 1``).
        """
        if self.explicit:
            return 1.0
        import numpy as np

        roots = np.roots([float(c) for c in reversed(self.denominator)])
        if not np.all(roots.real > 0):
            raise ModelError(f"step method {self.name}: D(z) has a root {roots[roots.real <= 0][0]} with "
                             "non-positive real part")
        bound = abs(float(self.denominator[-1])) * float(np.prod(roots.real))
        return 0.5 * bound ** n


def _fr(*values: int | str) -> tuple[Fraction, ...]:
    return tuple(Fraction(v) for v in values)


#: The step methods of the generated C and the Python observers, by stability function.
STEP_METHODS: dict[str, StepMethod] = {
    "rk4": StepMethod("rk4", _fr(1, 1, "1/2", "1/6", "1/24"), _fr(1), 4, "classic Runge-Kutta (explicit, order 4)"),
    "euler": StepMethod("euler", _fr(1, 1), _fr(1), 1, "forward Euler (explicit, order 1)"),
    "midpoint": StepMethod("midpoint", _fr(1, "1/2"), _fr(1, "-1/2"), 2,
                           "implicit midpoint rule (1-stage Gauss, A-stable, order 2)"),
    "radau3": StepMethod("radau3", _fr(1, "1/3"), _fr(1, "-2/3", "1/6"), 3,
                         "2-stage Radau IIA (L-stable, algebraically stable, order 3)"),
}

#: Discretisations of one step: "rk4", "euler" (explicit), "midpoint", "radau3" (implicit).
METHODS: tuple[str, ...] = tuple(STEP_METHODS)

#: The methods whose sampled switched observer keeps the design's Lyapunov function non-increasing for every step
#: length (algebraically stable, ``switchobs certify --discrete``); for rk4 (n >= 3) and euler (n >= 2) no step
#: bound is a certificate (docs/certify.md, "The sampled observer").
CERTIFIED_METHODS: tuple[str, ...] = ("midpoint", "radau3")

#: The step method chosen when none is given, wherever the right-hand side is affine in the state (the switched
#: observer): certified at every step length and of higher order than midpoint.  The adaptive observer, whose
#: right-hand side is not affine in its state, takes an explicit method (:func:`require_explicit`).
DEFAULT_METHOD = "radau3"


def default_method(n: int, *, affine: bool = True) -> str:
    """The step method when none is chosen, for an observer of ``n`` states.

    :data:`DEFAULT_METHOD` (radau3) wherever it applies: a right-hand side affine in the state (the switched
    observer) and ``n <= IMPLICIT_MAX_N`` (the cofactor solve grows like 2^n).  Elsewhere rk4: the adaptive
    observer (not affine: explicit steps only) and larger switched observers (uncertified: bound the step
    with ``h_max``).

    Examples
    --------
    >>> default_method(3), default_method(3, affine=False), default_method(IMPLICIT_MAX_N + 1)
    ('radau3', 'rk4', 'rk4')
    """
    return DEFAULT_METHOD if affine and n <= IMPLICIT_MAX_N else "rk4"


def uncertified_note(method: str) -> str | None:
    """One line saying that ``method`` is not certified, or None for a certified one.

    The command line prints it on stderr when an uncertified method is chosen (not an error).

    Examples
    --------
    >>> uncertified_note("radau3") is None
    True
    >>> uncertified_note("rk4")
    "method 'rk4' is not certified: for n >= 3 states no step bound keeps the sampled error decreasing; radau3 and midpoint are certified for every step"
    """
    if method in CERTIFIED_METHODS or method not in STEP_METHODS:
        return None
    n_min = 3 if method == "rk4" else 2
    return (f"method {method!r} is not certified: for n >= {n_min} states no step bound keeps the sampled error "
            f"decreasing; "
            f"radau3 and midpoint are certified for every step")

Entry = Any  # a scalar (float, casadi SX) or None for a structural zero


def _add(a: Entry, b: Entry) -> Entry:
    return b if a is None else a if b is None else a + b


def _mul(a: Entry, b: Entry) -> Entry:
    return None if a is None or b is None else a * b


def _scaled(coef: Fraction, a: Entry) -> Entry:
    if a is None or coef == 0:
        return None
    return a if coef == 1 else float(coef) * a


def _matpoly(coeffs: Sequence[Fraction], Z: list[list[Entry]]) -> list[list[Entry]]:
    """``sum_k coeffs[k] Z^k`` (``Z^0 = I``), structural zeros as None."""
    n = len(Z)
    out = [[_scaled(coeffs[0], 1.0) if i == j else None for j in range(n)] for i in range(n)]
    power = Z
    for k, coef in enumerate(coeffs[1:], start=1):
        if k > 1:
            power = [[_sum(_mul(power[i][m], Z[m][j]) for m in range(n)) for j in range(n)] for i in range(n)]
        out = [[_add(out[i][j], _scaled(coef, power[i][j])) for j in range(n)] for i in range(n)]
    return out


def _sum(terms) -> Entry:
    total = None
    for t in terms:
        total = _add(total, t)
    return total


def _vecpoly(coeffs: Sequence[Fraction], Z: list[list[Entry]], f: Sequence[Entry]) -> list[Entry]:
    """``sum_k coeffs[k] Z^k f`` (Horner-free: ``Z^k f`` as repeated products with ``f``)."""
    n = len(f)
    out = [_scaled(coeffs[0], v) for v in f]
    v = list(f)
    for coef in coeffs[1:]:
        v = [_sum(_mul(Z[i][m], v[m]) for m in range(n)) for i in range(n)]
        out = [_add(a, _scaled(coef, b)) for a, b in zip(out, v)]
    return out


def _alternating(terms, start: int = 0) -> Entry:
    """``sum_k (-1)^(start + k) terms[k]``, skipping structural zeros (None if all are)."""
    total = None
    for k, term in enumerate(terms, start=start):
        if term is None:
            continue
        if total is None:
            total = term if k % 2 == 0 else -term
        else:
            total = total + term if k % 2 == 0 else total - term
    return total


def _minor_det(M: list[list[Entry]], rows: tuple[int, ...], cols: tuple[int, ...],
               memo: dict[tuple[tuple[int, ...], tuple[int, ...]], Entry]) -> Entry:
    """Determinant of ``M[rows][cols]`` by expansion along its first row (minors shared through ``memo``)."""
    if len(rows) == 1:
        return M[rows[0]][cols[0]]
    key = (rows, cols)
    if key not in memo:
        memo[key] = _alternating(_mul(M[rows[0]][c], _minor_det(M, rows[1:], cols[:k] + cols[k + 1:], memo))
                                 for k, c in enumerate(cols))
    return memo[key]


def implicit_increment(method: StepMethod, J: Sequence[Sequence[Entry]], f: Sequence[Entry], dt: Any,
                       safe: Callable[[Any], Any]) -> tuple[list[Any], Any]:
    """``D(Z)^-1 F(Z) f`` with ``Z = dt J``, and ``det D(Z)``; the step is ``x + dt * increment``.

    Parameters
    ----------
    method : StepMethod
        An implicit method (``D`` not constant).
    J : n x n scalars or None
        The Jacobian of the held-signal right-hand side (None: structural zero).
    f : n scalars
        ``f(x)``.
    dt : scalar
    safe : callable
        ``safe(det)``: ``det`` where it is nonzero, else 1 (``d if d != 0 else 1.0`` for floats,
        ``casadi.if_else(d != 0, d, 1)`` for SX), so that the solve never divides by zero.

    Returns
    -------
    increment, det
        The caller must refuse the step unless ``det`` is finite and ``|det| >= method.det_floor(n)``
        (:meth:`StepMethod.det_floor`; below it the increment is meaningless or ill-conditioned).  By Cramer's rule with the cofactors of ``D(Z)``; ``D(Z)`` is
        nonsingular whenever ``J`` is Hurwitz (the roots of ``D`` have positive real part).
    """
    if method.explicit:
        raise ModelError(f"implicit_increment needs an implicit method, got {method.name!r}")
    n = len(f)
    if n > IMPLICIT_MAX_N:
        raise ModelError(f"method {method.name!r} solves its step by cofactors, whose size grows like 2^n: "
                         f"n = {n} > {IMPLICIT_MAX_N}; use an explicit method with a step bound (h_max) instead")
    Z = [[None if J[i][j] is None else dt * J[i][j] for j in range(n)] for i in range(n)]
    D = _matpoly(method.denominator, Z)
    r = _vecpoly(method.increment, Z, f)
    memo: dict = {}
    idx = tuple(range(n))
    # adj(D)_ij = (-1)^(i+j) det(D without row j, column i); det D by the first row's cofactors
    cof = [[_minor_det(D, idx[:j] + idx[j + 1:], idx[:i] + idx[i + 1:], memo) if n > 1 else 1.0
            for j in range(n)] for i in range(n)]
    det = _alternating(_mul(D[0][i], cof[i][0]) for i in range(n))
    if det is None:
        det = 0.0 * dt  # D(Z) is structurally singular
    inv = 1.0 / safe(det)
    out = []
    for i in range(n):
        total = _alternating((_mul(cof[i][j], r[j]) for j in range(n)), start=i)
        out.append(0.0 * dt if total is None else total * inv)
    return out, det


def affine_jacobian(A: Sequence[Sequence[Entry]], C: Sequence[Entry], s: Any, g: Sequence[Any]) -> list[list[Entry]]:
    """``J = s A - g C`` (``J_ij = s A_ij - g_i C_j``): the state Jacobian of the switched observer's right-hand side.

    ``s (A w) + c + g (y - C w)`` with the signals held (seed 000 eq. (8)-(9)); structural zeros of
    ``A`` and ``C`` are None and stay None.
    """
    n = len(C)
    out = []
    for i in range(n):
        row = []
        for j in range(n):
            a, c = _mul(s, A[i][j]), _mul(g[i], C[j])
            row.append(a if c is None else -c if a is None else a - c)
        out.append(row)
    return out


def require_explicit(method: str, why: str, error: type[Exception]) -> None:
    """Refuse an implicit ``method`` for a right-hand side that is not affine in the state (``why`` says which)."""
    if not STEP_METHODS[method].explicit:
        raise error(f"method {method!r} is implicit, and {why} is not affine in its state (the estimates multiply "
                    "Upsilon and the output error), so its step would need a nonlinear solve; use "
                    f"{' or '.join(m for m in METHODS if STEP_METHODS[m].explicit)}")
