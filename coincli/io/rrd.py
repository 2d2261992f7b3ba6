"""Rerun recordings of one throw: the coin in a 2-D view with y up, time series of its energies,
height, angle and penetrations, contact events on the timeline, and a default blueprint.

The numbers come from :func:`coincli.simulate.simulate` run with ``sample_dt`` (the display rate)
and ``record_events=True``. :func:`build_frames` merges the samples with the exact states at every
contact onset and lift-off and derives everything the scene shows (corner positions,
penetrations, contact forces, energies) in vectorised numpy; :func:`write_recording` sends it to
Rerun column by column (one ``send_columns`` call per entity, never one ``log`` call per frame).

Rerun itself is imported lazily, inside the functions that need it, so that importing this
module (or anything that imports it) stays cheap and nothing below ``coincli.io`` depends on it.

Units in the recording: lengths in the scene and the height plot in millimetres, penetrations in
micrometres, energies in millijoules, angles as quarter turns 2 phi / pi (the coin's transform
carries phi in radians), forces in newtons (drawn as arrows, see :func:`force_arrows`).
"""

from __future__ import annotations

import math
import os
import shutil
import sys
import uuid
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..model import SX, SY

APPLICATION_ID = "coin"
TIMELINE = "sim_time"
DEFAULT_LOG_EVERY = 1e-3  # s of simulated time between frames: a 2 s throw is 2001 frames
DEFAULT_CONNECT_URL = "rerun+http://127.0.0.1:9876/proxy"

# Entity paths.
SCENE = "scene"  # origin of the 2-D view (screen coordinates, y down)
WORLD = "scene/world"  # the physical plane, flipped so that y points up
COIN = "scene/world/coin"
COIN_BODY = "scene/world/coin/body"
COIN_FILL = "scene/world/coin/fill"
COIN_FACE = "scene/world/coin/face"
CORNERS = "scene/world/corners"
FORCES = "scene/world/forces"
PATH = "scene/world/path"
GROUND = "scene/world/ground"
ENERGY = "plots/energy"
HEIGHT = "plots/height"
ANGLE = "plots/angle"
PENETRATION = "plots/penetration"
EVENTS = "events"
INFO = "info"

MM = 1e3  # metres -> millimetres
UM = 1e6  # metres -> micrometres
MJ = 1e3  # joules -> millijoules

# Colours (RGBA).
FREE_COLOUR = (80, 160, 255, 255)
CONTACT_COLOUR = (235, 50, 40, 255)
COIN_COLOUR = (205, 165, 40, 255)
COIN_FILL_COLOUR = (205, 165, 40, 110)
FACE_COLOUR = (150, 40, 160, 255)
FORCE_COLOUR = (255, 140, 0, 255)
PATH_COLOUR = (150, 150, 150, 255)
GROUND_COLOUR = (120, 90, 60, 255)
CORNER_SERIES_COLOURS = ((31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40))
ENERGY_SERIES = (  # (entity, name, colour)
    ("kinetic", "kinetic", (31, 119, 180)),
    ("gravitational", "gravitational m g y", (44, 160, 44)),
    ("elastic", "elastic", (214, 39, 40)),
    ("total", "total", (235, 235, 235)),
    ("e_crit", "E_crit", (148, 103, 189)),
)


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

    def __len__(self) -> int:
        return len(self.t)

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


@dataclass
class RecordingInfo:
    """What :func:`write_recording` wrote and where."""

    rrd: Path | None
    connect: str | None
    spawn: bool
    frames: int
    events: int
    recording_id: str


# -- pure numpy ----------------------------------------------------------------------------------

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
    t = rows[:, 0].copy()
    state = rows[:, 1:].copy()

    scene = trajectory.scene
    coin, found = scene.coin, scene.foundation
    x, y, phi, vx, vy, vphi = state.T
    px = np.asarray(SX) * coin.r_d
    py = np.asarray(SY) * coin.r_t
    c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
    dx = px * c - py * s  # (N, 4) offsets d_i = R(phi) p_i
    dy = px * s + py * c
    heights = y[:, None] + dy
    corners = np.stack([x[:, None] + dx, heights], axis=-1)

    contact = _contact_sets(t, heights, events)
    vxi = vx[:, None] - vphi[:, None] * dy
    vyi = vy[:, None] + vphi[:, None] * dx
    fx = np.where(contact, -found.c * vxi, 0.0)
    fy = np.where(contact, -found.k * heights - found.c * vyi, 0.0)
    forces = np.stack([fx, fy], axis=-1)

    m, inertia = coin.mass, coin.inertia
    kinetic = 0.5 * m * (vx ** 2 + vy ** 2) + 0.5 * inertia * vphi ** 2
    gravitational = m * scene.g * y
    elastic = 0.5 * found.k * np.sum(np.where(heights < 0.0, heights ** 2, 0.0), axis=1)
    return Frames(t=t, state=state, is_event=is_event, contact=contact, corners=corners,
                  heights=heights, forces=forces, kinetic=kinetic, gravitational=gravitational,
                  elastic=elastic, events=events)


def _contact_sets(t: np.ndarray, heights: np.ndarray, events: np.ndarray) -> np.ndarray:
    """(N, 4) contact set at each frame time: replayed from the events (the integrator's own
    contact set, exact at the event rows), or the penetration y_i < 0 where no events exist."""
    from ..simulate import MAX_EVENTS

    if len(events) == 0 or len(events) >= MAX_EVENTS:
        return heights < 0.0
    contact = np.zeros(heights.shape, bool)
    for i in range(4):
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


def _rgba(colour) -> int:
    r, g, b, a = (tuple(colour) + (255,))[:4]
    return (r << 24) | (g << 16) | (b << 8) | a


def check_rrd_path(path: str | os.PathLike) -> Path:
    """Raise the OSError a user should see (one line) if ``path`` cannot be written as a file."""
    p = Path(path)
    if p.is_dir():
        raise IsADirectoryError(f"recording path '{path}' is a directory")
    if str(path) == "" or p.name == "":
        raise FileNotFoundError(f"invalid recording path '{path}'")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"cannot write '{p}': folder '{parent}' does not exist")
    if not os.access(parent, os.W_OK) or (p.exists() and not os.access(p, os.W_OK)):
        raise PermissionError(f"cannot write '{p}': permission denied")
    return p


def check_connect_url(url: str) -> str:
    """Raise ValueError (one line) unless ``url`` looks like a Rerun gRPC proxy address."""
    if not url.startswith(("rerun://", "rerun+http://", "rerun+https://")):
        raise ValueError(f"--connect URL '{url}' must start with rerun+http://, rerun+https:// "
                         f"or rerun:// (e.g. {DEFAULT_CONNECT_URL})")
    return url


def probe_viewer(url: str, timeout: float = 2.0) -> None:
    """Raise ConnectionError (one line) unless something accepts TCP connections at ``url``'s
    host and port: streaming to nobody would otherwise only fail after seconds of retries."""
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(check_connect_url(url))
    port = parts.port or (80 if parts.scheme == "rerun+http" else 443)
    host = parts.hostname or "127.0.0.1"
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        raise ConnectionError(f"no Rerun viewer reachable at {url} ({exc.strerror or exc}); "
                              "start one with `rerun` or use --spawn") from None


# -- Rerun ---------------------------------------------------------------------------------------

def blueprint(frames: Frames | None = None, scene=None):
    """The default layout: the coin (y up) over the contact log and parameters on the left,
    energies, height, angle and penetrations stacked on the right."""
    import rerun.blueprint as rrb

    view2d = {}
    if frames is not None and len(frames) and scene is not None:
        view2d["visual_bounds"] = _visual_bounds(frames, scene)
    trail = rrb.VisibleTimeRanges(timeline=TIMELINE, start=rrb.TimeRangeBoundary.infinite(),
                                  end=rrb.TimeRangeBoundary.cursor_relative())
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial2DView(name="coin (y up, mm)", origin=SCENE,
                                  background=(250, 250, 250, 255),
                                  overrides={PATH: trail}, **view2d),
                rrb.Tabs(
                    rrb.TextLogView(name="contact events", origin=EVENTS,
                                    columns=rrb.TextLogColumns(
                                        text_log_columns=["LogLevel", "Body"])),
                    rrb.TextDocumentView(name="parameters", origin=INFO),
                ),
                row_shares=[5, 1],
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(name="energy [mJ]", origin=ENERGY,
                                   plot_legend=rrb.PlotLegend(rrb.Corner2D.RightTop)),
                rrb.TimeSeriesView(name="height y [mm]", origin=HEIGHT,
                                   plot_legend=rrb.PlotLegend(visible=False)),
                rrb.TimeSeriesView(name="angle 2φ/π and n [quarter turns]", origin=ANGLE,
                                   plot_legend=rrb.PlotLegend(rrb.Corner2D.LeftTop)),
                rrb.TimeSeriesView(name="penetration [µm]", origin=PENETRATION,
                                   plot_legend=rrb.PlotLegend(rrb.Corner2D.RightTop)),
            ),
            column_shares=[1, 1],
        ),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(timeline=TIMELINE, state="collapsed", playback_speed=0.1,
                      play_state="following"),
    )


def _visual_bounds(frames: Frames, scene):
    """Bounds of the 2-D view (in its screen coordinates, y down) that frame the whole throw:
    every corner position and every force arrow, with a margin."""
    import rerun.blueprint as rrb

    d = scene.coin.diameter
    arrows = force_arrows(frames, scene.coin.mass * scene.g, d)
    points = np.concatenate([frames.corners.reshape(-1, 2),
                             (frames.corners - arrows).reshape(-1, 2)]) * MM
    d *= MM
    x0, x1 = float(points[:, 0].min()) - 0.5 * d, float(points[:, 0].max()) + 0.5 * d
    y0, y1 = min(float(points[:, 1].min()), 0.0) - 0.25 * d, float(points[:, 1].max()) + 0.25 * d
    return rrb.VisualBounds2D(x_range=[x0, x1], y_range=[-y1, -y0])


def _sinks(rr, rec, rrd: Path | None, spawn: bool, connect: str | None, port: int):
    sinks = []
    if rrd is not None:
        sinks.append(rr.FileSink(str(rrd)))
    urls = []
    if spawn:
        exe = shutil.which("rerun")
        if exe is None:
            candidate = Path(sys.executable).with_name("rerun")
            exe = str(candidate) if candidate.exists() else None
        rr.spawn(port=port, connect=False, executable_path=exe, recording=rec)
        urls.append(f"rerun+http://127.0.0.1:{port}/proxy")
    if connect is not None and connect not in urls:
        urls.append(connect)
    sinks.extend(rr.GrpcSink(url) for url in urls)
    return sinks


def write_recording(trajectory, *, rrd: str | os.PathLike | None = None, spawn: bool = False,
                    connect: str | None = None, frames: Frames | None = None,
                    log_every: float | None = None, port: int = 9876,
                    flush_timeout: float = 30.0) -> RecordingInfo:
    """Send the recording of ``trajectory`` to a ``.rrd`` file and/or a viewer.

    ``rrd``: file to write; ``spawn``: start a viewer and stream to it; ``connect``: stream to a
    running viewer at this URL (``rerun+http://host:port/proxy``). At least one must be given.
    ``frames`` defaults to :func:`build_frames` of the trajectory; ``log_every`` is only stored
    in the recording's description.
    """
    import rerun as rr

    rrd_path = check_rrd_path(rrd) if rrd is not None else None
    if connect is not None:
        check_connect_url(connect)
    if rrd_path is None and not spawn and connect is None:
        raise ValueError("write_recording needs a destination: rrd, spawn or connect")
    if frames is None:
        frames = build_frames(trajectory)
    scene = trajectory.scene

    rec = rr.RecordingStream(APPLICATION_ID, recording_id=uuid.uuid4())
    rec.set_sinks(*_sinks(rr, rec, rrd_path, spawn, connect, port))
    init = scene.initial
    rec.send_recording_name(f"coin simulate vy={init.vy:g} vphi={init.vphi:g} "
                            f"phi0={init.phi0:g} ({scene.integration.method})")
    rec.send_blueprint(blueprint(frames, scene), make_active=True, make_default=True)
    _log_static(rec, rr, trajectory, frames, log_every)
    if len(frames):
        _send_scene(rec, rr, trajectory, frames)
        _send_plots(rec, rr, trajectory, frames)
    _send_text_log(rec, rr, trajectory, frames)
    try:
        rec.flush(timeout_sec=flush_timeout)
    finally:
        rec.disconnect()  # closes the file sink (writes its footer) and hangs up on viewers
    return RecordingInfo(rrd=rrd_path, connect=connect, spawn=spawn, frames=len(frames),
                         events=len(frames.events), recording_id=str(rec.get_recording_id()))


def _log_static(rec, rr, trajectory, frames: Frames, log_every: float | None) -> None:
    from .. import __version__

    scene = trajectory.scene
    coin = scene.coin
    r_d, r_t = coin.r_d * MM, coin.r_t * MM
    rec.log(WORLD, rr.Transform3D(scale=[1.0, -1.0, 1.0]), static=True)  # y up
    # the coin in its body frame: an outline of its real size, a translucent fill (a line as
    # thick as the coin), its "+y" face marked so that its rotation can be followed
    rec.log(COIN_BODY, rr.Boxes2D(half_sizes=[[r_d, r_t]], radii=0.12,
                                  colors=[COIN_COLOUR], draw_order=20.0), static=True)
    rec.log(COIN_FILL, rr.LineStrips2D([[[-r_d + r_t, 0.0], [r_d - r_t, 0.0]]], radii=0.95 * r_t,
                                       colors=[COIN_FILL_COLOUR], draw_order=19.0), static=True)
    rec.log(COIN_FACE, rr.LineStrips2D([[[-r_d, r_t], [r_d, r_t]]], radii=0.2,
                                       colors=[FACE_COLOUR], draw_order=21.0), static=True)
    d = coin.diameter * MM
    xs = frames.corners[..., 0] * MM if len(frames) else np.zeros(1)
    x0, x1 = float(xs.min()) - 3 * d, float(xs.max()) + 3 * d
    rec.log(GROUND, rr.LineStrips2D([[[x0, 0.0], [x1, 0.0]]], radii=0.25,
                                    colors=[GROUND_COLOUR], labels=["ground y = 0"],
                                    show_labels=False, draw_order=10.0), static=True)
    rec.log(CORNERS, rr.Points2D.from_fields(labels=["0", "1", "2", "3"], show_labels=False,
                                             radii=0.6, draw_order=30.0), static=True)
    rec.log(FORCES, rr.Arrows2D.from_fields(colors=[FORCE_COLOUR], radii=0.25, draw_order=25.0,
                                            show_labels=False), static=True)  # |F| on hover
    rec.log(PATH, rr.LineStrips2D.from_fields(colors=[PATH_COLOUR], radii=0.12,
                                              draw_order=5.0), static=True)
    for name, label, colour in ENERGY_SERIES:
        style = dict(colors=[colour], names=[label], widths=[2.0], aggregation_policy="MinMax")
        if name == "e_crit":
            style["widths"] = [1.5]
        rec.log(f"{ENERGY}/{name}", rr.SeriesLines(**style), static=True)
    rec.log(f"{HEIGHT}/y", rr.SeriesLines(colors=[(31, 119, 180)], names=["y"], widths=[2.0]),
            static=True)
    rec.log(f"{ANGLE}/quarter_turns", rr.SeriesLines(colors=[(31, 119, 180)], names=["2φ/π"],
                                                     widths=[2.0]), static=True)
    rec.log(f"{ANGLE}/n", rr.SeriesLines(colors=[(214, 39, 40)], names=["n = round(2φ/π)"],
                                         widths=[2.0], interpolation_mode="StepAfter"),
            static=True)
    for i, colour in enumerate(CORNER_SERIES_COLOURS):
        rec.log(f"{PENETRATION}/corner{i}",
                rr.SeriesLines(colors=[colour], names=[f"corner {i}"], widths=[2.0],
                               aggregation_policy="MinMax"),  # zoomed out, keep the peaks
                static=True)

    params = _flat_parameters(trajectory, log_every)
    rec.log(INFO, rr.TextDocument(_info_markdown(trajectory, frames, log_every),
                                  media_type=rr.MediaType.MARKDOWN), static=True)
    rec.log(f"{INFO}/parameters", rr.AnyValues(**params), static=True)
    rec.send_property("coin", rr.AnyValues(version=__version__, method=scene.integration.method,
                                           dt=scene.integration.dt,
                                           rtol=scene.integration.rtol,
                                           outcome_n=trajectory.quarter_turns
                                           if trajectory.quarter_turns is not None else -1,
                                           status=trajectory.status))


def _flat_parameters(trajectory, log_every: float | None) -> dict:
    from .. import __version__

    params: dict = {"version": __version__}
    for section, values in trajectory.scene.to_dict().items():
        if isinstance(values, dict):
            for key, value in values.items():
                params[f"{section}.{key}"] = value
        else:
            params[section] = values
    params["log_every"] = float(log_every) if log_every else float("nan")
    params["status"] = trajectory.status
    params["quarter_turns"] = (trajectory.quarter_turns if trajectory.quarter_turns is not None
                               else -1)
    params["e_crit"] = trajectory.e_crit
    return params


def _info_markdown(trajectory, frames: Frames, log_every: float | None) -> str:
    from .. import __version__

    scene = trajectory.scene
    integ = scene.integration
    lines = [f"# coin simulate (coincli {__version__})", ""]
    if trajectory.quarter_turns is None:
        lines.append("**Outcome:** none, the run went non-finite.")
    else:
        lines.append(f"**Outcome:** n = {trajectory.quarter_turns} quarter turns, "
                     f"{trajectory.pose} ({trajectory.status}"
                     + (f" at t = {trajectory.settle_time:.6g} s" if trajectory.settled else "")
                     + ").")
    step = (f"rtol = {integ.rtol:g}" if integ.method in ("dopri5", "event")
            else f"dt = {integ.dt:g} s")
    lines += ["", f"**Method:** {integ.method}, {step}, t_end = {integ.t_end:g} s, "
              + ("stop when settled" if integ.stop_on_settle else "full run"), ""]
    lines += ["| parameter | value |", "|---|---|"]
    for section, values in scene.to_dict().items():
        if isinstance(values, dict):
            for key, value in values.items():
                lines.append(f"| {section}.{key} | {value} |")
        else:
            lines.append(f"| {section} | {values} |")
    lines.append(f"| E_crit | {trajectory.e_crit * MJ:.6g} mJ |")
    lines += ["", f"**Recording:** {len(frames)} frames (one every "
              + (f"{log_every:g} s" if log_every else "sample")
              + f" of simulated time, plus the exact state at each of the {len(frames.events)} "
              "contact events); timeline `sim_time`.", "",
              "Scene in mm with y up: the coin (gold, its +y face purple), its corners (red when "
              "in contact, blue when free), the contact forces (orange arrows from the ground "
              "into the corners they act on, |F| in their labels; length grows with "
              "log(1 + |F|/mg), the largest force of the run "
              f"{ARROW_PEAK_DIAMETERS:g} diameter(s) long) and the path "
              "of the centroid up to the current time (grey)."]
    if trajectory.notes:
        lines += [""] + [f"*Note:* {note}" for note in trajectory.notes]
    return "\n".join(lines)


def _durations(seconds) -> np.ndarray:
    """Seconds as timedelta64[ns], rounded to the nearest nanosecond (Rerun would truncate)."""
    return np.round(np.asarray(seconds, dtype=np.float64) * 1e9).astype(np.int64).astype(
        "timedelta64[ns]")


def _time(rr, frames: Frames):
    return [rr.TimeColumn(TIMELINE, duration=_durations(frames.t))]


def _rotations_about_z(phi: np.ndarray):
    """A RotationAxisAngle column about +z built directly in Arrow (one Python object per frame
    would cost ~5 us each)."""
    import pyarrow as pa
    from rerun.components import RotationAxisAngleBatch

    dtype = getattr(RotationAxisAngleBatch, "_ARROW_DATATYPE", None)
    if dtype is None:  # another rerun-sdk: the slow, public way
        import rerun as rr

        return [rr.RotationAxisAngle(axis=[0.0, 0.0, 1.0], radians=float(a)) for a in phi]
    n = len(phi)
    axis = pa.FixedSizeListArray.from_arrays(
        pa.array(np.tile(np.array([0.0, 0.0, 1.0], np.float32), n)),
        type=dtype.field("axis").type)
    return pa.StructArray.from_arrays([axis, pa.array(np.asarray(phi, np.float32))],
                                      fields=list(dtype))


def _send_scene(rec, rr, trajectory, frames: Frames) -> None:
    n = len(frames)
    index = _time(rr, frames)
    x, y, phi = frames.state[:, 0] * MM, frames.state[:, 1] * MM, frames.state[:, 2]
    rec.send_columns(COIN, indexes=index, columns=rr.Transform3D.columns(
        translation=np.column_stack([x, y, np.zeros(n)]),
        rotation_axis_angle=_rotations_about_z(phi)))

    colours = np.where(frames.contact, _rgba(CONTACT_COLOUR), _rgba(FREE_COLOUR)).astype(np.uint32)
    rec.send_columns(CORNERS, indexes=index, columns=rr.Points2D.columns(
        positions=frames.corners.reshape(-1, 2) * MM,
        colors=colours.reshape(-1)).partition(np.full(n, 4)))

    scene = trajectory.scene
    mask = frames.contact.reshape(-1)
    arrows = force_arrows(frames, scene.coin.mass * scene.g, scene.coin.diameter)
    vectors = arrows.reshape(-1, 2)[mask] * MM
    origins = frames.corners.reshape(-1, 2)[mask] * MM - vectors  # the tip on the corner
    magnitude = np.hypot(frames.forces[..., 0], frames.forces[..., 1]).reshape(-1)[mask]
    labels = np.char.mod("%.3g N", magnitude).tolist()
    rec.send_columns(FORCES, indexes=index, columns=rr.Arrows2D.columns(
        vectors=vectors, origins=origins, labels=labels).partition(frames.contact.sum(axis=1)))

    centre = np.column_stack([x, y])
    previous = np.vstack([centre[:1], centre[:-1]])
    segments = np.stack([previous, centre], axis=1)  # (N, 2, 2): one segment per frame
    rec.send_columns(PATH, indexes=index, columns=rr.LineStrips2D.columns(
        strips=segments).partition(np.ones(n, dtype=np.int64)))


def _send_plots(rec, rr, trajectory, frames: Frames) -> None:
    index = _time(rr, frames)
    for name, values in (("kinetic", frames.kinetic), ("gravitational", frames.gravitational),
                         ("elastic", frames.elastic), ("total", frames.total)):
        rec.send_columns(f"{ENERGY}/{name}", indexes=index,
                         columns=rr.Scalars.columns(scalars=values * MJ))
    ends = frames.t[[0, -1]]
    rec.send_columns(f"{ENERGY}/e_crit",
                     indexes=[rr.TimeColumn(TIMELINE, duration=_durations(ends))],
                     columns=rr.Scalars.columns(scalars=np.full(2, trajectory.e_crit * MJ)))
    rec.send_columns(f"{HEIGHT}/y", indexes=index,
                     columns=rr.Scalars.columns(scalars=frames.state[:, 1] * MM))
    rec.send_columns(f"{ANGLE}/quarter_turns", indexes=index,
                     columns=rr.Scalars.columns(scalars=frames.quarter_turns))
    rec.send_columns(f"{ANGLE}/n", indexes=index,
                     columns=rr.Scalars.columns(scalars=frames.n.astype(np.float64)))
    penetration = frames.penetration * UM
    for i in range(4):
        rec.send_columns(f"{PENETRATION}/corner{i}", indexes=index,
                         columns=rr.Scalars.columns(scalars=penetration[:, i]))


def _send_text_log(rec, rr, trajectory, frames: Frames) -> None:
    """One entry per contact onset and lift-off at its exact time, and the run's end."""
    times: list[float] = [0.0]
    init = trajectory.scene.initial
    texts = [f"throw: vy = {init.vy:g} m/s, vphi = {init.vphi:g} rad/s, phi0 = {init.phi0:g}, "
             f"y0 = {trajectory.scene.y0:.6g} m"]
    levels = ["INFO"]
    for row in frames.events:
        corner, kind = int(row[1]), int(row[2])
        times.append(float(row[0]))
        if kind > 0:
            texts.append(f"t = {row[0]:.9f} s: corner {corner} touches down (contact onset)")
        else:
            texts.append(f"t = {row[0]:.9f} s: corner {corner} lifts off")
        levels.append("DEBUG" if kind < 0 else "INFO")
    end = trajectory.t_final
    if trajectory.settled and not math.isnan(trajectory.settle_time):
        times.append(trajectory.settle_time)
        texts.append(f"t = {trajectory.settle_time:.9f} s: settled, energy below E_crit = "
                     f"{trajectory.e_crit * MJ:.4g} mJ, "
                     f"n = {trajectory.quarter_turns} is final ({trajectory.pose})")
        levels.append("INFO")
        if trajectory.scene.integration.stop_on_settle:
            times.append(end)
            texts.append("the run stops as soon as the outcome is certain, and so does this "
                         "recording (use --full to record the coin rocking until --t-end)")
            levels.append("INFO")
    for note in trajectory.notes:
        times.append(end)
        texts.append(note)
        levels.append("ERROR" if trajectory.status == "non-finite" else "WARN")
    rec.send_columns(EVENTS, indexes=[rr.TimeColumn(TIMELINE, duration=_durations(times))],
                     columns=rr.TextLog.columns(text=texts, level=levels))
