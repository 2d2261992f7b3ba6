"""Presets: named TOML files holding a scene's parameters (see ``presets/`` at the repo top).

A preset names any subset of the sections ``[coin]``, ``[foundation]``, ``[initial]``,
``[integration]`` and the top-level ``g``; what it leaves out takes the built-in default.
"""

from __future__ import annotations

import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

from .defaults import DEFAULT_PRESET
from .params import ParameterError, Scene, scene_from_dict, validate


def presets_dir() -> Path:
    """Where the shipped presets live: the repo's ``presets/`` (editable install or checkout),
    else the copy bundled into the wheel as ``coincli/presets``."""
    here = Path(__file__).resolve().parent
    for candidate in (here.parent / "presets", here / "presets"):
        if candidate.is_dir():
            return candidate
    raise ParameterError("no presets directory found (reinstall the package)")


@dataclass(frozen=True)
class Preset:
    name: str
    description: str
    path: Path
    scene: Scene


def load_preset_file(path: Path) -> Preset:
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ParameterError(f"malformed preset file {path}: {exc}") from None
    except OSError as exc:
        raise ParameterError(f"cannot read preset file {path}: {exc.strerror}") from None
    if not data:  # most likely the wrong file, not a wish for every default
        raise ParameterError(f"preset file {path} is empty: it needs at least one value "
                             "(presets/paper.toml shows them all)")
    try:
        scene = scene_from_dict(data)
    except TypeError as exc:  # a value of the wrong type for a dataclass field
        raise ParameterError(f"malformed preset file {path}: {exc}") from None
    except ParameterError as exc:
        raise ParameterError(f"malformed preset file {path}: {exc}") from None
    try:
        validate(scene)
    except ParameterError as exc:
        raise ParameterError(f"preset file {path}: {exc}") from None
    return Preset(name=str(data.get("name", path.stem)),
                  description=str(data.get("description", "")), path=path, scene=scene)


def available() -> list[Preset]:
    return [load_preset_file(p) for p in sorted(presets_dir().glob("*.toml"))]


def load(name_or_path: str | None) -> Preset:
    """Load a preset by name (a file in :func:`presets_dir`) or by path to a TOML file."""
    if name_or_path is not None and not isinstance(name_or_path, str | os.PathLike):
        raise TypeError(f"a preset is a name or the path of a TOML file, got "
                        f"{type(name_or_path).__name__}")
    name_or_path = str(name_or_path or DEFAULT_PRESET)
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml" or candidate.exists() or "/" in name_or_path:
        if not candidate.is_file():
            raise ParameterError(f"preset file {name_or_path} does not exist")
        return load_preset_file(candidate)
    path = presets_dir() / f"{name_or_path}.toml"
    if not path.is_file():
        names = ", ".join(p.stem for p in sorted(presets_dir().glob("*.toml")))
        raise ParameterError(f"unknown preset '{name_or_path}'; available: {names}")
    return load_preset_file(path)
