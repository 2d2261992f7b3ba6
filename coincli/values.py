"""Values as a user writes them and as a message says them back: the one error of a value that
makes no sense (:class:`ParameterError`), the one parser of a number or a whole number given as
text (ASCII digits only), a value quoted short in a message, and a duration in words.

The lowest module of the package: it imports nothing of it, so that :mod:`coincli.params` and
:mod:`coincli.quantities`, which both need these, do not import each other (params re-exports
them: ``from coincli.params import ParameterError`` is the same class)."""

from __future__ import annotations

import math


class ParameterError(ValueError):
    """A parameter value that makes no physical or numerical sense (reported in one line).

    The message names parameters as the Python API does (``res must be at least 2``);
    ``parameters`` lists those of its names that a command line gives as options, for the CLI
    to say ``--res`` instead (:func:`coincli.cli.common.in_cli_words`)."""

    def __init__(self, message: str = "", *, parameters: tuple[str, ...] = ()):
        super().__init__(message)
        self.parameters = tuple(parameters)


SHOWN_CHARS = 40  # an error message quotes at most this much of a value
ASCII_SPACE = " \t\n\r\f\v"  # what a number may have around it (not str.strip's Unicode)


def shown(text) -> str:
    """A value as an error message quotes it: whole if short, else its first SHOWN_CHARS
    characters and '...' (a 100 kB value must not come back as 100 kB of error)."""
    text = text if isinstance(text, str) else repr(text)
    return text if len(text) <= SHOWN_CHARS + 3 else f"{text[:SHOWN_CHARS]}..."


def parse_number(text: str, finite: bool = True) -> float:
    """The number ``text`` writes, in ASCII: Python's float() also reads other scripts' digits
    ('١.٥' is 1.5 to it), which no option or preset here means to accept; the one parser of
    every number given as text. ParameterError (one line, the value cut short by
    :func:`shown`) otherwise, and for inf, nan or an overflow unless ``finite=False`` (a
    scene's values are then refused by :func:`coincli.params.validate`, which names them)."""
    stripped = text.strip(ASCII_SPACE)
    if not stripped.isascii():
        raise ParameterError(f"'{shown(stripped)}' is not a number: write numbers with the "
                             "ASCII digits 0-9, a '.' and an optional exponent (1.5, 2e-3)")
    try:
        value = float(stripped)
    except ValueError:
        raise ParameterError(f"'{shown(stripped)}' is not a valid number (e.g. 1.5 or "
                             "2e-3)") from None
    if finite and not math.isfinite(value):
        raise ParameterError(f"'{shown(stripped)}' is not a finite number: give one between "
                             "-1.7e308 and 1.7e308")
    return value


def parse_whole(text: str) -> int:
    """The whole number ``text`` writes in ASCII digits (see :func:`parse_number`)."""
    stripped = text.strip(ASCII_SPACE)
    if not stripped.isascii():
        raise ParameterError(f"'{shown(stripped)}' is not a whole number: write it with the "
                             "ASCII digits 0-9")
    try:
        return int(stripped)
    except ValueError:
        raise ParameterError(f"'{shown(stripped)}' is not a valid whole number (e.g. "
                             "1000)") from None


def format_seconds(seconds: float) -> str:
    """A measured time: '0.047 s', '3.2 s', '162.2 s' (two significant digits below a second,
    where a tenth would say a short run took 0.0 s)."""
    return f"{seconds:.2g} s" if seconds < 1 else f"{seconds:.1f} s"


def format_duration(seconds: float) -> str:
    """'40 s', '12 min', '3.5 h', '9.3 days', '2.1 years'."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    if seconds < 48 * 3600:
        return f"{seconds / 3600:.1f} h"
    if seconds < 730 * 86400:
        return f"{seconds / 86400:.1f} days"
    return f"{seconds / (365.25 * 86400):.1f} years"


__all__ = ["ASCII_SPACE", "SHOWN_CHARS", "ParameterError", "format_duration", "format_seconds",
           "parse_number",
           "parse_whole", "shown"]
