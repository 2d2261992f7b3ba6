"""The kernels are one source run two ways: compiled by numba, or as plain CPython for one short
throw (Engine.PYTHON). The compiled code fuses multiplies and adds (FMA, coincli.jit), CPython
rounds each operation: both must give the same labels, statuses, steps and contact events, and
states equal to rounding."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

THROWS = [(1.197, 3.508, "event"), (0.4, -9.0, "event"), (1.9, 17.0, "event"),
          (0.6, 5.0, "dopri5"), (0.3, 12.0, "rk4")]


def fingerprint(engine_name: str) -> str:
    """Python code printing every number of the runs as JSON."""
    return f"""
import json, coincli
from coincli.enums import Engine
out = []
for vy, vphi, method in {THROWS!r}:
    scene = coincli.load_preset("paper").with_overrides(vy=vy, vphi=vphi, method=method)
    run = coincli.simulate(scene, sample_dt=1e-3, record_events=True,
                           engine=Engine.{engine_name})
    out.append([run.quarter_turns, int(run.status), run.steps, int(run.certainty),
                run.t_final, run.final_state.tolist(), run.samples.tolist(),
                run.events.tolist()])
print(json.dumps(out))
"""


def test_python_and_numba_engines_agree_to_rounding():
    runs = {}
    for engine in ("PYTHON", "NUMBA"):
        code = fingerprint(engine)
        runs[engine] = json.loads(subprocess.run([sys.executable, "-c", code], check=True,
                                                 capture_output=True, text=True).stdout)
    for py, nb in zip(runs["PYTHON"], runs["NUMBA"], strict=True):
        assert py[:4] == nb[:4]  # label, status, steps, certainty
        # rounding differences grow along a bouncing trajectory: 3e-10 s after 0.95 s here
        assert abs(py[4] - nb[4]) < 1e-8  # end time, s
        for a, b in zip(py[5:], nb[5:], strict=True):  # final state, samples, events
            a, b = np.asarray(a), np.asarray(b)
            assert a.shape == b.shape
            scale = np.maximum(np.abs(a).max(axis=0), 1e-3) if a.size else 1.0
            assert (np.abs(a - b) / scale).max(initial=0.0) < 1e-6, (a - b)  # 9e-8 at most
    assert [r[0] for r in runs["NUMBA"]][:1] == [6]


def test_auto_engine_redoes_a_long_run_compiled():
    """A run longer than the Python engine's cap is redone compiled, with the same result."""
    code = """
import json, coincli, coincli.models, coincli.throw as throw
from coincli.enums import Engine
from coincli.jit import is_built
throw.PYTHON_STEPS = 10  # the fig.-2 throw takes 45 and 27 steps
scene = coincli.load_preset("paper").with_overrides(vy=1.197, vphi=3.508)
auto = coincli.simulate(scene)
assert is_built(coincli.models.PAPER), "the long run must have gone to numba"
again = coincli.simulate(scene, engine=Engine.NUMBA)
print(json.dumps([auto.steps, again.steps, auto.final_state.tolist() == again.final_state.tolist(),
                  auto.quarter_turns]))
"""
    out = json.loads(subprocess.run([sys.executable, "-c", code], check=True,
                                    capture_output=True, text=True).stdout)
    assert out == [72, 72, True, 6]  # rtol 1e-6 and, with DOP853, 1e-8: 45 + 27 steps
