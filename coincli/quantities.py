"""Initial conditions as a user writes them: one syntax for a value and a range, in every command
and in the API (a scene's overrides, a sweep's axes, a throw's distributions, a cell to inspect).

    0.5   -1e-3   2e-3                    a number (ASCII digits)
    pi   -pi   2pi   pi/2   3pi/4   0.5pi  an angle or an angular velocity (phi0, vphi)
    r   5r   1.5r   r/2                    a height in the coin's half diagonal r (y0)
    LO:HI                                  a range, e.g. 0.05:2, -pi:pi, r:5r

A multiple of r depends on the coin, so a parsed value is a :class:`Quantity` that
:meth:`Quantity.resolve` turns into metres for the coin at hand (the scene's, after its own
overrides). Every other number given as text goes through :func:`coincli.values.parse_number`.
"""

from __future__ import annotations

import math
import numbers
import re
from dataclasses import dataclass

from .values import ParameterError, parse_number, shown

ANGLES = frozenset({"phi0", "vphi"})  # pi and its multiples mean radians (per second)
HEIGHTS = frozenset({"y0"})  # r and its multiples mean the coin's half diagonal
RANGE_HELP = "LO:HI, e.g. 0.05:2"

# A number's digits split one way only (no `\d+\.?\d*`, whose digits split n ways: a
# 100,000-digit value without a unit then took minutes to refuse)
_WITH_UNIT = re.compile(
    r"^(?P<sign>[+-]?)(?P<num>(\d+(\.\d*)?|\.\d+)(e[+-]?\d+)?)?\*?(?P<unit>pi|r)"
    r"(/(?P<div>(\d+(\.\d*)?|\.\d+)(e[+-]?\d+)?))?$")


@dataclass(frozen=True)
class Quantity:
    """A value as given: ``value`` itself, or ``value`` times the coin's half diagonal r
    (``per_r``, heights only)."""

    value: float
    per_r: bool = False

    def resolve(self, r: float) -> float:
        """The value in SI units for a coin of half diagonal ``r`` (m)."""
        return self.value * r if self.per_r else self.value

    def text(self) -> str:
        return f"{self.value:g}r" if self.per_r else f"{self.value:g}"


def units_of(name: str) -> str:
    """What a value of ``name`` may be written with, for messages: 'e.g. 0.5, -pi/2'."""
    extra = ", pi/2, -pi" if name in ANGLES else ", 5r (r: the half diagonal)" \
        if name in HEIGHTS else ""
    return f"e.g. 0.5, 2e-3{extra}"


def parse_quantity(name: str, value, *, finite: bool = True) -> Quantity:
    """One value of initial condition ``name``: a Python number, a Quantity, or text
    (:data:`module syntax <coincli.quantities>`). ParameterError (one line, naming ``name``)
    otherwise, and for an infinite value unless ``finite=False``."""
    if isinstance(value, Quantity):
        return value
    if isinstance(value, bool) or not isinstance(value, str | numbers.Real):
        raise ParameterError(f"{name}: {shown(value)} is not a number ({units_of(name)})",
                             parameters=(name,))
    if not isinstance(value, str):
        try:
            number = float(value)
        except OverflowError:  # an int past 1.8e308
            number = math.inf
        if finite and not math.isfinite(number):
            raise ParameterError(f"{name} must be finite, got {shown(value)}",
                                 parameters=(name,))
        return Quantity(number)
    text = value.strip()
    compact = text.replace(" ", "").lower()
    match = _WITH_UNIT.match(compact) if compact.isascii() else None
    if match is None:
        try:
            number = parse_number(text, finite=False)
        except ParameterError as exc:
            if not text.isascii():  # it says how: ASCII digits
                raise ParameterError(f"{name}: {exc}", parameters=(name,)) from None
            hint = f"; a range is {RANGE_HELP}" if _looks_like_a_range(text) else ""
            raise ParameterError(f"{name}: '{shown(text)}' is not a number ({units_of(name)})"
                                 f"{hint}", parameters=(name,)) from None
        if finite and not math.isfinite(number):
            raise ParameterError(f"{name}: '{shown(text)}' is not a finite number",
                                 parameters=(name,))
        return Quantity(number)
    unit = match.group("unit")
    if unit == "pi" and name not in ANGLES:
        raise ParameterError(f"{name}: '{shown(text)}': pi is for the angles "
                             f"({', '.join(sorted(ANGLES))})", parameters=(name,))
    if unit == "r" and name not in HEIGHTS:
        raise ParameterError(f"{name}: '{shown(text)}': multiples of r are for y0 only (r: the "
                             "coin's half diagonal)", parameters=(name, "y0"))
    number = float(match.group("num")) if match.group("num") else 1.0
    if unit == "pi":
        number *= math.pi
    if match.group("div"):
        divisor = float(match.group("div"))
        if divisor == 0:  # '/0', or a divisor below the smallest float ('/1e-400')
            raise ParameterError(f"{name}: '{shown(text)}' divides by zero", parameters=(name,))
        number /= divisor
    if match.group("sign") == "-":
        number = -number
    if not math.isfinite(number):
        raise ParameterError(f"{name}: '{shown(text)}' is not finite", parameters=(name,))
    return Quantity(number, per_r=unit == "r")


def _looks_like_a_range(text: str) -> bool:
    """'1..2', '1,2', '1-2', '1 2', '1 to 2': two numbers meant as a range."""
    return bool(re.search(r"\d\s*(\.\.|,|;|-|\s|to)\s*[-+.\dpr]", text.strip()))


def parse_span(name: str, value) -> Quantity | tuple[Quantity, Quantity]:
    """A fixed value, or a range (``'LO:HI'`` or a pair ``(lo, hi)``) of initial condition
    ``name``: a Quantity, or (lo, hi). LO must be below HI (in multiples of r both or neither:
    a range of heights is in one unit)."""
    if isinstance(value, tuple | list):
        if len(value) != 2:
            raise ParameterError(f"{name}: a range is (LO, HI), got {shown(value)}",
                                 parameters=(name,))
        lo, hi = (parse_quantity(name, v) for v in value)
        text = f"({shown(value[0])}, {shown(value[1])})"
    elif isinstance(value, str) and ":" in value:
        text = value.strip()
        parts = text.split(":")
        if len(parts) != 2 or not parts[0].strip() or not parts[1].strip():
            raise ParameterError(f"{name}: '{shown(text)}' is not a range: write it as "
                                 f"{RANGE_HELP}", parameters=(name,))
        lo, hi = (parse_quantity(name, part) for part in parts)
    else:
        try:
            return parse_quantity(name, value)
        except ParameterError as exc:
            if isinstance(value, str) and _looks_like_a_range(value):
                raise ParameterError(f"{name}: '{shown(value.strip())}' is not a number or a "
                                     f"range: write a range as {RANGE_HELP}",
                                     parameters=(name,)) from None
            raise exc from None
    if lo.per_r != hi.per_r:
        raise ParameterError(f"{name} {shown(text)}: give both ends in multiples of r (e.g. "
                             "r:5r) or both in metres, not a mix", parameters=(name,))
    if not lo.value < hi.value:
        raise ParameterError(f"{name} {shown(text)}: empty range (LO must be below HI)",
                             parameters=(name,))
    if not math.isfinite(hi.value - lo.value):  # its cell centres would be NaN
        raise ParameterError(f"{name} {shown(text)}: the range is too wide to divide into "
                             "cells (HI - LO is past the largest float, 1.8e308); narrow it",
                             parameters=(name,))
    return lo, hi


def resolve_span(span, r: float) -> float | tuple[float, float]:
    """A span of :func:`parse_span` in SI units for a coin of half diagonal ``r``."""
    if isinstance(span, Quantity):
        return span.resolve(r)
    lo, hi = (end.resolve(r) for end in span)
    return lo, hi


__all__ = ["ANGLES", "HEIGHTS", "Quantity", "RANGE_HELP", "parse_quantity", "parse_span",
           "resolve_span", "units_of"]
