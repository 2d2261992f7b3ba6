"""Checks made before long work starts: is an output path writable, is a viewer reachable."""

from __future__ import annotations

import os
from pathlib import Path

DEFAULT_CONNECT_URL = "rerun+http://127.0.0.1:9876/proxy"


def check_rrd_path(path: str | os.PathLike) -> Path:
    """Raise the OSError a user should see (one line) if ``path`` cannot be written as a file."""
    p = Path(path)
    if p.is_dir():
        raise IsADirectoryError(f"recording path '{path}' is a directory")
    if str(path) == "" or p.name == "":
        raise FileNotFoundError(f"invalid recording path '{path}'")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"cannot write '{p}': folder '{parent}' does not exist")
    if not os.access(parent, os.W_OK) or (p.exists() and not os.access(p, os.W_OK)):
        raise PermissionError(f"cannot write '{p}': permission denied")
    return p


def check_connect_url(url: str) -> str:
    """Raise ValueError (one line) unless ``url`` looks like a Rerun gRPC proxy address."""
    if not url.startswith(("rerun://", "rerun+http://", "rerun+https://")):
        raise ValueError(f"--connect URL '{url}' must start with rerun+http://, rerun+https:// "
                         f"or rerun:// (e.g. {DEFAULT_CONNECT_URL})")
    return url


def probe_viewer(url: str, timeout: float = 2.0) -> None:
    """Raise ConnectionError (one line) unless something accepts TCP connections at ``url``'s
    host and port: streaming to nobody would otherwise only fail after seconds of retries."""
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(check_connect_url(url))
    port = parts.port or (80 if parts.scheme == "rerun+http" else 443)
    host = parts.hostname or "127.0.0.1"
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        raise ConnectionError(f"no Rerun viewer reachable at {url} ({exc.strerror or exc}); "
                              "start one with `rerun` or use --spawn") from None


__all__ = ["DEFAULT_CONNECT_URL", "check_connect_url", "check_rrd_path", "probe_viewer"]
