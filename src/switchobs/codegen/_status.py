"""Status codes of the generated ``<prefix>_step`` and ``<prefix>_run``."""

from __future__ import annotations

from enum import IntEnum

__all__ = ["StepStatus", "STATUS_TEXT"]


class StepStatus(IntEnum):
    """What ``<prefix>_step`` returns; the state is left unchanged unless the status is ``OK``.

    Codes 0-5 are those of the Python reference observers
    (``switchobs.observers`` ``ErrorCode``, table in ``docs/observers.md``), so
    that the C binding raises the same :class:`~switchobs.exceptions.ObserverInputError`.
    Codes 6 and 7 exist only in C, where parameters are runtime inputs and
    pointers may be NULL.  Code 8 (``SUBSTEP_LIMIT``) exists only with a
    certified step bound ``H_MAX``; the Python reference observers built with
    ``h_max`` return it too.  The checks run in the order ``BAD_ARGUMENT``,
    ``BAD_DT``, ``NONFINITE_STATE``, ``NONFINITE_SIGNAL``, ``BAD_PARAM``,
    ``UNDEFINED_TIME_SCALE``, ``SUBSTEP_LIMIT``, then the domain of ``d`` and
    ``b`` and the result (``NONFINITE_RESULT``); the first failing check is reported.
    """

    OK = 0
    BAD_DT = 1                # dt is not finite or dt <= 0
    NONFINITE_STATE = 2       # an entry of xhat is NaN or +-inf
    NONFINITE_SIGNAL = 3      # a signal (y, external, input) is NaN or +-inf
    UNDEFINED_TIME_SCALE = 4  # a signal declared positive/negative has the wrong sign, a denominator of s is 0,
                              # or s is not finite
    NONFINITE_RESULT = 5      # d(y), b(y) undefined (zero denominator, log of a non-positive number, ...)
                              # or the new state is not finite (overflow)
    BAD_PARAM = 6             # a parameter is not finite, violates its declared sign, or a parameter-only
                              # denominator is 0
    BAD_ARGUMENT = 7          # xhat or signals is NULL, or n_steps < 0 (C only)
    SUBSTEP_LIMIT = 8         # |s|*dt exceeds MAX_SUBSTEPS*H_MAX (or is not finite): the step would need more
                              # sub-steps than allowed to stay within the certified bound


#: One-line description of each status (also returned by ``<prefix>_status_message``).
STATUS_TEXT: dict[StepStatus, str] = {
    StepStatus.OK: "ok",
    StepStatus.BAD_DT: "dt is not finite or dt <= 0",
    StepStatus.NONFINITE_STATE: "an entry of xhat is not finite",
    StepStatus.NONFINITE_SIGNAL: "a signal is not finite",
    StepStatus.UNDEFINED_TIME_SCALE: "the time scaling s is undefined at these signals",
    StepStatus.NONFINITE_RESULT: "d(y) or b(y) is undefined, or the new state is not finite",
    StepStatus.BAD_PARAM: "a parameter is not finite or violates its declared sign",
    StepStatus.BAD_ARGUMENT: "a required pointer is NULL or n_steps < 0",
    StepStatus.SUBSTEP_LIMIT: "|s|*dt exceeds MAX_SUBSTEPS*H_MAX (more sub-steps than allowed)",
}
