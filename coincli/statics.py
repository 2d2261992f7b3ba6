"""Static states and their stability (section 3 of the paper, eqs. 7-13), plus the exact energy
threshold E_crit that certifies a final state.

The paper's elastic energies (eq. 10) count the centroid's height only; we reproduce them as
printed, with eq. (13)'s denominator fixed to 2 (r - r_d) (NOTES.md). E_crit adds the elastic
energy stored in the foundation and is what the integrators use to stop.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from .params import Scene


@dataclass(frozen=True)
class EnergyLevels:
    v_max: float  # J, balancing on a corner (phi = phi_cr)
    v_min1: float  # J, lying (phi = 0)
    v_min2: float  # J, standing (phi = pi/2)

    @property
    def to_destabilise_lying(self) -> float:
        return self.v_max - self.v_min1

    @property
    def to_destabilise_standing(self) -> float:
        return self.v_max - self.v_min2

    @property
    def ratio(self) -> float:
        """How many times more energy tips a lying coin than a standing one (eqs. 9, 12)."""
        standing = self.to_destabilise_standing
        return self.to_destabilise_lying / standing if standing > 0 else math.inf


@dataclass(frozen=True)
class StabilityReport:
    phi_cr: float
    rigid: EnergyLevels
    elastic: EnergyLevels
    k: float
    k_min: float
    k_cr: float
    e_crit: float
    lying_static: bool
    standing_static: bool  # by the paper's criterion, k > k_cr
    single_corner_contact: bool
    standing_well_depth: float  # J, E_crit minus the exact resting energy of a standing coin
    k_stand_exact: float  # N/m, the stiffness where that depth vanishes (k_cr / 2)
    k_rock: float  # N/m, below it a standing coin is no minimum at all: m g r_d / (2 r_t^2)

    def to_dict(self) -> dict:
        out = asdict(self)
        for name in ("rigid", "elastic"):
            levels: EnergyLevels = getattr(self, name)
            out[name].update(to_destabilise_lying=levels.to_destabilise_lying,
                             to_destabilise_standing=levels.to_destabilise_standing,
                             ratio=levels.ratio)
        return out


def analyse(scene: Scene) -> StabilityReport:
    coin = scene.coin
    weight = coin.mass * scene.g
    k = scene.foundation.k
    r, r_d, r_t = coin.r, coin.r_d, coin.r_t
    rigid = EnergyLevels(v_max=weight * r, v_min1=weight * r_t, v_min2=weight * r_d)  # eq. 8
    sink = weight / (2 * k)  # settlement of a coin resting on two corners
    elastic = EnergyLevels(v_max=weight * (r - weight / k),  # eq. 10: centroid height only
                           v_min1=weight * (r_t - sink), v_min2=weight * (r_d - sink))
    k_min = weight * r / (2 * r_t**2)  # eq. 11
    k_cr = weight / (2 * (r - r_d))  # eq. 13 with the denominator's sign fixed
    # Exact: a standing coin rests on two corners (stiffness 2k), energy m g r_d - (m g)^2 / 4k
    # with the springs' energy counted. It is a well only while that is below E_crit.
    standing_rest = weight * r_d - weight**2 / (4 * k)
    return StabilityReport(
        phi_cr=coin.phi_cr, rigid=rigid, elastic=elastic, k=k, k_min=k_min, k_cr=k_cr,
        e_crit=scene.e_crit, lying_static=True, standing_static=k > k_cr,
        single_corner_contact=k >= k_min, standing_well_depth=scene.e_crit - standing_rest,
        k_stand_exact=weight / (4 * (r - r_d)), k_rock=weight * r_d / (2 * r_t**2))
