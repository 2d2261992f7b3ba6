"""The model seam: the names every integrator, the labeller and the recordings call the model by.

Each is a placeholder (:func:`coincli.jit.placeholder`), not code: a model (a registry entry of
:mod:`coincli.models`, its kernels in modules of its own) gives each name its meaning, and the
kernels compiled for that model (:func:`coincli.jit.kernels`) call the model's functions in
their place, with no call through a pointer: numba sees the model's function as it would a
direct import, and inlines it where it is marked so. A model that lacks a name fails when its
kernels are built, naming what it lacks (tests/test_models.py builds every model).

Kernels of a model call each other through these names too (the friction law reuses the
rectangle's corners through ``corner_offset``), so that a model can replace one part (another
cross-section, another contact law) and keep the rest.

The state is the 6-tuple (x, y, phi, vx, vy, vphi) of :data:`coincli.params.STATE_NAMES`: the
centroid's position, the angle, and their rates. ``p`` is the model's parameter tuple
(:attr:`coincli.models.Model.params`); ``c, s`` the cosine and sine of the angle where a
kernel takes them (the integrators carry them by rotation, :func:`.rotation.rotate`); ``mode``
a bit mask of the corners whose contact force acts (bit i: corner i).
"""

from __future__ import annotations

from ..jit import placeholder

# -- the cross-section ------------------------------------------------------------------------
CORNERS = placeholder("CORNERS", "how many corners the cross-section has (at most 62: masks "
                                 "are 64-bit)")
corner_offset = placeholder("corner_offset", "(p, i, c, s) -> (dx, dy): the offset of corner i "
                                             "from the centroid")
corner_heights = placeholder("corner_heights", "(p, y, c, s) -> the heights of the corners, a "
                                               "CORNERS-tuple (negative: below the surface)")
corner_rates = placeholder("corner_rates", "(p, vy, vphi, c, s) -> the corners' vertical "
                                           "speeds, a CORNERS-tuple")
below = placeholder("below", "(heights) -> the mask of the corners below the surface")
contact_mask = placeholder("contact_mask", "(p, y, phi) -> the mask of the corners below the "
                                           "surface")
# -- the contact law --------------------------------------------------------------------------
FRICTION = placeholder("FRICTION", "whether the law has friction at the corners (True: its "
                                   "stiff drivers are compiled, and a recorded run integrates "
                                   "the work friction does)")
corner_force = placeholder(
    "corner_force", "(p, y, dx, dy, vx, vy, vphi) -> (Fx, Fy): the force on a corner in contact "
                    "at offset (dx, dy) from the centroid at height y, the coin moving at (vx, "
                    "vy, vphi)")
corner_force_gradient = placeholder(
    "corner_force_gradient", "(p, y, dx, dy, vx, vy, vphi) -> (Fx, Fy, dFx, dFy): the force and "
                             "its derivatives along (y, phi, vx, vy, vphi), two 5-tuples (the "
                             "Jacobian of the implicit steps)")
contact_accelerations = placeholder(
    "contact_accelerations", "(p, mode, state, c, s) -> (ax, ay, aphi): gravity and the contact "
                             "forces of the corners in ``mode`` (whatever their height: the "
                             "law extends smoothly beyond the surface)")
accelerations_auto = placeholder(
    "accelerations_auto", "(p, state) -> (ax, ay, aphi), the corners in contact taken from the "
                          "state (below the surface)")
contact_jacobian = placeholder(
    "contact_jacobian", "(p, mode, state, c, s) -> (aq, av): the derivatives of the "
                        "accelerations in the fixed ``mode``, d a / d(y, phi) as a 6-tuple by "
                        "rows and d a / d(vx, vy, vphi) as a 9-tuple by rows")
stiffness = placeholder(
    "stiffness", "(p, mode, state, c, s) -> 1/s: a bound of the law's stiffness beyond the "
                 "contact's spring and damper (friction where a corner sticks; 0 without): "
                 "where it times a step passes an explicit pair's stability, the switching "
                 "pairs step implicitly")
step_limit = placeholder(
    "step_limit", "(p, mode, state, k1, c, s, h) -> the longest step to try from ``state`` "
                  "(k1: its derivative): ``h``, or less where the law turns sharply ahead (a "
                  "corner sliding into a stick)")
sliding = placeholder(
    "sliding", "(p, mode, state, c, s) -> (friction power, sliding load): the power of the "
               "friction forces (W, <= 0) and sum over the corners in ``mode`` of max(0, N_i) "
               "|v_xi| (W per unit friction coefficient: what a friction coefficient mu would "
               "take, mu times it, to first order)")
verlet_half_kick = placeholder(
    "verlet_half_kick", "(p, h2, state) -> (vx, vy, vphi): the velocity after the first half "
                        "kick of Stormer-Verlet, v + h2 a(q, v_half), implicit in what the law "
                        "lets solve exactly (the paper's damping is linear in v)")
contact_forces = placeholder(
    "contact_forces", "(p, state, c, s, i) -> (fx, fy, normal, tangential): corner i's contact "
                      "force (zero above the surface) and its parts: the normal force and the "
                      "tangential force beside the viscous one (what the recordings show)")
# -- energy, wells and the label ----------------------------------------------------------------
energy_with_heights = placeholder(
    "energy_with_heights", "(p, y, vx, vy, vphi, heights) -> the total energy (kinetic + m g y "
                           "+ what the foundation stores), the corner heights known")
energies = placeholder("energies", "(p, state) -> (kinetic, gravitational, elastic)")
total_energy = placeholder("total_energy", "(p, state) -> the total energy")
well_index = placeholder("well_index", "(p, phi) -> the well that holds the angle once the "
                                       "energy is below E_crit: the final count of quarter "
                                       "turns")
last_boundary = placeholder("last_boundary", "(p, phi_a, phi_b) -> the last boundary between "
                                             "wells passed from phi_a to phi_b (NaN if none)")
rounded_quarter_turns = placeholder("rounded_quarter_turns", "(phi) -> the paper's label "
                                                             "round(2 phi / pi)")
run_horizon = placeholder("run_horizon", "(p, t_end, state) -> how long a run may last: t_end, "
                                         "or without one (infinite) the cap of the throw")

__all__ = ["CORNERS", "FRICTION", "accelerations_auto", "below", "contact_accelerations",
           "contact_forces", "contact_jacobian", "contact_mask", "corner_force",
           "corner_force_gradient", "corner_heights", "corner_offset", "corner_rates",
           "energies", "energy_with_heights", "last_boundary", "rounded_quarter_turns",
           "run_horizon", "sliding", "step_limit", "stiffness", "total_energy",
           "verlet_half_kick", "well_index"]
