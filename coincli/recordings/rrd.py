"""Rerun recordings of one throw: the coin in a 2-D view with y up, time series of its energies,
height, angle and penetrations, contact events on the timeline, and a default blueprint.

The numbers come from :func:`coincli.simulate` run with ``sample_dt`` (the display rate) and
``record_events=True``; :func:`coincli.recordings.frames.build_frames` turns them into frames, and
:func:`write_recording` sends those to Rerun column by column (one ``send_columns`` call per
entity, never one ``log`` call per frame).

Rerun itself is imported lazily, inside the functions that need it, so that importing this
module (or anything that imports it) stays cheap and nothing below ``coincli.io`` depends on it.

Units in the recording: lengths in the scene and the height plot in millimetres, penetrations in
micrometres, energies in millijoules, angles as quarter turns 2 phi / pi (the coin's transform
carries phi in radians), forces in newtons (drawn as arrows, see :func:`force_arrows`).
"""

from __future__ import annotations

import math
import os
import uuid
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..charts.timeseries import with_samples
from ..enums import Status
from ..files import check_connect_url, check_rrd_path
from ..integrators.registry import setting_text
from ..models import horizon_text
from ..params import ParameterError, check_number
from ..version import __version__
from .frames import ARROW_PEAK_DIAMETERS, Frames, build_frames, force_arrows, friction_arrows
from .stream import APPLICATION_ID, open_stream, require_notebook, viewer_class

TIMELINE = "sim_time"

# Entity paths.
SCENE = "scene"  # origin of the 2-D view (screen coordinates, y down)
FOLLOW = "scene/follow"  # moves with the centroid: origin of the close-up view
WORLD = "scene/world"  # the physical plane, flipped so that y points up
COIN = "scene/world/coin"
COIN_BODY = "scene/world/coin/body"
COIN_FILL = "scene/world/coin/fill"
COIN_FACE = "scene/world/coin/face"
CORNERS = "scene/world/corners"
FORCES = "scene/world/forces"
FRICTION = "scene/world/friction"  # a scene with friction: each corner's friction force
PATH = "scene/world/path"
GROUND = "scene/world/ground"
ENERGY = "plots/energy"
HEIGHT = "plots/height"
ANGLE = "plots/angle"
PENETRATION = "plots/penetration"
CONTACT_FORCES = "plots/forces"  # a scene with friction: each corner's normal and friction force
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
FRICTION_COLOUR = (0, 175, 160, 255)
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
class RecordingInfo:
    """What :func:`write_recording` wrote and where."""

    rrd: Path | None
    connect: str | None
    spawn: bool
    frames: int
    events: int
    recording_id: str
    viewer: object | None = None  # the notebook's viewer (rerun.notebook.Viewer), if shown


def _rgba(colour) -> int:
    r, g, b, a = (tuple(colour) + (255,))[:4]
    return (r << 24) | (g << 16) | (b << 8) | a


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
    friction = scene is not None and scene.foundation.mu > 0
    close = {}
    if scene is not None:
        d = scene.coin.diameter * MM
        close["visual_bounds"] = rrb.VisualBounds2D(x_range=[-0.9 * d, 0.9 * d],
                                                    y_range=[-0.6 * d, 0.6 * d])
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Horizontal(
                    rrb.Spatial2DView(name="whole throw (y up, mm)", origin=SCENE,
                                      background=(250, 250, 250, 255),
                                      overrides={PATH: trail}, **view2d),
                    rrb.Spatial2DView(name="close-up, following the coin (mm)",
                                      origin=FOLLOW, contents=[f"{SCENE}/**"],
                                      background=(250, 250, 250, 255),
                                      overrides={PATH: trail}, **close),
                    column_shares=[3, 2],
                ),
                rrb.Tabs(
                    rrb.TextLogView(name="contact events", origin=EVENTS,
                                    columns=rrb.TextLogColumns(  # times are in the text
                                        timeline_columns=[],
                                        text_log_columns=["LogLevel", "Body"])),
                    rrb.TextDocumentView(name="parameters", origin=INFO),
                ),
                row_shares=[3, 2],
            ),
            rrb.Vertical(
                rrb.TimeSeriesView(name="energy [mJ]: total (white), kinetic (blue), "
                                        "gravitational (green), elastic (red), E_crit (purple)",
                                   origin=ENERGY, plot_legend=rrb.PlotLegend(visible=False)),
                rrb.TimeSeriesView(name="height y [mm]", origin=HEIGHT,
                                   plot_legend=rrb.PlotLegend(visible=False)),
                rrb.TimeSeriesView(name="angle 2φ/π (blue) and n = round(2φ/π) (red) [quarter "
                                        "turns]", origin=ANGLE,
                                   plot_legend=rrb.PlotLegend(visible=False)),
                rrb.TimeSeriesView(name="penetration of corners 0-3 [µm]", origin=PENETRATION,
                                   plot_legend=rrb.PlotLegend(rrb.Corner2D.RightTop)),
                *([rrb.TimeSeriesView(name="contact forces of corners 0-3 [N]: normal N (thick) "
                                           "and friction F_t (thin)", origin=CONTACT_FORCES,
                                      plot_legend=rrb.PlotLegend(rrb.Corner2D.RightTop))]
                  if friction else []),
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
    if frames is None:
        frames = build_frames(trajectory)

    with open_stream(_recording_name(trajectory), rrd=rrd_path, spawn=spawn, connect=connect,
                     port=port, flush_timeout=flush_timeout) as rec:
        _send_throw(rec, rr, trajectory, frames, log_every)
    return RecordingInfo(rrd=rrd_path, connect=connect, spawn=spawn, frames=len(frames),
                         events=len(frames.events), recording_id=str(rec.get_recording_id()))


def _recording_name(trajectory) -> str:
    init = trajectory.scene.initial
    return (f"coin simulate vy={init.vy:g} vphi={init.vphi:g} phi0={init.phi0:g} "
            f"({trajectory.scene.integration.method.label})")


def _send_throw(rec, rr, trajectory, frames: Frames, log_every: float | None) -> None:
    """Everything a recording of one throw holds, sent to the stream ``rec``."""
    rec.send_blueprint(blueprint(frames, trajectory.scene), make_active=True, make_default=True)
    _log_static(rec, rr, trajectory, frames, log_every)
    if len(frames):
        _send_scene(rec, rr, trajectory, frames)
        _send_plots(rec, rr, trajectory, frames)
    _send_text_log(rec, rr, trajectory, frames)


# -- the public recorder and the notebook's viewer -----------------------------------------------


def inline_viewer(trajectory, *, width: int | None = None, height: int | None = None,
                  log_every: float | None = None, frames: Frames | None = None):
    """A Rerun notebook viewer (``rerun.notebook.Viewer``, not yet displayed) holding the
    recording of ``trajectory`` (simulated again with samples every ``log_every`` seconds and
    its contact events if it kept none; ``frames``: those of its samples, if built already).
    NotebookMissing without rerun-notebook."""
    import rerun as rr

    viewer_type = viewer_class()
    run = with_samples(trajectory, log_every)
    if frames is None:
        frames = build_frames(run)
    rec = rr.RecordingStream(APPLICATION_ID, recording_id=uuid.uuid4())
    viewer = viewer_type(width=width, height=height, recording=rec)
    rec.send_recording_name(_recording_name(run))
    _send_throw(rec, rr, run, frames, run.sample_dt)
    rec.flush()
    return viewer


def show_inline(trajectory, *, width: int | None = None, height: int | None = None,
                log_every: float | None = None) -> None:
    """Display the recording of ``trajectory`` in the notebook's cell now
    (:meth:`coincli.Trajectory.show`); outside a notebook RuntimeError (one line, naming what
    to do instead)."""
    require_notebook("show()")
    inline_viewer(trajectory, width=width, height=height, log_every=log_every).display()


def record(trajectory, *, rrd: str | os.PathLike | None = None, spawn: bool = False,
           connect: str | None = None, notebook: bool = False, log_every: float | None = None,
           width: int | None = None, height: int | None = None) -> RecordingInfo:
    """Record one throw for Rerun's viewer: to the ``.rrd`` file ``rrd``, a new viewer
    (``spawn``), a running one (``connect``, ``rerun+http://host:port/proxy``) and/or inline in
    the notebook (``notebook``, ``width`` and ``height`` in pixels). ``log_every``: seconds of
    simulated time between frames; by default the trajectory's own samples, or every
    DEFAULT_LOG_EVERY s for a trajectory that kept none (it is then simulated again, keeping
    its samples and contact events). Returns what was written (``viewer``: the notebook's)."""
    if rrd is None and not spawn and connect is None and not notebook:
        raise ParameterError("record() needs a destination: rrd=PATH, spawn=True, connect=URL "
                             "or notebook=True")
    if log_every is not None:
        check_number("log_every", log_every, positive=True)
    if connect is not None:
        try:
            check_connect_url(connect)
        except ValueError:
            raise ParameterError(f"connect must be the URL of a running Rerun viewer, e.g. "
                                 f"rerun+http://127.0.0.1:9876/proxy, got {connect!r}") from None
    if notebook:
        require_notebook("record(notebook=True)")
    run = with_samples(trajectory, log_every)
    frames = build_frames(run)
    info = RecordingInfo(rrd=None, connect=None, spawn=False, frames=len(frames),
                         events=len(frames.events), recording_id="")
    if rrd is not None or spawn or connect is not None:
        info = write_recording(run, rrd=rrd, spawn=spawn, connect=connect, frames=frames,
                               log_every=run.sample_dt)
    if notebook:
        viewer = inline_viewer(run, width=width, height=height, frames=frames)
        viewer.display()
        info = replace(info, viewer=viewer)
    return info


def _log_static(rec, rr, trajectory, frames: Frames, log_every: float | None) -> None:
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
    friction = scene.foundation.mu > 0
    if friction:
        rec.log(FRICTION, rr.Arrows2D.from_fields(colors=[FRICTION_COLOUR], radii=0.3,
                                                  draw_order=26.0, show_labels=False),
                static=True)
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
        if friction:
            rec.log(f"{CONTACT_FORCES}/normal{i}",
                    rr.SeriesLines(colors=[colour], names=[f"N corner {i}"], widths=[2.5],
                                   aggregation_policy="MinMax"), static=True)
            rec.log(f"{CONTACT_FORCES}/tangential{i}",
                    rr.SeriesLines(colors=[colour], names=[f"F_t corner {i}"], widths=[1.0],
                                   aggregation_policy="MinMax"), static=True)

    params = _flat_parameters(trajectory, log_every)
    rec.log(INFO, rr.TextDocument(_info_markdown(trajectory, frames, log_every),
                                  media_type=rr.MediaType.MARKDOWN), static=True)
    rec.log(f"{INFO}/parameters", rr.AnyValues(**params), static=True)
    rec.send_property("coin", rr.AnyValues(version=__version__,
                                           method=scene.integration.method.label,
                                           dt=scene.integration.dt,
                                           rtol=scene.integration.rtol,
                                           outcome_n=trajectory.quarter_turns
                                           if trajectory.quarter_turns is not None else -1,
                                           status=trajectory.status.label))


def _flat_parameters(trajectory, log_every: float | None) -> dict:
    params: dict = {"version": __version__}
    for section, values in trajectory.scene.to_dict().items():
        if isinstance(values, dict):
            for key, value in values.items():
                params[f"{section}.{key}"] = value
        else:
            params[section] = values
    params["log_every"] = float(log_every) if log_every else float("nan")
    params["status"] = trajectory.status.label
    params["quarter_turns"] = (trajectory.quarter_turns if trajectory.quarter_turns is not None
                               else -1)
    params["e_crit"] = trajectory.e_crit
    return params


def _info_markdown(trajectory, frames: Frames, log_every: float | None) -> str:
    scene = trajectory.scene
    integ = scene.integration
    lines = [f"# coin simulate (coincli {__version__})", ""]
    if trajectory.quarter_turns is None:
        lines.append("**Outcome:** none, the run went non-finite.")
    else:
        lines.append(f"**Outcome:** n = {trajectory.quarter_turns} quarter turns, "
                     f"{trajectory.pose} ({trajectory.status.label}"
                     + (f" at t = {trajectory.settle_time:.6g} s" if trajectory.settled else "")
                     + ").")
    step = setting_text(integ.method, integ.dt, integ.rtol)
    lines += ["", f"**Method:** {integ.method.label}, {step}, {horizon_text(trajectory.scene)}, "
              + ("stop when settled" if integ.stop_on_settle else "full run"), ""]
    lines += ["| parameter | value |", "|---|---|"]
    for section, values in scene.to_dict().items():
        if isinstance(values, dict):
            for key, value in values.items():
                lines.append(f"| {section}.{key} | {value} |")
        else:
            lines.append(f"| {section} | {values} |")
    lines.append(f"| E_crit | {trajectory.e_crit * MJ:.6g} mJ |")
    lines += ["", _friction_markdown(trajectory)]
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
    if scene.foundation.mu > 0:
        lines[-1] += (" Friction forces: teal arrows along the ground into the corners they "
                      "act on, on the contact forces' scale; the plot of contact forces shows "
                      "each corner's normal force N (thick) and friction force F_t (thin).")
    if trajectory.notes:
        lines += [""] + [f"*Note:* {note}" for note in trajectory.notes]
    return "\n".join(lines)


def _friction_markdown(trajectory) -> str:
    """The recording's words on friction: its coefficient and slip velocity and the energy it
    took, or, without it, what a coefficient mu would take (about mu times the sliding work)."""
    foundation = trajectory.scene.foundation
    work, sliding, start = (trajectory.friction_work, trajectory.sliding_work,
                            trajectory.energy_initial)
    if foundation.mu > 0:
        text = (f"**Friction:** mu = {foundation.mu:g}, slip velocity "
                f"{foundation.slip_velocity:g} m/s (regularized Coulomb friction at each "
                "corner in contact, beside the paper's damper)")
        if work is not None and start > 0:
            text += (f"; it took {work * MJ:.4g} mJ, {100 * work / start:.3g} % of the throw's "
                     f"{start * MJ:.5g} mJ")
        return text + "."
    text = "**Friction:** none (mu = 0, the paper's model)"
    if sliding is not None and start > 0:
        text += (f"; a friction coefficient mu would take about mu x {sliding * MJ:.4g} mJ of "
                 f"the throw's {start * MJ:.5g} mJ")
    return text + "."


def _durations(seconds) -> np.ndarray:
    """Seconds as timedelta64[ns], rounded to the nearest nanosecond (Rerun would truncate)."""
    return np.round(np.asarray(seconds, dtype=np.float64) * 1e9).astype(np.int64).astype(
        "timedelta64[ns]")


def _time(rr, frames: Frames):
    return [rr.TimeColumn(TIMELINE, duration=_durations(frames.t))]


def _quaternions_about_z(phi: np.ndarray) -> np.ndarray:
    """The rotations by ``phi`` about +z as a column of quaternions (x, y, z, w): built in one
    numpy expression (one Python object a frame would cost ~5 us each)."""
    half = 0.5 * np.asarray(phi, dtype=np.float64)
    zeros = np.zeros_like(half)
    return np.column_stack([zeros, zeros, np.sin(half), np.cos(half)]).astype(np.float32)


def _send_scene(rec, rr, trajectory, frames: Frames) -> None:
    n = len(frames)
    index = _time(rr, frames)
    x, y, phi = frames.state[:, 0] * MM, frames.state[:, 1] * MM, frames.state[:, 2]
    rec.send_columns(COIN, indexes=index, columns=rr.Transform3D.columns(
        translation=np.column_stack([x, y, np.zeros(n)]),
        quaternion=_quaternions_about_z(phi)))
    # the close-up's frame: at the centroid, in screen coordinates (y down) like SCENE
    rec.send_columns(FOLLOW, indexes=index, columns=rr.Transform3D.columns(
        translation=np.column_stack([x, -y, np.zeros(n)])))

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
    if scene.foundation.mu > 0 and frames.tangential is not None:
        _send_friction(rec, rr, index, frames, scene)

    centre = np.column_stack([x, y])
    previous = np.vstack([centre[:1], centre[:-1]])
    segments = np.stack([previous, centre], axis=1)  # (N, 2, 2): one segment per frame
    rec.send_columns(PATH, indexes=index, columns=rr.LineStrips2D.columns(
        strips=segments).partition(np.ones(n, dtype=np.int64)))


def _send_friction(rec, rr, index, frames: Frames, scene) -> None:
    """The friction arrows: along the foundation, the tip on the corner it acts on (as the
    contact forces), on their scale, |F_t| in the label."""
    pushed = frames.contact & (frames.tangential != 0.0)
    mask = pushed.reshape(-1)
    arrows = friction_arrows(frames, scene.coin.mass * scene.g, scene.coin.diameter)
    vectors = arrows.reshape(-1, 2)[mask] * MM
    origins = frames.corners.reshape(-1, 2)[mask] * MM - vectors
    labels = np.char.mod("friction %.3g N", np.abs(frames.tangential.reshape(-1)[mask])).tolist()
    rec.send_columns(FRICTION, indexes=index, columns=rr.Arrows2D.columns(
        vectors=vectors, origins=origins, labels=labels).partition(pushed.sum(axis=1)))


def _send_plots(rec, rr, trajectory, frames: Frames) -> None:
    """The time series, of the simulated frames only (not the implied rest pose)."""
    if frames.implied is not None and frames.implied.any():
        frames = frames.subset(~frames.implied)
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
    if trajectory.scene.foundation.mu > 0 and frames.normal is not None:
        for i in range(4):
            rec.send_columns(f"{CONTACT_FORCES}/normal{i}", indexes=index,
                             columns=rr.Scalars.columns(scalars=frames.normal[:, i]))
            rec.send_columns(f"{CONTACT_FORCES}/tangential{i}", indexes=index,
                             columns=rr.Scalars.columns(scalars=frames.tangential[:, i]))


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
        if frames.implied is not None and frames.implied.any():
            times.append(float(frames.t[frames.implied][0]))
            texts.append(f"at rest in the well n = {trajectory.quarter_turns} "
                         f"({trajectory.pose}): implied by its energy, not simulated")
            levels.append("INFO")
    for note in trajectory.notes:
        times.append(end)
        texts.append(note)
        levels.append("ERROR" if trajectory.status == Status.NONFINITE else "WARN")
    rec.send_columns(EVENTS, indexes=[rr.TimeColumn(TIMELINE, duration=_durations(times))],
                     columns=rr.TextLog.columns(text=texts, level=levels))
