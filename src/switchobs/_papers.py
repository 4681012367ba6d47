"""The papers of the specification as a user reads them cited: by author and year, not by seed number.

The code, its comments and its docstrings cite the papers by the number of their file in the specification
(``seed 000 eq. (13)``: the seed documents are ``000_....txt``, ``001_....txt``, ...).  What a user reads cites
them by author and year with the same equation numbers (``Hoang et al. 2014 eq. (13)``): the generated pages
(``switchobs reproduce``, ``switchobs theory``), the command line's help, messages and printed descriptions,
and the generated C and its files.  :func:`cite` rewrites the one into the other from the one table
:data:`PAPERS`; the API pages rewrite the docstrings with it at build time (``docs/_hooks/roles.py``).
"""

from __future__ import annotations

import re
import unicodedata

__all__ = ["PAPERS", "SEED_NUMBER", "cite"]

#: The papers by seed number, as user-facing text cites them.  Seed 004 is a talk's slides: they give no year.
PAPERS: dict[str, str] = {"000": "Hoang et al. 2014", "001": "Aguado-Rojas 2020", "003": "M'Sirdi et al. 2008",
                          "004": "Pasillas-Lépine"}
#: The same in ASCII, for the generated C (whose source character set is ASCII) and its files.
_ASCII: dict[str, str] = {number: unicodedata.normalize("NFKD", paper).encode("ascii", "ignore").decode()
                          for number, paper in PAPERS.items()}
#: A citation by seed number: "seed 000", "Seed 001" (the number is group 1).
SEED_NUMBER = re.compile(r"\b[Ss]eed[ -](00[0-9])\b")


def cite(text: str, *, ascii: bool = False) -> str:
    """``text`` with every seed number of :data:`PAPERS` replaced by the paper's author and year.

    The equation, section and figure numbers that follow stay as they are.  With ``ascii``, accents are
    dropped (``Pasillas-Lepine``).  A number that is not in the table is left as written.

    Examples
    --------
    >>> cite("the observer of seed 000 eq. (8)-(9), Theorem 1 of seed 004")
    'the observer of Hoang et al. 2014 eq. (8)-(9), Theorem 1 of Pasillas-Lépine'
    >>> cite("Seed 004 (slides)", ascii=True)
    'Pasillas-Lepine (slides)'
    """
    papers = _ASCII if ascii else PAPERS
    return SEED_NUMBER.sub(lambda m: papers.get(m.group(1), m.group(0)), text)
