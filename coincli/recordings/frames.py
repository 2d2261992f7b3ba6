"""The frames of a recording, in numpy: a trajectory's display samples merged with its exact
contact events, and everything the scene shows at each (corner positions, penetrations, contact
forces, energies), computed with the model's own formulas."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..models import model_of


@dataclass
class Frames:
    """Everything a recording shows, one row per frame (display samples merged with the exact
    contact events, sorted by time, one row per distinct time; at an event the row holds the
    state just after it)."""

    t: np.ndarray  # (N,) s
    state: np.ndarray  # (N, 6): x, y, phi, vx, vy, vphi
    is_event: np.ndarray  # (N,) bool: the row is the exact state at a contact event
    contact: np.ndarray  # (N, 4) bool: corner i is in the contact set (carries a force)
    corners: np.ndarray  # (N, 4, 2) corner positions, m
    heights: np.ndarray  # (N, 4) corner heights y_i, m (negative = penetrating)
    forces: np.ndarray  # (N, 4, 2) contact force on each corner, N (zero when free)
    kinetic: np.ndarray  # (N,) J
    gravitational: np.ndarray  # (N,) J
    elastic: np.ndarray  # (N,) J
    events: np.ndarray  # (M, 9) the contact events: t, corner, kind, state
    implied: np.ndarray | None = None  # (N,) bool: the resting pose a settled run implies
    normal: np.ndarray | None = None  # (N, 4) normal force on each corner, N
    tangential: np.ndarray | None = None  # (N, 4) tangential force beside the damper's, N

    def __len__(self) -> int:
        return len(self.t)

    def subset(self, rows: np.ndarray) -> Frames:
        """The frames selected by a boolean mask (the contact events unchanged)."""
        fields = {name: getattr(self, name) for name in self.__dataclass_fields__}
        return Frames(**{name: value[rows] if name != "events" and value is not None
                         else value for name, value in fields.items()})

    @property
    def penetration(self) -> np.ndarray:
        """(N, 4) depth below the surface, m (zero above it)."""
        return np.maximum(-self.heights, 0.0)

    @property
    def total(self) -> np.ndarray:
        return self.kinetic + self.gravitational + self.elastic

    @property
    def quarter_turns(self) -> np.ndarray:
        """2 phi / pi, whose rounding is the paper's n."""
        return 2.0 * self.state[:, 2] / math.pi

    @property
    def n(self) -> np.ndarray:
        """The paper's n = round(2 phi / pi), ties away from zero (model.rounded_quarter_turns)."""
        q = self.quarter_turns
        return (np.sign(q) * np.floor(np.abs(q) + 0.5)).astype(np.int64)


def build_frames(trajectory) -> Frames:
    """Merge a trajectory's samples with its contact events and derive the scene's quantities.

    ``trajectory`` must come from ``simulate(scene, sample_dt=..., record_events=True)``. Rows
    that went non-finite (a diverged run) are dropped.
    """
    if trajectory.samples is None:
        raise ValueError("the trajectory has no samples: run simulate() with sample_dt")
    samples = np.asarray(trajectory.samples, dtype=np.float64)
    events = (np.asarray(trajectory.events, dtype=np.float64) if trajectory.events is not None
              else np.empty((0, 9)))
    events = events[np.isfinite(events).all(axis=1)]
    rows = np.concatenate([events[:, [0, 3, 4, 5, 6, 7, 8]], samples])
    is_event = np.concatenate([np.ones(len(events), bool), np.zeros(len(samples), bool)])
    finite = np.isfinite(rows).all(axis=1)
    rows, is_event = rows[finite], is_event[finite]
    # sort by time, an event before a sample at the same time; keep the first row of each time
    order = np.lexsort((~is_event, rows[:, 0]))
    rows, is_event = rows[order], is_event[order]
    keep = np.ones(len(rows), bool)
    keep[1:] = rows[1:, 0] != rows[:-1, 0]
    rows, is_event = rows[keep], is_event[keep]
    scene = trajectory.scene
    model = model_of(scene)
    p, python = model.params(scene), model.kernels("python")
    implied = np.zeros(len(rows), bool)
    rest = resting_state(trajectory)
    if rest is not None:
        rows = np.vstack([rows, np.concatenate([[rows[-1, 0] + REST_DELAY], rest])])
        is_event = np.append(is_event, False)
        implied = np.append(implied, True)
    t = rows[:, 0].copy()
    state = rows[:, 1:].copy()

    # the model's own formulas, its kernels run by CPython (a throw's few thousand frames)
    n_corners = python.CORNERS
    corners = np.empty((len(state), n_corners, 2))
    python.corner_table(p, state, corners)
    heights = corners[..., 1]
    contact = _contact_sets(t, heights, events)
    contact[implied] = heights[implied] < 0.0
    parts = np.empty((len(state), n_corners, 4))
    python.force_table(p, state, contact, parts)
    energy = np.empty((len(state), 3))
    python.energy_table(p, state, energy)
    return Frames(t=t, state=state, is_event=is_event, contact=contact, corners=corners,
                  heights=heights, forces=parts[..., :2], kinetic=energy[:, 0],
                  gravitational=energy[:, 1], elastic=energy[:, 2], events=events,
                  implied=implied, normal=parts[..., 2], tangential=parts[..., 3])


REST_DELAY = 0.05  # s after a settled run's last frame, where its implied rest pose is shown


def resting_state(trajectory) -> np.ndarray | None:
    """The pose a run that stopped once settled comes to rest in (it cannot leave its well):
    phi = n pi/2, on its two lower corners, sunk by m g / 2k, at rest where it was. None when
    the run went on (--full) or did not settle."""
    integ = trajectory.scene.integration
    if not (trajectory.settled and integ.stop_on_settle) or trajectory.quarter_turns is None:
        return None
    n = trajectory.quarter_turns
    coin = trajectory.scene.coin
    sink = coin.mass * trajectory.scene.g / (2 * trajectory.scene.foundation.k)
    height = (coin.r_d if n % 2 else coin.r_t) - sink
    return np.array([trajectory.final_state[0], height, n * math.pi / 2, 0.0, 0.0, 0.0])


def _contact_sets(t: np.ndarray, heights: np.ndarray, events: np.ndarray) -> np.ndarray:
    """(N, 4) contact set at each frame time: replayed from the events (the integrator's own
    contact set, exact at the event rows), or the penetration y_i < 0 where no events exist."""
    from ..throw import MAX_EVENTS

    if len(events) == 0 or len(events) >= MAX_EVENTS:
        return heights < 0.0
    contact = np.zeros(heights.shape, bool)
    for i in range(heights.shape[1]):
        ev = events[events[:, 1] == i]
        if len(ev) == 0:
            continue
        last = np.searchsorted(ev[:, 0], t, side="right") - 1  # last event of corner i <= t
        contact[:, i] = (last >= 0) & (ev[np.maximum(last, 0), 2] > 0)
    return contact


ARROW_PEAK_DIAMETERS = 1.0  # the largest contact force of a run is drawn this many diameters long


def force_arrows(frames: Frames, weight: float, diameter: float) -> np.ndarray:
    """(N, 4, 2) arrows (m) for the contact forces. Impact forces exceed the coin's weight by two
    orders of magnitude, so the length grows with log(1 + |F| / (m g)), the direction is the
    force's own, and the largest force of the run is ``ARROW_PEAK_DIAMETERS`` diameters long:
    the weight itself then shows as a few millimetres, an impact as centimetres."""
    magnitude = np.hypot(frames.forces[..., 0], frames.forces[..., 1])
    peak = float(np.max(magnitude, initial=0.0))
    if peak <= 0.0 or weight <= 0.0:
        return np.zeros_like(frames.forces)
    length = ARROW_PEAK_DIAMETERS * diameter * np.log1p(magnitude / weight) / np.log1p(
        peak / weight)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(magnitude[..., None] > 0, frames.forces / magnitude[..., None], 0.0)
    return unit * length[..., None]


def friction_arrows(frames: Frames, weight: float, diameter: float) -> np.ndarray:
    """(N, 4, 2) arrows (m) for the friction forces, along the foundation, on the scale of
    :func:`force_arrows` (the same log1p(|F| / (m g)) law, the largest contact force of the run
    ``ARROW_PEAK_DIAMETERS`` diameters long), so that a friction arrow beside its corner's
    contact force shows their ratio; zero without friction."""
    arrows = np.zeros_like(frames.forces)
    if frames.tangential is None:
        return arrows
    peak = float(np.max(np.hypot(frames.forces[..., 0], frames.forces[..., 1]), initial=0.0))
    if peak <= 0.0 or weight <= 0.0:
        return arrows
    tangential = frames.tangential
    arrows[..., 0] = np.sign(tangential) * ARROW_PEAK_DIAMETERS * diameter * np.log1p(
        np.abs(tangential) / weight) / np.log1p(peak / weight)
    return arrows


__all__ = ["ARROW_PEAK_DIAMETERS", "Frames", "REST_DELAY", "build_frames", "force_arrows",
           "friction_arrows",
           "resting_state"]
