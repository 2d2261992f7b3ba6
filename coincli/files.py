"""Checks made before long work starts (is an output writable, is a viewer reachable), writing
an output so that a failure leaves nothing behind, and one-line descriptions of OS errors."""

from __future__ import annotations

import contextlib
import errno
import os
import socket
from collections.abc import Iterator
from pathlib import Path

from .params import ParameterError

DEFAULT_CONNECT_URL = "rerun+http://127.0.0.1:9876/proxy"

# what a user should read for the errors a file system gives
REASONS = {
    errno.EROFS: "read-only file system",
    errno.ENOSPC: "no space left on device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
    errno.ENOENT: "no such file or directory",
    errno.ENOTDIR: "not a directory",
    errno.EISDIR: "is a directory",
    errno.EIO: "input/output error",
}


DISK_ERRORS = {errno.EROFS, errno.ENOSPC, errno.EDQUOT, errno.EACCES, errno.EPERM, errno.EIO}


class NotWritable(OSError):
    """An output that cannot be written; ``str()`` is the whole one-line message."""

    def __init__(self, code: int | None, message: str):
        super().__init__(code, message)
        self.message = message

    def __str__(self) -> str:
        return self.message


def describe(exc: OSError, doing: str | None = None) -> str:
    """One line for any OSError: 'cannot write out.zarr: read-only file system'."""
    if isinstance(exc, NotWritable):
        return str(exc)  # says what could not be written already
    if not exc.errno:
        return f"{doing}: {exc}" if doing else str(exc)
    reason = REASONS.get(exc.errno) or (exc.strerror or str(exc)).lower()
    text = f"{reason} ({errno.errorcode.get(exc.errno, exc.errno)})"
    if doing:
        return f"{doing}: {text}"
    return f"'{exc.filename}': {text}" if exc.filename is not None else text


def probe_name() -> str:
    """Name of the empty file a writability probe creates for an instant."""
    return f".coin-probe-{socket.gethostname()}-{os.getpid()}"


def _probe(folder: Path, target: Path) -> None:
    """Create and remove an empty file in ``folder``: what the file system says, not what the
    permission bits say (root passes os.access on a read-only mount's folders, and a full disk
    passes every permission check)."""
    probe = folder / probe_name()
    try:
        fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
    except FileExistsError:
        fd = os.open(probe, os.O_WRONLY)
    except OSError as exc:
        raise NotWritable(exc.errno, f"cannot write '{target}': "
                                     f"{REASONS.get(exc.errno, exc.strerror)}") from None
    try:
        os.write(fd, b"\0")
    except OSError as exc:
        raise NotWritable(exc.errno, f"cannot write '{target}': "
                                     f"{REASONS.get(exc.errno, exc.strerror)}") from None
    finally:
        os.close(fd)
        with contextlib.suppress(OSError):
            os.unlink(probe)


def check_writable(path: str | os.PathLike, *, what: str = "output",
                   directory: bool = False, create_parents: bool = False) -> Path:
    """Raise the OSError a user should see (one line) unless ``path`` can be written: a file
    (default) or a directory such as a Zarr store (``directory``: it, or the folder it would be
    created in, must accept new files). The folder is tried by creating and removing an empty
    file, so a read-only mount, a full disk or a missing permission is found before any work.
    ``create_parents`` creates missing folders first. A path of the wrong kind (a folder where
    a file is wanted, or the other way round) is a ParameterError, like any bad argument."""
    p = Path(path)
    if not directory and p.is_dir():
        raise ParameterError(f"{what} '{path}' is a directory")
    if str(path) == "" or p.name == "":
        raise FileNotFoundError(f"invalid {what} '{path}'")
    if directory and p.exists() and not p.is_dir():
        raise ParameterError(f"{what} '{path}' exists and is not a directory")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        if create_parents:
            try:
                parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise NotWritable(exc.errno, f"cannot create folder '{parent}': "
                                             f"{REASONS.get(exc.errno, exc.strerror)}") from None
        else:
            raise FileNotFoundError(f"cannot write '{p}': folder '{parent}' does not exist")
    if not directory and p.exists() and not os.access(p, os.W_OK):
        raise PermissionError(f"cannot write '{p}': permission denied")
    if not os.access(parent, os.W_OK) and not (directory and p.is_dir()):
        raise PermissionError(f"cannot write '{p}': permission denied")
    _probe(p if directory and p.is_dir() else parent, p)
    return p


def explain(exc: BaseException) -> str:
    """Why something failed, in one line: :func:`describe` for an OSError, else its message
    (or its kind, if it has none)."""
    return describe(exc) if isinstance(exc, OSError) else (str(exc) or type(exc).__name__)


def check_rrd_path(path: str | os.PathLike) -> Path:
    """:func:`check_writable` for a recording."""
    return check_writable(path, what="recording path")


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, tmp: Path | None = None) -> Iterator[Path]:
    """Write ``path`` through a temporary file beside it (``tmp``; by default a hidden name
    with the same suffix, so that writers that go by the suffix still do), renamed into place
    on success and removed on any failure: an output is complete or absent, never a truncated
    file or a leftover temporary one."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    if tmp is None:
        tmp = target.with_name(f".{target.stem}.tmp-{os.getpid()}{target.suffix}")
    try:
        yield tmp
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


FIGURE_FORMATS = (".png", ".svg", ".pdf")


def check_figure_path(path: str | os.PathLike, what: str = "figure") -> Path:
    """``path`` as a Path, or ParameterError unless it ends in a format matplotlib writes."""
    from .params import ParameterError

    path = Path(path)
    if path.suffix.lower() not in FIGURE_FORMATS:
        raise ParameterError(f"{path}: the {what}'s file name must end in .png, .svg or .pdf")
    return path


def made_by() -> str:
    """What every picture coin writes says made it, in its metadata: ``coin 0.11.0``."""
    from .version import __version__

    return f"coin {__version__}"


# the metadata key that names what made a picture, by format (matplotlib's keys: a PNG's text
# chunk "Software", the "Creator" of a PDF's or an SVG's metadata)
MADE_BY_KEY = {"png": "Software", "pdf": "Creator", "svg": "Creator"}


def save_figure(fig, path: str | os.PathLike, dpi: int) -> Path:
    """Save a matplotlib figure in the format its file name ends in (.png, .svg, .pdf), through
    :func:`atomic_output` (complete or absent), saying in its metadata the version that made it
    (:func:`made_by`, read back by :func:`picture_made_by`)."""
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    metadata = {MADE_BY_KEY[fmt]: made_by()} if fmt in MADE_BY_KEY else None
    with atomic_output(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=fmt, metadata=metadata)
    return path


PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    """The chunks of a PNG file, (type, data) in order; ValueError unless it is one."""
    if not data.startswith(PNG_SIGNATURE):
        raise ValueError("not a PNG file")
    chunks, at = [], len(PNG_SIGNATURE)
    while at + 8 <= len(data):
        length = int.from_bytes(data[at:at + 4], "big")
        kind = data[at + 4:at + 8]
        chunks.append((kind, data[at + 8:at + 8 + length]))
        at += 12 + length
        if kind == b"IEND":
            return chunks
    raise ValueError("a PNG file cut short")


def _png_chunk(kind: bytes, body: bytes) -> bytes:
    import zlib

    return (len(body).to_bytes(4, "big") + kind + body
            + zlib.crc32(kind + body).to_bytes(4, "big"))


def png_text(path: str | os.PathLike) -> dict[str, str]:
    """The text chunks (tEXt, and iTXt uncompressed) of a PNG file, keyword -> text."""
    out = {}
    for kind, body in _png_chunks(Path(path).read_bytes()):
        if kind == b"tEXt" and b"\0" in body:
            key, _, text = body.partition(b"\0")
            out[key.decode("latin-1")] = text.decode("latin-1")
        elif kind == b"iTXt" and b"\0" in body:
            key, _, rest = body.partition(b"\0")
            if rest[:1] == b"\0":  # not compressed: method, language, translated keyword
                _, _, rest = rest[2:].partition(b"\0")
                _, _, text = rest.partition(b"\0")
                out[key.decode("latin-1")] = text.decode("utf-8")
    return out


def stamp_png(path: str | os.PathLike, software: str | None = None) -> Path:
    """Say in a PNG made by another program (a Rerun viewer's screenshot) what made it: its
    "Software" text chunk (any other replaced) becomes ``software`` (:func:`made_by` unless
    given), written through :func:`atomic_output`; the image is untouched."""
    path = Path(path)
    chunks = [(kind, body) for kind, body in _png_chunks(path.read_bytes())
              if not (kind in (b"tEXt", b"iTXt") and body.partition(b"\0")[0] == b"Software")]
    text = b"Software\0" + (software or made_by()).encode("latin-1")
    chunks.insert(1, (b"tEXt", text))  # right after IHDR, which comes first
    with atomic_output(path) as tmp:
        tmp.write_bytes(PNG_SIGNATURE + b"".join(_png_chunk(k, b) for k, b in chunks))
    return path


def picture_made_by(path: str | os.PathLike) -> str | None:
    """The version of coin that made a PNG picture (``0.11.0``), from its "Software" text chunk
    (:func:`save_figure`, :func:`stamp_png`); None if it names none (another program, or a
    coin before 0.11)."""
    import re

    found = re.fullmatch(r"coin (\S+)", png_text(path).get("Software", ""))
    return found.group(1) if found else None


def check_connect_url(url: str) -> str:
    """Raise ValueError (one line) unless ``url`` looks like a Rerun gRPC proxy address."""
    if not url.startswith(("rerun://", "rerun+http://", "rerun+https://")):
        raise ValueError(f"--connect URL '{url}' must start with rerun+http://, rerun+https:// "
                         f"or rerun:// (e.g. {DEFAULT_CONNECT_URL})")
    return url


def probe_viewer(url: str, timeout: float = 2.0) -> None:
    """Raise ConnectionError (one line) unless something accepts TCP connections at ``url``'s
    host and port: streaming to nobody would otherwise only fail after seconds of retries."""
    from urllib.parse import urlsplit

    parts = urlsplit(check_connect_url(url))
    port = parts.port or (80 if parts.scheme == "rerun+http" else 443)
    host = parts.hostname or "127.0.0.1"
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as exc:
        raise ConnectionError(f"no Rerun viewer reachable at {url} ({exc.strerror or exc}); "
                              "start one with `rerun`") from None


__all__ = ["DEFAULT_CONNECT_URL", "DISK_ERRORS", "FIGURE_FORMATS", "MADE_BY_KEY", "NotWritable",
           "atomic_output", "check_figure_path", "save_figure", "made_by", "picture_made_by",
           "png_text", "stamp_png",
           "check_connect_url", "check_rrd_path", "check_writable", "describe", "explain",
           "probe_name",
           "probe_viewer"]
