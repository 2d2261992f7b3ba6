"""The models the kernels integrate, one registry entry each (:data:`MODELS`), and which one a
scene needs (:func:`model_of`).

A model is the seam's meaning (:mod:`.interface`): a cross-section (its corners, its wells and
the label they give) and a contact law (the forces on the corners, the energy the foundation
stores, how long a throw may take), each in kernel modules of its own, and the parameter tuple
its kernels take, made from a scene. The paper's model (:mod:`.rectangle` and :mod:`.paper`) is
the first; another law or another cross-section is a module that gives the names it changes,
and an entry here that names it before the modules it reuses. The integrators, the labeller
and the recordings never name a model: they ask :func:`coincli.jit.kernels` for the set of the
scene's model.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType

from ..jit import FIRST_COMPILE_SECONDS, NUMBA, Placeholder, kernels
from . import friction, interface, paper, rectangle


@dataclass(frozen=True)
class Model:
    """One model: its ``name`` (what a store's method attributes record), its kernel modules
    (the first that gives a seam name gives its meaning), ``params(scene)`` (the kernels'
    parameter tuple), ``parameters`` (the names of the scene's values it reads beyond the
    coin, k, c and g), and what a user reads of it."""

    name: str
    summary: str
    modules: tuple[ModuleType, ...]
    params: Callable
    parameters: tuple[str, ...] = ()
    # stiff beyond the contact's spring and damper: its verification ladder climbs on the
    # switching pairs (coincli.integrators.switching) where a method has them
    stiff: bool = False
    stiffest_frequency: Callable = paper.stiffest_frequency
    stick_rate: Callable = paper.stick_rate  # a decay mode at rest beside the rocking (1/s)
    horizon_rule: Callable = paper.horizon_rule
    # about how long its kernels take to compile the first time (s, docs/performance.md)
    compile_seconds: float = FIRST_COMPILE_SECONDS
    # the (name, value) overrides that make the default scene one of this model (what
    # compiles its kernels)
    example: tuple = ()

    def kernels(self, backend=NUMBA):
        """This model's kernel set for ``backend`` (:func:`coincli.jit.kernels`)."""
        return kernels(self, backend)

    def implementations(self) -> dict:
        """The model's meaning of every name of the seam: from the first of its kernel modules
        that defines the name (so a model extends another by naming its own module first);
        TypeError naming the first name it lacks."""
        found = {}
        for name, value in vars(interface).items():
            if not isinstance(value, Placeholder):
                continue
            for module in self.modules:
                meaning = vars(module).get(name)
                if meaning is not None and not isinstance(meaning, Placeholder):
                    found[name] = meaning
                    break
            else:
                raise TypeError(f"model {self.name} gives no {name}, a name of the seam "
                                "(coincli.models.interface)")
        return found


# the friction model's first compile, s (its set: the paper's law with friction's, and the
# Rodas5P and switching drivers): `Labeller.of(scene with mu > 0).compile_all()` took 56 s
# where the paper's kernels were compiled already (numba's cache shares what the two sets
# have in common) and 158 s (101 s of CPU) on a cold cache, on 2 busy cores
FRICTION_COMPILE_SECONDS = 120

PAPER = Model("paper", "the paper's: a Winkler spring and a viscous damper at each corner of a "
                       "rectangle (eqs. 1-2)", (paper, rectangle), paper.params)
FRICTION_MODEL = Model("friction", "the paper's with regularized Coulomb friction at the corners "
                                   "(mu, slip_velocity)", (friction, paper, rectangle),
                       friction.params, ("mu", "slip_velocity"), stiff=True,
                       stick_rate=friction.stick_rate,
                       compile_seconds=FRICTION_COMPILE_SECONDS, example=(("mu", 0.3),))

MODELS: dict[str, Model] = {m.name: m for m in (PAPER, FRICTION_MODEL)}


def model_of(scene) -> Model:
    """The model ``scene`` needs, and no more: friction's where its foundation has a friction
    coefficient (mu > 0), else the paper's."""
    return FRICTION_MODEL if scene.foundation.mu > 0 else PAPER


def model_params(scene):
    """The kernels' parameter tuple of ``scene`` under its model."""
    return model_of(scene).params(scene)


def scene_horizon(scene) -> float:
    """How long a run of ``scene`` from its initial state may last: its t_end, or without one
    the cap of its model's horizon rule (:func:`coincli.models.paper.run_horizon`)."""
    import math

    s, t_end = scene.initial, scene.integration.t_end
    state = (s.x0, scene.y0, s.phi0, s.vx, s.vy, s.vphi)  # Python floats: an absurd start's
    # energy overflows to inf (an infinite cap) without numpy's overflow warning
    model = model_of(scene)
    return float(model.kernels("python").run_horizon(
        model.params(scene), math.inf if t_end is None else t_end, state))


def horizon_text(scene) -> str:
    """The horizon of ``scene`` as a user reads it: ``t_end = 2 s`` or the cap's rule."""
    if scene.fixed_horizon:
        return f"t_end = {scene.integration.t_end:g} s"
    model = model_of(scene)
    return model.horizon_rule(model.params(scene))


def friction_text(scene) -> str | None:
    """The scene's friction as a user reads it (``mu = 0.3 at the corners, slip velocity 0.001
    m/s``), or None under the paper's frictionless law."""
    foundation = scene.foundation
    if not foundation.mu > 0:
        return None
    return (f"mu = {foundation.mu:g} at the corners, slip velocity "
            f"{foundation.slip_velocity:g} m/s")


def stiffest_frequency(scene) -> tuple[float, float]:
    """(omega, zeta) of the stiffest contact mode of ``scene`` under its model."""
    model = model_of(scene)
    return model.stiffest_frequency(model.params(scene))


def stick_rate(scene) -> float:
    """The rate (1/s) of the stiffest decay mode of ``scene``'s coin at rest beside its
    rocking mode under its model (0: none; friction's stick)."""
    model = model_of(scene)
    return model.stick_rate(model.params(scene))


__all__ = ["FRICTION_MODEL", "MODELS", "Model", "PAPER", "friction_text", "horizon_text",
           "model_of", "model_params", "scene_horizon", "stick_rate", "stiffest_frequency"]
