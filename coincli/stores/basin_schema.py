"""The format of a basin: its variables (dtype, fill value, attributes), its attributes (the
sweep's description, :attr:`coincli.engines.basin_plan.SweepPlan.attrs`, under the mark that
makes a group a basin store) and the digest of the parameters that every tile binds. The Zarr
store (:mod:`coincli.stores.basin_store`), the in-memory map (:mod:`coincli.stores.memory`) and
the Dataset (:mod:`coincli.stores.dataset`) hold the same thing."""

from __future__ import annotations

import hashlib
import json
import math

from ..enums import Certainty, Status
from ..grid import Grid
from ..integrators import NO_LABEL

FORMAT = 5  # 3: checksummed chunks, done = a digest of each tile; 4: ... and of the parameters;
# 5: certainty 3 = undecided (before, undecided labels were 0, uncertain, like chaotic ones)
# The attributes the sweep owns: what determines the labels (the parameters digest binds them)
COMPARED_ATTRS = ("version", "parameters", "sweep", "method")
# Earlier versions whose stores hold the labels this one computes (the kernels, the ladder and
# the store's layout unchanged since): a store of one of them is resumed as its own sweep, in
# its own version (its tiles keep binding its parameters digest).
RESUMES = ("0.9.0", "0.10.0")
# What a sweep's method attributes say since 0.11.0, and what a store of an earlier version
# means without them: the paper's model, run by numba's compiled kernels.
LATER_METHOD_ATTRS = {"model": "paper", "backend": "numba"}


def resumable_as(stored: dict, wanted: dict) -> dict | None:
    """``wanted`` in the version of the ``stored`` attributes, if that is all that tells them
    apart and that version's stores are :data:`RESUMES`'s; else None. Those versions recorded
    no model and no backend: ``wanted`` in their words drops them where they are what those
    versions computed with (:data:`LATER_METHOD_ATTRS`)."""
    version = stored.get("version")
    if version == wanted.get("version") or version not in RESUMES:
        return None
    method = dict(wanted.get("method") or {})
    for key, value in LATER_METHOD_ATTRS.items():
        if method.get(key) == value and key not in (stored.get("method") or {}):
            del method[key]
    return {**wanted, "version": version, "method": method}


def method_text(method: dict) -> str:
    """A sweep's method attributes (``attrs["method"]``) as a user reads them: its name, and the
    switching pair its ladder ran on where that is another (a friction scene's:
    ``event (run as event_rodas)``)."""
    rungs = method.get("verification", {}).get("rungs")
    first = rungs[0]["method"] if rungs else method["name"]
    return method["name"] if first == method["name"] else f"{method['name']} (run as {first})"


MARK = "coin_basin"  # the root attribute that makes a group a basin store
COPY = "sweep_attributes"  # the copy of COMPARED_ATTRS in the done array's attributes

# name -> (dtype, fill value, attributes)
VARIABLES = {
    "quarter_turns": ("int16", int(NO_LABEL), {
        "long_name": "final number n of quarter turns (phi / (pi/2)); odd = standing",
        "units": "1", "missing_value": int(NO_LABEL),
        "description": "the well that holds the settled coin; round(2 phi / pi) at t_end when "
                       "unsettled; -32768 where not computed or non-finite"}),
    "status": ("uint8", int(Status.NOT_COMPUTED), {
        "long_name": "run status (of the last rung run)",
        "flag_values": [int(s) for s in Status],
        "flag_meanings": " ".join(s.label.replace(" ", "_").replace("-", "_") for s in Status)}),
    "settle_time": ("float32", math.nan, {
        "long_name": "time at which the energy fell below E_crit (n final)", "units": "s"}),
    "steps": ("int64", -1, {"long_name": "integrator steps, summed over the rungs run",
                            "units": "1"}),
    "certainty": ("uint8", int(Certainty.NOT_COMPUTED), {
        "long_name": "whether the label converged on the ladder of settings (attribute "
                     "method.verification)",
        "flag_values": [int(c) for c in Certainty],
        "flag_meanings": " ".join(c.label.replace(" ", "_") for c in Certainty)}),
    "rung": ("int8", -1, {
        "long_name": "index of the last rung of the ladder run: the rung at which a certain "
                     "label converged", "units": "1"}),
}
DTYPES = {name: spec[0] for name, spec in VARIABLES.items()}
FILLS = {name: spec[1] for name, spec in VARIABLES.items()}
DONE_ATTRS = {"long_name": "digest of the tile, 0 = not done (written after its data)",
              "description": "32-bit BLAKE2b (person 'coin-tile') of the parameters digest (16 "
                             "bytes), the tile index (two int64) and, for each of "
                             + ", ".join(VARIABLES) + ", its shape (two int64) and its values, "
                             "all little-endian; never 0"}
DIGEST_NOTE = ("parameters digest: 16-byte BLAKE2b (person 'coin-params') of the JSON of "
               + ", ".join(COMPARED_ATTRS) + " (keys sorted, separators ',' and ':'), in hex")
COORD_NOTE = "linspace(lo, hi, n), ends included"


def owned(attrs: dict) -> dict:
    """The attributes the sweep owns (:data:`COMPARED_ATTRS`), as JSON has them (lists, not
    tuples), missing ones None."""
    return json.loads(json.dumps({k: attrs.get(k) for k in COMPARED_ATTRS}, allow_nan=True))


def parameters_digest(attrs: dict) -> bytes:
    """16-byte BLAKE2b of the attributes the sweep owns (see :data:`DIGEST_NOTE`): every tile's
    digest folds it in, so a tile verifies only under the parameters it was computed with."""
    text = json.dumps(owned(attrs), sort_keys=True, separators=(",", ":"), allow_nan=True)
    return hashlib.blake2b(text.encode(), digest_size=16, person=b"coin-params").digest()


def root_attrs(compared: dict) -> dict:
    """The group's attributes for the sweep attributes ``compared``: the mark (format and
    parameters digest) first."""
    return {MARK: {"format": FORMAT, "command": "coin basin",
                   "digest": parameters_digest(compared).hex()}, **owned(compared)}


def done_attrs(compared: dict) -> dict:
    """The ``done`` array's attributes: what it holds, and a copy of the sweep attributes with
    their digest (so that damaged group attributes can be rebuilt from what the tiles prove)."""
    return {**DONE_ATTRS, COPY: owned(compared), "digest": parameters_digest(compared).hex(),
            "digest_description": DIGEST_NOTE}


def tile_dims(grid: Grid) -> tuple[str, str]:
    return tuple(f"tile_{d}" for d in grid.dims)


__all__ = ["COMPARED_ATTRS", "COORD_NOTE", "COPY", "DIGEST_NOTE", "DONE_ATTRS", "DTYPES", "FILLS",
           "FORMAT", "LATER_METHOD_ATTRS", "MARK", "RESUMES", "VARIABLES", "done_attrs", "owned",
           "parameters_digest", "resumable_as", "root_attrs", "tile_dims"]
