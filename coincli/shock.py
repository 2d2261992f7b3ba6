"""The minimal shock: the smallest instantaneous kick that takes a coin at rest out of its well
(topples a standing coin, turns a lying one over), found with verified labels. Attractors.jl
calls it the minimal fatal shock.

A coin at rest in a static state (:func:`coincli.statics.rest`: lying or standing, on two
corners of the foundation) is given at t = 0 an instantaneous change of one velocity: vphi about
the centroid, vx or vy of the centroid. Its minimal shock of that kind is the smallest |change|
after which it settles in another well (n other than its own), each sign searched. A kick whose
energy is at most the well's depth E_crit - U_rest (the *static kick*) leaves the coin below
E_crit from the start, so in its well: the minimal shock is never below it. The search runs
the static kick and then kicks SCAN_STEP times larger each, up to the kick whose energy is
ENERGY_LIMIT times the depth, and bisects the first bracket it finds (a kick that certainly
stays below, one that certainly leaves above) to PRECISION. A kick whose label is not certain
ends its sign's search there: it is reported, never bisected through.
"""

from __future__ import annotations

import math
import numbers
import time
from dataclasses import asdict, dataclass, field
from enum import StrEnum

import numpy as np

from .enums import Certainty, Status
from .integrators import check_step
from .integrators.batch import NO_LABEL
from .jsonable import jsonable
from .labeller import Labeller
from .params import ParameterError, Scene, validate
from .statics import POSES, Rest, rest
from .values import shown

PRECISION = 1e-4  # the bisection stops when the bracket is this narrow, relative to its top
# Each kick of the scan is this many times the one before. Where the damping is weak the outcome
# is not monotonic in the kick near the threshold (a coin rocks over several times before it
# settles), and a scan in 2 % steps can miss the first window that leaves: on the paper's coin
# with c = 0.05 N s/m, a lying coin's vphi kick is 103.76 rad/s in 2 % steps and 103.34 in 0.1 %.
SCAN_STEP = 1.001
ENERGY_LIMIT = 1000.0  # the scan's last kick carries this many times the well's depth
# A vertical kick has no threshold to find (it keeps the coin's mirror symmetry: _words); its
# scan only checks that, in steps this coarse at least (a lying coin bouncing after a kick of
# 13 m/s on a stiff, lightly damped foundation takes thousands of steps).
VERTICAL_SCAN_STEP = 1.02
SCAN_CHUNK = 64  # kicks of one sign run together (the scan stops at the first chunk that leaves)


class Kick(StrEnum):
    """Which velocity a shock changes: vphi (rad/s, about the centroid), vx or vy (m/s, of
    the centroid)."""

    VPHI = "vphi"
    VX = "vx"
    VY = "vy"

    @property
    def unit(self) -> str:
        return "rad/s" if self is Kick.VPHI else "m/s"

    @property
    def column(self) -> int:
        """Its column in the state vector (x, y, phi, vx, vy, vphi)."""
        return {Kick.VX: 3, Kick.VY: 4, Kick.VPHI: 5}[self]


SIGN_WORDS = {Kick.VPHI: ("counter-clockwise", "clockwise"), Kick.VX: ("right", "left"),
              Kick.VY: ("up, off the foundation", "down, into it")}


@dataclass(frozen=True)
class KickLabel:
    """What one kick gave: its signed size, the count of quarter turns it settled at (None:
    no label), how sure that is, and whether it left its well (None: not certain)."""

    kick: float
    quarter_turns: int | None
    certainty: Certainty
    leaves: bool | None


@dataclass(frozen=True)
class ShockSearch:
    """The search of one sign. ``value``: the smallest |kick| found to take the coin to another
    well (the top of ``bracket``), None if none did up to ``scanned_to`` or the search
    stopped at a kick whose label is not certain (``unsure``). ``bracket``: (the largest |kick|
    known to keep it, ``value``), with ``below`` and ``above`` their labels; ``converged``:
    the bracket is within the precision asked."""

    sign: int  # +1 or -1
    direction: str  # the sign in words: "clockwise", "up, off the foundation", ...
    value: float | None
    bracket: tuple[float, float] | None
    below: KickLabel | None
    above: KickLabel | None
    converged: bool
    unsure: tuple[KickLabel, ...]
    scanned_to: float  # the largest |kick| the scan ran


@dataclass(frozen=True)
class MinimalShock:
    """The minimal shock of one kind for one static state (:func:`minimal_shock`).

    ``value`` (rad/s for vphi, m/s for vx and vy) is the smaller of the two signs' values, the
    smallest kick verified to take the coin to another well, with ``bracket`` (its sign's
    largest kick verified to keep it, and ``value``) and the labels at both ends (``below``,
    ``above``); None with a ``reason`` where no kick does. ``searches`` holds both signs
    (+ then -); ``signs_agree`` says whether their values agree within the precision (the
    mirror symmetry makes them equal for vphi and vx; for vy each sign is a different kick).
    ``static_kick`` is the kick the energy barrier alone asks, sqrt(2 depth / I) or
    sqrt(2 depth / m) with ``depth`` = E_crit - U_rest (springs counted), and ``ratio`` =
    value / static_kick. ``limit``: the scan's largest kick. The cost: ``throws`` initial
    conditions, ``steps`` over all rungs, ``seconds`` of wall time."""

    state: str
    kick: Kick
    unit: str
    value: float | None
    sign: int | None
    bracket: tuple[float, float] | None
    below: KickLabel | None
    above: KickLabel | None
    static_kick: float | None
    ratio: float | None
    signs_agree: bool | None
    reason: str | None
    note: str | None
    rest: Rest
    depth: float  # J
    limit: float | None
    precision: float
    searches: tuple[ShockSearch, ...] = field(default=())
    throws: int = 0
    steps: int = 0
    seconds: float = 0.0

    def __repr__(self) -> str:  # one line in a notebook; everything: to_dict()
        if self.value is None:
            return f"MinimalShock({self.state}, {self.kick}: none, {self.reason})"
        ratio = f", {self.ratio:.3f} x the static {self.static_kick:.5g}" if self.ratio else ""
        return (f"MinimalShock({self.state}, {self.kick} = {self.value:.5g} {self.unit}"
                f"{ratio}, {self.throws} throws, {self.seconds:.2f} s)")

    def to_dict(self) -> dict:
        """Plain JSON values: enums by name, the labels and searches as nested dicts."""
        return jsonable(asdict(self))


def minimal_shock(scene: Scene, state: str = "standing", kick: str = "vphi", *,
                  precision: float = PRECISION, energy_limit: float = ENERGY_LIMIT,
                  scan_step: float = SCAN_STEP, **overrides) -> MinimalShock:
    """The smallest instantaneous change of ``kick`` ("vphi" about the centroid, "vx" or "vy"
    of the centroid) that takes a coin at rest in ``state`` ("standing" or "lying", on the
    scene's foundation) to another well, both signs searched with the scene's integration
    (verified labels by default): a scan from the static kick up in steps of ``scan_step``
    to the kick of ``energy_limit`` times the well's depth, then a bisection to ``precision``
    (relative). The scene's initial state is not used. ``overrides`` change the scene's
    values by the flat names of :meth:`Scene.with_overrides` (``mu=0.3``: with friction at
    the corners), as :func:`coincli.simulate` takes them."""
    from .throw import with_keywords

    scene = with_keywords(scene, overrides, "minimal_shock")
    validate(scene)
    check_step(scene)
    if not isinstance(state, str) or state not in POSES:  # a list is unhashable: no `in`
        raise _not_one_of("state", state, POSES)
    try:
        kind = Kick(kick) if isinstance(kick, str) else None
    except ValueError:
        kind = None
    if kind is None:
        raise _not_one_of("kick", kick, Kick)
    for name, value, low in (("precision", precision, 0.0), ("scan_step", scan_step, 1.0),
                             ("energy_limit", energy_limit, 1.0)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real) \
                or not math.isfinite(value) or value <= low:
            raise ParameterError(f"{name} must be a number above {low:g}, got "
                                 f"{_given(value)}")
    start = time.perf_counter()
    at_rest = rest(scene, state)
    mass = scene.coin.inertia if kind is Kick.VPHI else scene.coin.mass
    common = dict(state=state, kick=kind, unit=kind.unit, rest=at_rest, depth=at_rest.depth,
                  precision=precision)
    if at_rest.depth <= 0:
        below_half_k_cr = " (k <= k_cr / 2)" if state == "standing" else ""
        return MinimalShock(**common, value=None, sign=None, bracket=None, below=None,
                            above=None, static_kick=None, ratio=None, signs_agree=None,
                            limit=None, note=None, reason=(
                                f"no {state} well: the coin at rest has energy "
                                f"{at_rest.energy * 1e3:.6g} mJ, not below E_crit = "
                                f"{scene.e_crit * 1e3:.6g} mJ{below_half_k_cr}, so no label "
                                "from it is certain"))
    static = math.sqrt(2 * at_rest.depth / mass)
    limit = static * math.sqrt(energy_limit)
    if scene.foundation.c == 0:
        undamped = ("without damping (c = 0) no force acts horizontally on the coin: a "
                    "horizontal kick only carries it sideways" if kind is Kick.VX else
                    "without damping (c = 0) the energy is conserved: after a kick above the "
                    "static one the coin stays above E_crit for ever, so no label is certain")
        return MinimalShock(**common, value=None, sign=None, bracket=None, below=None,
                            above=None, static_kick=static, ratio=None, signs_agree=None,
                            limit=None, note=None, reason=undamped)
    runner = _Runner(scene, at_rest, kind)
    # a vertical kick keeps the mirror symmetry: its scan is run, and what it finds reported,
    # but there is no threshold to bisect (see _words)
    vertical = kind is Kick.VY
    searches = _search(runner, static, limit, precision,
                       max(scan_step, VERTICAL_SCAN_STEP) if vertical else scan_step,
                       bisect=not vertical)
    found = [s for s in searches if s.value is not None and not vertical]
    best = min(found, key=lambda s: s.value) if found else None
    agree = None
    if len(found) == 2:
        agree = abs(found[0].value - found[1].value) <= 2 * precision * best.value
    value = best.value if best else None
    note, reason = _words(kind, searches, agree, value, limit, energy_limit)
    return MinimalShock(**common, value=value, sign=best.sign if best else None,
                        bracket=best.bracket if best else None,
                        below=best.below if best else None, above=best.above if best else None,
                        static_kick=static, ratio=value / static if best else None,
                        signs_agree=agree, limit=limit, note=note, reason=reason,
                        searches=searches, throws=runner.throws, steps=runner.steps,
                        seconds=time.perf_counter() - start)


def _given(value) -> str:
    """A value as a refusal quotes it: text in quotes, None or a number as itself, anything
    else with its type (a list ['standing'])."""
    if isinstance(value, str):
        return repr(shown(value))
    if value is None or isinstance(value, numbers.Number):
        return shown(value)
    return f"{type(value).__name__} {shown(value)}"


def _not_one_of(name: str, value, choices) -> ParameterError:
    """The refusal of ``value`` for ``name``, none of ``choices`` (their names); several of
    them in a list or tuple are one call each."""
    several = ("; one a call: call minimal_shock once for each"
               if isinstance(value, list | tuple | set | frozenset) else "")
    return ParameterError(f"{name} must be one of {', '.join(choices)}, got "
                          f"{_given(value)}{several}")


class _Runner:
    """Kicks a coin at rest and labels the outcomes (verified, compiled), counting the cost."""

    def __init__(self, scene: Scene, at_rest: Rest, kind: Kick):
        self.labeller = Labeller.of(scene)
        self.rest = at_rest
        self.kind = kind
        self.throws = 0
        self.steps = 0
        self.labeller.load(self.states([0.0])[0])

    def states(self, kicks) -> np.ndarray:
        states = np.zeros((len(kicks), 6))
        states[:, 1] = self.rest.y
        states[:, 2] = self.rest.phi
        states[:, self.kind.column] = kicks
        return states

    def labels(self, kicks: list[float]) -> list[KickLabel]:
        out = self.labeller.label(self.states(kicks))
        self.throws += len(kicks)
        self.steps += int(out.steps.sum())
        own = self.rest.quarter_turns
        labels = []
        for kick, n, status, certainty in zip(kicks, out.quarter_turns, out.status,
                                              out.certainty, strict=True):
            certainty = Certainty(int(certainty))
            usable = certainty == Certainty.CERTAIN or (
                not self.labeller.verified and Status(int(status)) == Status.SETTLED)
            n = None if n == NO_LABEL else int(n)
            labels.append(KickLabel(float(kick), n, certainty,
                                    (n != own) if usable and n is not None else None))
        return labels


@dataclass
class _Side:
    """One sign's search as it goes."""

    sign: int
    low: KickLabel | None = None  # the largest kick known to keep the coin in its well
    high: KickLabel | None = None  # the smallest kick known to take it out
    unsure: list = field(default_factory=list)
    scanned_to: float = 0.0
    stopped: bool = False  # at a kick whose label is not certain

    def take(self, label: KickLabel) -> bool:
        """Account for one more kick's label (between ``low`` and ``high``); True when this
        sign's walk up the scan ends (a bracket, or a label not certain)."""
        if label.leaves is None:
            self.unsure.append(label)
            self.stopped = True
        elif label.leaves:
            self.high = label
        else:
            self.low = label
        return self.stopped or self.high is not None


def _search(runner: _Runner, static: float, limit: float, precision: float, scan_step: float,
            bisect: bool) -> tuple[ShockSearch, ShockSearch]:
    count = math.floor(math.log(limit / static) / math.log(scan_step) + 1e-9) + 1
    scan = [static * scan_step ** i for i in range(count)]
    if scan[-1] < limit * (1 - 1e-12):
        scan.append(limit)
    sides = [_Side(+1), _Side(-1)]
    for first in range(0, len(scan), SCAN_CHUNK):
        walking = [s for s in sides if not s.stopped and s.high is None]
        if not walking:
            break
        chunk = scan[first:first + SCAN_CHUNK]
        labels = runner.labels([s.sign * k for s in walking for k in chunk])
        for i, side in enumerate(walking):
            for kick, label in zip(chunk, labels[i * len(chunk):(i + 1) * len(chunk)],
                                   strict=True):
                side.scanned_to = kick
                if side.take(label):
                    break
    while bisect:  # bisect the brackets, both signs' midpoints in one batch
        open_ = [s for s in sides if s.high is not None and s.low is not None and not s.stopped
                 and abs(s.high.kick) - abs(s.low.kick) > precision * abs(s.high.kick)]
        if not open_:
            break
        middles = [0.5 * (s.low.kick + s.high.kick) for s in open_]
        for side, label in zip(open_, runner.labels(middles), strict=True):
            side.take(label)
    return tuple(_finished(s, runner.kind, precision) for s in sides)


def _finished(side: _Side, kind: Kick, precision: float) -> ShockSearch:
    high = side.high
    value = abs(high.kick) if high is not None else None
    bracket = (abs(side.low.kick) if side.low else 0.0, value) if high is not None else None
    converged = bracket is not None and bracket[1] - bracket[0] <= precision * bracket[1]
    return ShockSearch(sign=side.sign, direction=SIGN_WORDS[kind][side.sign < 0], value=value,
                       bracket=bracket, below=side.low, above=high, converged=converged,
                       unsure=tuple(side.unsure), scanned_to=side.scanned_to)


def _words(kind: Kick, searches, agree: bool | None, value: float | None, limit: float,
           energy_limit: float) -> tuple[str | None, str | None]:
    """(note, reason): what a reader should know of the result, and why there is no value."""
    unit = kind.unit
    notes = []
    for s in searches:
        if s.unsure:
            first = s.unsure[0]
            notes.append(f"{s.direction}: the label of the kick {abs(first.kick):.6g} {unit} is "
                         f"{first.certainty.label}, where the search stopped")
        elif kind is not Kick.VY and s.value is not None and not s.converged:
            notes.append(f"{s.direction}: the bracket is wider than the precision asked")
    if agree is False:
        plus, minus = searches
        notes.append(f"the two signs disagree: {plus.value:.6g} ({plus.direction}) and "
                     f"{minus.value:.6g} {unit} ({minus.direction})")
    elif value is not None and len([s for s in searches if s.value is not None]) == 1:
        notes.append("only one sign takes the coin out of its well within the scan")
    reason = None
    if kind is Kick.VY:
        reason = ("a vertical kick keeps the mirror symmetry of the rest pose (vx = vphi = 0, "
                  "phi at rest for ever), so in this model no vertical kick tips the coin")
        tipped = [s for s in searches if s.value is not None]
        for s in tipped:
            notes.append(f"{s.direction}: the kick {s.value:.4g} {unit} ended in the well "
                         f"n = {s.above.quarter_turns}: the symmetric bouncing is unstable "
                         "here, and rounding errors grew into rocking")
        if not tipped and not any(s.unsure for s in searches):
            notes.append(f"no vertical kick up to {limit:.4g} {unit} ({energy_limit:g} times "
                         "the barrier's energy), up or down, changed the well")
    elif value is None:
        if any(s.unsure for s in searches):
            top = min(abs(s.unsure[0].kick) for s in searches if s.unsure)
            reason = (f"no kick below {top:.4g} {unit} took the coin out of its well, and from "
                      "there on the labels are not certain")
        else:
            reason = (f"no kick up to {limit:.4g} {unit} (energy {energy_limit:g} times the "
                      "barrier) takes the coin out of its well")
    return ("; ".join(notes) or None), reason


__all__ = ["ENERGY_LIMIT", "Kick", "KickLabel", "MinimalShock", "PRECISION", "SCAN_STEP",
           "ShockSearch", "minimal_shock"]
