"""The registry of integration methods: one entry per method, the one list of them. What a method
is (adaptive or fixed step, its order), which driver the kernels dispatch it to
(:func:`coincli.integrators.batch.integrate`, through :data:`DRIVER_OF`), whether it flies in
closed form between contacts, what the verification ladder climbs on past its first rung, its
step budget and its colour in the charts all come from here; a method missing an entry fails
the tests (tests/test_integrators.py).

Each fixed-step method declares its stable step for the current parameters, predicted from the
stiffest contact mode (a lying coin rocking on two corners, omega = sqrt(2 k r_d^2 / I), with its
damping ratio): the largest h for which the method's one-step map of that damped oscillator has
spectral radius <= 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..enums import Method
from ..models import stick_rate, stiffest_frequency
from ..params import Integration, ParameterError, RunSettings, Scene


def _map_symplectic_euler(h: float, omega: float, zeta: float) -> np.ndarray:
    # on (x, v): v' = v + h(-w^2 x - 2 z w v), x' = x + h v'
    a = 1.0 - 2.0 * zeta * omega * h
    b = -h * omega**2
    return np.array([[1.0 + h * b, h * a], [b, a]])


def _map_verlet(h: float, omega: float, zeta: float) -> np.ndarray:
    # first half kick implicit in the damping, second explicit, as in step_verlet
    cols = []
    for x, v in ((1.0, 0.0), (0.0, 1.0)):
        v = (v - 0.5 * h * omega**2 * x) / (1.0 + zeta * omega * h)
        x = x + h * v
        v = v + 0.5 * h * (-omega**2 * x - 2.0 * zeta * omega * v)
        cols.append((x, v))
    return np.array(cols).T


def _map_rk4(h: float, omega: float, zeta: float) -> np.ndarray:
    a = np.array([[0.0, 1.0], [-omega**2, -2.0 * zeta * omega]]) * h
    term = np.eye(2)
    total = np.eye(2)
    for n in range(1, 5):
        term = term @ a / n
        total = total + term
    return total


# where |1 + z + z^2/2 + z^3/6 + z^4/24| = 1 on the negative real axis
RK4_DECAY_LIMIT = 2.785293563405282


def _stable_limit(step_map, omega: float, zeta: float) -> float:
    """Largest h with spectral radius <= 1 (scan up to 10/omega, then bisect the first failure)."""
    def stable(h: float) -> bool:
        return max(abs(np.linalg.eigvals(step_map(h, omega, zeta)))) <= 1.0 + 1e-12

    lo = 0.0
    h = 0.01 / omega
    while h < 10.0 / omega and stable(h):
        lo, h = h, h * 1.05
    hi = h
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


# The drivers the kernels dispatch a method to (coincli.integrators.batch.integrate): the
# fixed-step driver, and the adaptive driver with each Runge-Kutta pair (coincli.integrators.pairs)
FIXED, DOPRI5_PAIR, DOP853_PAIR, DOPRI5_RODAS_PAIR, DOP853_RODAS_PAIR = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class MethodInfo:
    method: Method
    order: int
    adaptive: bool
    symplectic: bool
    summary: str
    colour: str  # in the charts (matplotlib's tab10)
    driver: int = FIXED  # FIXED, or the pair of the adaptive driver (DOPRI5_PAIR, ...)
    closed_form_flight: bool = False  # flies in closed form between contacts (adaptive only)
    # the verification ladder past its first rung: on that method, starting that many times
    # below the first rung's rtol (None: on itself, a decade below)
    upper_rungs: tuple[Method, float] | None = None
    # the method a stiff model's ladder climbs on in its place (its switching pair: the same
    # explicit pair where the law is not stiff, Rodas5P where it is)
    stiff_variant: Method | None = None
    step_map: object = None  # one-step map of the damped oscillator, fixed-step methods only
    # h rate at which the step stops being stable on a decay v' = -rate v taken explicitly (as
    # every fixed-step method takes friction): the end of its stability interval on the
    # negative real axis (2 for Euler's kick; Verlet's two explicit half kicks, (1 - h rate /
    # 2)^2, 4; RK4's polynomial, 2.785)
    decay_limit: float = math.inf

    @property
    def name(self) -> str:
        return self.method.label

    def stable_step(self, scene: Scene) -> float | None:
        """Predicted largest stable step (s), or None for an adaptive method: on the damped
        rocking mode, and on the model's decay mode at rest where it has one (friction's
        stick, :func:`coincli.models.stick_rate`)."""
        if self.step_map is None:
            return None
        omega, zeta = stiffest_frequency(scene)
        limit = _stable_limit(self.step_map, omega, zeta)
        rate = stick_rate(scene)
        return min(limit, self.decay_limit / rate) if rate > 0 else limit


METHODS: dict[Method, MethodInfo] = {
    m.method: m
    for m in (
        MethodInfo(Method.SYMPLECTIC_EULER, 1, False, True,
                   "the paper's scheme: kick with the old force, then drift", "#d62728",
                   step_map=_map_symplectic_euler, decay_limit=2.0),
        MethodInfo(Method.VERLET, 2, False, True,
                   "Stormer-Verlet (Lobatto IIIA-IIIB): first half kick implicit in the damping",
                   "#ff7f0e", step_map=_map_verlet, decay_limit=4.0),
        MethodInfo(Method.RK4, 4, False, False,
                   "classical Runge-Kutta, 4 force evaluations a step", "#2ca02c",
                   step_map=_map_rk4, decay_limit=RK4_DECAY_LIMIT),
        MethodInfo(Method.DOPRI5, 5, True, False,
                   "Dormand-Prince 5(4) with error control; lands on the contact onsets and "
                   "lift-offs it sees (flight integrated: a dip under ~3 um can hide in a step)",
                   "#1f77b4", DOPRI5_PAIR),
        MethodInfo(Method.EVENT, 5, True, False,
                   "dopri5 in contact, closed-form flight between contacts, stops once "
                   "the outcome is decided (E < E_crit)", "#9467bd", DOPRI5_PAIR, True,
                   (Method.EVENT_DOP853, 100.0), Method.EVENT_RODAS),
        MethodInfo(Method.EVENT_DOP853, 8, True, False,
                   "event with Hairer's DOP853 in contact (12 stages, 7th-order dense output "
                   "from 3 more): fewer steps from rtol 1e-7 down; the verified ladder's upper "
                   "rungs", "#8c564b", DOP853_PAIR, True, None, Method.EVENT_DOP853_RODAS),
        MethodInfo(Method.EVENT_RODAS, 5, True, False,
                   "event where the law is stiff (friction that sticks) takes a Rodas5P step "
                   "(Rosenbrock, order 5, the analytic Jacobian); a friction scene's event "
                   "method", "#e377c2", DOPRI5_RODAS_PAIR, True),
        MethodInfo(Method.EVENT_DOP853_RODAS, 8, True, False,
                   "event_dop853 where the law is stiff takes a Rodas5P step", "#7f7f7f",
                   DOP853_RODAS_PAIR, True),
    )
}


# What the kernels read of the registry, indexed by a method's value (compile-time constants)
DRIVER_OF = tuple(METHODS[m].driver for m in sorted(Method, key=int))
CLOSED_FORM_FLIGHT = tuple(METHODS[m].closed_form_flight for m in sorted(Method, key=int))

ADAPTIVE_MAX_STEPS = 1_000_000
FIXED_MAX_STEPS = 100_000_000  # a fixed-step run without a horizon (100 s at dt = 1e-6 s)


def step_budget(integration: Integration) -> int:
    """The run's step budget: ``max_steps`` if given, else the method's default."""
    if integration.max_steps is not None:
        return int(integration.max_steps)
    if METHODS[integration.method].adaptive:
        return ADAPTIVE_MAX_STEPS
    if integration.t_end is None:
        return FIXED_MAX_STEPS
    return int(math.ceil(integration.t_end / integration.dt - 1e-9))


def run_settings(integration: Integration, sample_dt: float = 0.0) -> RunSettings:
    """What a kernel takes of an integration's settings."""
    return RunSettings(method=int(integration.method), dt=float(integration.dt),
                       rtol=float(integration.rtol),
                       t_end=math.inf if integration.t_end is None else float(integration.t_end),
                       stop_on_settle=bool(integration.stop_on_settle),
                       max_steps=step_budget(integration), sample_dt=float(sample_dt))


def info(method: Method | str) -> MethodInfo:
    """The registry entry of a method (by member or name); ParameterError if unknown."""
    try:
        return METHODS[Method.parse(method)]
    except ValueError as exc:
        raise ParameterError(str(exc)) from None


def setting_text(method: Method, dt: float, rtol: float) -> str:
    """What sets a run's accuracy, as a user reads it: ``rtol = 1e-06`` for an adaptive
    method, ``dt = 1e-06 s`` for a fixed step."""
    return f"rtol = {rtol:g}" if METHODS[method].adaptive else f"dt = {dt:g} s"


def _binding_mode(scene: Scene, method: MethodInfo, limit: float) -> str:
    """The mode that sets a fixed step's limit, as a refusal says it."""
    rate = stick_rate(scene)
    if rate > 0 and limit < _stable_limit(method.step_map, *stiffest_frequency(scene)):
        return f"friction's stick at rest, rate {rate:.4g} /s"
    return f"the rocking frequency {stiffest_frequency(scene)[0]:.4g} rad/s"


def check_step(scene: Scene, force: bool = False) -> MethodInfo:
    """Return the scene's method; refuse a fixed step beyond its stable step unless forced."""
    method = info(scene.integration.method)
    limit = method.stable_step(scene)
    if limit is not None and scene.integration.dt > limit and not force:
        raise ParameterError(
            f"--dt {scene.integration.dt:g} s is beyond the stable step of {method.name} for "
            f"these parameters ({limit:.3g} s, from {_binding_mode(scene, method, limit)}); "
            "use a smaller --dt or --force")
    if (method.adaptive and scene.fixed_horizon
            and scene.integration.dt >= scene.integration.t_end):
        raise ParameterError(f"--t-end {scene.integration.t_end:g} s is not longer than the "
                             f"first step (--dt {scene.integration.dt:g} s): give a longer "
                             "--t-end (or a smaller --dt)")
    return method


__all__ = ["ADAPTIVE_MAX_STEPS", "CLOSED_FORM_FLIGHT", "DOP853_PAIR", "DOP853_RODAS_PAIR",
           "DOPRI5_PAIR", "DOPRI5_RODAS_PAIR",
           "DRIVER_OF", "FIXED", "FIXED_MAX_STEPS", "METHODS", "MethodInfo", "check_step", "info",
           "run_settings", "setting_text", "step_budget"]
