"""The model's quantities along recorded states, for the recordings and exports of a throw: each
corner's position and height, its contact force and that force's parts, and the energies. Kernels
on the seam (:mod:`.interface`), so that a recording shows whatever model the throw ran."""

from __future__ import annotations

import math

from ..jit import kernel
from .interface import CORNERS, contact_forces, corner_offset, energies


@kernel
def corner_table(p, states, corners):
    """Each corner's position (x, y) at each state (rows of ``states``, N x 6) into ``corners``
    (N x CORNERS x 2)."""
    for row in range(states.shape[0]):
        c = math.cos(states[row, 2])
        s = math.sin(states[row, 2])
        for i in range(CORNERS):
            dx, dy = corner_offset(p, i, c, s)
            corners[row, i, 0] = states[row, 0] + dx
            corners[row, i, 1] = states[row, 1] + dy


@kernel
def force_table(p, states, contact, forces):
    """Each corner's contact force where ``contact`` (N x CORNERS) says it acts, into ``forces``
    (N x CORNERS x 4: F_x, F_y, the normal force, the tangential force beside the damper's;
    zero where it does not act)."""
    for row in range(states.shape[0]):
        st = (states[row, 0], states[row, 1], states[row, 2], states[row, 3], states[row, 4],
              states[row, 5])
        c = math.cos(st[2])
        s = math.sin(st[2])
        for i in range(CORNERS):
            if contact[row, i]:
                fx, fy, normal, tangential = contact_forces(p, st, c, s, i)
            else:
                fx, fy, normal, tangential = 0.0, 0.0, 0.0, 0.0
            forces[row, i, 0] = fx
            forces[row, i, 1] = fy
            forces[row, i, 2] = normal
            forces[row, i, 3] = tangential


@kernel
def energy_table(p, states, out):
    """(kinetic, gravitational, elastic) at each state into ``out`` (N x 3)."""
    for row in range(states.shape[0]):
        kinetic, gravitational, elastic = energies(p, states[row])
        out[row, 0] = kinetic
        out[row, 1] = gravitational
        out[row, 2] = elastic


__all__ = ["corner_table", "energy_table", "force_table"]
