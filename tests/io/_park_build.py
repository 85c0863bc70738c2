"""Build a Park Systems spectroscopy TIFF from known arrays, for the tests of :mod:`afmforce.io.park` and
``tests/data/park-tiff_synthetic_2-spectra.tiff`` (``tests/data/make_park_example.py``).

Written with plain ``struct`` from the layout of Park's private TIFF tags (50432 magic, 50433 version,
50435 the 580-byte header, 50438 the spectroscopy header, 50439 the data; offsets as in the reader's
module docstring, which the real ``ForceCurve_009.tiff`` bears out), without afmforce. Every number
is chosen here: a 0.35 N/m lever, 25 V/um (40 nm/V), 0.5 um/s, 2 ms per sample, 20 approach and 17
retract samples padded to 32 each, channels Vertical (A-B) [V], Force [nN] = k / sensitivity x V,
Z Scan [um] (negative towards the sample, as Park's), Time Stamp [usec].
"""

from __future__ import annotations

import struct

import numpy as np

K, SENS_V_PER_UM, SPEED_UM_S = 0.35, 25.0, 0.5        # N/m, V/um (InvOLS 40 nm/V), um/s
RES, N_APP, N_RET, DT_US = 64, 20, 17, 2000.0          # samples per spectrum, real samples per run, step [us]
CHANNELS = (("Vertical (A-B)", "V", 0, 1), ("Force", "nN", 0, 1), ("Z Scan", "um", 1, 0),
            ("Time Stamp", "usec", 1, 0))


def _utf16(text: str, chars: int) -> bytes:
    return text.encode("utf-16-le").ljust(2 * chars, b"\0")


def _arrays(point: int):
    """The arrays of spectrum ``point`` in the file's units: the forward run descends in z (Park's Z Scan
    goes negative towards the sample), the backward run climbs back; each padded with its last sample."""
    z_app = -0.1 - SPEED_UM_S * DT_US * 1e-6 * np.arange(N_APP) - 0.01 * point
    z_ret = z_app[-1] + SPEED_UM_S * DT_US * 1e-6 * np.arange(N_RET)
    v_app = np.where(np.arange(N_APP) > 12, 0.02 * (np.arange(N_APP) - 12), 0.0) - 0.5 + 0.001 * point
    v_ret = np.linspace(v_app[-1], -0.6, N_RET)
    t_app = 100.0 + DT_US * np.arange(N_APP)
    t_ret = t_app[-1] + 500.0 + DT_US * np.arange(N_RET)
    out = []
    for app, ret in ((v_app, v_ret), (None, None), (z_app, z_ret), (t_app, t_ret)):
        out.append((app, ret))
    force = 1e9 * K / (SENS_V_PER_UM * 1e6)            # nN per V
    out[1] = (force * v_app, force * v_ret)
    half = RES // 2
    pad = lambda a: np.r_[a, np.full(half - a.size, a[-1])]   # noqa: E731
    return [np.r_[pad(a), pad(r)].astype("<f4") for a, r in out], (v_app, v_ret, z_app, z_ret, t_app, t_ret)


#: Park's data type codes (spectroscopy header, int32 at byte 1108) -> numpy type
DTYPES = {"i2": 0, "i4": 1, "f4": 2}


def stored(values, gain: float, offset: float, dtype: str) -> np.ndarray:
    """What the file holds for ``values`` (in the channel's unit) with the channel's gain and offset: the
    numbers whose ``number x gain + offset`` are the values, rounded to integers for int16/int32."""
    x = (np.asarray(values, float) - offset) / gain
    return (np.rint(x) if dtype != "f4" else x).astype("<" + dtype)


def grid_xy(p: int, volume) -> tuple[float, float]:
    """Position [um] of spectrum ``p`` of a ``volume`` (nx, ny, width, height, serpentine): row by row from
    the grid's origin (every other row backwards when serpentine), edge to edge over width x height."""
    nx, ny, width, height, serpentine = volume
    iy, ix = divmod(p, nx)
    if serpentine and iy % 2:
        ix = nx - 1 - ix
    return 0.5 + ix * width / max(nx - 1, 1), -1.0 + iy * height / max(ny - 1, 1)


def write_park(path, *, points=2, kind=2, version=2, k=K, sens=SENS_V_PER_UM, intensity=None, dtype="f4",
               gains=(1.0, 1.0, 1.0, 1.0), offsets=(0.0, 0.0, 0.0, 0.0), volume=None):
    """A little-endian Park TIFF: a 1 x 1 palette preview, Park's magic (50432) and version (50433), the
    580-byte header (50435; first int32 = ``kind``), and for spectroscopy the header (50438: 2972 bytes,
    version 2, or 936 bytes, version 1) and data (50439); ``intensity``: the header's intensity
    factor (float64 at byte 424; default zero: none). ``dtype``: ``"f4"``, ``"i2"`` or ``"i4"`` (written as
    :func:`stored` with each channel's ``gains`` and ``offsets``, in the channel's unit); ``volume``: (nx,
    ny, width [um], height [um], serpentine) of a force map of nx x ny = ``points`` spectra (volume flag at
    byte 804, points per x at 936, grid size at 944), each point's position :func:`grid_xy`."""
    if volume is not None:
        assert volume[0] * volume[1] == points
    head = bytearray(580)
    struct.pack_into("<i", head, 0, kind)
    if intensity is not None:
        struct.pack_into("<d", head, 424, intensity)
    head[4:68] = _utf16("Topography", 32)
    struct.pack_into("<ii", head, 100, 1, 1)
    struct.pack_into("<i", head, 348, 2)
    spec = bytearray(2972 if version == 2 else 936)
    for i, (name, unit, is_x, is_y) in enumerate(CHANNELS):
        o = 96 * i
        spec[o:o + 64], spec[o + 64:o + 80] = _utf16(name, 32), _utf16(unit, 8)
        struct.pack_into("<dii", spec, o + 80, gains[i], is_x, is_y)
        struct.pack_into("<d", spec, 808 + 8 * i, offsets[i])
    struct.pack_into("<5i", spec, 768, len(CHANNELS), 1, RES, points, 2)
    struct.pack_into("<4f", spec, 788, 1.0, 1.0, SPEED_UM_S, SPEED_UM_S)
    if volume is not None:
        struct.pack_into("<i", spec, 804, 1)
    if version == 2:
        if volume is not None:
            struct.pack_into("<ii4d", spec, 936, volume[0], 0, volume[2], volume[3], 0.0, 0.0)
        struct.pack_into("<dd", spec, 976, k, sens)
        struct.pack_into("<i", spec, 1108, DTYPES[dtype])
        for p in range(points):
            xy = grid_xy(p, volume) if volume is not None else (1.0 + p, 2.0)
            struct.pack_into("<3f", spec, 1208 + 12 * p, *xy, 0.0)
    data = b"".join(stored(a, g, o, dtype).tobytes() for p in range(points)
                    for a, g, o in zip(_arrays(p)[0], gains, offsets)) if kind == 2 else b""
    blocks = [(50435, 7, bytes(head))] + ([(50438, 7, bytes(spec)), (50439, 1, data)] if kind == 2 else [])
    inline = [(256, 4, 1, 1), (257, 4, 1, 1), (50432, 4, 1, 0x0E031301), (50433, 4, 1, 0x01000000 + version)]
    n = len(inline) + len(blocks)
    at = 8 + 2 + 12 * n + 4
    entries, body = list(inline), b""
    for tag, typ, raw in blocks:
        entries.append((tag, typ, len(raw), at + len(body)))
        body += raw
    ifd = struct.pack("<H", n) + b"".join(struct.pack("<HHII", *e) for e in sorted(entries)) + b"\0" * 4
    path.write_bytes(b"II*\x00" + struct.pack("<I", 8) + ifd + body)
    return path
