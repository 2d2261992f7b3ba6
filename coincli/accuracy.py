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

from .integrators import METHODS, NONFINITE, SETTLED
from .integrators.kernels import final_state, label_states, warm_up
from .model import total_energy
from .params import Scene, param_array, state_array

# The two references. A: the event method at a tolerance far below any setting on the chart.
# B: fixed-step RK4 -- no event location, no closed-form flight, no shared stepping code.
REFERENCE_A = ("event", 1e-6, 1e-12)
REFERENCE_B = ("rk4", 2.5e-7, 0.0)

LADDERS: dict[str, list[float]] = {
    "symplectic_euler": [1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7],
    "verlet": [1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7],
    "rk4": [2e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6],
    "dopri5": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    "event": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
}
PAPER_SETTING = ("symplectic_euler", 1e-6)


@dataclass(frozen=True)
class Setting:
    method: str
    dt: float
    rtol: float

    @property
    def adaptive(self) -> bool:
        return METHODS[self.method].adaptive

    @property
    def knob(self) -> float:
        """The number that sets the accuracy: rtol for adaptive methods, the step otherwise."""
        return self.rtol if self.adaptive else self.dt

    @property
    def label(self) -> str:
        return f"{self.method} {'rtol' if self.adaptive else 'h'}={self.knob:g}"

    def apply(self, scene: Scene, **extra) -> Scene:
        return scene.with_overrides(method=self.method, dt=self.dt,
                                    rtol=self.rtol if self.adaptive else None, **extra)


def ladder_settings(methods: list[str] | None = None) -> list[Setting]:
    out = []
    for name in methods or list(LADDERS):
        for knob in LADDERS[name]:
            if METHODS[name].adaptive:
                out.append(Setting(name, 1e-6, knob))
            else:
                out.append(Setting(name, knob, 1e-7))
    return out


# -- grids --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Grid:
    """A (vy0, vphi0) grid with the other initial conditions from the scene."""

    vy: np.ndarray
    vphi: np.ndarray

    @classmethod
    def linear(cls, vy_range=(0.05, 2.0), vphi_range=(-20.0, 20.0), res=(32, 32)) -> Grid:
        return cls(np.linspace(*vy_range, res[0]), np.linspace(*vphi_range, res[1]))

    def states(self, scene: Scene) -> np.ndarray:
        base = state_array(scene)
        vy, vphi = np.meshgrid(self.vy, self.vphi, indexing="ij")
        states = np.tile(base, (vy.size, 1))
        states[:, 4] = vy.ravel()
        states[:, 5] = vphi.ravel()
        return states

    @property
    def shape(self) -> tuple[int, int]:
        return (self.vy.size, self.vphi.size)


@dataclass
class GridRun:
    setting: Setting
    quarter_turns: np.ndarray  # int16, shape of the grid
    status: np.ndarray
    cpu_seconds: float  # summed over threads
    wall_seconds: float

    @property
    def cpu_per_trajectory(self) -> float:
        return self.cpu_seconds / self.quarter_turns.size


def run_grid(scene: Scene, setting: Setting, grid: Grid, threads: int = 2,
             stop_on_settle: bool = True, t_end: float | None = None) -> GridRun:
    """Label every cell of ``grid`` with ``setting``, on ``threads`` threads (the kernel
    releases the GIL). CPU time is the thread time of the workers, so it does not count the
    other processes of a shared machine."""
    run_scene = setting.apply(scene, stop_on_settle=stop_on_settle, t_end=t_end)
    p = param_array(run_scene)
    states = grid.states(run_scene)
    n = states.shape[0]
    n_out = np.empty(n, np.int16)
    st_out = np.empty(n, np.uint8)
    integ = run_scene.integration
    kernel = METHODS[setting.method].kernel_id
    warm_up(kernel, p, states[0], integ.dt, integ.rtol)  # before timing
    # interleave cells across threads so each gets a fair share of hard and easy cells
    parts = [np.arange(i, n, threads) for i in range(threads)]

    def work(idx):
        start = time.thread_time()
        n_out[idx], st_out[idx], _, _ = label_states(kernel, p, states[idx], integ.dt,
                                                     integ.rtol, integ.t_end,
                                                     integ.stop_on_settle)
        return time.thread_time() - start

    wall = time.perf_counter()
    with ThreadPoolExecutor(threads) as pool:
        cpu = sum(pool.map(work, parts))
    wall = time.perf_counter() - wall
    return GridRun(setting, n_out.reshape(grid.shape), st_out.reshape(grid.shape), cpu, wall)


def label_error(run: GridRun, reference: np.ndarray, robust: np.ndarray) -> float:
    """Fraction of robust cells whose label differs from the reference (a non-finite or
    unsettled cell counts as wrong)."""
    ok = (run.quarter_turns == reference) & (run.status == SETTLED)
    return float(np.mean(~ok[robust])) if robust.any() else math.nan


# -- trajectory error ------------------------------------------------------------------------------
# (vy0, vphi0, t): each throw is compared ~0.06 s after its first impact, a few impacts in and
# before chaos amplifies differences (there a 1e-10 nudge of vy0 still moves the state < 1e-8).
TRAJECTORY_THROWS = [(0.4, 6.0, 0.15), (0.6, -9.0, 0.18), (0.75, 3.0, 0.21), (0.5, -14.0, 0.15),
                     (0.3, 11.0, 0.12)]


def state_at(scene: Scene, setting: Setting, t: float) -> np.ndarray:
    """State at time t (no early stop). Fixed steps land on t exactly when dt divides it."""
    run_scene = setting.apply(scene, t_end=t, stop_on_settle=False)
    integ = run_scene.integration
    return final_state(METHODS[setting.method].kernel_id, param_array(run_scene),
                       state_array(run_scene), integ.dt, integ.rtol, t, False)[0]


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
    label_error: float
    cpu_per_trajectory: float
    nonfinite: int
    unsettled: int


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


def wilson_upper(fraction: float, n: int, z: float = 1.96) -> float:
    """Upper end of the 95 % Wilson score interval of a proportion observed on n trials."""
    if n == 0 or not math.isfinite(fraction):
        return math.inf
    centre = fraction + z * z / (2 * n)
    spread = z * math.sqrt(fraction * (1 - fraction) / n + z * z / (4 * n * n))
    return (centre + spread) / (1 + z * z / n)


def run_study(scene: Scene, grid: Grid, settings: list[Setting], threads: int = 2,
              progress=None) -> Study:
    """The whole work-precision study. ``progress(text)`` is called before each piece."""
    say = progress or (lambda text: None)
    ref_a_setting = Setting(*REFERENCE_A)
    ref_b_setting = Setting(*REFERENCE_B)
    say(f"reference A: {ref_a_setting.label}")
    ref_a = run_grid(scene, ref_a_setting, grid, threads)
    say(f"reference B: {ref_b_setting.label}")
    ref_b = run_grid(scene, ref_b_setting, grid, threads)
    settled = (ref_a.status == SETTLED) & (ref_b.status == SETTLED)
    robust = settled & (ref_a.quarter_turns == ref_b.quarter_turns)
    traj_ref = reference_states(scene, ref_a_setting)
    traj_check = reference_states(scene, replace(ref_a_setting, method="dopri5"))
    gap = float(np.median([state_error(scene, a, b) for a, b in zip(traj_ref, traj_check,
                                                                     strict=True)]))
    study = Study(grid, ref_a, ref_b, robust, float(np.mean(ref_a.quarter_turns
                                                            == ref_b.quarter_turns)), gap)
    for setting in settings:
        say(setting.label)
        run = run_grid(scene, setting, grid, threads)
        study.points.append(Point(
            setting, trajectory_error(scene, setting, traj_ref),
            label_error(run, ref_a.quarter_turns, robust), run.cpu_per_trajectory,
            int(np.sum(run.status == NONFINITE)), int(np.sum(run.status == 1))))
    # The paper's setting: symplectic Euler, h = 1e-6, always 2 s. Its labels are those of the
    # same step stopped early (the early stop is certified), so only its cost needs measuring,
    # on a few cells of the grid.
    paper = Setting(PAPER_SETTING[0], PAPER_SETTING[1], 1e-7)
    same = next((p for p in study.points if p.setting == paper), None)
    if same is not None:
        say("paper's setting (2 s runs, cost only)")
        cells = Grid(grid.vy[:: max(1, grid.vy.size // 4)][:4],
                     grid.vphi[:: max(1, grid.vphi.size // 4)][:4])
        cost = run_grid(scene, paper, cells, threads, stop_on_settle=False, t_end=2.0)
        study.paper_point = replace(same, cpu_per_trajectory=cost.cpu_per_trajectory)
    return study


# -- where fixed-step methods fail ----------------------------------------------------------------
# The test of a step: a coin resting flat on two corners, given a small rocking kick (its
# corners stay in contact), run for STABILITY_TIME. That excites exactly the stiffest mode, whose
# damping should make the energy decay; growth means the step is unstable. (A chaotic throw is a
# poor test: at a given step it may happen to end standing, where the rocking is much softer.)
STABILITY_KICK = 0.01  # rad/s
STABILITY_TIME = 0.5  # s


@dataclass
class StabilityLimit:
    method: str
    predicted: float
    measured: float  # smallest step seen to fail (bisection)


def resting_scene(scene: Scene) -> Scene:
    weight = scene.coin.mass * scene.g
    return scene.with_overrides(y0=scene.coin.r_t - weight / (2 * scene.foundation.k), vy=0.0,
                                vphi=STABILITY_KICK, phi0=0.0, vx=0.0,
                                t_end=STABILITY_TIME, stop_on_settle=False)


def fails(scene: Scene, method: str, dt: float) -> bool:
    """A step fails if the kicked resting coin goes non-finite or gains energy."""
    run_scene = resting_scene(scene).with_overrides(method=method, dt=dt)
    integ = run_scene.integration
    p = param_array(run_scene)
    state0 = state_array(run_scene)
    final, status = final_state(METHODS[method].kernel_id, p, state0, dt, integ.rtol,
                                integ.t_end, False)
    return status == NONFINITE or not total_energy(p, final) < total_energy(p, state0)


def measured_limit(scene: Scene, method: str, iterations: int = 12) -> StabilityLimit:
    """Bisect, between 0.25x and 4x the predicted stable step, for the step where runs start
    to fail."""
    predicted = METHODS[method].stable_step(scene)
    lo, hi = 0.25 * predicted, 4.0 * predicted
    if fails(scene, method, lo):
        return StabilityLimit(method, predicted, lo)
    if not fails(scene, method, hi):
        return StabilityLimit(method, predicted, math.inf)
    for _ in range(iterations):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if fails(scene, method, mid) else (mid, hi)
    return StabilityLimit(method, predicted, hi)

