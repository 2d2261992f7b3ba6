"""Rerun recordings of one throw (coincli.recordings.rrd and `coin simulate --rrd/--no-rrd`): the
.rrd is read back with rerun.chunk.RrdReader and pyarrow and checked against the simulation."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from collections import defaultdict

import numpy as np
import pyarrow as pa
import pytest
from typer.testing import CliRunner

from coincli import __version__, simulate
from coincli.cli import app
from coincli.models import PAPER, model_params
from coincli.params import Scene
from coincli.presets import load
from coincli.recordings import frames as frames_io
from coincli.recordings import rrd as rrd_io

rr = pytest.importorskip("rerun")
from rerun.chunk import RrdReader  # noqa: E402

FIG2 = dict(vy=1.197, vphi=3.508)
LOG_EVERY = 1e-3
RED = rrd_io._rgba(rrd_io.CONTACT_COLOUR)
BLUE = rrd_io._rgba(rrd_io.FREE_COLOUR)


pytestmark = pytest.mark.usefixtures("strict_rerun")  # conftest.py


def fig2_scene(**overrides) -> Scene:
    return load("paper").scene.with_overrides(verify=False).with_overrides(**FIG2, **overrides)


class Recording:
    """A .rrd read back: one pyarrow table per (entity, static) with rows sorted by sim_time."""

    def __init__(self, path):
        reader = RrdReader(path)
        self.reader = reader
        batches = defaultdict(list)
        for chunk in reader.store().stream().to_chunks():
            batches[(chunk.entity_path, chunk.is_static)].append(chunk.to_record_batch())
        self.tables = {}
        for key, parts in batches.items():
            table = pa.Table.from_batches(parts) if len({p.schema for p in parts}) == 1 else \
                pa.concat_tables([pa.Table.from_batches([p]) for p in parts],
                                 promote_options="default")
            if not key[1]:
                table = table.sort_by("sim_time")
            self.tables[key] = table

    @property
    def entities(self) -> set[str]:
        return {path for path, _ in self.tables}

    def temporal(self, entity: str) -> pa.Table:
        return self.tables[(entity, False)]

    def static(self, entity: str) -> pa.Table:
        return self.tables[(entity, True)]

    def times(self, entity: str) -> np.ndarray:
        """sim_time of each row in integer nanoseconds."""
        return self.temporal(entity).column("sim_time").cast(pa.int64()).to_numpy()

    def column(self, entity: str, component: str) -> list:
        return self.temporal(entity).column(component).to_pylist()

    def scalars(self, entity: str) -> np.ndarray:
        return np.array([row[0] for row in self.column(entity, "Scalars:scalars")])


@pytest.fixture(scope="module")
def fig2(tmp_path_factory):
    """The fig.-2 throw (event method, stops when settled), recorded at the default rate."""
    rr.set_strict_mode(True)
    tr = simulate(fig2_scene(), sample_dt=LOG_EVERY, record_events=True)
    path = tmp_path_factory.mktemp("rrd") / "fig2.rrd"
    info = rrd_io.write_recording(tr, rrd=path, log_every=LOG_EVERY)
    return tr, frames_io.build_frames(tr), info, Recording(path)


@pytest.fixture(scope="module")
def fig2_verlet(tmp_path_factory):
    """The same throw with a fixed-step method, run to t_end, so that the coin rocks on the
    ground and contacts switch often."""
    rr.set_strict_mode(True)
    scene = fig2_scene(method="verlet", dt=2e-5, t_end=0.6, stop_on_settle=False)
    tr = simulate(scene, sample_dt=LOG_EVERY, record_events=True)
    path = tmp_path_factory.mktemp("rrd") / "verlet.rrd"
    rrd_io.write_recording(tr, rrd=path, log_every=LOG_EVERY)
    return tr, frames_io.build_frames(tr), Recording(path)


def ns(seconds) -> np.ndarray:
    return np.round(np.asarray(seconds) * 1e9).astype(np.int64)


# -- the recording's contents ---------------------------------------------------------------------

def test_entities_exist(fig2):
    _, _, _, rec = fig2
    expected = {
        "/scene/world", "/scene/world/coin", "/scene/world/coin/body", "/scene/world/corners",
        "/scene/world/forces", "/scene/world/path", "/scene/world/ground",
        "/plots/energy/kinetic", "/plots/energy/gravitational", "/plots/energy/elastic",
        "/plots/energy/total", "/plots/energy/e_crit", "/plots/height/y",
        "/plots/angle/quarter_turns", "/plots/angle/n", "/events", "/info", "/info/parameters",
    } | {f"/plots/penetration/corner{i}" for i in range(4)}
    assert expected <= rec.entities, expected - rec.entities


def test_world_is_flipped_so_y_points_up(fig2):
    _, _, _, rec = fig2
    scale = rec.static("/scene/world").column("Transform3D:scale").to_pylist()[0][0]
    assert scale == [1.0, -1.0, 1.0]


def test_frames_are_the_samples_plus_the_exact_events(fig2):
    """The simulated frames are the display samples and the exact events; a run that stopped
    once settled ends with one more frame, the rest pose its well implies (scene only)."""
    tr, frames, info, rec = fig2
    sample_t, event_t = tr.samples[:, 0], tr.events[:, 0]
    assert len(tr.events) > 0
    expected = np.unique(np.concatenate([sample_t, event_t]))
    # the display rate, not the integrator's steps: about t_final / log_every frames
    assert len(sample_t) == pytest.approx(tr.t_final / LOG_EVERY, abs=3)
    simulated = frames.t[~frames.implied]
    assert len(frames) == info.frames == len(expected) + 1 and frames.implied[-1]
    np.testing.assert_array_equal(simulated, expected)
    for entity in ("/scene/world/coin", "/scene/world/corners", "/scene/world/forces",
                   "/scene/world/path", "/scene/follow"):
        times = rec.times(entity)
        assert len(times) == len(frames), entity
        np.testing.assert_array_equal(times, ns(frames.t))
    for entity in ("/plots/energy/total", "/plots/angle/quarter_turns",
                   "/plots/penetration/corner0"):
        np.testing.assert_array_equal(rec.times(entity), ns(simulated))
    assert set(ns(event_t)) <= set(rec.times("/scene/world/coin"))


def test_the_recording_ends_at_rest_in_the_settled_well(fig2):
    tr, frames, _, _ = fig2
    rest = frames.state[-1]
    assert rest[2] == pytest.approx(tr.quarter_turns * np.pi / 2) and not rest[3:].any()
    sink = tr.scene.coin.mass * tr.scene.g / (2 * tr.scene.foundation.k)
    assert rest[1] == pytest.approx(tr.scene.coin.r_t - sink)  # lying on two corners
    assert frames.contact[-1].sum() == 2 and frames.t[-1] > tr.t_final


def test_timeline_is_a_duration(fig2):
    _, _, _, rec = fig2
    assert pa.types.is_duration(rec.temporal("/scene/world/coin").schema.field("sim_time").type)


def test_logged_angle_is_the_simulated_one(fig2):
    tr, frames, _, rec = fig2
    q = np.array([row[0] for row in rec.column("/scene/world/coin", "Transform3D:quaternion")])
    assert not q[:, :2].any()  # about z: (0, 0, sin(phi / 2), cos(phi / 2))
    angles = 2 * np.arctan2(q[:, 2], q[:, 3])  # phi modulo a whole turn
    turns = np.round((frames.state[:, 2] - angles) / (2 * np.pi))
    np.testing.assert_allclose(angles + 2 * np.pi * turns, frames.state[:, 2], rtol=0,
                               atol=1e-6)  # float32
    # the plotted 2 phi / pi is float64: exact, and at the sample times it is the sample's phi
    quarter = rec.scalars("/plots/angle/quarter_turns")
    at_samples = np.searchsorted(frames.t, tr.samples[:, 0])
    np.testing.assert_array_equal(quarter[at_samples], 2.0 * tr.samples[:, 3] / math.pi)
    n = rec.scalars("/plots/angle/n")
    simulated = frames.state[~frames.implied]
    np.testing.assert_array_equal(n, np.round(2 * simulated[:, 2] / math.pi))
    assert n[-1] == tr.rounded_quarter_turns
    translation = np.array([row[0] for row in
                            rec.column("/scene/world/coin", "Transform3D:translation")])
    np.testing.assert_allclose(translation[:, :2], frames.state[:, :2] * 1e3, rtol=1e-6,
                               atol=1e-6)


def _check_colours(tr, frames, rec):
    colours = np.array(rec.column("/scene/world/corners", "Points2D:colors"), dtype=np.int64)
    assert colours.shape == (len(frames), 4)
    if frames.implied is not None and frames.implied.any():  # the rest pose: scene only
        colours, frames = colours[~frames.implied], frames.subset(~frames.implied)
    assert set(np.unique(colours)) <= {RED, BLUE}
    penetration = np.column_stack([rec.scalars(f"/plots/penetration/corner{i}")
                                   for i in range(4)])  # um
    assert (penetration > 0).any() and (colours == RED).any() and (colours == BLUE).any()
    event_rows = np.isin(frames.t, tr.events[:, 0])
    # between events: red exactly where the corner is below the surface
    clear = ~event_rows[:, None] & ((penetration > 1e-3) | (frames.heights > 1e-9))
    np.testing.assert_array_equal((colours == RED)[clear], (penetration > 0)[clear])
    # at an event the colour is the one after it: red from an onset, blue from a lift-off
    for t, corner, kind in tr.events[:, :3]:
        row = np.searchsorted(frames.t, t)
        assert colours[row, int(corner)] == (RED if kind > 0 else BLUE), (t, corner, kind)
    # one force arrow per red corner
    arrows = rec.column("/scene/world/forces", "Arrows2D:vectors")[:len(frames)]
    np.testing.assert_array_equal([len(a) for a in arrows], (colours == RED).sum(axis=1))
    positions = np.array(rec.column("/scene/world/corners", "Points2D:positions"))
    np.testing.assert_allclose(positions[:len(frames)], frames.corners * 1e3, rtol=1e-6,
                               atol=1e-5)


def test_contact_colours_agree_with_penetration(fig2):
    tr, frames, _, rec = fig2
    _check_colours(tr, frames, rec)


def test_contact_colours_agree_with_penetration_fixed_step(fig2_verlet):
    tr, frames, rec = fig2_verlet
    assert len(tr.events) > 10
    _check_colours(tr, frames, rec)


def test_contact_events_are_on_the_timeline(fig2):
    tr, _, _, rec = fig2
    texts = [row[0] for row in rec.column("/events", "TextLog:text")]
    times = rec.times("/events")
    for t, corner, kind in tr.events[:, :3]:
        word = "touches down" if kind > 0 else "lifts off"
        hits = [txt for tt, txt in zip(times, texts, strict=True)
                if tt == ns(t) and f"corner {int(corner)} {word}" in txt]
        assert len(hits) == 1, (t, corner, kind)
    assert any("settled" in t and f"n = {tr.quarter_turns}" in t for t in texts)


def test_parameters_and_version_are_stored(fig2):
    tr, _, _, rec = fig2
    doc = rec.static("/info").column("TextDocument:text").to_pylist()[0][0]
    assert __version__ in doc and "event" in doc and f"rtol = {tr.scene.integration.rtol:g}" in doc
    params = rec.static("/info/parameters")
    value = {name: params.column(name).to_pylist()[0] for name in params.column_names
             if not name.startswith("rerun")}
    flat = {k: (v[0] if isinstance(v, list) else v) for k, v in value.items()}
    assert flat["version"] == __version__
    assert flat["integration.method"] == "event"
    assert flat["integration.rtol"] == tr.scene.integration.rtol
    assert flat["initial.vy"] == 1.197 and flat["initial.vphi"] == 3.508
    assert flat["log_every"] == LOG_EVERY


def test_blueprint_is_stored(fig2):
    _, _, info, _ = fig2
    reader = RrdReader(info.rrd)
    blueprints = reader.blueprints()
    assert len(blueprints) == 1 and blueprints[0].application_id == "coin"
    origins, names, timelines = set(), set(), set()
    for chunk in reader.store(store=blueprints[0]).stream().to_chunks():
        batch = chunk.to_record_batch()
        for column, target in (("ViewBlueprint:space_origin", origins),
                               ("ViewBlueprint:display_name", names),
                               ("TimePanelBlueprint:timeline", timelines)):
            if column in batch.schema.names:
                target.update(v[0] for v in batch.column(column).to_pylist() if v)
    assert {"/scene", "/plots/energy", "/plots/height", "/plots/angle", "/plots/penetration",
            "/events", "/info"} <= {o if o.startswith("/") else "/" + o for o in origins}
    assert {"whole throw (y up, mm)", "close-up, following the coin (mm)"} <= names
    assert "/scene/follow" in {o if o.startswith("/") else "/" + o for o in origins}
    assert timelines == {"sim_time"}


# -- the numbers behind the scene -----------------------------------------------------------------

def test_energies_and_forces_match_the_model(fig2):
    tr, frames, _, _ = fig2
    p = model_params(tr.scene)
    model = PAPER.kernels("python")
    for row in range(0, len(frames), 7):
        state = frames.state[row]
        kinetic, gravity, elastic = model.energies(p, state)
        assert frames.kinetic[row] == pytest.approx(kinetic, rel=1e-12, abs=1e-18)
        assert frames.gravitational[row] == pytest.approx(gravity, rel=1e-12, abs=1e-18)
        assert frames.elastic[row] == pytest.approx(elastic, rel=1e-12, abs=1e-18)
        mask = int(sum(1 << i for i in range(4) if frames.contact[row, i]))
        ax, ay, _ = model.contact_accelerations(p, mask, state, math.cos(state[2]),
                                                math.sin(state[2]))
        fx, fy = frames.forces[row].sum(axis=0)
        m = tr.scene.coin.mass
        assert fx == pytest.approx(m * ax, rel=1e-9, abs=1e-12)
        assert fy - m * tr.scene.g == pytest.approx(m * ay, rel=1e-9, abs=1e-12)
    assert not frames.forces[~frames.contact].any()


# -- the command line -----------------------------------------------------------------------------

runner = CliRunner()


def test_cli_no_rrd_writes_nothing_and_json_parses(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["simulate", "--vy", "1.197", "--vphi", "3.508", "--no-rrd",
                                 "--json"])
    assert result.exit_code == 0, (result.stdout, result.stderr)
    data = json.loads(result.stdout)
    assert data["rrd"] is None and data["quarter_turns"] == 6
    assert list(tmp_path.iterdir()) == []


def test_cli_writes_coin_rrd_by_default(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["simulate", "--vy", "1.197", "--vphi", "3.508", "--json"])
    assert result.exit_code == 0, (result.stdout, result.stderr)
    data = json.loads(result.stdout)  # nothing but the JSON object on stdout
    assert data["rrd"] == "coin.rrd"
    assert (tmp_path / "coin.rrd").stat().st_size > 0
    assert len(RrdReader(tmp_path / "coin.rrd").blueprints()) == 1


def test_a_full_disk_leaves_no_recording_and_says_so(tmp_path, monkeypatch):
    """Rerun's file sink does not report a failed write; the recording is read back before it
    is renamed into place, so a file cut short (as on a full disk) is a one-line error and
    leaves neither a truncated .rrd nor a temporary file."""
    from coincli.recordings import stream as rerun_stream

    check = rerun_stream._check_complete

    def cut_short(path):
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 2])
        check(path)

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(rerun_stream, "_check_complete", cut_short)
    result = runner.invoke(app, ["simulate", "--vy", "1.197", "--vphi", "3.508"])
    assert result.exit_code == 2
    err = result.stderr.strip()
    assert err.startswith("error:") and len(err.splitlines()) == 1, err
    assert "disk full" in err, err
    assert list(tmp_path.iterdir()) == []


def test_cli_rrd_path_and_log_every(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "sub" / "throw.rrd"
    out.parent.mkdir()
    result = runner.invoke(app, ["simulate", "--vy", "1.197", "--vphi", "3.508", "--rrd",
                                 str(out), "--log-every", "0.01"])
    assert result.exit_code == 0, (result.stdout, result.stderr)
    assert str(out) in result.stdout and "frames" in result.stdout
    rec = Recording(out)
    assert 36 <= len(rec.times("/scene/world/coin")) <= 36 + 3 + 8  # 0.36 s / 10 ms + events


@pytest.mark.parametrize("args, fragment", [
    (["--rrd", "missing-dir/x.rrd"], "does not exist"),
    (["--rrd", "."], "directory"),
    (["--log-every", "0"], "--log-every"),
    (["--log-every", "1e-12"], "--log-every"),
    (["--connect", "localhost:9876"], "rerun+http"),
    (["--connect", "rerun+http://127.0.0.1:9/proxy", "--no-rrd"], "no Rerun viewer"),
])
def test_cli_bad_recording_options_fail_in_one_line(tmp_path, monkeypatch, args, fragment):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["simulate", *args])
    assert result.exit_code == 2, (result.stdout, result.stderr)
    assert result.stdout == ""
    err = result.stderr.strip()
    assert len(err.splitlines()) == 1 and fragment in err, err
    assert list(tmp_path.iterdir()) == []


def test_too_many_frames_names_no_rrd_and_the_smallest_log_every(tmp_path, monkeypatch):
    """The horizon of --t-end 2000 makes 2e6 frames of 1 ms: the message offers --no-rrd (the
    numbers only) and the smallest --log-every that fits, and following either works."""
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, ["simulate", "--t-end", "2000"])
    assert result.exit_code == 2, (result.stdout, result.stderr)
    err = result.stderr.strip()
    assert len(err.splitlines()) == 1, err
    assert "--no-rrd to write no recording" in err and "--log-every 0.002 or more" in err, err
    assert list(tmp_path.iterdir()) == []
    assert runner.invoke(app, ["simulate", "--t-end", "2000", "--no-rrd"]).exit_code == 0
    assert list(tmp_path.iterdir()) == []
    assert runner.invoke(app, ["simulate", "--t-end", "2000", "--log-every", "0.002"]
                         ).exit_code == 0
    assert (tmp_path / "coin.rrd").is_file()
    # where the file is not all that asks for frames, --no-rrd would not do
    err = runner.invoke(app, ["simulate", "--t-end", "2000", "--no-rrd", "--csv", "t.csv"]
                        ).stderr
    assert "--log-every 0.002 or more" in err and "--no-rrd" not in err, err


@pytest.mark.parametrize("horizon", [2000.0, 2.79801, 0.3, 7.0, 12.5, 1e-3, 0.14999999])
def test_the_smallest_log_every_said_fits_and_is_the_smallest_of_two_digits(horizon):
    from coincli.cli.recording import MAX_FRAMES, smallest_log_every

    said = float(smallest_log_every(horizon))
    assert horizon / said <= MAX_FRAMES
    unit = 10.0 ** (math.floor(math.log10(said)) - 1)  # one in its second significant digit
    assert horizon / (said - unit) > MAX_FRAMES


def test_rerun_is_not_imported_by_the_model():
    code = ("import sys, coincli.throw, coincli.integrators, coincli.recordings.rrd, coincli.cli; "
            "assert 'rerun' not in sys.modules, 'rerun imported'")
    subprocess.run([sys.executable, "-c", code], check=True)
