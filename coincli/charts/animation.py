"""An animation of one throw drawn with matplotlib, to share where Rerun's viewer is not at hand
(it exports no video): the coin as a rectangle of its diameter and thickness over the
foundation's surface, its corners red while in contact and blue while free, its +y face
purple, the path of its centroid in grey, the time in a corner.

A GIF is written with Pillow (installed with matplotlib); an MP4 with ffmpeg, when it is on PATH.
The figure is a bare :class:`matplotlib.figure.Figure` on an Agg canvas: no pyplot, no change to
the backend of a notebook the function is called from.
"""

from __future__ import annotations

import itertools
import math
import numbers
import os
import shutil
from pathlib import Path

import numpy as np

from ..defaults import DEFAULT_FPS, DEFAULT_SECONDS
from ..files import atomic_output, check_writable
from ..params import ParameterError
from ..recordings.frames import Frames, build_frames
from .timeseries import with_samples

FORMATS = (".gif", ".mp4")
MAX_FRAMES = 1000  # 40 s at 25 fps (a GIF's frames are held in memory: 0.2-0.5 MB each)
NO_FFMPEG = "writing an .mp4 needs ffmpeg on PATH (install it, e.g. apt install ffmpeg), or " \
    "write a .gif"

MM = 1e3
FREE = "#50a0ff"
CONTACT = "#eb3228"
COIN_EDGE = "#cda528"
COIN_FILL = "#cda52870"
FACE = "#9628a0"
GROUND = "#785a3c"
PATH = "#969696"


def check_animation_path(path: str | os.PathLike) -> Path:
    """``path`` as a Path, or ParameterError unless it ends in .gif, or in .mp4 with ffmpeg on
    PATH; the OSError a user should see unless it can be written (:func:`check_writable`)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise ParameterError(f"an animation is written as {' or '.join(FORMATS)} (by the file "
                             f"name's ending), got {str(path)!r}")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ParameterError(NO_FFMPEG)
    return check_writable(path, what="animation")


def frame_times(t0: float, t1: float, fps: int, seconds: float) -> np.ndarray:
    """The simulated times shown, one per frame of ``seconds`` at ``fps``: evenly spaced from the
    start to the end of the throw."""
    count = max(2, min(MAX_FRAMES, round(fps * seconds)))
    return np.linspace(t0, t1, count)


def animate(trajectory, path: str | os.PathLike, *, fps: int | None = None,
            seconds: float | None = None, dpi: int = 80) -> Path:
    """Write an animation of ``trajectory`` to ``path`` (``.gif``, or ``.mp4`` with ffmpeg):
    ``seconds`` long on screen (default 4 s, the throw slowed or sped to fit) at ``fps`` frames
    a second (default 25), each frame the state at or just before its simulated time. A
    trajectory without samples and contact events is simulated again with them. Written
    through a temporary file renamed into place: complete or absent. Returns the path."""
    path = check_animation_path(path)
    fps = DEFAULT_FPS if fps is None else fps
    seconds = DEFAULT_SECONDS if seconds is None else seconds
    if isinstance(fps, bool) or not isinstance(fps, numbers.Integral) or not 1 <= fps <= 100:
        raise ParameterError(f"fps must be a whole number of frames a second from 1 to 100, "
                             f"got {fps!r}")
    longest = MAX_FRAMES / fps
    if isinstance(seconds, bool) or not isinstance(seconds, numbers.Real) or \
            not math.isfinite(seconds) or not 0 < seconds <= longest:
        raise ParameterError(f"seconds must be > 0 and at most {longest:g} at {fps} frames a "
                             f"second, got {seconds!r}")
    frames = build_frames(with_samples(trajectory))
    if not len(frames):
        raise ParameterError("the trajectory has no finite state to draw")
    shown = np.searchsorted(frames.t, frame_times(frames.t[0], frames.t[-1], fps, seconds),
                            side="right") - 1
    pictures = _pictures(trajectory, frames, shown, dpi)
    with atomic_output(path) as tmp:
        if path.suffix.lower() == ".gif":
            _write_gif(tmp, pictures, fps)
        else:
            _write_mp4(tmp, pictures, fps)
    return path


def _write_gif(path: Path, pictures, fps: int) -> None:
    from PIL import Image

    images = [Image.fromarray(rgb).quantize(256, method=Image.Quantize.FASTOCTREE)
              for rgb in pictures]  # 6 ms a frame (an adaptive palette: 35)
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:],
                   duration=round(1000 / fps), loop=0)


def _write_mp4(path: Path, pictures, fps: int) -> None:
    """H.264 by ffmpeg, fed the frames as raw RGB on its standard input."""
    import subprocess

    first = next(pictures)
    height, width = first.shape[:2]
    command = [shutil.which("ffmpeg") or "ffmpeg", "-y", "-loglevel", "error", "-f", "rawvideo",
               "-pix_fmt", "rgb24", "-s", f"{width}x{height}", "-r", str(fps), "-i", "-",
               "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-pix_fmt",
               "yuv420p", "-f", "mp4", str(path)]
    with subprocess.Popen(command, stdin=subprocess.PIPE, stderr=subprocess.PIPE) as ffmpeg:
        try:
            for rgb in itertools.chain([first], pictures):
                ffmpeg.stdin.write(np.ascontiguousarray(rgb).tobytes())
            ffmpeg.stdin.close()
        except BrokenPipeError:
            pass  # ffmpeg stopped: its message and exit status follow
        except BaseException:
            ffmpeg.kill()
            raise
        why = ffmpeg.stderr.read().decode(errors="replace").strip()
        if ffmpeg.wait() != 0:
            last = why.splitlines()[-1] if why else f"exit status {ffmpeg.returncode}"
            raise RuntimeError(f"ffmpeg could not write the video: {last}")


def _pictures(trajectory, frames: Frames, shown: np.ndarray, dpi: int):
    """The frames' pictures, (height, width, 3) uint8 RGB each, one for every row of ``frames``
    in ``shown``. The axes, the ground and the labels are drawn once; each frame redraws only
    what moves over them."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    figure, moving, draw = _figure(trajectory, frames, dpi)
    canvas = FigureCanvasAgg(figure)
    for artist in moving:
        artist.set_animated(True)
    canvas.draw()
    background = canvas.copy_from_bbox(figure.bbox)
    for row in shown:
        draw(int(row))
        canvas.restore_region(background)
        for artist in moving:
            figure.draw_artist(artist)
        yield np.asarray(canvas.buffer_rgba())[..., :3].copy()


def _figure(trajectory, frames: Frames, dpi: int):
    """The figure, the artists that move, and a function setting them to frame ``i``."""
    from matplotlib.figure import Figure
    from matplotlib.patches import Polygon

    scene = trajectory.scene
    corners = frames.corners * MM  # (N, 4, 2)
    d = scene.coin.diameter * MM
    x0, x1 = float(corners[..., 0].min()) - 0.5 * d, float(corners[..., 0].max()) + 0.5 * d
    y0 = min(float(corners[..., 1].min()), 0.0) - 0.3 * d
    y1 = float(corners[..., 1].max()) + 0.3 * d
    if x1 - x0 < y1 - y0:  # a throw straight up: widened to a square, not a tall strip
        middle, half = 0.5 * (x0 + x1), 0.5 * (y1 - y0)
        x0, x1 = middle - half, middle + half
    width = 6.0
    height = max(width * (y1 - y0) / (x1 - x0), 2.5)
    figure = Figure(figsize=(width, height), dpi=dpi, layout="constrained")
    ax = figure.add_subplot()
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.axhspan(y0 - d, 0.0, color=GROUND, alpha=0.15, lw=0)
    ax.axhline(0.0, color=GROUND, lw=1.5)
    centre = frames.state[:, :2] * MM
    (path_line,) = ax.plot([], [], color=PATH, lw=1.0)
    coin = ax.add_patch(Polygon(corners[0], closed=True, facecolor=COIN_FILL,
                                edgecolor=COIN_EDGE, lw=1.5))
    (face,) = ax.plot([], [], color=FACE, lw=2.0)  # corners 2-3: the +y face
    dots = ax.scatter(corners[0, :, 0], corners[0, :, 1], s=18, zorder=3)
    init = scene.initial
    ax.set_title(f"vy0 = {init.vy:g} m/s, vphi0 = {init.vphi:g} rad/s, phi0 = {init.phi0:g}: "
                 + (f"n = {trajectory.quarter_turns} ({trajectory.pose})"
                    if trajectory.quarter_turns is not None else trajectory.status.label),
                 fontsize=9)
    clock = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=9)

    def draw(i: int) -> None:
        coin.set_xy(corners[i])
        face.set_data(corners[i, 2:, 0], corners[i, 2:, 1])
        dots.set_offsets(corners[i])
        dots.set_color([CONTACT if touching else FREE for touching in frames.contact[i]])
        path_line.set_data(centre[:i + 1, 0], centre[:i + 1, 1])
        rest = frames.implied is not None and frames.implied[i]
        clock.set_text("at rest (implied by its energy)" if rest else f"t = {frames.t[i]:.4f} s")

    figure.canvas.draw()  # the layout, made once and kept: only the moving artists change
    figure.set_layout_engine("none")
    return figure, (path_line, coin, face, dots, clock), draw


__all__ = ["DEFAULT_FPS", "DEFAULT_SECONDS", "FORMATS", "NO_FFMPEG", "animate",
           "check_animation_path", "frame_times"]
