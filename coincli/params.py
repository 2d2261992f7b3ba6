"""Parameters of one scene: the coin, the foundation, gravity, the initial state and the
integration settings.

Everything is a frozen dataclass so that a scene can be hashed, compared and stored verbatim in
every output (Zarr attributes, Rerun recordings). Kernels never see these objects: they get the
named tuples of plain floats built once from a scene, its model's parameters
(:attr:`coincli.models.Model.params`: the coin, the foundation, gravity and what follows from
them) and :class:`RunSettings` (how to integrate,
:func:`coincli.integrators.registry.run_settings`), and the float64 state vector of
:func:`state_array`; that is what lets numba cache its compiled code.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, field, fields, replace
from typing import NamedTuple

from .enums import Method

# the error of a bad value and the parsers of numbers as text live in coincli.values, which
# quantities imports too; re-exported here, where every caller has always found them
from .values import ParameterError, parse_number, parse_whole, shown  # noqa: F401

# Layout of the state vector.
STATE_NAMES = ("x", "y", "phi", "vx", "vy", "vphi")


@dataclass(frozen=True)
class Coin:
    """A rigid rectangle: diameter d, thickness t (m), mass m (kg), moment of inertia I (kg m^2)."""

    diameter: float = 0.02
    thickness: float = 0.002
    mass: float = math.pi * 1e-3
    inertia: float = 7.06e-8

    @property
    def r_d(self) -> float:
        return self.diameter / 2

    @property
    def r_t(self) -> float:
        return self.thickness / 2

    @property
    def r(self) -> float:
        """Half diagonal: the distance from the centroid to a corner."""
        return math.hypot(self.r_d, self.r_t)

    @property
    def phi_cr(self) -> float:
        """Angle at which the diagonal is vertical (the coin balances on one corner)."""
        return math.atan2(self.r_d, self.r_t)


@dataclass(frozen=True)
class Foundation:
    """Winkler foundation with viscous damping acting on each penetrating corner: stiffness k
    (N/m) and damping c (N s/m); and Coulomb friction at the corners, regularized: coefficient
    mu (0, the default, is the paper's frictionless foundation) over a slip velocity
    slip_velocity (m/s) below which a corner's friction force falls linearly to zero
    (docs/friction.md)."""

    k: float = 1.0e4  # N/m
    c: float = 0.5  # N s/m
    mu: float = 0.0  # friction coefficient
    slip_velocity: float = 1.0e-3  # m/s, the regularization's slip velocity v_s


@dataclass(frozen=True)
class InitialState:
    """Initial position (x0, y0 in m, phi0 in rad) and velocity (vx, vy in m/s, vphi in rad/s) of
    the centroid. ``y0=None`` means y0 = r (as in the paper)."""

    x0: float = 0.0
    y0: float | None = None
    phi0: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    vphi: float = 0.0


@dataclass(frozen=True)
class Integration:
    """How the equations of motion are integrated.

    ``dt`` is the step of a fixed-step method (or the initial step of an adaptive one), ``rtol``
    the relative tolerance of an adaptive one. ``t_end`` is a fixed horizon; None (the default)
    runs every throw until its outcome is decided, capped at CAP_FACTOR times the throw's
    :func:`coincli.models.paper.decision_time` (what its energy and the foundation's damping allow:
    :meth:`Scene.horizon`), with ``max_steps`` as the guard against runs that never end.
    ``stop_on_settle`` stops a run as soon as its outcome is certain (total energy below
    E_crit); the paper's own runs always last ``t_end`` (2 s, preset paper-method).
    ``verify`` computes every outcome at a ladder of tighter settings until two agree
    (coincli.integrators.ladder); without it a run is a single pass, its label unverified.
    ``max_steps`` bounds the work of one run (like diffrax's ``max_steps``): a run that needs
    more ends with status ``budget``, not with a label. By default an adaptive run may take
    ADAPTIVE_MAX_STEPS steps (a typical throw takes under a hundred), a fixed-step run the
    t_end / dt steps it asks for (FIXED_MAX_STEPS without a horizon).
    """

    method: Method = Method.EVENT
    dt: float = 1.0e-6
    rtol: float = 1.0e-6
    t_end: float | None = None  # s, a fixed horizon; None: until decided, within the cap
    stop_on_settle: bool = True
    max_steps: int | None = None  # the step budget of one run; None: the method's default
    verify: bool = True  # climb the ladder of settings until the label converges

    def __post_init__(self):
        # presets, stores and options name the method; the scene holds the member
        try:
            object.__setattr__(self, "method", Method.parse(self.method))
        except ValueError as exc:
            raise ParameterError(str(exc)) from None


@dataclass(frozen=True)
class Scene:
    """Everything one throw needs: the coin, the foundation, gravity g (m/s^2), the initial
    state and the integration settings, in SI units. Made by :func:`coincli.load_preset`;
    ``scene.with_overrides(vy=1.2, k=5000)`` gives a changed copy (flat names, see there)."""

    coin: Coin = field(default_factory=Coin)
    foundation: Foundation = field(default_factory=Foundation)
    g: float = 9.81
    initial: InitialState = field(default_factory=InitialState)
    integration: Integration = field(default_factory=Integration)

    # -- derived quantities -------------------------------------------------------------------
    @property
    def y0(self) -> float:
        return self.coin.r if self.initial.y0 is None else self.initial.y0

    @property
    def fixed_horizon(self) -> bool:
        """Whether runs last a fixed t_end (else: until decided, within the cap)."""
        return self.integration.t_end is not None

    @property
    def e_crit(self) -> float:
        """Total energy below which the count of quarter turns can no longer change (NOTES.md)."""
        weight = self.coin.mass * self.g
        return weight * (self.coin.r - weight / (2 * self.foundation.k))

    # -- conversions ----------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The nested plain-value form (as in a preset file, a store's or a recording's
        attributes): y0 resolved, the method by name, every real quantity a float (k=400 and
        k=400.0 are one scene, and must give one store digest)."""
        d = asdict(self)
        d["initial"]["y0"] = self.y0
        d["integration"]["method"] = self.integration.method.label
        d["g"] = float(d["g"])
        for group, names in REAL_FIELDS.items():
            for name in names:
                if d[group][name] is not None:
                    d[group][name] = float(d[group][name])
        if not self.foundation.mu:  # the paper's model: no friction, and nothing of it recorded
            for name in FRICTION_FIELDS:
                del d["foundation"][name]
        return d

    def with_overrides(self, **overrides) -> Scene:
        """Return a copy with flat overrides such as ``mass=...``, ``vy=...``, ``method=...``.
        An initial condition may be given as text (:mod:`coincli.quantities`: ``phi0="pi/2"``,
        ``y0="2r"``, a multiple of the half diagonal of the coin with its overrides).

        None values are ignored, so CLI options that were not given leave the preset alone.
        """
        groups = {"coin": self.coin, "foundation": self.foundation, "initial": self.initial,
                  "integration": self.integration}
        changes: dict[str, dict] = {name: {} for name in groups}
        top: dict = {}
        for key, value in overrides.items():
            if value is None:
                continue
            if key == "g":
                top["g"] = value
                continue
            for name, obj in groups.items():
                if key in {f.name for f in fields(obj)}:
                    changes[name][key] = value
                    break
            else:
                known = ", ".join(["g", *(f.name for obj in groups.values()
                                          for f in fields(obj))])
                raise ParameterError(f"unknown parameter '{key}'; known: {known}")
        written = {key: value for key, value in changes["initial"].items()
                   if not isinstance(value, numbers.Real)}
        if written:  # text or a Quantity: in SI units, for the coin as overridden
            from .quantities import parse_quantity

            coin = replace(self.coin, **changes["coin"])
            for key, value in written.items():
                quantity = parse_quantity(key, value)
                changes["initial"][key] = quantity.resolve(coin.r) if quantity.per_r \
                    else quantity.value
        new = {name: replace(obj, **changes[name]) for name, obj in groups.items()}
        return replace(self, **new, **top)


# The real quantities of each group of a scene (the others: a method, whole numbers, flags).
REAL_FIELDS = {
    "coin": ("diameter", "thickness", "mass", "inertia"),
    "foundation": ("k", "c", "mu", "slip_velocity"),
    "initial": ("x0", "y0", "phi0", "vx", "vy", "vphi"),
    "integration": ("dt", "rtol", "t_end"),
}

# What a scene records of friction only where there is friction (mu > 0): a scene without it is
# the paper's, and so is what it records (a store written before friction reads as mu = 0).
FRICTION_FIELDS = ("mu", "slip_velocity")

FLAT_KEYS = {
    "coin": [f.name for f in fields(Coin)],
    "foundation": [f.name for f in fields(Foundation)],
    "initial": [f.name for f in fields(InitialState)],
    "integration": [f.name for f in fields(Integration)],
}
# Every flat name Scene.with_overrides takes.
OVERRIDE_KEYS = ("g", *(name for names in FLAT_KEYS.values() for name in names))


def scene_from_dict(data: dict) -> Scene:
    """Build a scene from the nested dict form (as in a preset file or a store's attributes)."""
    known = {"coin", "foundation", "initial", "integration", "g", "name", "description"}
    unknown = set(data) - known
    if unknown:
        raise ParameterError(f"unknown section(s) {sorted(unknown)}; expected {sorted(known)}")
    kwargs: dict = {}
    for section, cls in (("coin", Coin), ("foundation", Foundation), ("initial", InitialState),
                         ("integration", Integration)):
        values = data.get(section, {})
        if not isinstance(values, dict):
            raise ParameterError(f"[{section}] must be a table of values")
        allowed = {f.name for f in fields(cls)}
        bad = set(values) - allowed
        if bad:
            raise ParameterError(f"unknown key(s) {sorted(bad)} in [{section}]; "
                                 f"allowed: {', '.join(sorted(allowed))}")
        kwargs[section] = cls(**values)
    if "g" in data:
        kwargs["g"] = data["g"]
    return Scene(**kwargs)


def check_number(name: str, value, positive: bool = False, nonnegative: bool = False) -> None:
    """ParameterError (one line, naming ``name``) unless ``value`` is a finite real number
    (numpy's too), and positive or not negative if asked."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ParameterError(f"{name} must be a number, got {shown(value)}")
    if not math.isfinite(value):
        raise ParameterError(f"{name} must be finite, got {value}")
    if positive and value <= 0:
        raise ParameterError(f"{name} must be positive, got {value}")
    if nonnegative and value < 0:
        raise ParameterError(f"{name} must not be negative, got {value}")


MU_MAX = 10.0  # the largest friction coefficient taken (rubber on dry concrete: about 1)


def check_friction(mu, slip_velocity) -> None:
    """ParameterError (one line, naming the parameter) unless ``mu`` is a friction coefficient
    from 0 (none: the paper's model) to MU_MAX and ``slip_velocity`` a speed above 0 (m/s)."""
    for name, value in (("mu", mu), ("slip_velocity", slip_velocity)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ParameterError(f"{name} must be a number, got {shown(value)}",
                                 parameters=(name,))
        if not math.isfinite(value):
            raise ParameterError(f"{name} must be finite, got {value}", parameters=(name,))
    if not 0 <= mu <= MU_MAX:
        raise ParameterError(f"mu must be a friction coefficient from 0 (none: the paper's "
                             f"model) to {MU_MAX:g}, got {mu:g}", parameters=("mu",))
    if slip_velocity <= 0:
        raise ParameterError(f"slip_velocity must be a speed above 0 m/s (the regularization "
                             f"of Coulomb friction, default 1e-3), got {slip_velocity:g}",
                             parameters=("slip_velocity",))


DEEPEST_FORCE = 100.0  # a start deeper than where the spring force is this many weights is refused


def penetration(scene: Scene, y0: float | None = None, phi0: float | None = None) -> float:
    """How deep (m) the lowest corner of the initial pose sits in the foundation (0 above it)."""
    y0 = scene.y0 if y0 is None else y0
    phi0 = scene.initial.phi0 if phi0 is None else phi0
    reach = scene.coin.r_d * abs(math.sin(phi0)) + scene.coin.r_t * abs(math.cos(phi0))
    return max(0.0, reach - y0)


def deepest_start(scene: Scene) -> float:
    """The deepest a corner may start in the foundation: where its spring pushes with
    DEEPEST_FORCE times the coin's weight (0.3 mm for the paper's coin). Deeper, the throw is
    not a throw: the coin would be fired out of the ground."""
    return DEEPEST_FORCE * scene.coin.mass * scene.g / scene.foundation.k


def check_start(scene: Scene, y0: float | None = None, phi0: float | None = None) -> None:
    """Refuse an initial pose deeper in the foundation than deepest_start (one line)."""
    depth = penetration(scene, y0, phi0)
    limit = deepest_start(scene)
    if depth > limit:
        y0 = scene.y0 if y0 is None else y0
        phi0 = scene.initial.phi0 if phi0 is None else phi0
        raise ParameterError(
            f"y0 = {y0:g} m, phi0 = {phi0:g} rad puts a corner {depth * 1e3:.4g} mm deep in the "
            f"foundation; at most {limit * 1e3:.3g} mm (where its spring force is "
            f"{DEEPEST_FORCE:g} times the coin's weight)")


def require_scene(scene) -> Scene:
    """TypeError naming the argument unless ``scene`` is a Scene (a preset's name is not)."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a coincli.Scene, e.g. coincli.load_preset('paper'), "
                        f"got {type(scene).__name__} {scene!r:.40}")
    return scene


def check_computable(scene: Scene) -> None:
    """Refuse, in one line, a coin whose numbers the model cannot form in floating point: a
    thickness whose (t/2)^2 is below the smallest float (eqs. 11 and 13 divide by it), or
    sizes, masses or a stiffness so large that the stiffest contact mode 2 k (d/2)^2 / I, the
    weight's moment m g r, the stiffness m g r / (t/2)^2 or I + m r^2 overflows."""
    c, k = scene.coin, scene.foundation.k
    r_d, r_t = c.diameter / 2, c.thickness / 2
    if r_t * r_t == 0:
        raise ParameterError(f"thickness {c.thickness:g} m is too thin to compute with: "
                             "(t/2)^2 is below the smallest float", parameters=("thickness",))
    r = math.hypot(r_d, r_t)
    for what, value in (("stiffest contact mode", 2 * k * r_d * r_d / c.inertia),
                        ("weight's moment", c.mass * scene.g * r),
                        ("stiffness of eq. (11)", c.mass * scene.g * r / (r_t * r_t)),
                        ("inertia about a corner", c.inertia + c.mass * r * r)):
        if not math.isfinite(value):  # the message names the values in the command's words
            raise ParameterError(
                f"this coin's {what} overflows (diameter {c.diameter:g} m, thickness "
                f"{c.thickness:g} m, mass {c.mass:g} kg, inertia {c.inertia:g} kg m^2, k "
                f"{k:g} N/m, g {scene.g:g} m/s^2): past what the model computes with; give "
                "values nearer a real coin's",
                parameters=("diameter", "thickness", "mass", "inertia", "k", "g"))


def validate(scene: Scene) -> Scene:
    """Raise ParameterError with a one-line message if a value is unusable; return the scene."""
    require_scene(scene)
    c, f, s, i = scene.coin, scene.foundation, scene.initial, scene.integration
    for name in ("diameter", "thickness", "mass", "inertia"):
        check_number(name, getattr(c, name), positive=True)
    if c.thickness > c.diameter:
        # lying and standing, phi_cr >= 45 deg and the wells of NOTES.md assume a coin no
        # thicker than wide; a square (t = d, phi_cr = 45 deg) is fine: its wells are all equal
        raise ParameterError(f"thickness ({c.thickness:g} m) must be smaller than the diameter "
                             f"({c.diameter:g} m), or equal to it (a square section)")
    check_number("k", f.k, positive=True)
    check_number("c", f.c, nonnegative=True)
    check_friction(f.mu, f.slip_velocity)
    check_number("g", scene.g, positive=True)  # without gravity no coin ever comes to rest
    check_computable(scene)
    for name in ("x0", "phi0", "vx", "vy", "vphi"):
        check_number(name, getattr(s, name))
    if s.y0 is not None:
        check_number("y0", s.y0)
    check_start(scene)
    check_number("dt", i.dt, positive=True)
    check_number("rtol", i.rtol, positive=True)
    if i.t_end is not None:
        check_number("t_end", i.t_end, positive=True)
    elif f.c == 0:
        raise ParameterError("an undamped foundation (c = 0) never decides a throw: give t_end, "
                             "a fixed horizon", parameters=("c", "t_end"))
    if not 1e-14 <= i.rtol < 1e-1:
        # below ~1e-14 the steps shrink into rounding noise and the run cannot proceed
        raise ParameterError(f"rtol must be between 1e-14 and 0.1, got {i.rtol:g}")
    if i.t_end is not None and i.t_end / i.dt > 1e12:
        raise ParameterError(f"t_end / dt is {i.t_end / i.dt:.3g} steps; at most 1e12",
                             parameters=("t_end", "dt"))
    if i.max_steps is not None and (isinstance(i.max_steps, bool)
                                    or not isinstance(i.max_steps, int) or i.max_steps < 1):
        raise ParameterError(f"max_steps must be a whole number of at least 1, got "
                             f"{i.max_steps!r}")
    for name in ("stop_on_settle", "verify"):
        if not isinstance(getattr(i, name), bool):
            raise ParameterError(f"{name} must be true or false, got {getattr(i, name)!r}")
    return scene


class RunSettings(NamedTuple):
    """How a kernel integrates one trajectory."""

    method: int  # a Method value
    dt: float  # s, the step of a fixed-step method, the first step of an adaptive one
    rtol: float  # relative tolerance of an adaptive method
    t_end: float  # s, a fixed horizon; infinite: until decided, within the cap (run_horizon)
    stop_on_settle: bool  # stop as soon as the outcome is certain
    max_steps: int  # the step budget (closed-form flights count their iterations)
    sample_dt: float  # s between recorded samples (0: record none)


def state_array(scene: Scene):
    """The initial state as a float64 array (x, y, phi, vx, vy, vphi)."""
    import numpy as np  # here only: the command line reads parameters without numpy

    s = scene.initial
    return np.array([s.x0, scene.y0, s.phi0, s.vx, s.vy, s.vphi], dtype=np.float64)
