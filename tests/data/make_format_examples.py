"""Write the example files of the registered formats that have no instrument file in tests/data.

Every format in ``afmforce.io.FORMATS`` must have at least one file here
(``tests/io/test_examples.py``). These six are written from real curves (one from
the virtual AFM, because only a simulation has ground truth), thinned so that each
stays well under 100 kB:

``afmforce-raw_jpk-cellhesion-spot3.txt`` (afmforce-raw)
    ``jpk_cellhesion_spot3.jpk-force`` read in raw volts (``format="jpk-zip"``,
    k and InvOLS from the file), every 8th sample, written by
    :func:`afmforce.io.native.rawfile.write_raw`.
``afmforce-hdf5_virtual-afm.h5`` (afmforce-hdf5)
    ``afmforce simulate --instrument typical --seed 1 --velocity 1um/s
    --acquisition-sample-rate 2kHz --raw ...``: the paper's Fig 5 beam through the
    "typical" virtual AFM, with its ``truth`` group (separation, forces, drift...).
``afmforce-map_jpk-map2x2.h5`` (afmforce-map)
    The four curves of ``shared/data/real/afmformats_jpk-fd_map2x2_extracted.jpk-force-map``
    (the corners of a 10 x 10 JPK map; calibrated, in N), each thinned to about
    300 samples, on their grid positions of a 10 x 10 map, written by
    :func:`afmforce.io.native.rawmap.write_map`.
``afmformats-hdf5_jpk-cellhesion-spot3.h5`` (afmformats-hdf5)
    ``jpk_cellhesion_spot3.jpk-force`` read by afmformats, every 8th sample,
    exported by afmformats' own ``AFMForceDistance.export_data(fmt="hdf5")``.
``afmformats-tab_asylum-sin-tip.tab`` (afmformats-tab)
    ``asylum-mfp3d_SiN-tip_air.ibw`` read by afmformats, every 4th sample,
    exported by ``AFMForceDistance.export_data(fmt="tab")``.
``chiaro-txt_AEBP1_Indentation_002_thinned.txt`` (chiaro-txt)
    A real Optics11 Chiaro export, afmformats' test file
    ``tests/data/fmt-chiaro-txt_AEBP1_Indentation_002.zip`` (afmformats 0.18.7
    sdist, MIT): header kept byte for byte (ISO-8859-1 micro signs, mixed line
    ends), every 10th data row plus the row of maximum load (where afmformats
    splits approach from retract). Get the source with
    ``pip download afmformats==0.18.7 --no-binary :all: --no-deps`` and pass the
    unpacked ``.zip`` with ``--chiaro-zip``; without it the existing file is kept.

Run from the repository root::

    python tests/data/make_format_examples.py [--shared DIR] [--chiaro-zip FILE]

A rerun rewrites every file byte for byte (checked with afmformats 0.18.7; another h5py
or afmformats version may lay out the HDF5 files differently, not their data).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SHARED = HERE.parents[2] / "shared" / "data" / "real"
CHIARO_MEMBER = "fmt-chiaro-txt_AEBP1_Indentation_002.txt"

RAW_TXT = "afmforce-raw_jpk-cellhesion-spot3.txt"
RAW_H5 = "afmforce-hdf5_virtual-afm.h5"
MAP_H5 = "afmforce-map_jpk-map2x2.h5"
AF_H5 = "afmformats-hdf5_jpk-cellhesion-spot3.h5"
AF_TAB = "afmformats-tab_asylum-sin-tip.tab"
CHIARO = "chiaro-txt_AEBP1_Indentation_002_thinned.txt"

#: Thinning steps (every n-th sample); the map's curves are thinned to about MAP_POINTS samples.
RAW_STEP, AF_H5_STEP, AF_TAB_STEP, CHIARO_STEP, MAP_POINTS = 8, 8, 4, 10, 300
_KEEP = ("spring_constant", "sensitivity", "velocity", "retract_velocity", "instrument")


def thin(curve, step: int, source: str):
    """Every ``step``-th sample of a RawCurve, with the sample rate divided by ``step``."""
    cut = slice(None, None, step)
    meta = {k: curve.metadata[k] for k in _KEEP if k in curve.metadata}
    if "sample_rate" in curve.metadata:
        meta["sample_rate"] = curve.metadata["sample_rate"] / step
    meta["source"] = source
    return dataclasses.replace(
        curve, time=curve.time[cut], piezo_nominal=curve.piezo_nominal[cut],
        piezo_measured=None if curve.piezo_measured is None else curve.piezo_measured[cut],
        deflection_signal=curve.deflection_signal[cut], segment=curve.segment[cut], metadata=meta, truth=None)


def make_raw_text() -> None:
    from afmforce.io import load
    from afmforce.io.native.rawfile import write_raw

    curve = load(HERE / "jpk_cellhesion_spot3.jpk-force", format="jpk-zip")[0]
    write_raw(thin(curve, RAW_STEP, f"tests/data/jpk_cellhesion_spot3.jpk-force (jpk-zip), every {RAW_STEP}th "
                                    "sample"), HERE / RAW_TXT, force=True)


def make_raw_hdf5() -> None:
    from afmforce.cli.main import main

    status = main(["simulate", "--instrument", "typical", "--seed", "1", "--velocity", "1um/s",
                   "--acquisition-sample-rate", "2kHz", "--raw", str(HERE / RAW_H5), "--force", "--no-progress"])
    if status:
        raise SystemExit(f"afmforce simulate failed ({status})")


def make_map(shared: Path) -> None:
    from afmforce.io import load
    from afmforce.io.native.rawmap import write_map

    src = shared / "afmformats_jpk-fd_map2x2_extracted.jpk-force-map"
    curves = load(src)
    out = []
    for c in curves:
        step = max(1, len(c) // MAP_POINTS)
        t = thin(c, step, f"shared/data/real/{src.name}, every {step}th sample")
        meta = {**t.metadata, **{k: c.metadata[k] for k in ("map_x", "map_y", "position_x", "position_y")}}
        out.append(dataclasses.replace(t, metadata=meta))
    shape = (curves[0].metadata["map_ny"], curves[0].metadata["map_nx"])
    write_map(out, HERE / MAP_H5, shape=shape, force=True)


def _afmformats_thinned(path: Path, step: int):
    import afmformats

    src = afmformats.load_data(path)[0]
    data = {col: np.asarray(src[col])[::step] for col in src.columns if col != "index"}
    meta = {k: v for k, v in src.metadata.items() if k != "z range"}  # z range: computed lazily from the data
    meta["path"] = Path(path.name)  # no local path in the export
    meta["point count"] = data["force"].size
    for key in ("rate approach", "rate retract"):
        if key in meta:
            meta[key] = meta[key] / step
    return afmformats.AFMForceDistance(data, meta)


def make_afmformats_exports() -> None:
    with tempfile.TemporaryDirectory() as tmp:  # afmformats writes in place: write, then move
        h5, tab = Path(tmp) / AF_H5, Path(tmp) / AF_TAB
        _afmformats_thinned(HERE / "jpk_cellhesion_spot3.jpk-force", AF_H5_STEP).export_data(h5, fmt="hdf5")
        _afmformats_thinned(HERE / "asylum-mfp3d_SiN-tip_air.ibw", AF_TAB_STEP).export_data(tab, fmt="tab")
        for f in (h5, tab):
            (HERE / f.name).write_bytes(f.read_bytes())


def make_chiaro(archive: Path | None) -> None:
    if archive is None:
        print(f"{CHIARO}: kept (give --chiaro-zip to rewrite it from afmformats' test file)")
        return
    with zipfile.ZipFile(archive) as arc:
        raw = arc.read(CHIARO_MEMBER)
    lines = raw.splitlines(keepends=True)
    head = next(i for i, ln in enumerate(lines) if ln.startswith(b"Time (s)\tLoad"))
    rows = [ln for ln in lines[head + 1:] if ln.strip()]
    load = np.array([float(r.split(b"\t")[1]) for r in rows])
    keep = sorted(set(range(0, len(rows), CHIARO_STEP)) | {int(np.argmax(load))})
    (HERE / CHIARO).write_bytes(b"".join(lines[:head + 1]) + b"".join(rows[i] for i in keep))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=SHARED, help="folder of the real instrument files")
    parser.add_argument("--chiaro-zip", type=Path, default=None,
                        help="afmformats' tests/data/fmt-chiaro-txt_AEBP1_Indentation_002.zip")
    args = parser.parse_args(argv)
    make_raw_text()
    make_raw_hdf5()
    make_map(args.shared)
    make_afmformats_exports()
    make_chiaro(args.chiaro_zip)
    for name in (RAW_TXT, RAW_H5, MAP_H5, AF_H5, AF_TAB, CHIARO):
        print(f"{name}: {(HERE / name).stat().st_size / 1e3:.1f} kB")


if __name__ == "__main__":
    sys.exit(main())
