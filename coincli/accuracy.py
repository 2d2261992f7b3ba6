"""Work-precision study: how accurate each method is for what it costs, and where it fails.

Pure computation (arrays and dataclasses, no printing, no files); ``coin accuracy`` and
``coin bench`` present the results.

* Trajectory error: the state at a fixed time after the first few impacts (before chaos
  amplifies differences), against a converged reference, for a handful of throws.
* Label error: the fraction of cells of a small basin grid whose n differs from the reference,
  counted on the *robust* cells only (where two independent converged references agree), since
  elsewhere no affordable computation decides n (NOTES.md).
* Cost: CPU seconds per trajectory, measured on the grid itself.
"""

from __future__ import annotations

import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from .enums import Certainty, Method, Status
from .grid import Grid, make_grid
from .integrators import METHODS
from .integrators.batch import new_control
from .labeller import Labeller
from .models import model_of
from .params import Scene, state_array
from .stats import wilson


# The two references. A: the event method at a tolerance far below any setting on the chart.
# B: fixed-step RK4 -- no event location, no closed-form flight, no shared stepping code.
@dataclass(frozen=True)
class Setting:
    """One point of a study: a method and the knob that sets its accuracy."""

    method: Method
    dt: float
    rtol: float
    verify: bool = False  # climb the verification ladder from this setting

    def __post_init__(self):
        object.__setattr__(self, "method", Method.parse(self.method))

    @property
    def adaptive(self) -> bool:
        return METHODS[self.method].adaptive

    @property
    def knob(self) -> float:
        """The number that sets the accuracy: rtol for adaptive methods, the step otherwise."""
        return self.rtol if self.adaptive else self.dt

    @property
    def label(self) -> str:
        return (f"{self.method.label} {'rtol' if self.adaptive else 'h'}={self.knob:g}"
                + (" verified" if self.verify else ""))

    def apply(self, scene: Scene, **extra) -> Scene:
        return scene.with_overrides(method=self.method, dt=self.dt,
                                    rtol=self.rtol if self.adaptive else None,
                                    verify=self.verify, **extra)


REFERENCE_A = Setting(Method.EVENT, 1e-6, 1e-12)
REFERENCE_B = Setting(Method.RK4, 2.5e-7, 0.0)
# With friction (a stiff model: coincli.models.Model.stiff) the event reference is the event
# method's switching pair, event_rodas (Rodas5P where a corner sticks: the explicit pair alone
# would crawl through every stick at its stability limit), and RK4's step is halved: without
# events its error comes from the contact onsets and the kinks of the friction law (max(0, N),
# the stick), a low order, and at mu = 1 its labels still move between h = 2e-7 and 5e-8 on
# long rolling throws (tests/test_friction.py).
REFERENCE_A_STIFF = Setting(Method.EVENT_RODAS, 1e-6, 1e-12)
REFERENCE_B_STIFF = Setting(Method.RK4, 1.25e-7, 0.0)


def references_of(scene: Scene) -> tuple[Setting, Setting]:
    """The two references (A: the event method, B: fixed-step RK4) for ``scene``'s model."""
    if model_of(scene).stiff:
        return REFERENCE_A_STIFF, REFERENCE_B_STIFF
    return REFERENCE_A, REFERENCE_B


LADDERS: dict[Method, list[float]] = {
    Method.SYMPLECTIC_EULER: [1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7],
    Method.VERLET: [1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7],
    Method.RK4: [2e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6],
    Method.DOPRI5: [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    Method.EVENT: [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    Method.EVENT_DOP853: [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    Method.EVENT_RODAS: [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    Method.EVENT_DOP853_RODAS: [1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
}
PAPER_SETTING = Setting(Method.SYMPLECTIC_EULER, 1e-6, 1e-7)


def ladder_settings(methods: list[Method] | None = None) -> list[Setting]:
    """Every setting of the methods' ladders. A switching pair (the registry's
    ``stiff_variant``: event_rodas, event_dop853_rodas) runs exactly as its explicit method on
    every scene (the explicit pair where the law is not stiff; and a friction scene runs its
    explicit methods on their switching pairs), so it is left out where that method is in the
    list too: the same points twice."""
    methods = [Method.parse(m) for m in (methods or list(LADDERS))]
    same = {METHODS[m].stiff_variant for m in methods}
    out = []
    for method in methods:
        if method in same:
            continue
        for knob in LADDERS[method]:
            if METHODS[method].adaptive:
                out.append(Setting(method, 1e-6, knob))
            else:
                out.append(Setting(method, knob, 1e-7))
    return out


def verified_default(scene: Scene) -> Setting:
    """The scene's own setting, verified: what `coin basin` and `coin simulate` run."""
    integ = scene.integration
    return Setting(integ.method, integ.dt, integ.rtol, verify=True)


def vy_vphi_grid(scene: Scene, vy=(0.05, 2.0), vphi=(-20.0, 20.0), res=(32, 32)) -> Grid:
    """The (vy0, vphi0) grid of the studies, the other initial conditions from the scene."""
    return make_grid(scene, {"vy": tuple(vy), "vphi": tuple(vphi)}, tuple(res), tuple(res))


@dataclass
class GridRun:
    setting: Setting
    quarter_turns: np.ndarray  # int16, shape of the grid
    status: np.ndarray
    cpu_seconds: float  # summed over threads
    wall_seconds: float
    certainty: np.ndarray | None = None  # uint8 Certainty of a verified setting

    @property
    def cpu_per_trajectory(self) -> float:
        return self.cpu_seconds / self.quarter_turns.size


def run_grid(scene: Scene, setting: Setting, grid: Grid, threads: int = 2,
             stop_on_settle: bool = True, t_end: float | None = None) -> GridRun:
    """Label every cell of ``grid`` with ``setting``, on ``threads`` threads (the kernel
    releases the GIL). CPU time is the thread time of the workers, so it does not count the
    other processes of a shared machine."""
    run_scene = setting.apply(scene, stop_on_settle=stop_on_settle, t_end=t_end)
    labeller = Labeller.of(run_scene)
    states = grid.states()
    n = states.shape[0]
    n_out = np.empty(n, np.int16)
    st_out = np.empty(n, np.uint8)
    certainty = np.empty(n, np.uint8)
    labeller.load(states[0])  # before timing
    # interleave cells across threads so each gets a fair share of hard and easy cells
    parts = [np.arange(i, n, threads) for i in range(threads)]

    control = new_control()

    def work(idx):
        start = time.thread_time()
        labels = labeller.label(states[idx], control)
        if setting.verify:
            certainty[idx] = labels.certainty
        n_out[idx], st_out[idx] = labels.quarter_turns, labels.status
        return time.thread_time() - start

    wall = time.perf_counter()
    with ThreadPoolExecutor(threads) as pool:
        try:
            cpu = sum(pool.map(work, parts))
        except KeyboardInterrupt:  # stop the kernels in flight at once, not at their end
            control[0] = 1
            raise
    wall = time.perf_counter() - wall
    return GridRun(setting, n_out.reshape(grid.shape), st_out.reshape(grid.shape), cpu, wall,
                   certainty.reshape(grid.shape) if setting.verify else None)


def label_error(run: GridRun, reference: np.ndarray, robust: np.ndarray) -> float:
    """Fraction of robust cells whose label differs from the reference (a non-finite or
    unsettled cell counts as wrong). For a verified run, the cells it calls certain and gets
    wrong (its uncertain cells are counted by :func:`uncertain_fraction`)."""
    ok = (run.quarter_turns == reference) & (run.status == Status.SETTLED)
    if run.certainty is not None:
        ok |= run.certainty != Certainty.CERTAIN
    return float(np.mean(~ok[robust])) if robust.any() else math.nan


def uncertain_fraction(run: GridRun, robust: np.ndarray) -> float:
    """Fraction of robust cells a verified run flags uncertain (NaN for a single pass)."""
    if run.certainty is None or not robust.any():
        return math.nan
    return float(np.mean(run.certainty[robust] != Certainty.CERTAIN))


# -- trajectory error ------------------------------------------------------------------------------
# (vy0, vphi0, t): each throw is compared ~0.06 s after its first impact, a few impacts in and
# before chaos amplifies differences (there a 1e-10 nudge of vy0 still moves the state < 1e-8).
TRAJECTORY_THROWS = [(0.4, 6.0, 0.15), (0.6, -9.0, 0.18), (0.75, 3.0, 0.21), (0.5, -14.0, 0.15),
                     (0.3, 11.0, 0.12)]


def state_at(scene: Scene, setting: Setting, t: float) -> np.ndarray:
    """State at time t (no early stop). Fixed steps land on t exactly when dt divides it."""
    run_scene = setting.apply(scene, t_end=t, stop_on_settle=False)
    return Labeller.of(run_scene).final_state(state_array(run_scene))[0]


def state_error(scene: Scene, a: np.ndarray, b: np.ndarray) -> float:
    """Largest component difference in the coin's natural units (r for positions, 1 rad,
    sqrt(2 g r) for speeds, sqrt(2 g r) / r for the spin)."""
    r = scene.coin.r
    v_ref = math.sqrt(2 * scene.g * r)
    scale = np.array([r, r, 1.0, v_ref, v_ref, v_ref / r])
    diff = np.abs(a - b) / scale
    return float(np.max(diff)) if np.all(np.isfinite(diff)) else math.inf


def trajectory_error(scene: Scene, setting: Setting, references: list[np.ndarray]) -> float:
    """Median over TRAJECTORY_THROWS of the state error at each throw's comparison time."""
    errors = []
    for (vy, vphi, t), ref in zip(TRAJECTORY_THROWS, references, strict=True):
        throw = scene.with_overrides(vy=vy, vphi=vphi)
        errors.append(state_error(scene, state_at(throw, setting, t), ref))
    return float(np.median(errors))


def reference_states(scene: Scene, setting: Setting) -> list[np.ndarray]:
    return [state_at(scene.with_overrides(vy=vy, vphi=vphi), setting, t)
            for vy, vphi, t in TRAJECTORY_THROWS]


# -- the study ------------------------------------------------------------------------------------
@dataclass
class Point:
    setting: Setting
    trajectory_error: float
    label_error: float  # of a verified setting: certain and wrong
    cpu_per_trajectory: float
    nonfinite: int
    unsettled: int
    uncertain: float = math.nan  # of a verified setting: flagged uncertain


@dataclass
class Study:
    grid: Grid
    reference_a: GridRun
    reference_b: GridRun
    robust: np.ndarray
    reference_agreement: float  # fraction of all cells where A and B agree
    trajectory_reference_gap: float  # state error between the two trajectory references
    points: list[Point] = field(default_factory=list)
    paper_point: Point | None = None
    verified_point: Point | None = None  # the scene's own setting, verified

    @property
    def robust_cells(self) -> int:
        return int(self.robust.sum())

    def best_under(self, max_label_error: float = 0.01) -> Point | None:
        """The cheapest setting whose label error on the robust cells is below the bound with
        95 % confidence (the upper end of the Wilson interval), so that a handful of cells on a
        small grid cannot pick a setting that is below it by luck."""
        ok = [p for p in self.points
              if wilson_upper(p.label_error, self.robust_cells) < max_label_error]
        return min(ok, key=lambda p: p.cpu_per_trajectory) if ok else None


def wilson_upper(fraction: float, n: int) -> float:
    """Upper end of the 95 % Wilson interval of a proportion observed on n trials."""
    if n == 0 or not math.isfinite(fraction):
        return math.inf
    return wilson(round(fraction * n), n)[1]


@dataclass
class References:
    """The two converged references on a grid and the cells where they agree."""

    a: GridRun
    b: GridRun

    @property
    def robust(self) -> np.ndarray:
        """Cells where both references settle to the same n: the only cells on which a label
        can be called right or wrong (elsewhere no affordable computation decides n)."""
        return ((self.a.status == Status.SETTLED) & (self.b.status == Status.SETTLED)
                & (self.a.quarter_turns == self.b.quarter_turns))

    @property
    def agreement(self) -> float:
        """Fraction of all cells where the references give the same n."""
        return float(np.mean(self.a.quarter_turns == self.b.quarter_turns))


def run_references(scene: Scene, grid: Grid, threads: int = 2, progress=None) -> References:
    say = progress or (lambda text: None)
    reference_a, reference_b = references_of(scene)
    say(f"reference A: {reference_a.label}")
    ref_a = run_grid(scene, reference_a, grid, threads)
    say(f"reference B: {reference_b.label}")
    return References(ref_a, run_grid(scene, reference_b, grid, threads))


def run_study(scene: Scene, grid: Grid, settings: list[Setting], threads: int = 2,
              progress=None, verified: bool = True) -> Study:
    """The whole work-precision study. ``progress(text)`` is called before each piece. With
    ``verified``, the scene's own setting verified (what `coin basin` runs) is a point too:
    its label error counts the cells it calls certain and gets wrong; its uncertain cells are
    counted apart."""
    say = progress or (lambda text: None)
    refs = run_references(scene, grid, threads, say)
    ref_a, ref_b, robust = refs.a, refs.b, refs.robust
    reference_a = ref_a.setting
    traj_ref = reference_states(scene, reference_a)
    # the same tolerance by the flight integrated (dopri5: with friction, its switching pair)
    traj_check = reference_states(scene, replace(reference_a, method=Method.DOPRI5))
    gap = float(np.median([state_error(scene, a, b) for a, b in zip(traj_ref, traj_check,
                                                                     strict=True)]))
    study = Study(grid, ref_a, ref_b, robust, refs.agreement, gap)

    def measure(setting: Setting) -> Point:
        say(setting.label)
        run = run_grid(scene, setting, grid, threads)
        return Point(setting, trajectory_error(scene, setting, traj_ref),
                     label_error(run, ref_a.quarter_turns, robust), run.cpu_per_trajectory,
                     int(np.sum(run.status == Status.NONFINITE)),
                     int(np.sum(run.status == Status.UNSETTLED)),
                     uncertain_fraction(run, robust))

    study.points = [measure(setting) for setting in settings]
    if verified:
        study.verified_point = measure(verified_default(scene))
    # The paper's setting: symplectic Euler, h = 1e-6, always 2 s. Its labels are those of the
    # same step stopped early (the early stop is certified), so only its cost needs measuring,
    # on a few cells of the grid.
    paper = PAPER_SETTING
    same = next((p for p in study.points if p.setting == paper), None)
    if same is not None:
        say("paper's setting (2 s runs, cost only)")
        cells = sample_grid(grid, 4)
        cost = run_grid(scene, paper, cells, threads, stop_on_settle=False, t_end=2.0)
        study.paper_point = replace(same, cpu_per_trajectory=cost.cpu_per_trajectory)
    return study


def sample_grid(grid: Grid, per_axis: int) -> Grid:
    """A coarse grid of ``per_axis`` cells per axis over the same ranges (a cheap subset)."""
    axes = tuple(replace(axis, n=min(per_axis, axis.n)) for axis in grid.axes)
    return replace(grid, axes=axes, chunk=tuple(a.n for a in axes))


# -- where fixed-step methods fail ----------------------------------------------------------------
# The test of a step: a coin resting flat on two corners, given a small rocking kick (its
# corners stay in contact), run for STABILITY_TIME. That excites exactly the stiffest mode, whose
# damping should make the energy decay; growth means the step is unstable. (A chaotic throw is a
# poor test: at a given step it may happen to end standing, where the rocking is much softer.)
# With friction the resting coin's corners stick: the kick slips them by STABILITY_KICK r_t
# (1e-5 m/s), inside the regularized law's linear part, where friction is a stiff damper on the
# slip (rate about mu N / v_s (1/m + r_t^2 / I)), coupled to the rocking; an explicit step
# beyond its limit there chatters (the slip overshoots, friction saturates at mu N): the energy
# grows, or where the saturation bounds the chatter below the kick's energy, the coin never
# comes to rest (:func:`fails`).
STABILITY_KICK = 0.01  # rad/s
STABILITY_TIME = 0.5  # s
STABILITY_DECAY = 1e-2  # of the kick's energy: what a stable damped step leaves of it, at most
LINEAR_PERTURBATION = 1e-7  # of the natural units, the central differences of a step
LINEAR_SLIP = 1e-4  # of the slip velocity: what those differences slip a corner by, at most
SPECTRAL_SLACK = 1e-6  # a spectral radius this far above 1 is the differences' rounding


@dataclass
class StabilityLimit:
    method: Method
    predicted: float  # the registry's: the damped rocking mode alone (what simulate checks)
    measured: float  # smallest step seen to fail (bisection)
    at_rest: float = math.nan  # the step linearized at the resting coin under the scene's law
    # (friction included): the largest step whose spectral radius is at most 1


def resting_scene(scene: Scene) -> Scene:
    weight = scene.coin.mass * scene.g
    return scene.with_overrides(y0=scene.coin.r_t - weight / (2 * scene.foundation.k), vy=0.0,
                                vphi=STABILITY_KICK, phi0=0.0, vx=0.0,
                                t_end=STABILITY_TIME, stop_on_settle=False)


def fails(scene: Scene, method: Method | str, dt: float) -> bool:
    """A step fails if the kicked resting coin goes non-finite or gains energy, or, on a
    damped foundation (c > 0), keeps more than STABILITY_DECAY of the kick's energy: a step
    beyond its limit where friction sticks need not gain energy, its chatter bounded where the
    slip saturates friction (at mu N), but the coin never comes to rest. (Without damping the
    rocking never dies out, even with friction: the corners stick, the coin rocks on them.)"""
    run_scene = resting_scene(scene).with_overrides(method=method, dt=dt)
    labeller = Labeller.of(run_scene)
    p = labeller.params
    state0 = state_array(run_scene)
    final, status = labeller.final_state(state0)
    energy = labeller.python.total_energy
    if status == Status.NONFINITE or not energy(p, final) < energy(p, state0):
        return True
    if scene.foundation.c <= 0:
        return False
    rest = state0.copy()
    rest[5] = 0.0
    return energy(p, final) - energy(p, rest) > STABILITY_DECAY * (energy(p, state0)
                                                                   - energy(p, rest))


def step_map(scene: Scene, method: Method | str, dt: float) -> np.ndarray:
    """The one-step map of a fixed-step method linearized at the coin resting flat (not
    kicked), under the scene's own law: its Jacobian over (y, phi, vx, vy, vphi) (x enters no
    force), in natural units (r, 1 rad, sqrt(g r), sqrt(g r) / r), by central differences of the
    model's step (its kernels as plain Python). The perturbations move no corner across the
    surface and slip none by more than LINEAR_SLIP of a friction law's slip velocity."""
    from .integrators.fixed import fixed_step

    run_scene = resting_scene(scene).with_overrides(method=method, dt=dt)
    labeller = Labeller.of(run_scene)
    p = labeller.params
    step = labeller.python[fixed_step]
    rest = state_array(run_scene)
    rest[5] = 0.0
    r = scene.coin.r
    speed = math.sqrt(scene.g * r)
    units = np.array([r, 1.0, speed, speed, speed / r])
    delta = LINEAR_PERTURBATION * units
    slip = LINEAR_SLIP * getattr(p, "v_s", math.inf)  # a friction law's slip velocity
    delta[2] = min(delta[2], slip)
    delta[4] = min(delta[4], slip / scene.coin.r_t)  # vphi slips a lying coin's corner by r_t
    method_id = int(Method.parse(method))
    jacobian = np.empty((5, 5))
    for col in range(5):
        up, down = rest.copy(), rest.copy()
        up[col + 1] += delta[col]
        down[col + 1] -= delta[col]
        moved = (np.array(step(method_id, p, dt, tuple(up)))
                 - np.array(step(method_id, p, dt, tuple(down))))[1:]
        jacobian[:, col] = moved / units / (2 * delta[col] / units[col])
    return jacobian


def linear_limit(scene: Scene, method: Method | str) -> float:
    """The largest step whose map linearized at the resting coin (:func:`step_map`) has
    spectral radius at most 1: the first instability, scanned upwards from a thousandth of the
    registry's prediction in steps of 5 %, then bisected."""
    method = Method.parse(method)

    def stable(h: float) -> bool:
        return max(abs(np.linalg.eigvals(step_map(scene, method, h)))) <= 1.0 + SPECTRAL_SLACK

    top = 10.0 * METHODS[method].stable_step(scene)
    lo, h = 0.0, 1e-3 * METHODS[method].stable_step(scene)
    while h < top and stable(h):
        lo, h = h, h * 1.05
    if h >= top:
        return math.inf
    hi = h
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def measured_limit(scene: Scene, method: Method | str, iterations: int = 12) -> StabilityLimit:
    """Bisect, between 0.25x and 4x the stable step the resting coin's linearized step predicts
    (:func:`linear_limit`: the registry's, :attr:`MethodInfo.stable_step`, where the law is the
    paper's; friction lowers it), for the step where runs start to fail."""
    method = Method.parse(method)
    predicted = METHODS[method].stable_step(scene)
    at_rest = linear_limit(scene, method)
    centre = at_rest if math.isfinite(at_rest) else predicted
    lo, hi = 0.25 * centre, 4.0 * centre
    if fails(scene, method, lo):
        return StabilityLimit(method, predicted, lo, at_rest)
    if not fails(scene, method, hi):
        return StabilityLimit(method, predicted, math.inf, at_rest)
    for _ in range(iterations):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if fails(scene, method, mid) else (mid, hi)
    return StabilityLimit(method, predicted, hi, at_rest)
