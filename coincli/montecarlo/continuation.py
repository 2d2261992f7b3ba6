"""The scenes along one or more physical parameters, mass and inertia following a solid disc,
a corner's coefficient of restitution, and Pender & Uhrin's prediction for comparison."""

from __future__ import annotations

import math
import re

import numpy as np

from ..defaults import PARAMETER_UNITS
from ..params import ParameterError, Scene, validate


def parse_over(text: str) -> tuple[str, np.ndarray]:
    """``thickness=0.001:0.02:20`` -> ('thickness', linspace(0.001, 0.02, 20));
    ``c=0.1,0.5,2`` -> ('c', [0.1, 0.5, 2]) (values listed, e.g. spaced unevenly). A name
    may be spelled as its option is, ``slip-velocity`` for ``slip_velocity``."""
    m = re.fullmatch(r"\s*([a-z_-]+)\s*=\s*(.+?)\s*", str(text), re.IGNORECASE | re.DOTALL)
    if m is None or ("," not in m.group(2) and m.group(2).count(":") != 2):
        raise ParameterError(f"over '{text}' is not NAME=LO:HI:STEPS (e.g. "
                             "thickness=0.001:0.02:20) or NAME=V1,V2,... (e.g. c=0.1,0.5,2)",
                             parameters=("over",))
    name = m.group(1).lower().replace("-", "_")
    if name not in PARAMETERS:
        raise ParameterError(f"over {name}: not a physical parameter; one of "
                             f"{', '.join(PARAMETERS)}", parameters=("over",))
    if "," in m.group(2):
        try:
            values = np.array([float(v) for v in m.group(2).split(",")])
        except ValueError:
            raise ParameterError(f"over '{text}': the values V1,V2,... must be numbers",
                                 parameters=("over",)) from None
        if not np.isfinite(values).all() or len(set(values.tolist())) != values.size:
            raise ParameterError(f"over '{text}': the values must be finite and differ",
                                 parameters=("over",))
        return name, values
    lo, hi, steps = m.group(2).split(":")
    try:
        lo, hi = float(lo), float(hi)
        steps = float(steps)
    except ValueError:
        raise ParameterError(f"over '{text}': LO, HI and STEPS must be numbers",
                             parameters=("over",)) from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
        raise ParameterError(f"over '{text}': LO must be below HI", parameters=("over",))
    if not steps.is_integer() or not 2 <= steps <= 10_000:
        raise ParameterError(f"over '{text}': STEPS must be a whole number from 2 to 10000",
                             parameters=("over",))
    return name, np.linspace(lo, hi, int(steps))


PARAMETERS = tuple(PARAMETER_UNITS)


def disc_density(scene: Scene) -> float:
    """kg/m^3 of the scene's coin as a solid disc of its diameter and thickness."""
    c = scene.coin
    return c.mass / (math.pi * c.r_d ** 2 * c.thickness)


def disc_inertia(mass: float, diameter: float, thickness: float) -> float:
    """A uniform solid disc turning about a diameter: m (3 (d/2)^2 + t^2) / 12."""
    return mass * (3 * (diameter / 2) ** 2 + thickness ** 2) / 12


def lamina_inertia(mass: float, diameter: float, thickness: float) -> float:
    """A rectangle lamina d x t turning in its plane: m (d^2 + t^2) / 12 (the square coin)."""
    return mass * (diameter ** 2 + thickness ** 2) / 12


def scene_at(scene: Scene, parameter: str, value: float, keep: tuple[str, ...] = ()) -> Scene:
    """The scene with ``parameter`` set to ``value`` (see :func:`point_scene`)."""
    return point_scene(scene, {parameter: value}, keep)


def point_scene(scene: Scene, at: dict[str, float], keep: tuple[str, ...] = ()) -> Scene:
    """The scene with each parameter of ``at`` set to its value. For thickness and diameter,
    the mass and the inertia follow a uniform solid disc of the base coin's density
    (m = rho pi (d/2)^2 t, I = m (3 (d/2)^2 + t^2) / 12), except those named in ``keep`` or
    set in ``at``, which keep their values."""
    for parameter in at:
        if parameter not in PARAMETERS:
            raise ParameterError(f"cannot vary '{parameter}'; one of {', '.join(PARAMETERS)}")
    new = scene.with_overrides(**{name: float(value) for name, value in at.items()})
    if {"thickness", "diameter"} & set(at):
        c = new.coin
        fixed = set(keep) | set(at)
        mass = c.mass if "mass" in fixed else \
            disc_density(scene) * math.pi * c.r_d ** 2 * c.thickness
        inertia = c.inertia if "inertia" in fixed else \
            disc_inertia(mass, c.diameter, c.thickness)
        new = new.with_overrides(mass=mass, inertia=inertia)
    return validate(new)


def continuation_note(scene: Scene, parameters: str | tuple[str, ...],
                      keep: tuple[str, ...] = ()) -> str | None:
    """What a user must know about the scenes of a continuation in thickness or diameter."""
    parameters = (parameters,) if isinstance(parameters, str) else tuple(parameters)
    shaped = [p for p in parameters if p in ("thickness", "diameter")]
    if not shaped:
        return None
    follow = [name for name in ("mass", "inertia") if name not in (*keep, *parameters)]
    if not follow:
        return "mass and inertia are held at the scene's values at every " + \
            " and ".join(shaped)
    c = scene.coin
    disc_i = disc_inertia(c.mass, c.diameter, c.thickness)
    text = (f"{' and '.join(follow)} follow{'s' if len(follow) == 1 else ''} a uniform solid "
            f"disc of the base coin's density ({disc_density(scene):.5g} kg/m^3): "
            "m = rho pi (d/2)^2 t, I = m (3 (d/2)^2 + t^2) / 12")
    if "inertia" in follow and abs(disc_i - c.inertia) > 1e-3 * c.inertia:
        paper = " printed in the paper" if abs(c.inertia - 7.06e-8) < 1e-12 else ""
        text += (f"; at the base coin (d = {c.diameter:g} m, t = {c.thickness:g} m) the "
                 f"disc's I is {disc_i:.3g} kg m^2, not the scene's {c.inertia:.3g}{paper}: "
                 "the curve does not pass through the base scene")
    if keep:
        text += f"; {' and '.join(keep)} held at the scene's value"
    return text


def corner_restitution(scene: Scene, lever: float = 0.0) -> float:
    """The coefficient of restitution of one corner of the coin struck straight down on the
    foundation, ``lever`` m horizontally from the centroid. Over the brief contact the corner
    is a damped oscillator: its vertical force -k y - c y' (eqs. 1-2) accelerates it by
    F (1/m + lever^2 / I) (the centroid by F / m, the turn by lever F / I), so its mass is
    m_eff = 1 / (1/m + lever^2 / I), zeta = c / (2 sqrt(k m_eff)), and it leaves the surface
    (y = 0 again) after half a damped period with e = exp(-pi zeta / sqrt(1 - zeta^2)) of its
    speed; 0 from critical damping (zeta >= 1) on, where it never comes back up. Gravity,
    the turn during the contact and the horizontal damper are left out (lever = 0, a corner
    under the centroid, with no spin and no sliding, is exact but for gravity)."""
    coin, k, c = scene.coin, float(scene.foundation.k), float(scene.foundation.c)
    if c <= 0:
        return 1.0
    m_eff = 1.0 / (1.0 / coin.mass + lever ** 2 / coin.inertia)
    zeta = c / (2.0 * math.sqrt(k * m_eff))
    if zeta >= 1.0:
        return 0.0
    return math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta))


def pender_uhrin(ratio) -> np.ndarray:
    """P(standing) of a planar die with sides d and t = ratio d after Pender and Uhrin
    (arXiv:1407.6307): P(edge) / P(face) = (sqrt(d^2 + t^2) - d) / (sqrt(d^2 + t^2) - t)
    * arctan(t / d) / arctan(d / t), i.e. the ratio of the energy barriers times the ratio of
    the angular widths of the wells (a die with random orientation rolling through many
    revolutions on a bouncy or grippy surface). 1/2 for a square, 3.7e-4 for t/d = 0.1."""
    x = np.asarray(ratio, dtype=np.float64)
    hyp = np.hypot(1.0, x)
    odds = (hyp - 1.0) / (hyp - x) * np.arctan(x) / np.arctan(1.0 / x)
    return odds / (1.0 + odds)
