"""More public files never read here before (tests/data/README.md, "Files tried", second round).

Each test asserts against values read without afmforce (header text with a regular expression, the
table with numpy), a closed form, or nanite 4.2.3. The files are GPL or carry no licence: they are not in
tests/data but looked for in ``AFMFORCE_REAL_DATA`` (tests/realdata.py) and skipped where absent; each fix
is also tested on a synthetic file written here in the same layout.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from afmforce.io import load
from realdata import nanite_hertz_para, real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

# --- a step (multi-) indentation: extend, hold, extend, hold, ..., retract -------------------------------

K, R, E, NU = 0.05, 5e-6, 2000.0, 0.5          # [N/m], [m], [Pa], [-]
STIFF = 4.0 / 3.0 * E / (1 - NU ** 2) * math.sqrt(R)   # Hertz paraboloid: F = STIFF * delta^1.5 [N m^-1.5]


def _hertz(z: np.ndarray) -> np.ndarray:
    """The Hertz force [N] at piezo position ``z`` [m] (contact at z = 0, a lever of K): z = delta + F / K."""
    delta = np.linspace(0.0, 3e-6, 300001)
    f = STIFF * delta ** 1.5
    return np.interp(z, delta + f / K, f, left=0.0)


def _jpk_text(path: Path, blocks: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]) -> None:
    """A JPK Data Processing text export in the layout of afmToolkit's ``force-save-JPK-multiIndent.txt``
    (one ``# segment:`` block per segment: height [m, decreasing into the sample], vDeflection [N], seriesTime)."""
    out = ["# TEXT EXPORT", "# data-description.instrument: JPK00563-CellHesion",
           "# data-description.source-software: 5.0.135"]
    for i, (style, z, f, t) in enumerate(blocks):
        out += ["# index: 0", f"# segmentIndex: {i}", f"# recorded-num-points: {z.size}", f"# segment: {style}",
                "# columns: height vDeflection seriesTime", "# sensitivity: 3.5E-8", f"# springConstant: {K}",
                "# units: m N s", "#"]
        out += [f"{-a:.9e} {b:.6e} {c:.6f}" for a, b, c in zip(z, f, t)]
        out.append("")
    path.write_text("\n".join(out))


def _step_indentation(path: Path, rng: np.random.Generator) -> int:
    """Extend from 10 um out to 1 um into a Hertz sample, hold (the force relaxes to 60 %), extend 0.4 um
    deeper twice more with holds, retract. Returns the first extend's sample count."""
    noise = 2e-12
    z1 = np.linspace(-10e-6, 1e-6, 2200)
    blocks, t0 = [], 0.0

    def add(style, z, f):
        nonlocal t0
        t = t0 + np.arange(z.size) * 1e-3
        t0 = float(t[-1]) + 1e-3
        blocks.append((style, z, f + rng.normal(0, noise, z.size), t))

    add("extend", z1, _hertz(z1))
    top, level = z1[-1], float(_hertz(z1[-1:])[0])
    for _ in range(2):
        hold = np.full(400, top)
        relaxed = level * (0.6 + 0.4 * np.exp(-np.arange(400) / 80.0))
        add("pause", hold, relaxed)
        z = np.linspace(top, top + 0.4e-6, 300)
        f = relaxed[-1] + _hertz(z) - _hertz(np.array([top]))[0]
        add("extend", z, f)
        top, level = z[-1], float(f[-1])
    add("pause", np.full(400, top), level * (0.6 + 0.4 * np.exp(-np.arange(400) / 80.0)))
    zr = np.linspace(top, -10e-6, 2500)
    add("retract", zr, 0.5 * _hertz(zr - (top - 1e-6)))
    _jpk_text(path, blocks)
    return z1.size


def test_step_indentation_approach_is_its_first_extend(tmp_path):
    """afmToolkit's multi-indent JPK export (extend, pause, extend, pause, ..., retract) was read with its four
    extends as one approach, the holds' relaxation drops inside it: the Hertz fit ran over the steps. A synthetic
    export of the same layout (Hertz paraboloid, E = 2 kPa, R = 5 um): the approach is the first extend only,
    the later extends are dwell, a warning says so, and the modulus is the sample's (before: biased by the steps)."""
    from afmforce.analysis.options import IndentationOptions
    from afmforce.analysis.pipeline import analyze

    path = tmp_path / "force-save-multiIndent.txt"
    n_first = _step_indentation(path, np.random.default_rng(7))
    (c,) = load(path)
    runs = [int(c.segment[0])] + [int(b) for a, b in zip(c.segment[:-1], c.segment[1:]) if a != b]
    assert runs == [0, 2, 1]
    assert int(np.sum(c.segment == 0)) == n_first
    assert "step indentation: 3 extend segments" in c.metadata["approach_steps"]
    r = analyze(c, options=[IndentationOptions(model="hertz_paraboloid", tip_radius=R, poisson=NU)])
    assert any(w.startswith("step indentation") for w in r.warnings)
    assert r.contact_kind == "soft"
    assert r.youngs_modulus == pytest.approx(E, rel=0.03)
    assert r.youngs_modulus_low <= E <= r.youngs_modulus_high


@pytest.mark.parametrize("runs", [(0, 2, 1), (2, 0, 2, 1), (0, 1, 0, 1), (0, 2, 1, 2, 0, 1)])
def test_one_extend_before_the_retract_is_unchanged(runs):
    """A curve with one extend run before its retract (extend, pause, retract; a pause first) keeps its
    segments, and so does a cyclic one (an extend after a retract starts a new cycle, no step): no note."""
    from afmforce.io._meta import first_approach_only
    from afmforce.io.curve import RawCurve

    seg = np.repeat(np.array(runs, dtype=np.int8), 5)
    z = np.cumsum(np.where(seg == 0, 1.0, np.where(seg == 1, -1.0, 0.0)))
    c = RawCurve(time=np.arange(seg.size, dtype=float), piezo_nominal=z, piezo_measured=None,
                 deflection_signal=np.zeros(seg.size), segment=seg, metadata={}, deflection_unit="V")
    assert first_approach_only(c) is c


def _jpk_text_blocks(path: Path) -> list[dict]:
    """A JPK text export's segment blocks read with numpy: style, columns, springConstant, table."""
    blocks, cur = [], None
    for line in path.read_text(encoding="latin-1").splitlines():
        if line.startswith("# segment:"):
            cur = {"style": line.split(":", 1)[1].strip(), "rows": []}
            blocks.append(cur)
        elif cur is not None and line.startswith("# columns:"):
            cur["columns"] = line.split(":", 1)[1].split()
        elif cur is not None and line.startswith("# springConstant:"):
            cur["k"] = float(line.split(":", 1)[1])
        elif cur is not None and line.strip() and not line.startswith("#"):
            cur["rows"].append(line)
    for b in blocks:
        b["table"] = np.array([[float(v) for v in r.split()] for r in b["rows"]])
    return blocks


def test_real_jpk_multi_indent_export_approach_is_the_first_extend():
    """afmToolkit (GPL: not kept) ``inst/force-save-JPK-multiIndent.txt``: JPK CellHesion 5.0.135, segmented
    force settings, four extends (4096 points, then three triggered 0.5 um steps) with 10 s holds between them.
    The approach is the first extend's 4096 rows exactly (the header's, read with numpy), the force its
    vDeflection [N]; k as the header states it."""
    path = real_file("afmtoolkit_jpk-txt_5.0.135_multi-indent.txt")
    blocks = _jpk_text_blocks(path)
    assert [b["style"] for b in blocks] == ["extend", "pause"] * 4 + ["retract"]
    (c,) = load(path)
    first = blocks[0]["table"][:, blocks[0]["columns"].index("vDeflection")]
    np.testing.assert_array_equal(c.deflection_signal[c.segment == 0], first)
    assert c.metadata["spring_constant"] == blocks[0]["k"]
    assert "step indentation: 4 extend segments" in c.metadata["approach_steps"]


# --- a cut-down JPK archive: fewer samples than its header states ----------------------------------------

CUT = Path(__file__).resolve().parents[1] / "data" / "refused" / "jpkay_cut-down_retract-1000-of-78635.jpk-force"


@pytest.mark.parametrize("fmt", [None, "jpk-zip"])
def test_cut_down_jpk_archive_is_refused_naming_what_it_lacks(fmt):
    """tku137/JPKay's test fixture ``tests/data/sample.jpk-force`` (MIT, kept in tests/data/refused): a JPK
    archive cut down to one retract segment of 1000 samples (4000-byte channels) while its header states 78635
    and lists four channels, two absent. It was refused as "data file ... capacitiveSensorHeight.dat is
    missing", which says neither why nor what to give; a reader that took the 1000 samples would have divided
    the header's 15.7 s duration by them (a 64 Hz time base for a 5 kHz curve). Now one line: how many samples
    of how many (the header's, read with zipfile), and what to give instead."""
    import zipfile

    from afmforce.errors import FileFormatError

    with zipfile.ZipFile(CUT) as arc:
        (head,) = [n for n in arc.namelist() if n.endswith("segment-header.properties")]
        stated = int(re.search(r"force-segment-header\.num-points=(\d+)", arc.read(head).decode()).group(1))
        (dat,) = [n for n in arc.namelist() if n.endswith("vDeflection.dat")]
        held = arc.getinfo(dat).file_size // 4
    assert (held, stated) == (1000, 78635)
    with pytest.raises(FileFormatError) as err:
        load(CUT, format=fmt) if fmt else load(CUT)
    msg = str(err.value)
    assert "\n" not in msg
    assert f"holds {held} of the {stated} samples" in msg and "as the JPK software saved it" in msg


# --- NanoScope 9.1 BioScope Catalyst force files on chromosomes (PLSysGitHub, no licence: not kept) ------

def _nanoscope_chunks(path: Path) -> tuple[str, dict[str, np.ndarray]]:
    """A NanoScope force file read without afmforce: its header text and each channel's int16 samples x V/LSB."""
    raw = path.read_bytes()
    head = raw[:raw.index(b"\x1a")].decode("latin-1")
    chans = {}
    for block in head.split("\\*Ciao force image list")[1:]:
        at = int(re.search(r"\\Data offset: (\d+)", block).group(1))
        n = int(re.search(r"\\Data length: (\d+)", block).group(1))
        lsb = float(re.search(r"Z scale: V \[.*?\] \(([\d.eE+-]+) V/LSB\)", block).group(1))
        chans[re.search(r"Image Data: S \[(\w+)\]", block).group(1)] = np.frombuffer(raw[at:at + n], "<i2") * lsb
    return head, chans


@pytest.mark.parametrize("name", ["bruker-nanoscope_v9.1_Catalyst_PLSys_cr00028.000",
                                  "bruker-nanoscope_v9.1_Catalyst_PLSys_cr00043.000",
                                  "bruker-nanoscope_v9.1_Catalyst_PLSys_cr00082.000"])
def test_real_catalyst_chromosome_curves_agree_with_nanite(name):
    """PLSysGitHub/Nanoscope_ForceCurve_analysis ``Example_RawData/cr000*.000`` (NanoScope 9.1, BioScope Catalyst,
    PeakForce QNM head in force mode, 4096 + 4096 samples, the header's 5 nm tip; no licence: not kept): k and
    DeflSens as the header states them (regex), and the default Hertz paraboloid modulus within 3 % of nanite
    4.2.3's on the file parsed here (129.5 vs 129.5, 195.0 vs 191.9, 261.7 vs 264.2 kPa; read as a user types it)."""
    pytest.importorskip("nanite")   # the bench extra: the reference fit

    from afmforce.analysis.pipeline import analyze

    path = real_file(name)
    head, chans = _nanoscope_chunks(path)
    k = float(re.search(r"\\Spring Constant: ([\d.]+)", head).group(1))
    sens = float(re.search(r"Sens\. DeflSens: V ([\d.]+)", head).group(1)) * 1e-9
    radius = float(re.search(r"\\Tip Radius: ([\d.]+)", head).group(1)) * 1e-9
    force = k * sens * chans["DeflectionError"]
    z = chans["ZSensor"] * float(re.search(r"Sens\. ZsensSens: V ([\d.]+)", head).group(1)) * 1e-9
    half = force.size // 2     # the approach stored turning point first
    force, z = np.r_[force[:half][::-1], force[half:]], np.r_[z[:half][::-1], z[half:]]
    e_nanite = nanite_hertz_para(force, z, radius, k)
    (c,) = load(path)
    assert c.metadata["spring_constant"] == k
    assert c.metadata["sensitivity"] == pytest.approx(sens, rel=1e-12)
    assert c.metadata["radius"] == pytest.approx(radius, rel=1e-12)
    r = analyze(c)
    assert r.contact_kind == "soft"
    assert r.youngs_modulus == pytest.approx(e_nanite, rel=0.03)
