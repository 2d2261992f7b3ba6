"""`coin fractions` in Rerun as it runs (:class:`FractionsRecorder`): each probability with its
95 % band against the samples counted, or, over a parameter, against the parameter as each value
finishes; the leading n; what the run draws, as text."""

from __future__ import annotations

import math

import numpy as np

from .basin_view import INFO
from .rerun_stream import Destination, InProcessRecording

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


class FractionsRecorder(InProcessRecording):
    """The live recording of a `coin fractions` run: :meth:`progress` takes each
    FractionsProgress; :meth:`result` the run's result (a continuation's values are sent as
    they finish, and all of them again from the result, which is what counts). A recording
    that cannot be made leaves ``error`` set and the run alone."""

    def __init__(self, plan, where: Destination):
        from ..defaults import PARAMETER_UNITS
        from ..integrators.ladder import ladder_of

        super().__init__(where)
        self.plan = plan
        self.verified = ladder_of(plan.scene.integration).verified
        self.sent: set[int] = set()  # values of a continuation sent
        self.values_done = 0
        if plan.parameter is not None:
            self.timeline, self.power = parameter_timeline(
                plan.parameter, PARAMETER_UNITS[plan.parameter], plan.values)

    def __enter__(self):
        import rerun as rr

        if not self.open("coin fractions" + (f" over {self.plan.parameter}"
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


__all__ = ["FractionsRecorder", "fractions_blueprint", "parameter_timeline"]
