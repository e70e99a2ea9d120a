"""navfuse's exceptions (raised by the Rust extension)."""

from __future__ import annotations

from typing import Any, Optional


class NavfuseError(Exception):
    """Base class of navfuse's errors."""


class InputError(NavfuseError, ValueError):
    """A bad input file or configuration.

    ``file``, ``line`` (1-based, or None) and ``field`` (column, key or record, or None)
    say where; the message says what was expected and what was found.
    """

    def __init__(self, message: str, *, file: Optional[str] = None, line: Optional[int] = None,
                 field: Optional[str] = None, partial: Any = None) -> None:
        super().__init__(message)
        self.message = message
        self.file = file
        self.line = line
        self.field = field
        self.partial = partial
        self.result = None


class RunError(NavfuseError, RuntimeError):
    """A run that could not start or had to stop (no initial pose, refused inputs,
    numerical failure). ``result`` holds what was computed before, or None."""

    def __init__(self, message: str, *, partial: Any = None) -> None:
        super().__init__(message)
        self.message = message
        self.partial = partial
        self.result = None


class Interrupted(NavfuseError):
    """A run stopped by its stop flag (Ctrl-C raises KeyboardInterrupt instead);
    ``result`` holds what was computed."""

    def __init__(self, message: str, *, partial: Any = None) -> None:
        super().__init__(message)
        self.message = message
        self.partial = partial
        self.result = None


class NavfuseWarning(UserWarning):
    """A plausibility finding about a run's inputs or result (the ``warnings`` of
    summary.json: units, axes, time scales, a mostly free-inertial solution, ...) or
    about its configuration."""


class UnreliableWarning(NavfuseWarning):
    """The run went to its end but its result is meaningless (summary.json ``status``
    "unreliable", its reasons in ``unreliable``: almost every GNSS epoch refused, a
    source's innovations beyond 10 sigma most of the time, IMU data ending long before
    the GNSS). ``navfuse run`` exits with status 3 then; ``RunResult.status`` says
    "unreliable"."""
