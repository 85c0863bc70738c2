"""An attacker's and a careless user's audit of ``afmforce serve`` (every route, docs/web.md "What the
web refuses"): each test is a request that answered wrongly before (a job started for a fit the CLI
refuses, a value ignored silently, a 400 or a field left unnamed, a computation going on after its client
left, as many simulations at once as the thread pool has threads), and the web's answers for one real
file of every reader family equal to the CLI's, no file written outside the session's folder and no
input file modified."""

from __future__ import annotations

import hashlib
import io
import json
import threading
import time
from contextlib import redirect_stdout
from pathlib import Path

import pytest

from realdata import DATA, real_file


def _error(r, status=422):
    assert r.status_code == status, r.text[:300]
    body = r.json()
    assert set(body) == {"error"} and "Traceback" not in r.text
    return body["error"]


# -- a fit the CLI refuses is refused before a process starts -----------------------------------------
@pytest.mark.parametrize("free, truth", [(["hamaker", "radius"], {}), (["xi"], {"model": "spring"}),
                                         (["xi"], {"friction": "none"})])
def test_fit_free_parameters_the_model_cannot_fit_are_refused_before_a_job(client, workers, free, truth):
    """Before: 202 and a job process that failed a few seconds later with the CLI's message."""
    from afmforce.dynamics import SimulationConfig
    from afmforce.errors import ParameterError
    from afmforce.fit.params import check_free

    cfg = SimulationConfig(**truth)
    with pytest.raises(ParameterError) as cli:       # what `afmforce fit --free ...` says before loading
        check_free(free, cfg.model, cfg.friction.law if cfg.model == "beam" else None)
    before = workers()
    err = _error(client.post("/api/fit", json={"free": free, "truth": truth, "velocities": [1e-6, 4e-6]}))
    assert err["field"] == "free" and err["message"] == str(cli.value).replace("`", "")
    assert client.get("/api/jobs").json() == [] and workers() == before


# -- every refusal names its field, never ignores a value ------------------------------------------------
def test_an_option_given_twice_names_its_field(client):
    """Before: 422 ``parameter_error`` with ``field`` null."""
    err = _error(client.post("/api/analyze", data={"example": "asylum-air",
                                                   "option": ["vdw.max_separation=1nm", "vdw.max_separation=2nm"]}))
    assert err["field"] == "option.vdw.max_separation" and err["type"] == "invalid_value"
    assert "given twice" in err["message"]


_CALIBRATION = b'{"afmforce_calibration": 1, "spring_constant": 0.1}'


def test_calibration_keys_are_never_ignored(client):
    """Before: 200, the key ``k`` (or the keys without a file) silently ignored: the analysis ran with the
    file's own spring constant while the user meant the calibration file's."""
    err = _error(client.post("/api/analyze", data={"example": "asylum-air", "calibration_keys": "k"},
                             files={"calibration": ("c.json", _CALIBRATION)}))
    assert err["field"] == "calibration_keys[0]" and "spring_constant" in err["message"]
    err = _error(client.post("/api/analyze", data={"example": "asylum-air", "calibration_keys": "spring_constant"}))
    assert err["field"] == "calibration_keys" and "calibration" in err["message"]
    ok = client.post("/api/analyze", data={"example": "asylum-air", "calibration_keys": "spring_constant"},
                     files={"calibration": ("c.json", _CALIBRATION)})
    assert ok.status_code == 200 and ok.json()["results"]["asylum-air"]["spring_constant"] == pytest.approx(0.1)


@pytest.mark.parametrize("file_id", ["%00", "0" * 32, "..%2F..%2Findex.json"])
def test_deleting_an_upload_that_is_not_this_sessions_is_not_found(make_client, file_id):
    """Before: 422 ``parameter_error`` (a job's unknown id was 404 already); another session's upload too."""
    err = _error(make_client().delete(f"/api/files/{file_id}"), 404)
    assert err["type"] == "not_found"
    owner = make_client()
    fid = owner.post("/api/analyze", files={"file": ("x.txt", b"1 2\n")}).json()["files"][0]["id"]
    assert _error(make_client().delete(f"/api/files/{fid}"), 404)["type"] == "not_found"
    assert [f["id"] for f in owner.get("/api/files").json()] == [fid]          # still there


@pytest.mark.parametrize("url", ["/api/simulate", "/api/simulate/raw", "/api/fit", "/api/sweep"])
@pytest.mark.parametrize("body, why", [(b"[" * 100_000, "nested too deeply"),
                                       (b'{"seed": ' + b"9" * 5000 + b"}", "4,300 digits")])
def test_json_bodies_python_cannot_read_say_why(client, url, body, why):
    """Before: 400 "There was an error parsing the body" (FastAPI's words)."""
    err = _error(client.post(url, content=body, headers={"content-type": "application/json"}))
    assert err["type"] == "invalid_request" and why in err["message"] and "application/json" in err["message"]


# -- bounded work: a slot per computation, stopped when its client leaves ------------------------------
def test_no_more_than_max_computing_simulations_run_at_once(client, monkeypatch):
    """Before: as many simulations at once as the thread pool has threads (40; 24 of 775,001 samples
    held 2.2 GB together). Twelve requests sent together now compute at most MAX_COMPUTING at a time,
    every one answered."""
    import afmforce.web.routes_simulate as routes
    from afmforce.web.limits import MAX_COMPUTING

    assert client.app.state.gate.slots == MAX_COMPUTING
    lock, now, most = threading.Lock(), [0], [0]
    real = routes.run

    def counted(*a, **k):
        with lock:
            now[0] += 1
            most[0] = max(most[0], now[0])
        try:
            time.sleep(0.3)         # every request overlaps the others (an order, not a verdict)
            return real(*a, **k)
        finally:
            with lock:
                now[0] -= 1

    monkeypatch.setattr(routes, "run", counted)
    codes = []
    threads = [threading.Thread(target=lambda: codes.append(
        client.post("/api/simulate?max_points=100", json={"velocity": 1e-5}).status_code)) for _ in range(12)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=300)
    assert codes == [200] * 12 and 1 <= most[0] <= MAX_COMPUTING


def test_a_full_queue_is_refused_busy(client, monkeypatch):
    """One slot, no queue: a second simulation while the first computes gets 429 ``busy``."""
    import afmforce.web.routes_simulate as routes
    from afmforce.web.compute import Gate

    monkeypatch.setattr(client.app.state, "gate", Gate(slots=1, queue=0))
    inside, release = threading.Event(), threading.Event()
    real = routes.run

    def held(*a, **k):
        inside.set()
        release.wait(60)
        return real(*a, **k)

    monkeypatch.setattr(routes, "run", held)
    first = []
    t = threading.Thread(target=lambda: first.append(client.post("/api/simulate?max_points=100", json={})))
    t.start()
    try:
        assert inside.wait(60)
        r = client.post("/api/simulate?max_points=100", json={})
        assert _error(r, 429)["type"] == "busy" and r.headers["retry-after"]
    finally:
        release.set()
        t.join(120)
    assert first[0].status_code == 200


def test_an_analysis_whose_client_left_stops(tmp_path, monkeypatch):
    """A live server; the client gives up half a second into an analysis of four curves, each taking a
    second. Before: the server analysed all four (its budget, 60 s, was the only stop); now the analysis
    stops after the curve it is on (at most two of the four)."""
    import socket

    import httpx
    import uvicorn

    import afmforce.web.routes_analyze as routes
    from afmforce.web import Settings, create_app
    from afmforce.web import analysis
    from afmforce.web.replies import PastBudget

    calls, ended = [], threading.Event()
    real_call, real_run = analysis.CachedAnalysis.__call__, routes.run_analysis

    def slow(self, ref):
        calls.append(ref)
        time.sleep(1.0)
        return real_call(self, ref)

    outcome = {}

    def watched(*a, **k):
        try:
            outcome["value"] = real_run(*a, **k)
            return outcome["value"]
        except PastBudget as exc:
            outcome["stopped"] = str(exc)
            raise
        finally:
            ended.set()

    monkeypatch.setattr(analysis.CachedAnalysis, "__call__", slow)
    monkeypatch.setattr(routes, "run_analysis", watched)
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    port = sock.getsockname()[1]
    app = create_app(Settings(port=port, data=tmp_path / "data", spare_job=False))
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    try:
        url = f"http://127.0.0.1:{port}/"
        for _ in range(600):
            if server.started and httpx.get(url + "api/health").json()["warm"]:
                break
            time.sleep(0.1)
        with pytest.raises(httpx.TimeoutException):
            httpx.post(url + "api/analyze", data={"example": ["asylum-air"] * 4}, timeout=0.5)
        assert ended.wait(60), "the analysis never ended"
    finally:
        server.should_exit = True
        thread.join(10)
    assert "client left" in outcome.get("stopped", "") and "value" not in outcome
    assert 1 <= len(calls) <= 2


# -- the web equals the CLI, writes only in the session's folder, never modifies an input ------------
#: One real file of every reader family the analyse view reads (shared real files, or the repository's
#: real or real-derived copies; tests/data/README.md).
FAMILIES = {
    "asylum-ibw": "asylum-mfp3d_SiN-tip_air.ibw",
    "bruker-nanoscope": "bruker-nanoscope_sapphire_TAP525.001",
    "bruker-ascii": DATA / "bruker-ascii_egel_force-separation.txt",
    "jpk-force": "jpk_cellhesion_spot3.jpk-force",
    "jpk-force map": "afmformats_jpk-fd_map2x2_extracted.jpk-force-map",
    "jpk-qi-data": DATA / "corpus" / "jpk-qi-data_2020.02.07.jpk-qi-data",
    "jpk-txt": "afmtoolkit_jpk-txt_4.2.53_force-save-1.txt",
    "nanosurf-nid map": DATA / "nanosurf-nid_spectroscopy-map_2x2_trimmed.nid",
    "asylum-ardf": DATA / "asylum-ardf_mfp3d-curve_2x2.ARDF",
    "afm-workshop-csv": "afm-workshop_single.csv",
    "ntmdt-txt": ("ntmdt_gel-in-water.txt", "spring_constant=0.1N/m", "sensitivity=50nm/V"),   # it stores neither
    "chiaro-txt": "optics11-piuma_V3.5.0_NanoPrepare_test2.txt",
    "park-tiff": "park-xe_nanoAFMr_ForceCurve_009.tiff",
    "wsxm-curves": DATA / "corpus" / "wsxm-curves_spectrocurve_0001_Normalforce.f.curves",
    "afmforce-raw": DATA / "afmforce-raw_jpk-cellhesion-spot3.txt",
    "afmforce-hdf5": DATA / "afmforce-hdf5_virtual-afm.h5",
    "afmforce-map": DATA / "afmforce-map_jpk-map2x2.h5",
    "afmformats-hdf5": DATA / "afmformats-hdf5_jpk-cellhesion-spot3.h5",
    "afmformats-tab": DATA / "afmformats-tab_asylum-sin-tip.tab",
}


def _digest(path: Path) -> tuple[str, int]:
    return hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime_ns


@pytest.mark.parametrize("family", list(FAMILIES))
def test_the_web_answers_what_the_cli_prints(make_client, tmp_path, family):
    from afmforce.cli.main import main

    name, *meta = FAMILIES[family] if isinstance(FAMILIES[family], tuple) else (FAMILIES[family],)
    src = name if isinstance(name, Path) else real_file(name)
    assert src.is_file(), f"{src} is missing from tests/data"   # real_file skips only for the shared files
    before = _digest(src)
    out = io.StringIO()
    with redirect_stdout(out):
        main(["analyze", str(src), "--json", *(f"--meta={m}" for m in meta)])
    cli = json.loads(out.getvalue())
    client = make_client(data=tmp_path / "data")
    r = client.post("/api/analyze", files={"file": (src.name, src.read_bytes())}, data={"meta": meta})
    assert r.status_code == 200, r.text[:300]
    api = r.json()
    assert set(api["results"]) == set(cli["results"]) and api["results"]
    for key, a in api["results"].items():
        c = dict(cli["results"][key])
        assert a.pop("source") == src.name and Path(c.pop("source")).name == src.name
        assert a == c, key                 # every number, verdict, warning and unit identical
    assert api["failed"] == [{"file": Path(f["file"]).name, "error": f["error"].replace(str(src), src.name)}
                             for f in cli["failed"]]
    assert _digest(src) == before          # never modified, by either face
    session = client.get("/api/session").json()
    written = [p.relative_to(tmp_path / "data") for p in (tmp_path / "data").rglob("*") if p.is_file()]
    folders = {p.parts[:2] for p in written}
    assert len(folders) == 1 and next(iter(folders))[0] == "sessions", written      # one session's folder
    assert sum(p.stat().st_size for p in (tmp_path / "data").rglob("*") if p.is_file()
               and p.name not in ("index.json", "last-used")) == session["stored"] == src.stat().st_size


# -- a force map declaring a million curves --------------------------------------------------------------
def _forged_ardf(path: Path, nx: int, ny: int) -> Path:
    """An ARDF map of one real curve whose every line pointer names its one line: ``nx`` x ``ny`` declared
    curves in ~70 kB (tests/io/_ardf_build.py writes the real curve's records)."""
    import importlib.util
    import struct

    spec = importlib.util.spec_from_file_location("_ardf_build", Path(__file__).parents[1] / "io" / "_ardf_build.py")
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    data, note = build.source_curve()
    cols = {c: data[:, j].astype(float) for j, c in enumerate(("Raw", "Defl", "ZSnsr"))}
    build.write_ardf(path, [(0, 0, cols)], nx=nx, ny=ny, note=note, ends=(224, 1232, 1260))
    raw = bytearray(path.read_bytes())
    at = raw.index(b"VTOC") - 8
    first = struct.unpack("<Q", raw[at + 64:at + 72])[0]       # line 0's pointer, given to every line
    for j in range(struct.unpack("<I", raw[at + 24:at + 28])[0]):
        raw[at + 32 + 40 * j + 32:at + 32 + 40 * j + 40] = struct.pack("<Q", first)
    path.write_bytes(bytes(raw))
    return path


def test_a_map_declaring_a_million_curves_is_refused_before_any_is_read(make_client, tmp_path, monkeypatch):
    """Before: a work item per declared curve (999,001, ~150 MB), then the analysis ran its whole budget
    and answered 504 past_budget. Now the reader refuses the line table that repeats its one line (branch
    mapcap), so the file is one damaged item named in the answer; and a map whose header declares more
    curves than a request takes (the caps lowered to 3 here, the 2 x 2 map's 4 curves) is 422 naming the
    file, from the header's count, nothing analysed."""
    from afmforce.errors import FileFormatError
    from afmforce.io.ardf import count_curves
    from afmforce.fit import core as fit_core
    from afmforce.web import analysis

    src = _forged_ardf(tmp_path / "forged.ARDF", 1000, 1000)
    assert src.stat().st_size < 100_000
    with pytest.raises(FileFormatError, match="line table names byte .* for recorded lines 0 and 1"):
        count_curves(src)
    calls = []
    real = analysis.CachedAnalysis.__call__
    monkeypatch.setattr(analysis.CachedAnalysis, "__call__", lambda self, ref: calls.append(ref) or real(self, ref))
    client = make_client(request_budget=5.0)
    r = client.post("/api/analyze", data={"example": "asylum-air"}, files={"file": ("forged.ARDF", src.read_bytes())})
    assert "line table names byte" in r.text and len(calls) == 2, r.text[:300]   # the example and the file, once

    honest = DATA / "asylum-ardf_mfp3d-curve_2x2.ARDF"
    assert count_curves(honest) == 4
    monkeypatch.setattr(analysis, "ANALYSIS_CURVES", 3)
    monkeypatch.setattr(fit_core, "MAX_CURVES", 3)
    calls.clear()
    err = _error(client.post("/api/analyze", data={"example": "asylum-air"},
                             files={"file": ("map.ARDF", honest.read_bytes())}))
    assert err["field"] == "file[0]" and "4 curves" in err["message"] and "afmforce analyze" in err["message"]
    fid = client.get("/api/files").json()[-1]["id"]
    err = _error(client.post("/api/analyze", data={"example": "asylum-air", "file_id": fid}))
    assert err["field"] == "file_id[0]"
    err = _error(client.post("/api/fit", json={"file_ids": [fid]}))
    assert err["field"] == "file_ids" and "4 curves" in err["message"]
    assert calls == []


def test_a_fit_never_ignores_velocities_or_meta(client, workers):
    """Before: ``file_ids`` with ``velocities`` fitted the uploads and dropped the speeds silently, and ``meta``
    with virtual curves was dropped (202 both)."""
    before = workers()
    fid = client.post("/api/analyze", files={"file": ("x.txt", b"1 2\n")}).json()["files"][0]["id"]
    err = _error(client.post("/api/fit", json={"file_ids": [fid], "velocities": [1e-6, 4e-6]}))
    assert err["field"] == "velocities" and "one or the other" in err["message"]
    err = _error(client.post("/api/fit", json={"velocities": [1e-6, 4e-6], "meta": ["spring_constant=0.1N/m"]}))
    assert err["field"] == "meta" and "file_ids" in err["message"]
    assert client.get("/api/jobs").json() == [] and workers() == before


@pytest.mark.parametrize("form", [{"option": "vdw.max_separation=abc"}, {"meta": "sensitivity=1e400"},
                                  {"probe": "radius=-1nm"}, {"step": "nope"}, {"format": "../x"},
                                  {"channel": "sideways"}])
def test_a_refused_analysis_stores_no_upload(make_client, tmp_path, form):
    """Before: the upload was stored first (counted against the session's storage, its id never sent back),
    then the typo refused: each retry of a 200 MB file left 200 MB on the server's disk."""
    from afmforce.datasets import path

    client = make_client(data=tmp_path / "data")
    src = path("asylum-air")
    _error(client.post("/api/analyze", files={"file": (src.name, src.read_bytes())}, data=form))
    assert client.get("/api/files").json() == [] and client.get("/api/session").json()["stored"] == 0
    assert not [p for p in (tmp_path / "data").rglob("*") if p.is_file()]


def test_an_upload_is_copied_to_disk_never_read_whole_into_memory(client, monkeypatch):
    """Before: ``await up.read()`` held each upload in the server's memory (two 150 MB uploads sent together:
    the server's peak +380 MB; now +82 MB, measured with psutil on a live server). The route now copies the
    request's spooled part to the session's folder: ``UploadFile.read`` is never called for a curve file."""
    from starlette.datastructures import UploadFile

    from afmforce.datasets import path

    reads = []
    real = UploadFile.read

    async def read(self, size=-1):
        reads.append((self.filename, size))
        return await real(self, size)

    monkeypatch.setattr(UploadFile, "read", read)
    src = path("asylum-air")
    r = client.post("/api/analyze", files={"file": (src.name, src.read_bytes())})
    assert r.status_code == 200 and r.json()["files"][0]["size"] == src.stat().st_size
    assert r.json()["results"][src.name]["pull_off_force"] < 0
    assert [name for name, _ in reads if name == src.name] == []


@pytest.mark.parametrize("url, extra", [("/api/calibration", {}), ("/api/analyze", {"example": "asylum-air"})])
def test_a_huge_calibration_file_is_refused_without_reading_it_whole(client, monkeypatch, url, extra):
    """Before: a 5 MB "calibration" file was read whole into memory, then refused for its size."""
    from starlette.datastructures import UploadFile

    from afmforce.web.limits import CALIBRATION_BYTES

    sizes = []
    real = UploadFile.read

    async def read(self, size=-1):
        sizes.append(size)
        return await real(self, size)

    monkeypatch.setattr(UploadFile, "read", read)
    part = "file" if url == "/api/calibration" else "calibration"
    err = _error(client.post(url, data=extra, files={part: ("c.json", b" " * 5_000_000)}))
    assert err["field"] == "calibration" and "5,000,000 bytes is not a calibration file" in err["message"]
    assert sizes == [CALIBRATION_BYTES + 1]


@pytest.mark.parametrize("host", ["[::1", "[zz]", "[127.0.0.1"])
def test_a_malformed_host_header_is_refused_not_a_500(client, host):
    """Before: ``Host: [::1`` (curl -H 'Host: [::1' ...) answered 500 internal, a traceback in the log
    (``urlsplit`` raised ValueError in the security layer)."""
    err = _error(client.get("/api/health", headers={"host": host}), 403)
    assert err["type"] == "forbidden" and "Host header is malformed" in err["message"]
