"""MISRA C:2012 status of the generated C: the guidelines' categories and the deviation record.

The emitter (:mod:`switchobs.codegen._emit`, :mod:`switchobs.codegen._generate`) writes C in which cppcheck
2.10's misra addon (``cppcheck --addon=misra --enable=style --std=c99 <prefix>.c``) finds no violation of
a mandatory or required guideline (``tests/test_codegen_misra.py`` checks it for the built-in models, a user
model, every method and both real types).  What it still finds are advisory rules that the emitter keeps on
purpose; :func:`deviations` lists them for one generated observer, from what the emitter wrote (the macros
of the header the source does not use, the functions with more than one ``return``...), and
:func:`misra_record` writes them with their reasons into ``<prefix>_misra.md`` beside the code.

The category of every guideline of MISRA C:2012 (with Amendments 1 and 2), as published in its Appendix A,
is :data:`CATEGORY`; the tests classify each cppcheck finding with it.
"""

from __future__ import annotations

import re
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = ["CATEGORY", "Deviation", "deviations", "functions", "identifier_clashes", "misra_record",
           "misra_summary", "misra_findings", "CPPCHECK_COMMAND"]

#: How the files are checked (cppcheck 2.10 with its misra addon).
CPPCHECK_COMMAND = "cppcheck --addon=misra --enable=style --std=c99 {source}"

_MANDATORY = "9.1 12.5 13.6 17.3 17.4 17.6 19.1 21.13 21.17 21.18 21.19 21.20 22.2 22.4 22.5 22.6"
_ADVISORY = ("Dir 4.2 Dir 4.4 Dir 4.5 Dir 4.6 Dir 4.8 Dir 4.9 Dir 4.13 "
             "1.2 2.3 2.4 2.5 2.6 2.7 4.2 5.9 8.7 8.9 8.11 8.13 10.5 11.4 11.5 12.1 12.3 12.4 13.3 13.4 15.1 15.4 "
             "15.5 17.5 17.8 18.4 18.5 19.2 20.1 20.5 20.10 21.12")
_RULES = {1: 4, 2: 7, 3: 2, 4: 2, 5: 9, 6: 2, 7: 4, 8: 14, 9: 5, 10: 8, 11: 9, 12: 5, 13: 6, 14: 4, 15: 7,
          16: 7, 17: 8, 18: 8, 19: 2, 20: 14, 21: 21, 22: 10}
_DIRECTIVES = {1: 1, 2: 1, 3: 1, 4: 14}


def _categories() -> dict[str, str]:
    names = [f"{c}.{k}" for c, n in _RULES.items() for k in range(1, n + 1)]
    names += [f"Dir {c}.{k}" for c, n in _DIRECTIVES.items() for k in range(1, n + 1)]
    mandatory, advisory = set(_MANDATORY.split()), set(re.findall(r"(?:Dir )?\d+\.\d+", _ADVISORY))
    return {n: "Mandatory" if n in mandatory else "Advisory" if n in advisory else "Required" for n in names}


#: Guideline ("10.3" for Rule 10.3, "Dir 4.6") -> "Mandatory", "Required" or "Advisory" (MISRA C:2012
#: Appendix A, with Amendment 1 (rules 12.5, 21.13-21.20, Dir 4.14) and Amendment 2 (rules 1.4, 21.21)).
CATEGORY: dict[str, str] = _categories()

#: External identifiers must be distinct in their first 31 characters (C99 5.2.4.1, MISRA C:2012 rule 5.1),
#: macro and internal identifiers in their first 63 (rules 5.2, 5.4, 5.5).
_EXTERNAL, _INTERNAL = 31, 63


@dataclass(frozen=True)
class Deviation:
    """One advisory guideline that the generated files do not follow, where, and why.

    Attributes
    ----------
    rule : str
        The guideline (``"15.5"``, ``"Dir 4.9"``).
    file : str
        The file it concerns.
    where : tuple of str
        The identifiers (macros, functions, objects) it concerns.
    why : str
        The reason the emitter keeps it.
    reported : bool
        Whether cppcheck 2.10's misra addon reports it (the others it does not check).
    """

    rule: str
    file: str
    where: tuple[str, ...]
    why: str
    reported: bool = True

    @property
    def category(self) -> str:
        return CATEGORY[self.rule]


_DEFINE = re.compile(r"^#define ([A-Za-z_]\w*)", re.M)
_NAME = re.compile(r"([A-Za-z_]\w*)\(")


def functions(source: str) -> dict[str, tuple[int, int]]:
    """Name -> (first, last) line (1-based) of each function definition of a generated source: its first
    line starts in column 0 with a type, its body opens and closes with a brace in column 0."""
    out: dict[str, tuple[int, int]] = {}
    name, start = None, 0
    for number, line in enumerate(source.splitlines(), start=1):
        if line[:1].isalpha() and not line.startswith(("typedef", "extern")) and "(" in line and name is None:
            name, start = _NAME.search(line).group(1), number
            if line.endswith("}"):  # a one-line helper
                out[name] = (number, number)
                name = None
        elif line == "}" and name is not None:
            out[name] = (start, number)
            name = None
        elif line.endswith(";") and name is not None and line[:1].isalpha():  # a prototype, not a definition
            name = None
    return out


def deviations(prefix: str, header: str, source: str) -> tuple[Deviation, ...]:
    """The advisory deviations of one generated observer, from its files' text.

    Parameters
    ----------
    prefix : str
        The C prefix of the files (``<prefix>.h``, ``<prefix>.c``).
    header, source : str
        Their text.
    """
    h, c = f"{prefix}.h", f"{prefix}.c"
    P = prefix.upper()
    tokens = set(re.findall(r"[A-Za-z_]\w*", re.sub(r"/\*.*?\*/", " ", source, flags=re.S)))
    unused = tuple(m for m in _DEFINE.findall(header) if m not in tokens and m != f"{P}_H")
    text = source.splitlines()
    early = tuple(name for name, (first, last) in functions(source).items()
                  if sum(len(re.findall(r"\breturn\b", line)) for line in text[first - 1:last]) > 1)
    out = []
    if unused:
        out.append(Deviation("2.5", h, unused, "the header's macros are the API of the integrator (sizes, the index "
                             "of each state, signal and parameter, the status codes, the step bound); the source "
                             "uses only those it needs"))
    if f"{prefix}_default_params" in tokens:
        out.append(Deviation("8.7", c, (f"{prefix}_default_params",), "the default parameter vector is part of the "
                             "API (declared in the header for the integrator, who starts from it); the step also "
                             "reads it when params is NULL"))
    if early:
        out.append(Deviation("15.5", c, early, "each check returns its status code at once, before anything is "
                             "written (guard clauses, in the documented order of the status codes); a single exit "
                             "would nest every check in the one before it, a dozen levels in the step"))
    if f"{P}_UNLIKELY" in tokens:
        out.append(Deviation("Dir 4.9", c, (f"{P}_UNLIKELY",), "the branch hint must wrap the condition itself; "
                             "the macro is the condition unless SWITCHOBS_BRANCH_HINTS is defined", reported=False))
        out.append(Deviation("1.2", c, (f"{P}_UNLIKELY",), "only when compiled by clang with "
                             "-DSWITCHOBS_BRANCH_HINTS: __builtin_expect marks the refusals unlikely (clang then "
                             "inlines the kernel, faster steps); off by default", reported=False))
    return tuple(out)


def _clashes(names: Sequence[str], significant: int) -> list[tuple[str, str]]:
    """Pairs of distinct names equal in their first ``significant`` characters."""
    seen: dict[str, str] = {}
    out = []
    for name in dict.fromkeys(names):
        key = name[:significant]
        if key in seen and seen[key] != name:
            out.append((seen[key], name))
        seen.setdefault(key, name)
    return out


def identifier_clashes(prefix: str, header: str, source: str) -> list[tuple[str, str, str]]:
    """``(rule, name, name)`` for identifiers that C99 need not tell apart (rules 5.1, 5.4/5.5), e.g. with a long
    prefix: external identifiers in their first 31 characters, macros and internal ones in their first 63."""
    external = sorted(set(re.findall(rf"\b({re.escape(prefix)}_\w+)\(", header))
                      | set(re.findall(rf"\b({re.escape(prefix)}_default_params)\b", header)))
    internal = sorted(set(re.findall(r"\b([A-Za-z_]\w*)\b", re.sub(r"/\*.*?\*/|\"[^\"]*\"", " ", source + header,
                                                                    flags=re.S))))
    return ([("5.1", a, b) for a, b in _clashes(external, _EXTERNAL)]
            + [("5.4/5.5", a, b) for a, b in _clashes(internal, _INTERNAL)])


def misra_record(prefix: str, header: str, source: str) -> str:
    """``<prefix>_misra.md``: the MISRA C:2012 status of the files and the deviations with their reasons."""
    devs = deviations(prefix, header, source)
    clashes = identifier_clashes(prefix, header, source)
    lines = [f"# MISRA C:2012 deviation record of `{prefix}.c` and `{prefix}.h`", "",
             "Generated by switchobs with the files; do not edit, regenerate.", "",
             "How the files are checked (cppcheck 2.10 and its misra addon):", "", "```sh",
             CPPCHECK_COMMAND.format(source=f"{prefix}.c"), "```", "",
             "The emitter writes no violation of a mandatory or required guideline that this check finds "
             "(switchobs's tests run it on every method and both real types of abs-xbs3, abs-xbs4, abs-adaptive2 "
             "and a user model, and on the adaptive, super-twisting and vehicle-speed observers); "
             "what it reports are the advisory rules below, kept on purpose.  Rules marked *not checked* are not "
             "checked by the addon and are listed from what the emitter writes.", ""]
    if clashes:
        lines += ["**Not met (required):** identifiers that C99 need not tell apart, because of a long prefix: "
                  + "; ".join(f"rule {r}: `{a}` and `{b}`" for r, a, b in clashes)
                  + f".  Regenerate with a prefix of at most {_EXTERNAL - 5} characters (`--prefix`).", ""]
    lines += ["| guideline | category | file | where | why | reported by cppcheck |",
              "| --- | --- | --- | --- | --- | --- |"]
    for d in devs:
        name = d.rule if d.rule.startswith("Dir") else f"Rule {d.rule}"
        lines.append(f"| {name} | {d.category} | `{d.file}` | {', '.join(f'`{w}`' for w in d.where)} | {d.why} | "
                     f"{'yes' if d.reported else 'not checked'} |")
    lines += ["", "By construction (not all checked by the addon): every real is `" + prefix + "_real` (Dir 4.6), "
              "comparisons are `bool` (rules 10.1, 10.3, 14.4), every body is braced (15.6), loops have a constant "
              "or counted bound (14.2), no parameter is assigned (17.8), arrays are indexed and never reached by "
              "pointer arithmetic (18.4), no heap, no recursion, no global mutable state (Dir 4.12, rules 17.2, "
              "8.9).", ""]
    return "\n".join(lines)


_FINDING = re.compile(r"^(.+?):(\d+):(\S+)$")


def misra_findings(cppcheck: str, prefix: str, files: dict[str, str],
                   directory: Path | None = None) -> list[tuple[str, int, str]]:
    """(file name, line, guideline or cppcheck id) of every finding of cppcheck's misra addon on ``<prefix>.c``
    (:data:`CPPCHECK_COMMAND`; the header is analysed through its ``#include``).

    ``files`` are the generated files by name, written to ``directory`` (a temporary one by default) and checked
    there with the executable ``cppcheck``.

    Raises
    ------
    RuntimeError
        cppcheck failed or printed a line that is not a finding.
    """
    with tempfile.TemporaryDirectory(prefix="switchobs-misra-") as tmp:
        where = Path(tmp) if directory is None else directory
        where.mkdir(parents=True, exist_ok=True)
        for name, text in files.items():
            (where / name).write_text(text, encoding="utf-8")
        proc = subprocess.run([cppcheck, "--addon=misra", "--enable=style", "--std=c99", "-q",
                               "--template={file}:{line}:{id}", f"{prefix}.c"], cwd=where, capture_output=True,
                              text=True, check=False, timeout=300)
    if proc.returncode != 0:
        raise RuntimeError(f"cppcheck failed on {prefix}.c: {proc.stderr.strip()[:300]}")
    out = []
    for line in proc.stderr.splitlines():
        match = _FINDING.match(line)
        if not match:
            raise RuntimeError(f"unexpected cppcheck output: {line!r}")
        name, number, ident = match.groups()
        out.append((Path(name).name, int(number), ident.removeprefix("misra-c2012-")))
    return out


def misra_summary(prefix: str, header: str, source: str) -> list[str]:
    """The README's MISRA section: the status in a sentence and the deviated rules, the record named."""
    devs = deviations(prefix, header, source)
    clashes = identifier_clashes(prefix, header, source)
    rules = ", ".join(f"{d.rule if d.rule.startswith('Dir') else 'rule ' + d.rule} ({d.category.lower()})"
                      for d in devs)
    return ["## MISRA C:2012", "",
            f"cppcheck 2.10's misra addon (`{CPPCHECK_COMMAND.format(source=f'{prefix}.c')}`) finds no violation of "
            "a mandatory or required rule in what the emitter writes"
            + (" -- except rule 5.1 here: the prefix is too long, see the record" if clashes else "")
            + f".  Deviations, each with where and why, in `{prefix}_misra.md`: {rules}.", ""]
