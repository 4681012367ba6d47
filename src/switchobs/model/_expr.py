"""Safe parsing of expression strings into sympy expressions.

Strings are parsed with Python's :mod:`ast` and translated node by node into
sympy objects; nothing is ever passed to :func:`eval`.  Only arithmetic,
numbers, whitelisted function calls and names from an explicit table are
accepted, so a model file cannot run code.

Exact arithmetic makes short text expensive (``9**9**9**9``, ``2**1000000``),
so every expression is bounded before any of it is evaluated: its length,
its nesting depth and number of terms, the digits of its exact numbers and
the exponent of its exact powers (:mod:`switchobs._limits`).  A decimal
literal must be a double (``1e400`` and ``1e-400`` are refused).
"""

from __future__ import annotations

import ast
import math
from collections.abc import Mapping
from fractions import Fraction
from numbers import Integral
from typing import Any

import numpy as np
import sympy as sp

from .._limits import (MAX_EXPONENT, MAX_EXPRESSION_DEPTH, MAX_EXPRESSION_LENGTH, MAX_EXPRESSION_TERMS,
                       MAX_NUMBER_DIGITS, check_double, digits, decimal_fraction)
from ..exceptions import ExpressionError

__all__ = ["parse_expression", "free_names", "exact_number", "non_finite", "FUNCTIONS"]

#: Functions an expression string may call, by name.
FUNCTIONS: Mapping[str, sp.Basic] = {
    "exp": sp.exp,
    "log": sp.log,
    "sqrt": sp.sqrt,
    "sin": sp.sin,
    "cos": sp.cos,
    "tan": sp.tan,
    "tanh": sp.tanh,
    "atan": sp.atan,
    "Abs": sp.Abs,
    "abs": sp.Abs,
    "sign": sp.sign,
}
_CONSTANTS = {"pi": sp.pi, "E": sp.E, "I": sp.I}
#: What sympy makes of a division by zero, ``log(0)``, ``0**-1`` or ``0/0``: no value a model may hold.
_NON_FINITE = (sp.zoo, sp.nan, sp.oo, -sp.oo)


def non_finite(expr: sp.Basic) -> bool:
    """Whether ``expr`` holds an infinity or NaN (``1/0`` is ``zoo``, ``0/0`` is ``nan`` to sympy)."""
    return any(expr.has(x) for x in _NON_FINITE)

_BINOPS = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
    ast.Pow: lambda a, b: a**b,
}


def exact_number(value: Any, *, what: str = "number") -> Any:
    """The one float rule: a number object as an exact sympy number; any other value unchanged.

    A binary float (Python, NumPy of any width, a sympy ``Float``, also inside a
    sympy expression) is its exact binary value: ``0.1`` is
    ``3602879701896397/36028797018963968``, the number the computer holds, as the
    certificate checker reads it.  Integers (also NumPy's) and fractions are
    exact anyway, complex numbers take the rule per part.  Text is left alone:
    it is the decimal it spells, read by :func:`parse_expression`.  NumPy
    scalars never pass through their ``repr`` (``np.float64(-40)`` in NumPy 2).

    Raises
    ------
    ExpressionError
        For a boolean, NaN or an infinity.
    """
    if isinstance(value, (bool, np.bool_)):
        raise ExpressionError(f"{what}: expected a number, got the boolean {value!r}")
    if isinstance(value, (float, np.floating)):
        if not math.isfinite(value):
            raise ExpressionError(f"{what}: {value!r} is not finite; give a finite number")
        return sp.Rational(*value.as_integer_ratio())
    if isinstance(value, Integral):
        return sp.Integer(int(value))
    if isinstance(value, Fraction):
        return sp.Rational(value.numerator, value.denominator)
    if isinstance(value, (complex, np.complexfloating)):
        return exact_number(value.real, what=what) + sp.I * exact_number(value.imag, what=what)
    if isinstance(value, sp.Basic) and not isinstance(value, sp.Rational):
        floats = value.atoms(sp.Float)
        if any(not f.is_finite for f in floats):
            raise ExpressionError(f"{what}: {value!r} is not finite")
        return value.xreplace({f: sp.Rational(f) for f in floats}) if floats else value
    return value


def parse_expression(text: str | int | float, names: Mapping[str, sp.Symbol], *, what: str = "expression") -> sp.Expr:
    """Parse ``text`` into a sympy expression using only the symbols in ``names``.

    Parameters
    ----------
    text : str or number
        The expression, e.g. ``"-a*y/vx"`` or ``"c2^2"``.  Decimal numbers in
        text are converted exactly (``"187.5"`` becomes ``375/2``); a float
        object is its exact binary value.
    names : mapping of str to Symbol
        The only names the expression may use (besides the functions in
        :data:`FUNCTIONS` and ``pi``, ``E``, ``I``).
    what : str
        Where the expression comes from, for error messages (e.g. ``"A[1][2]"``).

    Raises
    ------
    ExpressionError
        On a syntax error, an unknown name, or any construct other than
        arithmetic and whitelisted function calls.
    """
    text = exact_number(text, what=what)
    if isinstance(text, sp.Basic):
        return _rename(text, names, what)
    if not isinstance(text, str):
        raise ExpressionError(f"{what}: expected an expression string, got {type(text).__name__} {text!r}")
    body, source = _syntax_tree(text, what)
    return _Translator(names, what, text, source).visit(body)


def _syntax_tree(text: str, what: str) -> tuple[ast.expr, str]:
    """The checked syntax tree of ``text``: length, depth and size within the limits before anything is built."""
    if len(text) > MAX_EXPRESSION_LENGTH:
        raise ExpressionError(f"{what}: the expression has {len(text)} characters (limit {MAX_EXPRESSION_LENGTH}): "
                              f"{text[:30]!r}...; simplify it or split it into parameters")
    # Engineers write x^2; Python's ^ binds looser than + and *, so it is
    # rewritten before parsing rather than mapped on the syntax tree.
    source = text.strip().replace("^", "**")
    try:
        tree = ast.parse(source, mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"{what}: cannot parse {text!r} ({exc.msg})") from None
    except (RecursionError, MemoryError):  # the parser's own stack: nesting far beyond the limit
        raise ExpressionError(f"{what}: the expression is nested more than {MAX_EXPRESSION_DEPTH} levels deep "
                              f"(limit {MAX_EXPRESSION_DEPTH}): {text[:30]!r}...") from None
    terms, stack = 0, [(tree.body, 1)]
    while stack:  # iterative: a deep tree must not exhaust the Python stack here either
        node, depth = stack.pop()
        # Operands and calls, not operators: an operator joins operands already counted, so counting it too
        # would refuse a legitimate expanded polynomial (a 42-monomial f of 750 characters) long before the
        # length limit, while a hostile text is bounded by its operands just as well.
        terms += isinstance(node, (ast.Name, ast.Constant, ast.Call))
        if depth > MAX_EXPRESSION_DEPTH:
            raise ExpressionError(f"{what}: the expression is nested more than {MAX_EXPRESSION_DEPTH} levels deep "
                                  f"(limit {MAX_EXPRESSION_DEPTH}): {text[:30]!r}...")
        if terms > MAX_EXPRESSION_TERMS:
            raise ExpressionError(f"{what}: the expression has more than {MAX_EXPRESSION_TERMS} terms (numbers, "
                                  f"names and calls; limit {MAX_EXPRESSION_TERMS}): {text[:30]!r}...; split it "
                                  "into parameters")
        stack.extend((child, depth + (0 if _chained(node, child) else 1)) for child in ast.iter_child_nodes(node)
                     if not isinstance(child, (ast.operator, ast.unaryop, ast.expr_context)))
    return tree.body, source


_SUMS, _PRODUCTS = (ast.Add, ast.Sub), (ast.Mult, ast.Div)


def _chained(parent: ast.AST, child: ast.AST) -> bool:
    """``a + b + c`` is one sum, not a nesting: the left operand of a sum (product) that is a sum (product)."""
    if not (isinstance(parent, ast.BinOp) and isinstance(child, ast.BinOp) and child is parent.left):
        return False
    return any(isinstance(parent.op, group) and isinstance(child.op, group) for group in (_SUMS, _PRODUCTS))


def _rename(expr: sp.Basic, names: Mapping[str, sp.Symbol], what: str) -> sp.Expr:
    """A sympy expression over ``names``: its symbols matched by name (a user's ``Symbol("a")`` is the model's ``a``)."""
    unknown = sorted(s.name for s in expr.free_symbols if s.name not in names)
    if unknown:
        known = ", ".join(sorted(names)) or "none"
        raise ExpressionError(f"{what}: unknown name(s) {unknown} in {expr} (known names: {known})")
    return expr.xreplace({s: names[s.name] for s in expr.free_symbols})


def free_names(text: str) -> list[str]:
    """Names an expression string uses, other than functions and constants (``[]`` if it does not parse).

    Lets callers declare new design symbols (``beta1``) before parsing.
    """
    try:
        body, _ = _syntax_tree(str(text), "expression")
    except ExpressionError:
        return []  # parse_expression reports the error with context
    return [node.id for node in ast.walk(body)
            if isinstance(node, ast.Name) and node.id not in FUNCTIONS and node.id not in _CONSTANTS]


class _Translator(ast.NodeVisitor):
    def __init__(self, names: Mapping[str, sp.Symbol], what: str, text: str, source: str):
        self.names = names
        self.what = what
        self.text = text
        self.source = source

    def _fail(self, detail: str) -> ExpressionError:
        return ExpressionError(f"{self.what}: {detail} in {self.text!r}")

    def generic_visit(self, node: ast.AST) -> sp.Expr:
        raise self._fail(f"unsupported syntax {type(node).__name__!r} (only arithmetic and calls to "
                         f"{', '.join(sorted(FUNCTIONS))} are allowed)")

    def visit_Constant(self, node: ast.Constant) -> sp.Expr:
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self._fail(f"unsupported constant {value!r}")
        # The literal as written ("0.1" is 1/10, "1e400" is not inf): the digits are checked before expansion.
        literal = ast.get_source_segment(self.source, node) or repr(value)
        number = decimal_fraction(literal, what=self.what, error=ExpressionError)
        if isinstance(value, float):
            check_double(number, what=self.what, error=ExpressionError, text=literal)
        return sp.Rational(number.numerator, number.denominator)

    def visit_Name(self, node: ast.Name) -> sp.Expr:
        if node.id in self.names:
            return self.names[node.id]
        if node.id in _CONSTANTS:
            return _CONSTANTS[node.id]
        known = ", ".join(sorted(self.names)) or "none"
        raise self._fail(f"unknown name {node.id!r} (known names: {known}; declare it under "
                         "'parameters', 'external' or 'inputs')")

    def visit_BinOp(self, node: ast.BinOp) -> sp.Expr:
        op = _BINOPS.get(type(node.op))
        if op is None:
            raise self._fail(f"unsupported operator {type(node.op).__name__!r}")
        left, right = self.visit(node.left), self.visit(node.right)
        if isinstance(node.op, ast.Pow):
            self._check_power(left, right)
        return self._check_size(op(left, right))

    def _check_power(self, base: sp.Expr, exponent: sp.Expr) -> None:
        """An exact power may not explode: a bounded numeric exponent, a result of bounded size (estimated)."""
        if not exponent.is_Number:
            if exponent.free_symbols:
                raise self._fail(f"the exponent {exponent} is not a number (a symbolic exponent can take any "
                                 "size once values are given); write exp(k*log(x)) if you mean it")
            return
        if exponent.is_Rational:
            p, q = abs(int(exponent.p)), int(exponent.q)
            # A number to a power is bounded by its digits; a power of a name by its exponent, since the
            # name's value is only known later.
            if base.is_Rational and q <= MAX_EXPONENT:
                if max(digits(int(base.p)), digits(int(base.q))) * p > MAX_NUMBER_DIGITS:
                    raise self._fail(f"{_short(base)}**{_short(exponent)} has more than {MAX_NUMBER_DIGITS} digits "
                                     f"(limit {MAX_NUMBER_DIGITS})")
            elif max(p, q) > MAX_EXPONENT:
                raise self._fail(f"the exponent {_short(exponent)} is larger than {MAX_EXPONENT} "
                                 f"(limit {MAX_EXPONENT} on exact powers of names)")

    def _check_size(self, value: sp.Expr) -> sp.Expr:
        """Exact numbers stay within MAX_NUMBER_DIGITS and powers within MAX_EXPONENT (sympy merges them); the
        value is finite (a division by zero is refused where it is written, not found as ``zoo`` in a result)."""
        if non_finite(value):
            raise self._fail(f"the value is {value} (a division by zero, log(0) or 0**-1); an entry must be finite")
        for atom in value.atoms(sp.Rational) if not value.is_Rational else (value,):
            if max(digits(int(atom.p)), digits(int(atom.q))) > MAX_NUMBER_DIGITS:
                raise self._fail(f"an exact number has more than {MAX_NUMBER_DIGITS} digits "
                                 f"(limit {MAX_NUMBER_DIGITS})")
        for power in value.atoms(sp.Pow):
            exponent = power.exp
            if exponent.is_Rational and max(abs(int(exponent.p)), int(exponent.q)) > MAX_EXPONENT:
                raise self._fail(f"the power {_short(power)} has an exponent larger than {MAX_EXPONENT} "
                                 f"(limit {MAX_EXPONENT} on exact powers)")
        return value

    def visit_UnaryOp(self, node: ast.UnaryOp) -> sp.Expr:
        if isinstance(node.op, ast.USub):
            return self._check_size(-self.visit(node.operand))
        if isinstance(node.op, ast.UAdd):
            return self.visit(node.operand)
        raise self._fail(f"unsupported operator {type(node.op).__name__!r}")

    def visit_Call(self, node: ast.Call) -> sp.Expr:
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            name = node.func.id if isinstance(node.func, ast.Name) else ast.unparse(node.func)
            raise self._fail(f"call of {name!r} is not allowed (allowed: {', '.join(sorted(FUNCTIONS))})")
        if node.keywords:
            raise self._fail("keyword arguments are not allowed")
        args = [self.visit(arg) for arg in node.args]
        if len(args) != 1:  # every function of FUNCTIONS takes one argument
            raise self._fail(f"{node.func.id}() takes exactly one argument, got {len(args)}")
        return self._check_size(FUNCTIONS[node.func.id](*args))


def _short(value: sp.Basic) -> str:
    """A value for a message: its text, or its size when the text would be long."""
    if isinstance(value, sp.Integer) and digits(int(value)) > 40:
        return f"<integer of about {digits(int(value))} digits>"
    text = str(value)
    return text if len(text) <= 60 else text[:30] + "..."
