"""Exceptions raised by switchobs.

Every exception subclasses a builtin so that callers that only know the
builtins (``ValueError``, ``RuntimeError``) still catch them.  Messages name
the offending value and say what to do; the CLI prints them as one line and
exits with a non-zero status.
"""

from __future__ import annotations

from ._papers import cite

__all__ = [
    "SwitchobsError",
    "ModelError",
    "ExpressionError",
    "DimensionError",
    "NotObservableError",
    "SpectrumError",
    "NotHurwitzError",
    "FreeSymbolError",
    "NotRealError",
    "CertificateError",
    "SolverFailure",
    "SimulationError",
    "ObserverInputError",
    "CodegenError",
    "PrerequisiteError",
    "TransformError",
    "OutputError",
    "LogError",
    "StructureLostWarning",
    "EXTRAS",
    "install_hint",
]


class SwitchobsError(Exception):
    """Base class of every error switchobs raises on purpose.

    Its text cites the papers by author and year (:func:`switchobs._papers.cite`): the code writes the
    messages with the specification's seed numbers, the user reads ``Aguado-Rojas 2020 eq. (3.4)``.
    """

    def __str__(self) -> str:
        return cite(super().__str__())


class ModelError(SwitchobsError, ValueError):
    """A model definition (built-in name, TOML file, matrices) is invalid."""


class ExpressionError(ModelError):
    """An expression string uses an unknown name, unsafe syntax or cannot be parsed."""


class DimensionError(SwitchobsError, ValueError):
    """A matrix or vector has the wrong shape."""


class NotObservableError(SwitchobsError, ValueError):
    """The pair (A, C) is not observable."""


class SpectrumError(SwitchobsError, ValueError):
    """A requested spectrum is not admissible (length, sign of real part, conjugation)."""


class NotHurwitzError(SwitchobsError, ValueError):
    """A matrix that must be Hurwitz is not."""


class FreeSymbolError(SwitchobsError, ValueError):
    """A numeric computation was asked of an expression with free symbols left."""


class NotRealError(SwitchobsError, ValueError):
    """A value that must be real (a gain, a matrix entry) has a nonzero imaginary part."""


class CertificateError(SwitchobsError, ValueError):
    """A certificate is malformed or does not hold."""


class SolverFailure(SwitchobsError, RuntimeError):
    """A numerical solver failed or returned an inaccurate answer."""


class SimulationError(SwitchobsError, ValueError):
    """A simulation or scenario was given inadmissible settings."""


class ObserverInputError(SimulationError):
    """An observer step refused its input (state, signals, dt or time scaling).

    ``code`` is the non-zero status the generated C ``<prefix>_step`` returns for
    the same case (table in ``docs/observers.md``), so that a C binding can raise
    the same error as the Python reference observer.
    """

    def __init__(self, message: str, code: int = 0):
        super().__init__(message)
        self.code = code


class CodegenError(SwitchobsError, RuntimeError):
    """C code generation or compilation failed."""


class PrerequisiteError(SwitchobsError, RuntimeError):
    """A pipeline stage cannot start: a package does not import or a tool (C compiler) is missing."""


class TransformError(SwitchobsError, ValueError):
    """A candidate time scale or change of coordinates that cannot be checked (wrong length, unknown name)."""


class OutputError(SwitchobsError, OSError):
    """An output file or directory cannot be written (missing directory, a directory in the way, no space)."""


class LogError(SwitchobsError, ValueError):
    """A measurement log or channel map that cannot be replayed (a channel missing, an unknown unit, time stamps
    that are not increasing, NaN samples, a file beyond the limits)."""


class StructureLostWarning(UserWarning):
    """A float input lost an exact structure that the certificate of the exact object relies on (e.g. a
    ``control.StateSpace`` pair exported by ``GainDesign.to_statespace`` no longer satisfies
    ``A_plus + A_minus = (K_minus - K_plus) C`` after rounding); the message names it and what to certify instead."""


#: Optional third-party packages -> the extra of switchobs that installs them (``pip install "switchobs[EXTRA]"``).
EXTRAS: dict[str, str] = {"casadi": "codegen", "dask": "sweep", "distributed": "sweep", "fmpy": "fmu",
                          "asammdf": "logs", "pyarrow": "logs", "pandas": "logs"}


def install_hint(module: str | None) -> str:
    """How to get a package that ``module`` belongs to: its extra, or a reinstall (a base dependency).

    The hint of a :class:`PrerequisiteError`, for installed users: an extra, never a repository command.

    Examples
    --------
    >>> install_hint("casadi.casadi")
    'install it with pip install "switchobs[codegen]"'
    """
    extra = EXTRAS.get((module or "").split(".")[0])
    if extra is not None:
        return f'install it with pip install "switchobs[{extra}]"'
    return 'reinstall switchobs and its dependencies (pip install --force-reinstall "switchobs")'
