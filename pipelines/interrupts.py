"""Ctrl-C, remembered.

The command line's SIGINT handler raises KeyboardInterrupt once and then ignores further
interrupts, so that the clean-up runs to its end. A KeyboardInterrupt raised while Python runs
a weak-reference callback or a destructor is printed as "Exception ignored" and lost, and the
command would then run on to a normal end. The handler therefore also records the request here,
and the run's observers call :func:`check` at every increment, which raises it again.
"""

from __future__ import annotations

_requested = False


def request() -> None:
    """Record a Ctrl-C (called by the signal handler)."""
    global _requested
    _requested = True


def clear() -> None:
    global _requested
    _requested = False


def check() -> None:
    """Raise KeyboardInterrupt if a Ctrl-C was recorded and not yet acted on."""
    global _requested
    if _requested:
        _requested = False
        raise KeyboardInterrupt
