"""coin: the plane model of a rigid coin impacting an elastic foundation."""

__version__ = "0.1.0"
