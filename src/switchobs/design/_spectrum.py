"""Target spectra and characteristic polynomials for K_plus placement."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import sympy as sp
from sympy import QQ_I

from ..exceptions import SpectrumError
from ..model import Model, entries, free_names, make_symbol, parse_expression
from ._routh import is_hurwitz_exact

__all__ = ["parse_spectrum", "spectrum_coefficients", "polynomial_coefficients", "LAPLACE"]

#: The Laplace variable used in characteristic polynomials.
LAPLACE = sp.Symbol("s")


def _names_for(model: Model, texts: Sequence[str]) -> dict[str, sp.Symbol]:
    """Model parameters plus fresh positive symbols for every other name used.

    New names in a spectrum (``beta1``) are design parameters; they are
    declared positive so that ``-beta1`` is a pole with negative real part.
    """


    names = {p: model.symbols[p] for p in model.parameters}
    forbidden = set(model.states) | {model.output} | set(model.external) | set(model.inputs) | {"t"}
    for text in texts:
        for name in free_names(text):
            if name in names:
                continue
            if name in forbidden:
                raise SpectrumError(f"the spectrum uses {name!r}, a state or signal of model "
                                    f"{model.name!r}; poles may only use parameters and new design symbols")
            names[name] = make_symbol(name, positive=True)
    return names


def parse_spectrum(spectrum: str | Sequence, model: Model) -> tuple[sp.Expr, ...]:
    """Parse and validate a target spectrum for ``A_plus``.

    Parameters
    ----------
    spectrum : str or sequence
        Comma-separated string (``"-beta1,-beta2,-beta2"``) or a sequence of
        numbers / strings / sympy expressions.  Unknown names are new design
        symbols, assumed positive.
    model : Model

    Raises
    ------
    SpectrumError
        Wrong length, a pole whose real part is non-negative or undecidable,
        or a set of poles not closed under conjugation.
    """
    spectrum = entries(spectrum, name="the spectrum")
    items = [p for p in spectrum.split(",")] if isinstance(spectrum, str) else list(spectrum)
    texts = [str(p) for p in items if not isinstance(p, sp.Basic)]
    names = _names_for(model, texts)
    poles = []
    for i, p in enumerate(items):
        if isinstance(p, sp.Basic):  # numbers were made exact by entries() (the one float rule)
            poles.append(p)
        else:
            if isinstance(p, str) and not p.strip():
                raise SpectrumError(f"pole {i + 1} of the spectrum {spectrum!r} is empty")
            poles.append(parse_expression(p, names, what=f"spectrum pole {i + 1}"))
    if len(poles) != model.n:
        raise SpectrumError(f"the spectrum has {len(poles)} pole(s) but model {model.name!r} has dimension "
                            f"{model.n}; give exactly {model.n} poles (repeat a pole for multiplicity)")
    for p in poles:
        real = sp.re(p)
        if real.is_negative is True:
            continue
        if real.is_negative is False or real.is_nonnegative:
            raise SpectrumError(f"pole {p} has a non-negative real part ({real}); every pole of A_plus "
                                "must have a negative real part")
        raise SpectrumError(f"cannot decide the sign of the real part of pole {p}; write it with positive "
                            "design symbols (e.g. -beta1) or give the parameter values")
    coeffs = spectrum_coefficients(poles)
    if any((sp.im(c) if c.is_number else sp.simplify(sp.im(c))) != 0 for c in coeffs):
        raise SpectrumError(f"the poles {[str(p) for p in poles]} are not closed under complex conjugation, "
                            "so no real gain places them")
    return tuple(poles)


def _gaussian(p: sp.Expr) -> Any:
    """``p`` as an element of QQ<I> (Gaussian rationals), or None if it is not one."""
    if not p.is_number:
        return None
    re, im = p.as_real_imag()
    return QQ_I.from_sympy(re + sp.I * im) if re.is_Rational and im.is_Rational else None


def spectrum_coefficients(poles: Sequence[sp.Expr]) -> tuple[sp.Expr, ...]:
    """``alpha_1..alpha_n`` of ``prod (s - p) = s^n + alpha_1 s^(n-1) + ... + alpha_n``.

    Numeric poles (Gaussian rationals) are multiplied out as coefficient lists
    over QQ<I>, exactly and without building an expression.
    """
    numbers = [_gaussian(sp.sympify(p)) for p in poles]
    if all(x is not None for x in numbers):
        coeffs = [QQ_I(1)]
        for x in numbers:  # (s - x) * sum c_k s^(m-k)
            coeffs = [c - x * prev for c, prev in zip(coeffs + [QQ_I(0)], [QQ_I(0)] + coeffs)]
        return tuple(QQ_I.to_sympy(c) for c in coeffs[1:])
    coeffs = sp.Poly(sp.Mul(*[(LAPLACE - p) for p in poles]), LAPLACE).all_coeffs()
    return tuple(sp.expand(c) for c in coeffs[1:])


def polynomial_coefficients(poly: str | sp.Expr | Sequence, model: Model) -> tuple[sp.Expr, ...]:
    """Coefficients of a target characteristic polynomial, normalised to be monic.

    ``poly`` is an expression in ``s`` (``"s^3 + 6*s^2 + 11*s + 6"``) or the
    list (NumPy vector, sympy matrix) of its coefficients, highest degree first.

    Raises
    ------
    SpectrumError
        Wrong degree, zero leading coefficient, or a polynomial that is
        provably not Hurwitz.
    """
    if not isinstance(poly, (str, sp.Basic)):
        poly = entries(poly, name="the characteristic polynomial")
    if isinstance(poly, (list, tuple)):
        texts = [str(c) for c in poly]
        names = _names_for(model, texts)
        coeffs = [c if isinstance(c, sp.Basic) else parse_expression(c, names, what=f"coefficient {i}")
                  for i, c in enumerate(poly)]
    else:
        names = _names_for(model, [str(poly)])
        names.pop("s", None)
        names["s"] = LAPLACE
        expr = poly if isinstance(poly, sp.Basic) else parse_expression(poly, names, what="characteristic polynomial")
        coeffs = sp.Poly(expr, LAPLACE).all_coeffs()
    if len(coeffs) != model.n + 1:
        raise SpectrumError(f"the characteristic polynomial has degree {len(coeffs) - 1} but model "
                            f"{model.name!r} has dimension {model.n}")
    lead = sp.sympify(coeffs[0])
    if lead == 0:
        raise SpectrumError("the characteristic polynomial has a zero leading coefficient")
    alpha = tuple(sp.cancel(c / lead) for c in coeffs[1:])
    if is_hurwitz_exact(alpha) is False:
        raise SpectrumError(f"the characteristic polynomial with coefficients {[str(a) for a in alpha]} is not "
                            "Hurwitz (a Routh–Hurwitz condition fails); A_plus would be unstable")
    return alpha


