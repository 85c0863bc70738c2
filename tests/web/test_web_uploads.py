"""Uploads the page must read as the CLI does (issue 33): an Asylum curve saved as one Igor wave per
channel (``...Defl.ibw`` + ``...ZSnsr.ibw``), and a file without a time base (its "time" is the
sample index, said so in the raw signals the page draws)."""

from __future__ import annotations

import importlib.util
import io
import json
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

fastapi = pytest.importorskip("fastapi")

DATA = Path(__file__).resolve().parents[1] / "data"
REAL = DATA / "asylum-mfp3d_ForceMetric_X60_3_x4_0100.ibw"      # one wave: Raw, Defl, ZSnsr (MIT)
PREFIX = "ForceMetric_X60_3_x4_0100"


def _writer():
    """``write_ibw`` of the reader's own tests (tests/io/test_asylum_pairs.py): a plain Igor v5 wave."""
    spec = importlib.util.spec_from_file_location("_asylum_pairs", Path(__file__).parents[1] / "io" / "test_asylum_pairs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.write_ibw


def split_channels(folder: Path) -> dict[str, Path]:
    """The real three-channel MFP-3D wave saved as the instrument saves per-channel waves:
    ``PREFIXDefl.ibw`` and ``PREFIXZSnsr.ibw``, each with the wave's note (read with igor2)."""
    from igor2 import binarywave

    wave = binarywave.load(REAL)["wave"]
    data, note = wave["wData"], wave["note"].decode("latin-1")
    labels = [b.decode() for b in wave["labels"][1][1:]]
    step = float(wave["wave_header"]["sfA"][0])
    write = _writer()
    out = {}
    for channel in ("Defl", "ZSnsr"):
        out[channel] = folder / f"{PREFIX}{channel}.ibw"
        write(out[channel], data[:, labels.index(channel)], note, step=step, name=channel)
    return out


def _cli(paths) -> dict:
    from afmforce.cli.main import main

    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", *map(str, paths), "--json"]) == 0
    return json.loads(out.getvalue())


def test_per_channel_asylum_waves_uploaded_together_are_one_curve(client, tmp_path):
    """Both waves in one upload: each is read with its partner as one curve, the JSON equal to
    ``afmforce analyze PREFIXDefl.ibw PREFIXZSnsr.ibw --json``; the curve is the real file's
    (its Defl and ZSnsr columns, read independently with igor2)."""
    from igor2 import binarywave

    waves = split_channels(tmp_path)
    cli = _cli(waves.values())
    assert not cli["failed"] and len(cli["results"]) == 2
    files = [("file", (p.name, p.read_bytes())) for p in waves.values()]
    r = client.post("/api/analyze", files=files, data={"arrays": "true", "max_points": "4000"})
    assert r.status_code == 200, r.text
    api = r.json()
    assert api["failed"] == [] and sorted(api["results"]) == sorted(cli["results"])
    for name, res in api["results"].items():
        want = dict(cli["results"][name])
        got = {k: v for k, v in res.items() if k in want}
        got.pop("source"), want.pop("source")
        assert got == want
        assert res["source"] == name                        # no stored name shown
    raw = api["raw"][f"{PREFIX}Defl.ibw"]
    wave = binarywave.load(REAL)["wave"]
    labels = [b.decode() for b in wave["labels"][1][1:]]
    defl = wave["wData"][:, labels.index("Defl")].astype(float)
    assert len(raw["signal"]) == defl.size and raw["unit"] == "m"
    np.testing.assert_allclose(raw["signal"], defl, rtol=1e-6)     # the Defl wave, not a lone channel
    assert raw["time_base"] is True


def test_the_partner_wave_uploaded_later_pairs_too(client, tmp_path):
    """One channel alone fails with the reader's reason, naming the partner as the user named it
    (no stored name, no server path); uploaded afterwards, the partner completes the curve, as
    a second file copied into the folder does for the CLI."""
    waves = split_channels(tmp_path)
    first = client.post("/api/analyze", files={"file": (waves["Defl"].name, waves["Defl"].read_bytes())}).json()
    assert first["results"] == {} and len(first["failed"]) == 1
    msg = first["failed"][0]["error"]
    assert f"keep {PREFIX}Defl.ibw and {PREFIX}ZSnsr.ibw together" in msg, msg
    assert "sessions" not in msg and str(tmp_path) not in msg
    fid = first["files"][0]["id"]
    second = client.post("/api/analyze", files={"file": (waves["ZSnsr"].name, waves["ZSnsr"].read_bytes())},
                         data={"file_id": fid}).json()
    assert second["failed"] == [] and sorted(second["results"]) == sorted(p.name for p in waves.values())
    cli = _cli(waves.values())["results"]
    got = second["results"][f"{PREFIX}Defl.ibw"]
    assert got["contact_kind"] == cli[f"{PREFIX}Defl.ibw"]["contact_kind"]
    assert got["adhesion_force"] == cli[f"{PREFIX}Defl.ibw"]["adhesion_force"]
    # the same wave name again replaces the earlier upload (a folder holds one file of a name)
    again = client.post("/api/analyze", files={"file": (waves["Defl"].name, waves["Defl"].read_bytes())}).json()
    listed = client.get("/api/files").json()
    assert [f["name"] for f in listed].count(f"{PREFIX}Defl.ibw") == 1
    assert again["files"][0]["id"] in {f["id"] for f in listed} and fid not in {f["id"] for f in listed}


def test_stored_names_of_channel_waves_hold_nothing_the_user_typed(tmp_path):
    """The stored name is a hash and a channel word of the reader's list: a hostile name never
    reaches the file system; two sessions' waves of one name never meet."""
    from afmforce.io.igor import CHANNELS, POSITIONS
    from afmforce.web.sessions import channel_name

    a = channel_name("../../etc/Map1Point0000Defl.ibw", "session-a")
    b = channel_name("Map1Point0000ZSnsr.ibw", "session-a")
    c = channel_name("Map1Point0000ZSnsr.ibw", "session-b")
    assert a[:32] == b[:32] != c[:32] and a.endswith("Defl.ibw") and b.endswith("ZSnsr.ibw")
    assert all(ch in CHANNELS or ch in POSITIONS for ch in (a[32:-4], b[32:-4]))
    assert channel_name("curve.ibw", "s") is None and channel_name("Defl.ibw", "s") is None
    assert channel_name("xDefl.jpk-force", "s") is None


def test_a_file_without_a_time_base_says_so(client):
    """AFM Workshop's CSV has no time column and no sample rate: the raw signals the page draws
    against time carry ``time_base: false`` (the page titles that axis "sample index"), and the
    "time" is the sample index, 0, 1, 2, ...; a file with a sample rate has ``time_base: true``."""
    from afmforce.io import load

    path = DATA / "afm-workshop_single.csv"
    assert load(path)[0].metadata.get("time_is_sample_index") is True
    r = client.post("/api/analyze", files={"file": (path.name, path.read_bytes())},
                    data={"arrays": "true", "max_points": "20000"}).json()
    raw = r["raw"][path.name]
    assert raw["time_base"] is False
    assert raw["time"] == [float(i) for i in range(len(raw["time"]))]
    timed = client.post("/api/analyze", data={"example": "asylum-air", "arrays": "true"}).json()
    assert all(x["time_base"] is True for x in timed["raw"].values())
