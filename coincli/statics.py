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

    def __repr__(self) -> str:  # a small table in mJ, as `coin stability` prints it
        rows = [("(energies in mJ)", "rigid", "elastic"), *energy_rows(self)]
        wide = [max(len(row[i]) for row in rows) for i in range(3)]
        lines = ["StabilityReport"]
        lines += [f"  {a:<{wide[0]}}  {b:>{wide[1]}}  {c:>{wide[2]}}" for a, b, c in rows]
        critical = critical_rows(self)
        name_width = max(len(name) for name, _, _ in critical)
        lines += [f"  {name:<{name_width}}  {value}" for name, value, _ in critical]
        states = "lying" + (", standing" if self.standing_static else "")
        lines.append(f"  static states: {states}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        out = asdict(self)
        for name in ("rigid", "elastic"):
            levels: EnergyLevels = getattr(self, name)
            out[name].update(to_destabilise_lying=levels.to_destabilise_lying,
                             to_destabilise_standing=levels.to_destabilise_standing,
                             ratio=levels.ratio)
        return out


MJ = 1e3  # joules -> millijoules, the unit the report is read in
ENERGY_ROWS = (  # (label, EnergyLevels attribute)
    ("V_max  (on a corner, phi_cr)", "v_max"),
    ("V_min1 (lying, phi = 0)", "v_min1"),
    ("V_min2 (standing, phi = pi/2)", "v_min2"),
    ("to tip a lying coin  V_max - V_min1", "to_destabilise_lying"),
    ("to tip a standing coin  V_max - V_min2", "to_destabilise_standing"),
)


def energy_rows(report: StabilityReport) -> list[tuple[str, str, str]]:
    """The static energy table as text, in mJ: (label, rigid, elastic) rows, the ratio last."""
    rows = [(label, f"{getattr(report.rigid, attr) * MJ:.6g}",
             f"{getattr(report.elastic, attr) * MJ:.6g}") for label, attr in ENERGY_ROWS]
    elastic = report.elastic.ratio
    rows.append(("ratio (eqs. 9, 12)", f"{report.rigid.ratio:.1f}",
                 f"{elastic:.1f}" if math.isfinite(elastic) and elastic > 0
                 else "none (k <= k_cr)"))
    return rows


def critical_rows(report: StabilityReport) -> list[tuple[str, str, str]]:
    """The critical values as text: (name, value with its unit, meaning) rows."""
    return [
        ("phi_cr", f"{math.degrees(report.phi_cr):.3f} deg",
         "the diagonal is vertical: the coin balances on a corner"),
        ("k", f"{report.k:.6g} N/m", "this foundation"),
        ("k_min (eq. 11)", f"{report.k_min:.1f} N/m",
         "above it a coin on phi_cr rests on one corner only"),
        ("k_cr (eq. 13)", f"{report.k_cr:.2f} N/m", "above it a standing coin can be at rest"),
        ("E_crit", f"{report.e_crit * MJ:.6g} mJ",
         "m g (r - m g / 2k): below it the count of quarter turns is final"),
        ("standing well", f"{report.standing_well_depth * MJ:.4g} mJ",
         "E_crit minus a standing coin's resting energy, springs counted "
         "(exact; > 0 for k > k_cr/2)"),
    ]


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
