"""Rerun streams of a basin sweep as it fills in, of a basin store (`coin basin show`), of the
running estimates of `coin fractions`, and of `coin basin analyze` as each band is measured.

The map is two SegmentationImages over one AnnotationContext: ``basin/n`` the outcome n in the
paper's colours (one class per n, named "n = 7, standing", so that hovering a pixel
says what it is), ``basin/certainty`` over it: uncertain grey, unsettled purple, non-finite
magenta (certain cells transparent); cells not computed are transparent in both, over the
view's light grey background. The first swept axis is horizontal (growing to the right), the
second vertical (growing upwards), as in `coin basin render`.

A sweep sends the whole map again after the tiles written (at most every ``min_interval``
seconds, and always at the end, read back from the store: the recording's last map is the
store's), with the cells done and the rate as time series on the ``sweep_time`` timeline; one
call per layer, never one per cell. A sweep's recording is made by a process of its own
(:mod:`coincli.io.sweep_recording`) that runs :func:`record_tiles`, so that Rerun's start-up
costs the sweep next to nothing. Rerun is imported lazily (as in :mod:`coincli.io.rrd`).
"""

from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..grid import AXIS_INFO
from .basin_render import (
    NONFINITE,
    STANDING,
    UNCERTAIN,
    UNDECIDED,
    UNSETTLED,
    cell_classes,
    n_range,
)
from .dataset import Basin
from .rrd import open_stream

# Entity paths.
BASIN = "basin"  # holds the annotation context of both layers
BASIN_N = "basin/n"
BASIN_CERTAINTY = "basin/certainty"
PROGRESS_CELLS = "progress/cells"
PROGRESS_RATE = "progress/rate"
INFO = "info"
SWEEP_TIME = "sweep_time"

# Class ids of the n layer: 0 is "no n"; a labelled cell's id is n + N_BIAS (n is an int16
# and NO_LABEL, -32768, never a label, so ids run 1 to 65535 in a uint16 image).
NO_N = 0
N_BIAS = 32768
N_CLASSES = 128  # the n named from the start, -N_CLASSES to N_CLASSES (the paper's map: 46)
# Class ids of the certainty layer.
CERTAIN, UNCERTAIN_ID, UNSETTLED_ID, NONFINITE_ID, NOT_COMPUTED_ID = 0, 1, 2, 3, 4
UNDECIDED_ID = 5
BACKGROUND = (238, 238, 238, 255)  # not computed: as the hatched background of the PNG


def _rgb(colour) -> tuple[int, int, int]:
    return tuple(int(round(255 * c)) for c in colour[:3])


# The certainty layer's class id of each class of basin_render.cell_classes drawn over the n.
OVERLAY_IDS = {"uncertain": UNCERTAIN_ID, "undecided": UNDECIDED_ID, "unsettled": UNSETTLED_ID,
               "non-finite": NONFINITE_ID, "not computed": NOT_COMPUTED_ID}


def class_ids(arrays: dict, verified: bool) -> tuple[np.ndarray, np.ndarray]:
    """The class ids of cells (``arrays``: quarter_turns, status and, for a ``verified``
    sweep, certainty): of the n layer, n + N_BIAS where there is a label, else NO_N; of the
    certainty layer, CERTAIN or the class drawn over the n (as `coin basin render` draws it)."""
    q = arrays["quarter_turns"]
    cells = cell_classes(arrays, verified)
    labelled = cells["labelled"]
    n_ids = np.zeros(q.shape, dtype=np.uint16)
    n_ids[labelled] = (q[labelled].astype(np.int32) + N_BIAS).astype(np.uint16)
    certainty_ids = np.full(q.shape, CERTAIN, dtype=np.uint8)
    for name, class_id in OVERLAY_IDS.items():
        if name in cells:
            certainty_ids[cells[name]] = class_id
    return n_ids, certainty_ids


# The even n's colours of `coin basin render` (basin_render.ramp_colours(n_range(None)) as
# 8-bit RGB), written out because computing them imports matplotlib: 0.2 s of CPU, a tenth of
# the default sweep, in every recording (tests/test_live.py checks they are still the same).
RAMP = {
    -24: (138, 0, 38), -22: (153, 0, 38), -20: (168, 0, 38), -18: (185, 0, 38),
    -16: (199, 7, 35), -14: (211, 15, 32), -12: (224, 24, 29), -10: (235, 43, 33),
    -8: (246, 66, 39), -6: (252, 95, 47), -4: (253, 138, 59), -2: (254, 202, 102),
    0: (255, 255, 255),
    2: (142, 211, 186), 4: (53, 170, 195), 6: (31, 147, 192), 8: (31, 123, 182),
    10: (33, 102, 172), 12: (35, 85, 164), 14: (36, 72, 157), 16: (37, 59, 151),
    18: (33, 49, 141), 20: (26, 43, 126), 22: (19, 38, 111), 24: (13, 33, 97),
}


def n_classes(rr, ns) -> list:
    """One class per n in ``ns``, in the colours of `coin basin render` (even n beyond its
    colour bar take its end colours)."""
    top = n_range(None)
    ramp = RAMP
    out = [rr.ClassDescription(info=(NO_N, "no n (not computed or no outcome)",
                                     (0, 0, 0, 0)))]
    for n in sorted(int(n) for n in ns):
        if n % 2:
            colour, pose = _rgb(STANDING), "standing"
        else:
            colour, pose = ramp[max(-top, min(top, n))], "lying"
        out.append(rr.ClassDescription(info=(n + N_BIAS, f"n = {n}, {pose}", colour)))
    return out


def certainty_classes(rr, verified: bool) -> list:
    grey = (*_rgb(UNCERTAIN), 255)
    return [rr.ClassDescription(info=(CERTAIN, "certain" if verified else
                                      "settled (single pass: not verified)", (0, 0, 0, 0))),
            rr.ClassDescription(info=(UNCERTAIN_ID, "uncertain: decided, but no two rungs "
                                      "agreed (chaotic)", grey)),
            rr.ClassDescription(info=(UNDECIDED_ID, "undecided: a rung did not settle",
                                      (*_rgb(UNDECIDED), 255))),
            rr.ClassDescription(info=(UNSETTLED_ID, "unsettled at t_end",
                                      (*_rgb(UNSETTLED), 255))),
            rr.ClassDescription(info=(NONFINITE_ID, "non-finite", (*_rgb(NONFINITE), 255))),
            rr.ClassDescription(info=(NOT_COMPUTED_ID, "not computed", (0, 0, 0, 0)))]


def _image(cells: np.ndarray) -> np.ndarray:
    """Cells (axis 0 the first swept axis) as an image: rows from the top, the second axis's
    highest value first; columns the first axis."""
    return np.ascontiguousarray(cells.T[::-1])


def _axes_text(attrs: dict) -> tuple[str, str]:
    ax0, ax1 = attrs["sweep"]["axes"][:2]

    def one(ax, where):  # the plain names: the viewer shows no TeX
        return f"{ax['name']} {ax['lo']:g} to {ax['hi']:g} {AXIS_INFO[ax['name']][1]} {where}"

    return one(ax0, "(left to right)"), one(ax1, "(bottom to top)")


def basin_blueprint(attrs: dict, live: bool):
    import rerun.blueprint as rrb

    horizontal, vertical = _axes_text(attrs)
    n0, n1 = (ax["n"] for ax in attrs["sweep"]["axes"][:2])
    the_map = rrb.Spatial2DView(name=f"n: {horizontal}, {vertical}", origin=BASIN,
                                background=BACKGROUND, visual_bounds=rrb.VisualBounds2D(
                                    x_range=[0, n0], y_range=[0, n1]))
    side = [rrb.TextDocumentView(name="sweep", origin=INFO)]
    if live:
        side = [rrb.TimeSeriesView(name="cells done", origin=PROGRESS_CELLS,
                                   plot_legend=rrb.PlotLegend(visible=False)),
                rrb.TimeSeriesView(name="rate [cells/s]", origin=PROGRESS_RATE,
                                   plot_legend=rrb.PlotLegend(visible=False)), *side]
    return rrb.Blueprint(
        rrb.Horizontal(the_map, rrb.Vertical(*side), column_shares=[3, 1]),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline=SWEEP_TIME, play_state="following")
        if live else rrb.TimePanel(state="collapsed"),
    )


def _info_markdown(attrs: dict, path, shape, note: str = "") -> str:
    horizontal, vertical = _axes_text(attrs)
    fixed = ", ".join(f"{k} = {v:.4g} {AXIS_INFO[k][1]}"
                      for k, v in attrs["sweep"].get("fixed", {}).items())
    return "\n".join([
        f"# coin basin {path}", "", f"**{shape[0]} x {shape[1]} cells.** Horizontal: "
        f"{horizontal}; vertical: {vertical}." + (f" Fixed: {fixed}." if fixed else ""), "",
        "Colours as `coin basin render`: n < 0 (clockwise) yellow to red, n > 0 "
        "(counter-clockwise) green to blue, n = 0 white, standing (odd n) black; the certainty "
        "layer over it: uncertain grey, unsettled at t_end purple, non-finite magenta; cells "
        "not computed show the light grey background. Hover a pixel for its class.",
        *([""] + [note] if note else [])])


class BasinStream:
    """The map of one basin store in a Rerun recording stream ``rec``: :meth:`update` with
    tiles' arrays as they are written, :meth:`whole` with a whole :class:`Basin`; ``live``
    puts everything on the ``sweep_time`` timeline, else all is static."""

    def __init__(self, rec, attrs: dict, shape: tuple[int, int], *, path, verified: bool,
                 live: bool, min_interval: float = 0.5, blueprint: bool = True):
        import rerun as rr

        self.rr, self.rec, self.live, self.verified = rr, rec, live, verified
        self.shape = tuple(shape)
        self.n_ids = np.zeros(self.shape[::-1], dtype=np.uint16)  # image: rows x columns
        self.certainty_ids = np.full(self.shape[::-1], NOT_COMPUTED_ID, dtype=np.uint8)
        # class ids of the n on the map, and of those in the context sent: every |n| up to
        # N_CLASSES from the start, so that the context need not grow as n come in (with a
        # growing context, Rerun 0.41's web viewer, in a notebook or a browser, drew a live
        # map in its default colours; the native viewer did not)
        self.known: set[int] = {n + N_BIAS for n in range(-N_CLASSES, N_CLASSES + 1)}
        self.classes_sent: set[int] = set()
        self.min_interval = min_interval
        self.points: list[tuple[float, int]] = []  # (s, cells done) not sent yet
        self.last_sent = -math.inf
        self.pending = False
        self.start = time.perf_counter()
        if blueprint:  # else the caller's layout shows the map
            rec.send_blueprint(basin_blueprint(attrs, live), make_active=True,
                               make_default=True)
        rec.log(BASIN_CERTAINTY, rr.AnnotationContext(certainty_classes(rr, verified)),
                static=True)
        self._log_classes()
        rec.log(INFO, rr.TextDocument(_info_markdown(attrs, path, self.shape),
                                      media_type=rr.MediaType.MARKDOWN), static=True)
        if live:
            rec.log(PROGRESS_CELLS, rr.SeriesLines(names=["cells done"], widths=[2.0]),
                    static=True)
            rec.log(PROGRESS_RATE, rr.SeriesLines(names=["cells/s"], widths=[2.0],
                                                  colors=[(255, 127, 14)]), static=True)

    def _log_classes(self) -> None:
        """The n layer's context: one class per n known."""
        self.rec.log(BASIN_N, self.rr.AnnotationContext(
            n_classes(self.rr, [i - N_BIAS for i in self.known])), static=True)
        self.classes_sent = set(self.known)

    def _put(self, s0: slice, s1: slice, arrays: dict) -> None:
        """Cells [s0, s1] of the map (s0 along the first axis, s1 along the second)."""
        n_ids, certainty_ids = class_ids(arrays, self.verified)
        rows = slice(self.shape[1] - s1.stop, self.shape[1] - s1.start)
        self.n_ids[rows, s0] = _image(n_ids)
        self.certainty_ids[rows, s0] = _image(certainty_ids)
        # an n beyond those named from the start gets a class too (the context, sent with the
        # map, grows then: once for all the tiles since the last)
        self.known |= set(np.unique(n_ids).tolist()) - {NO_N}

    def update(self, tiles: dict, grid, points=(), send: bool = True) -> None:
        """Tiles written (``{tile: arrays}``) and the sweep's progress at some moments
        (``points``: (elapsed seconds, cells done) each, for the time series); the map is sent
        if ``min_interval`` has passed since it last was (and ``send``)."""
        for tile, arrays in tiles.items():
            self._put(*grid.tile_slices(tile), arrays)
        self.pending = self.pending or bool(tiles)
        if self.live:
            self.points += points
        if send and time.perf_counter() - self.last_sent >= self.min_interval:
            self.send(points[-1][0] if points else None)

    def series(self, points) -> None:
        """The cells done and the rate at each (elapsed seconds, cells done) of ``points``."""
        rr = self.rr
        t, cells = (np.asarray(x, dtype=np.float64) for x in zip(*points, strict=True))
        with np.errstate(divide="ignore", invalid="ignore"):
            rate = np.where(t > 0, cells / t, 0.0)
        times = [rr.TimeColumn(SWEEP_TIME, duration=t)]
        self.rec.send_columns(PROGRESS_CELLS, indexes=times,
                              columns=rr.Scalars.columns(scalars=cells))
        self.rec.send_columns(PROGRESS_RATE, indexes=times,
                              columns=rr.Scalars.columns(scalars=rate))

    def whole(self, basin: Basin, elapsed: float | None = None) -> None:
        """The whole map of ``basin`` (a store read back), sent at once."""
        whole = (slice(0, self.shape[0]), slice(0, self.shape[1]))
        self._put(*whole, basin.arrays)
        self.pending = True
        self.send(elapsed)

    def _time(self, elapsed: float) -> None:
        self.rec.set_time(SWEEP_TIME, duration=float(elapsed))

    def send(self, elapsed: float | None = None) -> None:
        """The map (if it changed) and the progress points gathered since the last send."""
        rr = self.rr
        static = not self.live
        if self.points:
            self.series(self.points)
            self.points = []
        if self.live:
            self._time(time.perf_counter() - self.start if elapsed is None else elapsed)
        if self.known != self.classes_sent:
            self._log_classes()
        if self.pending or static:
            self.rec.log(BASIN_N, rr.SegmentationImage(self.n_ids, draw_order=1.0),
                         static=static)
            self.rec.log(BASIN_CERTAINTY, rr.SegmentationImage(self.certainty_ids,
                                                               draw_order=2.0), static=static)
        self.last_sent = time.perf_counter()
        self.pending = False


@dataclass
class Destination:
    """Where a recording goes: an .rrd file, a spawned viewer, a running viewer's URL; or,
    alone, a viewer in the notebook's cell."""

    rrd: Path | None = None
    spawn: bool = False
    connect: str | None = None
    notebook: object = False  # True (a new viewer in the cell), or a viewer shown before

    def __bool__(self) -> bool:
        return (self.rrd is not None or self.spawn or self.connect is not None
                or self.notebook is not False)

    def stream(self, name: str):
        """:func:`coincli.io.rrd.open_stream` to this destination."""
        return open_stream(name, rrd=self.rrd, spawn=self.spawn, connect=self.connect,
                           notebook=self.notebook)


def check_destination(rrd=None, spawn: bool = False, connect: str | None = None,
                      notebook=False) -> Destination | None:
    """The destination of a live recording (None if none is asked for), checked before any
    work: ParameterError (naming ``rrd``, ``spawn``, ``connect`` or ``notebook``) for an
    ``rrd`` whose name does not end in .rrd, ``spawn`` without a display, a ``connect`` that is
    no viewer's URL, ``notebook`` with another destination; OSError for an ``rrd`` that cannot
    be written, ConnectionError when no viewer answers at ``connect``; for ``notebook``,
    ImportError without rerun-notebook and RuntimeError outside a notebook."""
    from ..params import ParameterError
    from .paths import DEFAULT_CONNECT_URL, check_rrd_path, probe_viewer
    from .rrd import LIVE_ELSEWHERE, NO_DISPLAY, display_available, require_notebook

    if notebook is not False and notebook is not None:
        if rrd is not None or spawn or connect is not None:
            raise ParameterError("notebook=True shows the recording in the cell, and goes "
                                 "alone: record to a file (rrd=PATH) or a viewer in another "
                                 "call", parameters=("notebook",))
        require_notebook("notebook=True", LIVE_ELSEWHERE)
        if notebook is not True and not hasattr(notebook, "add_recording"):
            raise ParameterError(f"notebook must be True or a viewer of coincli.viewer(), got "
                                 f"{type(notebook).__name__}", parameters=("notebook",))
        return Destination(notebook=notebook)

    if rrd is not None:
        rrd = check_rrd_path(rrd)
        if rrd.suffix != ".rrd":
            raise ParameterError(f"rrd must be a file name ending in .rrd, got '{rrd}'",
                                 parameters=("rrd",))
    if connect is not None:
        try:
            probe_viewer(connect)
        except ValueError:
            raise ParameterError(f"connect must be the URL of a running Rerun viewer, e.g. "
                                 f"{DEFAULT_CONNECT_URL}, got {connect!r}",
                                 parameters=("connect",)) from None
    if spawn and not display_available():
        raise ParameterError(f"spawn: {NO_DISPLAY}; record to a file (rrd=PATH) or stream to "
                             "a running viewer (connect=URL)", parameters=("spawn",))
    where = Destination(rrd, bool(spawn), connect)
    return where if where else None


def show_basin(basin: Basin, where: Destination) -> None:
    """A static recording of a basin store, finished or partial (`coin basin show`)."""
    shape = tuple(basin.arrays["quarter_turns"].shape)
    with where.stream(f"coin basin show {basin.path or ''}".strip()) as rec:
        stream = BasinStream(rec, basin.attrs, shape, path=basin.path, verified=basin.verified,
                             live=False)
        stream.whole(basin)


class StoreMap:
    """The live map of a sweep into the store at ``path`` (a :class:`BasinStream` in ``rec``),
    fed from the store: :meth:`update` with what the sweep did since (the tiles written, its
    progress points), :meth:`end` once it has ended. The tiles are read back from the store,
    verified, so that the map shown is the store's; the first look and the last take every
    tile done and not drawn yet (a resumed store's, those of other processes)."""

    def __init__(self, rec, path, attrs: dict, *, verified: bool, min_interval: float = 0.5):
        from .store import grid_of

        self.path, self.grid = Path(path), grid_of(attrs)
        self.view = None
        self.drawn: set[tuple[int, int]] = set()  # tiles read from the store, on the map
        self.stream = BasinStream(rec, attrs, self.grid.shape, path=self.path,
                                  verified=verified, live=True, min_interval=min_interval)

    def _read(self, written, every: bool) -> dict:
        from ..params import ParameterError
        from .store import Tile, is_store, open_view, scan

        if self.view is None and (written or every) and is_store(self.path):
            with contextlib.suppress(ParameterError, OSError):  # a sweep that failed
                self.view = open_view(self.path, self.grid)
            every = True  # its first look: tiles done before (a resumed store)
        wanted = ([tile for tile in np.ndindex(*self.grid.tile_grid) if tile not in self.drawn]
                  if every else [tile for tile in written if tile not in self.drawn])
        tiles = {}
        if self.view is not None and wanted:
            for tile, state, data, _ in scan(self.view, with_data=True, tiles=wanted):
                if state is Tile.DONE:
                    tiles[tile] = data
                    self.drawn.add(tile)
        return tiles

    def update(self, written, points=()) -> None:
        """The tiles ``written`` since (and the progress ``points``: (elapsed s, cells done))."""
        self.stream.update(self._read([tuple(t) for t in written], False), self.grid,
                           list(points))

    def end(self, elapsed: float | None, points=()) -> None:
        """The sweep has ended: every tile done, and the last map (the store's), sent now."""
        self.stream.update(self._read((), True), self.grid, list(points), send=False)
        self.stream.send(elapsed)


def record_tiles(setup: dict, inbox) -> None:
    """The live recording of a sweep into a store (a :class:`StoreMap`), from the messages in
    ``inbox`` (a queue; None: the end) of :mod:`coincli.io.sweep_recording`: ``setup`` says
    what to record and where, each message what the sweep did (elapsed seconds, cells done,
    the tiles written)."""
    import queue

    path = Path(setup["path"])
    where = Destination(None if setup["rrd"] is None else Path(setup["rrd"]), setup["spawn"],
                        setup["connect"])
    with where.stream(f"coin basin {path}") as rec:
        live_map = StoreMap(rec, path, setup["attrs"], verified=setup["verified"],
                            min_interval=setup["min_interval"])
        ended, elapsed = False, None
        while not ended:
            messages = [inbox.get()]
            with contextlib.suppress(queue.Empty):  # all that came meanwhile, as one update
                while True:
                    messages.append(inbox.get_nowait())
            points, written = [], []
            for message in messages:
                if message is None:
                    ended = True
                    break
                elapsed = message["elapsed"]
                if "cells_done" in message:
                    points.append((elapsed, message["cells_done"]))
                written += [tuple(tile) for tile in message.get("written", ())]
            if ended:
                live_map.end(elapsed, points)
            else:
                live_map.update(written, points)


# -- coin fractions ------------------------------------------------------------------------------
ESTIMATE = "estimate"  # P(outcome) in % against the samples counted
LEADING_N = "leading_n"
OVER = "over"  # P(outcome) in % against the parameter of a continuation
SAMPLES = "samples"
SERIES = (  # (name, label, colour)
    ("standing", "P(standing)", (200, 40, 200)),
    ("lying", "P(lying)", (0, 160, 200)),
    ("uncertain", "uncertain", (140, 140, 140)),
    ("leading", "P(leading n)", (255, 127, 14)),
)


def parameter_timeline(parameter: str, unit: str, values) -> tuple[str, int]:
    """A sequence timeline for the values of a continuation (Rerun's timelines are whole
    numbers): its name, with the unit the values are counted in, and the power of ten k they
    are multiplied by (the smallest that makes them whole)."""
    for k in range(13):
        scaled = np.asarray(values, dtype=np.float64) * 10.0 ** k
        if np.all(np.abs(scaled - np.round(scaled)) < 1e-6 * np.maximum(1.0, np.abs(scaled))):
            break
    if k == 0:
        return (f"{parameter} [{unit}]" if unit else parameter), 0
    return f"{parameter} [1e-{k}{' ' + unit if unit else ''}]", k


def fractions_blueprint(over: str | None):
    """One plot a quantity (each on its own scale: P(standing) may be 0.2 % and P(lying)
    99.8 %), the thin lines its 95 % band; the leading n beside them."""
    import rerun.blueprint as rrb

    root = OVER if over is not None else ESTIMATE
    against = f"against {over}, as each value finishes" if over is not None else \
        "against the samples"
    whole = rrb.TimeAxis(view_range=rrb.TimeRange(start=rrb.TimeRangeBoundary.infinite(),
                                                  end=rrb.TimeRangeBoundary.infinite()))
    plots = [rrb.TimeSeriesView(name=f"{label} [%] {against} (thin: 95 % band)",
                                origin=f"{root}/{name}", axis_x=whole,
                                plot_legend=rrb.PlotLegend(visible=False))
             for name, label, _ in SERIES if over is None or name != "leading"]
    side = [rrb.TextDocumentView(name="run", origin=INFO)]
    if over is None:
        side.insert(0, rrb.TimeSeriesView(name="leading n (the most frequent)",
                                          origin=LEADING_N, axis_x=whole,
                                          plot_legend=rrb.PlotLegend(visible=False)))
    return rrb.Blueprint(
        rrb.Horizontal(rrb.Grid(*plots, grid_columns=2), rrb.Vertical(*side),
                       column_shares=[3, 1]),
        rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed"))


def _estimates(tally, verified: bool) -> dict:
    """{series name: (P, low, high)} in %, and the leading n (None without a counted label)."""
    from ..montecarlo.tally import summary

    s = summary(tally, verified)
    out = {name: tuple(100.0 * s[name][key] for key in ("probability", "low", "high"))
           for name in ("standing", "lying", "uncertain")}
    leading = max(s["outcomes"], key=lambda row: row["count"], default=None)
    if leading is not None:
        out["leading"] = tuple(100.0 * leading[key] for key in ("probability", "low", "high"))
    return out, (None if leading is None else int(leading["n"]))


class InProcessRecording:
    """A recording made in this process to ``self.where`` (a :class:`Destination`):
    :meth:`_open` opens the stream (``rec``); one that cannot be opened leaves ``error`` set
    and ``rec`` None, and the work goes on without it. Leaving closes the stream."""

    where: Destination
    error: Exception | None = None
    rec = _context = None

    def _open(self, name: str) -> bool:
        try:
            self._context = self.where.stream(name)
            self.rec = self._context.__enter__()
        except (OSError, RuntimeError, ValueError) as exc:
            self.error, self.rec, self._context = exc, None, None
        return self.rec is not None

    def __exit__(self, *exc):
        if self._context is not None:
            try:
                self._context.__exit__(None, None, None)
            except (OSError, RuntimeError) as error:
                self.error = error
        return False


class InlineSweep(InProcessRecording):
    """The live map of a sweep into the store at ``path`` in a notebook's viewer: the same
    :class:`StoreMap` as a sweep's recording process makes, here in this process (a notebook's
    viewer belongs to its kernel); :meth:`progress` takes each SweepProgress. The map is
    opened with the first progress (or on leaving, if there was none: a store complete
    already), not for a sweep refused before any work. A map that cannot be shown leaves
    ``error`` set and the sweep alone."""

    def __init__(self, path, attrs: dict, where: Destination, *, verified: bool,
                 min_interval: float = 0.5):
        self.path, self.attrs, self.where = Path(path), attrs, where
        self.verified, self.min_interval = verified, min_interval
        self.map: StoreMap | None = None
        self.elapsed: float | None = None

    def __enter__(self):
        return self

    def _start(self) -> None:
        if (self.map is None and self.error is None and self._context is None
                and self._open(f"coin basin {self.path}")):
            self.map = StoreMap(self.rec, self.path, self.attrs, verified=self.verified,
                                min_interval=self.min_interval)

    def progress(self, update) -> None:
        self._start()
        if self.map is None:
            return
        self.elapsed = update.elapsed
        self.map.update(update.written, [(update.elapsed, update.cells_done)])

    def __exit__(self, exc_type, *exc):
        if exc_type is None:
            self._start()
        try:
            if self.map is not None:
                self.map.end(self.elapsed)
        finally:
            super().__exit__(exc_type, *exc)
        return False


class FractionsRecorder(InProcessRecording):
    """The live recording of a `coin fractions` run: :meth:`progress` takes each
    FractionsProgress; :meth:`result` the run's result (a continuation's values are sent as
    they finish, and all of them again from the result, which is what counts). A recording
    that cannot be made leaves ``error`` set and the run alone."""

    def __init__(self, plan, where: Destination):
        from ..defaults import PARAMETER_UNITS
        from ..integrators.ladder import ladder_of

        self.plan, self.where = plan, where
        self.verified = ladder_of(plan.scene.integration).verified
        self.sent: set[int] = set()  # values of a continuation sent
        self.values_done = 0
        if plan.parameter is not None:
            self.timeline, self.power = parameter_timeline(
                plan.parameter, PARAMETER_UNITS[plan.parameter], plan.values)

    def __enter__(self):
        import rerun as rr

        if not self._open("coin fractions" + (f" over {self.plan.parameter}"
                                               if self.plan.parameter else "")):
            return self
        rec = self.rec
        rec.send_blueprint(fractions_blueprint(self.plan.parameter), make_active=True,
                           make_default=True)
        root = OVER if self.plan.parameter is not None else ESTIMATE
        for name, label, colour in SERIES:
            faint = (*colour, 150)
            rec.log(f"{root}/{name}", rr.SeriesLines(colors=[colour], names=[label],
                                                     widths=[2.5]), static=True)
            for side in ("low", "high"):
                rec.log(f"{root}/{name}/{side}", rr.SeriesLines(
                    colors=[faint], names=[f"{label} 95 % {side}"], widths=[1.0]),
                    static=True)
        rec.log(LEADING_N, rr.SeriesLines(names=["leading n"], widths=[2.0],
                                          interpolation_mode="StepAfter"), static=True)
        rec.log(INFO, rr.TextDocument(self._info(), media_type=rr.MediaType.MARKDOWN),
                static=True)
        return self

    def _info(self) -> str:
        plan = self.plan
        lines = ["# coin fractions", "", f"Drawn: {plan.sampling.describe(plan.scene)}", ""]
        if plan.parameter is not None:
            lines.append(f"Over {plan.parameter} ({len(plan.values)} values): timeline "
                         f"`{self.timeline}`.")
        else:
            lines.append("Timeline `samples`: the samples counted so far.")
        lines += ["", "Probabilities over the certain labels (single pass: the settled ones) "
                      "with 95 % Wilson intervals; uncertain: the share of all samples "
                      "without one."]
        return "\n".join(lines)

    def _log(self, root: str, estimates: dict) -> None:
        import rerun as rr

        for name, (p, low, high) in estimates.items():
            if math.isnan(p):
                continue
            self.rec.log(f"{root}/{name}", rr.Scalars(p))
            self.rec.log(f"{root}/{name}/low", rr.Scalars(low))
            self.rec.log(f"{root}/{name}/high", rr.Scalars(high))

    def progress(self, update) -> None:
        if self.rec is None or update.tally is None:
            return
        estimates, leading = _estimates(update.tally, self.verified)
        if self.plan.parameter is None:
            self.rec.set_time(SAMPLES, sequence=update.samples)
            self._log(ESTIMATE, estimates)
            if leading is not None:
                import rerun as rr

                self.rec.log(LEADING_N, rr.Scalars(float(leading)))
        elif update.values_done > self.values_done:  # this value just met its goal
            self._send_value(update.value, estimates)
        self.values_done = update.values_done

    def _send_value(self, v: int, estimates: dict) -> None:
        value = self.plan.values[v]
        self.rec.set_time(self.timeline, sequence=int(round(value * 10.0 ** self.power)))
        self._log(OVER, {k: e for k, e in estimates.items() if k != "leading"})
        self.sent.add(v)

    def result(self, result) -> None:
        """The run's result: a continuation's every value, from it."""
        if self.rec is None or self.plan.parameter is None:
            return
        for v, r in enumerate(result.results):
            if v in self.sent:  # sent as it finished, with these same counts
                continue
            self._send_value(v, {name: tuple(100.0 * getattr(r, name)[key] for key in
                                             ("probability", "low", "high"))
                                 for name in ("standing", "lying", "uncertain")})


# -- coin basin analyze ---------------------------------------------------------------------------
ANALYSIS_F = "analysis/f"  # log10 f(eps) of each region, against log10 eps
ANALYSIS_FIT = "analysis/fit"  # the fitted line of each region
ANALYSIS_INFO = "analysis/info"
BANDS = "basin/bands"  # the band edges over the map
WHOLE_COLOUR = (235, 235, 235)  # the whole map: light, on the viewer's dark plots


def _region_key(index: int | None) -> str:
    return "whole" if index is None else f"band_{index + 1}"


def analysis_blueprint(attrs: dict, timeline: str):
    import rerun.blueprint as rrb

    horizontal, vertical = _axes_text(attrs)
    n0, n1 = (ax["n"] for ax in attrs["sweep"]["axes"][:2])
    the_map = rrb.Spatial2DView(name=f"n: {horizontal}, {vertical} (lines: the bands)",
                                origin=BASIN, background=BACKGROUND,
                                visual_bounds=rrb.VisualBounds2D(x_range=[0, n0],
                                                                 y_range=[0, n1]))
    whole = rrb.TimeAxis(view_range=rrb.TimeRange(start=rrb.TimeRangeBoundary.infinite(),
                                                  end=rrb.TimeRangeBoundary.infinite()))
    f_plot = rrb.TimeSeriesView(name="log10 f(eps): uncertain fraction (points; lines: fits)",
                                origin="analysis", contents=[f"{ANALYSIS_F}/**",
                                                             f"{ANALYSIS_FIT}/**"],
                                axis_x=whole)
    return rrb.Blueprint(
        rrb.Horizontal(the_map, rrb.Vertical(f_plot, rrb.TextDocumentView(
            name="measures", origin=ANALYSIS_INFO), row_shares=[3, 2]),
            column_shares=[1, 1]),
        rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed", timeline=timeline))


class AnalysisRecorder(InProcessRecording):
    """The live recording of `coin basin analyze`: the map analysed with its bands, each
    region's uncertain fraction f(eps) as it is measured (:meth:`band`, then the whole map's
    with the fits from :meth:`result`) against log10 eps, and the measures as text. A
    recording that cannot be made leaves ``error`` set and the analysis alone."""

    def __init__(self, basin: Basin, where: Destination, *, bands: int, eps):
        from .analysis_charts import band_colours

        self.basin, self.where = basin, where
        self.eps = np.asarray(eps, dtype=np.float64)
        self.timeline, self.power = parameter_timeline("log10 eps", "", self._log_eps(self.eps))
        self.colours = [_rgb(c) for c in band_colours(bands)]
        self.edges: set[int] = set()  # the rows of the band edges drawn
        self.lines = ["# coin basin analyze", "", "Measuring: the map first, then f(eps) band "
                      "by band with the simulator."]

    def __enter__(self):
        import rerun as rr

        basin = self.basin
        if not self._open(f"coin basin analyze {basin.path or ''}".strip()):
            return self
        rec = self.rec
        rec.send_blueprint(analysis_blueprint(basin.attrs, self.timeline), make_active=True,
                           make_default=True)
        shape = tuple(basin.arrays["quarter_turns"].shape)
        BasinStream(rec, basin.attrs, shape, path=basin.path, verified=basin.verified,
                    live=False, blueprint=False).whole(basin)
        regions = [(None, WHOLE_COLOUR, "whole map")] + [
            (i, colour, f"band {i + 1}") for i, colour in enumerate(self.colours)]
        for index, colour, name in regions:
            key = _region_key(index)
            rec.log(f"{ANALYSIS_F}/{key}", rr.SeriesPoints(colors=[colour], names=[name],
                                                          marker_sizes=[4.0]), static=True)
            rec.log(f"{ANALYSIS_FIT}/{key}", rr.SeriesLines(colors=[colour],
                                                           names=[f"{name}: fit"],
                                                           widths=[1.5]), static=True)
        self._info()
        return self

    @staticmethod
    def _log_eps(eps) -> np.ndarray:
        """log10 eps as the timeline counts it: to 1e-4 of a decade (Rerun's timelines are
        whole numbers; eps 0.02 % apart would share a place)."""
        return np.round(np.log10(np.asarray(eps, dtype=np.float64)), 4)

    def _at(self, eps: float) -> None:
        self.rec.set_time(self.timeline, sequence=int(round(
            float(self._log_eps(eps)) * 10.0 ** self.power)))

    def _edges(self, rows) -> None:
        """The bands' first rows, vertical lines over the map (the first axis is horizontal)."""
        import rerun as rr

        new = {int(a) for a, _ in rows if a > 0} - self.edges
        if new:
            self.edges |= new
            height = float(self.basin.arrays["quarter_turns"].shape[1])
            strips = [[(float(a), 0.0), (float(a), height)] for a in sorted(self.edges)]
            self.rec.log(BANDS, rr.LineStrips2D(strips, colors=[(255, 255, 255)],
                                                radii=[0.6], draw_order=3.0), static=True)

    def _info(self) -> None:
        import rerun as rr

        self.rec.log(ANALYSIS_INFO, rr.TextDocument("\n".join(self.lines),
                                                    media_type=rr.MediaType.MARKDOWN),
                     static=True)

    def _fraction(self, key: str, fraction) -> None:
        import rerun as rr

        for eps, f in zip(fraction.eps, fraction.fraction, strict=True):
            if not (f > 0 and math.isfinite(f)):  # log10: no point where none is uncertain
                continue
            self._at(eps)
            self.rec.log(f"{ANALYSIS_F}/{key}", rr.Scalars(math.log10(f)))

    def band(self, index: int, rows: tuple[int, int], fraction) -> None:
        """Band ``index`` (``rows`` of the first axis) and its f(eps), just measured."""
        if self.rec is None:
            return
        self._edges([rows])
        self._fraction(_region_key(index), fraction)
        self.lines.append(f"- band {index + 1}: f(eps) measured")
        self._info()

    def result(self, analysis) -> None:
        """The analysis done: the whole map's f(eps), every fit, and the measures."""
        if self.rec is None:
            return
        import rerun as rr

        self._edges([band.rows for band in analysis.bands])  # those not measured too
        regions = [(None, analysis.whole)] + list(enumerate(analysis.bands))
        for index, region in regions:
            key = _region_key(index)
            if index is None and region.perturbation is not None:
                self._fraction(key, region.perturbation)
            fit = region.exponent
            if fit is None or not math.isfinite(fit.alpha):
                continue
            # the fitted line, log f = alpha log eps + c (c in natural logs), across the eps
            for eps in (self.eps.min(), self.eps.max()):
                self._at(eps)
                self.rec.log(f"{ANALYSIS_FIT}/{key}",
                             rr.Scalars(fit.alpha * math.log10(eps) + fit.intercept / LN10))
        self.lines = analysis_markdown(analysis)
        self._info()


LN10 = math.log(10.0)


def _number(value, spec: str = ".3f") -> str:
    return "-" if value is None or not math.isfinite(value) else format(value, spec)


def analysis_markdown(analysis) -> list[str]:
    """The measures of an analysis as Markdown lines: a row a region."""
    axis = analysis.axes[0]
    conf = int(round(100 * analysis.options.confidence))
    lines = ["# coin basin analyze", "",
             f"Boxes of {analysis.options.box} x {analysis.options.box} cells; "
             f"{analysis.trajectories:,} throws for f(eps) "
             f"({'certain' if analysis.verified else 'settled'} labels only).", "",
             f"| {axis['name']} ({axis['units']}) | S_b | S_bb | ball test | Wada | alpha "
             f"({conf} %) | D |", "|---|---:|---:|---|---|---:|---:|"]
    for region in (analysis.whole, *analysis.bands):
        e, ft, x = region.entropy, region.fractal_test, region.exponent
        name = ("whole map" if region is analysis.whole
                else f"{region.span[0]:.3g} to {region.span[1]:.3g}")
        alpha = "-" if x is None or not math.isfinite(x.alpha) else (
            f"{x.alpha:.2f} ({_number(x.alpha_low, '.2f')} to {_number(x.alpha_high, '.2f')})")
        lines.append(f"| {name} | {_number(e.basin_entropy)} | "
                     f"{_number(e.boundary_basin_entropy)} | "
                     f"{'-' if ft is None else ft.verdict} | "
                     f"{'yes' if region.wada.is_wada else 'no'} | {alpha} | "
                     f"{'-' if x is None else _number(x.boundary_dimension, '.2f')} |")
    lines += ["", "f(eps): the share of throws whose label changes when the throw is moved by "
              "eps (relative to each axis's range); alpha is the slope of log f against "
              "log eps, D = 2 - alpha the boundary's dimension."]
    return lines


__all__ = ["AnalysisRecorder", "BasinStream", "Destination", "FractionsRecorder",
           "InProcessRecording", "InlineSweep", "StoreMap",
           "analysis_markdown", "check_destination", "record_tiles", "show_basin"]
