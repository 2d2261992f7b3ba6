"""Integration methods: fixed-step kernels, the adaptive event-locating kernel, the verification
ladder over a batch, and the registry that describes them (the one list of methods)."""

from .batch import NO_LABEL, new_control
from .registry import METHODS, MethodInfo, check_step, info

__all__ = ["METHODS", "MethodInfo", "NO_LABEL", "check_step", "info", "new_control"]
