"""The one gate for user text that reaches generated files.

A model's name, description, references, signal roles, the recorded command
line and certificate summary are written into C comments (and the README's
Markdown).  Unescaped, ``description = "x */ int injected = 1; /*"`` ends the
header's comment and what follows is compiled into the user's application;
an ``__attribute__((constructor))`` function placed there runs when it starts.
:func:`c_comment` makes any text inert inside a ``/* ... */`` comment:

* ``*/`` and ``/*`` are split (``* /``, ``/ *``), so no comment ends or nests;
* ``??`` becomes ``? ?`` (every pair: ``???`` is ``? ? ?``) (a trigraph ``??/`` is a backslash in translation phase 1);
* a backslash becomes ``(backslash)`` (a backslash-newline splices lines in phase 2);
* control characters (newlines included) become spaces, so the text stays on its line;
* non-ASCII characters become ``<U+XXXX>`` (the source character set of C99 is ASCII,
  and a compiler's reading of other bytes depends on its locale and flags);
* a backtick becomes ``'`` (the README quotes names in Markdown code spans);
* a paper cited by seed number is cited by author and year (``switchobs._papers.cite``, in ASCII), as every
  text a user reads cites it.
"""

from __future__ import annotations

import re

from .._papers import cite

__all__ = ["c_comment"]

#: The first character of ``*/``, ``/*`` and ``??``: a space goes after it.
_PAIR_START = re.compile(r"\*(?=/)|/(?=\*)|\?(?=\?)")


def c_comment(text: str) -> str:
    """``text`` made safe as the inside of a C block comment and a Markdown code span, on one line.

    Examples
    --------
    >>> c_comment("x */ int injected = 1; /*")
    'x * / int injected = 1; / *'
    >>> c_comment("line\\nbreak ??/ \\u00b5s")
    'line break ? ?/ <U+00B5>s'
    >>> c_comment("observer (seed 000 eq. (8)-(9), seed 004)")
    'observer (Hoang et al. 2014 eq. (8)-(9), Pasillas-Lepine)'
    """
    out = []
    for ch in cite(str(text), ascii=True):
        code = ord(ch)
        if ch == "\\":
            out.append("(backslash)")
        elif ch == "`":
            out.append("'")
        elif code < 0x20 or code == 0x7F:
            out.append(" ")
        elif code > 0x7E:
            out.append(f"<U+{code:04X}>")
        else:
            out.append(ch)
    return _PAIR_START.sub(lambda m: m.group(0) + " ", "".join(out))
