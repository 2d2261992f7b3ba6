"""The public functions of one throw and of what every throw shares: the presets, a throw
(:func:`simulate`), the statics (:func:`stability`), the integration methods
(:func:`method_table`, :func:`step_bound`) and the compilation of the kernels.

Light to import: the modules that do the work (numpy, the integrators) load inside the
functions, so that `coin simulate` starts with no more than one throw needs."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from .. import jit
from ..enums import Engine
from ..jit import FIRST_COMPILE_SECONDS
from ..params import Scene, validate
from ..presets import load

if TYPE_CHECKING:
    from ..recordings.trajectory import Trajectory
    from ..statics import StabilityReport


def load_preset(name_or_path: str = "paper") -> Scene:
    """The scene of a shipped preset (``coin presets`` lists them) or of a TOML file."""
    return load(name_or_path).scene


def simulate(scene: Scene, *, sample_dt: float | None = None, record_events: bool = False,
             force: bool = False, engine: Engine = Engine.AUTO, control=None,
             before_compile=None, **overrides) -> Trajectory:
    """Integrate one throw (a :class:`Trajectory`), verified on the ladder of settings unless
    ``verify=False``.

    ``overrides`` change the scene for this throw, by the flat names of
    :meth:`Scene.with_overrides`: initial conditions (``vy=1.197, vphi=3.508``, ``phi0="pi/2"``,
    ``y0="2r"``), physical parameters (``k=5000``) and integration settings (``rtol=1e-8``).
    With ``sample_dt`` the state is kept every ``sample_dt`` seconds of simulated time (exact
    times for the adaptive methods); with ``record_events`` every contact onset and lift-off is
    kept with its state. ``force`` allows a fixed step beyond the method's stable step.
    ``engine`` chooses what runs the kernel (the same result to rounding: compiled code fuses
    multiplies and adds, :mod:`coincli.jit`); ``control`` (from
    :func:`coincli.integrators.new_control`) lets another thread stop it; ``before_compile``
    (a function of no arguments) is called before the kernels of the scene's model are first
    compiled on this machine (a minute or more, once: :func:`compile_kernels`).

    Friction: a scene with a friction coefficient (``mu=0.3``) runs the friction model; every
    throw says how much energy friction took (``friction_work``, J) and, without friction,
    what a coefficient mu would take, about mu times ``sliding_work`` (J)."""
    from ..recordings.trajectory import Trajectory
    from ..throw import simulate as simulate_throw

    return Trajectory.of(simulate_throw(scene, sample_dt=sample_dt, record_events=record_events,
                                        force=force, engine=engine, control=control,
                                        before_compile=before_compile, **overrides))


def stability(scene: Scene) -> StabilityReport:
    """The static energy table and critical stiffnesses of the paper's section 3, and E_crit."""
    from ..statics import analyse

    return analyse(validate(scene))


@dataclass(frozen=True)
class MethodTable:
    """The integration methods for a scene (:func:`method_table`): its stiffest mode (rocking
    on the two corners of a lying coin), with friction the decay of its stick at rest, and
    each method's order, kind and stable step."""

    omega: float  # rad/s, the stiffest mode's angular frequency
    zeta: float  # its damping ratio
    methods: tuple[dict, ...]  # name, order, adaptive, symplectic, stable_step (s; None for
    # an adaptive method), summary, default (the scene's own method)
    stick_rate: float = 0.0  # 1/s, friction's stick at rest (0 without friction): a fixed
    # step's stable step is the smaller of the rocking's and the stick's

    def __repr__(self) -> str:  # one line in a notebook; everything: to_dict()
        default = next((m["name"] for m in self.methods if m["default"]), None)
        stick = f", stick rate {self.stick_rate:.4g} /s" if self.stick_rate > 0 else ""
        return (f"MethodTable(stiffest mode {self.omega:.4g} rad/s, damping ratio "
                f"{self.zeta:.3f}{stick}; {len(self.methods)} methods, the scene's: {default})")

    def to_dict(self) -> dict:
        """What `coin methods --json` prints."""
        return {"omega_max": self.omega, "zeta": self.zeta, "stick_rate": self.stick_rate,
                "methods": [dict(m) for m in self.methods]}


def method_table(scene: Scene) -> MethodTable:
    """Every integration method with its properties for ``scene`` (what `coin methods` lists):
    the stable step of a fixed-step method is the largest whose error on the scene's stiffest
    mode (and, with friction, on its stick at rest) does not grow (``simulate`` and ``basin``
    refuse a larger ``dt`` without ``force``)."""
    from ..integrators import METHODS
    from ..models import stick_rate, stiffest_frequency

    scene = validate(scene)
    omega, zeta = stiffest_frequency(scene)
    rows = tuple({"name": m.name, "order": m.order, "adaptive": m.adaptive,
                  "symplectic": m.symplectic, "stable_step": m.stable_step(scene),
                  "summary": m.summary, "default": m.method == scene.integration.method}
                 for m in METHODS.values())
    return MethodTable(omega, zeta, rows, stick_rate(scene))


@dataclass(frozen=True)
class StepBound:
    """How many steps a throw of a scene may take at most (:func:`step_bound`)."""

    adaptive: bool  # an adaptive method: its steps are not known before the run
    steps: int | None  # a fixed step: over every rung of its ladder, each rung's budget or
    # the steps to the throw's horizon, whichever is fewer (None: adaptive)
    dts: tuple[float, ...]  # each rung's step, s (fixed steps)

    def to_dict(self) -> dict:
        return asdict(self)


def step_bound(scene: Scene) -> StepBound:
    """The most steps one throw of ``scene`` may take up its verification ladder: what a front
    end says before a long fixed-step run."""
    import math

    from ..integrators import info
    from ..integrators.ladder import scene_ladder
    from ..models import scene_horizon

    integ = scene.integration
    if info(integ.method).adaptive:
        return StepBound(True, None, ())
    ladder = scene_ladder(scene)
    horizon = scene_horizon(scene)  # t_end, or the throw's cap (infinite: a non-finite start)
    steps = sum(min(budget, math.ceil(horizon / dt)) if math.isfinite(horizon) else budget
                for budget, dt in zip(ladder.budgets, ladder.dts, strict=True))
    return StepBound(False, int(steps), tuple(ladder.dts))


def compile_kernels(scene: Scene | None = None, *, model: str | None = None) -> bool:
    """Compile the kernels of ``scene``'s model (:func:`coincli.models.model_of`: the
    paper's unless its foundation has friction, mu > 0) for this machine now, unless this
    version has compiled them here already (:func:`kernels_cached`): what the first run of any
    of them would do, in about :func:`compile_seconds`. ``model`` names a model instead
    ("paper", "friction"; :func:`model_names`); neither: the paper's. Whatever the scene, a
    model's kernels take the same argument types, so one scene's compile serves every later
    scene of its model. True if it compiled. Silent: a caller that wants to show the wait
    does (``coin compile``)."""
    from ..labeller import Labeller

    found, scene = _model_and_scene(scene, model)
    if jit.kernels_cached(found.name):
        return False
    Labeller.of(scene).compile_all()
    return True


def kernels_cached(scene: Scene | None = None, *, model: str | None = None) -> bool:
    """Whether this version's kernels of ``scene``'s model (or of ``model``; neither: the
    paper's) are compiled on this machine already (then they load in a second; else the first
    call that integrates a scene of that model compiles them, in about
    :func:`compile_seconds`)."""
    return jit.kernels_cached(_model_and_scene(scene, model)[0].name)


def kernel_model(scene: Scene | None = None) -> str:
    """The name of the model whose kernels ``scene`` runs ("paper", or "friction" where its
    foundation has a friction coefficient); None: the paper's."""
    return _model_and_scene(scene, None)[0].name


def model_names() -> tuple[str, ...]:
    """Every model's name, the paper's first (what ``model=`` takes)."""
    from ..models import MODELS

    return tuple(MODELS)


def compile_seconds(scene: Scene | None = None, *, model: str | None = None) -> float:
    """About how long compiling the kernels of ``scene``'s model (or ``model``'s) takes on a
    machine like the one of docs/performance.md (FIRST_COMPILE_SECONDS for the paper's)."""
    return float(_model_and_scene(scene, model)[0].compile_seconds)


def _model_and_scene(scene, model):
    """(the Model, a scene of it): ``scene``'s, or ``model``'s by name with the default scene
    given its example values; neither: the paper's."""
    from ..models import MODELS, model_of
    from ..params import ParameterError, require_scene

    if model is None:
        scene = Scene() if scene is None else require_scene(scene)
        return model_of(scene), scene
    if scene is not None:
        raise ParameterError("give a scene or a model, not both", parameters=("model",))
    if model not in MODELS:
        raise ParameterError(f"model must be one of {', '.join(MODELS)}, got {model!r}",
                             parameters=("model",))
    found = MODELS[model]
    return found, Scene().with_overrides(**dict(found.example))


def cache_dir() -> Path:
    """Where coincli keeps its compiled kernels (``$NUMBA_CACHE_DIR/coincli``, else in the
    user's cache folder); it may be deleted at any time: the kernels then compile again."""
    return jit.cache_dir()


def viewer(*, width: int | None = None, height: int | None = None):
    """A Rerun viewer shown in the notebook's cell now (``width`` and ``height`` in pixels),
    for the work of later cells: ``coincli.basin(..., store=..., notebook=v)``,
    ``fractions(..., notebook=v)``, ``analyze(..., notebook=v)``, ``show_basin(ds,
    notebook=v)`` show in it as they run (a viewer made in the cell that runs the work is
    ready only once the cell has run: Jupyter hands the kernel its "ready" between cells)."""
    from ..recordings.stream import notebook_viewer

    return notebook_viewer(width=width, height=height)


__all__ = ["FIRST_COMPILE_SECONDS", "MethodTable", "StepBound", "cache_dir", "compile_kernels",
           "compile_seconds", "kernel_model", "kernels_cached", "load_preset", "method_table",
           "model_names", "simulate",
           "stability", "step_bound", "viewer"]
