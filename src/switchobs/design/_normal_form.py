"""Observability and the observer normal form (seed 004, slide 'Observer normal form').

For an observable pair (A, C) with one output, the coordinates ``z_nf = T z``
give ``T A T^-1 = A_nf`` with first column ``(a_1, ..., a_n)`` and ones on the
superdiagonal, and ``C T^-1 = (1, 0, ..., 0)``.  Then
``det(sI - A) = s^n - a_1 s^(n-1) - ... - a_n``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import flint
import sympy as sp
from sympy import QQ, ZZ
from sympy.core.basic import Basic
from sympy.core.containers import Tuple
from sympy.polys.matrices import DomainMatrix
from sympy.polys.matrices._dfm import DFM

from ..exceptions import ModelError, NotObservableError
from ..model import Model, parse_expression, symbols_from_json, symbols_to_json

__all__ = ["ObserverNormalForm", "observer_normal_form", "normal_form_matrix", "is_rational", "rational_rows",
           "flint_matrix", "sympy_matrix", "rational_coordinates"]


def normal_form_matrix(a: sp.MatrixBase | list) -> sp.ImmutableMatrix:
    """The observer normal form matrix with first column ``a`` and a unit superdiagonal."""
    n = len(a)
    return sp.ImmutableMatrix(n, n, lambda i, j: a[i] if j == 0 else (1 if j == i + 1 else 0))


def _observability_matrix(A: sp.MatrixBase, C: sp.MatrixBase) -> sp.Matrix:
    rows = [sp.Matrix(C)]
    for _ in range(A.shape[0] - 1):
        rows.append((rows[-1] * A).applyfunc(sp.expand))
    return sp.Matrix.vstack(*rows)


def _is_normal_form(A: sp.MatrixBase, C: sp.MatrixBase) -> bool:
    n = A.shape[0]
    if list(C) != [1] + [0] * (n - 1):
        return False
    return all(A[i, j] == (1 if j == i + 1 else 0) for i in range(n) for j in range(1, n))


def _rational_rep(M: sp.MatrixBase) -> DomainMatrix | None:
    """The matrix's own representation when it is over ZZ or QQ (sympy keeps rational matrices so), else None:
    reading it builds no sympy Rational per entry, which took seconds on 64-state decimal designs."""
    rep = getattr(M, "_rep", None)
    return rep if isinstance(rep, DomainMatrix) and (rep.domain.is_QQ or rep.domain.is_ZZ) else None


def rational_rows(M: sp.MatrixBase) -> list[list] | None:
    """The entries of a rational matrix as its ring's elements (python-flint's ``fmpq``/``fmpz`` here: they
    print as sympy prints the Rational and have ``numerator``/``denominator``), or None when ``M`` is not held
    over ZZ or QQ (it may still be rational: see :func:`is_rational`)."""
    rep = _rational_rep(M)
    return None if rep is None else rep.to_list()


def is_rational(M: sp.MatrixBase) -> bool:
    """Every entry is a rational number (no symbol, no irrational constant)."""
    return _rational_rep(M) is not None or all(sp.sympify(x).is_Rational for x in M)


def flint_matrix(M: sp.MatrixBase) -> flint.fmpq_mat | None:
    """A rational sympy matrix as python-flint's ``fmpq_mat``, or None when an entry is not rational.

    The design's rational products, solves and characteristic polynomials run on it: sympy's DomainMatrix
    calls the same routines, but through its sparse Python loops for everything it builds from a Matrix.
    """
    rep = _rational_rep(M)
    if rep is not None:
        return flint.fmpq_mat(*M.shape, [x for row in rep.to_list() for x in row])
    M = sp.Matrix(M)
    if not all(getattr(x, "is_Rational", False) for x in M):
        return None
    return flint.fmpq_mat(*M.shape, [flint.fmpq(int(x.p), int(x.q)) for x in M])


def sympy_matrix(M: flint.fmpq_mat) -> sp.ImmutableMatrix:
    """The ``fmpq_mat`` ``M`` as a sympy ImmutableMatrix, equal in every part to ``ImmutableMatrix(entries)``.

    The same object sympy builds (its entries as sympy Rationals, its ``_rep`` over ZZ when every entry is
    an integer, else QQ, stored sparse), made from the entries' own numerators and denominators, which flint
    keeps coprime: sympy's constructor takes a gcd and a cache look-up per entry, seconds for the 128-state
    decimal designs whose entries have thousands of digits.
    """
    entries = M.entries()
    flat = [sp.Rational.from_coprime_ints(int(x.p), int(x.q)) for x in entries]
    rows, cols = M.nrows(), M.ncols()
    rep = DomainMatrix.from_rep(DFM(M, (rows, cols), QQ)).to_sparse()
    if all(x.q == 1 for x in entries):
        rep = rep.convert_to(ZZ)
    obj = Basic.__new__(sp.ImmutableMatrix, sp.Integer(rows), sp.Integer(cols), Tuple(*flat, sympify=False))
    obj._rows, obj._cols, obj._rep = rows, cols, rep
    return obj


def rational_coordinates(A: flint.fmpq_mat, C: flint.fmpq_mat) -> tuple[list[flint.fmpq], flint.fmpq_mat,
                                                                         flint.fmpq_mat]:
    """``(c, O, T)`` of a rational single-output pair: ``[1, c_1, ..., c_n]`` with
    ``det(sI - A) = s^n + c_1 s^(n-1) + ... + c_n``, the observability matrix ``O`` and the normal form's
    coordinates ``T = O_nf^-1 O`` (``T A = A_nf T``, ``C = e_1' T``), on python-flint.

    ``O_nf``, the observability matrix of the normal form, is unit lower triangular and its inverse is the
    lower triangular Toeplitz matrix of ``(1, c_1, ..., c_(n-1))`` (row ``i`` of ``O_nf^-1 O_nf`` is
    ``e1' p_i(A_nf)`` with ``p_i`` the degree-``i`` head of the characteristic polynomial, which is ``e_(i+1)'``
    for the normal form), so ``T`` is one product: no solve, and no inverse of ``O``, whose entries for a dense
    decimal ``A`` are thousands of digits long.  ``det T = det O``.
    """
    n = A.nrows()
    rows = [C]
    for _ in range(n - 1):
        rows.append(rows[-1] * A)
    O = flint.fmpq_mat(n, n, [x for row in rows for x in row.entries()])
    c = A.charpoly().coeffs()[::-1]
    O_nf_inv = flint.fmpq_mat(n, n, [c[i - j] if i >= j else 0 for i in range(n) for j in range(n)])
    return c, O, O_nf_inv * O


def _determinant(M: flint.fmpq_mat) -> flint.fmpq:
    """``det M``: the product of the diagonal for a triangular ``M`` (the observability matrix of every chain
    ``x_i' = -d_i x_i + x_(i+1)``, ``y = x_1``), else flint's determinant (7 s for a 128-state decimal chain)."""
    n = M.nrows()
    entries = M.entries()
    lower = all(entries[i * n + j] == 0 for i in range(n) for j in range(i + 1, n))
    if lower or all(entries[i * n + j] == 0 for i in range(n) for j in range(i)):
        det = flint.fmpq(1)
        for i in range(n):
            det *= entries[i * n + i]
        return det
    return M.det()


def _unobservable(model: Model, direction: list) -> NotObservableError:
    pretty = "[" + ", ".join(str(x) for x in direction) + "]"
    return NotObservableError(
        f"the pair (A, C) of model {model.name!r} is not observable: the direction v = {pretty} "
        f"(in states {list(model.states)}) is unobservable (C A^k v = 0 for all k); "
        "change C or A so that every state shows up in the output")


def _rational_normal_form(model: Model) -> ObserverNormalForm:
    """The normal form of a numeric pair, in exact rational matrix arithmetic (python-flint; no expressions)."""
    n = model.n
    c, O, T = rational_coordinates(flint_matrix(model.A), flint_matrix(model.C))
    det = _determinant(O)
    if det == 0:
        nullspace = DomainMatrix.from_rep(DFM(O, (n, n), QQ)).nullspace()
        raise _unobservable(model, [QQ.to_sympy(x) for x in nullspace.to_Matrix().row(0)])
    a_sym = sympy_matrix(flint.fmpq_mat(n, 1, [-x for x in c[1:]]))
    O_sym = sympy_matrix(O)
    det_sym = sp.Rational.from_coprime_ints(int(det.p), int(det.q))
    if _is_normal_form(sp.Matrix(model.A), sp.Matrix(model.C)):
        eye = sp.ImmutableMatrix.eye(n)
        return ObserverNormalForm(a_sym, eye, eye, O_sym, det_sym, ())
    return ObserverNormalForm(a_sym, sympy_matrix(T), sympy_matrix(T.inv()), O_sym, det_sym, ())


@dataclass(frozen=True)
class ObserverNormalForm:
    """The observer normal form of a model's pair (A, C).

    Attributes
    ----------
    a : sympy.ImmutableMatrix (n x 1)
        First column of the normal form; ``det(sI - A) = s^n - sum a_i s^(n-i)``.
    T, T_inv : sympy.ImmutableMatrix
        ``z_nf = T z``; gains map as ``K_nf = T K``, Lyapunov matrices as ``P = T' P_nf T``.
    observability_matrix : sympy.ImmutableMatrix
    observability_determinant : sympy.Expr
    observability_conditions : tuple of sympy.Ne
        The pair is observable iff none of these factors vanishes (reported,
        not hidden: a factor may involve parameters).
    """

    a: sp.ImmutableMatrix
    T: sp.ImmutableMatrix
    T_inv: sp.ImmutableMatrix
    observability_matrix: sp.ImmutableMatrix
    observability_determinant: sp.Expr
    observability_conditions: tuple[sp.Basic, ...]

    @property
    def is_identity(self) -> bool:
        """True when the model is already in observer normal form (``T = I``)."""
        return self.T == sp.eye(self.T.rows)

    @property
    def A(self) -> sp.ImmutableMatrix:
        """The normal-form matrix ``T A T^-1``."""
        return normal_form_matrix(list(self.a))

    def to_json(self) -> dict[str, Any]:
        def rows(M: sp.ImmutableMatrix) -> list[list[str]]:
            return [[str(x) for x in M.row(i)] for i in range(M.rows)]

        return {
            "a": [str(x) for x in self.a],
            "T": rows(self.T),
            "T_inv": rows(self.T_inv),
            "observability_matrix": rows(self.observability_matrix),
            "observability_determinant": str(self.observability_determinant),
            "observability_conditions": [str(c) for c in self.observability_conditions],
            "symbols": symbols_to_json(self.a, self.T, self.T_inv, self.observability_matrix,
                                       self.observability_determinant),
        }

    @classmethod
    def from_json(cls, data: Any) -> ObserverNormalForm:
        """The normal form of :meth:`to_json`, its entries parsed over its ``symbols``.

        Raises
        ------
        ModelError
            A missing key, an entry that does not parse, or a condition not of the form ``Ne(factor, 0)``.
        """
        if not isinstance(data, Mapping):
            raise ModelError(f"an observer normal form JSON must be an object, got {data!r:.80}")
        names = symbols_from_json(data.get("symbols", {}), what="observer normal form")

        def expr(text: Any, what: str) -> sp.Expr:
            return parse_expression(text, names, what=f"observer normal form {what}")

        def matrix(key: str) -> sp.ImmutableMatrix:
            return sp.ImmutableMatrix([[expr(x, key) for x in row] for row in data[key]])

        def condition(text: Any) -> sp.Basic:  # every condition is Ne(factor, 0) (observer_normal_form)
            if not (isinstance(text, str) and text.startswith("Ne(") and text.endswith(", 0)")):
                raise ModelError(f"an observability condition must read 'Ne(factor, 0)', got {text!r}")
            return sp.Ne(expr(text[3:-4], "condition"), 0, evaluate=False)

        try:
            return cls(sp.ImmutableMatrix([expr(x, "a") for x in data["a"]]), matrix("T"), matrix("T_inv"),
                       matrix("observability_matrix"), expr(data["observability_determinant"], "determinant"),
                       tuple(condition(c) for c in data["observability_conditions"]))
        except (KeyError, TypeError) as exc:
            raise ModelError(f"not an observer normal form JSON ({type(exc).__name__}: {exc})") from None


def observer_normal_form(model: Model) -> ObserverNormalForm:
    """Compute the observer normal form of ``(model.A, model.C)`` exactly.

    Parameters
    ----------
    model : Model

    Returns
    -------
    ObserverNormalForm

    Raises
    ------
    NotObservableError
        When the observability matrix is singular for every parameter value;
        the message gives an unobservable direction ``v`` (``O v = 0``).

    Notes
    -----
    ``T = O_nf^-1 O`` with ``O`` the observability matrix of (A, C) and
    ``O_nf`` that of the normal form, which is unit lower triangular, so the
    transformation is exact and needs no pivoting.

    References
    ----------
    seed 004, 'Observer normal form' and Theorem 1.

    Examples
    --------
    >>> from switchobs.model import builtin_model
    >>> nf = observer_normal_form(builtin_model("abs-xbs3"))
    >>> nf.observability_conditions
    (Ne(a, 0),)
    """
    A, C = sp.Matrix(model.A), sp.Matrix(model.C)
    if is_rational(A) and is_rational(C):
        return _rational_normal_form(model)
    n = model.n
    O = _observability_matrix(A, C)
    det = sp.factor(O.det(method="berkowitz"))
    if det == 0:
        raise _unobservable(model, [sp.simplify(x) for x in O.nullspace(simplify=True)[0]])
    # det may be a rational function of the parameters (A = [[0, 7/a], ...]): its numerator's factors must not
    # vanish, nor its denominator's (where the model is not defined)
    num, den = sp.fraction(sp.together(det))
    factors = [f for part in (num, den) for f, _ in sp.factor_list(part)[1]]
    conditions = tuple(dict.fromkeys(sp.Ne(f, 0, evaluate=False) for f in factors if f.free_symbols))
    s = sp.Dummy("s")
    coeffs = A.charpoly(s).all_coeffs()  # [1, c1, ..., cn]
    a = sp.ImmutableMatrix([sp.expand(-c) for c in coeffs[1:]])
    if _is_normal_form(A, C):
        eye = sp.ImmutableMatrix.eye(n)
        return ObserverNormalForm(a, eye, eye, sp.ImmutableMatrix(O), det, conditions)
    O_nf = _observability_matrix(normal_form_matrix(list(a)), sp.Matrix([[1] + [0] * (n - 1)]))
    T = O_nf.LUsolve(O).applyfunc(sp.cancel)
    T_inv = O.LUsolve(O_nf).applyfunc(sp.cancel)
    return ObserverNormalForm(a, sp.ImmutableMatrix(T), sp.ImmutableMatrix(T_inv), sp.ImmutableMatrix(O),
                              det, conditions)
