"""What a certificate is about: its model and gains, and the links :func:`verify_certificate` could check.

The exact checks of :mod:`switchobs.certify._verify` prove statements about
the family ``{A_p}`` in the document.  Whether that family is the switched
observer of the model named in ``provenance`` is a separate link:
``A_plus = A - K_plus C`` and ``A_minus = -A + K_minus C`` (the ``observer``
section's check), and ``A``, ``C`` of the ``observer`` section equal to the
model's at the recorded parameter values (checked here, for a built-in model
or a model given to the checker).  A link that cannot be checked is reported
as such, never silently skipped.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..exceptions import SwitchobsError
from ..exact import fraction_matrix
from ._schema import CertificateDocument, Check, ObserverSection

__all__ = ["model_link"]


def model_link(document: CertificateDocument, model: Any = None) -> tuple[Check | None, tuple[str, ...]]:
    """The check of the model–observer link, if it can be made, and what was not checked.

    Parameters
    ----------
    document : CertificateDocument
    model : Model, optional
        The model the certificate should be about (``switchobs verify --model``); by default
        the built-in model named in ``provenance.model``, when there is one.

    Returns
    -------
    (Check or None, tuple of str)
        The ``model`` check (None when it cannot be made) and one sentence per link left unchecked.
    """
    observer = document.sections.get(ObserverSection.KEY)
    unchecked: list[str] = []
    if observer is None:
        unchecked.append("observer section absent: the model-gain link (A_plus = A - K_plus C, "
                         "A_minus = -A + K_minus C) is not checked")
    name = document.provenance.get("model")
    if model is None:
        if not isinstance(name, str):
            unchecked.append("provenance.model absent: which model the certificate is about is not checked")
            return None, tuple(unchecked)
        from ..model import builtin_model

        try:
            model = builtin_model(name)
        except SwitchobsError:
            unchecked.append(f"model {name!r} is not a built-in model: its A and C are not compared with the "
                             "certificate (give it with --model FILE)")
            return None, tuple(unchecked)
    if observer is None:
        unchecked.append(f"model {model.name!r}: with no observer section, its A and C are not compared")
        return None, tuple(unchecked)
    parameters = document.provenance.get("parameters") or {}
    if not isinstance(parameters, Mapping):
        return Check("model", False, "provenance.parameters must be an object name -> value, got "
                                     f"{str(parameters)[:60]!r}"), tuple(unchecked)
    if isinstance(name, str) and name != model.name:
        return Check("model", False, f"the certificate names the model {name!r}, not {model.name!r}"), \
            tuple(unchecked)
    n = len(observer.A) if isinstance(observer.A, list) else None
    if n != model.n:
        return Check("model", False, f"the observer has {n} states, model {model.name!r} has {model.n}"), \
            tuple(unchecked)
    # A model whose values were substituted before certify_model records only the rest: it cannot be rebuilt.
    needed = sorted({str(s) for s in model.A.free_symbols | model.C.free_symbols} - set(parameters))
    if needed:
        unchecked.append(f"model {model.name!r}: the certificate does not record {needed}, so its A and C are "
                         "not compared with the observer's")
        return None, tuple(unchecked)
    return _compare(model, parameters, observer), tuple(unchecked)


def _compare(model: Any, parameters: Mapping[str, Any], observer: ObserverSection) -> Check:
    """``A``, ``C`` of the observer section against the model's at the recorded values, exactly."""
    values = {k: v for k, v in parameters.items() if k in model.parameters}
    try:
        numeric = model.with_values(values).numeric()
        A = fraction_matrix(numeric.A, what=f"{model.name} A")
        C = fraction_matrix(numeric.C, what=f"{model.name} C")
    except SwitchobsError as exc:
        return Check("model", False, f"model {model.name!r} at the recorded parameters: {exc}")
    try:
        claimed_A = fraction_matrix(observer.A, what="observer A")
        claimed_C = fraction_matrix(observer.C, what="observer C")
    except SwitchobsError as exc:
        return Check("model", False, str(exc))
    shown = ", ".join(f"{k} = {v}" for k, v in values.items())
    where = f"model {model.name!r}" + (f" at {shown}" if shown else "")
    if claimed_A != A:
        return Check("model", False, f"the observer's A differs from the A of {where}")
    if claimed_C != C:
        return Check("model", False, f"the observer's C differs from the C of {where}")
    return Check("model", True, f"the observer's A and C are those of {where}")
