"""Integration methods: fixed-step kernels, the adaptive event-locating kernel, the batch runner
and the registry that names them."""

from .fixed import NONFINITE, SETTLED, UNSETTLED
from .kernels import NOT_COMPUTED, integrate, run_batch
from .registry import METHODS, Method, check_step, get

STATUS_NAMES = {SETTLED: "settled", UNSETTLED: "unsettled", NONFINITE: "non-finite"}

__all__ = ["METHODS", "Method", "NONFINITE", "NOT_COMPUTED", "SETTLED", "STATUS_NAMES",
           "UNSETTLED", "check_step", "get", "integrate", "run_batch"]
