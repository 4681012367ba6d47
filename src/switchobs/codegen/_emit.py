"""casadi C kernels, post-processed into strict C99 for double or float.

casadi's ``CodeGenerator`` writes each SX function as a straight-line body of
scalar temporaries ``a0, a1, ...`` (``codegen_scalars``) wrapped in its own
calling convention (``arg``/``res`` pointer arrays, ``iw``, ``w``, ``mem``)
and runtime boilerplate.  Only the body is kept; it is rewritten so that

* inputs are plain pointers (``x[k]``, ``sig[k]``, ``par[k]``) or the scalar ``dt``,
  the output is ``out[k]``, and the function is ``static`` with no unused argument;
* ``casadi_real`` becomes ``double`` or ``float``; in the float build every
  literal gets an ``f`` suffix and every libm call its float variant
  (``sqrtf``, ``expf``...), so nothing is promoted to double;
* casadi's helpers (``casadi_sq``, ``casadi_sign``, ``casadi_fabs``) become static
  functions of the generated file, so no global symbol is added.

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
_LOCAL = re.compile(r"^a\d+$")
_NUMBER = re.compile(r"(?<![\w.])\d+(?:\.\d*)?(?:[eE][+-]?\d+)?[fF]?(?![\w.])")
# casadi tests reals for truth (``a1=(a0?a2:0);``, ``a1=(!a0);``): clang's -Wfloat-conversion refuses the
# implicit real -> _Bool conversion, so the tests are written as comparisons with 0.
_TRUTH = re.compile(r"\((a\d+)\?")
_NOT = re.compile(r"\(!(a\d+)\)")
_BOOLEAN = re.compile(r"\?|!(?!=)|&&|\|\|")


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
    rewritten = []
    for line in lines:
        line = _ARG.sub(arg, line)
        line = _RES.sub(lambda m: f"out[{m.group(1)}]=", line)
        line = line.replace("casadi_real", real)
        line = _NOT.sub(r"(\1==0)", _TRUTH.sub(r"(\1!=0?", line))
        if _BOOLEAN.search(line.replace("!=0?", "")):
            raise CodegenError(f"unexpected logical operator in casadi's C for {name} ({line!r}); "
                               f"casadi {ca.__version__} output is not supported by switchobs.codegen")
        for helper, repl in _HELPERS.items():
            line = re.sub(rf"\b{helper}\(", repl.format(p=prefix, f=suffix) + "(", line)
        if real == "float":
            for dbl, flt in LIBM.items():
                line = re.sub(rf"\b{dbl}\(", f"{flt}(", line)
            line = _LITERAL.sub(lambda m: m.group(1) + "f", line)
        rewritten.append(line)

    allowed = {real, "out", *(nm for nm, _ in inputs)}
    allowed |= set(LIBM.values()) if real == "float" else set(LIBM)
    allowed |= {f"{prefix}_sq", f"{prefix}_sign"}
    for line in rewritten:
        for token in re.findall(r"[A-Za-z_]\w*", _NUMBER.sub("", line)):
            if token not in allowed and not _LOCAL.match(token):
                raise CodegenError(f"unexpected token {token!r} in casadi's C for {name} ({line!r}); "
                                   f"casadi {ca.__version__} output is not supported by switchobs.codegen")
    order = [i for i in range(len(inputs)) if i in used]
    params = []
    for i in order:
        nm = inputs[i][0]
        params.append(f"{real} {nm}" if nm in scalars else f"const {real} *{nm}")
    params.append(f"{real} *out")
    signature = f"static void {name}({', '.join(params)})"
    body_text = "\n".join(f"    {line}" for line in rewritten)
    definition = f"{signature}\n{{\n{body_text}\n}}\n"
    return CFunction(name=name, inputs=tuple(inputs[i][0] for i in order), body=definition,
                  temporaries=int(fn.sz_w()))
