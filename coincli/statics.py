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
from .version import documentation


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
    k_cr: float  # N/m, the paper's eq. (13) as printed: twice the model's threshold (k_cr_model)
    e_crit: float
    lying_static: bool
    standing_static: bool  # by the paper's criterion, k > k_cr
    single_corner_contact: bool
    standing_well_depth: float  # J, E_crit minus the exact resting energy of a standing coin
    k_stand_exact: float  # N/m, the stiffness where that depth vanishes (k_cr / 2)
    k_rock: float  # N/m, below it a standing coin is no minimum at all: m g r_d / (2 r_t^2)

    @property
    def k_cr_paper(self) -> float:
        """N/m, the paper's printed k_cr (eq. 13): centroid heights only (eq. 10)."""
        return self.k_cr

    @property
    def k_cr_model(self) -> float:
        """N/m, the threshold the model uses, k_cr / 2: above it a standing coin at rest has
        energy below E_crit, springs counted (docs/model.md, section 9)."""
        return self.k_stand_exact

    @property
    def standing_static_model(self) -> bool:
        """Whether a standing coin can be at rest in a well (k > k_cr / 2)."""
        return self.standing_well_depth > 0

    def __repr__(self) -> str:  # a small table in mJ, as `coin stability` prints it
        rows = [("(energies in mJ)", "rigid", "elastic"), *energy_rows(self)]
        wide = [max(len(row[i]) for row in rows) for i in range(3)]
        lines = ["StabilityReport"]
        lines += [f"  {a:<{wide[0]}}  {b:>{wide[1]}}  {c:>{wide[2]}}" for a, b, c in rows]
        critical = critical_rows(self)
        name_width = max(len(name) for name, _, _ in critical)
        lines += [f"  {name:<{name_width}}  {value}" for name, value, _ in critical]
        states = "lying" + (", standing" if self.standing_static else
                            ", standing (k > k_cr / 2; not by the paper's k_cr)"
                            if self.standing_static_model else "")
        lines.append(f"  static states: {states}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        out = asdict(self)
        for name in ("rigid", "elastic"):
            levels: EnergyLevels = getattr(self, name)
            out[name].update(to_destabilise_lying=levels.to_destabilise_lying,
                             to_destabilise_standing=levels.to_destabilise_standing,
                             ratio=levels.ratio)
        out.update(k_cr_paper=self.k_cr_paper, k_cr_model=self.k_cr_model,
                   standing_static_model=self.standing_static_model, k_cr_note=K_CR_NOTE)
        return out


K_CR_SECTION = f"{documentation('model', 'The model')}, section 9"  # where k_cr / 2 is derived
K_CR_NOTE = ("k_cr and k_cr_paper are the paper's eq. (13) as printed (with standing_static, "
             "its criterion k > k_cr): it compares centroid heights only and is twice too "
             "high. k_cr_model = k_cr / 2 is the threshold this model uses: above it a "
             "standing coin at rest has energy below E_crit, springs counted "
             f"(standing_static_model; {K_CR_SECTION})")


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
        ("k_cr (paper, eq. 13)", f"{report.k_cr_paper:.2f} N/m",
         "the paper's threshold for a standing coin at rest: twice too high (it counts "
         "centroid heights only)"),
        ("k_cr / 2 (model)", f"{report.k_cr_model:.2f} N/m",
         f"the model's: above it a standing coin rests below E_crit ({K_CR_SECTION})"),
        ("E_crit", f"{report.e_crit * MJ:.6g} mJ",
         "m g (r - m g / 2k): below it the count of quarter turns is final"),
        ("standing well", f"{report.standing_well_depth * MJ:.4g} mJ",
         "E_crit minus a standing coin's resting energy, springs counted "
         "(exact; > 0 for k > k_cr/2)"),
    ]


POSES = {"lying": 0.0, "standing": math.pi / 2}  # a static state's name: its angle phi


@dataclass(frozen=True)
class Rest:
    """A coin at rest in a static state on the foundation: its two lower corners in contact,
    each spring carrying half the weight (sunk m g / 2k), the centroid at ``y``; ``energy`` is
    m g y plus the springs' energy, ``depth`` the energy it must gain to leave its well,
    E_crit - energy (J; not positive: no state from which a label can be certified there)."""

    pose: str
    phi: float  # rad
    y: float  # m
    energy: float  # J
    depth: float  # J

    @property
    def quarter_turns(self) -> int:
        """The well it rests in: n = 0 lying, 1 standing."""
        return round(2 * self.phi / math.pi)


def rest(scene: Scene, pose: str) -> Rest:
    """The static state ``pose`` ("lying", phi = 0, or "standing", phi = pi/2) of ``scene``: two
    corners at depth s = m g / 2k below the surface (2 k s = m g), so y = h - s with h = r_t
    lying, r_d standing, and energy m g y + 2 (k s^2 / 2) = m g h - (m g)^2 / 4k."""
    if pose not in POSES:
        raise ValueError(f"unknown pose {pose!r}; available: {', '.join(POSES)}")
    coin = scene.coin
    weight = coin.mass * scene.g
    half = coin.r_t if pose == "lying" else coin.r_d  # the centroid's height over the corners
    sink = weight / (2 * scene.foundation.k)
    energy = weight * half - weight * sink / 2
    return Rest(pose=pose, phi=POSES[pose], y=half - sink, energy=energy,
                depth=scene.e_crit - energy)


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
    # r - r_d written as r_t^2 / (r + r_d): the difference of two near-equal lengths of a thin
    # coin cancels to a few digits (t/d = 1e-7) or to zero (t/d = 1e-10: a division by zero)
    above = r_t**2 / (r + r_d)
    k_cr = weight / (2 * above)  # eq. 13 with the denominator's sign fixed
    # Exact: a standing coin rests on two corners (stiffness 2k), energy m g r_d - (m g)^2 / 4k
    # with the springs' energy counted. It is a well only while that is below E_crit.
    standing_rest = rest(scene, "standing").energy
    return StabilityReport(
        phi_cr=coin.phi_cr, rigid=rigid, elastic=elastic, k=k, k_min=k_min, k_cr=k_cr,
        e_crit=scene.e_crit, lying_static=True, standing_static=k > k_cr,
        single_corner_contact=k >= k_min, standing_well_depth=scene.e_crit - standing_rest,
        k_stand_exact=weight / (4 * above), k_rock=weight * r_d / (2 * r_t**2))
