"""The paper's cross-section: a rectangle of diameter d and thickness t, its four corners, its
potential wells and the label they give (docs/model.md derives each).

Corner i sits at body coordinates p_i = (SX[i] r_d, SY[i] r_t); its offset from the centroid is
d_i = R(phi) p_i and its velocity v_i = v + vphi z x d_i = (vx - vphi d_yi, vy + vphi d_xi).
The wells are those of NOTES.md: once the total energy is below E_crit, the count of quarter
turns is the index j of the well that holds phi, |phi - j pi/2| < phi_cr for even j (lying),
|phi - j pi/2| < pi/2 - phi_cr for odd j (standing), phi_cr = arctan(r_d / r_t).

These are the seam's geometry and label (:mod:`.interface`) for every model of a rectangular
coin: kernels on plain floats and the model's parameter tuple ``p`` (its fields ``r_d``,
``r_t``, ``phi_cr``), which apply as plain Python to numpy arrays too.
"""

from __future__ import annotations

import math

from ..jit import kernel

CORNERS = 4
# Body-frame signs of the corners: 0 = (+r_d, -r_t), 1 = (-r_d, -r_t), 2 = (-r_d, +r_t),
# 3 = (+r_d, +r_t). With phi = 0 corners 0 and 1 are the lower ones.
SX = (1.0, -1.0, -1.0, 1.0)
SY = (-1.0, -1.0, 1.0, 1.0)


@kernel(inline=True)
def corner_offset(p, i, c, s):
    """Offset d_i = R(phi) p_i of corner i from the centroid, given c = cos phi, s = sin phi."""
    px = SX[i] * p.r_d
    py = SY[i] * p.r_t
    return px * c - py * s, px * s + py * c


@kernel
def corner_heights(p, y, c, s):
    """Heights y_i = y + d_yi of the four corners (negative = penetrating)."""
    return (y + corner_offset(p, 0, c, s)[1], y + corner_offset(p, 1, c, s)[1],
            y + corner_offset(p, 2, c, s)[1], y + corner_offset(p, 3, c, s)[1])


@kernel
def corner_rates(p, vy, vphi, c, s):
    """Vertical speeds vy + vphi d_xi of the four corners (c, s: trig of the angle)."""
    return (vy + vphi * corner_offset(p, 0, c, s)[0], vy + vphi * corner_offset(p, 1, c, s)[0],
            vy + vphi * corner_offset(p, 2, c, s)[0], vy + vphi * corner_offset(p, 3, c, s)[0])


@kernel
def below(heights):
    """Bit mask of the corners whose height is negative (bit i set = corner i penetrates)."""
    mask = 0
    for i in range(CORNERS):
        if heights[i] < 0.0:
            mask |= 1 << i
    return mask


@kernel
def contact_mask(p, y, phi):
    """Bit mask of the corners below the surface (bit i set = corner i penetrates)."""
    return below(corner_heights(p, y, math.cos(phi), math.sin(phi)))


@kernel
def rounded_quarter_turns(phi):
    """The paper's label n = round(2 phi / pi) (ties away from zero)."""
    q = 2.0 * phi / math.pi
    return int(math.floor(q + 0.5)) if q >= 0 else -int(math.floor(-q + 0.5))


@kernel
def well_index(p, phi):
    """Index j of the potential well that holds phi: |phi - j pi/2| < phi_cr for even j (lying),
    |phi - j pi/2| < pi/2 - phi_cr for odd j (standing). Once E < E_crit, j is the final n."""
    j = rounded_quarter_turns(phi)
    if j % 2 == 0:
        return j
    offset = phi - j * (0.5 * math.pi)
    if abs(offset) < 0.5 * math.pi - p.phi_cr:
        return j
    return j + 1 if offset > 0 else j - 1


@kernel
def last_boundary(p, phi_a, phi_b):
    """The last well boundary passed going monotonically from phi_a to phi_b (NaN if none):
    the boundaries between wells are the angles k pi +- phi_cr."""
    if phi_b == phi_a:
        return math.nan
    best = math.nan
    for c in (p.phi_cr, math.pi - p.phi_cr):
        if phi_b > phi_a:
            value = math.floor((phi_b - c) / math.pi) * math.pi + c
            if value > phi_a and not value <= best:
                best = value
        else:
            value = math.ceil((phi_b - c) / math.pi) * math.pi + c
            if value < phi_a and not value >= best:
                best = value
    return best


__all__ = ["CORNERS", "SX", "SY", "below", "contact_mask", "corner_heights", "corner_offset",
           "corner_rates", "last_boundary", "rounded_quarter_turns", "well_index"]
