"""Switched-observer gain design: K_plus, K_minus, Routh conditions and the common P.

Error dynamics in the rescaled time ``tau = ∫|s| dt`` (seed 004; seed 000 eq. (13)):

    de/dtau = A_plus e   (s > 0),   A_plus  =  A - K_plus  C
    de/dtau = A_minus e  (s < 0),   A_minus = -A + K_minus C

In observer normal form (``K_nf = T K``), ``D A_minus D`` with
``D = diag(1, -1, 1, ...)`` is the companion matrix of the coefficients
``alpha_minus_i = (-1)^i (k_nf_minus_i - a_i)``, while ``A_plus`` has
``alpha_plus_i = k_nf_plus_i - a_i``.  The observer-form Lyapunov solution
``P(alpha)`` is checkerboard, so ``D P D = P`` and a common ``P`` with
``C_plus = c_plus C``, ``C_minus = c_minus C`` exists iff ``P(alpha_plus)`` and
``P(alpha_minus)`` are proportional (the family of Hoang et al., seed 000
eq. (17) for n = 3).  ``alpha_minus = alpha_plus`` is the unique choice with
``c_plus = c_minus`` (Theorem 1 of seed 004):
``k_i^- = (-1)^i k_i^+ + (1 - (-1)^i) a_i`` in normal form.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import flint
import numpy as np
import sympy as sp
from sympy.polys.matrices import DomainMatrix

from ..exceptions import (CertificateError, DimensionError, ExpressionError, ModelError, NotHurwitzError,
                          NotObservableError, SpectrumError)
from ..model import Model, entries, free_names, make_symbol, numeric, parse_expression, rational_value
from ._lyapunov import _generic_solution, checkerboard_rows, gramian_entries, observer_form_gramian
from .._display import ROUNDED_NOTE, is_shortened, readable, unicode_output
from .._progress import progress
from ._normal_form import (ObserverNormalForm, flint_matrix, is_rational, normal_form_matrix, observer_normal_form,
                           rational_coordinates, rational_rows, sympy_matrix)
from ._recheck import lyapunov_by_substitution, lyapunov_residual_is_zero
from ._routh import hurwitz_conditions, readable_condition, routh_first_column
from ._spectrum import LAPLACE, parse_spectrum, polynomial_coefficients, spectrum_coefficients

__all__ = ["GainDesign", "NormalFormDesign", "NORMAL_FORM_DIGITS", "design_gains", "design", "normal_form_design",
           "normal_form_statement", "theorem1_K_minus", "hoang_family_constraints", "minus_coefficients",
           "plus_coefficients", "parse_gains"]


#: Coupling constraints are expanded and tidied up to this dimension (readability vs cost).
_FACTOR_MAX_DIMENSION = 3
PRETTY_MAX_N = 4  # up to this dimension str() shows full pretty-printed matrices; beyond, the compact form


def _column(values: Sequence[sp.Expr]) -> sp.ImmutableMatrix:
    return sp.ImmutableMatrix(len(values), 1, list(values))


def _flat(rows: Any) -> list:
    return [x for r in rows for x in (r if isinstance(r, list) else [r])]


def _matrix_json(M: sp.MatrixBase) -> list:
    ring = rational_rows(M)  # its elements print as sympy prints the Rational ("-5/7", "2")
    rows = [[str(x) for x in row] for row in (ring if ring is not None else M.tolist())]
    return [row[0] for row in rows] if M.cols == 1 else rows


def _product(*factors: sp.MatrixBase) -> sp.ImmutableMatrix | None:
    """The product of the factors when all are rational (exact, on python-flint's ``fmpq_mat``); else None."""
    exact = [flint_matrix(M) for M in factors]
    if any(M is None for M in exact):
        return None
    out = exact[0]
    for M in exact[1:]:
        out = out * M
    return sympy_matrix(out)


def _to_model(nf: ObserverNormalForm, k_nf: sp.MatrixBase) -> sp.ImmutableMatrix:
    """``T^-1 k_nf``: a normal-form gain in the model's coordinates."""
    if nf.is_identity:
        return sp.ImmutableMatrix(k_nf)
    rational = _product(nf.T_inv, k_nf)
    return rational if rational is not None else sp.ImmutableMatrix((nf.T_inv * k_nf).applyfunc(sp.cancel))


def _to_normal_form(nf: ObserverNormalForm, K: sp.MatrixBase) -> sp.MatrixBase:
    rational = _product(nf.T, K)
    return rational if rational is not None else nf.T * sp.Matrix(K)


def _sign(i: int) -> int:
    """(-1)^i for the 1-based index i."""
    return -1 if i % 2 else 1


def plus_coefficients(nf: ObserverNormalForm, K_plus: sp.MatrixBase) -> tuple[sp.Expr, ...]:
    """``alpha_plus_i = (T K_plus)_i - a_i``: characteristic coefficients of ``A_plus``."""
    k_nf = _to_normal_form(nf, K_plus)
    return tuple(sp.expand(k_nf[i] - nf.a[i]) for i in range(len(nf.a)))


def minus_coefficients(nf: ObserverNormalForm, K_minus: sp.MatrixBase) -> tuple[sp.Expr, ...]:
    """``alpha_minus_i = (-1)^i ((T K_minus)_i - a_i)``: characteristic coefficients of ``A_minus``."""
    k_nf = _to_normal_form(nf, K_minus)
    return tuple(sp.expand(_sign(i + 1) * (k_nf[i] - nf.a[i])) for i in range(len(nf.a)))


def theorem1_K_minus(nf: ObserverNormalForm, K_plus: sp.MatrixBase) -> sp.ImmutableMatrix:
    """The unique K_minus of Theorem 1 (seed 004), mapped back to the model's coordinates.

    In normal form ``k_i^- = (-1)^i k_i^+ + (1 - (-1)^i) a_i``; then
    ``K_minus = T^-1 K_nf_minus``.
    """
    return _to_model(nf, sp.Matrix(_theorem1_normal_form(list(_to_normal_form(nf, K_plus)), list(nf.a))))


def _theorem1_normal_form(k_plus: Sequence[Any], a: Sequence[Any]) -> list[Any]:
    """Theorem 1 (seed 004) in normal form: ``k_i^- = (-1)^i k_i^+ + (1 - (-1)^i) a_i``."""
    return [_sign(i) * k_plus[i - 1] + (1 - _sign(i)) * a[i - 1] for i in range(1, len(a) + 1)]


def hoang_family_constraints(alpha_plus: Sequence[sp.Expr], alpha_minus: Sequence[sp.Expr]) -> list[sp.Expr]:
    """Polynomials that vanish iff ``P(alpha_plus)`` and ``P(alpha_minus)`` are proportional.

    With ``u_m = N_m / D`` (see :func:`observer_form_gramian`), proportionality of
    the checkerboard matrices is ``N_m(alpha_plus) N_1(alpha_minus) = N_1(alpha_plus) N_m(alpha_minus)``
    for ``m = 2..n``.  For abs-xbs3 these are equivalent to seed 000 eq. (17).
    """
    n = len(alpha_plus)
    generic, nums, _ = _generic_solution(n)
    plus = [N.xreplace(dict(zip(generic, alpha_plus))) for N in nums]
    minus = [N.xreplace(dict(zip(generic, alpha_minus))) for N in nums]
    out = []
    for m in range(1, n):
        expr = plus[m] * minus[0] - plus[0] * minus[m]
        # Pulling out the common monomial shows the structure of (17) in the seeds'
        # dimensions.  Full factorisation is avoided: sympy's multivariate factoring
        # time varies by orders of magnitude from run to run on these polynomials.
        out.append(sp.factor_terms(sp.expand(expr)) if n <= _FACTOR_MAX_DIMENSION else expr)
    return out


def parse_gains(gains: str | Sequence, model: Model, *, what: str) -> sp.ImmutableMatrix:
    """Gains as a column: numbers, expressions in the parameters, or new (real) gain symbols.

    ``gains`` is a comma-separated string, a sequence, a NumPy vector or a sympy
    column; numbers follow the one float rule (:func:`~switchobs.model.exact_number`).
    """
    gains = entries(gains, name=what)
    items = gains.split(",") if isinstance(gains, str) else list(gains)
    if len(items) != model.n:
        raise DimensionError(f"{what} has {len(items)} entries but model {model.name!r} has dimension {model.n}")
    names = {p: model.symbols[p] for p in model.parameters}
    forbidden = set(model.states) | {model.output} | set(model.external) | set(model.inputs)
    out = []
    for i, g in enumerate(items):
        if isinstance(g, sp.Basic):
            out.append(g)
            continue
        text = str(g).strip()
        for name in free_names(text):
            if name in forbidden:
                raise ExpressionError(f"{what} entry {i + 1} uses {name!r}, a state or signal; gains are constants "
                                      "(numbers, parameters or new gain symbols)")
            names.setdefault(name, make_symbol(name))
        out.append(parse_expression(text, names, what=f"{what} entry {i + 1}"))
    return _column(out)


def _gain_symbols(K: sp.MatrixBase, model: Model) -> list[sp.Symbol]:
    params = set(model.parameter_symbols)
    syms = sorted((s for s in K.free_symbols if s not in params), key=lambda s: s.name)
    order = {s: min(i for i, k in enumerate(K) if s in k.free_symbols) for s in syms}
    return sorted(syms, key=lambda s: order[s])


def _all_rational(values: Sequence[sp.Expr]) -> bool:
    return all(sp.sympify(x).is_Rational for x in values)


def _readable(alpha: Sequence[sp.Expr], unknowns: Sequence[sp.Symbol]) -> tuple[sp.Basic, ...]:
    if _all_rational(alpha):  # decided by the numeric Routh array: nothing is left open, or it fails
        column = routh_first_column(alpha)
        return () if len(column) == len(alpha) + 1 and column[-1] > 0 else (sp.false,)
    out = []
    for g in hurwitz_conditions(alpha):
        cond = readable_condition(g, unknowns)
        if cond is sp.true:
            continue
        out.append(cond)
    return tuple(out)


@dataclass(frozen=True)
class GainDesign:
    """A switched gain pair with its exact common Lyapunov certificate.

    Attributes
    ----------
    model : Model
    choice : str
        ``"theorem1"`` (K_minus from Theorem 1, ``C_minus = C_plus``) or
        ``"hoang-family"`` (a given K_minus satisfying the coupling constraints).
    spectrum : tuple or None
        Requested poles of ``A_plus`` (None when K_plus was given).
    alpha_plus, alpha_minus : tuple
        Achieved characteristic coefficients of ``A_plus`` and ``A_minus``
        (monic, highest power omitted).
    normal_form : ObserverNormalForm
    K_plus, K_minus : sympy.ImmutableMatrix (n x 1)
    A_plus, A_minus : sympy.ImmutableMatrix
    hurwitz_plus, hurwitz_minus : tuple of relationals
        Routh–Hurwitz conditions still open (those proven by the sign
        assumptions are dropped); empty means Hurwitz for all admissible values.
    P : sympy.ImmutableMatrix
        ``A_plus' P + P A_plus = -C_plus' C_plus`` and ``A_minus' P + P A_minus = -C_minus' C_minus``.
        ``P > 0`` iff the ``hurwitz_plus`` conditions hold (the pair (A_plus, C) is observable).
    C_plus, C_minus : sympy.ImmutableMatrix (1 x n)
    gain_constraints : tuple of sympy.Eq
        The Hoang-family coupling constraints on a generic ``K_minus``
        (symbols ``k1_minus, ...``) for this ``K_plus``; the chosen K_minus satisfies them.
    family_symbols : tuple of Symbol
    conditional : bool
        True when K_minus holds free gain symbols: the minus-side Lyapunov
        equation then holds exactly when ``gain_constraints`` hold.
    """

    model: Model
    choice: str
    spectrum: tuple[sp.Expr, ...] | None
    alpha_plus: tuple[sp.Expr, ...]
    alpha_minus: tuple[sp.Expr, ...]
    normal_form: ObserverNormalForm
    K_plus: sp.ImmutableMatrix
    K_minus: sp.ImmutableMatrix
    A_plus: sp.ImmutableMatrix
    A_minus: sp.ImmutableMatrix
    hurwitz_plus: tuple[sp.Basic, ...]
    hurwitz_minus: tuple[sp.Basic, ...]
    P: sp.ImmutableMatrix
    C_plus: sp.ImmutableMatrix
    C_minus: sp.ImmutableMatrix
    gain_constraints: tuple[sp.Basic, ...]
    family_symbols: tuple[sp.Symbol, ...] = field(default=())
    conditional: bool = False

    @property
    def n(self) -> int:
        return self.model.n

    @property
    def design_symbols(self) -> tuple[sp.Symbol, ...]:
        """Symbols of the design that are not model parameters (``beta1``, gain names, ...)."""
        params = set(self.model.parameter_symbols)
        syms = (self.K_plus.free_symbols | self.K_minus.free_symbols) - params
        return tuple(sorted(syms, key=lambda s: s.name))

    def characteristic_polynomial(self, which: str = "plus") -> sp.Expr:
        """``s^n + alpha_1 s^(n-1) + ... + alpha_n`` of ``A_plus`` or ``A_minus``."""
        alpha = self.alpha_plus if which == "plus" else self.alpha_minus
        n = len(alpha)
        return LAPLACE**n + sum(a * LAPLACE**(n - i - 1) for i, a in enumerate(alpha))

    # ------------------------------------------------------------ checks
    def verify(self) -> dict[str, bool]:
        """Re-check the certificate exactly (``cancel(residual) == 0``), independently of how it was built.

        Returns a mapping of check name to outcome: both Lyapunov equations,
        the characteristic polynomials of ``A_plus``/``A_minus`` computed from
        the matrices against ``alpha_plus``/``alpha_minus``, symmetry of P and
        the coupling constraints at the chosen K_minus.  For a conditional
        design the two minus-side checks are left out (they hold exactly on
        the set where ``gain_constraints`` hold, not identically).  For a model
        in observer normal form the Lyapunov equations are proved once per
        dimension for generic coefficients and re-checked here by substitution
        (:mod:`switchobs.design._recheck`), which keeps fully symbolic designs
        past N = 7 within seconds.
        """
        # a design in observer normal form is re-checked by substituting into identities proved once per n
        generic = None if self.conditional or not self.normal_form.is_identity else lyapunov_by_substitution(
            self.A_plus, self.A_minus, self.P, self.C_plus, self.C_minus, self.alpha_plus)

        def residual_zero(A: sp.MatrixBase, C: sp.MatrixBase) -> bool:
            return generic if generic is not None else lyapunov_residual_is_zero(A, self.P, sp.Matrix(C).T * C)

        similarity = self._normal_form_similarity()

        def charpoly_is(A: sp.MatrixBase, alpha: Sequence[sp.Expr], sign: int) -> bool:
            # For numbers on flint's fmpq_mat (sympy's sparse Berkowitz took 8 s per matrix at n = 128): first as
            # S A = N S with S = T (plus) or Sigma T (minus) invertible and N the companion matrix of alpha, which
            # proves det(sI - A) = det(sI - N) in three products (flint's charpoly of a 128-state decimal A_plus
            # takes 7 s), else coefficient by coefficient; no degree-n expression either way.
            exact = flint_matrix(A)
            if exact is not None and _all_rational(alpha):
                N = flint_matrix(normal_form_matrix([-a for a in alpha]))
                if similarity is not None and similarity[sign] * exact == N * similarity[sign]:
                    return True
                coeffs = exact.charpoly().coeffs()[::-1]
                return coeffs[0] == 1 and all(c == flint.fmpq(int(a.p), int(a.q)) for c, a in zip(coeffs[1:], alpha))
            dm = DomainMatrix.from_Matrix(sp.Matrix(A))
            coeffs = [dm.domain.to_sympy(c) for c in dm.charpoly()]
            return coeffs[0] == 1 and all(sp.cancel(c - a) == 0 for c, a in zip(coeffs[1:], alpha))

        subs = dict(zip(self.family_symbols, self.K_minus))
        checks = {
            "lyapunov_plus": residual_zero(self.A_plus, self.C_plus),
            "charpoly_plus": charpoly_is(self.A_plus, self.alpha_plus, 1),
            "charpoly_minus": charpoly_is(self.A_minus, self.alpha_minus, -1),
            "P_symmetric": self.P == self.P.T or all(sp.cancel(x) == 0 for x in self.P - self.P.T),
        }
        if not self.conditional:
            checks["lyapunov_minus"] = residual_zero(self.A_minus, self.C_minus)
            checks["gain_constraints"] = all(sp.cancel(c.lhs.xreplace(subs) - c.rhs.xreplace(subs)) == 0
                                             for c in self.gain_constraints)
        return checks

    def _normal_form_similarity(self) -> dict[int, flint.fmpq_mat] | None:
        """``{1: T, -1: Sigma T}`` (``Sigma = diag(1, -1, 1, ...)``) as flint matrices when ``T`` is rational, not the
        identity and ``T T_inv = I`` holds (so ``T`` is invertible), else None: ``T A_plus T^-1`` and
        ``Sigma T A_minus T^-1 Sigma`` are the companion matrices of ``alpha_plus`` and ``alpha_minus``."""
        nf = self.normal_form
        T, T_inv = (None, None) if nf.is_identity else (flint_matrix(nf.T), flint_matrix(nf.T_inv))
        if T is None or T_inv is None:
            return None
        n = T.nrows()
        if T * T_inv != flint.fmpq_mat(n, n, [int(i == j) for i in range(n) for j in range(n)]):
            return None
        signed = flint.fmpq_mat(n, n, [x if (k // n) % 2 == 0 else -x for k, x in enumerate(T.entries())])
        return {1: T, -1: signed}

    def gains_for(self, model: Model, values: Mapping[str, Any] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Float ``(K_plus, K_minus)`` for an observer of ``model``, at the design's values overridden by ``values``.

        Raises
        ------
        ModelError
            The design is for a model with other states.
        FreeSymbolError
            A parameter or design symbol has no value.
        """
        self.check_model(model)
        merged = {**self.model.values, **dict(values or {})}
        return (numeric(self.K_plus, merged, what="K_plus").reshape(-1),
                numeric(self.K_minus, merged, what="K_minus").reshape(-1))

    def check_model(self, model: Model) -> None:
        """Refuse a model other than the one designed for (compared by its states)."""
        if self.model.states != model.states:
            raise ModelError(f"the gain design is for model {self.model.name!r} with states "
                             f"{list(self.model.states)}, not for {model.name!r} with {list(model.states)}")

    @property
    def is_numeric(self) -> bool:
        """No parameter and no design symbol is left: the gains are exact rational numbers."""
        return not self.model.parameters and not (self.K_plus.free_symbols | self.K_minus.free_symbols)

    def at(self, values: Mapping[str, Any] | None = None) -> "GainDesign":
        """The design evaluated exactly at the model's stored values, overridden and completed by ``values``.

        ``values`` gives model parameters and design symbols (``beta1``...) as
        numbers or exact strings (``"187.5"`` is ``375/2``).  The result is the
        design of the model with those values substituted
        (:meth:`Model.with_values`): every field is evaluated, conditions that
        hold are dropped.  This is the form the later stages take
        (``certify_model``, the observers, ``generate_observer``).

        Raises
        ------
        ModelError
            A value for a name that is neither a parameter nor a design symbol, or not a finite number.
        NotHurwitzError, NotObservableError
            The values break a Routh–Hurwitz or an observability condition.
        """
        given = dict(values or {})
        symbols = {s.name: s for s in self.design_symbols}
        params = {**{k: v for k, v in self.model.values.items() if k in self.model.parameters},
                  **{k: v for k, v in given.items() if k not in symbols}}
        model = self.model.with_values(params)
        subs = {self.model.symbols[k]: rational_value(v, what=f"parameter {k!r}") for k, v in params.items()}
        subs.update({symbols[k]: rational_value(v, what=f"design symbol {k!r}") for k, v in given.items()
                     if k in symbols})

        def ev(x: Any) -> Any:
            if isinstance(x, tuple):
                return tuple(ev(e) for e in x)
            return x.xreplace(subs) if isinstance(x, (sp.Basic, sp.MatrixBase)) else x

        def still_open(conditions: tuple, error: type[Exception], what: str) -> tuple:
            out = tuple(c for c in ev(conditions) if c is not sp.true)
            if any(c is sp.false for c in out):
                broken = [sp.sstr(c) for c, e in zip(conditions, ev(conditions)) if e is sp.false]
                raise error(f"at these values {what} fails: {broken[0]} does not hold")
            return out

        nf = self.normal_form
        fields = {f.name: ev(getattr(nf, f.name)) for f in dataclasses.fields(nf)}
        fields["observability_conditions"] = still_open(nf.observability_conditions, NotObservableError,
                                                        "observability")
        normal_form = dataclasses.replace(nf, **fields)
        evaluated = {f.name: ev(getattr(self, f.name)) for f in dataclasses.fields(self)
                     if f.name not in ("model", "normal_form", "hurwitz_plus", "hurwitz_minus")}
        hurwitz = {f"hurwitz_{side}": still_open(getattr(self, f"hurwitz_{side}"), NotHurwitzError,
                                                 f"the A_{side} Routh–Hurwitz condition") for side in ("plus", "minus")}
        return GainDesign(**evaluated, **hurwitz, model=model, normal_form=normal_form)

    def numeric(self, values: Mapping[str, Any] | None = None) -> dict[str, np.ndarray]:
        """Float arrays of the gains and certificate, through the model's numeric gate.

        ``values`` completes/overrides the model's stored parameter values and
        gives the design symbols (``beta1``...).
        """
        merged = {**{k: v for k, v in self.model.values.items()}, **dict(values or {})}
        out = {}
        for name in ("K_plus", "K_minus", "A_plus", "A_minus", "P", "C_plus", "C_minus"):
            out[name] = numeric(getattr(self, name), merged, what=name)
        out["K_plus"] = out["K_plus"].reshape(-1)
        out["K_minus"] = out["K_minus"].reshape(-1)
        return out

    def to_numpy(self, values: Mapping[str, Any] | None = None) -> dict[str, np.ndarray]:
        """The same as :meth:`numeric`: every gain and matrix as a float array, in one call."""
        return self.numeric(values)

    def to_statespace(self, sign: str = "plus", values: Mapping[str, Any] | None = None) -> Any:
        """The error system of one mode as a python-control ``StateSpace``, in the rescaled time ``tau``.

        ``de/dtau = A_sign e + B v``, ``y_e = C e``: the input ``v`` is the
        measurement noise (``y = C z + v``), which enters as ``B = -K_plus`` for
        ``s > 0`` and ``B = K_minus`` for ``s < 0`` (the observer injects
        ``s K (y - C z_hat)`` and ``dtau = |s| dt``; seed 000 eq. (13)), and the
        output is the output error ``C e``.

        Parameters
        ----------
        sign : {"plus", "minus"} (also ``"+"``, ``"-"``, ``1``, ``-1``)
        values : mapping, optional
            Parameter and design-symbol values, as in :meth:`numeric`.

        Raises
        ------
        SpectrumError
            An unknown ``sign``.
        FreeSymbolError
            A parameter or design symbol has no value.
        """
        import control

        side = {"plus": "plus", "+": "plus", 1: "plus", "minus": "minus", "-": "minus", -1: "minus"}.get(sign)
        if side is None:
            raise SpectrumError(f"sign = {sign!r}: give 'plus' (A_plus, s > 0) or 'minus' (A_minus, s < 0)")
        num = self.numeric(values)
        B = (-num["K_plus"] if side == "plus" else num["K_minus"]).reshape(-1, 1)
        C = numeric(self.model.C, {**self.model.values, **dict(values or {})}, what="C")
        return control.ss(num[f"A_{side}"], B, C, np.zeros((1, 1)), name=f"{self.model.name} error, A_{side}",
                          inputs=["v"], outputs=["Ce"], states=[f"e_{z}" for z in self.model.states])

    # ----------------------------------------------------------- output
    def to_json(self) -> dict[str, Any]:
        """Plain-JSON view; every expression is a string that :func:`switchobs.model.parse_expression` parses back
        with its symbols (a bare ``sympy.sympify`` reads a symbol ``beta`` as sympy's beta function)."""
        return {
            "model": self.model.name,
            "n": self.n,
            "states": list(self.model.states),
            "parameters": list(self.model.parameters),
            "choice": self.choice,
            "conditional": self.conditional,
            "spectrum": None if self.spectrum is None else [str(p) for p in self.spectrum],
            "characteristic_polynomial_plus": str(self.characteristic_polynomial("plus")),
            "characteristic_polynomial_minus": str(self.characteristic_polynomial("minus")),
            "A": _matrix_json(self.model.A),
            "C": [str(x) for x in self.model.C],
            "K_plus": _matrix_json(self.K_plus),
            "K_minus": _matrix_json(self.K_minus),
            "A_plus": _matrix_json(self.A_plus),
            "A_minus": _matrix_json(self.A_minus),
            "hurwitz_plus": [str(c) for c in self.hurwitz_plus],
            "hurwitz_minus": [str(c) for c in self.hurwitz_minus],
            "P": _matrix_json(self.P),
            "C_plus": [str(x) for x in self.C_plus],
            "C_minus": [str(x) for x in self.C_minus],
            "gain_constraints": [str(c) for c in self.gain_constraints],
            "family_symbols": [str(s) for s in self.family_symbols],
            "normal_form": self.normal_form.to_json(),
            "references": dict(self.model.references),
            "model_definition": self.model.to_json(),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "GainDesign":
        """The design of :meth:`to_json`, recomputed from its model and inputs and checked against the file.

        The model (``model_definition``), the spectrum or ``K_plus`` (and, for the Hoang family,
        ``K_minus``) are read back and the design is run again, exactly; the stored gains and ``P``
        must be what it gives, so a tampered or foreign file is refused rather than trusted.

        Raises
        ------
        ModelError
            A file without ``model_definition`` (written before it existed), or whose stored gains or
            ``P`` differ from the recomputed ones.
        """
        if not isinstance(data, Mapping) or "model_definition" not in data:
            raise ModelError("a gain design JSON needs its 'model_definition' (GainDesign.to_json writes it); "
                             "design again from the model")
        model = Model.from_json(data["model_definition"])
        spectrum = data.get("spectrum")
        minus = data["K_minus"] if data.get("choice") == "hoang-family" else None
        design = design_gains(model, spectrum, K_plus=None if spectrum is not None else data["K_plus"],
                              K_minus=minus, coupling=bool(data.get("gain_constraints")))
        stored = design.to_json()
        for key in ("K_plus", "K_minus", "P", "C_minus"):
            if [sp.sympify(x) for x in _flat(stored[key])] != [sp.sympify(x) for x in _flat(data[key])]:
                raise ModelError(f"the stored {key} = {data[key]} is not what the design of model "
                                 f"{model.name!r} gives ({stored[key]}); the file was changed or is from another version")
        return design

    def to_json_string(self, indent: int = 2) -> str:
        return json.dumps(self.to_json(), indent=indent)

    def __repr__(self) -> str:
        target = ", ".join(map(str, self.spectrum)) if self.spectrum is not None else "given K_plus"
        target = target if len(target) <= 60 else target[:57] + "..."
        return (f"<GainDesign for model {self.model.name!r}: n={self.n}, {self.choice}, spectrum [{target}]"
                f"{', conditional' if self.conditional else ''}>")

    def _repr_markdown_(self) -> str:
        """The design in a notebook: gains, error matrices and P in LaTeX (gains only past PRETTY_MAX_N)."""
        nf = self.normal_form
        latex = _readable_latex
        target = (", ".join(f"${latex(p)}$" for p in self.spectrum) if self.spectrum is not None
                  else "from the given $K^+$")
        rows = [f"**Switched observer design** for model `{self.model.name}` (n = {self.n}, {self.choice}"
                f"{', conditional on the coupling constraints' if self.conditional else ''})", "",
                f"spectrum of $A^+$: {target}; observable iff: "
                + (", ".join(f"${latex(c)}$" for c in nf.observability_conditions) or "always"), "",
                f"$$K^+ = {latex(self.K_plus.T)}^\\top,\\quad K^- = {latex(self.K_minus.T)}^\\top$$"]
        if self.n <= PRETTY_MAX_N:
            rows += ["", f"$$A^+ = A - K^+ C = {latex(self.A_plus)},\\quad "
                         f"A^- = -A + K^- C = {latex(self.A_minus)}$$",
                     "", f"common Lyapunov matrix ($A^{{\\pm\\top}} P + P A^\\pm = -C_\\pm^\\top C_\\pm$): "
                         f"$$P = {latex(self.P)}$$"]
        else:
            rows += ["", "(matrices past n = 4: `str(design)`, `design.to_json()` or `design.to_numpy()`)"]
        open_conditions = [*self.hurwitz_plus, *([] if self.choice == "theorem1" else self.hurwitz_minus)]
        rows += ["", "Routh–Hurwitz conditions left: " + (", ".join(f"${latex(c)}$" for c in open_conditions)
                                                        or "none (Hurwitz by construction)")]
        if is_shortened([*(self.spectrum or ()), *self.K_plus, *self.K_minus, *self.P]):
            rows += ["", ROUNDED_NOTE.replace("--exact or --json", "`design.to_json()`")]
        return "\n".join(rows)

    def __str__(self) -> str:
        return self.describe(full=self.n <= PRETTY_MAX_N)

    def describe(self, full: bool = True) -> str:
        """The design as text: full matrices (pretty up to n = PRETTY_MAX_N, ``sstr`` beyond) or compact.

        The compact form gives the gains as lists and, in observer normal form, ``P`` by its ``n`` free
        entries ``u_m = P_mm`` (the checkerboard rule of seed 004 Theorem 1 gives the rest) over their
        common denominator: megabytes less text for a fully symbolic model past N = 7.  Past
        PRETTY_MAX_N, sums are printed in sympy's internal order of their terms (``order="none"``):
        sorting them is half the printing time of a symbolic N = 8 design.
        """
        text, gains, lyapunov = self._blocks(full)
        nf = self.normal_form
        lines = [
            f"switched observer design for model {self.model.name!r} (n = {self.n}, choice: {self.choice}"
            f"{', conditional on the coupling constraints' if self.conditional else ''})",
            f"  spectrum of A_plus: {', '.join(map(text, self.spectrum)) if self.spectrum else 'from the given K_plus'}",
            f"  observable iff: {', '.join(map(text, nf.observability_conditions)) or 'always'}",
            f"  normal form a = {text(list(nf.a))}",
            *gains,
            *self._routh_lines(text),
            *lyapunov,
            f"  C_plus = {text(list(self.C_plus))},  C_minus = {text(list(self.C_minus))}",
            "  coupling constraints on K_minus (Hoang family):",
            "\n".join(f"    {text(c)}" for c in self.gain_constraints) or "    (none)",
        ]
        if not full:
            lines.append("  (compact: full matrices with `switchobs design --full` or in `--json`)")
        if is_shortened([*(self.spectrum or ()), *nf.a, *self.K_plus, *self.K_minus, *self.P, *self.C_plus,
                         *self.C_minus]):
            lines.append("  " + ROUNDED_NOTE)
        return "\n".join(lines)

    @property
    def stored_values(self) -> dict[str, Any]:
        """The model's stored values of its parameters (a model file's ``[values]``): what :meth:`at` substitutes
        when given nothing, and what ``switchobs design`` evaluates the design at."""
        return {k: v for k, v in self.model.values.items() if k in self.model.parameters}

    def describe_at_values(self, full: bool | None = None) -> str:
        """The gains, the Routh–Hurwitz conditions left and ``P`` of the design :meth:`at` the model's
        :attr:`stored_values`, as text: what ``switchobs design`` prints after the symbolic design.

        Design symbols stay symbols; ``P`` is printed when no symbol is left in it (else its symbols are named:
        ``to_json`` of :meth:`at` holds it); ``full`` as in :meth:`describe` (default: as ``str()``, full matrices up
        to n = PRETTY_MAX_N).

        Raises
        ------
        NotHurwitzError, NotObservableError
            The values break a Routh–Hurwitz or an observability condition (as :meth:`at`).
        """
        at = self.at()
        text, gains, lyapunov = at._blocks(self.n <= PRETTY_MAX_N if full is None else full)
        values = ", ".join(f"{k} = {text(v)}" for k, v in self.stored_values.items())
        left = sorted(s.name for s in at.P.free_symbols)
        if left:
            lyapunov = [f"  common Lyapunov matrix P: the one above at these values, in {', '.join(left)} "
                        f"(in full with --json)"]
        lines = [f"at the model's values {values} (switchobs design --symbolic leaves this out):", *gains,
                 *at._routh_lines(text), *lyapunov]
        if is_shortened([*at.K_plus, *at.K_minus, *at.P]):
            lines.append("  " + ROUNDED_NOTE)
        return "\n".join(lines)

    def _blocks(self, full: bool) -> tuple[Callable[[Any], str], list[str], list[str]]:
        """The printer of one expression and the lines of the gains and of ``P`` (full or compact)."""
        small = self.n <= PRETTY_MAX_N
        printer = sp.sstr if small else _unsorted_sstr

        def text(expr: Any) -> str:
            return printer(readable(expr))

        def mat(M: sp.MatrixBase) -> str:
            shown = sp.pretty(readable(M), use_unicode=unicode_output()) if small else text(M.tolist())
            return "\n".join("    " + line for line in shown.splitlines())

        if full:
            return (text, ["  K_plus =", mat(self.K_plus), "  K_minus =", mat(self.K_minus)],
                    ["  common Lyapunov matrix P =", mat(self.P)])
        return (text, [f"  K_plus = {text(list(self.K_plus))}", f"  K_minus = {text(list(self.K_minus))}"],
                self._compact_P(text))

    def _routh_lines(self, text: Callable[[Any], str]) -> list[str]:
        def conds(cs: Sequence[sp.Basic]) -> str:
            return "\n".join(f"    {text(c)}" for c in cs) if cs else "    (none left: Hurwitz by construction)"

        return ["  Routh–Hurwitz conditions for A_plus:", conds(self.hurwitz_plus),
                "  Routh–Hurwitz conditions for A_minus:", conds(self.hurwitz_minus)]

    def _compact_P(self, text: Callable[[Any], str]) -> list[str]:
        if not self.normal_form.is_identity:
            return ["  common Lyapunov matrix P (rows) =", *(f"    {text(list(row))}" for row in
                                                           self.P.tolist())]
        parts = [sp.fraction(self.P[m, m]) for m in range(self.n)]
        head = ["  common Lyapunov matrix P: P_ij = (-1)^((j-i)/2) u_((i+j)/2) for i + j even, 0 otherwise, with"]
        dens = {d for _, d in parts}
        if len(dens) == 1 and dens != {1}:
            return [*head, f"    u_m = N_m / D,  D = {text(dens.pop())}",
                    *(f"    N_{m + 1} = {text(num)}" for m, (num, _) in enumerate(parts))]
        return [*head, *(f"    u_{m + 1} = {text(self.P[m, m])}" for m in range(self.n))]


def _readable_latex(expr: Any) -> str:
    return sp.latex(readable(expr))


def _unsorted_sstr(expr: Any) -> str:
    return sp.sstr(expr, order="none")


def design_gains(model: Model, spectrum: str | Sequence | None = None, *,
           characteristic_polynomial: str | sp.Expr | Sequence | None = None,
           K_plus: str | Sequence | sp.MatrixBase | None = None,
           K_minus: str | Sequence | sp.MatrixBase | None = None, coupling: bool | None = None) -> GainDesign:
    """Design the switched gain pair and its common Lyapunov certificate, exactly.

    Give exactly one of ``spectrum``, ``characteristic_polynomial`` or ``K_plus``.

    Parameters
    ----------
    model : Model
    spectrum : str or sequence, optional
        Poles of ``A_plus`` (``"-beta1,-beta2,-beta2"``); new names are
        positive design symbols.
    characteristic_polynomial : str, expr or sequence, optional
        Target ``det(sI - A_plus)`` in ``s`` or its coefficients.
    K_plus : optional
        Gains for ``s > 0`` (numbers, expressions or new symbols ``"k1,k2,k3"``).
    K_minus : optional
        Gains for ``s < 0``.  Omitted: the Theorem 1 choice.  Given: must
        satisfy the Hoang-family coupling constraints (seed 000 eq. (17)).
    coupling : bool, optional
        Compute the coupling constraints on a generic ``K_minus``
        (``gain_constraints``).  Default: when symbols are left in the
        characteristic coefficients (they are conditions worth reading), not
        for numbers.  A numeric ``K_minus`` is then checked directly: ``P`` of
        both sides proportional, in exact rational arithmetic.  Asking for them
        on a numeric design of large dimension is costly (a generic solve in
        ``n`` symbols).

    Returns
    -------
    GainDesign

    Raises
    ------
    SpectrumError, NotObservableError, NotHurwitzError, DimensionError, CertificateError

    Notes
    -----
    Numbers stay numbers: when the model, the target and the gains are
    rational, the normal form, ``K_plus``, ``K_minus``, the Routh array and ``P``
    are computed by exact matrix arithmetic over QQ (sympy's DomainMatrix,
    flint-backed), with no expression and no symbolic determinant; only
    remaining symbols go through the symbolic path.

    References
    ----------
    seed 004 Theorem 1; seed 000 eq. (13)-(17), (23)-(28), Sec. III-E and IV-D;
    seed 001 Proposition 1, eq. (3.20).

    Examples
    --------
    >>> from switchobs.model import builtin_model
    >>> d = design_gains(builtin_model("abs-xbs3"), "-beta1,-beta2,-beta2")
    >>> d.K_plus[0]
    beta1 + 2*beta2 + c
    """
    given = [x is not None for x in (spectrum, characteristic_polynomial, K_plus)]
    if sum(given) != 1:
        raise SpectrumError("give exactly one of spectrum, characteristic_polynomial or K_plus "
                            f"(got {sum(given)})")
    progress(f"design: observer normal form (n = {model.n})")
    nf = observer_normal_form(model)
    a = list(nf.a)
    poles = None
    progress(f"design: K_plus and Routh–Hurwitz conditions (n = {model.n})")
    if K_plus is not None:
        Kp = parse_gains(K_plus, model, what="K_plus")
        alpha_plus = plus_coefficients(nf, Kp)
    else:
        if spectrum is not None:
            poles = parse_spectrum(spectrum, model)
            alpha_plus = spectrum_coefficients(poles)
        else:
            alpha_plus = polynomial_coefficients(characteristic_polynomial, model)
        Kp = _to_model(nf, sp.Matrix([a[i] + alpha_plus[i] for i in range(model.n)]))
    if poles is not None and _all_rational(alpha_plus):
        # parse_spectrum proved every pole's real part negative, so prod (s - p) is Hurwitz: its Routh array (2 s
        # at n = 128 on 6-digit poles) would only repeat that
        hurwitz_plus: tuple[sp.Basic, ...] = ()
    else:
        hurwitz_plus = _readable(alpha_plus, _gain_symbols(Kp, model))
    if any(c is sp.false for c in hurwitz_plus):
        _raise_not_hurwitz("A_plus", model.A - Kp * model.C)

    progress(f"design: common Lyapunov matrix P (n = {model.n})")
    P_nf, nums, den = observer_form_gramian(alpha_plus)
    P = P_nf if nf.is_identity else _congruence(nf.T, P_nf)
    C = model.C
    family = tuple(make_symbol(f"k{i}_minus") for i in range(1, model.n + 1))
    if K_minus is None:
        choice = "theorem1"
        conditional = False
        Km = theorem1_K_minus(nf, Kp)
        alpha_minus = tuple(alpha_plus)
        C_minus = C
    else:
        choice = "hoang-family"
        Km = parse_gains(K_minus, model, what="K_minus")
        alpha_minus = minus_coefficients(nf, Km)
    if coupling is None:
        coupling = not (_all_rational(alpha_plus) and _all_rational(alpha_minus))
    constraints: tuple[sp.Basic, ...] = ()
    if coupling:
        progress(f"design: Hoang-family coupling constraints (n = {model.n})")
        alpha_family = minus_coefficients(nf, sp.Matrix(family))
        constraints = tuple(sp.Eq(c, 0, evaluate=False) for c in hoang_family_constraints(alpha_plus, alpha_family))
    if K_minus is not None:
        _, nums_minus, den_minus = observer_form_gramian(alpha_minus)
        conditional = bool(Km.free_symbols - set(model.parameter_symbols) - Kp.free_symbols)
        if constraints:
            subs = dict(zip(family, Km))
            broken = [c for c in constraints if sp.cancel(c.lhs.xreplace(subs)) != 0]
            if broken and not conditional:
                _raise_not_coupled(Kp, Km, f"the coupling constraint {sp.sstr(broken[0])} evaluates to "
                                           f"{sp.factor(broken[0].lhs.xreplace(subs))} instead of 0")
        else:  # rational u_m on both sides: P(alpha_plus) and P(alpha_minus) must be proportional
            m = next((m for m in range(1, model.n) if nums[m] * nums_minus[0] != nums[0] * nums_minus[m]), None)
            if m is not None:
                _raise_not_coupled(Kp, Km, f"P(alpha_plus) and P(alpha_minus) are not proportional "
                                           f"(u_{m + 1}/u_1 is {nums[m] / nums[0]} on the plus side and "
                                           f"{nums_minus[m] / nums_minus[0]} on the minus side)")
        ratio = sp.cancel((nums[0] / den) / (nums_minus[0] / den_minus))
        C_minus = sp.ImmutableMatrix(sp.sqrt(ratio) * C)
    # Theorem 1 gives A_minus the characteristic polynomial of A_plus: same conditions.
    hurwitz_minus = hurwitz_plus if choice == "theorem1" else _readable(alpha_minus, _gain_symbols(Km, model))
    if any(c is sp.false for c in hurwitz_minus):
        _raise_not_hurwitz("A_minus", -model.A + Km * model.C)
    return GainDesign(
        model=model, choice=choice, spectrum=poles, alpha_plus=tuple(alpha_plus), alpha_minus=tuple(alpha_minus),
        normal_form=nf, K_plus=Kp, K_minus=sp.ImmutableMatrix(Km),
        A_plus=sp.ImmutableMatrix(model.A - Kp * C), A_minus=sp.ImmutableMatrix(-model.A + Km * C),
        hurwitz_plus=hurwitz_plus, hurwitz_minus=hurwitz_minus, P=P, C_plus=sp.ImmutableMatrix(C),
        C_minus=sp.ImmutableMatrix(C_minus), gain_constraints=constraints, family_symbols=family,
        conditional=conditional)


#: Entries of the normal form's coordinates ``T`` longer than this many digits make them the statement of a
#: rational design (:func:`normal_form_statement`): the model's gains ``T^-1 k`` are then longer still (for a
#: dense decimal model by a factor of about ``n``); shorter, the design stays in the model's own coordinates,
#: where users read it.
NORMAL_FORM_DIGITS = 100


@dataclass(frozen=True)
class NormalFormDesign:
    """The Theorem 1 design of a rational model, in its observer normal form's coordinates ``z = T x``.

    The same gains as :func:`design_gains` (seed 004 Theorem 1), stated where their numbers are short:
    ``K_plus = T^-1 k_plus`` and ``K_minus = T^-1 k_minus`` in the model's coordinates need ``T``'s inverse,
    whose entries, for a dense model with decimal entries, have tens of thousands of digits, while
    ``a``, ``T``, the gains ``k`` and ``P`` here have at most a few thousand.  ``T A_plus = A_nf_plus T``
    with ``A_nf_plus = A_nf - k_plus e_1'`` and ``A_minus`` likewise: the families are similar, so every
    stability certificate of one holds for the other (``P_model = T' P T``).

    Attributes
    ----------
    model : Model
    spectrum : tuple of sympy numbers
        The poles asked for ``A_plus`` (and, Theorem 1, ``A_minus``).
    a : tuple of Fraction
        ``det(sI - A) = s^n - a_1 s^(n-1) - ... - a_n``.
    T : list of rows of Fraction
    alpha : tuple of Fraction
        ``det(sI - A_plus) = s^n + alpha_1 s^(n-1) + ... + alpha_n``.
    k_plus, k_minus : tuple of Fraction
        ``T K_plus`` and ``T K_minus``.
    u : tuple of Fraction
        The common Lyapunov matrix's free entries: ``P_ij = (-1)^((j-i)/2) u_((i+j)/2)`` for ``i + j`` even,
        0 otherwise (the observer-form Gramian, :mod:`switchobs.design._lyapunov`).
    """

    model: Model
    spectrum: tuple[sp.Expr, ...]
    a: tuple[Fraction, ...]
    T: list[list[Fraction]]
    alpha: tuple[Fraction, ...]
    k_plus: tuple[Fraction, ...]
    k_minus: tuple[Fraction, ...]
    u: tuple[Fraction, ...]

    @property
    def n(self) -> int:
        return len(self.a)

    @property
    def P(self) -> list[list[Fraction]]:
        """The common Lyapunov matrix in these coordinates: ``A_p' P + P A_p = -e_1 e_1'`` for both modes."""
        return checkerboard_rows(self.u)

    @property
    def C(self) -> list[list[Fraction]]:
        """``e_1'``: the output in these coordinates (``C = e_1' T`` in the model's)."""
        return [[Fraction(1)] + [Fraction(0)] * (self.n - 1)]

    @property
    def A_plus(self) -> list[list[Fraction]]:
        """``A_nf - k_plus e_1'``: the plus mode in these coordinates."""
        return _normal_form_rows([x - k for x, k in zip(self.a, self.k_plus)], 1)

    @property
    def A_minus(self) -> list[list[Fraction]]:
        """``-A_nf + k_minus e_1'``: the minus mode in these coordinates."""
        return _normal_form_rows([k - x for x, k in zip(self.a, self.k_minus)], -1)

    def gains(self) -> tuple[np.ndarray, np.ndarray]:
        """``K_plus`` and ``K_minus`` in the model's coordinates, as the doubles nearest the exact values."""
        from ..exact import solve_float

        K = solve_float(self.T, [[p, m] for p, m in zip(self.k_plus, self.k_minus)])
        return np.array([row[0] for row in K]), np.array([row[1] for row in K])

    def verify(self) -> dict[str, bool]:
        """Re-check the design exactly from its own numbers and the model's ``A``, ``C``.

        ``similarity``: ``T A = A_nf T``, ``C = e_1' T`` and ``det T != 0``; ``lyapunov_plus`` and
        ``lyapunov_minus``: ``A_p' P + P A_p = -e_1 e_1'``; ``charpoly``: the first column of ``A_plus`` is
        ``-alpha`` and ``alpha`` the coefficients of ``prod (s - p)`` of the spectrum (``A_minus = -D A_plus D``
        with ``D = diag(1, -1, ...)`` then has the same, Theorem 1).
        """
        from ..exact import add, fraction_matrix, lyapunov_form, matmul, nonsingular

        n = self.n
        A = fraction_matrix(rational_rows(sp.Matrix(self.model.A)), what="A")
        C = fraction_matrix(rational_rows(sp.Matrix(self.model.C)), what="C")
        e1 = self.C
        outer = [[e1[0][i] * e1[0][j] for j in range(n)] for i in range(n)]
        zero = [[0] * n for _ in range(n)]
        A_nf = _normal_form_rows(list(self.a), 1)
        P = self.P
        alpha = tuple(Fraction(str(x)) for x in spectrum_coefficients(self.spectrum))
        return {"similarity": matmul(self.T, A) == matmul(A_nf, self.T) and matmul(e1, self.T) == C
                and nonsingular(self.T),
                "lyapunov_plus": add(lyapunov_form(self.A_plus, P), outer) == zero,
                "lyapunov_minus": add(lyapunov_form(self.A_minus, P), outer) == zero,
                "charpoly": alpha == self.alpha and [row[0] for row in self.A_plus] == [-x for x in alpha]}

    def to_json(self) -> dict[str, Any]:
        """The exact design (rational strings) and the model's gains as doubles."""
        K_plus, K_minus = self.gains()
        return {"model": self.model.name, "model_definition": self.model.to_json(), "n": self.n, "choice": "theorem1",
                "coordinates": "observer normal form z = T x (K = T^-1 k)",
                "spectrum": [str(p) for p in self.spectrum], **self._exact_json(),
                "K_plus": [float(x) for x in K_plus], "K_minus": [float(x) for x in K_minus]}

    def _exact_json(self) -> dict[str, Any]:
        return {"a": [str(x) for x in self.a], "T": [[str(x) for x in row] for row in self.T],
                "alpha": [str(x) for x in self.alpha], "k_plus": [str(x) for x in self.k_plus],
                "k_minus": [str(x) for x in self.k_minus], "P_u": [str(x) for x in self.u]}

    def __repr__(self) -> str:  # the dataclass's would print T, thousands of digits each entry
        return f"<NormalFormDesign: Theorem 1 design of {self.model.name} (n = {self.n}) in z = T x>"

    def _repr_markdown_(self) -> str:
        return "```\n" + str(self) + "\n```"

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "NormalFormDesign":
        """The design of :meth:`to_json`, designed again from its model and spectrum and checked against the file.

        Raises
        ------
        ModelError
            No ``model_definition``, or stored exact numbers that are not what the design gives (a changed file).
        """
        if not isinstance(data, Mapping) or "model_definition" not in data or "spectrum" not in data:
            raise ModelError("a normal-form design JSON needs its 'model_definition' and 'spectrum' "
                             "(NormalFormDesign.to_json writes them); design again from the model")
        design = normal_form_design(Model.from_json(data["model_definition"]), list(data["spectrum"]))
        stored = design._exact_json()  # not to_json: the gains' enclosure is not compared
        for key in ("T", "k_plus", "k_minus", "P_u"):
            if stored[key] != data.get(key):
                raise ModelError(f"the stored {key} is not what the design of model {design.model.name!r} gives; "
                                 "the file was changed or is from another version")
        return design

    def __str__(self) -> str:
        K_plus, K_minus = self.gains()
        rows = [f"Theorem 1 design of {self.model.name} (n = {self.n}) in its observer normal form's coordinates "
                "z = T x",
                f"  spectrum of A_plus and A_minus: [{', '.join(_pole_text(p) for p in self.spectrum)}]",
                f"  K_plus  = [{', '.join(f'{k:.6g}' for k in K_plus)}]",
                f"  K_minus = [{', '.join(f'{k:.6g}' for k in K_minus)}]",
                "  (the doubles nearest T^-1 k, 6 significant digits; exact: T, k_plus, k_minus and the common P "
                "of z in --json, their numbers being shorter than K's)"]
        return "\n".join(rows)


def _pole_text(p: sp.Expr) -> str:
    """A numeric pole with 6 significant digits, as users type it (``-1.06667``, ``-2+3j``)."""
    z = complex(p)
    return f"{z.real:.6g}" if z.imag == 0 else f"{z.real:.6g}{z.imag:+.6g}j"


def _normal_form_rows(first: Sequence[Fraction], superdiagonal: int) -> list[list[Fraction]]:
    n = len(first)
    return [[first[i] if j == 0 else Fraction(superdiagonal if j == i + 1 else 0) for j in range(n)]
            for i in range(n)]


def normal_form_design(model: Model, spectrum: str | Sequence) -> NormalFormDesign:
    """The Theorem 1 gain pair for ``spectrum`` and its common P, in the observer normal form's coordinates.

    For a numeric model with rational entries and numeric poles; what :func:`design_gains` computes for a
    spectrum, without leaving the normal form (no ``T^-1``, no matrix in the model's coordinates), on
    python-flint.

    Raises
    ------
    ModelError
        The model has parameters without values or irrational entries.
    SpectrumError, NotObservableError, NotHurwitzError
        As :func:`design_gains`; a pole that is not a number.

    References
    ----------
    seed 004 Theorem 1 and 'Observer normal form'.
    """
    if not (is_rational(sp.Matrix(model.A)) and is_rational(sp.Matrix(model.C))):
        raise ModelError(f"model {model.name!r} is not numeric with rational entries; give its parameter values")
    poles = parse_spectrum(spectrum, model)
    if any(sp.sympify(p).free_symbols for p in poles):
        raise SpectrumError(f"the spectrum {[str(p) for p in poles]} has design symbols; give numbers here "
                            "(design_gains keeps symbols)")
    c, T = _coordinates(model)
    return _design_in_coordinates(model, poles, c, T)


def normal_form_statement(model: Model, spectrum: str | Sequence) -> NormalFormDesign | None:
    """The Theorem 1 design in the normal form's coordinates when it is the better statement, else None.

    None when the model is not rational, already in normal form (``T = I``), the poles are not all numbers,
    or ``T``'s entries have at most :data:`NORMAL_FORM_DIGITS` digits: the model's own coordinates then read
    better and cost little more.  ``design`` and ``certify`` follow this one rule; it is decided on ``T``
    before anything else of the design is computed.
    """
    if model.n < 2 or not (is_rational(sp.Matrix(model.A)) and is_rational(sp.Matrix(model.C))):
        return None
    poles = parse_spectrum(spectrum, model)
    if any(sp.sympify(p).free_symbols for p in poles):
        return None
    c, T = _coordinates(model)
    if max(len(str(x)) for x in T.entries()) <= NORMAL_FORM_DIGITS:
        return None
    return _design_in_coordinates(model, poles, c, T)


def _coordinates(model: Model) -> tuple[list[Any], Any]:
    """``[1, c_1, ..., c_n]`` and ``T`` (python-flint) of an observable rational model; NotObservableError
    naming an unobservable direction otherwise (decided modulo a prime first, not by ``det O``)."""
    from ..exact import fraction_matrix, observable

    progress(f"design: observer normal form (n = {model.n})")
    A, C = flint_matrix(model.A), flint_matrix(model.C)
    if not observable(fraction_matrix(A.tolist(), what="A"), fraction_matrix(C.tolist(), what="C"))[0]:
        observer_normal_form(model)  # raises, naming an unobservable direction
    c, _, T = rational_coordinates(A, C)
    return c, T


def _design_in_coordinates(model: Model, poles: tuple[sp.Expr, ...], c: Sequence[Any], T: Any) -> NormalFormDesign:
    """The rest of :func:`normal_form_design` once the coordinates are known."""
    a = [-Fraction(int(x.p), int(x.q)) for x in c[1:]]
    alpha = tuple(Fraction(str(x)) for x in spectrum_coefficients(poles))
    # parse_spectrum proved every pole left of the axis, exactly: prod (s - p) is Hurwitz, no Routh array needed
    k_plus = [x + y for x, y in zip(a, alpha)]
    progress(f"design: common Lyapunov matrix P (n = {model.n})")
    rows = [[Fraction(int(x.p), int(x.q)) for x in row] for row in T.tolist()]
    return NormalFormDesign(model, poles, tuple(a), rows, alpha, tuple(k_plus),
                            tuple(_theorem1_normal_form(k_plus, a)), tuple(gramian_entries(alpha)))


#: The same function under the name of its sub-package: ``from switchobs.design import design``.
#: At the top level only ``switchobs.design_gains`` is exported, so that ``switchobs.design`` is always
#: the sub-package, whatever was imported first.
design = design_gains


def _congruence(T: sp.MatrixBase, P_nf: sp.MatrixBase) -> sp.ImmutableMatrix:
    """``T' P_nf T``: the normal-form Lyapunov matrix in the model's coordinates."""
    rational = _product(T.T, P_nf, T)
    return rational if rational is not None else sp.ImmutableMatrix((T.T * P_nf * T).applyfunc(sp.cancel))


def _raise_not_coupled(Kp: sp.MatrixBase, Km: sp.MatrixBase, why: str) -> None:
    raise CertificateError(
        f"K_minus = {list(Km)} admits no common P with K_plus = {list(Kp)}: {why}; "
        "omit K_minus for the Theorem 1 choice or use `switchobs certify` for a dwell-time verdict")


def _raise_not_hurwitz(name: str, M: sp.MatrixBase) -> None:
    try:
        eig = np.linalg.eigvals(numeric(M, what=name))
        spec = ", ".join(f"{z.real:.6g}{z.imag:+.6g}j" for z in eig)
    except Exception:  # symbolic leftovers: give the polynomial instead
        spec = str(sp.Matrix(M).charpoly(LAPLACE).as_expr())
    raise NotHurwitzError(f"{name} is not Hurwitz: its spectrum is [{spec}]; choose gains that satisfy "
                          "the Routh–Hurwitz conditions")
