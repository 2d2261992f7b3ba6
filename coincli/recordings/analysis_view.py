"""`coin basin analyze` in Rerun as it runs (:class:`AnalysisRecorder`): the map analysed with its
bands, each region's uncertain fraction f(eps) against log10 eps as it is measured, the fitted
lines, and the measures as a Markdown table."""

from __future__ import annotations

import math

import numpy as np

from ..stores.dataset import Basin
from .basin_view import BACKGROUND, BASIN, BasinStream, axes_text, rgb
from .fractions_view import parameter_timeline
from .stream import Destination, InProcessRecording

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

    horizontal, vertical = axes_text(attrs)
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
        from ..charts.analysis import band_colours

        super().__init__(where)
        self.basin = basin
        self.eps = np.asarray(eps, dtype=np.float64)
        self.timeline, self.power = parameter_timeline("log10 eps", "", self._log_eps(self.eps))
        self.colours = [rgb(c) for c in band_colours(bands)]
        self.edges: set[int] = set()  # the rows of the band edges drawn
        self.lines = ["# coin basin analyze", "", "Measuring: the map first, then f(eps) band "
                      "by band with the simulator."]

    def __enter__(self):
        import rerun as rr

        basin = self.basin
        if not self.open(f"coin basin analyze {basin.path or ''}".strip()):
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


__all__ = ["AnalysisRecorder", "analysis_blueprint", "analysis_markdown"]
