"""Exact rational linear algebra (standard library rationals, python-flint integers and balls).

Everything here works on matrices stored as lists of rows of
:class:`fractions.Fraction` (or of Python ``int`` for the integer kernels); the
arithmetic runs on python-flint: products on ``fmpz_mat`` over a common
denominator, rank, reduced forms and solutions on ``fmpz_mat``/``fmpq_mat``, the
modular observability test on ``nmod_mat``, the LDL' factor read off the
fraction-free elimination.
Definiteness is decided by fraction-free symmetric Bareiss elimination on an
integer multiple of the matrix, which is exact and fast: the intermediate
numbers are minors of the matrix, so their size grows linearly with the step,
never exponentially as in naive rational elimination.

The module deliberately imports nothing from numpy, scipy, cvxpy or sympy, so
that the certificate checker built on it (:mod:`switchobs.certify._verify`)
shares no code with the floating-point pipeline that produced a certificate.

Every definiteness check first runs an LDL' elimination in python-flint's
``arb`` balls (outward rounding, 256 to 4096 bits): pivot balls of one sign are a
proof (each contains the exact pivot); whatever they cannot decide is decided by
the exact elimination above.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from .._limits import MAX_CERTIFICATE_DIGITS, MAX_CERTIFICATE_WORK, digits, decimal_fraction
from ..exceptions import CertificateError, DimensionError

__all__ = [
    "Matrix", "to_fraction", "fraction_matrix", "matrix_strings", "identity", "zeros", "transpose",
    "matmul", "add", "sub", "scale", "lyapunov_form", "integer_form", "Definiteness", "definiteness",
    "rank", "nullspace", "solve", "observable", "expm_enclosure", "inf_norm", "sqrt_lower", "sqrt_upper",
    "is_zero", "ARITHMETICS", "arithmetic", "float_matrix", "ldl_psd", "lyapunov_solve", "charpoly", "product_work",
]

Matrix = list[list[Fraction]]


# --------------------------------------------------------------------------- parsing
def to_fraction(value: Any, *, what: str = "entry") -> Fraction:
    """An exact rational from an int, Fraction, decimal/fraction string or float.

    Floats are taken at their exact binary value (``0.1`` becomes
    ``3602879701896397/36028797018963968``); write ``"0.1"`` or ``"1/10"`` for
    the decimal.  Objects with ``p``/``q`` (sympy Rationals) and numpy scalars
    are accepted.

    Raises
    ------
    CertificateError
        For NaN, infinities, non-numbers, irrational symbolic values and numbers of more than
        :data:`~switchobs._limits.MAX_CERTIFICATE_DIGITS` digits (a decimal exponent counting as
        that many digits, checked before the number is expanded).
    """
    if isinstance(value, bool):
        raise CertificateError(f"{what}: expected a number, got {value!r}")
    if isinstance(value, (int, Fraction)):
        out = Fraction(value)
        if max(digits(out.numerator), digits(out.denominator)) > MAX_CERTIFICATE_DIGITS:
            raise CertificateError(f"{what}: a number of more than {MAX_CERTIFICATE_DIGITS} digits "
                                   f"(limit {MAX_CERTIFICATE_DIGITS})")
        return out
    if isinstance(value, str):
        # Size first: "1e999999999" would otherwise be expanded to a billion digits.
        return decimal_fraction(value, what=what, error=CertificateError, max_digits=MAX_CERTIFICATE_DIGITS)
    # sympy Rationals (p, q), python-flint's fmpq and numpy integers (numerator, denominator): exact, never
    # through float (an fmpq's parts are fmpz, not int)
    for num, den in (("p", "q"), ("numerator", "denominator")):
        try:
            p, q = operator.index(getattr(value, num)), operator.index(getattr(value, den))
        except (AttributeError, TypeError):
            continue
        if q != 0:
            return to_fraction(Fraction(p, q), what=what)
    try:
        f = float(value)
    except (TypeError, ValueError):
        raise CertificateError(f"{what}: {value!r} is not a rational number (irrational or symbolic values "
                               "cannot be certified exactly; substitute numbers first)") from None
    if not math.isfinite(f):
        raise CertificateError(f"{what}: {value!r} is not finite")
    if getattr(value, "is_Float", False) and value == f:
        return Fraction(f)  # a sympy Float holding a double: its exact binary value, like a float
    if hasattr(value, "is_Number") and not getattr(value, "is_Rational", True):
        raise CertificateError(f"{what}: {value!r} is irrational; give a rational approximation")
    return Fraction(f)


def fraction_matrix(data: Any, *, what: str = "matrix", rows: int | None = None,
                    cols: int | None = None) -> Matrix:
    """Validate a rectangular matrix and convert every entry with :func:`to_fraction`.

    Accepts nested sequences, numpy arrays and sympy matrices.  A flat
    sequence is read as one row.
    """
    if hasattr(data, "tolist") and not isinstance(data, (list, tuple)):
        data = data.tolist()
    if not isinstance(data, (list, tuple)) or not data:
        raise DimensionError(f"{what} must be a non-empty list of rows, got {data!r}")
    if not isinstance(data[0], (list, tuple)):
        data = [data]
    out = []
    width = len(data[0])
    for i, row in enumerate(data):
        if not isinstance(row, (list, tuple)):
            raise DimensionError(f"{what} row {i + 1} is not a list: {row!r}")
        if len(row) != width:
            raise DimensionError(f"{what} is not rectangular: row 1 has {width} entries, row {i + 1} has {len(row)}")
        out.append([to_fraction(x, what=f"{what}[{i + 1}][{j + 1}]") for j, x in enumerate(row)])
    if rows is not None and len(out) != rows:
        raise DimensionError(f"{what} has the wrong number of rows; expected {rows} instead of {len(out)}")
    if cols is not None and width != cols:
        raise DimensionError(f"{what} has the wrong number of columns; expected {cols} instead of {width}")
    return out


def matrix_strings(M: Sequence[Sequence[Fraction]]) -> list[list[str]]:
    """Rows of rational strings (``"-375/2"``), the certificate's storage format."""
    return [[str(Fraction(x)) for x in row] for row in M]


# ------------------------------------------------------------------ basic algebra
def identity(n: int) -> Matrix:
    return [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]


def zeros(r: int, c: int) -> Matrix:
    return [[Fraction(0)] * c for _ in range(r)]


def transpose(M: Sequence[Sequence[Any]]) -> list[list[Any]]:
    return [list(col) for col in zip(*M)]


def matmul(A: Sequence[Sequence[Any]], B: Sequence[Sequence[Any]]) -> list[list[Any]]:
    """Product of two rational matrices (exact): ints for integer inputs, Fractions otherwise.

    Entries may be ints, Fractions or any rational with ``numerator``/``denominator`` (python-flint's
    ``fmpq``).  The product runs on python-flint's ``fmpz_mat`` over a common denominator of each
    factor (``A = N_A / d_A``), in C; only the entries of the result become Fractions.
    """
    cols = len(B[0]) if B else 0
    if not A or not B or not cols:
        return [[0] * cols for _ in A]
    NA, dA, int_A = _integer_rows(A)
    NB, dB, int_B = _integer_rows(B)
    return _from_fmpz(_fmpz_mat(NA) * _fmpz_mat(NB), dA * dB, int_A and int_B)


def _integer_rows(M: Sequence[Sequence[Any]]) -> tuple[Sequence[Sequence[int]], int, bool]:
    """``(N, d, ints)``: ``M = N / d`` with ``N`` integer, ``d > 0``; ``ints`` when every entry is an int."""
    if _all_int(M):
        return M, 1, True
    N, d = integer_form([[_rational(x) for x in row] for row in M])
    return N, d, False


def _rational(x: Any) -> Fraction:
    if isinstance(x, (int, Fraction)):
        return Fraction(x)
    return Fraction(int(x.numerator), int(x.denominator))


def _fmpz_mat(N: Sequence[Sequence[int]]) -> Any:
    import flint

    return flint.fmpz_mat([[int(x) for x in row] for row in N])


def _from_fmpz(M: Any, d: int, ints: bool) -> list[list[Any]]:
    """The entries of the ``fmpz_mat`` ``M`` divided by ``d``: ints if ``ints`` (then ``d = 1``), else Fractions."""
    rows = M.tolist()
    if ints:
        return [[int(x) for x in row] for row in rows]
    return [[Fraction(int(x), d) for x in row] for row in rows]


def add(A: Sequence[Sequence[Any]], B: Sequence[Sequence[Any]]) -> list[list[Any]]:
    return [[a + b for a, b in zip(ra, rb)] for ra, rb in zip(A, B)]


def sub(A: Sequence[Sequence[Any]], B: Sequence[Sequence[Any]]) -> list[list[Any]]:
    return [[a - b for a, b in zip(ra, rb)] for ra, rb in zip(A, B)]


def scale(c: Any, A: Sequence[Sequence[Any]]) -> list[list[Any]]:
    return [[c * a for a in row] for row in A]


def is_zero(M: Iterable[Iterable[Any]]) -> bool:
    return all(x == 0 for row in M for x in row)


def lyapunov_form(A: Sequence[Sequence[Any]], P: Sequence[Sequence[Any]]) -> list[list[Any]]:
    """``A' P + P A`` (exact), ints for integer inputs and Fractions otherwise.

    The products run on python-flint's integer matrices over a common denominator (``A = N_A / d_A``,
    ``P = N_P / d_P``) and only the ``n^2`` entries of the result become Fractions: the same
    values as Fraction arithmetic throughout, without a gcd in each of the ``n^3`` products.
    """
    NA, dA, int_A = _integer_rows(A)
    NP, dP, int_P = _integer_rows(P)
    AtP = _fmpz_mat(NA).transpose() * _fmpz_mat(NP)
    return _from_fmpz(AtP + AtP.transpose(), dA * dP, int_A and int_P)


def _all_int(M: Sequence[Sequence[Any]]) -> bool:
    return all(type(x) is int for row in M for x in row)


def integer_form(M: Sequence[Sequence[Fraction]]) -> tuple[list[list[int]], int]:
    """``(N, d)`` with ``M = N / d``, ``N`` integer and ``d > 0`` the lcm of the denominators."""
    d = math.lcm(*{x.denominator for row in M for x in row})   # distinct denominators: few for decimal data
    return [[x.numerator * (d // x.denominator) for x in row] for row in M], d


def float_matrix(M: Sequence[Sequence[Any]]) -> Any:
    """The exact matrix ``M`` as a NumPy float array (each entry rounded to nearest)."""
    import numpy as np

    return np.array([[float(x) for x in row] for row in M])


def inf_norm(M: Sequence[Sequence[Any]]) -> Any:
    """Induced infinity norm (largest absolute row sum), exact."""
    return max(sum(abs(x) for x in row) for row in M)


def sqrt_lower(x: Fraction, bits: int = 64) -> Fraction:
    """A rational ``q`` with ``0 <= q <= sqrt(x)`` and ``sqrt(x) - q < 2**-bits * max(1, sqrt(x))``."""
    if x <= 0:
        return Fraction(0)
    s = 4 ** bits
    return Fraction(math.isqrt(x.numerator * s // x.denominator), 2 ** bits)


def sqrt_upper(x: Fraction, bits: int = 64) -> Fraction:
    """A rational ``q >= sqrt(x)`` close to it."""
    q = sqrt_lower(x, bits)
    return q if q * q == x else q + Fraction(1, 2 ** bits)


# ------------------------------------------------------------------ definiteness
#: Accepted names of the arithmetic (``--arithmetic``): both decide exactly, the ``arb`` enclosure first
#: (see :func:`definiteness`).  ``"interval"`` named that first try when it was not yet the default; it is
#: kept so that scripts and the certificates recording it in their provenance keep working.
ARITHMETICS = ("exact", "interval")
#: Working precisions [bits] of the interval LDL', tried in turn for a strict claim.
INTERVAL_BITS = (256, 1024, 4096)


@contextmanager
def arithmetic(kind: str) -> Iterator[None]:
    """Check that ``kind`` is one of :data:`ARITHMETICS` and run the block (both decide the same way).

    Raises
    ------
    CertificateError
        ``kind`` is not one of :data:`ARITHMETICS`.
    """
    if kind not in ARITHMETICS:
        raise CertificateError(f"arithmetic {kind!r} is unknown; use one of {', '.join(ARITHMETICS)}")
    yield


def _negative_minor(rows: Sequence[int], k: int) -> Definiteness:
    return Definiteness(False, k, f"the principal minor on rows/columns {[i + 1 for i in rows] + [k + 1]} "
                                  "is negative")


def _enclosed_definiteness(N: Sequence[Sequence[int]], *, strict: bool) -> Definiteness | None:
    """``N > 0`` proven, or a leading principal minor proven negative, by an LDL' in arb balls; else None.

    Every ball contains the exact value of its entry (outward rounding), so a pivot ball that
    lies right of 0 is a proof that the exact pivot is positive: the pivots are the ratios of
    consecutive leading principal minors, and positive pivots prove ``N > 0`` (Sylvester's
    criterion), which implies ``N >= 0``.  A pivot ball left of 0 after positive ones proves the
    leading principal minor of that size negative, which refutes both claims with the same index
    and reason as the exact elimination.  A ball containing 0 decides nothing: a strict claim is
    retried at a higher precision, a semidefinite one (whose zero pivots are exact zeros as a
    rule) goes to the exact elimination at once.
    """
    import flint

    n = len(N)
    saved = flint.ctx.prec
    try:
        for bits in INTERVAL_BITS if strict else INTERVAL_BITS[:1]:
            flint.ctx.prec = bits
            a = [[flint.arb(x) for x in row] for row in N]
            for k in range(n):
                p = a[k][k]
                if p < 0:
                    return _negative_minor(range(k), k)
                if not p > 0:
                    break
                row_k = a[k]
                for i in range(k + 1, n):
                    f = a[i][k] / p
                    row_i = a[i]
                    for j in range(i, n):
                        row_i[j] -= f * row_k[j]
                        a[j][i] = row_i[j]
            else:
                return Definiteness(True)
    finally:
        flint.ctx.prec = saved
    return None


@dataclass(frozen=True)
class Definiteness:
    """Outcome of :func:`definiteness`.

    Attributes
    ----------
    holds : bool
    index : int or None
        0-based index at which elimination failed.
    reason : str
        Empty when ``holds``; otherwise which minor or Schur-complement entry
        breaks the claim (1-based indices, as a person reads them).
    """

    holds: bool
    index: int | None = None
    reason: str = ""


def definiteness(M: Sequence[Sequence[Any]], *, strict: bool) -> Definiteness:
    """Exactly decide ``M > 0`` (``strict``) or ``M >= 0`` for a symmetric rational matrix.

    First an enclosure: an LDL' elimination of ``N = d M`` (integers) in python-flint's ``arb``
    balls (midpoint and radius, outward rounding).  When every pivot ball is positive, or one is
    negative after positive ones, that *is* the proof -- each ball contains the exact pivot, so its
    sign is the exact pivot's sign -- not a floating-point estimate; the verdict, index and reason
    are those of the exact elimination.  Only when a ball contains 0 (a singular or nearly singular
    leading block, a semidefinite matrix with a zero pivot) does the exact elimination decide:
    fraction-free symmetric Bareiss elimination on ``N`` (python-flint's ``fmpz``).
    After eliminating the pivots ``K``, entry ``(i, j)`` of the working matrix
    is the minor ``det N[K+i, K+j]``, so the diagonal pivots are leading
    principal minors (Sylvester's criterion) and every division is exact.
    For the semidefinite test a zero pivot is allowed only when its whole row
    of the Schur complement vanishes; that index is then dropped, which is
    the LDL' rule for semidefinite matrices.

    Raises
    ------
    DimensionError
        If ``M`` is not square or not symmetric.
    """
    a = _symmetric_integer_form(M)
    enclosed = _enclosed_definiteness(a, strict=strict)
    return enclosed if enclosed is not None else _eliminated_definiteness(a, strict=strict)


def _symmetric_integer_form(M: Sequence[Sequence[Any]]) -> list[list[Any]]:
    """``d M`` as integers (``d`` the common denominator) after checking that ``M`` is square and symmetric."""
    n = len(M)
    if any(len(row) != n for row in M):
        raise DimensionError(f"definiteness needs a square matrix, got {n} rows of lengths {[len(r) for r in M]}")
    for i in range(n):
        for j in range(i):
            if M[i][j] != M[j][i]:
                raise DimensionError(f"matrix is not symmetric: entry ({i + 1},{j + 1}) = {M[i][j]} but "
                                     f"({j + 1},{i + 1}) = {M[j][i]}")
    if _all_int(M):
        return [list(row) for row in M]
    return integer_form([[Fraction(x) for x in row] for row in M])[0]


def _eliminated_definiteness(N: Sequence[Sequence[Any]], *, strict: bool) -> Definiteness:
    """The exact fraction-free elimination of :func:`definiteness` on the symmetric integer matrix ``N``."""
    return _symmetric_bareiss(N, strict=strict)[0]


def elimination_work(rows: int, bits: int) -> float:
    """The work of one pivot step of the exact elimination, counted against
    :data:`~switchobs._limits.MAX_CERTIFICATE_WORK`: ``rows (rows + 1) / 2`` updates of entries of ``bits`` bits,
    each two GMP products costing about ``(bits / 64) ** 1.5`` (measured: the total tracks the process time of
    dense 16-64 state matrices of 300-4000 digits within a factor 2)."""
    return rows * (rows + 1) / 2 * (bits / 64 + 1) ** 1.5


def product_work(n: int, bits: int) -> float:
    """The work of the ``n**3`` entry products of two ``n x n`` integer matrices of ``bits``-bit entries on
    python-flint's ``fmpz_mat`` (multi-modular, in C), in the units of :func:`elimination_work`: about a fifth of
    an elimination update each (measured: 16-128 states, 300-26000 bits, within a factor 3 above the process
    time, never below it)."""
    return n ** 3 * (bits / 64 + 1) ** 1.5 / 5


def _symmetric_bareiss(N: Sequence[Sequence[Any]], *, strict: bool, factor: bool = False
                       ) -> tuple[Definiteness, list[list[Fraction]] | None, list[Fraction] | None]:
    """Fraction-free symmetric elimination of the integer matrix ``N``: the verdict and, with ``factor``,
    ``N = L diag(d) L'`` (unit lower ``L``; ``d_k`` the ratio of consecutive pivots, 0 at a dropped index).

    Before step ``k`` entry ``(i, k)`` is the minor ``det N[K+i, K+k]`` and the pivot ``det N[K+k, K+k]``
    (``K`` the kept indices), so ``L[i][k] = a[i][k] / a[k][k]`` and ``d_k = a[k][k] / previous pivot``:
    the ``LDL'`` of rational elimination, without its ``n^3`` gcds.
    """
    # GMP integers (python-flint): the same operations, 7x faster than Python's ints at n = 64 on
    # 150-digit entries (the minors grow to n times the digits)
    import flint

    n = len(N)
    a = [[flint.fmpz(x) for x in row] for row in N]
    L = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)] if factor else None
    d = [Fraction(0)] * n if factor else None
    prev = flint.fmpz(1)
    kept: list[int] = []
    work = 0.0
    for k in range(n):
        p = a[k][k]
        rest = range(k + 1, n)
        if p != 0:
            work += elimination_work(n - k - 1, max(p.bit_length(), max((abs(a[i][k]).bit_length() for i in rest),
                                                                        default=0)))
            if work > MAX_CERTIFICATE_WORK:
                raise CertificateError(
                    f"the exact elimination of a {n} x {n} matrix would take too long: at pivot {k + 1} of {n} "
                    f"its work reaches {work:.2g} > {MAX_CERTIFICATE_WORK:.2g} = MAX_CERTIFICATE_WORK (entries of "
                    f"{p.bit_length() * 0.30103:.0f} digits); round the certificate to fewer digits")
        if p < 0:
            return _negative_minor(kept, k), None, None
        if p == 0 and strict:
            return Definiteness(False, k, f"the principal minor on rows/columns {[i + 1 for i in kept] + [k + 1]} "
                                          "is zero"), None, None
        if p == 0:
            bad = next((j for j in rest if a[k][j] != 0), None)
            if bad is not None:
                return Definiteness(False, k, f"a zero pivot at {k + 1} has a nonzero coupling to {bad + 1} "
                                              f"(the principal minor on {[i + 1 for i in kept] + [k + 1, bad + 1]} "
                                              "is negative)"), None, None
            continue
        if factor:
            d[k] = Fraction(int(p), int(prev))
            for i in rest:
                L[i][k] = Fraction(int(a[i][k]), int(p))
        for i in rest:
            aik = a[i][k]
            row_i = a[i]
            for j in range(i, n):
                v = (p * row_i[j] - aik * a[k][j]) // prev
                row_i[j] = v
                a[j][i] = v
        prev = p
        kept.append(k)
    return Definiteness(True), L, d


def ldl_psd(M: Sequence[Sequence[Any]]) -> tuple[Matrix, list[Fraction]] | None:
    """Exact ``M = L diag(d) L'`` of a positive semidefinite rational matrix (``None`` if ``M`` is not PSD).

    ``L`` is unit lower triangular; a zero ``d_k`` has a unit column ``k`` (the semidefinite LDL' rule).
    The fraction-free elimination of :func:`definiteness` on ``N = c M`` gives it: ``d = d_N / c``.
    """
    N = _symmetric_integer_form(M)
    c = 1 if _all_int(M) else integer_form([[Fraction(x) for x in row] for row in M])[1]
    verdict, L, d = _symmetric_bareiss(N, strict=False, factor=True)
    if not verdict.holds:
        return None
    return L, [x / c for x in d]


# ------------------------------------------------------------- rank and kernels
def _rref(M: Sequence[Sequence[Any]]) -> tuple[list[list[Fraction]], list[int]]:
    """Reduced row-echelon form (nonzero rows) and pivot columns, by python-flint's ``fmpq_mat``.

    Each row is scaled to integers first (the row space, hence the reduced form, is unchanged).
    """
    import flint

    rows = len(M)
    cols = len(M[0]) if rows else 0
    if not rows or not cols:
        return [], []
    ints = [integer_form([[_rational(x) for x in row]])[0][0] for row in M]
    R, r = flint.fmpq_mat(_fmpz_mat(ints)).rref()
    out = [[Fraction(int(x.p), int(x.q)) for x in row] for row in R.tolist()[:r]]
    return out, [next(c for c, x in enumerate(row) if x != 0) for row in out]
def rank(M: Sequence[Sequence[Any]]) -> int:
    """Exact rank of a rational matrix (python-flint's ``fmpz_mat``, each row scaled to integers)."""
    if not M or not M[0]:
        return 0
    return _fmpz_mat([integer_form([[_rational(x) for x in row]])[0][0] for row in M]).rank()


def solve(M: Sequence[Sequence[Any]], B: Sequence[Sequence[Any]]) -> list[list[Fraction]]:
    """``X`` with ``M X = B`` for a square nonsingular rational ``M`` (python-flint's ``fmpq_mat``, in C).

    Raises
    ------
    DimensionError
        If ``M`` is singular (its rank is named).
    """
    n = len(M)
    try:
        X = _fmpq_mat(M).solve(_fmpq_mat(B))
    except ZeroDivisionError:
        raise DimensionError(f"the {n} x {n} matrix is singular (rank {rank(M)})") from None
    return [[Fraction(int(x.p), int(x.q)) for x in row] for row in X.tolist()]


def _fmpq_mat(M: Sequence[Sequence[Any]]) -> Any:
    import flint

    N, d, _ = _integer_rows(M)
    return flint.fmpq_mat(_fmpz_mat(N)) / d


def charpoly(M: Sequence[Sequence[Any]]) -> list[Fraction]:
    """``[1, c_1, ..., c_n]`` with ``det(sI - M) = s^n + c_1 s^(n-1) + ... + c_n``, exact (python-flint's
    ``fmpq_mat``, in C: sympy's sparse Berkowitz took 7 s for a 128-state observer's error matrix)."""
    coeffs = _fmpq_mat(M).charpoly().coeffs()[::-1]
    return [Fraction(int(c.p), int(c.q)) for c in coeffs]


def lyapunov_solve(A: Sequence[Sequence[Any]], Q: Sequence[Sequence[Any]]) -> list[list[Fraction]]:
    """The exact ``P`` with ``A' P + P A = -Q`` (unique when no two eigenvalues of ``A`` sum to 0).

    The Kronecker system ``(I (x) A' + A' (x) I) vec(P) = -vec(Q)`` of ``n^2`` unknowns, by :func:`solve`
    (the ``n = 16`` system of 256 unknowns takes milliseconds).

    Raises
    ------
    DimensionError
        If the system is singular.
    """
    n = len(A)
    At = transpose(A)
    rows = []
    for i in range(n):
        for j in range(n):
            row: list[Any] = [0] * (n * n)
            for k in range(n):
                row[k * n + j] += At[i][k]   # (A' P)_ij
                row[i * n + k] += A[k][j]    # (P A)_ij
            rows.append(row)
    vec = solve(rows, [[-Q[i][j]] for i in range(n) for j in range(n)])
    return [[vec[i * n + j][0] for j in range(n)] for i in range(n)]


def nullspace(M: Sequence[Sequence[Any]], cols: int | None = None) -> list[list[Fraction]]:
    """A rational basis of ``{x : M x = 0}`` (list of vectors)."""
    ncols = cols if cols is not None else len(M[0])
    if not M:
        return [[Fraction(int(i == j)) for i in range(ncols)] for j in range(ncols)]
    R, pivots = _rref(M)
    free = [c for c in range(ncols) if c not in pivots]
    basis = []
    for f in free:
        v = [Fraction(0)] * ncols
        v[f] = Fraction(1)
        for row, pc in zip(R, pivots):
            v[pc] = -row[f]
        basis.append(v)
    return basis


#: A prime near 2**61 for the modular rank test of :func:`observable`.
_PRIME = (1 << 61) - 1


def _full_rank_mod_p(A: Sequence[Sequence[Fraction]], C: Sequence[Sequence[Fraction]]) -> bool:
    """The Krylov rows of ``(d A, d C)`` (``d`` the common denominator) have rank ``n`` modulo a prime.

    Their determinant is then a nonzero integer, so ``(A, C)`` is observable; the converse
    can fail (the prime may divide it), and a False answer proves nothing.  The products and the
    rank run on python-flint's ``nmod_mat`` (word-size residues, in C): ``O(n^3)`` small operations
    instead of the exact elimination's big rationals.
    """
    import flint

    n = len(A)
    p = _PRIME
    NA = flint.nmod_mat([[x % p for x in row] for row in integer_form([[_rational(x) for x in r] for r in A])[0]], p)
    block = flint.nmod_mat([[x % p for x in row] for row in integer_form([[_rational(x) for x in r] for r in C])[0]],
                           p)
    rows: list[list[int]] = []
    for _ in range(n):  # C A^k for k < n span the Krylov space (Cayley-Hamilton)
        rows += [[int(x) for x in row] for row in block.tolist()]
        if len(rows) >= n and flint.nmod_mat(rows, p).rank() == n:
            return True
        block = block * NA
    return False


def nonsingular(M: Sequence[Sequence[Any]]) -> bool:
    """``det M != 0`` for a square rational ``M``, exactly: full rank modulo a prime decides at once.

    The integer form's determinant is then nonzero; when the prime divides it, the exact rank decides.
    """
    import flint

    n = len(M)
    N, _, _ = _integer_rows(M)
    if flint.nmod_mat([[int(x) % _PRIME for x in row] for row in N], _PRIME).rank() == n:
        return True
    return rank(M) == n


def solve_float(M: Sequence[Sequence[Any]], B: Sequence[Sequence[Any]]) -> list[list[float]]:
    """``X`` with ``M X = B`` to double precision, from a rigorous enclosure (arb balls, in C).

    For display and for the doubles of generated code when the exact ``X`` is too long to be worth
    computing: the working precision doubles from 256 bits until every entry's ball is narrower than
    ``2^-60`` of its value, so each float is the double nearest to the exact entry within one unit in
    the last place however ill-conditioned ``M`` is (an observability matrix can be, by hundreds of
    digits).

    Raises
    ------
    DimensionError
        If ``M`` is singular.
    """
    import flint

    if not nonsingular(M):
        raise DimensionError(f"the {len(M)} x {len(M)} matrix is singular (rank {rank(M)})")
    FM, FB = _fmpq_mat(M), _fmpq_mat(B)
    old = flint.ctx.prec
    prec = 256
    try:
        while True:
            flint.ctx.prec = prec
            try:
                X = flint.arb_mat(FM).solve(flint.arb_mat(FB))
            except ZeroDivisionError:  # the balls still contain a singular matrix: more precision
                X = None
            if X is not None and all(x.rad() <= abs(x.mid()) * flint.arb(2) ** -60 or x.rad() == 0
                                     for row in X.tolist() for x in row):
                return [[float(x.mid()) for x in row] for row in X.tolist()]
            prec *= 2
    finally:
        flint.ctx.prec = old


def observable(A: Sequence[Sequence[Fraction]], C: Sequence[Sequence[Fraction]]) -> tuple[bool, int]:
    """Exact observability of ``(A, C)``: grow the row space of ``C, CA, CA^2, ...`` until it stops.

    A full rank modulo a prime decides it at once (the integer Krylov determinant is then
    nonzero); otherwise the row space is grown in exact rational arithmetic.

    Returns ``(observable, dimension of the observable subspace)``.
    """
    n = len(A)
    if C and _full_rank_mod_p(A, C):
        return True, n
    basis, _ = _rref(C) if C else ([], [])
    block = basis
    dim = len(basis)
    while dim < n and block:
        block = matmul(block, A)
        new, _ = _rref(basis + block)
        if len(new) == dim:
            break
        basis, dim = new, len(new)
    return dim == n, dim


# ----------------------------------------------------------- matrix exponential
def _up(x: Fraction, bits: int = 64) -> Fraction:
    """``x`` rounded up to a dyadic with about ``bits`` significant bits (keeps error bounds short)."""
    if x <= 0:
        return Fraction(0) if x == 0 else -_down(-x, bits)
    e = bits - (x.numerator.bit_length() - x.denominator.bit_length())
    return Fraction(-((-x.numerator << e) // x.denominator), 1 << e) if e >= 0 else \
        Fraction(-((-x.numerator) // (x.denominator << -e)) << -e)


def _down(x: Fraction, bits: int = 64) -> Fraction:
    if x <= 0:
        return -_up(-x, bits)
    e = bits - (x.numerator.bit_length() - x.denominator.bit_length())
    return Fraction((x.numerator << e) // x.denominator, 1 << e) if e >= 0 else \
        Fraction((x.numerator // (x.denominator << -e)) << -e)


def expm_enclosure(A: Sequence[Sequence[Fraction]], T: Fraction, bits: int = 160
                   ) -> tuple[list[list[int]], int, Fraction]:
    """Rigorous enclosure of ``exp(A T)``: ``(E, w, err)`` with ``||exp(AT) - E/2**w||_inf <= err``.

    Scaling and squaring in fixed-point integer arithmetic with ``w = bits``
    fractional bits.  ``B = A T / 2**s`` with ``||B||_inf <= 1/2``; Taylor
    polynomial of degree ``K`` with the tail bound
    ``||B||^(K+1) / (K+1)! / (1 - ||B||/(K+2))``; every rounding (at most
    ``2**-w`` per entry) and the rounding of ``B`` itself are propagated
    through the recurrences as exact rational bounds, then through the ``s``
    squarings with ``eps' = (2 ||E|| + eps) eps + n 2**-w``.
    """
    n = len(A)
    T = Fraction(T)
    if T < 0:
        raise CertificateError(f"expm_enclosure needs T >= 0, got {T}")
    B = [[Fraction(x) * T for x in row] for row in A]
    nb = inf_norm(B) if n else Fraction(0)
    s = 0
    while nb / 2 ** s > Fraction(1, 2):
        s += 1
    Bs = [[x / 2 ** s for x in row] for row in B]
    nu = _up(nb / 2 ** s)
    one = 1 << bits
    unit = Fraction(1, one)
    Bh = [[round(x * one) for x in row] for row in Bs]
    beta = Fraction(n, 2) * unit  # ||Bs - Bh/2^w||_inf
    nu_hat = _up(inf_norm(Bh) * unit)
    # degree: tail < 2^-w
    K = 1
    fact = Fraction(1)
    while True:
        fact *= K + 1
        tail = _up(nu ** (K + 1) / fact / (1 - nu / (K + 2)))
        if tail < unit:
            break
        K += 1
    term = [[one if i == j else 0 for j in range(n)] for i in range(n)]
    total = [row[:] for row in term]
    err = Fraction(0)
    e_prev = Fraction(0)
    t_norm = Fraction(1)  # ||Bs^(k-1)/(k-1)!|| bound
    for k in range(1, K + 1):
        prod = matmul(term, Bh)
        div = k * one
        term = [[x // div for x in row] for row in prod]
        e_k = _up((e_prev * nu_hat + t_norm * beta) / k + n * unit)
        err = _up(err + e_k)
        e_prev = e_k
        t_norm = _up(t_norm * nu / k)
        total = [[x + y for x, y in zip(r1, r2)] for r1, r2 in zip(total, term)]
    err = _up(err + tail)
    E = total
    for _ in range(s):
        norm_E = _up(inf_norm(E) * unit)
        sq = matmul(E, E)
        E = [[x >> bits for x in row] for row in sq]
        err = _up((2 * norm_E + err) * err + n * unit)
    return E, bits, err
