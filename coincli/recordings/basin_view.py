"""A basin map in Rerun: the stream of a store's map (:class:`BasinStream`), a store shown whole
(`coin basin show`, :func:`show_basin`), and a sweep's map as it fills in, read back from its store
(:class:`StoreMap`, fed by :func:`record_tiles` in a sweep's recording process or by a notebook's
in-process recording, :mod:`coincli.recordings.sweep_recording`).

The map is two SegmentationImages over one AnnotationContext: ``basin/n`` the outcome n in the
paper's colours (one class per n, named "n = 7, standing", so that hovering a pixel
says what it is), ``basin/certainty`` over it: uncertain grey, unsettled purple, non-finite
magenta (certain cells transparent); cells not computed are transparent in both, over the
view's light grey background. The first swept axis is horizontal (growing to the right), the
second vertical (growing upwards), as in `coin basin render`.

A sweep sends the whole map again after the tiles written (at most every ``min_interval``
seconds, and always at the end, read back from the store: the recording's last map is the
store's), with the cells done and the rate as time series on the ``sweep_time`` timeline; one
call per layer, never one per cell. Rerun is imported lazily, inside the functions that need it.
"""

from __future__ import annotations

import contextlib
import math
import time
from pathlib import Path

import numpy as np

from ..charts.basin_render import (
    NONFINITE,
    STANDING,
    UNCERTAIN,
    UNDECIDED,
    UNSETTLED,
    cell_classes,
    n_range,
)
from ..grid import AXIS_INFO
from ..params import ParameterError
from ..stores.basin_layout import grid_of
from ..stores.basin_store import BasinStore, Tile
from ..stores.dataset import Basin
from ..stores.zarr_v3 import is_store
from .stream import Destination

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


def rgb(colour) -> tuple[int, int, int]:
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
            colour, pose = rgb(STANDING), "standing"
        else:
            colour, pose = ramp[max(-top, min(top, n))], "lying"
        out.append(rr.ClassDescription(info=(n + N_BIAS, f"n = {n}, {pose}", colour)))
    return out


def certainty_classes(rr, verified: bool) -> list:
    grey = (*rgb(UNCERTAIN), 255)
    return [rr.ClassDescription(info=(CERTAIN, "certain" if verified else
                                      "settled (single pass: not verified)", (0, 0, 0, 0))),
            rr.ClassDescription(info=(UNCERTAIN_ID, "uncertain: decided, but no two rungs "
                                      "agreed (chaotic)", grey)),
            rr.ClassDescription(info=(UNDECIDED_ID, "undecided: a rung did not settle",
                                      (*rgb(UNDECIDED), 255))),
            rr.ClassDescription(info=(UNSETTLED_ID, "unsettled at t_end",
                                      (*rgb(UNSETTLED), 255))),
            rr.ClassDescription(info=(NONFINITE_ID, "non-finite", (*rgb(NONFINITE), 255))),
            rr.ClassDescription(info=(NOT_COMPUTED_ID, "not computed", (0, 0, 0, 0)))]


def _image(cells: np.ndarray) -> np.ndarray:
    """Cells (axis 0 the first swept axis) as an image: rows from the top, the second axis's
    highest value first; columns the first axis."""
    return np.ascontiguousarray(cells.T[::-1])


def axes_text(attrs: dict) -> tuple[str, str]:
    ax0, ax1 = attrs["sweep"]["axes"][:2]

    def one(ax, where):  # the plain names: the viewer shows no TeX
        return f"{ax['name']} {ax['lo']:g} to {ax['hi']:g} {AXIS_INFO[ax['name']][1]} {where}"

    return one(ax0, "(left to right)"), one(ax1, "(bottom to top)")


def basin_blueprint(attrs: dict, live: bool):
    import rerun.blueprint as rrb

    horizontal, vertical = axes_text(attrs)
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
    horizontal, vertical = axes_text(attrs)
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
        self.path, self.grid = Path(path), grid_of(attrs)
        self.store: BasinStore | None = None  # opened at its first look (the sweep made it)
        self.drawn: set[tuple[int, int]] = set()  # tiles read from the store, on the map
        self.stream = BasinStream(rec, attrs, self.grid.shape, path=self.path,
                                  verified=verified, live=True, min_interval=min_interval)

    def _read(self, written, every: bool) -> dict:
        if self.store is None and (written or every) and is_store(self.path):
            with contextlib.suppress(ParameterError, OSError):  # a sweep that failed
                self.store = BasinStore.open(self.path, self.grid)
            every = True  # its first look: tiles done before (a resumed store)
        wanted = ([tile for tile in np.ndindex(*self.grid.tile_grid) if tile not in self.drawn]
                  if every else [tile for tile in written if tile not in self.drawn])
        tiles = {}
        if self.store is not None and wanted:
            for tile, state, data, _ in self.store.scan(with_data=True, tiles=wanted):
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
    ``inbox`` (a queue; None: the end) of :mod:`coincli.recordings.sweep_recording`: ``setup`` says
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


__all__ = ["BACKGROUND", "BASIN", "BasinStream", "StoreMap", "axes_text", "class_ids",
           "record_tiles", "rgb", "show_basin"]
