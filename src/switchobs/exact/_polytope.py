"""Polytopes of matrices that depend polynomially on parameters in a box (exact, standard library only).

``A(theta) = sum_m theta^m M_m`` (one rational matrix ``M_m`` per monomial ``m``) over a box of
``theta``: every condition affine in ``A`` holds on the whole box once it holds at the vertices of a
polytope containing ``{A(theta)}``.  For affine dependence these are the box's own vertices; for
polynomial dependence (monomial lifting) each monomial ranges over its exact interval on a sub-box
(``pieces`` per parameter of degree > 1), and the vertices of every lifted sub-box contain the image.
Used by the box certificates, their independent check and the box gain synthesis.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence
from fractions import Fraction

from ._exact import Matrix, add, matmul, scale, sub, zeros

__all__ = ["Interval", "monomial_range", "box_pieces", "vertex_values", "evaluate_terms", "observer_pair",
           "vertex_matrices"]

Interval = tuple[Fraction, Fraction]


def monomial_range(exponents: Sequence[int], box: Sequence[Interval]) -> Interval:
    """Exact range of ``prod theta_i^e_i`` over a box (product of the exact ranges of the powers)."""
    lo, hi = Fraction(1), Fraction(1)
    for e, (a, b) in zip(exponents, box):
        if e == 0:
            continue
        ends = (a ** e, b ** e)
        plo, phi = (Fraction(0), max(ends)) if e % 2 == 0 and a < 0 < b else (min(ends), max(ends))
        cands = (lo * plo, lo * phi, hi * plo, hi * phi)
        lo, hi = min(cands), max(cands)
    return lo, hi


def box_pieces(box: Sequence[Interval], degrees: Sequence[int], pieces: int) -> Iterator[list[Interval]]:
    """The sub-boxes: parameters of degree > 1 cut into ``pieces`` equal intervals, the others kept whole."""
    axes = []
    for (a, b), deg in zip(box, degrees):
        k = pieces if deg > 1 else 1
        axes.append([(a + (b - a) * i / k, a + (b - a) * (i + 1) / k) for i in range(k)])
    for combo in itertools.product(*axes):
        yield list(combo)


def vertex_values(monomials: Sequence[Sequence[int]], box: Sequence[Interval], pieces: int
                  ) -> list[list[Fraction]]:
    """Monomial values at the vertices of the lifted boxes (one list of values per vertex, deduplicated)."""
    degrees = [max((m[i] for m in monomials), default=0) for i in range(len(box))]
    seen: dict[tuple[Fraction, ...], None] = {}
    for sub_box in box_pieces(box, degrees, pieces):
        ranges = [monomial_range(m, sub_box) for m in monomials]
        choices = [(r[0],) if r[0] == r[1] else r for r in ranges]
        for values in itertools.product(*choices):
            seen.setdefault(tuple(values), None)
    return [list(v) for v in seen]


def evaluate_terms(terms: Sequence[tuple[Sequence[int], Matrix]], values: Sequence[Fraction]) -> Matrix:
    """``sum_m values[m] M_m``."""
    n = len(terms[0][1])
    A = zeros(n, n)
    for (_, M), v in zip(terms, values):
        if v:
            A = add(A, scale(v, M))
    return A


def observer_pair(A: Matrix, C: Matrix, K_plus: Matrix, K_minus: Matrix) -> tuple[Matrix, Matrix]:
    """``(A - K_plus C, -A + K_minus C)``."""
    return sub(A, matmul(K_plus, C)), add(scale(-1, A), matmul(K_minus, C))


def vertex_matrices(terms: Sequence[tuple[Sequence[int], Matrix]], box: Sequence[Interval], pieces: int,
                    C: Matrix, K_plus: Matrix, K_minus: Matrix) -> tuple[list[Matrix], list[Matrix]]:
    """``A_plus`` and ``A_minus`` at every vertex of the lifted boxes: ``(plus list, minus list)``."""
    plus, minus = [], []
    for values in vertex_values([m for m, _ in terms], box, pieces):
        Ap, Am = observer_pair(evaluate_terms(terms, values), C, K_plus, K_minus)
        plus.append(Ap)
        minus.append(Am)
    return plus, minus
