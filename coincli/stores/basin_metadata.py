"""What a basin store's metadata say, and how they compare: the three copies of the sweep's
attributes, the differences between two sets of attributes in words a user acts on, and the
comparison of a metadata file with what the sweep wrote (and its repair).

The sweep's attributes (what determines the labels:
:data:`coincli.stores.basin_schema.COMPARED_ATTRS`) are kept in three copies, each with its digest:
the group's attributes, and the ``done`` array's
attributes in the consolidated metadata and in done/zarr.json, so that one damaged or edited copy
is found out and rebuilt from the others (:class:`coincli.stores.basin_store.BasinStore` judges
which copy the computed tiles prove). Metadata files are compared parsed, on what the sweep
wrote (shape, chunks, dtype, fill value, codecs, dimension names, its attributes): what a user
adds (an attribute, an array listed in the consolidated metadata) is theirs, kept on a repair
and never called damage.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from .basin_schema import COMPARED_ATTRS, COPY, MARK, owned, parameters_digest
from .zarr_v3 import dig, json_bytes, load_json


# -- the differences between two sets of attributes ------------------------------------------
def flatten_attrs(value, prefix: str = "") -> dict:
    """Nested attribute dicts -> {'parameters.foundation.k': 1e4, 'sweep.axes.vy.lo': 0.05}."""
    if isinstance(value, dict):
        out = {}
        for key, sub in value.items():
            out.update(flatten_attrs(sub, f"{prefix}.{key}" if prefix else str(key)))
        return out
    if isinstance(value, list) and value and all(isinstance(v, dict) and "name" in v
                                                for v in value):
        out = {}
        for sub in value:
            out.update(flatten_attrs({k: v for k, v in sub.items() if k != "name"},
                                     f"{prefix}.{sub['name']}"))
        return out
    if isinstance(value, list):
        return {prefix: json.dumps(value)}
    return {prefix: value}


def display_name(key: str) -> str:
    """A flattened attribute as the command line names it: 'k', '--res (vy cells)'."""
    parts = key.split(".")
    if parts[0] == "parameters":
        return parts[-1]
    if parts[0] == "sweep" and parts[1] == "axes" and len(parts) == 4:
        return {"n": f"--res ({parts[2]} cells)", "lo": f"--{parts[2]} LO",
                "hi": f"--{parts[2]} HI"}.get(parts[3], f"{parts[2]} {parts[3]}")
    if parts[0] == "sweep":
        return {"dims": "swept axes", "chunk": "--chunk", "fixed": "fixed initial value",
                "mirror": "mirrored axes (none: --no-mirror)"}.get(
            parts[1], parts[1]) + (f" {parts[2]}" if len(parts) > 2 else "")
    if parts[0] == "method":
        return "method" if parts[1] == "name" else parts[1]
    if parts[0] == "version":
        return "coincli version"
    return key


def show_value(value) -> str:
    if value is None:
        return "none"
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


def differences(stored: dict, wanted: dict, where: tuple[str, str] = ("in the store", "here"),
                compared=COMPARED_ATTRS) -> list[str]:
    """One phrase per differing parameter: 'k = 10000 in the store, 5000 here' (``where``
    names the two sides; ``compared``: the top-level attributes compared)."""
    a = with_friction(flatten_attrs({k: stored.get(k) for k in compared}))
    b = with_friction(flatten_attrs({k: wanted.get(k) for k in compared}))
    said = FrictionWords(a, b, where)
    out = []
    # the sweep first, then in the attributes' own order (the axes as swept: vy, then vphi)
    for key in sorted(dict.fromkeys([*a, *b]), key=lambda k: k.split(".")[0] != "sweep"):
        if key.startswith("sweep.axes.") and key.endswith((".units", ".long_name")):
            continue  # they follow from the axis's name, which differs too
        if said.skips(key):
            continue
        if a.get(key, "absent") != b.get(key, "absent"):
            out.append(f"{display_name(key)} = {show_value(a.get(key))} {where[0]}, "
                       f"{show_value(b.get(key))} {where[1]}{said.after(key)}")
    return out


MU = "parameters.foundation.mu"
SLIP_VELOCITY = "parameters.foundation.slip_velocity"
MODEL = "method.model"


def model_words(name) -> str:
    """A model's name as a sentence says it: "the paper's model", "the friction model"."""
    return "the paper's model" if name == "paper" else f"the {name} model"


class FrictionWords:
    """How a difference of two flattened sets of attributes (``a``: the store's, ``b``: this
    run's; :func:`with_friction` applied) is said where friction differs: the model follows
    from mu (the friction model where mu > 0), and its verification ladder from the model, so
    both are said once, after mu, not as values of their own; a slip velocity without friction
    means nothing and is not said. ``where`` names the two sides."""

    def __init__(self, a: dict, b: dict, where: tuple[str, str]):
        self.a, self.b, self.where = a, b, where
        self.model_follows = (a.get(MODEL, "absent") != b.get(MODEL, "absent")
                              and a.get(MU, 0.0) != b.get(MU, 0.0))

    def skips(self, key: str) -> bool:
        """Whether the difference of ``key`` goes unsaid."""
        if self.model_follows and (key == MODEL or key.startswith("method.verification.")):
            return True
        return key == SLIP_VELOCITY and 0 in (self.a.get(MU), self.b.get(MU))

    def after(self, key: str) -> str:
        """What follows the phrase of ``key``'s difference: after mu, the models."""
        if not (self.model_follows and key == MU):
            return ""
        return (f" ({model_words(self.a.get(MODEL))} {self.where[0]}, "
                f"{model_words(self.b.get(MODEL))} {self.where[1]}, each with its verification "
                "ladder)")


def with_friction(flat: dict) -> dict:
    """Flattened attributes with friction said as a scene means it: a sweep's parameters that
    record no mu (the paper's model, and every store written before friction) have mu = 0,
    and a slip velocity only matters, and is only compared, where mu > 0."""
    if not any(key.startswith("parameters.foundation.") for key in flat):
        return flat
    flat = dict(flat)
    flat.setdefault(MU, 0.0)
    if flat[MU] == 0:  # None: mu is varied (a continuation), friction at some values
        flat.pop(SLIP_VELOCITY, None)
    return flat


# -- the three copies of the sweep's attributes -----------------------------------------------
@dataclass
class Copy:
    """One copy of the sweep attributes in a store's metadata."""

    where: str
    value: dict | None  # None: unreadable
    digest: str | None = None  # the parameters digest stored beside them

    @property
    def consistent(self) -> bool:
        return self.value is not None and self.digest == parameters_digest(self.value).hex()


def _copy_in(where: str, attributes) -> Copy:
    """The copy of the sweep attributes in the ``done`` array's attributes."""
    value = dig(attributes, COPY)
    if not isinstance(value, dict):
        return Copy(where, None)
    return Copy(where, owned(value), dig(attributes, "digest"))


def read_copies(path: Path) -> tuple[dict | None, list[Copy]]:
    """The group's attributes (None if unreadable) and the three copies of the sweep
    attributes: the group's own, and the ``done`` array's in the consolidated metadata and in
    its zarr.json."""
    root = load_json(path / "zarr.json")
    attrs = dig(root, "attributes")
    if isinstance(attrs, dict):
        group = Copy("the group's attributes (zarr.json)", owned(attrs),
                     dig(attrs, MARK, "digest"))
    else:
        attrs, group = None, Copy("zarr.json", None)
    return attrs, [group,
                   _copy_in("the consolidated metadata of done (zarr.json)",
                            dig(root, "consolidated_metadata", "metadata", "done",
                                "attributes")),
                   _copy_in("done/zarr.json", dig(load_json(path / "done" / "zarr.json"),
                                                  "attributes"))]


def unique(values) -> list[dict]:
    out = []
    for value in values:
        if value not in out:
            out.append(value)
    return out


def disagreement(copies: list[Copy]) -> str:
    """'the group's attributes (zarr.json) and done/zarr.json disagree: c = 0.4 in the one,
    0.5 in the other'."""
    readable = [c for c in copies if c.value is not None]
    for a in readable:
        for b in readable:
            if a.value != b.value:
                diff = differences(a.value, b.value, ("in the one", "in the other"))
                return f"{a.where} and {b.where} disagree ({'; '.join(diff[:2])})"
    return "every copy of them fails its digest"


PROOF = {"tiles": "proven by its computed tiles", "digest": "confirmed by its digest",
         "agree": "in the other copies"}


def problems_of(copies: list[Copy], proven: dict, proof: str) -> list[str]:
    """The copies that differ from the ``proven`` attributes, and how."""
    problems = []
    for c in copies:
        if c.value is None:
            problems.append(f"{c.where} cannot be read")
        elif c.value != proven:
            problems.append(f"{c.where}: " + "; ".join(
                differences(c.value, proven, ("there", PROOF[proof]))))
        elif not c.consistent:
            problems.append(f"{c.where}: the digest stored with them is not theirs")
    return problems


# -- a metadata file against what the sweep wrote ----------------------------------------------
# Where a user may add entries to the metadata the sweep wrote (a group or array attribute, an
# array in the consolidated listing): those are theirs, kept, and never damage.
_OPEN_KEYS = ("attributes", "metadata")


def _same(found, want) -> bool:
    if isinstance(want, float) and isinstance(found, float) and math.isnan(want):
        return math.isnan(found)
    return type(found) is type(want) and found == want


def agrees(found, want, extensible: bool = False) -> bool:
    """Whether parsed metadata ``found`` holds what the sweep wrote, ``want``: equal, except
    for entries added where a user may add them."""
    if isinstance(want, dict):
        if not isinstance(found, dict) or not (extensible or set(found) == set(want)):
            return False
        return all(k in found and agrees(found[k], v, k in _OPEN_KEYS)
                   for k, v in want.items())
    if isinstance(want, list):
        return (isinstance(found, list) and len(found) == len(want)
                and all(agrees(f, w) for f, w in zip(found, want, strict=True)))
    return _same(found, want)


def merged(found, want, extensible: bool = False):
    """``want`` with the entries a user added to ``found`` (where they may add them)."""
    if not (isinstance(want, dict) and isinstance(found, dict)):
        return want
    out = {k: merged(found.get(k), v, k in _OPEN_KEYS) for k, v in want.items()}
    if extensible:
        out.update({k: v for k, v in found.items() if k not in want})
    return out


def differs(file: Path, data: bytes) -> bool:
    """Whether a file of the store does not hold what the template has for it: a metadata file
    compared parsed, on what the sweep wrote; a coordinate chunk byte for byte."""
    if file.name == "zarr.json":
        found = load_json(file)
        return found is None or not agrees(found, json.loads(data))
    try:
        return file.read_bytes() != data
    except OSError:
        return True


def repaired(file: Path, data: bytes) -> bytes:
    """What a differing file is rewritten with: the template's, with what a user added."""
    if file.name != "zarr.json":
        return data
    found = load_json(file)
    result = merged(found, json.loads(data))
    return data if result == json.loads(data) else json_bytes(result)


__all__ = ["PROOF", "Copy", "FrictionWords", "agrees", "differences", "differs", "disagreement",
           "display_name", "flatten_attrs", "merged", "model_words", "problems_of", "read_copies",
           "repaired", "show_value", "unique", "with_friction"]
