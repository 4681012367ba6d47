"""The one validation gate for a switched family ``{A_p}``: shapes, finiteness, Hurwitz."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Union

import numpy as np
from sympy import QQ, Poly, Symbol

from ..design import routh_first_column
from ..exceptions import CertificateError, DimensionError, ModelError, NotHurwitzError
from ..model import matrix_rows
from ..exact import Matrix, charpoly, float_matrix, fraction_matrix, integer_form, matrix_strings

__all__ = ["Family", "as_family", "format_spectrum", "FamilyLike"]


@dataclass(frozen=True)
class Family:
    """A validated finite family of square matrices, exact and in floating point.

    Attributes
    ----------
    names : tuple of str
        ``("A_plus", "A_minus")`` for an observer, ``("A_1", "A_2", ...)`` otherwise.
    exact : tuple of Matrix
        The matrices as :class:`fractions.Fraction` rows (floats are taken at
        their exact binary value, strings and sympy Rationals exactly).
    numeric : tuple of numpy.ndarray
    hurwitz : bool
        Every matrix was proven Hurwitz by :func:`as_family` (not proven again when the family is passed on).
    """

    names: tuple[str, ...]
    exact: tuple[Matrix, ...]
    numeric: tuple[np.ndarray, ...]
    hurwitz: bool = field(default=False, compare=False, repr=False)
    #: Each matrix's eigenvalues when known exactly beforehand (a Theorem 1 design's poles), for display:
    #: the floating-point eigenvalues of a large normal-form matrix, whose characteristic polynomial is its
    #: first column, are off by whole units when the poles cluster, and its exact roots cost seconds.
    poles: tuple[tuple[complex, ...], ...] | None = field(default=None, compare=False, repr=False)

    @property
    def n(self) -> int:
        return len(self.exact[0])

    def __len__(self) -> int:
        return len(self.exact)

    def to_numpy(self) -> np.ndarray:
        """The matrices stacked as one float array of shape ``(len(family), n, n)``."""
        return np.stack(self.numeric)

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        return self.to_numpy() if dtype is None else self.to_numpy().astype(dtype)

    def to_json(self) -> dict[str, Any]:
        return {"names": list(self.names), "matrices": [matrix_strings(M) for M in self.exact]}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> "Family":
        """The family of :meth:`to_json` (exact entries read back, nothing re-validated but the shapes)."""
        try:
            names = tuple(str(nm) for nm in data["names"])
            exact = tuple(fraction_matrix(M, what=f"family matrix {nm}") for nm, M in zip(names, data["matrices"]))
        except (KeyError, TypeError) as exc:
            raise CertificateError(f"not a family JSON ({type(exc).__name__}: {exc})") from None
        if len(exact) != len(names) or not exact:
            raise CertificateError(f"a family JSON needs one matrix per name, got {len(names)} names and "
                                   f"{len(data['matrices'])} matrices")
        return cls(names, exact, tuple(float_matrix(M) for M in exact))

    def spectra(self) -> dict[str, str]:
        """Each matrix's name and its spectrum as :func:`format_spectrum` prints it."""
        if self.poles is not None:
            return {nm: _format_eigenvalues(np.asarray(p, dtype=complex)) for nm, p in zip(self.names, self.poles)}
        return {nm: format_spectrum(M, E) for nm, M, E in zip(self.names, self.numeric, self.exact)}

    def __str__(self) -> str:
        return f"family of {len(self)} matrices of size {self.n}: {', '.join(self.names)}"


FamilyLike = Union[Family, Sequence[Any], Mapping[str, Any]]


def format_spectrum(M: np.ndarray, exact: Matrix | None = None) -> str:
    """The eigenvalues of ``M`` sorted by real part, 6 significant digits.

    With the ``exact`` matrix, a repeated eigenvalue is printed as the root of its square-free factor of
    the exact characteristic polynomial: the floating-point eigenvalues of an m-fold root scatter by
    ``eps**(1/m)`` (``-100`` as ``-100.001 +- 0.00095j``, differently on every BLAS).
    """
    return _format_eigenvalues(_spectrum(np.asarray(M, dtype=float), exact))


def _format_eigenvalues(eig: np.ndarray) -> str:
    eig = eig[np.lexsort((eig.imag, eig.real))]
    parts = []
    for z in eig:
        parts.append(f"{z.real:.6g}" if abs(z.imag) <= 1e-6 * max(1.0, abs(z)) else f"{z.real:.6g}{z.imag:+.6g}j")
    return "[" + ", ".join(parts) + "]"


def _spectrum(M: np.ndarray, exact: Matrix | None) -> np.ndarray:
    eig = np.linalg.eigvals(M)
    gaps = np.abs(eig[:, None] - eig[None, :])[~np.eye(len(eig), dtype=bool)]
    if exact is None or len(eig) < 2 or np.min(gaps) > 1e-3 * max(1.0, float(np.max(np.abs(eig)))):
        return eig   # no cluster: the eigenvalues are simple and well separated
    _, factors = Poly(charpoly(exact), Symbol("lam"), domain=QQ).sqf_list()
    return np.concatenate([np.asarray(np.roots([float(c) for c in f.all_coeffs()]), dtype=complex)
                           for f, m in factors for _ in range(m)])


#: Working precision [bits] of the eigenvalue enclosure of :func:`_hurwitz_exact`.
EIGENVALUE_BITS = 256
#: Digits of the integer form above which the enclosure is tried before the exact characteristic polynomial.
ENCLOSURE_DIGITS = 1000


def _hurwitz_exact(M: Matrix) -> bool:
    """``M`` is Hurwitz, decided rigorously: floating-point eigenvalues of a large observer's error matrix can
    land on the wrong side of the axis (seed 004 gains grow fast with n).

    The Routh array of the exact characteristic polynomial (QQ, flint-backed) decides.  Its cost grows with
    the digits of the entries: at n = 32 with the 4000-digit entries of a dense 6-digit model it is 4 s per
    matrix.  For entries beyond :data:`ENCLOSURE_DIGITS` digits python-flint's ``acb_mat.eig(multiple=True)``
    (Rump's verified enclosures, with multiplicities) runs first, in complex balls of
    :data:`EIGENVALUE_BITS` bits, 0.2 s there: every ball contains an eigenvalue, counted with
    multiplicity, so balls left of the imaginary axis prove ``M`` Hurwitz and one right of it proves it is
    not; balls that cannot be isolated or straddle the axis leave it to the Routh array.  (For the
    300-digit entries of a 64-state chain the Routh array takes 0.2 s and the enclosure 1 to 18 s.)
    """
    N, d = integer_form(M)
    bits = max(max(abs(x).bit_length() for row in N for x in row), d.bit_length())
    if bits * math.log10(2) > ENCLOSURE_DIGITS:
        verdict = _hurwitz_enclosed(N, d)
        if verdict is not None:
            return verdict
    return _hurwitz_routh(M)


def _hurwitz_enclosed(N: Sequence[Sequence[int]], d: int) -> bool | None:
    """The verdict of the eigenvalue enclosure of ``N / d``, or None when it cannot decide."""
    import flint

    saved = flint.ctx.prec
    try:
        flint.ctx.prec = EIGENVALUE_BITS
        try:
            eig = (flint.acb_mat(flint.fmpz_mat(N)) / d).eig(multiple=True)
        except ValueError:   # not isolated at this precision
            return None
        if all(z.real < 0 for z in eig):
            return True
        if any(z.real > 0 for z in eig):
            return False
    finally:
        flint.ctx.prec = saved
    return None


def _hurwitz_routh(M: Matrix) -> bool:
    alpha = charpoly(M)[1:]
    column = routh_first_column(alpha)
    return len(column) == len(alpha) + 1 and column[-1] > 0


def as_family(matrices: FamilyLike, names: Sequence[str] | None = None, *, hurwitz: bool = True) -> Family:
    """Validate a finite family of square matrices of one size.

    Parameters
    ----------
    matrices : Family, sequence of matrices, or mapping name -> matrix
        A matrix is a list of rows, a NumPy array, a sympy matrix or a
        ``control.StateSpace`` (its ``A``); entries may be ints, floats (their
        exact binary value), fraction/decimal strings or sympy numbers.
    names : sequence of str, optional
        Names used in messages and certificates (default ``A_1, A_2, ...``).
    hurwitz : bool
        Require every matrix to be Hurwitz (all eigenvalues with negative real part).

    Raises
    ------
    DimensionError
        Empty family, non-square or mismatched sizes.
    ModelError
        NaN, infinite or non-numeric entries.
    NotHurwitzError
        A matrix is not Hurwitz; the message names it and gives its spectrum.
    """
    if isinstance(matrices, Family):
        fam = matrices
    else:
        if isinstance(matrices, Mapping):
            names = list(matrices)
            items = list(matrices.values())
        else:
            items = list(matrices)
        if not items:
            raise DimensionError("the switched family is empty; give at least one matrix")
        names = list(names) if names is not None else [f"A_{i + 1}" for i in range(len(items))]
        if len(names) != len(items):
            raise DimensionError(f"{len(names)} names for {len(items)} matrices")
        exact = []
        for nm, M in zip(names, items):
            rows = matrix_rows(M, name=nm)
            if not isinstance(rows, (list, tuple)) or not rows or not all(isinstance(r, (list, tuple)) for r in rows):
                raise DimensionError(f"{nm} must be a matrix given as a list of rows, got {M!r}")
            try:
                F = fraction_matrix(rows, what=nm)
            except CertificateError as exc:
                raise ModelError(str(exc)) from None
            if len(F) != len(F[0]):
                raise DimensionError(f"{nm} is not square: shape {len(F)}x{len(F[0])}")
            exact.append(F)
        n = len(exact[0])
        for nm, M in zip(names, exact):
            if len(M) != n:
                raise DimensionError(f"{nm} is {len(M)}x{len(M)} but {names[0]} is {n}x{n}; "
                                     "all matrices of a family must have the same size")
        fam = Family(tuple(str(x) for x in names), tuple(exact),
                     tuple(float_matrix(M) for M in exact))
    if hurwitz and not fam.hurwitz:
        for nm, M, E in zip(fam.names, fam.numeric, fam.exact):
            if not np.all(np.isfinite(M)):
                raise ModelError(f"{nm} has entries too large for floating point")
            if not _hurwitz_exact(E):
                raise NotHurwitzError(f"{nm} is not Hurwitz: its spectrum is {format_spectrum(M)}; every matrix "
                                      "of the family must have eigenvalues with negative real part "
                                      "(check the gains against the Routh-Hurwitz conditions)")
        fam = replace(fam, hurwitz=True)
    return fam
