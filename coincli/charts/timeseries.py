"""A throw's time series as named data: an xarray Dataset (time as the coordinate, units and
long names on every variable, the outcome and the scene as flat NetCDF-safe attributes), its
contact events as a pandas table, and a CSV file with names and units in its header.

The names, units and descriptions come from :data:`coincli.throw.SAMPLE_NAMES`,
:data:`coincli.throw.EVENT_NAMES` and :data:`coincli.throw.QUANTITIES`; the energies from the
model's own formulas (:func:`coincli.recordings.frames.build_frames`).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ..defaults import DEFAULT_LOG_EVERY
from ..files import atomic_output, check_writable
from ..params import ParameterError
from ..recordings.frames import build_frames
from ..throw import (
    EVENT_KINDS,
    EVENT_NAMES,
    QUANTITIES,
    SAMPLE_NAMES,
    STATE_NAMES,
    simulate,
)
from ..version import __version__

ENERGY_NAMES = ("kinetic", "gravitational", "elastic", "energy")
# the Dataset's variables and the CSV's columns after the time, in this order
SERIES_NAMES = (*STATE_NAMES, *ENERGY_NAMES)


def _samples(trajectory) -> np.ndarray:
    if trajectory.samples is None:
        raise ParameterError("the trajectory kept no samples: simulate it with sample_dt "
                             "(seconds between samples), e.g. simulate(scene, sample_dt=1e-3)")
    return np.asarray(trajectory.samples, dtype=np.float64)


def with_samples(trajectory, sample_dt: float | None = None):
    """``trajectory`` itself if it kept its samples (every ``sample_dt`` seconds, when given)
    and its contact events, else the same throw simulated again keeping them (every
    ``sample_dt`` seconds, by default DEFAULT_LOG_EVERY): what a recording or an animation
    draws."""
    kept = trajectory.samples is not None and trajectory.events is not None
    if kept and (sample_dt is None or sample_dt == trajectory.sample_dt):
        return trajectory
    # force: the throw was run once already, its step allowed (or forced) then
    return simulate(trajectory.scene, sample_dt=sample_dt or DEFAULT_LOG_EVERY,
                    record_events=True, force=True)


def series(trajectory) -> dict[str, np.ndarray]:
    """The time ``t`` and every SERIES_NAMES column at the trajectory's samples (not at its
    contact events, nor the resting pose a recording adds), in SI units."""
    samples = _samples(trajectory)
    plain = trajectory.__class__(**{**vars(trajectory), "events": None})
    frames = build_frames(plain)  # the samples' energies by the model's formulas
    if frames.implied is not None:
        frames = frames.subset(~frames.implied)
    # build_frames drops non-finite rows and repeated times: match each sample to its frame
    t = samples[:, 0]
    index = np.minimum(np.searchsorted(frames.t, t), max(len(frames) - 1, 0))
    found = (frames.t[index] == t) & np.isfinite(samples).all(axis=1) if len(frames) else \
        np.zeros(len(t), bool)
    out = {name: samples[:, i] for i, name in enumerate(SAMPLE_NAMES)}
    for name, values in zip(ENERGY_NAMES, _energies(frames), strict=True):
        out[name] = np.where(found, values[index] if len(frames) else math.nan, math.nan)
    return out


def _energies(frames):
    return frames.kinetic, frames.gravitational, frames.elastic, frames.total


def outcome_attributes(trajectory) -> dict:
    """The outcome, the run and the scene's parameters as flat attributes of plain scalars
    (NetCDF-safe: no None, no bool, no nested dict; an absent count is left out)."""
    attrs: dict = {"title": "coin: one throw", "coincli_version": __version__}
    if trajectory.quarter_turns is not None:
        attrs["n"] = int(trajectory.quarter_turns)
    attrs.update(pose=trajectory.pose, status=trajectory.status.label,
                 certainty=trajectory.certainty.label,
                 settle_time=float(trajectory.settle_time), t_final=float(trajectory.t_final),
                 e_crit=float(trajectory.e_crit),
                 energy_initial=float(trajectory.energy_initial),
                 energy_final=float(trajectory.energy_final), steps=int(trajectory.steps))
    if trajectory.sample_dt is not None:
        attrs["sample_dt"] = float(trajectory.sample_dt)
    for section, values in trajectory.scene.to_dict().items():
        for key, value in (values.items() if isinstance(values, dict) else [(None, values)]):
            if value is None:
                continue
            name = f"{section}.{key}" if key is not None else section
            attrs[name] = int(value) if isinstance(value, bool) else value
    if trajectory.notes:
        attrs["notes"] = "\n".join(trajectory.notes)
    return attrs


def trajectory_dataset(trajectory):
    """The throw's samples as an ``xarray.Dataset`` (:meth:`coincli.Trajectory.to_dataset`)."""
    import xarray as xr

    columns = series(trajectory)
    t = columns.pop("t")
    units, long_name = QUANTITIES["t"]
    coords = {"t": ("t", t, {"units": units, "long_name": long_name})}
    data = {name: ("t", values, {"units": QUANTITIES[name][0], "long_name": QUANTITIES[name][1]})
            for name, values in columns.items()}
    return xr.Dataset(data, coords=coords, attrs=outcome_attributes(trajectory))


def events_table(trajectory):
    """The contact events as a ``pandas.DataFrame`` (:meth:`coincli.Trajectory.events_table`)."""
    import pandas as pd

    if trajectory.events is None:
        raise ParameterError("the trajectory kept no contact events: simulate it with "
                             "record_events=True")
    events = np.asarray(trajectory.events, dtype=np.float64)
    table = pd.DataFrame(events, columns=list(EVENT_NAMES))
    table["corner"] = table["corner"].astype(np.int8)
    table["kind"] = [EVENT_KINDS[int(kind)] for kind in events[:, EVENT_NAMES.index("kind")]]
    table.attrs["units"] = {name: QUANTITIES[name][0] for name in EVENT_NAMES if name != "kind"}
    return table


def csv_header() -> str:
    """``t [s],x [m],...``: every column's name and units."""
    return ",".join(f"{name} [{QUANTITIES[name][0]}]" for name in ("t", *SERIES_NAMES))


def write_csv(trajectory, path: str | os.PathLike) -> Path:
    """Write the samples as CSV: one header line of names and units (:func:`csv_header`), then
    one row per sample, every number to full precision (``%.17g``). Written through a temporary
    file renamed into place: complete or absent."""
    path = check_writable(path, what="CSV file")
    columns = series(trajectory)
    table = np.column_stack([columns[name] for name in ("t", *SERIES_NAMES)])
    with atomic_output(path) as tmp:
        np.savetxt(tmp, table, fmt="%.17g", delimiter=",", header=csv_header(), comments="")
    return path


__all__ = ["ENERGY_NAMES", "SERIES_NAMES", "csv_header", "events_table", "outcome_attributes",
           "series", "trajectory_dataset", "with_samples", "write_csv"]
