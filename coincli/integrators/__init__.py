"""Integration methods: fixed-step kernels, the adaptive event-locating kernel, the batch runner
and the registry that describes them."""

from .batch import NO_LABEL, Labels, final_state, integrate, label_states, new_control, warm_up
from .registry import METHODS, MethodInfo, check_step, info

__all__ = ["METHODS", "Labels", "MethodInfo", "NO_LABEL", "check_step", "final_state", "info",
           "integrate", "label_states", "new_control", "warm_up"]
