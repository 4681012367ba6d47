"""casadi C kernels, post-processed into strict C99 for double or float.

casadi's ``CodeGenerator`` writes each SX function as a straight-line body of
scalar temporaries ``a0, a1, ...`` (``codegen_scalars``) wrapped in its own
calling convention (``arg``/``res`` pointer arrays, ``iw``, ``w``, ``mem``)
and runtime boilerplate.  Only the body is kept; it is rewritten so that

* inputs are plain pointers (``x[k]``, ``sig[k]``, ``par[k]``) or the scalar ``dt``,
  the output is ``out[k]``, and the function is ``static`` with no unused argument;
* ``casadi_real`` becomes the header's ``<prefix>_real`` (``double`` or ``float``; MISRA C:2012 Dir 4.6);
  in the float build every literal gets an ``f`` suffix and every libm call its float variant
  (``sqrtf``, ``expf``...), so nothing is promoted to double;
* casadi's helpers (``casadi_sq``, ``casadi_sign``, ``casadi_fabs``) become static
  functions of the generated file, so no global symbol is added;
* the type model of MISRA C:2012 (the essential types of its rules 10.x and 14.4): casadi keeps the result
  of a comparison in a real temporary (``a10=(a09<a04);``) and tests reals for truth (``(a10?a11:0)``,
  ``(!a10)``).  A comparison is written into a ``bool`` temporary ``b10`` instead, read as the condition
  of the ternary (whose zero becomes a real literal) and negated with ``!``; a boolean read as a number
  is ``(b10?1.0:0.0)``, a real tested for truth ``(!((a<=0.0)&&(a>=0.0)))``.  ``==`` and ``!=`` between
  reals are written with ``<=`` and ``>=`` (gcc ``-Wfloat-equal``), which give the same result for every
  value, NaN included; so every temporary has one essential type and the results are unchanged;
* one declaration per line (MISRA rule 12.3 reads a list as the comma operator).

Anything in casadi's output that this rewriting does not recognise raises
:class:`~switchobs.exceptions.CodegenError` instead of producing C that might
silently differ.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca

from ..exceptions import CodegenError

__all__ = ["CFunction", "kernel", "LIBM", "float_literal"]

#: libm functions casadi may call, double name -> float name.
LIBM = {"sqrt": "sqrtf", "exp": "expf", "log": "logf", "sin": "sinf", "cos": "cosf", "tan": "tanf",
        "tanh": "tanhf", "atan": "atanf", "pow": "powf", "fabs": "fabsf", "fmin": "fminf", "fmax": "fmaxf"}
#: casadi helpers and what they become (``{p}`` is the prefix, ``{f}`` the libm suffix).
_HELPERS = {"casadi_sq": "{p}_sq", "casadi_sign": "{p}_sign", "casadi_fabs": "fabs{f}",
            "casadi_fmin": "fmin{f}", "casadi_fmax": "fmax{f}"}

_LITERAL = re.compile(r"(?<![\w.])(\d+\.\d*(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")
_ARG = re.compile(r"arg\[(\d+)\]\? arg\[\1\]\[(\d+)\] : 0")
_RES = re.compile(r"if \(res\[0\]!=0\) res\[0\]\[(\d+)\]=")
_LOCAL = re.compile(r"^[ab]\d+$")
_NUMBER = re.compile(r"(?<![\w.])\d+(?:\.\d*)?(?:[eE][+-]?\d+)?[fF]?(?![\w.])")
_DECLARATION = re.compile(r"^casadi_real (a\d+(?:, a\d+)*);$")
_ASSIGNMENT = re.compile(r"^(a\d+|out\[\d+\])=(.*);$")
_TEMPORARY = re.compile(r"\ba(\d+)\b")
# the only logic casadi's C holds for the translated observers (OP_LT, OP_LE, OP_EQ, OP_NE, OP_NOT,
# OP_IF_ELSE_ZERO); anything else with a logical operator is refused
_COMPARISON = re.compile(r"^\((a\d+)(<=|<|==|!=)(a\d+)\)$")
_NOT = re.compile(r"^\(!(a\d+)\)$")
_IF_ELSE_ZERO = re.compile(r"^\((a\d+)\?(a\d+):0\)$")
_BOOLEAN = re.compile(r"\?|!|&&|\|\||<|>|==")


def float_literal(value: float, real: str) -> str:
    """A C literal of ``value`` that round-trips in double and carries ``f`` in float."""
    text = repr(float(value))
    if "." not in text and "e" not in text and "inf" not in text and "nan" not in text:
        text += ".0"
    return text + ("f" if real == "float" else "")


@dataclass(frozen=True)
class CFunction:
    """One generated static C function ``void name(inputs..., real *out)``.

    Attributes
    ----------
    name : str
    inputs : tuple of str
        The argument names it takes, in order (only those it uses).
    body : str
        The C definition.
    temporaries : int
        Number of scalar temporaries (casadi's ``sz_w``): the stack the kernel needs, in reals.
    """

    name: str
    inputs: tuple[str, ...]
    body: str
    temporaries: int

    def call(self, out: str, **args: str) -> str:
        """The C call with the given argument expressions (by input name)."""
        return f"{self.name}({', '.join([*(args[k] for k in self.inputs), out])});"


def kernel(name: str, inputs: Sequence[tuple[str, ca.SX]], output: ca.SX, *, real: str, prefix: str,
           scalars: Sequence[str] = ("dt",)) -> CFunction:
    """Generate and post-process the C of ``output`` as a function of ``inputs``.

    Parameters
    ----------
    name : str
        C name of the static function.
    inputs : sequence of (name, casadi.SX)
        Symbolic inputs; those named in ``scalars`` are passed by value, the others as ``const real *``.
    output : casadi.SX
        Column of outputs (made dense).
    real : {"double", "float"}
    prefix : str
        Prefix of the helper functions (``<prefix>_sq``...).
    """
    out = ca.densify(ca.SX(output))
    fn = ca.Function(name, [sym for _, sym in inputs], [out])
    gen = ca.CodeGenerator(name, {"with_header": False, "with_export": False, "casadi_real": "casadi_real"})
    gen.add(fn)
    text = gen.dump()
    start = text.find("static int casadi_f0(")
    if start < 0:
        raise CodegenError(f"casadi {ca.__version__} output has no kernel 'static int casadi_f0(' for {name}; "
                           "this casadi version is not supported by switchobs.codegen")
    open_brace = text.index("{", start)
    close = text.find("\n}\n", open_brace)
    body = text[open_brace + 1:close].strip("\n")
    lines = [line.strip() for line in body.splitlines() if line.strip()]
    if not lines or lines[-1] != "return 0;":
        raise CodegenError(f"unexpected end of the casadi kernel for {name}: {lines[-1:]!r}")
    lines = lines[:-1]

    used: set[int] = set()

    def arg(match: re.Match) -> str:
        i, k = int(match.group(1)), int(match.group(2))
        used.add(i)
        nm = inputs[i][0]
        if nm in scalars:
            if k != 0:
                raise CodegenError(f"scalar input {nm} indexed at {k} in the casadi kernel {name}")
            return nm
        return f"{nm}[{k}]"

    suffix = "f" if real == "float" else ""
    declared: list[str] = []
    statements = []
    for line in lines:
        decl = _DECLARATION.match(line)
        if decl:
            declared += decl.group(1).split(", ")
            continue
        line = _ARG.sub(arg, line)
        line = _RES.sub(lambda m: f"out[{m.group(1)}]=", line)
        for helper, repl in _HELPERS.items():
            line = re.sub(rf"\b{helper}\(", repl.format(p=prefix, f=suffix) + "(", line)
        if real == "float":
            for dbl, flt in LIBM.items():
                line = re.sub(rf"\b{dbl}\(", f"{flt}(", line)
            line = _LITERAL.sub(lambda m: m.group(1) + "f", line)
        statements.append(line)
    rewritten, reals, booleans = _typed(statements, real=real, name=name)
    if not set(reals) | set(booleans) <= set(declared):
        raise CodegenError(f"casadi's C for {name} uses undeclared temporaries; casadi {ca.__version__} output is "
                           "not supported by switchobs.codegen")

    real_t = f"{prefix}_real"
    allowed = {"out", *(nm for nm, _ in inputs)}
    allowed |= set(LIBM.values()) if real == "float" else set(LIBM)
    allowed |= {f"{prefix}_sq", f"{prefix}_sign"}
    for line in rewritten:
        for token in re.findall(r"[A-Za-z_]\w*", _NUMBER.sub("", line)):
            if token not in allowed and not _LOCAL.match(token):
                raise CodegenError(f"unexpected token {token!r} in casadi's C for {name} ({line!r}); "
                                   f"casadi {ca.__version__} output is not supported by switchobs.codegen")
    locals_ = [f"{real_t} {a};" for a in declared if a in reals]
    locals_ += [f"bool b{a[1:]};" for a in declared if a in booleans]
    rewritten = locals_ + rewritten
    order = [i for i in range(len(inputs)) if i in used]
    params = []
    for i in order:
        nm = inputs[i][0]
        params.append(f"{real_t} {nm}" if nm in scalars else f"const {real_t} *{nm}")
    params.append(f"{real_t} *out")
    signature = f"static void {name}({', '.join(params)})"
    body_text = "\n".join(f"    {line}" for line in rewritten)
    definition = f"{signature}\n{{\n{body_text}\n}}\n"
    return CFunction(name=name, inputs=tuple(inputs[i][0] for i in order), body=definition,
                  temporaries=int(fn.sz_w()))


def _typed(statements: Sequence[str], *, real: str, name: str) -> tuple[list[str], list[str], list[str]]:
    """casadi's assignments with one essential type per temporary (the module docstring).

    Returns the statements and the temporaries ``aN`` that hold a real somewhere and those that hold a
    boolean somewhere (declared as ``bN``).  The temporaries are reused for values of either kind, so
    the kind of each is followed through the straight-line code.
    """
    zero, one = float_literal(0.0, real), float_literal(1.0, real)
    boolean: set[str] = set()  # temporaries that hold a boolean at this point of the code
    reals: dict[str, None] = {}
    booleans: dict[str, None] = {}

    def as_real(a: str) -> str:
        return f"(b{a[1:]}?{one}:{zero})" if a in boolean else a

    def as_bool(a: str) -> str:
        return f"b{a[1:]}" if a in boolean else f"(!(({a}<={zero})&&({a}>={zero})))"

    out = []
    for line in statements:
        match = _ASSIGNMENT.match(line)
        if match is None:
            raise CodegenError(f"unexpected statement in casadi's C for {name} ({line!r}); "
                               f"casadi {ca.__version__} output is not supported by switchobs.codegen")
        lhs, rhs = match.groups()
        cmp, neg, sel = _COMPARISON.match(rhs), _NOT.match(rhs), _IF_ELSE_ZERO.match(rhs)
        if cmp:
            left, op, right = as_real(cmp.group(1)), cmp.group(2), as_real(cmp.group(3))
            value = {"<": f"({left}<{right})", "<=": f"({left}<={right})",
                     "==": f"(({left}<={right})&&({left}>={right}))",
                     "!=": f"(!(({left}<={right})&&({left}>={right})))"}[op]
        elif neg:
            a = neg.group(1)
            value = f"(!b{a[1:]})" if a in boolean else f"(({a}<={zero})&&({a}>={zero}))"
        elif sel:
            value = f"({as_bool(sel.group(1))}?{as_real(sel.group(2))}:{zero})"
        elif _BOOLEAN.search(rhs):
            raise CodegenError(f"unexpected logical operator in casadi's C for {name} ({line!r}); "
                               f"casadi {ca.__version__} output is not supported by switchobs.codegen")
        else:
            value = _TEMPORARY.sub(lambda m: as_real(m.group(0)), rhs)
        if (cmp or neg) and lhs.startswith("a"):
            out.append(f"b{lhs[1:]}={value};")
            boolean.add(lhs)
            booleans[lhs] = None
            continue
        if cmp or neg:  # a boolean output: the number 0 or 1
            value = f"({value}?{one}:{zero})"
        out.append(f"{lhs}={value};")
        if lhs.startswith("a"):
            boolean.discard(lhs)
            reals[lhs] = None
    for line in out:
        reals.update((f"a{m.group(1)}", None) for m in _TEMPORARY.finditer(line))
    return out, list(reals), list(booleans)
