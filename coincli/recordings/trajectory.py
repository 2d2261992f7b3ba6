"""The throw as the public API gives it (:class:`Trajectory`): a :class:`coincli.throw.Throw` with
its views in the io layer, a Dataset of its samples, a table of its contact events, a CSV file,
an animation and a viewer in a notebook's cell. The views import their libraries (xarray, pandas,
matplotlib, Rerun) when called, so that a throw computed without them costs none of them."""

from __future__ import annotations

from dataclasses import fields

from ..throw import Throw


class Trajectory(Throw):
    """One throw (:func:`coincli.simulate`): its outcome, status, certainty, final state,
    energies, its samples and contact events if kept, and its views."""

    @classmethod
    def of(cls, throw: Throw) -> Trajectory:
        """The throw with its views."""
        return cls(**{f.name: getattr(throw, f.name) for f in fields(Throw)})

    def to_dataset(self):
        """The samples as an ``xarray.Dataset``: time ``t`` as the coordinate, the state and
        the energies as variables with ``units`` and ``long_name``, the outcome and the scene's
        parameters as flat attributes (``ds.to_netcdf()`` works). Needs ``sample_dt``."""
        from ..charts.timeseries import trajectory_dataset

        return trajectory_dataset(self)

    def events_table(self):
        """Every contact onset and lift-off as a ``pandas.DataFrame``, one row per event, columns
        EVENT_NAMES (``kind`` as "onset" or "lift-off"); units in ``.attrs["units"]``. Needs
        ``record_events=True``."""
        from ..charts.timeseries import events_table

        return events_table(self)

    def to_csv(self, path):
        """Write the samples to the CSV file ``path`` (what `coin simulate --csv` writes): a
        header of names with units, then a row a sample, every number to full precision;
        complete or absent. Needs ``sample_dt``; returns the path."""
        from ..charts.timeseries import write_csv

        return write_csv(self, path)

    def show(self, *, width: int | None = None, height: int | None = None):
        """Show the throw in the notebook's cell now, in Rerun's viewer (``width`` and
        ``height`` in pixels; needs the extra ``coincli[notebook]``). Outside a notebook a
        one-line RuntimeError says what to do instead (:func:`coincli.record`). A throw that
        kept no samples or events is simulated again keeping them (every DEFAULT_LOG_EVERY s);
        ``coincli.record(run, notebook=True)`` also gives the viewer object."""
        from .rrd import show_inline

        return show_inline(self, width=width, height=height)

    def animate(self, path, *, fps: int | None = None, seconds: float | None = None):
        """Write an animation of the throw (``.gif``; ``.mp4`` with ffmpeg) drawn with
        matplotlib; returns its path. See :func:`coincli.charts.animation.animate`."""
        from ..charts.animation import animate

        return animate(self, path, fps=fps, seconds=seconds)


__all__ = ["Trajectory"]
