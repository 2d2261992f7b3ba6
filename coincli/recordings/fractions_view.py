"""`coin fractions` in Rerun as it runs (:class:`FractionsRecorder`): each probability with its
95 % band against the samples counted, or, over a parameter, against the parameter as each value
finishes, or, over a grid of two, maps of P(standing) that fill in as the points finish; the
leading n; what the run draws, as text."""

from __future__ import annotations

import math

import numpy as np

from ..defaults import display_unit
from .basin_view import INFO
from .stream import Destination, InProcessRecording

# -- coin fractions ------------------------------------------------------------------------------
ESTIMATE = "estimate"  # P(outcome) in % against the samples counted


LEADING_N = "leading_n"


OVER = "over"  # P(outcome) in % against the parameter of a continuation


SAMPLES = "samples"


MAP = "map"  # a grid's maps of P(standing): map/certain and map/decided, each an image
POINTS_DONE = "points_done"  # the timeline of a grid: the points finished
MAP_TOP = 0.5  # P(standing) at the top of the maps' colour scale (viridis, from 0)
MAP_BASES = (("certain", "P(standing), certain labels"),
             ("decided", "P(standing), all decided labels"))


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


class FractionsRecorder(InProcessRecording):
    """The live recording of a `coin fractions` run: :meth:`progress` takes each
    FractionsProgress; :meth:`result` the run's result (a continuation's values are sent as
    they finish, and all of them again from the result, which is what counts). A recording
    that cannot be made leaves ``error`` set and the run alone."""

    def __init__(self, plan, where: Destination):

        super().__init__(where)
        self.plan = plan
        self.verified = plan.scene.integration.verify
        self.sent: set[int] = set()  # values of a continuation sent
        self.values_done = 0
        self.grid = len(plan.parameters) > 1
        self.points: dict[int, dict] = {}  # a grid's points sent: {basis: (P, low, high)}
        if plan.parameter is not None:
            self.timeline, self.power = parameter_timeline(
                plan.parameter, display_unit(plan.parameter), plan.values)

    def __enter__(self):
        import rerun as rr

        if not self.open("coin fractions" + (f" over {' and '.join(self.plan.parameters)}"
                                               if self.plan.parameters else "")):
            return self
        rec = self.rec
        if self.grid:
            rec.send_blueprint(grid_blueprint(), make_active=True, make_default=True)
            rec.log(INFO, rr.TextDocument(self._info(), media_type=rr.MediaType.MARKDOWN),
                    static=True)
            return self
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
        if self.grid:
            first, second = plan.parameters
            lines += [f"Over {first} (across, left to right) and {second} (up, bottom to "
                      f"top), {' x '.join(str(n) for n in plan.shape)} points, one pixel a "
                      "point, filled in as each point finishes (timeline "
                      f"`{POINTS_DONE}`); colour: P(standing) from 0 (dark violet) to "
                      f"{100 * MAP_TOP:g} % (yellow) and above; white dots: the points whose "
                      "95 % interval holds 1/3 (the band of the line P = 1/3); hover a dot "
                      "for its values.", "",
                      *(f"- {name}: {', '.join(f'{v:g}' for v in values)} "
                        f"{display_unit(name)}".rstrip() for name, values
                        in zip(plan.parameters, plan.axes, strict=True))]
        elif plan.parameter is not None:
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
        if self.grid:
            if update.values_done > self.values_done:  # this point just met its goal
                self._send_point(update.value, _bases(update.tally, self.verified))
            self.values_done = update.values_done
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

    def _send_point(self, v: int, bases: dict) -> None:
        """A grid's point finished: both maps again, with it, at the next points_done."""
        import rerun as rr

        self.points[v] = bases
        self.rec.set_time(POINTS_DONE, sequence=len(self.points))
        for name, _ in MAP_BASES:
            image, centres, labels, band = grid_layers(self.plan, self.points, name)
            self.rec.log(f"{MAP}/{name}", rr.Image(image, draw_order=0.0))
            self.rec.log(f"{MAP}/{name}/points", rr.Points2D(
                centres, labels=labels, show_labels=False, draw_order=1.0,
                radii=np.where(band, 0.22, 0.06),
                colors=np.where(band[:, None], [255, 255, 255, 255], [90, 90, 90, 255])))

    def result(self, result) -> None:
        """The run's result: a continuation's every value, from it."""
        if self.rec is None or not self.plan.parameters:
            return
        if self.grid:
            for v, r in enumerate(result.results):
                if v not in self.points:
                    self._send_point(v, {"certain": _row(r.standing),
                                         "decided": _row(r.all_decided["standing"])})
            return
        for v, r in enumerate(result.results):
            if v in self.sent:  # sent as it finished, with these same counts
                continue
            self._send_value(v, {name: tuple(100.0 * getattr(r, name)[key] for key in
                                             ("probability", "low", "high"))
                                 for name in ("standing", "lying", "uncertain")})


def _row(row: dict) -> tuple[float, float, float]:
    return row["probability"], row["low"], row["high"]


def _bases(tally, verified: bool) -> dict:
    """{"certain": (P, low, high), "decided": ...} of P(standing) from a tally."""
    from ..montecarlo.tally import summary

    s = summary(tally, verified)
    return {"certain": _row(s["standing"]), "decided": _row(s["all_decided"]["standing"])}


def grid_layers(plan, points: dict, basis: str, level: float = 1 / 3):
    """A grid's map of P(standing) over ``basis`` from the ``points`` finished ({flat index:
    {basis: (P, low, high)}}): an RGBA image, one pixel a point (the first parameter across,
    the second up; transparent where not finished), and of the finished points their pixels'
    centres, their labels and whether their 95 % interval holds ``level``."""
    from matplotlib import colormaps

    nx, ny = plan.shape
    image = np.zeros((ny, nx, 4), dtype=np.uint8)
    colour = colormaps["viridis"]
    centres, labels, band = [], [], []
    for v, bases in sorted(points.items()):
        i, j = np.unravel_index(v, plan.shape)
        p, low, high = bases[basis]
        if math.isnan(p):
            continue
        image[ny - 1 - j, i] = np.round(255 * np.asarray(colour(min(p / MAP_TOP, 1.0))))
        centres.append((i + 0.5, ny - 1 - j + 0.5))
        labels.append(f"{plan.label(v)}: P(standing) {100 * p:.3g} % "
                      f"({100 * low:.3g}-{100 * high:.3g})")
        band.append(low <= level <= high)
    return (image, np.asarray(centres, dtype=np.float32).reshape(-1, 2), labels,
            np.asarray(band, dtype=bool))


def grid_blueprint():
    """A grid's two maps side by side (certain labels, all decided labels), the run's text
    beside them."""
    import rerun.blueprint as rrb

    maps = [rrb.Spatial2DView(name=label, origin=f"{MAP}/{name}") for name, label in MAP_BASES]
    return rrb.Blueprint(
        rrb.Horizontal(*maps, rrb.TextDocumentView(name="run", origin=INFO),
                       column_shares=[2, 2, 1]),
        rrb.BlueprintPanel(state="collapsed"), rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(state="collapsed"))


__all__ = ["FractionsRecorder", "fractions_blueprint", "grid_blueprint", "grid_layers",
           "parameter_timeline"]
